// cullkit/detail/mesh_occlusion/coverage_triangles.hpp: the triangle and edge operations of
// CoverageGrid (coverage.hpp), the walks over the rows one triangle or one outline edge reaches:
// a triangle's depth bounds along its rows, the behind test of one row, and an outline edge's
// crossings and outline marks in one walk of its rows (four rows at a time where the compiler
// targets AVX2, with the scalar walk's operations on the same values, so an edge gives the same
// cells from both its triangles and in every build).
// Included by coverage.hpp after the class; not on its own.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "coverage.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

inline CellRect CoverageGrid::add_depth(const double* x, const double* y, const double* w, const TriangleEdges& edges) {
  const double xmin = std::min(std::min(x[0], x[1]), x[2]), xmax = std::max(std::max(x[0], x[1]), x[2]);
  const double ymin = std::min(std::min(y[0], y[1]), y[2]), ymax = std::max(std::max(y[0], y[1]), y[2]);
  const double m = cell_margin(std::max(std::max(std::fabs(xmin), std::fabs(xmax)), std::max(std::fabs(ymin), std::fabs(ymax))));
  CellRect r{width_, height_, -1, -1};
  if (xmax + m < 0.0 || xmin - m >= width_ || ymax + m < 0.0 || ymin - m >= height_) return r;
  r = CellRect{clamp_cell(xmin - m, width_), clamp_cell(ymin - m, height_), clamp_cell(xmax + m, width_),
               clamp_cell(ymax + m, height_)};
  // The plane's bound is set up on all the triangle's cells, whatever rows are worked on, so that a
  // row's bounds are the same bits in a strip of rows as in the whole grid.
  const CellRect all = r;
  if (!window_rows(r)) return r;
  // Depth bounds alone never make a cell covered (counts and outline marks do, and those mark
  // their rows for end_band), so rows are not marked here; the bounds only need clearing later.
  grow(dirty_, r);
  // Every point of the triangle has w <= its largest corner w: 1/w >= lowest.
  const double w_max = std::max(std::max(w[0], w[1]), w[2]);
  const float lowest = static_cast<float>((1.0 / w_max) * (1.0 - 0x1p-20));
  // 1/w is affine over the screen for a plane: inside a cell, 1/w >= its value at the cell corner
  // that minimizes it. Worth it for big triangles seen at a slant (floors, long walls).
  const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  const double extent = std::max(xmax - xmin, ymax - ymin);
  const int cells = (all.x1 - all.x0 + 1) * (all.y1 - all.y0 + 1);
  if (cells > 4 && std::fabs(area2) > 1e-6 * extent * extent) {
    const double inv[3] = {1.0 / w[0], 1.0 / w[1], 1.0 / w[2]};
    const double a = ((inv[1] - inv[0]) * (y[2] - y[0]) - (inv[2] - inv[0]) * (y[1] - y[0])) / area2;
    const double b = ((x[1] - x[0]) * (inv[2] - inv[0]) - (x[2] - x[0]) * (inv[1] - inv[0])) / area2;
    // Value at the minimizing corner of cell (all.x0, all.y0); then a per column, b per row.
    const double v00 = inv[0] + a * (all.x0 + (a < 0.0 ? 1.0 : 0.0) - x[0]) + b * (all.y0 + (b < 0.0 ? 1.0 : 0.0) - y[0]);
    const double span = std::fabs(a) * (all.x1 - all.x0 + 1) + std::fabs(b) * (all.y1 - all.y0 + 1);
    // Rounding of the solve (relative to the values, amplified by a thin triangle) and of the
    // float loop below.
    const double inv_max = std::max(std::max(inv[0], inv[1]), inv[2]);
    const double err = 0x1p-19 * (std::fabs(v00) + span + inv_max) +
                       1e-12 * inv_max * (1.0 + extent * extent / std::fabs(area2));
    const float af = static_cast<float>(a), bf = static_cast<float>(b);
    const float v00f = static_cast<float>(v00 - err);
    for_each_row_span(edges, r, m, [&](int j, int i0, int i1) {
      float* row = bound_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      const float start = v00f + bf * static_cast<float>(j - all.y0);
      lower_row_sloped(row, i0, i1, i0 - all.x0, start, af, lowest);
    });
  } else {
    for_each_row_span(edges, r, m, [&](int j, int i0, int i1) {
      float* row = bound_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      lower_row_flat(row, i0, i1, lowest);
    });
  }
  return r;
}

