// cullkit/detail/mesh_occlusion/coverage.hpp: the coverage grid. Occluder triangles go in by
// bands (one occluder object each); a cell is covered once the union of the triangles so far covers
// all of it, and then keeps a bound on the depth at which every ray through it meets an occluder.
//
// Why the union and not each triangle: for triangles that all face the eye, the number of them
// covering a point equals the winding number of their edges around it, and an edge used by two of
// them in opposite directions contributes nothing. So only the outline edges (the uncancelled
// ones) matter: a cell that no outline edge touches has one count over all its area, and if that
// count is at least one, every point of the cell is covered; a cell that outline edges cross is
// covered when the count at its centre exceeds the number of those edges it could fall by (see
// `touch_edge`). Counts are exact integers, added and removed by the same arithmetic on the same
// inputs, so two triangles sharing an edge leave no seam.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../../config.hpp"
#include "../bits.hpp"
#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif
// Where the compiler targets AVX2 (-march), the per-cell loops run eight cells at a time; SSE2 is
// the floor. Both widths make the same comparisons and the same float operations as the scalar
// loops they replace, so what these loops compute does not depend on the width taken.
#if CULLKIT_HAS_SSE2 && defined(__AVX2__)
#define CULLKIT_COVERAGE_AVX2 1
#include <immintrin.h>
#else
#define CULLKIT_COVERAGE_AVX2 0
#endif

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// A cell rectangle, inclusive, within the grid; empty when x0 > x1.
struct CellRect {
  int x0, y0, x1, y1;
  [[nodiscard]] bool empty() const { return x0 > x1 || y0 > y1; }
};

/// Margin (in cells) added around edges and boxes: it absorbs the double-precision rounding of
/// projected coordinates, which grows with their size (off-screen corners can be far away).
inline double cell_margin(double magnitude) { return 1.0 / 1024.0 + 0x1p-36 * magnitude; }

