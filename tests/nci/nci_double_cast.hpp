// tests/nci/nci_double_cast.hpp: a double-precision ray cast for the moving-object tests: which
// triangle a pixel-centre ray truly meets first, decided only where rounding cannot change it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cullkit/geometry/camera.hpp>

namespace nci_test {

/// A world triangle in double. `flip`: its counted side is the other one (a mirrored object's
/// triangles count where they face the eye in the object's frame).
struct DoubleTriangle {
  glm::dvec3 a, b, c;
  bool flip = false;
};

/// The pixel-centre ray of the Camera rule, in double (unit direction; zero when undefined).
inline glm::dvec3 double_pixel_ray(const cullkit::Camera& cam, int x, int y) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.view_proj));
  const double u = 2.0 * (x + 0.5) / cam.width - 1.0, v = 1.0 - 2.0 * (y + 0.5) / cam.height;
  const glm::dvec4 xy = inv[0] * u + inv[1] * v;
  glm::dvec4 h = xy + inv[2] + inv[3];
  if (!(std::fabs(h.w) > 1e-9 * (std::fabs(h.x) + std::fabs(h.y) + std::fabs(h.z))))
    h = xy + inv[2] * (cam.depth == cullkit::DepthRange::zero_to_one ? 0.0 : -1.0) + inv[3];
  const glm::dvec3 d = glm::dvec3(h) / h.w - glm::dvec3(cam.eye);
  const double len = glm::length(d);
  return len > 0.0 && std::isfinite(len) ? d / len : glm::dvec3(0.0);
}

/// Where ray o + t d meets triangle `tri`'s plane inside its edges grown by `grow` (barycentric),
/// from its counted side, at t > 0: t, else -1. `robust` says whether the hit is at least `grow`
/// inside every edge and the ray is not grazing (cosine to the normal at least 1e-4).
inline double double_hit(const glm::dvec3& o, const glm::dvec3& d, const DoubleTriangle& tri, double grow, bool& robust) {
  robust = false;
  const glm::dvec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a, n = glm::cross(e1, e2);
  const double facing = glm::dot(d, n) * (tri.flip ? -1.0 : 1.0);
  const double nl = glm::length(n);
  if (!(nl > 0.0)) return -1.0;
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return -1.0;
  const double inv = 1.0 / det;
  const glm::dvec3 s = o - tri.a;
  const double u = glm::dot(s, p) * inv;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) * inv;
  const double t = glm::dot(e2, q) * inv;
  const double w = 1.0 - u - v;
  if (!(t > 0.0) || u < -grow || v < -grow || w < -grow) return -1.0;
  if (facing >= 0.0 && -facing <= 1e-4 * nl) {
    // Back face, or nearly edge-on: not a hit, but a grazing one stays a possible hit.
    return facing > 1e-4 * nl ? -1.0 : t;
  }
  robust = u >= grow && v >= grow && w >= grow && -facing >= 1e-4 * nl;
  return t;
}

/// The robust first hit of ray (o, d) among `tris`: the index of a triangle met robustly that lies
/// nearer, by `gap` relative depth, than every other triangle possibly met (edges grown by `grow`);
/// -1 when there is none (a miss, or a case rounding could decide either way).
inline int robust_first_hit(const glm::dvec3& o, const glm::dvec3& d, const std::vector<DoubleTriangle>& tris,
                            double grow = 1e-4, double gap = 1e-4) {
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity(), second_t = best_t;
  bool best_robust = false;
  for (std::size_t k = 0; k < tris.size(); ++k) {
    bool robust = false;
    const double t = double_hit(o, d, tris[k], grow, robust);
    if (t < 0.0) continue;
    if (t < best_t) {
      second_t = best_t;
      best_t = t;
      best = static_cast<int>(k);
      best_robust = robust;
    } else {
      second_t = std::min(second_t, t);
    }
  }
  if (best < 0 || !best_robust || !(second_t > best_t * (1.0 + gap))) return -1;
  return best;
}

}  // namespace nci_test
