// Triangles inserted into a CoverageGrid on their own, as the culler inserts an occluder patch's:
// shared by the tests of the coverage grid against points (test_mesh_occlusion_coverage_grid and
// test_mesh_occlusion_margins).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <cullkit/detail/mesh_occlusion/coverage.hpp>

namespace coverage_grid_test {

namespace dmo = cullkit::detail::mesh_occlusion;

/// A front-facing triangle in grid coordinates (positive area: orient +1), with its depths.
struct Triangle {
  double x[3], y[3], w[3];
  int twin[3];  // per edge (corner k to the next), the triangle of the set sharing it, or -1
  int patch;
};

inline double area2(const Triangle& t) {
  return (t.x[1] - t.x[0]) * (t.y[2] - t.y[0]) - (t.x[2] - t.x[0]) * (t.y[1] - t.y[0]);
}

/// Inserts the triangles of `patch` (-1: all) into `grid` as one band: an edge shared with another
/// member leaves no crossings and no mark; every other edge is outline.
inline void insert_band(dmo::CoverageGrid& grid, const std::vector<Triangle>& set, int patch) {
  const auto member = [&](int t) { return t >= 0 && (patch < 0 || set[std::size_t(t)].patch == patch); };
  for (const Triangle& t : set) {
    if (patch >= 0 && t.patch != patch) continue;
    unsigned inner = 0;
    for (int k = 0; k < 3; ++k) inner |= member(t.twin[k]) ? 1u << k : 0u;
    grid.add_depth(t.x, t.y, t.w);
    grid.add_count(t.x, t.y, 1, inner);  // orient +1: front faces have positive area here
    for (int k = 0; k < 3; ++k) {
      if ((inner >> k) & 1u) continue;
      const int l = k == 2 ? 0 : k + 1;
      grid.touch_edge(t.x[k], t.y[k], t.x[l], t.y[l], 1, 1);
    }
  }
  grid.end_band();
}

/// Patch 0, then patch 1, each in a grid of its own added into the union, as the culler does.
inline void insert_patches(dmo::CoverageGrid& grid, dmo::CoverageGrid& own, const std::vector<Triangle>& set) {
  for (int patch = 0; patch < 2; ++patch) {
    double xmin = HUGE_VAL, ymin = HUGE_VAL, xmax = -HUGE_VAL, ymax = -HUGE_VAL, wmin = HUGE_VAL;
    for (const Triangle& t : set) {
      if (t.patch != patch) continue;
      for (int k = 0; k < 3; ++k) {
        xmin = std::min(xmin, t.x[k]);
        xmax = std::max(xmax, t.x[k]);
        ymin = std::min(ymin, t.y[k]);
        ymax = std::max(ymax, t.y[k]);
        wmin = std::min(wmin, t.w[k]);
      }
    }
    if (!(xmin <= xmax)) continue;
    own.reset(grid.width(), grid.height());
    if (!own.seed_frozen(grid, grid.cells_of(xmin, ymin, xmax, ymax), static_cast<float>(1.0 / wmin))) continue;
    insert_band(own, set, patch);
    grid.absorb(own, true);
    if (patch == 1) {
      for (const Triangle& t : set) {
        if (t.patch != 1) continue;
        for (int k = 0; k < 3; ++k) {
          if (t.twin[k] < 0 || set[std::size_t(t.twin[k])].patch != 0) continue;
          const int l = k == 2 ? 0 : k + 1;
          grid.touch_edge(t.x[l], t.y[l], t.x[k], t.y[k], 1, -1);  // patch 0's edge, as its triangle runs
          grid.touch_edge(t.x[k], t.y[k], t.x[l], t.y[l], 1, -1);
        }
      }
    }
    grid.end_band();
  }
}

}  // namespace coverage_grid_test