/// The grid's cells and their state. All arrays are width * height, row-major, row 0 at the top.
class CoverageGrid {
 public:
  /// Sizes the grid (a no-op when the size is unchanged) and leaves it empty.
  void reset(int width, int height) {
    if (width != width_ || height != height_) {
      width_ = width;
      height_ = height;
      const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
      net_.assign(n, 0);
      diff_.assign(n, 0);
      bound_.assign(n, std::numeric_limits<float>::infinity());
      depth_.assign(n, 0.0f);
      tiles_x_ = (width + tile - 1) / tile;
      tiles_y_ = (height + tile - 1) / tile;
      tile_depth_.assign(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_), 0.0f);
      words_ = (width + 63) / 64;
      frozen_bits_.assign(static_cast<std::size_t>(words_) * static_cast<std::size_t>(height), 0);
      band_lo_.assign(static_cast<std::size_t>(height), width);
      band_hi_.assign(static_cast<std::size_t>(height), -1);
      band_rows_.assign(static_cast<std::size_t>(height), 0);
      used_lo_.assign(static_cast<std::size_t>(height), width);
      used_hi_.assign(static_cast<std::size_t>(height), -1);
      used_rows_.assign(static_cast<std::size_t>(height), 0);
      used_row_count_ = 0;
      band_row_count_ = 0;
      band_crossings_ = false;
      dirty_ = CellRect{width, height, -1, -1};
      row_first_ = 0;
      row_last_ = height - 1;
      return;
    }
    clear_dirty();
    row_first_ = 0;
    row_last_ = height_ - 1;
  }

  /// Limits the grid's work to rows [first, last] (full-height row numbers, within the grid; the
  /// whole grid after `reset`): counts, outline marks, depth bounds, seeding and the covered test
  /// of `all_frozen` clamp to them, every other row is left as it is. Every per-cell operation
  /// depends on its own row only, so rows [first, last] end as the same operations on the whole
  /// grid would leave them.
  void set_rows(int first, int last) {
    row_first_ = std::max(first, 0);
    row_last_ = std::min(last, height_ - 1);
  }

  /// Copies the rows `from` (a grid of the same size) has used since it was last reset, counts,
  /// bounds, depths and covered bits, into this grid, which must not have used them. The rows of a
  /// strip inserted into a grid of its own join the frame's grid so.
  void take_rows(const CoverageGrid& from) {
    copy_rows(from);
    adopt_rows(from);
  }

  /// take_rows' cells alone: writes nothing of this grid outside the rows `from` used, so it may run
  /// while another thread works on this grid's other rows. adopt_rows must follow before this grid
  /// is read or cleared as a whole.
  void copy_rows(const CoverageGrid& from) {
    for (int n = 0; n < from.used_row_count_; ++n) {
      const int j = from.used_rows_[static_cast<std::size_t>(n)];
      const int lo = from.used_lo_[static_cast<std::size_t>(j)], hi = from.used_hi_[static_cast<std::size_t>(j)];
      const auto b = static_cast<std::ptrdiff_t>(j) * width_ + lo, e = static_cast<std::ptrdiff_t>(j) * width_ + hi + 1;
      std::copy(from.net_.begin() + b, from.net_.begin() + e, net_.begin() + b);
      std::copy(from.bound_.begin() + b, from.bound_.begin() + e, bound_.begin() + b);
      std::copy(from.depth_.begin() + b, from.depth_.begin() + e, depth_.begin() + b);
      const auto words = static_cast<std::ptrdiff_t>(j) * words_;
      std::copy(from.frozen_bits_.begin() + words, from.frozen_bits_.begin() + words + words_, frozen_bits_.begin() + words);
    }
  }

  /// take_rows' bookkeeping alone, after copy_rows: the rows `from` used become this grid's used
  /// rows (what a later clear and the used-row tests go by).
  void adopt_rows(const CoverageGrid& from) {
    for (int n = 0; n < from.used_row_count_; ++n) {
      const int j = from.used_rows_[static_cast<std::size_t>(n)];
      const int lo = from.used_lo_[static_cast<std::size_t>(j)], hi = from.used_hi_[static_cast<std::size_t>(j)];
      use(j, lo, hi);
      grow(dirty_, CellRect{lo, j, hi, j});
    }
  }

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }


  /// Adds a front-facing triangle's count: `sign` is +1 or -1 so that the triangle counts +1 inside.
  /// (x, y) are grid coordinates of the corners in the triangle's own order. Edges whose bit is set
  /// in `skip` (bit k: corner k to the next) are left out: the caller passes the edges that the
  /// same band's other triangles also leave out, whose crossings would cancel exactly.
  void add_count(const double* x, const double* y, int sign, unsigned skip = 0) {
    for (int k = 0; k < 3; ++k) {
      if ((skip >> k) & 1u) continue;
      const int l = k == 2 ? 0 : k + 1;
      // An edge's crossings are computed from its endpoints sorted by y, so the same edge seen from
      // its two triangles gives bit-identical crossings (and opposite signs).
      if (y[k] == y[l]) continue;
      const bool down = y[l] > y[k];
      add_crossings(down ? x[k] : x[l], down ? y[k] : y[l], down ? x[l] : x[k], down ? y[l] : y[k],
                    down ? -sign : sign);
    }
  }

  /// An outline edge joins (delta +1) or leaves (delta -1) the outline: `from` -> `to` as its own
  /// triangle runs, `orient` the sign of front-facing areas. Every cell the segment touches (with a
  /// margin) whose centre lies on the edge's inner side (towards its triangle) gets `delta` added
  /// to its outline counter, which is kept subtracted from the cell's count (`net_`); where the
  /// side is too close to call, 2 * delta. The arithmetic runs on the endpoints sorted, so the
  /// edge's removal gives back exactly what its addition took.
  ///
  /// Why the inner side only: a segment from the cell centre to any point of the cell crosses each
  /// outline edge at most once, and crossing an edge changes the count by one: down when leaving its
  /// inner side, up otherwise. So the count anywhere in the cell is at least the count at the centre
  /// minus this counter (an edge near the centre may also have put the centre's count off by one:
  /// hence the double weight there).
  void touch_edge(double x_from, double y_from, double x_to, double y_to, int orient, int delta) {
    walk_edge(x_from, y_from, x_to, y_to, orient, delta, 0);
  }

  /// The outline edge from corner k to corner l of a front-facing triangle or polygon (x, y), as
  /// add_count(x, y, orient) gives that edge's crossings and then touch_edge(k -> l, orient, +1)
  /// or, when `leaves` (its twin, in an earlier band, is on the outline), touch_edge(l -> k, orient,
  /// -1) would make it: the same counts, marks and bits, in one walk of the edge's rows with one
  /// setup.
  void add_outline_edge(const double* x, const double* y, int k, int l, int orient, bool leaves) {
    // add_count's sign for the edge's crossings (counted from its lower endpoint up).
    const int crossing = y[l] > y[k] ? -orient : orient;
    if (leaves) walk_edge(x[l], y[l], x[k], y[k], orient, -1, crossing);
    else walk_edge(x[k], y[k], x[l], y[l], orient, 1, crossing);
  }

  /// Lowers the running depth bound of every cell the triangle's box touches to what this
  /// triangle allows there: inverse depth, so the bound kept is a minimum. Returns the cells.
  CellRect add_depth(const double* x, const double* y, const double* w) { return add_depth(x, y, w, edges_of(x, y)); }

  /// Inserts a front-facing triangle as add_depth(x, y, w) and then add_outline_edge(x, y, k, l,
  /// orient, bit k of `leaves`) for each edge k (corner k to the next, l) not in `inner` would: the
  /// same cells and bits, with the triangle's edges sorted and their slopes divided once for both.
  /// Returns add_depth's cells.
  CellRect add_triangle(const double* x, const double* y, const double* w, int orient, unsigned inner, unsigned leaves) {
    const TriangleEdges edges = edges_of(x, y);
    const CellRect r = add_depth(x, y, w, edges);
    for (int k = 0; k < 3; ++k) {
      if ((inner >> k) & 1u) continue;
      const int l = k == 2 ? 0 : k + 1;
      const bool leaves_k = (leaves >> k) & 1u;
      // An edge that is not level is sorted by y alike here and in edges_of (a level edge, or one
      // with a NaN end, is sorted by x too: add_outline_edge sorts it).
      if (!(y[k] < y[l] || y[k] > y[l])) {
        add_outline_edge(x, y, k, l, orient, leaves_k);
        continue;
      }
      // touch_edge's side: `orient` for an edge run upwards (y growing) as given, flipped otherwise.
      const bool up = leaves_k ? y[l] < y[k] : y[k] < y[l];
      walk_sorted_edge(edges.xa[k], edges.ya[k], edges.xb[k], edges.yb[k], edges.slope[k], up ? orient : -orient,
                       leaves_k ? -1 : 1, y[l] > y[k] ? -orient : orient);
    }
    return r;
  }

  /// Ends a band (the triangles added since the last end): accumulates its counts and freezes the
  /// cells it newly covered at their running bound. Only the cells the band changed are visited.
  /// Returns how many cells it covered.
  std::size_t end_band() {
    std::size_t covered = 0;
    for (int n = 0; n < band_row_count_; ++n) {
      const int j = band_rows_[static_cast<std::size_t>(n)];
      const int i0 = band_lo_[static_cast<std::size_t>(j)], i1 = band_hi_[static_cast<std::size_t>(j)];
      band_lo_[static_cast<std::size_t>(j)] = width_;
      band_hi_[static_cast<std::size_t>(j)] = -1;
      // A band that added no crossings (the union's, which takes whole patches' counts) leaves the
      // row's counts as they are: nothing to accumulate.
      int last = i1;
      if (band_crossings_) {
        covered += accumulate_freeze_row(j, i0, i1, last);
      } else {
        // Whole groups of the vector loop (within the row): the cells around the band's range hold
        // no crossing and none of them qualifies (see `freeze`), so they change nothing.
        covered += freeze(j, i0 & ~(row_group - 1), std::min(i1 | (row_group - 1), width_ - 1));
      }
      grow(dirty_, CellRect{i0, j, last, j});
      use(j, i0, last);
    }
    band_row_count_ = 0;
    band_crossings_ = false;
    return covered;
  }

  /// Freezes the cells of row j in [a, b] that are covered and not yet frozen at their running
  /// bound. Cells outside the band's changed ranges never qualify (any change of their counters
  /// was scanned at the end of its band), so whole aligned groups of cells may be tested.
  std::size_t freeze(int j, int a, int b);

  /// Starts a patch's own grid over the cells `r` of `main` (the union, a grid of the same size): a
  /// cell that `main` covers with an inverse depth of at least `nearest` (the patch's nearest point)
  /// can gain nothing from the patch, so it starts covered and the patch's depth and outline work
  /// skips it (as it skips cells its own earlier bands covered). Only its covered bit is set: its
  /// depth stays 0 here, since the union's is already at least as near and a patch's depth only
  /// matters where it is nearer (`absorb`). Returns false when every cell of `r` is such a cell.
  ///
  /// A cell `main` has not covered holds depth 0, below any `nearest`: only the words of `main`'s
  /// covered bits that have some bit set are compared cell by cell.
  bool seed_frozen(const CoverageGrid& main, CellRect r, float nearest) {
    if (r.empty() || !window_rows(r)) return false;
    grow(dirty_, r);
    // A `nearest` that is not positive (or NaN) is compared against every cell, covered or not, as
    // a plain comparison would.
    const bool every_cell = !(nearest > 0.0f);
    bool open = false;
    for (int j = r.y0; j <= r.y1; ++j) {
      const std::size_t base = static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      const float* from = main.depth_.data() + base;
      const std::size_t word_base = static_cast<std::size_t>(j) * static_cast<std::size_t>(words_);
      const std::uint64_t* covered = main.frozen_bits_.data() + word_base;
      std::uint64_t* frozen = frozen_bits_.data() + word_base;
      for (int word = r.x0 >> 6; word <= r.x1 >> 6; ++word) {
        const int lo = std::max(r.x0, word << 6), hi = std::min(r.x1, (word << 6) + 63);
        const std::uint64_t range = (~std::uint64_t{0} << (lo & 63)) & (~std::uint64_t{0} >> (63 - (hi & 63)));
        const std::uint64_t candidates = every_cell ? range : covered[word] & range;
        // Compared by whole groups of the vector loop (within the row): a comparison of a cell that is
        // no candidate is masked off.
        const std::uint64_t seeded =
            candidates == 0 ? 0
                            : nearer_bits(from, lo & ~(row_group - 1), std::min(hi | (row_group - 1), width_ - 1), nearest) & candidates;
        frozen[word] |= seeded;
        open = open || seeded != range;
      }
    }
    return open;
  }

  /// True when `r` (on the rows worked on) reaches some row and every cell of it is covered with an
  /// inverse depth of at least `nearest` (positive): then `seed_frozen` from this grid over any part
  /// of `r`, with any `nearest` no larger, finds no open cell, now and after any later operation on
  /// this grid (a covered cell stays covered, and its depth only ever grows nearer).
  [[nodiscard]] bool covered_nearer(CellRect r, float nearest) const {
    if (!(nearest > 0.0f) || r.empty() || !window_rows(r)) return false;
    for (int j = r.y0; j <= r.y1; ++j)
      if (!row_frozen(j, r.x0, r.x1)) return false;
    for (int j = r.y0; j <= r.y1; ++j) {
      const float* depth = depth_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      for (int word = r.x0 >> 6; word <= r.x1 >> 6; ++word) {
        const int lo = std::max(r.x0, word << 6), hi = std::min(r.x1, (word << 6) + 63);
        const std::uint64_t range = (~std::uint64_t{0} << (lo & 63)) & (~std::uint64_t{0} >> (63 - (hi & 63)));
        // The comparisons of seed_frozen, by the same whole groups.
        const std::uint64_t nearer =
            nearer_bits(depth, lo & ~(row_group - 1), std::min(hi | (row_group - 1), width_ - 1), nearest);
        if ((nearer & range) != range) return false;
      }
    }
    return true;
  }

  /// True when `r` (on the rows worked on) reaches some row and no cell of it, nor the cell after it
  /// in its row, has been used since the grid was last cleared: those cells then hold no count,
  /// outline mark, bound, depth or covered bit (every operation that changes one uses the cell).
  /// Operations of triangles whose boxes (with the margin) lie in `r` reach no other cell: their
  /// bounds, outline marks and covered tests stay in `r`, a crossing falls at most one cell right
  /// of it, and a row's sum runs on to the row's end only past a crossing dropped beyond the last
  /// column, which `r` then reaches.
  [[nodiscard]] bool untouched(CellRect r) const {
    if (r.empty() || !window_rows(r)) return false;
    const int right = std::min(r.x1 + 1, width_ - 1);
    for (int j = r.y0; j <= r.y1; ++j) {
      const auto k = static_cast<std::size_t>(j);
      if (used_hi_[k] >= r.x0 && used_lo_[k] <= right) return false;
    }
    return true;
  }

  /// True when `other` (a grid of the same size) holds the same cells: counts, pending crossings,
  /// running bounds, frozen depths and covered bits.
  [[nodiscard]] bool same_cells(const CoverageGrid& other) const {
    return width_ == other.width_ && height_ == other.height_ && net_ == other.net_ && diff_ == other.diff_ &&
           bound_ == other.bound_ && depth_ == other.depth_ && frozen_bits_ == other.frozen_bits_;
  }

  /// Adds `patch` (a grid of the same size) into this one, in one pass over every cell it changed:
  /// first the patch's band still open ends there (as its `end_band` would: the band's crossings
  /// summed into its counts, and the cells it covers frozen in the patch's grid, so a patch needs
  /// no pass of its own for its last band); then its counts, outline counters and running bounds
  /// are added; then the cells this
  /// grid now covers freeze at its running bound; then, with `layers`, a cell the patch covers with
  /// a nearer bound takes the patch's (either set of occluders bounds the depth of every ray through
  /// the cell, so the nearer bound holds). Returns the cells newly covered by the counts.
  ///
  /// Freezing here, before the caller takes shared edges out of the outline and ends the band, gives
  /// what freezing after it would: taking an edge out only raises counts, and bounds do not change.
  /// Taking the patch's bound before those later freezes does too: the running bound here is at
  /// most the patch's last running bound, which is at most the bound the patch froze the cell at.
  ///
  /// The patch's grid is left empty where it was used (its counts, bounds and depths), so resetting
  /// it for the next patch has only its covered bits left to clear.
  std::size_t absorb(CoverageGrid& patch, bool layers);

  /// After the last band: per-tile minimum of the frozen inverse depths (0 where uncovered).
  void finish() {
    std::fill(tile_depth_.begin(), tile_depth_.end(), 0.0f);
    if (dirty_.empty()) return;
    for (int ty = dirty_.y0 / tile; ty <= dirty_.y1 / tile; ++ty)
      for (int tx = dirty_.x0 / tile; tx <= dirty_.x1 / tile; ++tx) {
        const int j0 = ty * tile, j1 = std::min(height_, (ty + 1) * tile);
        const int i0 = tx * tile, i1 = std::min(width_, (tx + 1) * tile);
        tile_depth_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_) + static_cast<std::size_t>(tx)] =
            tile_minimum(j0, j1, i0, i1);
      }
  }

  /// True when every cell of `r` is covered with an inverse depth above `threshold`.
  [[nodiscard]] bool all_nearer(const CellRect& r, float threshold) const {
    for (int ty = r.y0 / tile; ty <= r.y1 / tile; ++ty)
      for (int tx = r.x0 / tile; tx <= r.x1 / tile; ++tx) {
        if (tile_depth_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tiles_x_) + static_cast<std::size_t>(tx)] > threshold)
          continue;
        const int j0 = std::max(r.y0, ty * tile), j1 = std::min(r.y1, ty * tile + tile - 1);
        const int i0 = std::max(r.x0, tx * tile), i1 = std::min(r.x1, tx * tile + tile - 1);
        for (int j = j0; j <= j1; ++j) {
          const float* row = depth_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
          for (int i = i0; i <= i1; ++i)
            if (!(row[i] > threshold)) return false;
        }
      }
    return true;
  }

  /// True when every cell the triangle (grid corners x, y, depths w, all beyond the near plane)
  /// touches is covered nearer than any point of the triangle in that cell. Per cell, the
  /// triangle's inverse depth is at most its plane's largest value over the cell (1/w is affine on
  /// screen over a plane) and at most its nearest corner's: a big triangle seen at a slant is held
  /// to its own depth cell by cell, not to its nearest corner's everywhere on its rectangle.
  [[nodiscard]] bool triangle_behind(const double* x, const double* y, const double* w) const {
    const double xmin = std::min(std::min(x[0], x[1]), x[2]), xmax = std::max(std::max(x[0], x[1]), x[2]);
    const double ymin = std::min(std::min(y[0], y[1]), y[2]), ymax = std::max(std::max(y[0], y[1]), y[2]);
    const CellRect r = cells_of(xmin, ymin, xmax, ymax);
    if (r.empty()) return true;  // it meets no ray through the frustum
    const double m = cell_margin(std::max(std::max(std::fabs(xmin), std::fabs(xmax)), std::max(std::fabs(ymin), std::fabs(ymax))));
    const TriangleEdges edges = edges_of(x, y);
    const double w_min = std::min(std::min(w[0], w[1]), w[2]);
    const double highest = (1.0 / w_min) * (1.0 + 0x1p-20);
    if (!std::isfinite(highest)) return false;
    // The plane's inverse depth at the corner of cell (r.x0, r.y0) that maximizes it, then a per
    // column and b per row, plus the rounding of the solve (as add_depth's, the other way).
    double v00 = HUGE_VAL, a = 0.0, b = 0.0;
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    const double extent = std::max(xmax - xmin, ymax - ymin);
    if (std::fabs(area2) > 1e-6 * extent * extent) {
      const double inv[3] = {1.0 / w[0], 1.0 / w[1], 1.0 / w[2]};
      a = ((inv[1] - inv[0]) * (y[2] - y[0]) - (inv[2] - inv[0]) * (y[1] - y[0])) / area2;
      b = ((x[1] - x[0]) * (inv[2] - inv[0]) - (x[2] - x[0]) * (inv[1] - inv[0])) / area2;
      const double v = inv[0] + a * (r.x0 + (a > 0.0 ? 1.0 : 0.0) - x[0]) + b * (r.y0 + (b > 0.0 ? 1.0 : 0.0) - y[0]);
      const double span = std::fabs(a) * (r.x1 - r.x0 + 1) + std::fabs(b) * (r.y1 - r.y0 + 1);
      const double inv_max = std::max(std::max(inv[0], inv[1]), inv[2]);
      const double err = 0x1p-19 * (std::fabs(v) + span + inv_max) + 1e-12 * inv_max * (1.0 + extent * extent / std::fabs(area2));
      if (std::isfinite(v) && std::isfinite(err) && std::isfinite(a) && std::isfinite(b)) v00 = v + err;
    }
    return for_each_triangle_row(edges, r, m, [&](int j, int i0, int i1) {
      const float* row = depth_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
      return row_behind(row, i0, i1, i0 - r.x0, v00 + b * (j - r.y0), a, highest);
    });
  }

  /// True when every cell the box [xmin, xmax] x [ymin, ymax] touches (with a margin) is covered
  /// already.
  [[nodiscard]] bool all_frozen(double xmin, double ymin, double xmax, double ymax) const {
    CellRect r = cells_of(xmin, ymin, xmax, ymax);
    if (r.empty() || !window_rows(r)) return false;
    for (int j = r.y0; j <= r.y1; ++j)
      if (!row_frozen(j, r.x0, r.x1)) return false;
    return true;
  }

  /// Covered cells, from the covered bits: what the grid holds, whichever steps covered them (the
  /// sums of newly covered cells that `end_band` and `absorb` return depend on the order of the
  /// steps, which the strips of rows change).
  [[nodiscard]] std::size_t covered_count() const {
    std::size_t n = 0;
    for (const std::uint64_t w : frozen_bits_) n += static_cast<std::size_t>(detail::popcount(w));
    return n;
  }


  /// Cells touched by the rectangle [x0, x1] x [y0, y1] in grid coordinates, with a margin,
  /// clamped to the grid (empty when it misses the grid).
  [[nodiscard]] CellRect cells_of(double x0, double y0, double x1, double y1) const {
    const double m = cell_margin(std::max(std::max(std::fabs(x0), std::fabs(x1)), std::max(std::fabs(y0), std::fabs(y1))));
    if (x1 + m < 0.0 || x0 - m >= width_ || y1 + m < 0.0 || y0 - m >= height_) return CellRect{0, 0, -1, -1};
    return CellRect{clamp_cell(x0 - m, width_), clamp_cell(y0 - m, height_), clamp_cell(x1 + m, width_),
                    clamp_cell(y1 + m, height_)};
  }

  static constexpr int tile = 8;

 private:
  // A triangle's edges sorted by y, with their slopes, for the per-row spans.
  struct TriangleEdges {
    double xa[3], ya[3], xb[3], yb[3], slope[3];
  };
  static TriangleEdges edges_of(const double* x, const double* y) {
    TriangleEdges e;
    for (int k = 0; k < 3; ++k) {
      const int l = k == 2 ? 0 : k + 1;
      const bool up = y[k] <= y[l];
      e.xa[k] = up ? x[k] : x[l];
      e.ya[k] = up ? y[k] : y[l];
      e.xb[k] = up ? x[l] : x[k];
      e.yb[k] = up ? y[l] : y[k];
      e.slope[k] = e.yb[k] > e.ya[k] ? (e.xb[k] - e.xa[k]) / (e.yb[k] - e.ya[k]) : 0.0;
    }
    return e;
  }

  // add_depth with the triangle's edges (edges_of) given.
  CellRect add_depth(const double* x, const double* y, const double* w, const TriangleEdges& edges);

  // Calls body(j, i0, i1) for each row j of r that the triangle touches, [i0, i1] its cells there
  // (row_span) narrowed to those between its first and last cell not yet covered, after noting
  // them used; rows with no such cell are passed over.
  template <typename Body>
  CULLKIT_FORCEINLINE void for_each_row_span(const TriangleEdges& edges, const CellRect& r, double m, Body&& body) {
    for_each_triangle_row(edges, r, m, [&](int j, int i0, int i1) {
      if (unfrozen_span(j, i0, i1)) {
        use(j, i0, i1);
        body(j, i0, i1);
      }
      return true;
    });
  }

  // Calls body(j, i0, i1) for each row j of r that the triangle touches, [i0, i1] its cells there
  // (row_span's, four rows at a time by row_spans4), until body returns false; false then.
  template <typename Body>
  CULLKIT_FORCEINLINE bool for_each_triangle_row(const TriangleEdges& edges, const CellRect& r, double m, Body&& body) const {
    for (int j = r.y0; j <= r.y1; j += 4) {
      int lo[4], hi[4];
      unsigned rows = row_spans4(edges, j, m, lo, hi);
      if (r.y1 - j < 3) rows &= (1u << (r.y1 - j + 1)) - 1u;
      for (; rows != 0; rows &= rows - 1) {
        const int q = lowest_bit(rows);
        if (!body(j + q, lo[q], hi[q])) return false;
      }
    }
    return true;
  }

  // Cells of row j that the triangle touches (its part in the row's slab, widened by m): the
  // depth bound of a triangle only matters where a ray can meet it, and a slanted triangle's box
  // is mostly elsewhere. False when it misses the row.
  CULLKIT_FORCEINLINE bool row_span(const TriangleEdges& e, int j, double m, int& i0, int& i1) const {
    const double lo = j - m, hi = j + 1 + m;
    double xl = HUGE_VAL, xr = -HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
      if (e.yb[k] < lo || e.ya[k] > hi) continue;
      if (e.yb[k] > e.ya[k]) {
        const double y0 = std::max(e.ya[k], lo), y1 = std::min(e.yb[k], hi);
        const double x0 = e.xa[k] + (y0 - e.ya[k]) * e.slope[k], x1 = e.xa[k] + (y1 - e.ya[k]) * e.slope[k];
        xl = std::min(xl, std::min(x0, x1));
        xr = std::max(xr, std::max(x0, x1));
      } else {
        xl = std::min(xl, std::min(e.xa[k], e.xb[k]));
        xr = std::max(xr, std::max(e.xa[k], e.xb[k]));
      }
    }
    if (!(xl <= xr) || xr + m < 0.0 || xl - m >= width_) return false;
    i0 = clamp_cell(xl - m, width_);
    i1 = clamp_cell(xr + m, width_);
    return true;
  }

  // row_span for the four rows j to j + 3 at once (rows past the grid are computed too; the caller
  // leaves them out): bit q of the result is set when row j + q has cells, which are then
  // [i0[q], i1[q]]. Where the compiler targets them, the rows run in double lanes with the same
  // operations on the same values as row_span's (a product and a sum fused where the compiler
  // fuses row_span's, under FMA), so each row's span is row_span's, bit for bit.
  unsigned row_spans4(const TriangleEdges& e, int j, double m, int* i0, int* i1) const;

  // An outline edge's side test in one row (see touch_edge): a = (xa, ya) is its first endpoint,
  // qy the row's centre line minus ya, (dx, dy) the edge, near_line and rounding its tolerance's
  // terms, side and delta as touch_edge's.
  struct EdgeSides {
    double xa, qy, dx, dy, near_line, rounding;
    int side, delta;
  };
  // Subtracts the edge's weight from the counts row[i0..i1] by the side of each cell's centre:
  // delta on the inner side, 2 * delta where the side is too close to call. Where the compiler
  // targets AVX2, four centres at a time, the last 1 to 4 under a lane mask (a row takes about two
  // cells, so mostly one masked group and no loop), with the same double operations as the scalar
  // loop (a product and a sum fused where the compiler fuses the scalar loop's, under FMA).
  static void touch_centres(std::int32_t* row, int i0, int i1, const EdgeSides& e);

