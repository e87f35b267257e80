// tests/mesh_occlusion/mesh_occlusion_oracle.hpp: brute-force ground truth for MeshOcclusionCuller.
// Rays by the Camera pixel rule (at continuous pixel positions), an exact-as-double ray/triangle
// test, front faces only, hits beyond the near plane only (the plane at `near` along `forward`).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/ext/vector_double3.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

namespace mesh_oracle {

/// A small mesh with objects, kept as doubles for the oracle.
struct TestScene {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  std::vector<cullkit::MeshObject> objects;

  std::uint32_t begin_object() {
    objects.push_back(cullkit::MeshObject{static_cast<std::uint32_t>(indices.size() / 3), 0});
    return static_cast<std::uint32_t>(objects.size() - 1);
  }
  void triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const auto base = static_cast<std::uint32_t>(positions.size());
    positions.push_back(a);
    positions.push_back(b);
    positions.push_back(c);
    indices.insert(indices.end(), {base, base + 1, base + 2});
    ++objects.back().triangle_count;
  }
  // A box as 12 outward counter-clockwise triangles (one object).
  std::uint32_t box(const glm::vec3& lo, const glm::vec3& hi) {
    const std::uint32_t o = begin_object();
    const cullkit::Aabb b{lo, hi};
    for (int t = 0; t < 12; ++t)
      triangle(cullkit::corner(b, static_cast<int>(cullkit::support::kBoxTriangleCorners[3 * t])),
               cullkit::corner(b, static_cast<int>(cullkit::support::kBoxTriangleCorners[3 * t + 1])),
               cullkit::corner(b, static_cast<int>(cullkit::support::kBoxTriangleCorners[3 * t + 2])));
    return o;
  }
  cullkit::MeshView<glm::vec3> mesh() const {
    return {positions.data(), positions.size(), indices.data(), indices.size()};
  }
};

