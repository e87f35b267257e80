// bench/soa_scan.hpp: the brute-force peer. Boxes stored as six float arrays (structure of
// arrays); each plane is tested against every box in a branchless loop the compiler vectorizes.
// This is what a renderer writes when it has no hierarchy, and the baseline every tree must beat.
#pragma once

#include <cstdint>
#include <vector>

#include <cullkit/geometry.hpp>

namespace cullkit_bench {

class SoaBoxes {
 public:
  explicit SoaBoxes(const std::vector<cullkit::Aabb>& boxes) {
    const std::size_t n = boxes.size();
    for (auto* v : {&cx_, &cy_, &cz_, &ex_, &ey_, &ez_}) v->resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3 c = boxes[i].center(), e = boxes[i].extent() * 0.5f;
      cx_[i] = c.x; cy_[i] = c.y; cz_[i] = c.z;
      ex_[i] = e.x; ey_[i] = e.y; ez_[i] = e.z;
    }
    flags_.resize(n);
  }
  [[nodiscard]] std::size_t size() const { return cx_.size(); }

  /// Writes the index of every box not rejected by a plane into `out` (same conservative rule as
  /// cullkit::Frustum, without the rounding slack: the peer is allowed to be a little faster).
  void cull(const cullkit::Frustum& f, std::vector<std::uint32_t>& out) {
    const std::size_t n = size();
    std::uint8_t* flag = flags_.data();
    for (std::size_t i = 0; i < n; ++i) flag[i] = 1;
    for (int p = 0; p < cullkit::Frustum::max_planes; ++p) {
      if (!f.has_plane(p)) continue;
      const cullkit::Plane pl = f.plane(p);
      const float nx = pl.normal.x, ny = pl.normal.y, nz = pl.normal.z, d = pl.d;
      const float ax = nx < 0 ? -nx : nx, ay = ny < 0 ? -ny : ny, az = nz < 0 ? -nz : nz;
      const float *cx = cx_.data(), *cy = cy_.data(), *cz = cz_.data();
      const float *ex = ex_.data(), *ey = ey_.data(), *ez = ez_.data();
      for (std::size_t i = 0; i < n; ++i) {
        const float dist = nx * cx[i] + ny * cy[i] + nz * cz[i] + d;
        const float r = ax * ex[i] + ay * ey[i] + az * ez[i];
        flag[i] &= static_cast<std::uint8_t>(dist + r >= 0.0f);
      }
    }
    out.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (flag[i]) out.push_back(static_cast<std::uint32_t>(i));
    }
  }

 private:
  std::vector<float> cx_, cy_, cz_, ex_, ey_, ez_;
  std::vector<std::uint8_t> flags_;
};

}  // namespace cullkit_bench
