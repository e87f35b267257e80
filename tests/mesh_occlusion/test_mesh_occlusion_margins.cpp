// The coverage grid's conservative margins at rounding level. Every edge here passes a cell corner
// or a cell centre of the grid by a hair, from a corner far off the grid (2^8 to 2^23 cells away):
// either to the far corner mirrored through the point and moved a lattice step (the line then
// passes the point by down to 2^-80 cells: below the rounding of the grid's double arithmetic,
// which is up to about 2^-50 of the coordinates' size), or to the nearest lattice point on the side
// wanted 1.5 to 6 cells beyond it (about 2^-33 cells). Nearly horizontal edges, nearly vertical ones
// (slopes down to 2^-51, where no slab margin times the slope helps) and slanted ones; a triangle
// alone, two with a crack or an overlap of that width between them (a near one and a far one, so
// that a missed depth span shows), and two sharing the edge; inserted as one band or as two patches.
// Every covered cell near those points is checked, exactly, at its corners, at its corners moved
// one lattice step inward, at the triangles' corners in it and at 9 x 9 points over it: each point
// must lie in some triangle, and the cell's float depth bound must be no nearer than the nearest
// triangle through the point, to the last bit.
//
// Then the object test of a triangle (CoverageGrid::triangle_behind) at the same level: a far
// triangle whose edge passes the corner of the first covered column by a hair must not count as
// hidden unless every cell it meets is covered.
//
// Corners lie on a lattice of 2^-28 cells, up to 2^23 cells out: the coordinates are integers below
// 2^51 in lattice steps, so the inside tests are exact in 128-bit integers, whatever the grid's own
// arithmetic rounds. A margin the grid needs is one whose absence leaves a cell covered with a point
// outside every triangle, bounded nearer than a point's nearest triangle, or a triangle hidden that
// meets an open cell.
//
// Mutants this test caught (each margin set to 0 by hand, then reverted; default build, then the
// -march=native build where it differs):
//   the outline marks' cell margin at a span's left end (touch_edge's xl - m): 4 wrong cells;
//   both of touch_edge's x margins: 4;
//   the outline marks' near-centre tolerance (near_line and rounding in touch_edge): 9, native 13;
//   the depth spans' x margin in row_spans4's lanes (SSE2; AVX2 in the native build): 3;
//   the object test's x margin in row_span (triangle_behind): 172 triangles hidden that meet an
//   open cell; all of row_span's margins: 175;
//   add_depth's rounding margin of the sloped bound: 24,444 wrong cells;
//   cell_margin itself: 27 wrong cells and 175 triangles;
//   touch_edge's slab margins with its right x margin: none, native 2.
// Not caught, because another margin covers the grid's own rounding there (see "What the margins
// absorb" in docs/mesh_occlusion.md): touch_edge's slab margins (alone or both), its right x margin
// and its row range; row_span's and row_spans4's slab margins; add_depth's box margin; cells_of's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <cullkit/detail/mesh_occlusion/coverage.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "coverage_grid_insert.hpp"

namespace dmo = cullkit::detail::mesh_occlusion;
using coverage_grid_test::Triangle;
using cullkit::support::Rng;