#if CULLKIT_COVERAGE_AVX2
  // b * c + a in lanes as the compiler computes a scalar `a + b * c`: fused under FMA.
  static __m256d mul_add(__m256d b, __m256d c, __m256d a) {
#if defined(__FMA__)
    return _mm256_fmadd_pd(b, c, a);
#else
    return _mm256_add_pd(a, _mm256_mul_pd(b, c));
#endif
  }
#endif

  // True when row[i] > min(highest, start + a * (i - i0 + step0)) > 0 for every i in [i0, i1]: the
  // triangle_behind test of one row (an uncovered cell holds 0, and a bound that is not positive,
  // rounding gone wild, proves nothing). Where the compiler targets AVX2, four cells at a time, the
  // last 1 to 4 under a lane mask, with the same double operations as the scalar loop (the product
  // and the sum fused where the compiler fuses the scalar loop's, under FMA): the same answer.
  static bool row_behind(const float* row, int i0, int i1, int step0, double start, double a, double highest);

  // The smallest depth over rows [j0, j1) and columns [i0, i1). Depths are never NaN (frozen
  // bounds and 0), so the minimum does not depend on the order it is taken in.
  [[nodiscard]] float tile_minimum(int j0, int j1, int i0, int i1) const;

  // row[i] = min(row[i], max(lowest, start + slope * (i - i0 + step0))) for i in [i0, i1]: a plane's
  // bound along a row. The lanes compute exactly what the scalar tail does (the same float
  // operations on the same exact integer steps; min and max pick the same operand for NaN).
  static void lower_row_sloped(float* row, int i0, int i1, int step0, float start, float slope, float lowest);

  // row[i] = min(row[i], lowest) for i in [i0, i1].
  static void lower_row_flat(float* row, int i0, int i1, float lowest);

