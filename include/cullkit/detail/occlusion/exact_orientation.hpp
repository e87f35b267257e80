// cullkit/detail/occlusion/exact_orientation.hpp: the exact orientation of four float points, for
// OcclusionTree's seams (not public API).
//
// The tree must know for certain whether two occluder edges span the same plane through the eye
// (collinear edges of a regular grid), and how the planes through the eye and one mesh corner turn
// around it. Rounding must not decide either, so the determinant is summed exactly when a
// double-precision estimate cannot tell its sign: each of its terms p_i * q_j * r_k is a float product
// (exact in double) times a float, split into a rounded part and its exact error by a fused
// multiply-add; the parts are added without loss into a floating-point expansion (non-overlapping
// parts of increasing magnitude), whose largest part has the sign of the sum. Products of floats
// never overflow nor underflow in double (|x| < 2^128 and >= 2^-149 give products within
// 2^-447..2^384), so the result is exact for every finite input.
#pragma once

#include <cmath>

#include <glm/vec3.hpp>

namespace cullkit::detail {

/// A sum of doubles kept exactly, as parts of increasing magnitude that do not overlap.
class ExactSum {
 public:
  /// Adds `x` exactly.
  void add(double x) noexcept {
    int kept = 0;
    double q = x;
    for (int i = 0; i < count_; ++i) {
      // Knuth's two-sum: s + err == q + parts_[i] exactly.
      const double s = q + parts_[i];
      const double bv = s - q;
      const double av = s - bv;
      const double err = (q - av) + (parts_[i] - bv);
      q = s;
      if (err != 0.0) parts_[kept++] = err;
    }
    if (q != 0.0) parts_[kept++] = q;
    count_ = kept;
  }
  /// Adds the product of `x` and `y` exactly.
  void add_product(double x, double y) noexcept {
    const double p = x * y;
    add(std::fma(x, y, -p));
    add(p);
  }
  /// -1, 0 or 1: the sign of the exact sum.
  [[nodiscard]] int sign() const noexcept {
    if (count_ == 0) return 0;
    return parts_[count_ - 1] > 0.0 ? 1 : -1;
  }

 private:
  static constexpr int capacity = 48;  // 24 products, each adding at most two parts
  double parts_[capacity] = {};
  int count_ = 0;
};

/// The exact sign (-1, 0 or 1) of det[a - e; b - e; c - e] for finite float points: the orientation
/// of the tetrahedron (e, a, b, c), 0 exactly when the four points lie in one plane. By linearity in
/// each row it is det[a; b; c] - det[e; b; c] - det[a; e; c] - det[a; b; e], 24 products of three
/// floats. A double-precision sum with an error bound decides almost every call; only a sum too
/// close to 0 is done exactly.
[[nodiscard]] inline int orientation_sign(const glm::vec3& e, const glm::vec3& a, const glm::vec3& b,
                                          const glm::vec3& c) noexcept {
  const glm::vec3* rows[4][3] = {{&a, &b, &c}, {&e, &b, &c}, {&a, &e, &c}, {&a, &b, &e}};
  const double row_sign[4] = {1.0, -1.0, -1.0, -1.0};
  // The six terms of det[p; q; r]: p_i q_j r_k with the sign of the permutation (i, j, k).
  static constexpr int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
  double pairs[24], thirds[24];
  double sum = 0.0, magnitude = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int t = 0; t < 6; ++t) {
      const glm::vec3& p = *rows[r][0];
      const glm::vec3& q = *rows[r][1];
      const glm::vec3& w = *rows[r][2];
      const double sign = t < 3 ? row_sign[r] : -row_sign[r];
      const int k = r * 6 + t;
      pairs[k] = sign * double(p[perm[t][0]]) * double(q[perm[t][1]]);  // exact: float * float
      thirds[k] = double(w[perm[t][2]]);
      const double term = pairs[k] * thirds[k];  // one rounding: relative error <= 2^-53
      sum += term;
      magnitude += std::fabs(term);
    }
  // 24 terms, each rounded once, summed with 23 more roundings: the error is below 48 * 2^-53 of the
  // magnitude; 1e-13 leaves room to spare (and covers magnitudes near the underflow range).
  if (std::fabs(sum) > 1e-13 * magnitude + 1e-290) return sum > 0.0 ? 1 : -1;
  ExactSum exact;
  for (int k = 0; k < 24; ++k) exact.add_product(pairs[k], thirds[k]);
  return exact.sign();
}

}  // namespace cullkit::detail
