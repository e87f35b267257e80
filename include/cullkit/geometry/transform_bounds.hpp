// cullkit/geometry/transform_bounds.hpp: world bounds of an object from its local box and matrix.
#pragma once

#include <cmath>
#include <limits>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "aabb.hpp"

namespace cullkit {

/// The tightest axis-aligned box of the 8 corners of `local` moved by `model` (column vectors,
/// GLM layout: world = model * (local, 1)). Computed in double and rounded outward to float: the
/// box holds every corner moved in exact arithmetic up to double rounding (1e-16 relative, far
/// below the culling tests' float slack), and an identity `model` returns `local` unchanged. An affine `model` (bottom row 0 0 0 1) uses the centre/extent form, 2 matrix
/// products; a projective one moves the 8 corners with their divide, and any corner at w <= 0
/// makes the answer invalid.
/// Bad input has a defined answer: a `local` that is not `is_valid`, a non-finite `model`, or a
/// result that overflows float gives a box whose coordinates are NaN (not `is_valid`), which every
/// cullkit container holds as "bounds unknown" and reports by every cull.
/// Cost: O(1), no allocation; thread-safe.
[[nodiscard]] inline Aabb transform_bounds(const Aabb& local, const glm::mat4& model) noexcept {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Aabb bad{glm::vec3(nan), glm::vec3(nan)};
  if (!is_valid(local)) return bad;
  double lo[3], hi[3];
  const bool affine = model[0][3] == 0.0f && model[1][3] == 0.0f && model[2][3] == 0.0f && model[3][3] == 1.0f;
  if (affine) {
    double c[3], e[3];
    for (int a = 0; a < 3; ++a) {
      c[a] = 0.5 * (double(local.min[a]) + double(local.max[a]));
      e[a] = 0.5 * (double(local.max[a]) - double(local.min[a]));
    }
    for (int r = 0; r < 3; ++r) {
      double cr = double(model[3][r]), er = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double m = double(model[k][r]);
        cr += m * c[k];
        er += std::fabs(m) * e[k];
      }
      lo[r] = cr - er;
      hi[r] = cr + er;
    }
  } else {
    for (int r = 0; r < 3; ++r) {
      lo[r] = std::numeric_limits<double>::infinity();
      hi[r] = -lo[r];
    }
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 p = corner(local, i);
      double h[4];
      for (int r = 0; r < 4; ++r)
        h[r] = double(model[0][r]) * p.x + double(model[1][r]) * p.y + double(model[2][r]) * p.z + double(model[3][r]);
      if (!(h[3] > 0.0)) return bad;
      for (int r = 0; r < 3; ++r) {
        const double v = h[r] / h[3];
        lo[r] = std::fmin(lo[r], v);
        hi[r] = std::fmax(hi[r], v);
      }
    }
  }
  Aabb out;
  for (int r = 0; r < 3; ++r) {
    const double l = lo[r], h = hi[r];
    float fl = static_cast<float>(l), fh = static_cast<float>(h);
    if (double(fl) > l) fl = std::nextafter(fl, -std::numeric_limits<float>::infinity());
    if (double(fh) < h) fh = std::nextafter(fh, std::numeric_limits<float>::infinity());
    out.min[r] = fl;
    out.max[r] = fh;
  }
  if (!is_valid(out)) return bad;
  return out;
}

}  // namespace cullkit