#if CULLKIT_COVERAGE_AVX2
  // The lanes of a group of eight cells that hold the first `count` (1 to 8) of them, for a masked
  // load and store.
  static __m256i tail_lanes(int count) {
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(count), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  }
#endif

  // Bit (i & 63) set for each i in [lo, hi] (one word's cells, lo <= hi) with row[i] >= limit.
  static std::uint64_t nearer_bits(const float* row, int lo, int hi, float limit);

  // What absorb does to the cells of one row of `patch`: `band_row` when the patch's open band
  // changed the row (its cells then freeze in the patch's grid first), `accumulate` when that band
  // added crossings (summed into the patch's counts on the way).
  struct AbsorbPass {
    CoverageGrid& patch;
    int j;
    bool band_row, accumulate, layers;
  };
  // absorb's pass over the cells [a, b] of the row, `run` the crossings' sum carried in and out:
  // returns the cells newly covered here by the counts.
  std::size_t absorb_span(const AbsorbPass& pass, int a, int b, std::int32_t& run);
  // Cells the row kernels' vector loops (freeze, accumulate_freeze_row, absorb_span) take at once.
  static constexpr int row_group = CULLKIT_COVERAGE_AVX2 ? 8 : CULLKIT_HAS_SSE2 ? 4 : 1;

  // True when every cell of row j in [i0, i1] is covered (0 <= i0 <= i1 < width).
  [[nodiscard]] bool row_frozen(int j, int i0, int i1) const {
    const std::uint64_t* w = frozen_bits_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(words_);
    const int a = i0 >> 6, b = i1 >> 6;
    const std::uint64_t first = ~std::uint64_t{0} << (i0 & 63), last = ~std::uint64_t{0} >> (63 - (i1 & 63));
    if (a == b) return (w[a] & first & last) == (first & last);
    if ((w[a] & first) != first || (w[b] & last) != last) return false;
    for (int k = a + 1; k < b; ++k)
      if (w[k] != ~std::uint64_t{0}) return false;
    return true;
  }

  // Narrows the cells [i0, i1] of row j to those between its first and last cell not yet covered
  // (a covered cell's depth is frozen and its counters no longer matter). False when none is left.
  CULLKIT_FORCEINLINE bool unfrozen_span(int j, int& i0, int& i1) const {
    const std::uint64_t* w = frozen_bits_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(words_);
    for (;;) {
      // Bits past the last column are clear, so they read as "not covered" and end the search.
      const std::uint64_t open = ~w[i0 >> 6] >> (i0 & 63);
      if (open != 0) {
        i0 += lowest_bit(open);
        break;
      }
      i0 = (i0 | 63) + 1;
      if (i0 > i1) return false;
    }
    if (i0 > i1) return false;
    for (;;) {  // ends: cell i0 is not covered
      const std::uint64_t open = ~w[i1 >> 6] << (63 - (i1 & 63));
      if (open != 0) {
        i1 -= 63 - highest_bit(open);
        return true;
      }
      i1 = (i1 & ~63) - 1;
    }
  }

  static std::size_t bits_in_nibble(int v) {  // 0 <= v < 16
    return (0x4332322132212110ull >> (4 * v)) & 15u;
  }

  static int lowest_bit(std::uint64_t v) { return detail::lowest_bit(v); }    // v != 0
  static int highest_bit(std::uint64_t v) { return detail::highest_bit(v); }  // v != 0

  // Adds the running sum of the row's crossings (diff_, cleared on the way) to its counts, from i0
  // through i1, and on to the row's end while the sum is not zero: a crossing beyond the last column
  // is dropped, so a row's sum need not return to zero. Every crossing of the band lies in
  // [i0, i1] (`mark`), so past i1 the sum is constant. In the same pass, freezes the cells whose
  // count makes them covered (as `freeze` would after it). `last` gets the last cell changed (i1,
  // or the row's end); returns how many cells it covered. The pass runs over whole groups of its
  // vector loop: a cell of the row outside the band's range holds no crossing, so before i0 the sum
  // adds 0, past i1 it adds what the run on to the row's end would, and such a cell that counts at
  // least one is covered already (see `freeze`).
  std::size_t accumulate_freeze_row(int j, int i0, int i1, int& last);