inline bool CoverageGrid::row_behind(const float* row, int i0, int i1, int step0, double start, double a, double highest) {
  int i = i0;
#if CULLKIT_COVERAGE_AVX2
  const __m256d a4 = _mm256_set1_pd(a), start4 = _mm256_set1_pd(start), highest4 = _mm256_set1_pd(highest);
  const __m256d zero = _mm256_setzero_pd(), four = _mm256_set1_pd(4.0);
  const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
  __m256d steps = _mm256_cvtepi32_pd(_mm_add_epi32(_mm_set1_epi32(step0), lane));
  for (;;) {
    // std::min(highest, v) is v when v < highest, else highest (NaN included): min_pd(v, highest).
    const __m256d upper = _mm256_min_pd(mul_add(a4, steps, start4), highest4);
    const __m128i lanes = _mm_cmpgt_epi32(_mm_set1_epi32(i1 - i + 1), lane);
    const __m256d depth = _mm256_cvtps_pd(_mm_maskload_ps(row + i, lanes));
    const __m256d behind = _mm256_and_pd(_mm256_cmp_pd(upper, zero, _CMP_GT_OQ), _mm256_cmp_pd(depth, upper, _CMP_GT_OQ));
    const int wanted = _mm_movemask_ps(_mm_castsi128_ps(lanes));
    if ((_mm256_movemask_pd(behind) & wanted) != wanted) return false;
    if (i + 3 >= i1) return true;
    i += 4;
    steps = _mm256_add_pd(steps, four);
  }
#else
  for (; i <= i1; ++i) {
    const double upper = std::min(highest, start + a * (step0 + (i - i0)));
    if (!(upper > 0.0 && static_cast<double>(row[i]) > upper)) return false;
  }
  return true;
#endif
}

inline void CoverageGrid::crossing_rows(double ya, double yb, int& j0, int& j1) const {
  j0 = static_cast<int>(std::max(-1.0, std::min(double(height_), std::ceil(ya - 0.5))));
  j1 = static_cast<int>(std::max(-1.0, std::min(double(height_), std::ceil(yb - 0.5)))) - 1;
  while (j0 > 0 && j0 - 0.5 >= ya) --j0;
  while (j0 < height_ && j0 + 0.5 < ya) ++j0;
  while (j1 + 1 < height_ && j1 + 1.5 < yb) ++j1;
  while (j1 >= 0 && j1 + 0.5 >= yb) --j1;
  j0 = std::max(j0, row_first_);
  j1 = std::min(j1, row_last_);
}

inline int CoverageGrid::crossing_cell(double xa, double ya, double slope, int j) const {
  const double x = xa + (j + 0.5 - ya) * slope;
  const double k = std::floor(x + 0.5);
  if (k >= width_) return -1;
  return k < 0.0 ? 0 : static_cast<int>(k);
}

inline void CoverageGrid::walk_edge(double x_from, double y_from, double x_to, double y_to, int orient, int delta, int crossing) {
  double xa = x_from, ya = y_from, xb = x_to, yb = y_to;
  int side = orient;
  if (ya > yb || (ya == yb && xa > xb)) {
    std::swap(xa, xb);
    std::swap(ya, yb);
    side = -side;
  }
  walk_sorted_edge(xa, ya, xb, yb, yb - ya > 0.0 ? (xb - xa) / (yb - ya) : 0.0, side, delta, crossing);
}

