// cullkit/detail/abt/leaf.hpp: the plane tests of AdaptiveBinaryTree walks (node box and sphere
// against any plane list with a bit mask), and the per-object test inside a straddling leaf,
// over boxes stored as structure-of-arrays (centers and half extents), a fixed number of lanes at
// a time so the compiler vectorizes the plane loop. Users never name this.
//
// The rule is Frustum::classify's, term for term: a box is outside a plane when the farthest
// corner along the normal, dot(n, c) + d + r, is below -slack, and inside it when the nearest,
// dot(n, c) + d - r, is at least slack, with slack = Frustum::tolerance(plane, c, r). Centers and
// half extents are rounded exactly as Frustum::classify rounds them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "../../config.hpp"
#include "../bits.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/plane.hpp"
#include "../../geometry/sphere.hpp"
#include "../../geometry/frustum.hpp"

namespace cullkit::detail {

/// Index of the lowest set bit of a non-zero mask.
[[nodiscard]] CULLKIT_FORCEINLINE int abt_lowest_bit(std::uint32_t m) noexcept { return lowest_bit(m); }

/// Box test against planes[i] for the bits of `mask`, by the rule of `Frustum::classify` term for
/// term. Clears from `mask` the planes the box is inside of; true when it is outside one.
[[nodiscard]] inline bool abt_box_outside(const Plane* planes, std::uint32_t& mask, const Aabb& box) noexcept {
  const glm::vec3 c = (box.min + box.max) * 0.5f;
  const glm::vec3 e = (box.max - box.min) * 0.5f;
  std::uint32_t straddled = mask;
  for (std::uint32_t rest = mask; rest != 0; rest &= rest - 1u) {
    const int i = abt_lowest_bit(rest);
    const Plane& p = planes[i];
    const float dc = glm::dot(p.normal, c) + p.d;
    const float r = std::fabs(p.normal.x) * e.x + std::fabs(p.normal.y) * e.y + std::fabs(p.normal.z) * e.z;
    const float slack = Frustum::tolerance(p, c, r);
    if (dc + r < -slack) return true;
    if (dc - r >= slack) straddled &= ~(std::uint32_t{1} << i);
  }
  mask = straddled;
  return false;
}

/// Sphere test, same rule as `Frustum::classify(Sphere)`; an empty sphere (radius < 0) is outside.
[[nodiscard]] inline bool abt_sphere_outside(const Plane* planes, std::uint32_t& mask, const Sphere& s) noexcept {
  if (!(s.radius >= 0.0f)) return true;
  std::uint32_t straddled = mask;
  for (std::uint32_t rest = mask; rest != 0; rest &= rest - 1u) {
    const int i = abt_lowest_bit(rest);
    const Plane& p = planes[i];
    const float dc = glm::dot(p.normal, s.center) + p.d;
    const float slack = Frustum::tolerance(p, s.center, s.radius);
    if (dc + s.radius < -slack) return true;
    if (dc - s.radius >= slack) straddled &= ~(std::uint32_t{1} << i);
  }
  mask = straddled;
  return false;
}

/// The node test of every top-down walk, in the seed paper's order: the bounding sphere first
/// (cheap; it may settle the whole subtree), then the box.
[[nodiscard]] inline bool abt_node_outside(const Plane* planes, std::uint32_t& mask, const Aabb& box,
                                           const Sphere& sphere) noexcept {
  if (mask == 0) return false;
  if (abt_sphere_outside(planes, mask, sphere)) return true;
  return mask != 0 && abt_box_outside(planes, mask, box);
}

/// Object boxes by position, as six padded float arrays: cx, cy, cz, ex, ey, ez.
class AbtLeafBoxes {
 public:
  static constexpr std::uint32_t lanes = 16;

  void assign(const std::vector<Aabb>& boxes) {
    n_ = static_cast<std::uint32_t>(boxes.size());
    stride_ = n_ + lanes;  // padding: a lane group may run past the last box (zero boxes, ignored)
    data_.assign(std::size_t{stride_} * 6, 0.0f);
    for (std::uint32_t i = 0; i < n_; ++i) set(i, boxes[i]);
  }
  /// One more box at position size(); the columns grow geometrically (amortized O(1)).
  void append(const Aabb& b) {
    if (n_ + 1 + lanes > stride_) {
      const std::uint32_t stride = std::max<std::uint32_t>(2 * stride_, n_ + 1 + lanes);
      std::vector<float> grown(std::size_t{stride} * 6, 0.0f);
      for (std::size_t k = 0; k < 6; ++k)
        std::copy(data_.begin() + std::ptrdiff_t(k * stride_), data_.begin() + std::ptrdiff_t(k * stride_ + n_),
                  grown.begin() + std::ptrdiff_t(k * stride));
      data_.swap(grown);
      stride_ = stride;
    }
    set(n_++, b);
  }
  /// Drops the box at the last position.
  void pop_back() noexcept {
    if (n_ > 0) set(--n_, Aabb{glm::vec3(0.0f), glm::vec3(0.0f)});
  }

