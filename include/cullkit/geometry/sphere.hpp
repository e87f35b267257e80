// cullkit/geometry/sphere.hpp: bounding spheres.
#pragma once

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "aabb.hpp"

namespace cullkit {

/// A closed ball. Trivially copyable aggregate.
struct Sphere {
  glm::vec3 center;
  float radius;
};

/// The sphere circumscribing a box: center at the (rounded) box center, radius the distance to the
/// farthest corner computed in double and rounded up, so every corner is inside despite float
/// rounding. Empty box: radius -1.
[[nodiscard]] inline Sphere bounding_sphere(const Aabb& b) noexcept {
  if (is_empty(b)) return Sphere{glm::vec3(0.0f), -1.0f};
  const glm::vec3 c = b.center();
  double r2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double e = std::fmax(double(b.max[a]) - double(c[a]), double(c[a]) - double(b.min[a]));
    r2 += e * e;
  }
  const float r = static_cast<float>(std::sqrt(r2));
  return Sphere{c, std::nextafter(r * (1.0f + 2.0f * std::numeric_limits<float>::epsilon()),
                                  std::numeric_limits<float>::infinity())};
}

[[nodiscard]] inline bool contains(const Sphere& s, const glm::vec3& p) noexcept {
  const glm::vec3 d = p - s.center;
  return glm::dot(d, d) <= s.radius * s.radius;
}

}  // namespace cullkit
