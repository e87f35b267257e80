// tests/occlusion/brute.hpp: double-precision ground truth for occlusion tests: is the segment from
// the eye to a point blocked by a polygon or a solid box?
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/ext/vector_double3.hpp>
#include <glm/ext/vector_double4.hpp>
#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/mat4x4.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

namespace occlusion_test {

using glm::dvec3;

/// Segment eye->p meets the convex planar polygon (closed; touching counts).
inline bool segment_hits_polygon(const dvec3& eye, const dvec3& p, const std::vector<glm::vec3>& poly) {
  const std::size_t n = poly.size();
  dvec3 normal(0.0), c(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    normal += glm::cross(dvec3(poly[i]), dvec3(poly[(i + 1) % n]));
    c += dvec3(poly[i]);
  }
  c /= double(n);
  const double de = glm::dot(normal, eye - c), dp = glm::dot(normal, p - c);
  if ((de > 0 && dp > 0) || (de < 0 && dp < 0)) return false;
  if (de == dp) return false;  // parallel (in the plane): no area blocks
  const double t = de / (de - dp);
  const dvec3 x = eye + (p - eye) * t;
  // Inside test: x on the inner side of every edge (within a tiny tolerance: touching counts).
  const double scale = glm::length(normal);
  for (std::size_t i = 0; i < n; ++i) {
    const dvec3 a(poly[i]), b(poly[(i + 1) % n]);
    const double s = glm::dot(glm::cross(b - a, x - a), normal) / scale;
    if (s < -1e-9 * (glm::length(b - a) + 1.0)) return false;
  }
  return true;
}

/// Segment eye->p meets the closed box.
inline bool segment_hits_box(const dvec3& eye, const dvec3& p, const cullkit::Aabb& box) {
  double t0 = 0.0, t1 = 1.0;
  const dvec3 d = p - eye;
  for (int a = 0; a < 3; ++a) {
    const double lo = box.min[a], hi = box.max[a];
    if (d[a] == 0.0) {
      if (eye[a] < lo || eye[a] > hi) return false;
      continue;
    }
    double ta = (lo - eye[a]) / d[a], tb = (hi - eye[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

/// A solid box placed by an affine matrix; the brute force works in its local frame.
struct OrientedBox {
  cullkit::Aabb local;
  glm::dmat4 world_to_local;
  OrientedBox(const cullkit::Aabb& box, const glm::mat4& model)
      : local(box), world_to_local(glm::inverse(glm::dmat4(model))) {}
  [[nodiscard]] bool blocks(const dvec3& eye, const dvec3& p) const {
    const dvec3 e(world_to_local * glm::dvec4(eye, 1.0)), q(world_to_local * glm::dvec4(p, 1.0));
    return segment_hits_box(e, q, local);
  }
};

struct Occluders {
  std::vector<std::vector<glm::vec3>> polygons;
  std::vector<cullkit::Aabb> boxes;
  std::vector<OrientedBox> oriented;
  bool blocks(const dvec3& eye, const dvec3& p) const {
    for (const auto& poly : polygons)
      if (segment_hits_polygon(eye, p, poly)) return true;
    for (const auto& b : boxes)
      if (segment_hits_box(eye, p, b)) return true;
    for (const auto& b : oriented)
      if (b.blocks(eye, p)) return true;
    return false;
  }
};

/// Sample points of a box: corners, a grid on every face, random interior points. Returns the first
/// point found visible (not blocked), or false if every sample is blocked.
inline bool find_visible_sample(const Occluders& occ, const glm::vec3& eye, const cullkit::Aabb& box,
                                cullkit::support::Rng& rng, int grid, int random_points, glm::dvec3* witness) {
  const dvec3 e(eye);
  const dvec3 lo(box.min), hi(box.max);
  auto test = [&](const dvec3& p) {
    if (!occ.blocks(e, p)) {
      if (witness) *witness = p;
      return true;
    }
    return false;
  };
  for (int c = 0; c < 8; ++c)
    if (test(dvec3(cullkit::corner(box, c)))) return true;
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i <= grid; ++i)
        for (int j = 0; j <= grid; ++j) {
          dvec3 p;
          p[axis] = side ? hi[axis] : lo[axis];
          p[a1] = lo[a1] + (hi[a1] - lo[a1]) * i / grid;
          p[a2] = lo[a2] + (hi[a2] - lo[a2]) * j / grid;
          if (test(p)) return true;
        }
  }
  for (int k = 0; k < random_points; ++k) {
    const dvec3 p(lo.x + (hi.x - lo.x) * rng.uniform(), lo.y + (hi.y - lo.y) * rng.uniform(),
                  lo.z + (hi.z - lo.z) * rng.uniform());
    if (test(p)) return true;
  }
  return false;
}

}  // namespace occlusion_test
