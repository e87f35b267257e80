// cullkit/geometry/plane.hpp: oriented planes and the three-state containment answer.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

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

namespace detail {
/// The plane of the row (a, b, c, d), scaled in double to a unit normal and rounded to float, into
/// `out`. False (and `out` untouched) when no usable float plane results: a zero or non-finite
/// normal, a non-finite offset, or a unit coefficient that is not zero but below the smallest
/// normal float (its relative precision would be lost, and the box and sphere tests' tolerances are
/// relative; dropping the plane only grows the region). The rounding to float moves the plane by at
/// most half an ulp of each term, well inside the tests' 8-epsilon tolerance.
[[nodiscard]] inline bool unit_plane(double a, double b, double c, double d, Plane& out) noexcept {
  const double len = std::sqrt(a * a + b * b + c * c);
  if (!(len > 0.0) || !std::isfinite(len) || !std::isfinite(d)) return false;
  const double q[4] = {a / len, b / len, c / len, d / len};
  for (double v : q) {
    const double m = std::fabs(v);
    if (m > 0.0 && m < static_cast<double>(std::numeric_limits<float>::min())) return false;
    if (!(m <= static_cast<double>(std::numeric_limits<float>::max()))) return false;
  }
  out = Plane{glm::vec3(static_cast<float>(q[0]), static_cast<float>(q[1]), static_cast<float>(q[2])),
              static_cast<float>(q[3])};
  return true;
}
}  // namespace detail

/// `p` scaled to a unit normal, or the zero plane {0,0,0,0} when `p` is not valid or its unit form
/// is not representable in float (see `is_valid`). Every container that stores user planes keeps
/// them in this form, because its sphere tests read `d` as a distance.
[[nodiscard]] inline Plane normalized(const Plane& p) noexcept {
  Plane out{glm::vec3(0.0f), 0.0f};
  if (!detail::unit_plane(static_cast<double>(p.normal.x), static_cast<double>(p.normal.y),
                          static_cast<double>(p.normal.z), static_cast<double>(p.d), out))
    return Plane{glm::vec3(0.0f), 0.0f};
  return out;
}

/// The same plane facing the other way.
[[nodiscard]] inline Plane flipped(const Plane& p) noexcept { return Plane{-p.normal, -p.d}; }

}  // namespace cullkit