  void set(std::uint32_t i, const Aabb& b) {
    const glm::vec3 c = (b.min + b.max) * 0.5f;
    const glm::vec3 e = (b.max - b.min) * 0.5f;
    float* d = data_.data();
    d[i] = c.x;
    d[stride_ + i] = c.y;
    d[2 * std::size_t{stride_} + i] = c.z;
    d[3 * std::size_t{stride_} + i] = e.x;
    d[4 * std::size_t{stride_} + i] = e.y;
    d[5 * std::size_t{stride_} + i] = e.z;
  }

  /// Classifies the 16 boxes at positions [base, base + lanes) against the planes in `mask`
  /// (bit i for planes[i]): bit i of the first result is set when box base + i is outside some
  /// plane, bit i of the second when it is not inside every plane. Lanes past the end are padding.
  CULLKIT_FORCEINLINE void classify_lanes(const Plane* planes, std::uint32_t mask, std::uint32_t base,
                                          std::uint32_t& outside_bits, std::uint32_t& straddle_bits) const noexcept {
    const float* d = data_.data();
    const std::size_t s = stride_;
    constexpr float k = 8.0f * std::numeric_limits<float>::epsilon();  // as Frustum::tolerance
    // 32-bit flags: the same width as the float lanes, so no packing in the vector loop.
    std::uint32_t out[lanes] = {};
    std::uint32_t cross[lanes] = {};
    const float* cx = d + base;
    const float* cy = d + s + base;
    const float* cz = d + 2 * s + base;
    const float* ex = d + 3 * s + base;
    const float* ey = d + 4 * s + base;
    const float* ez = d + 5 * s + base;
    for (std::uint32_t rest = mask; rest != 0; rest &= rest - 1u) {
      const Plane& pl = planes[abt_lowest_bit(rest)];
      const float nx = pl.normal.x, ny = pl.normal.y, nz = pl.normal.z, pd = pl.d;
      const float ax = std::fabs(nx), ay = std::fabs(ny), az = std::fabs(nz), ad = std::fabs(pd);
      for (std::uint32_t i = 0; i < lanes; ++i) {
        const float px = nx * cx[i], py = ny * cy[i], pz = nz * cz[i];
        const float dc = px + py + pz + pd;
        const float r = ax * ex[i] + ay * ey[i] + az * ez[i];
        const float slack = (std::fabs(px) + std::fabs(py) + std::fabs(pz) + ad + r) * k;
        out[i] |= static_cast<std::uint32_t>(dc + r < -slack);
        cross[i] |= static_cast<std::uint32_t>(!(dc - r >= slack));
      }
    }
    std::uint32_t ob = 0, cb = 0;
    for (std::uint32_t i = 0; i < lanes; ++i) {
      ob |= out[i] << i;
      cb |= cross[i] << i;
    }
    outside_bits = ob;
    straddle_bits = cb;
  }

  /// The six columns (cx, cy, cz, ex, ey, ez), each padded by `lanes` zero boxes past the end.
  [[nodiscard]] const float* column(int k) const noexcept { return data_.data() + std::size_t(k) * stride_; }

  /// Calls `emit(position, containment)` for every box in [begin, end) not outside the planes in
  /// `mask` (bit i for planes[i]); returns false as soon as `emit` does.
  template <class Emit>
  bool test(const Plane* planes, std::uint32_t mask, std::uint32_t begin, std::uint32_t end, Emit&& emit) const {
    for (std::uint32_t base = begin; base < end; base += lanes) {
      std::uint32_t out = 0, cross = 0;
      classify_lanes(planes, mask, base, out, cross);
      const std::uint32_t count = end - base < lanes ? end - base : lanes;
      for (std::uint32_t i = 0; i < count; ++i) {
        if ((out >> i) & 1u) continue;
        if (!emit(base + i, ((cross >> i) & 1u) ? Containment::intersecting : Containment::inside)) return false;
      }
    }
    return true;
  }

 private:
  std::vector<float> data_;
  std::uint32_t n_ = 0, stride_ = 0;
};

}  // namespace cullkit::detail
