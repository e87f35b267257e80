// cullkit/detail/mesh_occlusion/query.hpp: one frame of MeshOcclusionCuller::cull, as named steps:
// frustum walk, object boxes on screen, occluder choice, occluder bands into the coverage grid,
// object tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "../../geometry/camera.hpp"
#include "coverage.hpp"
#include "index.hpp"
#include "view.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// An object's box seen from the eye: its grid rectangle and its smallest depth, when every corner
/// is clearly beyond the near plane (`usable`); otherwise it can be neither hidden nor measured.
struct BoxView {
  double x0, y0, x1, y1;
  double w_min;
  bool usable;
};

/// Per-thread working memory of a query; only grows.
struct Scratch {
  MeshOcclusionStats stats;
  std::vector<std::uint32_t> in_frustum;  // tree positions, then objects
  std::vector<BoxView> boxes;             // parallel to in_frustum
  std::vector<std::pair<float, std::uint32_t>> candidates;  // (screen cells, position in in_frustum)
  std::vector<std::pair<double, std::uint32_t>> occluders;  // (depth key, object)
  // Per-frame caches, valid where the stamp equals `frame`.
  const void* owner = nullptr;
  std::uint32_t frame = 0;
  std::vector<std::uint32_t> vertex_stamp, vertex_slot, triangle_stamp;
  std::vector<Projected> projected;
  View view;
  CoverageGrid grid;
};

/// Makes the caches fit `index` and starts a new frame.
inline void begin_frame(const MeshIndex& index, Scratch& s) {
  if (s.owner != &index || s.vertex_stamp.size() != index.positions.size() ||
      s.triangle_stamp.size() != index.corners.size() / 3) {
    s.owner = &index;
    s.vertex_stamp.assign(index.positions.size(), 0);
    s.vertex_slot.assign(index.positions.size(), 0);
    s.triangle_stamp.assign(index.corners.size() / 3, 0);
    s.frame = 0;
  }
  if (++s.frame == 0) {
    std::fill(s.vertex_stamp.begin(), s.vertex_stamp.end(), 0);
    std::fill(s.triangle_stamp.begin(), s.triangle_stamp.end(), 0);
    s.frame = 1;
  }
  s.projected.clear();
}

inline const Projected& project_vertex(const MeshIndex& index, Scratch& s, std::uint32_t v) {
  if (s.vertex_stamp[v] != s.frame) {
    s.vertex_stamp[v] = s.frame;
    s.vertex_slot[v] = static_cast<std::uint32_t>(s.projected.size());
    const glm::vec3& p = index.positions[v];
    s.projected.push_back(s.view.project(p.x, p.y, p.z));
  }
  return s.projected[s.vertex_slot[v]];
}

inline BoxView project_box(const View& view, const Aabb& box) {
  BoxView b{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL, true};
  for (int k = 0; k < 8; ++k) {
    const Projected p = view.project(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y,
                                     k & 4 ? box.max.z : box.min.z);
    if (!p.usable) {
      b.usable = false;
      return b;
    }
    b.x0 = std::min(b.x0, p.x);
    b.x1 = std::max(b.x1, p.x);
    b.y0 = std::min(b.y0, p.y);
    b.y1 = std::max(b.y1, p.y);
    b.w_min = std::min(b.w_min, p.w);
  }
  return b;
}

/// Picks occluder objects by size on screen, biggest first, within the triangle budget; fills
/// `s.occluders` sorted nearest first.
inline void choose_occluders(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const double grid_cells = double(s.grid.width()) * double(s.grid.height());
  const double min_cells = std::max(1.0, params.min_occluder_screen_fraction * grid_cells);
  s.candidates.clear();
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const BoxView& b = s.boxes[i];
    double cells = grid_cells;  // a box through the near plane: near the eye, likely big
    if (b.usable) {
      const double w = std::min(b.x1, double(s.grid.width())) - std::max(b.x0, 0.0);
      const double h = std::min(b.y1, double(s.grid.height())) - std::max(b.y0, 0.0);
      cells = w > 0.0 && h > 0.0 ? w * h : 0.0;
    }
    if (cells >= min_cells) s.candidates.emplace_back(static_cast<float>(cells), static_cast<std::uint32_t>(i));
  }
  // Biggest first. A full sort of the candidates only (they are the objects above the size floor).
  std::sort(s.candidates.begin(), s.candidates.end(),
            [](const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
              return a.first > b.first || (a.first == b.first && a.second < b.second);
            });
  s.occluders.clear();
  std::uint64_t budget = params.occluder_triangle_budget;
  for (const auto& c : s.candidates) {
    if (s.occluders.size() >= params.max_occluder_objects) break;
    const std::uint32_t o = s.in_frustum[c.second];
    const std::uint32_t n = index.objects[o].triangle_count;
    if (n > budget) continue;
    budget -= n;
    const BoxView& b = s.boxes[c.second];
    s.occluders.emplace_back(b.usable ? b.w_min : 0.0, o);
  }
  std::sort(s.occluders.begin(), s.occluders.end());
}