#if CULLKIT_COVERAGE_AVX2
  // Freezes those of the eight cells from i (a multiple of 8) whose count `c` is at least one and
  // that are not covered yet; returns how many. The depths are stored whether any cell froze or not
  // (a blend under an empty mask keeps them): which groups freeze is data, and a branch on it costs
  // more than the store.
  static std::size_t freeze8(__m256i c, int i, const float* bound, float* depth, std::uint64_t* frozen);
#endif
#if CULLKIT_HAS_SSE2
  // The same for the four cells from i (a multiple of 4), returning early when none freezes: with no
  // blend instruction, the store costs more than the branch.
  static std::size_t freeze4(__m128i c, int i, const float* bound, float* depth, std::uint64_t* frozen);
#endif

  // Cell range [i0, i1] of row j changed in this band: end_band scans it.
  void mark(int j, int i0, int i1) {
    use(j, i0, i1);
    const auto r = static_cast<std::size_t>(j);
    if (band_hi_[r] < 0) band_rows_[static_cast<std::size_t>(band_row_count_++)] = j;  // each row once per band
    band_lo_[r] = std::min(band_lo_[r], i0);
    band_hi_[r] = std::max(band_hi_[r], i1);
  }

  // Cell range [i0, i1] of row j may have changed counters, bounds or depths since the grid was last
  // cleared: clear_dirty and absorb visit it.
  void use(int j, int i0, int i1) {
    const auto r = static_cast<std::size_t>(j);
    if (used_hi_[r] < 0) used_rows_[static_cast<std::size_t>(used_row_count_++)] = j;
    used_lo_[r] = std::min(used_lo_[r], i0);
    used_hi_[r] = std::max(used_hi_[r], i1);
  }

  // Narrows r's rows to those set by set_rows; false when none is left.
  bool window_rows(CellRect& r) const {
    r.y0 = std::max(r.y0, row_first_);
    r.y1 = std::min(r.y1, row_last_);
    return r.y0 <= r.y1;
  }

  static int clamp_cell(double v, int n) {
    if (!(v >= 0.0)) return 0;
    if (v >= n) return n - 1;
    return static_cast<int>(v);
  }
  static void grow(CellRect& r, const CellRect& s) {
    r.x0 = std::min(r.x0, s.x0);
    r.y0 = std::min(r.y0, s.y0);
    r.x1 = std::max(r.x1, s.x1);
    r.y1 = std::max(r.y1, s.y1);
  }

  // The rows j with ya <= j + 0.5 < yb (ya < yb) on the rows worked on: an edge's crossings.
  void crossing_rows(double ya, double yb, int& j0, int& j1) const;

  // The cell of row j whose count an edge's crossing there changes (the first cell whose centre is
  // right of the crossing), or -1 past the last column. The same arithmetic for every caller, so
  // that an edge gives the same crossings from its two triangles.
  int crossing_cell(double xa, double ya, double slope, int j) const;

  // touch_edge (from -> to, orient, delta), and with `crossing` not 0 the crossings of the edge
  // with that sign (add_crossings on its endpoints sorted by y, when they differ in y), walking the
  // rows of both once: where a row has a crossing and outline marks, one `mark` spans both (the
  // same ranges as two).
  void walk_edge(double x_from, double y_from, double x_to, double y_to, int orient, int delta, int crossing);

  // walk_edge on the edge's endpoints sorted as it sorts them, `slope` the edge's (xb - xa) /
  // (yb - ya), or 0 when yb - ya is not positive, and `side` its side.
  void walk_sorted_edge(double xa, double ya, double xb, double yb, double slope, int side, int delta, int crossing);

  // An outline edge's endpoints sorted as touch_edge sorts them, its slope and margin.
  struct EdgeRow {
    double xa, ya, xb, yb, dy, slope, m;
  };
  // The cells of row j an outline edge's marks reach (touch_edge's): its part in the row's slab,
  // widened by the margin, into [i0, i1]; left as they are when it misses the row.
  void touch_span(int j, const EdgeRow& e, int& i0, int& i1) const;