inline void CoverageGrid::walk_sorted_edge(double xa, double ya, double xb, double yb, double slope, int side, int delta, int crossing) {
  const double dx = xb - xa, dy = yb - ya;
  int c0 = 0, c1 = -1;  // the crossings' rows
  if (crossing != 0 && ya < yb) crossing_rows(ya, yb, c0, c1);
  const double magnitude = std::max(std::max(std::fabs(xa), std::fabs(xb)), std::max(std::fabs(ya), std::fabs(yb)));
  const double m = cell_margin(magnitude);
  int t0 = std::max(row_first_, clamp_cell(ya - m, height_)), t1 = std::min(row_last_, clamp_cell(yb + m, height_));
  if (yb + m < 0.0 || ya - m >= height_) t1 = t0 - 1;  // the outline marks' rows
  if (c0 > c1 && t0 > t1) return;
  // |orient2d| below this: the centre is within about 2^-20 cells (plus rounding) of the line.
  const double near_line = (0x1p-20 + 0x1p-40 * magnitude) * (std::fabs(dx) + std::fabs(dy));
  const double rounding = 0x1p-48 * (std::fabs(dx) + std::fabs(dy));
  const int first = c0 > c1 ? t0 : t0 > t1 ? c0 : std::min(c0, t0);
  const int last = c0 > c1 ? t1 : t0 > t1 ? c1 : std::max(c1, t1);
  const EdgeRow e{xa, ya, xb, yb, dy, slope, m};
  // Row j's work: `cell` its crossing's cell (add_crossings'; below 0: none), [i0, i1] the cells
  // its outline marks reach (touch_edge's, before the covered ones are left out; empty: none).
  const auto row_work = [&](int j, int cell, int i0, int i1) {
    int lo = width_, hi = -1;  // the cells to mark
    if (j >= c0 && j <= c1 && cell >= 0) {
      lo = hi = cell;
      band_crossings_ = true;
      diff_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(cell)] += crossing;
    }
    // A covered cell never changes again: its outline counter no longer matters (an edge that
    // leaves the outline later skips it too, as it is still covered then).
    if (j >= t0 && j <= t1 && i0 <= i1 && unfrozen_span(j, i0, i1)) {
      lo = std::min(lo, i0);
      hi = std::max(hi, i1);
      std::int32_t* row = net_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      touch_centres(row, i0, i1, EdgeSides{xa, j + 0.5 - ya, dx, dy, near_line, rounding, side, delta});
    }
    if (hi >= 0) mark(j, lo, hi);
  };
#if CULLKIT_COVERAGE_AVX2
  for (int j = first; j <= last; j += 4) {
    int cell[4], i0[4], i1[4];
    edge_rows4(e, j, cell, i0, i1);
    const int rows = std::min(4, last - j + 1);
    for (int q = 0; q < rows; ++q) row_work(j + q, cell[q], i0[q], i1[q]);
  }
#else
  for (int j = first; j <= last; ++j) {
    int i0 = 0, i1 = -1;
    if (j >= t0 && j <= t1) touch_span(j, e, i0, i1);
    row_work(j, j >= c0 && j <= c1 ? crossing_cell(xa, ya, slope, j) : -1, i0, i1);
  }
#endif
}

inline void CoverageGrid::touch_span(int j, const EdgeRow& e, int& i0, int& i1) const {
  const double m = e.m;
  double xl = e.xa, xr = e.xb;
  if (e.dy > 0.0) {
    const double y0 = std::max(e.ya, j - m), y1 = std::min(e.yb, j + 1 + m);
    xl = e.xa + (y0 - e.ya) * e.slope;
    xr = e.xa + (y1 - e.ya) * e.slope;
    if (xl > xr) std::swap(xl, xr);
  } else if (xl > xr) {
    std::swap(xl, xr);
  }
  if (xr + m < 0.0 || xl - m >= width_) return;
  i0 = clamp_cell(xl - m, width_);
  i1 = clamp_cell(xr + m, width_);
}

