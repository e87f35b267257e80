// cullkit/geometry/sphere.hpp: bounding spheres.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "aabb.hpp"

namespace cullkit {

/// A closed ball. Trivially copyable aggregate.
struct Sphere {
  glm::vec3 center;
  float radius;
};

/// The sphere circumscribing a box (center at the box center, radius half the diagonal), rounded
/// up by a few ulps so every corner is inside despite float rounding. Empty box: radius -1.
[[nodiscard]] inline Sphere bounding_sphere(const Aabb& b) noexcept {
  if (is_empty(b)) return Sphere{glm::vec3(0.0f), -1.0f};
  const glm::vec3 c = b.center();
  const float r = 0.5f * glm::length(b.max - b.min);
  return Sphere{c, r * (1.0f + 4.0f * std::numeric_limits<float>::epsilon()) +
                       std::numeric_limits<float>::denorm_min()};
}

[[nodiscard]] inline bool contains(const Sphere& s, const glm::vec3& p) noexcept {
  const glm::vec3 d = p - s.center;
  return glm::dot(d, d) <= s.radius * s.radius;
}

}  // namespace cullkit