#if CULLKIT_COVERAGE_AVX2
  // crossing_cell and touch_span for the rows j to j + 3 at once, in double lanes with the same
  // operations on the same values (a product and a sum fused where the compiler fuses theirs, under
  // FMA), so each row's cells are theirs, bit for bit: cell[q] the crossing's cell of row j + q
  // (-1 past the last column), [i0[q], i1[q]] its marks' cells (i0 > i1 when it misses the row).
  // Coordinates are finite here (a triangle's area was finite to be gathered).
  void edge_rows4(const EdgeRow& e, int j, int* cell, int* i0, int* i1) const;
#endif

  // Crossings of the edge (xa, ya) -> (xb, yb), ya < yb, with the rows' centre lines, half-open in
  // y: the count at a cell centre is the signed number of edges crossing its row left of it.
  void add_crossings(double xa, double ya, double xb, double yb, int sign);

  // Returns the touched part of the grid to the empty state.
  void clear_dirty() {
    // Counters, bounds and depths where they were used (only freezing writes a depth, on a used
    // cell); covered bits over the changed rectangle's rows (seed_frozen sets them across it).
    for (int n = 0; n < used_row_count_; ++n) {
      const auto j = static_cast<std::size_t>(used_rows_[static_cast<std::size_t>(n)]);
      const std::size_t base = j * static_cast<std::size_t>(width_);
      const auto b = static_cast<std::ptrdiff_t>(base) + used_lo_[j], e = static_cast<std::ptrdiff_t>(base) + used_hi_[j] + 1;
      std::fill(net_.begin() + b, net_.begin() + e, 0);
      std::fill(bound_.begin() + b, bound_.begin() + e, std::numeric_limits<float>::infinity());
      std::fill(depth_.begin() + b, depth_.begin() + e, 0.0f);
      used_lo_[j] = width_;
      used_hi_[j] = -1;
    }
    used_row_count_ = 0;
    if (dirty_.empty()) return;
    std::fill(frozen_bits_.begin() + static_cast<std::ptrdiff_t>(dirty_.y0) * words_,
              frozen_bits_.begin() + static_cast<std::ptrdiff_t>(dirty_.y1 + 1) * words_, 0);
    dirty_ = CellRect{width_, height_, -1, -1};
  }

  int width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  // Per cell, the count at its centre minus its outline counter (touch_edge), kept as one number:
  // the cell is covered when it is at least one, and a patch's grid adds into the union's by a sum.
  std::vector<std::int32_t> net_, diff_;
  std::vector<float> bound_;   // running lower bound of 1/w over the triangles touching the cell
  std::vector<float> depth_;   // frozen lower bound of 1/w at the first hit; 0: not covered
  std::vector<float> tile_depth_;
  int words_ = 0;                            // words of frozen bits per row
  std::vector<std::uint64_t> frozen_bits_;   // per row, a bit per covered (frozen) cell
  std::vector<int> band_lo_, band_hi_, band_rows_;  // per row: cells changed in the current band
  int band_row_count_ = 0;                          // rows listed in band_rows_
  bool band_crossings_ = false;                     // some crossing was added to diff_ in this band
  std::vector<int> used_lo_, used_hi_, used_rows_;  // per row: cells whose counters or bound changed since clear_dirty
  int used_row_count_ = 0;                          // rows listed in used_rows_
  CellRect dirty_{0, 0, -1, -1};
  int row_first_ = 0, row_last_ = -1;  // the rows worked on (set_rows)
};

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit

#include "coverage_rows.hpp"
#include "coverage_triangles.hpp"