namespace {

__extension__ typedef __int128 Wide;  // products of lattice coordinates, exact

constexpr double step = 0x1p-28;  // the lattice, in cells
constexpr double steps_per_cell = 0x1p28;

struct Point {
  std::int64_t x, y;  // in lattice steps
};

double cell_coordinate(std::int64_t v) { return static_cast<double>(v) * step; }  // exact below 2^53
std::int64_t lattice(double cells) { return static_cast<std::int64_t>(std::llround(cells * steps_per_cell)); }

Wide orient(Point a, Point b, Point c) {
  return Wide(b.x - a.x) * Wide(c.y - a.y) - Wide(b.y - a.y) * Wide(c.x - a.x);
}

Point corner(const Triangle& t, int k) { return Point{lattice(t.x[k]), lattice(t.y[k])}; }

// The largest 1/w of the triangles holding p (closed), 0 when none does. Inside is decided exactly;
// the depth is interpolated in long double (its rounding is far below the grid's 2^-20 margins).
long double nearest_inverse_depth(const std::vector<Triangle>& set, Point p) {
  long double best = 0.0L;
  for (const Triangle& t : set) {
    const Point c[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
    Wide b[3];
    for (int k = 0; k < 3; ++k) b[k] = orient(c[k], c[k == 2 ? 0 : k + 1], p);
    if (b[0] < 0 || b[1] < 0 || b[2] < 0) continue;
    const long double s0 = static_cast<long double>(b[0]), s1 = static_cast<long double>(b[1]),
                      s2 = static_cast<long double>(b[2]);
    // Barycentric weight of corner k is the sub-area opposite it: b[(k + 1) % 3].
    const long double inv = (s1 / t.w[0] + s2 / t.w[1] + s0 / t.w[2]) / (s0 + s1 + s2);
    best = std::max(best, inv);
  }
  return best;
}

enum class Reach { slanted, nearly_horizontal, nearly_vertical };

// A far point, from the cell corner p: 2^8 to 2^23 cells away.
Point far_point(Rng& rng, Point p, Reach reach) {
  const double far = std::ldexp(1.0 + rng.uniform(), rng.range(8, 22));
  const double sx = rng.range(0, 1) ? 1.0 : -1.0;
  double dx = 0.0, dy = 0.0;
  switch (reach) {
    case Reach::slanted: {
      const double a = 6.283185307179586 * rng.uniform();
      dx = far * std::cos(a);
      dy = far * std::sin(a);
      break;
    }
    case Reach::nearly_horizontal:
    case Reach::nearly_vertical: {
      // Across: a few lattice steps (slopes down to 2^-51, where the edge's x at a slab's top or
      // bottom is exact but for the last bits), up to 2^20 steps (slopes where the slab's margin
      // times the slope is below the rounding of that x), or up to a few hundred cells.
      const int scale = rng.range(0, 2);
      const std::int64_t across = scale == 0   ? rng.range(-3, 3)
                                  : scale == 1 ? (std::int64_t{1} << rng.range(2, 20)) * (rng.range(0, 1) ? 1 : -1) + rng.range(-3, 3)
                                               : lattice(rng.range(-400, 400) * 0.37);
      const std::int64_t along = lattice(sx * far);
      return reach == Reach::nearly_horizontal ? Point{p.x + along, p.y + across} : Point{p.x + across, p.y + along};
    }
  }
  return Point{p.x + lattice(dx), p.y + lattice(dy)};
}

// A lattice point g beyond the cell corner p from f, such that the line f-g passes p on the side
// `side` (+1: orient(f, g, p) > 0, -1: < 0, 0: through p when it can) by a hair. Either f mirrored
// through p and moved a lattice step or two (the line then passes p by |step x (f - p)| / |f - g|:
// down to 2^-80 cells for a nearly vertical or horizontal f - p, below any rounding of the grid's
// arithmetic), or 1.5 to 6 cells beyond p on the line, the nearest lattice point of a small search
// on the side asked (about 2^-33 cells).
Point beyond(Rng& rng, Point f, Point p, int side) {
  if (rng.range(0, 1) == 0) {
    const Point mirror{2 * p.x - f.x, 2 * p.y - f.y};
    for (int attempt = 0; attempt < 8; ++attempt) {
      Point g{mirror.x + rng.range(-2, 2), mirror.y + rng.range(-2, 2)};
      const Wide v = orient(f, g, p);
      if (side == 0 || (v > 0) == (side > 0)) {
        if (side == 0 || v != 0) return g;
      } else if (v != 0) {
        return Point{2 * mirror.x - g.x, 2 * mirror.y - g.y};  // the other way round: the other side
      }
    }
  }
  const double dx = static_cast<double>(p.x - f.x), dy = static_cast<double>(p.y - f.y);
  const double scale = (1.5 + 4.5 * rng.uniform()) * steps_per_cell / std::sqrt(dx * dx + dy * dy);
  const Point g0{p.x + static_cast<std::int64_t>(std::llround(dx * scale)), p.y + static_cast<std::int64_t>(std::llround(dy * scale))};
  Point best = g0;
  Wide best_value = -1;
  for (int a = -6; a <= 6; ++a)
    for (int b = -6; b <= 6; ++b) {
      const Point g{g0.x + a, g0.y + b};
      const Wide v = orient(f, g, p);
      if ((side > 0 && v <= 0) || (side < 0 && v >= 0)) continue;
      const Wide size = v < 0 ? -v : v;
      if (best_value < 0 || size < best_value) {
        best_value = size;
        best = g;
      }
    }
  return best;
}

// A third corner on the side `side` of the line f-g (orient(f, g, h) of that sign): near p (up to 6
// cells, on quarter cells plus a random lattice step) or far.
Point third_corner(Rng& rng, Point f, Point g, Point p, int side, bool far) {
  for (int attempt = 0; attempt < 40; ++attempt) {
    Point h;
    if (far) {
      h = far_point(rng, p, Reach::slanted);
    } else {
      h = Point{p.x + lattice(rng.range(-24, 24) / 4.0) + rng.range(-1, 1), p.y + lattice(rng.range(-24, 24) / 4.0) + rng.range(-1, 1)};
    }
    const Wide v = orient(f, g, h);
    if ((side > 0 && v > 0) || (side < 0 && v < 0)) return h;
  }
  return p;  // none found: a degenerate triangle, left out
}

// Adds the triangle (a, b, c) with its depths, wound to a positive area; false when it has none.
bool add(std::vector<Triangle>& set, Point a, Point b, Point c, const double* w, int patch) {
  const Wide area = orient(a, b, c);
  if (area == 0) return false;
  if (area < 0) std::swap(b, c);
  const double w1 = area < 0 ? w[2] : w[1], w2 = area < 0 ? w[1] : w[2];
  set.push_back(Triangle{{cell_coordinate(a.x), cell_coordinate(b.x), cell_coordinate(c.x)},
                         {cell_coordinate(a.y), cell_coordinate(b.y), cell_coordinate(c.y)},
                         {w[0], w1, w2},
                         {-1, -1, -1},
                         patch});
  return true;
}

void depths(Rng& rng, double* w, double lo, double hi) {
  for (int k = 0; k < 3; ++k) w[k] = lo + (hi - lo) * rng.uniform();
}

// One group of triangles around the cell corner p, all with an edge from a far point f passing p by
// a hair: one triangle; two with a crack or an overlap of a hair between them (one near, one far);
// or two sharing that edge exactly (twins, in one patch or across the two).
void add_group(std::vector<Triangle>& set, Rng& rng, Point p) {
  const Reach reach = static_cast<Reach>(rng.range(0, 2));
  const Point f = far_point(rng, p, reach);
  const int kind = rng.range(0, 2);
  double w[3];
  if (kind == 0) {
    const int side = rng.range(-1, 1);
    const Point g = beyond(rng, f, p, side);
    const int inner = rng.range(0, 1) ? 1 : -1;
    depths(rng, w, 1.0, 10.0);
    add(set, f, g, third_corner(rng, f, g, p, inner, rng.range(0, 3) == 0), w, rng.range(0, 1));
    return;
  }
  if (kind == 1) {
    // Each triangle's edge passes p on its own side: a crack through p, an overlap over it, or
    // edges through p on both. The near one and the far one go in either order of patches.
    const Point g1 = beyond(rng, f, p, rng.range(-1, 1)), g2 = beyond(rng, f, p, rng.range(-1, 1));
    const bool far_first = rng.range(0, 1) == 1;
    depths(rng, w, far_first ? 20.0 : 1.0, far_first ? 30.0 : 10.0);
    const int patch = rng.range(0, 1);
    add(set, f, g1, third_corner(rng, f, g1, p, 1, rng.range(0, 3) == 0), w, patch);
    depths(rng, w, far_first ? 1.0 : 20.0, far_first ? 10.0 : 30.0);
    add(set, f, g2, third_corner(rng, f, g2, p, -1, rng.range(0, 3) == 0), w, rng.range(0, 1));
    return;
  }
  const Point g = beyond(rng, f, p, rng.range(-1, 1));
  const std::size_t first = set.size();
  depths(rng, w, 1.0, 10.0);
  if (!add(set, f, g, third_corner(rng, f, g, p, 1, rng.range(0, 3) == 0), w, rng.range(0, 1))) return;
  depths(rng, w, 1.0, 10.0);
  if (!add(set, g, f, third_corner(rng, g, f, p, 1, rng.range(0, 3) == 0), w, rng.range(0, 1))) {
    set.resize(first);
    return;
  }
  // Triangle `first` runs f -> g -> h (positive), the next g -> f -> h'; find the shared edge in each.
  const auto edge_of = [&](const Triangle& t, Point from, Point to) {
    for (int k = 0; k < 3; ++k) {
      const Point a = corner(t, k), b = corner(t, k == 2 ? 0 : k + 1);
      if (a.x == from.x && a.y == from.y && b.x == to.x && b.y == to.y) return k;
    }
    return -1;
  };
  const int k0 = edge_of(set[first], f, g), k1 = edge_of(set[first + 1], g, f);
  if (k0 < 0 || k1 < 0) {  // wound the other way round: no shared edge in the triangles' own order
    set.resize(first);
    return;
  }
  set[first].twin[k0] = static_cast<int>(first + 1);
  set[first + 1].twin[k1] = static_cast<int>(first);
}

struct Tally {
  long covered = 0, points = 0, failures = 0;
};

// The points a covered cell (i, j) is checked at, in lattice steps: its corners, each moved one
// lattice step inward (along x, along y and both), and the lattice of eighths over it.
void cell_points(int i, int j, std::vector<Point>& out) {
  out.clear();
  const std::int64_t x0 = lattice(i), y0 = lattice(j), x1 = lattice(i + 1), y1 = lattice(j + 1);
  for (int c = 0; c < 4; ++c) {
    const std::int64_t x = c & 1 ? x1 : x0, y = c & 2 ? y1 : y0, in_x = c & 1 ? -1 : 1, in_y = c & 2 ? -1 : 1;
    out.push_back(Point{x + in_x, y});
    out.push_back(Point{x, y + in_y});
    out.push_back(Point{x + in_x, y + in_y});
  }
  for (int b = 0; b <= 8; ++b)
    for (int a = 0; a <= 8; ++a) out.push_back(Point{x0 + lattice(a / 8.0), y0 + lattice(b / 8.0)});
}

void one_case(Rng& rng, dmo::CoverageGrid& grid, dmo::CoverageGrid& own, Tally& tally, int index) {
  const int width = 24, height = 16;
  grid.reset(width, height);
  std::vector<Triangle> set;
  const int groups = rng.range(1, 3);
  // The cells near the groups' corners are checked (the 4 x 4 around each): elsewhere the edges run
  // as in test_mesh_occlusion_coverage_grid, far from any cell corner.
  std::vector<char> near(static_cast<std::size_t>(width * height), 0);
  for (int k = 0; k < groups; ++k) {
    // A cell corner, or a cell centre (where the outline marks decide which side of the edge the
    // centre is on).
    const int ci = rng.range(0, width), cj = rng.range(0, height);
    const double to_centre = rng.range(0, 3) == 0 ? 0.5 : 0.0;
    add_group(set, rng, Point{lattice(ci + to_centre), lattice(cj + to_centre)});
    for (int j = std::max(0, cj - 2); j < std::min(height, cj + 2); ++j)
      for (int i = std::max(0, ci - 2); i < std::min(width, ci + 2); ++i) near[static_cast<std::size_t>(j * width + i)] = 1;
  }
  if (index % 2 == 0) coverage_grid_test::insert_band(grid, set, -1);
  else coverage_grid_test::insert_patches(grid, own, set);
  grid.finish();
  std::vector<Point> points;
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const dmo::CellRect cell{i, j, i, j};
      if (!near[static_cast<std::size_t>(j * width + i)] || !grid.all_nearer(cell, 0.0f)) continue;
      ++tally.covered;
      cell_points(i, j, points);
      // And the triangles' corners in the cell: a flat bound is tightest at the farthest corner.
      for (const Triangle& t : set)
        for (int k = 0; k < 3; ++k)
          if (t.x[k] >= i && t.x[k] <= i + 1 && t.y[k] >= j && t.y[k] <= j + 1) points.push_back(corner(t, k));
      long double least = HUGE_VALL;
      for (const Point& p : points) {
        ++tally.points;
        least = std::min(least, nearest_inverse_depth(set, p));
      }
      // Covered at a bound no nearer than every point's nearest hit, exactly: `below` is the largest
      // float not above `least`, so a float bound is above it exactly when it is above `least`.
      float below = static_cast<float>(least);
      if (static_cast<long double>(below) > least) below = std::nextafter(below, 0.0f);
      const bool ok = least > 0.0L && !grid.all_nearer(cell, below);
      if (!ok) {
        ++tally.failures;
        CHECK_MSG(ok, "case %d: cell (%d, %d) covered, but %s", index, i, j,
                  least > 0.0L ? "its bound is nearer than a point's nearest hit" : "a point of it is in no triangle");
      }
    }
}

// True when triangle t meets the closed cell (i, j): exact (no axis of the cell's or the
// triangle's separates them; both are convex).
bool meets_cell(const Triangle& t, int i, int j) {
  const Point c[3] = {corner(t, 0), corner(t, 1), corner(t, 2)};
  const std::int64_t x0 = lattice(i), y0 = lattice(j), x1 = lattice(i + 1), y1 = lattice(j + 1);
  const auto all = [&](auto&& below) { return below(c[0]) && below(c[1]) && below(c[2]); };
  if (all([&](Point p) { return p.x < x0; }) || all([&](Point p) { return p.x > x1; }) ||
      all([&](Point p) { return p.y < y0; }) || all([&](Point p) { return p.y > y1; }))
    return false;
  for (int k = 0; k < 3; ++k) {
    const Point a = c[k], b = c[k == 2 ? 0 : k + 1];
    bool outside = true;  // every corner of the cell strictly on the outer side of edge a-b
    for (int q = 0; q < 4 && outside; ++q) outside = orient(a, b, Point{q & 1 ? x1 : x0, q & 2 ? y1 : y0}) < 0;
    if (outside) return false;
  }
  return true;
}

struct BehindTally {
  long hidden = 0, failures = 0;
};

// The object test of a triangle against the grid (CoverageGrid::triangle_behind), at rounding level:
// a near occluder covers the grid on one side of the column line x = c (cells beyond the next line
// covered), and a far triangle has its edge facing that line pass a corner of the first covered
// column's cells by a hair (from a far corner, as above), its other corners on the covered side.
// When the test calls the triangle hidden, every cell it meets (exactly) must be covered.
void behind_case(Rng& rng, dmo::CoverageGrid& grid, BehindTally& tally, int index) {
  const int width = 24, height = 16;
  grid.reset(width, height);
  const int c = rng.range(2, width - 8);
  const bool right = rng.range(0, 1) == 1;  // the occluder covers x >= c (else x <= width - c)
  const double line = right ? c : width - c;
  const double far = 0x1p20, toward = right ? 0x1p21 : -0x1p21;
  // One front-facing triangle far around the grid with an edge along the line.
  std::vector<Triangle> occluder;
  const double w_near[3] = {1.0, 1.0, 1.0};
  add(occluder, Point{lattice(line), lattice(-far)}, Point{lattice(line), lattice(far)}, Point{lattice(toward), 0}, w_near, 0);
  coverage_grid_test::insert_band(grid, occluder, -1);
  grid.finish();
  // The query's edge passes the corner (first covered column's line, row line r) by a hair, or a
  // point 2^-8 cells into that column (beyond the margins: then it can be hidden).
  const int first = right ? c + 1 : width - c - 1;
  const double into = rng.range(0, 1) ? (right ? 0x1p-8 : -0x1p-8) : 0.0;
  const Point p{lattice(first + into), lattice(rng.range(0, height))};
  const Reach reach = rng.range(0, 3) == 0 ? Reach::slanted : Reach::nearly_vertical;
  const Point f = far_point(rng, p, reach);
  const Point g = beyond(rng, f, p, rng.range(-1, 1));
  const double w_far[3] = {50.0, 50.0, 50.0};
  for (int attempt = 0; attempt < 20; ++attempt) {
    const Point h{p.x + lattice((right ? 1 : -1) * rng.range(4, 20) / 4.0), p.y + lattice(rng.range(-12, 12) / 4.0)};
    const Wide side = orient(f, g, h);
    if (side == 0 || ((h.x > p.x) != right)) continue;
    std::vector<Triangle> query;
    if (!add(query, f, g, h, w_far, 0)) continue;
    const Triangle& t = query[0];
    if (!grid.triangle_behind(t.x, t.y, t.w)) return;
    ++tally.hidden;
    for (int j = 0; j < height; ++j)
      for (int i = 0; i < width; ++i) {
        if (!meets_cell(t, i, j)) continue;
        const bool ok = grid.all_nearer(dmo::CellRect{i, j, i, j}, 0.0f);
        if (!ok) {
          ++tally.failures;
          CHECK_MSG(ok, "behind case %d: the triangle counts as hidden, but it meets cell (%d, %d), not covered", index, i, j);
        }
      }
    return;
  }
}

}  // namespace

int main() {
  // Each round: a set of triangles around corners and centres, then an object test.
  Rng rng(20261129);
  dmo::CoverageGrid grid, own;
  Tally cells;
  BehindTally behind;
  const int rounds = 6000;
  for (int c = 0; c < rounds; ++c) {
    one_case(rng, grid, own, cells, c);
    behind_case(rng, grid, behind, c);
  }
  std::printf("%d sets: %ld covered cells checked at %ld points, %ld wrong; %d object tests: %ld hidden, %ld wrongly\n",
              rounds, cells.covered, cells.points, cells.failures, rounds, behind.hidden, behind.failures);
  CHECK(cells.covered > 50000);  // the checks have cells and triangles to fail on
  CHECK(behind.hidden > 1000);
  CHECK(cells.failures == 0);
  CHECK(behind.failures == 0);
  return cullkit_test::report("test_mesh_occlusion_margins");
}