/// Adds a grid of nu x nv quads spanning the parallelogram origin + [0,1] u + [0,1] v to the
/// current object, counter-clockwise seen from the side u x v points to.
inline void grid_quads(TestScene& s, const glm::vec3& origin, const glm::vec3& u, const glm::vec3& v, int nu, int nv) {
  const auto at = [&](int i, int j) { return origin + u * (float(i) / float(nu)) + v * (float(j) / float(nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      s.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      s.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
}

/// The culler's index of `s` (the library's own build, as a culler makes it), its objects cut into
/// patches of up to `patch_triangles`.
inline void build_test_index(const TestScene& s, cullkit::detail::mesh_occlusion::MeshIndex& index,
                             std::uint32_t patch_triangles) {
  cullkit::detail::mesh_occlusion::build_index(
      index, s.indices.size() / 3,
      [&s](std::size_t t, glm::vec3 p[3]) {
        for (int k = 0; k < 3; ++k) p[k] = s.positions[s.indices[3 * t + std::size_t(k)]];
        return true;
      },
      s.objects.data(), s.objects.size(), cullkit::AbtParams{}, patch_triangles);
}

/// The near side of a camera: a point counts only if dot(p - eye, forward) > near.
struct NearSide {
  glm::dvec3 eye, forward;
  double near;
};

/// Ray parameter of the front-face hit of triangle (a, b, c), or -1. `grow` > 0 widens the
/// triangle by that barycentric amount (used for occluders: never a crack between neighbours),
/// < 0 shrinks it (used for the hidden object: a grazing touch is not a sighting).
inline double hit(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                  const glm::dvec3& c, double grow) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 n = glm::cross(e1, e2);
  const double dn = glm::dot(d, n);
  if (!(dn < 0.0)) return -1.0;  // back-facing or parallel
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  const double inv = 1.0 / det;
  const glm::dvec3 s = o - a;
  const double u = glm::dot(s, p) * inv;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) * inv;
  const double t = glm::dot(e2, q) * inv;
  if (u < -grow || v < -grow || u + v > 1.0 + grow) return -1.0;
  return t > 0.0 && std::isfinite(t) ? t : -1.0;
}

/// Nearest hit beyond the near plane on the triangles of `object` (or of every other object when
/// `others`), or -1. With `before` > 0, returns the first hit found nearer than `before` instead.
inline double nearest(const TestScene& s, const NearSide& ns, const glm::dvec3& d, std::uint32_t object,
                      bool others, double grow, double before = -1.0) {
  double best = -1.0;
  const std::size_t tri_count = s.indices.size() / 3;
  for (std::uint32_t ob = 0; ob < s.objects.size(); ++ob) {
    if ((ob == object) == others) continue;
    const cullkit::MeshObject& r = s.objects[ob];
    for (std::uint64_t t = r.first_triangle; t < std::uint64_t(r.first_triangle) + r.triangle_count && t < tri_count; ++t) {
      std::uint32_t id[3];
      bool ok = true;
      for (int k = 0; k < 3; ++k) {
        id[k] = s.indices[3 * t + std::uint64_t(k)];
        ok = ok && id[k] < s.positions.size();
      }
      if (!ok) continue;
      const glm::dvec3 a(s.positions[id[0]]), b(s.positions[id[1]]), c(s.positions[id[2]]);
      const double th = hit(ns.eye, d, a, b, c, grow);
      if (th < 0.0) continue;
      if (!(glm::dot(ns.eye + d * th - ns.eye, ns.forward) > ns.near)) {
        // This hit is nearer than the near plane; a second hit of the same triangle is impossible.
        continue;
      }
      if (best < 0.0 || th < best) best = th;
      if (before > 0.0 && best < before) return best;
    }
  }
  return best;
}

/// True when the ray through continuous pixel position (px, py) sees `object` first (its hit
/// beyond the near plane comes before every other object's).
inline bool sees(const TestScene& s, const NearSide& ns, const cullkit::PixelRays& rays, double px, double py,
                 std::uint32_t object) {
  const cullkit::Ray r = rays.ray_at(px, py);
  const glm::dvec3 d(r.direction);
  if (d == glm::dvec3(0.0)) return false;
  const double t_object = nearest(s, ns, d, object, false, -1e-9);
  if (t_object < 0.0) return false;
  const double t_other = nearest(s, ns, d, object, true, 1e-9, t_object);
  return !(t_other >= 0.0 && t_other < t_object);
}

/// Searches for a ray that sees `object`: a regular grid (grid x grid) and `jitter` random rays
/// over the object's screen rectangle (from its corners when they are all in front of the eye,
/// else the whole screen), and its border. Returns true when one is found.
inline bool find_sighting(const TestScene& s, const NearSide& ns, const cullkit::Camera& cam, std::uint32_t object,
                          int grid, int jitter, cullkit::support::Rng& rng) {
  const cullkit::PixelRays rays(cam);
  const cullkit::MeshObject& r = s.objects[object];
  // Screen rectangle of the object's triangles (pixels), clamped; whole screen when unknown.
  double x0 = 0, y0 = 0, x1 = cam.width, y1 = cam.height;
  {
    double bx0 = HUGE_VAL, by0 = HUGE_VAL, bx1 = -HUGE_VAL, by1 = -HUGE_VAL;
    bool ok = true;
    const glm::dmat4 m(cam.view_proj);
    for (std::uint64_t t = r.first_triangle; ok && t < std::uint64_t(r.first_triangle) + r.triangle_count; ++t)
      for (int k = 0; k < 3 && ok; ++k) {
        if (3 * t + std::uint64_t(k) >= s.indices.size() || s.indices[3 * t + std::uint64_t(k)] >= s.positions.size()) {
          ok = false;
          break;
        }
        const glm::dvec4 c = m * glm::dvec4(glm::dvec3(s.positions[s.indices[3 * t + std::uint64_t(k)]]), 1.0);
        if (!(c.w > 1e-9)) {
          ok = false;
          break;
        }
        const double px = (c.x / c.w + 1.0) * 0.5 * cam.width, py = (1.0 - c.y / c.w) * 0.5 * cam.height;
        bx0 = std::min(bx0, px);
        bx1 = std::max(bx1, px);
        by0 = std::min(by0, py);
        by1 = std::max(by1, py);
      }
    if (ok && bx1 >= bx0) {
      x0 = std::max(0.0, bx0 - 1.0);
      y0 = std::max(0.0, by0 - 1.0);
      x1 = std::min(double(cam.width), bx1 + 1.0);
      y1 = std::min(double(cam.height), by1 + 1.0);
      if (x1 <= x0 || y1 <= y0) return false;  // off screen
    }
  }
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i)
      if (sees(s, ns, rays, x0 + (i + 0.5) * (x1 - x0) / grid, y0 + (j + 0.5) * (y1 - y0) / grid, object)) return true;
  for (int k = 0; k < jitter; ++k) {
    const double px = x0 + (x1 - x0) * rng.uniform(), py = y0 + (y1 - y0) * rng.uniform();
    if (sees(s, ns, rays, px, py, object)) return true;
  }
  // The rectangle's own border and corners, where grazing sightings hide.
  for (int k = 0; k <= 16; ++k) {
    const double f = k / 16.0;
    if (sees(s, ns, rays, x0 + (x1 - x0) * f, y0 + 0.5, object) || sees(s, ns, rays, x0 + (x1 - x0) * f, y1 - 0.5, object) ||
        sees(s, ns, rays, x0 + 0.5, y0 + (y1 - y0) * f, object) || sees(s, ns, rays, x1 - 0.5, y0 + (y1 - y0) * f, object))
      return true;
  }
  return false;
}