#if CULLKIT_COVERAGE_AVX2
inline void CoverageGrid::edge_rows4(const EdgeRow& e, int j, int* cell, int* i0, int* i1) const {
  const __m256d rows = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(j)), _mm256_setr_pd(0.0, 1.0, 2.0, 3.0));
  const __m256d xa = _mm256_set1_pd(e.xa), ya = _mm256_set1_pd(e.ya), slope = _mm256_set1_pd(e.slope);
  const __m256d half = _mm256_set1_pd(0.5), zero = _mm256_setzero_pd(), w = _mm256_set1_pd(static_cast<double>(width_));
  // crossing_cell: x = xa + (j + 0.5 - ya) * slope, k = floor(x + 0.5); -1 from the width on, 0
  // below 0 (-0.0 included), else k.
  const __m256d x = mul_add(_mm256_sub_pd(_mm256_add_pd(rows, half), ya), slope, xa);
  const __m256d k = _mm256_floor_pd(_mm256_add_pd(x, half));
  const __m256d past = _mm256_cmp_pd(k, w, _CMP_GE_OQ);
  const __m256d crossing = _mm256_blendv_pd(_mm256_min_pd(_mm256_max_pd(k, zero), w), _mm256_set1_pd(-1.0), past);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(cell), _mm256_cvttpd_epi32(crossing));
  // touch_span: std::max(ya, j - m) is (j - m > ya ? j - m : ya) and std::min(yb, j + 1 + m) is
  // (j + 1 + m < yb ? j + 1 + m : yb) for these values: max_pd and min_pd with the row first.
  const __m256d m = _mm256_set1_pd(e.m);
  __m256d xl, xr;
  if (e.dy > 0.0) {
    const __m256d y0 = _mm256_max_pd(_mm256_sub_pd(rows, m), ya);
    const __m256d y1 = _mm256_min_pd(_mm256_add_pd(_mm256_add_pd(rows, _mm256_set1_pd(1.0)), m), _mm256_set1_pd(e.yb));
    const __m256d x0 = mul_add(_mm256_sub_pd(y0, ya), slope, xa), x1 = mul_add(_mm256_sub_pd(y1, ya), slope, xa);
    // The swap when x0 > x1: the smaller first (equal values are the same value).
    xl = _mm256_min_pd(x1, x0);
    xr = _mm256_max_pd(x1, x0);
  } else {
    xl = _mm256_set1_pd(std::min(e.xa, e.xb));
    xr = _mm256_set1_pd(std::max(e.xa, e.xb));
  }
  const __m256d left = _mm256_sub_pd(xl, m), right = _mm256_add_pd(xr, m);
  // `xr + m < 0.0 || xl - m >= width_` misses the row.
  const __m256d meets = _mm256_and_pd(_mm256_cmp_pd(right, zero, _CMP_NLT_UQ), _mm256_cmp_pd(left, w, _CMP_NGE_UQ));
  // clamp_cell: below 0 (or NaN) gives 0, from width - 1 on gives width - 1, else truncated.
  const __m256d top = _mm256_set1_pd(static_cast<double>(width_ - 1));
  const __m256d first = _mm256_blendv_pd(zero, _mm256_min_pd(_mm256_max_pd(left, zero), top), meets);
  const __m256d last = _mm256_blendv_pd(_mm256_set1_pd(-1.0), _mm256_min_pd(_mm256_max_pd(right, zero), top), meets);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(i0), _mm256_cvttpd_epi32(first));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(i1), _mm256_cvttpd_epi32(last));
}
#endif

inline void CoverageGrid::add_crossings(double xa, double ya, double xb, double yb, int sign) {
  int j0, j1;
  crossing_rows(ya, yb, j0, j1);
  const double slope = (xb - xa) / (yb - ya);
  for (int j = j0; j <= j1; ++j) {
    const int i = crossing_cell(xa, ya, slope, j);
    if (i < 0) continue;
    mark(j, i, i);
    band_crossings_ = true;
    diff_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i)] += sign;
  }
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
