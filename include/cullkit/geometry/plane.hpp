// cullkit/geometry/plane.hpp: oriented planes and the three-state containment answer.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace cullkit {

/// Where a shape lies with respect to a region.
enum class Containment : std::uint8_t {
  outside,       ///< no point of the shape is in the region
  intersecting,  ///< the shape may straddle the boundary (conservative: "not proven either way")
  inside,        ///< every point of the shape is in the region
};

/// An oriented plane: signed distance of `p` is `dot(normal, p) + d`. The *inside* (front, positive)
/// side is the one the normal points into; a point with distance exactly 0 is inside. Planes
/// cullkit builds have unit normals; `signed_distance` is only a distance if the normal is unit.
struct Plane {
  glm::vec3 normal;
  float d;
};

[[nodiscard]] inline float signed_distance(const Plane& p, const glm::vec3& x) noexcept {
  return glm::dot(p.normal, x) + p.d;
}

/// The plane through `point` with the given (not necessarily unit) normal, normalized.
/// A zero or non-finite normal gives the zero plane {0,0,0,0}; check with `is_valid`.
[[nodiscard]] inline Plane plane_from_point_normal(const glm::vec3& point, const glm::vec3& normal) noexcept {
  const float len = glm::length(normal);
  if (!(len > 0.0f) || !std::isfinite(len)) return Plane{glm::vec3(0.0f), 0.0f};
  const glm::vec3 n = normal / len;
  return Plane{n, -glm::dot(n, point)};
}

/// The plane through three points, inside where (b - a) x (c - a) points: counter-clockwise
/// corners seen from the inside. Collinear points give the zero plane.
[[nodiscard]] inline Plane plane_from_points(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) noexcept {
  return plane_from_point_normal(a, glm::cross(b - a, c - a));
}

/// A plane with a finite, non-zero normal and a finite offset.
[[nodiscard]] inline bool is_valid(const Plane& p) noexcept {
  const float l = glm::dot(p.normal, p.normal);
  return l > 0.0f && std::isfinite(l) && std::isfinite(p.d);
}

/// The same plane facing the other way.
[[nodiscard]] inline Plane flipped(const Plane& p) noexcept { return Plane{-p.normal, -p.d}; }

}  // namespace cullkit