/// Inserts one occluder object as a band. Returns the triangles inserted.
inline std::size_t insert_occluder(const MeshIndex& index, Scratch& s, std::uint32_t object) {
  const MeshObject& range = index.objects[object];
  CoverageGrid& grid = s.grid;
  const int orient = s.view.orient;
  const double gw = grid.width(), gh = grid.height();
  std::size_t inserted = 0;
  grid.begin_band();
  for (std::uint32_t t = range.first_triangle; t < range.first_triangle + range.triangle_count; ++t) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
    if (c[0] == none) continue;
    double x[3], y[3], w[3];
    bool usable = true;
    for (int k = 0; k < 3 && usable; ++k) {
      const Projected& p = project_vertex(index, s, c[k]);
      usable = p.usable;
      x[k] = p.x;
      y[k] = p.y;
      w[k] = p.w;
    }
    if (!usable) continue;  // a corner not clearly beyond the near plane: its neighbours' edges become outline
    const double xmin = std::min(std::min(x[0], x[1]), x[2]), xmax = std::max(std::max(x[0], x[1]), x[2]);
    const double ymin = std::min(std::min(y[0], y[1]), y[2]), ymax = std::max(std::max(y[0], y[1]), y[2]);
    if (xmax < 0.0 || xmin > gw || ymax < 0.0 || ymin > gh) continue;
    // Front-facing, clearly: back-facing and edge-on triangles are left out (their neighbours'
    // edges then stay on the outline, which only covers less).
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    const double extent = std::max(xmax - xmin, ymax - ymin);
    if (!(area2 * orient > 1e-9 * extent * extent)) continue;
    grid.add_depth(x, y, w);
    grid.add_count(x, y, orient);
    for (int k = 0; k < 3; ++k) {
      const int l = k == 2 ? 0 : k + 1;
      const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
      // The twin already in: its edge (l -> k, as its triangle runs) leaves the outline, and this
      // one never joins it.
      if (twin != none && s.triangle_stamp[twin / 3] == s.frame) grid.touch_edge(x[l], y[l], x[k], y[k], orient, -1);
      else grid.touch_edge(x[k], y[k], x[l], y[l], orient, 1);
    }
    s.triangle_stamp[t] = s.frame;
    ++inserted;
  }
  grid.end_band();
  return inserted;
}

inline void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                 std::vector<std::uint32_t>& out) {
  out.clear();
  MeshOcclusionStats& stats = s.stats;
  stats = MeshOcclusionStats{};
  index.tree.cull(frustum_of(camera), s.in_frustum);
  for (std::uint32_t& i : s.in_frustum) i = index.tree_objects[i];
  stats.objects_in_frustum = s.in_frustum.size();
  out.insert(out.end(), index.unusable.begin(), index.unusable.end());
  stats.objects_unusable_visible = index.unusable.size();

  s.view.setup(camera, params.grid_width, params.grid_height);
  stats.occlusion_enabled = s.view.enabled;
  if (!s.view.enabled || s.in_frustum.empty()) {
    out.insert(out.end(), s.in_frustum.begin(), s.in_frustum.end());
    return;
  }
  begin_frame(index, s);
  s.grid.reset(params.grid_width, params.grid_height);
  s.boxes.resize(s.in_frustum.size());
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) s.boxes[i] = project_box(s.view, index.bounds[s.in_frustum[i]]);

  choose_occluders(index, params, s);
  for (const auto& o : s.occluders) {
    const std::size_t n = insert_occluder(index, s, o.second);
    stats.occluder_triangles += n;
    stats.occluders_used += n > 0;
  }
  s.grid.finish();
  stats.cells_covered = s.grid.covered_cells();

  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const BoxView& b = s.boxes[i];
    bool hidden = false;
    if (b.usable) {
      const CellRect r = s.grid.cells_of(b.x0, b.y0, b.x1, b.y1);
      // A box that misses the grid meets no ray through the frustum.
      const float threshold = static_cast<float>((1.0 / b.w_min) * (1.0 + 0x1p-20));
      hidden = r.empty() || (std::isfinite(threshold) && s.grid.all_nearer(r, threshold));
    }
    if (hidden) ++stats.objects_hidden;
    else out.push_back(s.in_frustum[i]);
  }
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
