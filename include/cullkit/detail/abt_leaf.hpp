// cullkit/detail/abt_leaf.hpp: the per-object test inside a straddling AdaptiveBinaryTree leaf,
// over boxes stored as structure-of-arrays (centers and half extents), a fixed number of lanes at
// a time so the compiler vectorizes the plane loop. Users never name this.
//
// The rule is Frustum::classify's, term for term: a box is outside a plane when the farthest
// corner along the normal, dot(n, c) + d + r, is below -slack, and inside it when the nearest,
// dot(n, c) + d - r, is at least slack, with slack = Frustum::tolerance(plane, c, r). Centers and
// half extents are rounded exactly as Frustum::classify rounds them.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../geometry/aabb.hpp"
#include "../geometry/frustum.hpp"

namespace cullkit::detail {

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

  /// Calls `emit(position, containment)` for every box in [begin, end) not outside the planes in
  /// `mask`; returns false as soon as `emit` does.
  template <class Emit>
  bool test(const Frustum& frustum, PlaneMask mask, std::uint32_t begin, std::uint32_t end, Emit&& emit) const {
    const float* d = data_.data();
    const std::size_t s = stride_;
    constexpr float k = 8.0f * std::numeric_limits<float>::epsilon();  // as Frustum::tolerance
    for (std::uint32_t base = begin; base < end; base += lanes) {
      // 32-bit flags: the same width as the float lanes, so no packing in the vector loop.
      std::uint32_t out[lanes] = {};
      std::uint32_t cross[lanes] = {};
      const float* cx = d + base;
      const float* cy = d + s + base;
      const float* cz = d + 2 * s + base;
      const float* ex = d + 3 * s + base;
      const float* ey = d + 4 * s + base;
      const float* ez = d + 5 * s + base;
      for (int p = 0; p < Frustum::max_planes; ++p) {
        if (!((mask >> p) & 1u)) continue;
        const Plane& pl = frustum.plane(p);
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
      const std::uint32_t count = end - base < lanes ? end - base : lanes;
      for (std::uint32_t i = 0; i < count; ++i) {
        if (out[i]) continue;
        if (!emit(base + i, cross[i] ? Containment::intersecting : Containment::inside)) return false;
      }
    }
    return true;
  }

 private:
  std::vector<float> data_;
  std::uint32_t n_ = 0, stride_ = 0;
};

}  // namespace cullkit::detail
