// cullkit/detail/nci/overlap.hpp: exact triangle/box overlap by separating axes (the 13 axes of
// Akenine-Moeller's test), evaluated in double. The NormalClassIndex calls it with cells already
// inflated, so float rounding in the caller's data can only add cells, never drop one.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace cullkit::detail {

/// True if the closed box (centre `center`, half extents `half`) and the triangle `v` overlap or
/// touch. No separating axis found means overlap; NaN input reports overlap (callers reject it first).
[[nodiscard]] inline bool triangle_box_overlap(const double center[3], const double half[3],
                                               const double tri[3][3]) noexcept {
  double v[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) v[i][k] = tri[i][k] - center[k];

  // Box face normals: the triangle's bounds against the box.
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min({v[0][k], v[1][k], v[2][k]});
    const double hi = std::max({v[0][k], v[1][k], v[2][k]});
    if (lo > half[k] || hi < -half[k]) return false;
  }

  double e[3][3];
  for (int k = 0; k < 3; ++k) {
    e[0][k] = v[1][k] - v[0][k];
    e[1][k] = v[2][k] - v[1][k];
    e[2][k] = v[0][k] - v[2][k];
  }

  // The nine cross products of box axes and triangle edges.
  for (int i = 0; i < 3; ++i) {      // edge
    for (int a = 0; a < 3; ++a) {    // box axis
      // axis = unit(a) x e[i]
      double axis[3] = {0, 0, 0};
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      axis[b] = -e[i][c];
      axis[c] = e[i][b];
      const double p0 = axis[0] * v[0][0] + axis[1] * v[0][1] + axis[2] * v[0][2];
      const double p1 = axis[0] * v[1][0] + axis[1] * v[1][1] + axis[2] * v[1][2];
      const double p2 = axis[0] * v[2][0] + axis[1] * v[2][1] + axis[2] * v[2][2];
      const double r = half[0] * std::fabs(axis[0]) + half[1] * std::fabs(axis[1]) + half[2] * std::fabs(axis[2]);
      const double lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2});
      if (lo > r || hi < -r) return false;
    }
  }

  // The triangle's plane.
  const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                       e[0][0] * e[1][1] - e[0][1] * e[1][0]};
  const double d = n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2];
  const double r = half[0] * std::fabs(n[0]) + half[1] * std::fabs(n[1]) + half[2] * std::fabs(n[2]);
  if (d > r || d < -r) return false;
  return true;
}

/// Morton code (10 bits per axis, x lowest) of a point given in [0, 1]^3: orders a cell's
/// triangles so that consecutive ones lie close together.
[[nodiscard]] inline std::uint32_t nci_morton(const double u[3]) noexcept {
  std::uint32_t code = 0;
  for (int a = 0; a < 3; ++a) {
    const double q = std::clamp(u[a], 0.0, 1.0) * 1024.0;
    const std::uint32_t v = std::min<std::uint32_t>(1023u, static_cast<std::uint32_t>(q));
    for (int b = 0; b < 10; ++b) code |= ((v >> b) & 1u) << (3 * b + a);
  }
  return code;
}

}  // namespace cullkit::detail
