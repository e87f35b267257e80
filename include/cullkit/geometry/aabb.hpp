// cullkit/geometry/aabb.hpp: axis-aligned boxes.
#pragma once

#include <cmath>
#include <limits>

#include <glm/vec3.hpp>
#include <glm/common.hpp>

namespace cullkit {

/// An axis-aligned box, closed: a point on a face is inside. `min <= max` on every axis for a
/// valid box; `Aabb::empty()` is the inverted box that absorbs nothing and is the identity of
/// `merge`. Trivially copyable aggregate.
struct Aabb {
  glm::vec3 min;
  glm::vec3 max;

  /// The inverted box (+inf, -inf): `merge(empty(), b) == b`, and it meets nothing.
  [[nodiscard]] static constexpr Aabb empty() noexcept {
    constexpr float inf = std::numeric_limits<float>::infinity();
    return Aabb{glm::vec3(inf), glm::vec3(-inf)};
  }
  [[nodiscard]] constexpr glm::vec3 center() const noexcept { return (min + max) * 0.5f; }
  [[nodiscard]] constexpr glm::vec3 extent() const noexcept { return max - min; }
};

/// True if every coordinate is finite and `min <= max` on each axis (a flat or point box is valid).
/// NaN fails every comparison, so a box with a NaN is never valid.
[[nodiscard]] inline bool is_valid(const Aabb& b) noexcept {
  for (int a = 0; a < 3; ++a) {
    if (!(b.min[a] <= b.max[a])) return false;
    if (!std::isfinite(b.min[a]) || !std::isfinite(b.max[a])) return false;
  }
  return true;
}

/// True if `min > max` on some axis (including the `Aabb::empty()` box). NaN boxes are not empty;
/// check `is_valid` first.
[[nodiscard]] inline bool is_empty(const Aabb& b) noexcept {
  return b.min.x > b.max.x || b.min.y > b.max.y || b.min.z > b.max.z;
}

[[nodiscard]] inline Aabb merge(const Aabb& a, const Aabb& b) noexcept {
  return Aabb{glm::min(a.min, b.min), glm::max(a.max, b.max)};
}
[[nodiscard]] inline Aabb merge(const Aabb& a, const glm::vec3& p) noexcept {
  return Aabb{glm::min(a.min, p), glm::max(a.max, p)};
}
/// The overlap of two boxes; `is_empty` if they do not meet.
[[nodiscard]] inline Aabb intersection(const Aabb& a, const Aabb& b) noexcept {
  return Aabb{glm::max(a.min, b.min), glm::min(a.max, b.max)};
}

/// Closed-box overlap: boxes that only touch overlap.
[[nodiscard]] inline bool overlaps(const Aabb& a, const Aabb& b) noexcept {
  return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
         a.min.z <= b.max.z && b.min.z <= a.max.z;
}
[[nodiscard]] inline bool contains(const Aabb& b, const glm::vec3& p) noexcept {
  return p.x >= b.min.x && p.x <= b.max.x && p.y >= b.min.y && p.y <= b.max.y && p.z >= b.min.z &&
         p.z <= b.max.z;
}
[[nodiscard]] inline bool contains(const Aabb& outer, const Aabb& inner) noexcept {
  return contains(outer, inner.min) && contains(outer, inner.max);
}

/// Volume; 0 for an empty box.
[[nodiscard]] inline float volume(const Aabb& b) noexcept {
  const glm::vec3 e = glm::max(b.max - b.min, glm::vec3(0.0f));
  return e.x * e.y * e.z;
}
/// Surface area; 0 for an empty box.
[[nodiscard]] inline float surface_area(const Aabb& b) noexcept {
  const glm::vec3 e = glm::max(b.max - b.min, glm::vec3(0.0f));
  return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}
/// Index (0, 1, 2) of the longest axis; ties go to the lower axis.
[[nodiscard]] inline int longest_axis(const Aabb& b) noexcept {
  const glm::vec3 e = b.max - b.min;
  return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
}

/// Corner `i` (bit 0: x, bit 1: y, bit 2: z; set means max).
[[nodiscard]] inline glm::vec3 corner(const Aabb& b, int i) noexcept {
  return glm::vec3((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                   (i & 4) ? b.max.z : b.min.z);
}

}  // namespace cullkit
