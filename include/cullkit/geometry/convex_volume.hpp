// cullkit/geometry/convex_volume.hpp: the intersection of up to 32 half-spaces.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "../detail/bits.hpp"
#include "aabb.hpp"
#include "frustum.hpp"
#include "plane.hpp"
#include "sphere.hpp"

namespace cullkit {

/// One bit per plane of a `ConvexVolume` (bit i for `plane(i)`).
using VolumeMask = std::uint32_t;

/// A convex region: the points on the inside (normal) side of every one of its planes.
///
/// The frustum generalised: a frustum narrowed by a portal's edges, a shadow-caster volume, a view
/// with extra user planes. With no planes it holds all of space. Tests are conservative exactly as
/// `Frustum`'s are: `outside` only when float rounding cannot have moved the shape across a plane.
///
/// Cost: `classify(Aabb)` tests two corners per plane. Thread safety: immutable once built; a
/// value type of 516 bytes that is cheap to copy and never allocates.
class ConvexVolume {
 public:
  static constexpr std::size_t max_planes = 32;

  /// No planes: everything is inside.
  ConvexVolume() noexcept = default;

  /// The planes of `frustum` that exist (a dropped far plane stays dropped).
  explicit ConvexVolume(const Frustum& frustum) noexcept {
    for (int i = 0; i < Frustum::max_planes; ++i)
      if (frustum.has_plane(i)) add_plane(frustum.plane(i));
  }

  /// Adds a plane (normal pointing inward, of any positive length: it is stored scaled to a unit
  /// normal, see `normalized`, so `plane(i)` may differ from what was given by that factor and a
  /// rounding). Returns false and adds nothing when the volume already has `max_planes`. A plane
  /// that is not valid (zero or non-finite normal, non-finite offset) cannot reject anything: it is
  /// not stored, and the call still returns true.
  bool add_plane(const Plane& plane) noexcept {
    if (count_ >= max_planes) return false;
    const Plane unit = normalized(plane);
    if (!is_valid(unit)) return true;
    planes_[count_++] = unit;
    return true;
  }

  [[nodiscard]] std::size_t plane_count() const noexcept { return count_; }
  [[nodiscard]] const Plane& plane(std::size_t i) const noexcept { return planes_[i]; }
  /// The mask with a bit for every stored plane.
  [[nodiscard]] VolumeMask full_mask() const noexcept {
    return count_ >= 32 ? ~VolumeMask{0} : ((VolumeMask{1} << count_) - 1u);
  }

  /// Box test. Never `outside` for a box that meets the volume; a box with NaN is `intersecting`.
  [[nodiscard]] Containment classify(const Aabb& box) const noexcept {
    VolumeMask m = full_mask();
    return classify(box, m);
  }

  /// Box test against the planes in `mask` only. On return `mask` holds the planes the box
  /// straddles (those it is fully inside of are cleared, so a child box can skip them). If the
  /// answer is `outside`, `mask` is unspecified.
  [[nodiscard]] Containment classify(const Aabb& box, VolumeMask& mask) const noexcept {
    const glm::vec3 c = (box.min + box.max) * 0.5f;
    const glm::vec3 e = (box.max - box.min) * 0.5f;
    VolumeMask straddled = mask;
    for (VolumeMask rest = mask; rest != 0; rest &= rest - 1u) {
      const int i = detail::lowest_bit(rest);
      const Plane& p = planes_[i];
      const float dc = glm::dot(p.normal, c) + p.d;
      const float r = std::fabs(p.normal.x) * e.x + std::fabs(p.normal.y) * e.y +
                      std::fabs(p.normal.z) * e.z;
      const float slack = Frustum::tolerance(p, c, r);
      if (dc + r < -slack) return Containment::outside;
      if (dc - r >= slack) straddled &= ~(VolumeMask{1} << i);
    }
    mask = straddled;
    return straddled == 0 ? Containment::inside : Containment::intersecting;
  }

  /// Sphere test, same guarantees as the box test.
  [[nodiscard]] Containment classify(const Sphere& s) const noexcept {
    if (!(s.radius >= 0.0f)) return Containment::outside;  // the empty sphere
    bool inside = true;
    for (std::size_t i = 0; i < count_; ++i) {
      const Plane& p = planes_[i];
      const float dc = glm::dot(p.normal, s.center) + p.d;
      const float slack = Frustum::tolerance(p, s.center, s.radius);
      if (dc + s.radius < -slack) return Containment::outside;
      if (!(dc - s.radius >= slack)) inside = false;
    }
    return inside ? Containment::inside : Containment::intersecting;
  }

  /// Point test: true unless the point is clearly outside some plane.
  [[nodiscard]] bool contains(const glm::vec3& p) const noexcept {
    return classify(Sphere{p, 0.0f}) != Containment::outside;
  }

 private:
  Plane planes_[max_planes] = {};
  std::size_t count_ = 0;
};

}  // namespace cullkit
