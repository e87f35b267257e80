// The coverage grid on its own, against points. Random fans of front-facing triangles (their inner
// edges shared, so they fuse) and loose triangles, with corners on a lattice of quarter cells, go in
// as the culler inserts them: one band (depth bounds, counts without the shared edges, outline
// edges), or two patches, each fan split between them, each patch in a grid of its own seeded from
// the union, added into the union, and the edges the patches share taken out of the union's outline.
// So edges run exactly through cell centres and corners, where the grid's margins decide. Then every
// cell the grid calls covered is checked at 17 x 17 points over its closed square (the lattice of
// sixteenths: every containment test below is exact in double): each point must lie in some
// triangle, and the cell's depth bound must be no nearer than the nearest triangle through the
// point (the largest 1/w there). The test counts the covered cells it checked, so it can fail.
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
using coverage_grid_test::insert_band;
using coverage_grid_test::insert_patches;

namespace {

// The largest 1/w of the triangles holding (px, py) (closed), 0 when none holds it.
double nearest_inverse_depth(const std::vector<Triangle>& set, double px, double py) {
  double best = 0.0;
  for (const Triangle& t : set) {
    double b[3];
    for (int k = 0; k < 3; ++k) {
      const int l = k == 2 ? 0 : k + 1;
      b[k] = (t.x[l] - t.x[k]) * (py - t.y[k]) - (t.y[l] - t.y[k]) * (px - t.x[k]);  // exact: sixteenths
    }
    if (b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0) continue;
    const double a = b[0] + b[1] + b[2];
    // Barycentric weight of corner k is the sub-area opposite it: b[(k + 1) % 3].
    const double inv = (b[1] * (1.0 / t.w[0]) + b[2] * (1.0 / t.w[1]) + b[0] * (1.0 / t.w[2])) / a;
    best = std::max(best, inv);
  }
  return best;
}

double lattice(Rng& rng, int cells) { return rng.range(-8, 4 * cells + 8) / 4.0; }

// A fan around a centre: corners in counter-clockwise order of angle, consecutive triangles sharing
// their edges from the centre. Triangles of zero area are left out (with their edges unshared).
void add_fan(std::vector<Triangle>& set, Rng& rng, int width, int height) {
  const double cx = lattice(rng, width), cy = lattice(rng, height);
  const int n = rng.range(3, 7);
  std::vector<std::pair<double, std::pair<double, double>>> ring;
  for (int k = 0; k < n; ++k) {
    const double r = rng.range(2, 40) / 4.0, a = 6.283185307179586 * (k + 0.25 + 0.5 * rng.uniform()) / n;
    const double px = std::round((cx + r * std::cos(a)) * 4.0) / 4.0, py = std::round((cy + r * std::sin(a)) * 4.0) / 4.0;
    ring.push_back({a, {px, py}});
  }
  const double wc = 1.0 + 9.0 * rng.uniform();
  std::vector<double> wr;
  for (int k = 0; k < n; ++k) wr.push_back(1.0 + 9.0 * rng.uniform());
  const bool closed = rng.range(0, 1) == 1;
  const std::size_t first = set.size();
  for (int k = 0; k + (closed ? 0 : 1) < n; ++k) {
    const int l = (k + 1) % n;
    Triangle t{{cx, ring[std::size_t(k)].second.first, ring[std::size_t(l)].second.first},
               {cy, ring[std::size_t(k)].second.second, ring[std::size_t(l)].second.second},
               {wc, wr[std::size_t(k)], wr[std::size_t(l)]},
               {-1, -1, -1},
               0};
    if (!(area2(t) > 0.0)) {
      set.resize(first);  // a fold: the fan would overlap itself; keep it simple and drop it
      return;
    }
    set.push_back(t);
  }
  const int count = static_cast<int>(set.size() - first);
  // Edge 0 (centre -> ring k) is shared with the previous triangle, edge 2 (ring l -> centre) with
  // the next. The fan's first `split` triangles go to patch 0, the others to patch 1.
  const int split = rng.range(0, count);
  for (int k = 0; k < count; ++k) {
    Triangle& t = set[first + std::size_t(k)];
    if (k > 0 || closed) t.twin[0] = static_cast<int>(first) + (k > 0 ? k - 1 : count - 1);
    if (k + 1 < count || closed) t.twin[2] = static_cast<int>(first) + (k + 1 < count ? k + 1 : 0);
    t.patch = k < split ? 0 : 1;
  }
}

void add_loose(std::vector<Triangle>& set, Rng& rng, int width, int height) {
  Triangle t{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {-1, -1, -1}, rng.range(0, 1)};
  for (int k = 0; k < 3; ++k) {
    t.x[k] = lattice(rng, width);
    t.y[k] = lattice(rng, height);
    t.w[k] = 1.0 + 9.0 * rng.uniform();
  }
  if (area2(t) < 0.0) {
    std::swap(t.x[1], t.x[2]);
    std::swap(t.y[1], t.y[2]);
    std::swap(t.w[1], t.w[2]);
  }
  if (area2(t) > 0.0) set.push_back(t);
}

struct Tally {
  long covered = 0, points = 0, failures = 0;
};

void one_case(Rng& rng, dmo::CoverageGrid& grid, dmo::CoverageGrid& own, Tally& tally, int index) {
  const int width = 24, height = 16;
  grid.reset(width, height);
  std::vector<Triangle> set;
  const int fans = rng.range(1, 3), loose = rng.range(0, 3);
  for (int k = 0; k < fans; ++k) add_fan(set, rng, width, height);
  for (int k = 0; k < loose; ++k) add_loose(set, rng, width, height);
  if (index % 2 == 0) insert_band(grid, set, -1);
  else insert_patches(grid, own, set);
  grid.finish();
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const dmo::CellRect cell{i, j, i, j};
      if (!grid.all_nearer(cell, 0.0f)) continue;
      ++tally.covered;
      double least = HUGE_VAL;
      for (int b = 0; b <= 16; ++b)
        for (int a = 0; a <= 16; ++a) {
          ++tally.points;
          least = std::min(least, nearest_inverse_depth(set, i + a / 16.0, j + b / 16.0));
        }
      // Covered at a bound no nearer than the nearest hit of every point, to the last bit of the
      // float bound (`below`: the largest float not above `least`).
      float below = static_cast<float>(least);
      if (static_cast<double>(below) > least) below = std::nextafter(below, 0.0f);
      const bool ok = least > 0.0 && !grid.all_nearer(cell, below);
      if (!ok) {
        ++tally.failures;
        CHECK_MSG(ok, "case %d: cell (%d, %d) covered, but %s", index, i, j,
                  least > 0.0 ? "its bound is nearer than a point's nearest hit" : "a point of it is in no triangle");
      }
    }
}

}  // namespace

int main() {
  Rng rng(20261128);
  dmo::CoverageGrid grid, own;
  Tally tally;
  const int cases = 1500;
  for (int c = 0; c < cases; ++c) one_case(rng, grid, own, tally, c);
  std::printf("%d cases: %ld covered cells checked at %ld points, %ld wrong\n", cases, tally.covered, tally.points,
              tally.failures);
  CHECK(tally.covered > 20000);  // the check has cells to fail on
  CHECK(tally.failures == 0);
  return cullkit_test::report("test_mesh_occlusion_coverage_grid");
}
