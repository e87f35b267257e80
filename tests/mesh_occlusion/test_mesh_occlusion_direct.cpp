// A patch inserted straight into the union where the union is untouched, against the same patch
// inserted into a grid of its own and added into the union (the culler's two ways, row_strips.hpp).
// Patch 0 (fans and loose triangles, in two depth bands) goes in first; then patch 1, either way,
// into two copies of the union: where `CoverageGrid::untouched` allows the direct way, both copies
// must end with the same cells (counts, bounds, frozen depths, covered bits), after the shared
// edges are taken out and the band is ended. Patch 1 is placed near patch 0 (it often overlaps
// or shares edges with it: then the direct way must not be allowed, and the test counts how
// often it would differ), apart from patch 0, and reaching past the grid's right edge (its row
// sums then run on to the row's end). So the test fails when the check lets the direct way in
// where the union holds something.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/detail/mesh_occlusion/coverage.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "coverage_grid_insert.hpp"

namespace dmo = cullkit::detail::mesh_occlusion;
using cullkit::support::Rng;
using coverage_grid_test::Triangle;
using coverage_grid_test::area2;

namespace {

constexpr int width = 40, height = 24;

// A fan of front-facing triangles around (cx, cy), consecutive ones sharing edges, all in `patch`;
// corners on a lattice of quarter cells. Nothing when a triangle would have no area.
void add_fan(std::vector<Triangle>& set, Rng& rng, double cx, double cy, double reach, int patch) {
  const int n = rng.range(3, 6);
  const std::size_t first = set.size();
  std::vector<double> px, py, pw;
  for (int k = 0; k < n; ++k) {
    const double r = reach * (0.3 + 0.7 * rng.uniform()), a = 6.283185307179586 * (k + 0.25 + 0.5 * rng.uniform()) / n;
    px.push_back(std::round((cx + r * std::cos(a)) * 4.0) / 4.0);
    py.push_back(std::round((cy + r * std::sin(a)) * 4.0) / 4.0);
    pw.push_back(1.0 + 9.0 * rng.uniform());
  }
  const double wc = 1.0 + 9.0 * rng.uniform();
  for (int k = 0; k < n; ++k) {
    const int l = (k + 1) % n;
    Triangle t{{cx, px[std::size_t(k)], px[std::size_t(l)]}, {cy, py[std::size_t(k)], py[std::size_t(l)]},
               {wc, pw[std::size_t(k)], pw[std::size_t(l)]}, {-1, -1, -1}, patch};
    if (!(area2(t) > 0.0)) {
      set.resize(first);
      return;
    }
    set.push_back(t);
  }
  for (int k = 0; k < n; ++k) {
    Triangle& t = set[first + std::size_t(k)];
    t.twin[0] = static_cast<int>(first) + (k > 0 ? k - 1 : n - 1);
    t.twin[2] = static_cast<int>(first) + (k + 1 < n ? k + 1 : 0);
  }
}

// Inserts the triangles of `patch` into `grid` as insert_run does, by bands (`band` per triangle,
// from 0 up): before a band, its triangles over cells all covered already are dropped; in a band,
// an edge shared with a member of the same band adds nothing, one shared with a member of an
// earlier band takes that member's outline mark out, every other edge is outline. The last band is
// left open. `inserted` marks the members.
void insert_bands(dmo::CoverageGrid& grid, const std::vector<Triangle>& set, const std::vector<int>& band, int patch,
                  std::vector<char>& inserted) {
  const int bands = *std::max_element(band.begin(), band.end()) + 1;
  for (int b = 0; b < bands; ++b) {
    for (std::size_t t = 0; t < set.size(); ++t) {
      if (set[t].patch != patch || band[t] != b) continue;
      const Triangle& tri = set[t];
      const double x0 = std::min({tri.x[0], tri.x[1], tri.x[2]}), x1 = std::max({tri.x[0], tri.x[1], tri.x[2]});
      const double y0 = std::min({tri.y[0], tri.y[1], tri.y[2]}), y1 = std::max({tri.y[0], tri.y[1], tri.y[2]});
      inserted[t] = !grid.all_frozen(x0, y0, x1, y1);
    }
    for (std::size_t t = 0; t < set.size(); ++t) {
      if (set[t].patch != patch || band[t] != b || !inserted[t]) continue;
      const Triangle& tri = set[t];
      const auto member = [&](int u) { return u >= 0 && set[std::size_t(u)].patch == patch && inserted[std::size_t(u)]; };
      unsigned inner = 0;
      for (int k = 0; k < 3; ++k)
        if (member(tri.twin[k]) && band[std::size_t(tri.twin[k])] == b) inner |= 1u << k;
      grid.add_depth(tri.x, tri.y, tri.w);
      grid.add_count(tri.x, tri.y, 1, inner);
      for (int k = 0; k < 3; ++k) {
        if ((inner >> k) & 1u) continue;
        const int l = k == 2 ? 0 : k + 1;
        if (member(tri.twin[k]) && band[std::size_t(tri.twin[k])] < b) grid.touch_edge(tri.x[l], tri.y[l], tri.x[k], tri.y[k], 1, -1);
        else grid.touch_edge(tri.x[k], tri.y[k], tri.x[l], tri.y[l], 1, 1);
      }
    }
    if (b + 1 < bands) grid.end_band();
  }
}

// Takes out of `grid` the outline marks of the edges patch 1 shares with patch 0 (both inserted),
// then ends the band: what the culler does after either way.
void take_shared_edges(dmo::CoverageGrid& grid, const std::vector<Triangle>& set, const std::vector<char>& inserted,
                       long& shared) {
  for (std::size_t t = 0; t < set.size(); ++t) {
    if (set[t].patch != 1 || !inserted[t]) continue;
    const Triangle& tri = set[t];
    for (int k = 0; k < 3; ++k) {
      const int u = tri.twin[k];
      if (u < 0 || set[std::size_t(u)].patch != 0 || !inserted[std::size_t(u)]) continue;
      ++shared;
      const int l = k == 2 ? 0 : k + 1;
      grid.touch_edge(tri.x[l], tri.y[l], tri.x[k], tri.y[k], 1, -1);
      grid.touch_edge(tri.x[k], tri.y[k], tri.x[l], tri.y[l], 1, -1);
    }
  }
  grid.end_band();
}

struct Tally {
  long direct = 0, direct_differs = 0, direct_shared = 0, direct_right_edge = 0, refused = 0, refused_differs = 0;
};

void one_case(Rng& rng, int index, Tally& tally) {
  std::vector<Triangle> set;
  const int placement = index % 3;  // 0: near patch 0, 1: apart from it, 2: past the right edge
  // Patch 0: a fan, the second half of it given to patch 1 when patch 1 is placed near (edges
  // shared between the patches).
  const double cx0 = 4.0 + rng.range(0, 4 * 14) / 4.0, cy0 = 3.0 + rng.range(0, 4 * 18) / 4.0;
  add_fan(set, rng, cx0, cy0, 2.0 + 4.0 * rng.uniform(), 0);
  if (placement == 0 && !set.empty())
    for (std::size_t t = set.size() / 2; t < set.size(); ++t) set[t].patch = 1;
  const double cx1 = placement == 0   ? cx0 + rng.range(-4 * 6, 4 * 6) / 4.0
                     : placement == 1 ? 26.0 + rng.range(0, 4 * 8) / 4.0
                                      : width - 1.0 + rng.range(0, 4 * 3) / 4.0;
  const double cy1 = placement == 0 ? cy0 + rng.range(-4 * 6, 4 * 6) / 4.0 : 2.0 + rng.range(0, 4 * 20) / 4.0;
  add_fan(set, rng, cx1, cy1, 1.5 + 4.0 * rng.uniform(), 1);
  if (set.empty()) return;
  std::vector<int> band(set.size());
  for (int& b : band) b = rng.range(0, 1);
  std::vector<char> inserted(set.size(), 0);

  dmo::CoverageGrid grid, own;
  grid.reset(width, height);
  if (std::any_of(set.begin(), set.end(), [](const Triangle& t) { return t.patch == 0; })) {
    insert_bands(grid, set, band, 0, inserted);
    grid.end_band();
  }
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, w0 = HUGE_VAL;
  for (const Triangle& t : set)
    if (t.patch == 1)
      for (int k = 0; k < 3; ++k) {
        x0 = std::min(x0, t.x[k]), x1 = std::max(x1, t.x[k]);
        y0 = std::min(y0, t.y[k]), y1 = std::max(y1, t.y[k]);
        w0 = std::min(w0, t.w[k]);
      }
  if (!(x0 <= x1)) return;
  const dmo::CellRect cells = grid.cells_of(x0, y0, x1, y1);

  // The patch's own grid, added into the union.
  dmo::CoverageGrid by_patch = grid;
  std::vector<char> inserted_by_patch = inserted;
  own.reset(width, height);
  long shared_by_patch = 0;
  if (own.seed_frozen(by_patch, cells, static_cast<float>(1.0 / w0))) {
    insert_bands(own, set, band, 1, inserted_by_patch);
    by_patch.absorb(own, true);
    take_shared_edges(by_patch, set, inserted_by_patch, shared_by_patch);
  }
  // Straight into the union.
  dmo::CoverageGrid direct = grid;
  std::vector<char> inserted_direct = inserted;
  long shared_direct = 0;
  insert_bands(direct, set, band, 1, inserted_direct);
  direct.end_band();
  take_shared_edges(direct, set, inserted_direct, shared_direct);

  const bool same = direct.same_cells(by_patch) && inserted_direct == inserted_by_patch;
  if (grid.untouched(cells)) {
    ++tally.direct;
    if (shared_direct > 0) ++tally.direct_shared;
    if (cells.x1 == width - 1) ++tally.direct_right_edge;
    if (!same) ++tally.direct_differs;
    CHECK_MSG(same, "case %d: the direct insertion left other cells than the patch's own grid", index);
  } else {
    ++tally.refused;
    if (!same) ++tally.refused_differs;
  }
}

}  // namespace

int main() {
  Rng rng(20261129);
  Tally tally;
  const int cases = 3000;
  for (int c = 0; c < cases; ++c) one_case(rng, c, tally);
  std::printf("%d cases: direct allowed %ld (%ld reaching the right edge, %ld sharing edges), differing %ld; "
              "refused %ld, of which the direct way would differ in %ld\n",
              cases, tally.direct, tally.direct_right_edge, tally.direct_shared, tally.direct_differs, tally.refused,
              tally.refused_differs);
  // Both ways are exercised, and refusing matters: where the union holds something, the direct way
  // would often leave other cells.
  CHECK(tally.direct > 500);
  CHECK(tally.direct_right_edge > 100);
  CHECK(tally.refused_differs > 100);
  CHECK(tally.direct_shared == 0);
  CHECK(tally.direct_differs == 0);
  return cullkit_test::report("test_mesh_occlusion_direct");
}
