// cullkit/detail/occlusion/geometry.hpp: eye-relative helpers for OcclusionTree (not public API).
//
// The occlusion tree works in coordinates relative to its eye: every plane through the eye then has
// d == 0 exactly, and plane normals are computed in double precision from float corners (the
// difference of two floats is exact in double for all but absurd exponent gaps), then rounded once.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/ext/vector_double3.hpp>

#include "../../geometry/aabb.hpp"
#include "../../geometry/convex_polygon.hpp"
#include "../../geometry/plane.hpp"
#include "query.hpp"
#include "seams.hpp"

namespace cullkit::detail {

/// Sum of absolute coordinates: a cheap upper bound of the Euclidean length, used for margins.
[[nodiscard]] inline float norm1(const glm::vec3& v) noexcept {
  return std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z);
}

[[nodiscard]] inline bool finite3(const glm::vec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The unit normal `n` rounded to float, as a plane through the origin (the eye). Zero plane if the
/// normal vanished.
[[nodiscard]] inline Plane eye_plane_from_normal(const glm::dvec3& n) noexcept {
  const double len = glm::length(n);
  if (!(len > 0.0) || !std::isfinite(len)) return Plane{glm::vec3(0.0f), 0.0f};
  return Plane{glm::vec3(n / len), 0.0f};
}

/// Edge planes of the beam from the origin through a convex polygon (eye-relative corners).
///
/// Corners whose direction from the eye is within `min_angle` (radians, as a sine) of the previous
/// kept corner are dropped: a beam through fewer corners is a subset of the original beam, so this
/// only ever shrinks an occluder. Writes one plane per kept corner into `out` (inside: toward the
/// polygon) and returns how many, or 0 when fewer than 3 corners survive or the polygon has no area
/// as seen from the eye (then the fragment must be dropped, which is also safe).
/// With `angles`, also writes for each edge 1 - cos of the angle it subtends at the eye (which grows
/// with the angle, so it orders edges by angular length without an atan2). With `sources`, writes
/// the index in `poly` of each kept corner: edge i runs from corner sources[i] to sources[(i + 1) % n].
/// Each normal is computed from the edge's corners in their canonical order (`corner_before`), so two
/// occluders sharing an edge get planes that are exact negations of each other.
/// pre: `out` (and `angles`, `sources`, if given) has room for `poly.size()` entries.
template <std::size_t Capacity>
[[nodiscard]] inline std::size_t beam_planes(const BasicConvexPolygon<Capacity>& poly, float min_angle,
                                             Plane* out, float* angles = nullptr,
                                             std::uint32_t* sources = nullptr) noexcept {
  glm::dvec3 kept[Capacity];
  std::uint32_t kept_source[Capacity];
  std::size_t n = 0;
  const double min_sin = static_cast<double>(min_angle);
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const glm::dvec3 p(poly[i]);
    const double len = glm::length(p);
    if (!(len > 0.0) || !std::isfinite(len)) return 0;  // a corner at the eye or non-finite
    if (n > 0) {
      const glm::dvec3& q = kept[n - 1];
      const double s = glm::length(glm::cross(q, p)) / (glm::length(q) * len);
      if (s <= min_sin && glm::dot(q, p) > 0.0) continue;
    }
    kept_source[n] = static_cast<std::uint32_t>(i);
    kept[n++] = p;
  }
  // The cycle closes: the last kept corner may duplicate the first.
  while (n >= 2) {
    const glm::dvec3& q = kept[n - 1];
    const glm::dvec3& p = kept[0];
    const double s = glm::length(glm::cross(q, p)) / (glm::length(q) * glm::length(p));
    if (s <= min_sin && glm::dot(q, p) > 0.0) --n;
    else break;
  }
  if (n < 3) return 0;
  // Orientation: sum of cross products is twice the area vector; its sign against the centroid
  // direction says whether the corners turn clockwise or counter-clockwise as seen from the eye.
  glm::dvec3 area(0.0), centroid(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    area += glm::cross(kept[i], kept[(i + 1) % n]);
    centroid += kept[i];
  }
  const double facing = glm::dot(area, centroid);
  const double scale = glm::length(area) * glm::length(centroid);
  if (!(std::fabs(facing) > min_sin * scale)) return 0;  // seen edge-on: no area from the eye
  const double sign = facing < 0.0 ? -1.0 : 1.0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3& a = kept[i];
    const glm::dvec3& b = kept[(i + 1) % n];
    // kept[] holds floats exactly, so the float round trip is exact.
    const glm::dvec3 cross = corner_before(glm::vec3(b), glm::vec3(a)) ? -glm::cross(b, a) : glm::cross(a, b);
    out[i] = eye_plane_from_normal(sign * cross);
    if (sources) sources[i] = kept_source[i];
    if (!is_valid(out[i])) return 0;
    if (angles) {
      angles[i] = static_cast<float>(1.0 - glm::dot(a, b) / (glm::length(a) * glm::length(b)));
    }
  }
  return n;
}

/// The faces of the box `local_box` placed by the affine matrix `model` that the eye (world) sees:
/// up to 3 quads of world corners, written to `out`; returns how many. Every face uses the same 8
/// rounded world corners, so neighbouring faces share their edges bit for bit. 0 when the box or
/// the matrix is not finite, the box is invalid (min > max), the matrix is not affine (last row not
/// 0 0 0 1), or the eye sees no face (inside or on the box). A face counts as seen when the eye is
/// strictly on its outer side (away from the box's centre), in double precision.
[[nodiscard]] inline int oriented_box_front_faces(const Aabb& local_box, const glm::mat4& model, const glm::vec3& eye,
                                                  glm::vec3 out[3][4]) noexcept {
  if (!is_valid(local_box)) return 0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(model[c][r])) return 0;
  if (model[0][3] != 0.0f || model[1][3] != 0.0f || model[2][3] != 0.0f || model[3][3] != 1.0f) return 0;
  glm::vec3 world[8];
  glm::dvec3 centre(0.0);
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p(corner(local_box, c));
    const glm::dvec3 w = glm::dvec3(glm::vec3(model[3])) + glm::dvec3(glm::vec3(model[0])) * p.x +
                         glm::dvec3(glm::vec3(model[1])) * p.y + glm::dvec3(glm::vec3(model[2])) * p.z;
    world[c] = glm::vec3(w);
    if (!finite3(world[c])) return 0;
    centre += glm::dvec3(world[c]);
  }
  centre /= 8.0;
  const glm::dvec3 e(eye);
  int count = 0;
  for (int axis = 0; axis < 3 && count < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int side = 0; side < 2 && count < 3; ++side) {
      const int base = side << axis;
      const int ids[4] = {base, base | (1 << a1), base | (1 << a1) | (1 << a2), base | (1 << a2)};
      const glm::dvec3 p0(world[ids[0]]), p1(world[ids[1]]), p3(world[ids[3]]), p2(world[ids[2]]);
      glm::dvec3 normal = glm::cross(p1 - p0, p3 - p0);
      if (glm::dot(normal, 0.25 * (p0 + p1 + p2 + p3) - centre) < 0.0) normal = -normal;
      if (!(glm::dot(normal, e - p0) > 0.0)) continue;
      for (int k = 0; k < 4; ++k) out[count][k] = world[ids[k]];
      ++count;
    }
  }
  return count;
}

}  // namespace cullkit::detail