/// The must-hide rule of the fusion tests: the object's screen rectangle, widened by three cells
/// of a grid_w x grid_h grid, lies on screen, and 9 x 9 rays over it all meet one of the objects
/// [first_occluder, first_occluder + occluders) beyond the near plane, at a depth along the view
/// axis below `depth_ratio` times the object's nearest corner's (HUGE_VAL: any depth, for objects
/// behind the occluders by construction).
inline bool covered_in_front(const TestScene& s, const cullkit::Camera& cam, const NearSide& ns, std::uint32_t object,
                             std::uint32_t first_occluder, std::uint32_t occluders, int grid_w, int grid_h,
                             double depth_ratio) {
  const glm::dmat4 m(cam.view_proj);
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, w_near = HUGE_VAL;
  const cullkit::MeshObject& r = s.objects[object];
  for (std::uint32_t t = r.first_triangle; t < r.first_triangle + r.triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p(s.positions[s.indices[3 * t + std::uint32_t(k)]]);
      const glm::dvec4 c = m * glm::dvec4(p, 1.0);
      if (!(c.w > 0.0)) return false;
      x0 = std::min(x0, c.x / c.w);
      x1 = std::max(x1, c.x / c.w);
      y0 = std::min(y0, c.y / c.w);
      y1 = std::max(y1, c.y / c.w);
      w_near = std::min(w_near, glm::dot(p - ns.eye, ns.forward));
    }
  const double mx = 3.0 * 2.0 / grid_w, my = 3.0 * 2.0 / grid_h;
  x0 -= mx;
  x1 += mx;
  y0 -= my;
  y1 += my;
  if (x0 < -1 || x1 > 1 || y0 < -1 || y1 > 1) return false;
  const cullkit::PixelRays rays(cam);
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) {
      const double u = x0 + (x1 - x0) * i / 8, v = y0 + (y1 - y0) * j / 8;
      const cullkit::Ray ray = rays.ray_at((u + 1) * 0.5 * cam.width, (1 - v) * 0.5 * cam.height);
      const glm::dvec3 d(ray.direction);
      bool in_front = false;
      for (std::uint32_t o = first_occluder; o < first_occluder + occluders && !in_front; ++o) {
        const double t = nearest(s, ns, d, o, false, 1e-9);
        in_front = t >= 0.0 && (depth_ratio == HUGE_VAL || glm::dot(d * t, ns.forward) < depth_ratio * w_near);
      }
      if (!in_front) return false;
    }
  return true;
}

}  // namespace mesh_oracle
