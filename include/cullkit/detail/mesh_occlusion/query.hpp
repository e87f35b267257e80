// cullkit/detail/mesh_occlusion/query.hpp: one frame of MeshOcclusionCuller::cull, as named steps:
// frustum walk, object boxes on screen, occluder choice, occluder bands into the coverage grid,
// object tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

#include "../../geometry/camera.hpp"
#include "../../occlusion_tree.hpp"
#include "coverage.hpp"
#include "index.hpp"
#include "phase_times.hpp"
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
  Frustum frustum;                        // this frame's
  glm::vec3 view_eye{0.0f};               // this frame's eye
  std::vector<std::uint32_t> in_frustum;  // tree positions, then objects
  std::vector<BoxView> boxes;             // parallel to in_frustum
  std::vector<std::pair<float, std::uint32_t>> candidates;  // (screen cells, patch)
  std::vector<std::pair<double, std::uint32_t>> occluders;  // (depth key, patch)
  std::vector<std::pair<std::uint32_t, std::uint32_t>> triangles, sort_buffer;  // (depth bits, triangle)
  // Per-frame caches, valid where the stamp equals `frame`.
  const void* owner = nullptr;
  std::uint32_t frame = 0;
  std::vector<std::uint32_t> vertex_stamp, vertex_slot, triangle_stamp, triangle_band, patch_stamp;
  std::vector<BoxView> patch_boxes;       // per patch, valid where patch_stamp equals `frame`
  std::vector<Projected> projected;
  View view;
  CoverageGrid grid;
  std::vector<std::pair<float, std::uint32_t>> box_candidates;  // (screen cells, object)
  std::vector<Aabb> box_occluders;
  OcclusionTree box_tree{glm::vec3(0.0f)};  // the solid boxes' hidden region, when box_occluders is not empty
};

/// Sorts (key, value) pairs by key, stable: three passes of 11 bits.
inline void radix_sort(std::vector<std::pair<std::uint32_t, std::uint32_t>>& items,
                       std::vector<std::pair<std::uint32_t, std::uint32_t>>& buffer) {
  if (items.size() < 2) return;
  buffer.resize(items.size());
  for (int pass = 0; pass < 3; ++pass) {
    const int shift = 11 * pass;
    std::uint32_t offsets[2048] = {};
    for (const auto& it : items) ++offsets[(it.first >> shift) & 2047u];
    std::uint32_t sum = 0;
    for (std::uint32_t& o : offsets) {
      const std::uint32_t n = o;
      o = sum;
      sum += n;
    }
    for (const auto& it : items) buffer[offsets[(it.first >> shift) & 2047u]++] = it;
    items.swap(buffer);
  }
}

/// Makes the caches fit `index` and starts a new frame.
inline void begin_frame(const MeshIndex& index, Scratch& s) {
  if (s.owner != &index || s.vertex_stamp.size() != index.positions.size() ||
      s.triangle_stamp.size() != index.corners.size() / 3 || s.patch_stamp.size() != index.patches.patches.size()) {
    s.owner = &index;
    s.vertex_stamp.assign(index.positions.size(), 0);
    s.vertex_slot.assign(index.positions.size(), 0);
    s.triangle_stamp.assign(index.corners.size() / 3, 0);
    s.triangle_band.assign(index.corners.size() / 3, 0);
    s.patch_stamp.assign(index.patches.patches.size(), 0);
    s.patch_boxes.resize(index.patches.patches.size());
    s.frame = 0;
  }
  if (++s.frame == 0) {
    std::fill(s.vertex_stamp.begin(), s.vertex_stamp.end(), 0);
    std::fill(s.triangle_stamp.begin(), s.triangle_stamp.end(), 0);
    std::fill(s.patch_stamp.begin(), s.patch_stamp.end(), 0);
    s.frame = 1;
  }
  s.projected.clear();
}

inline const Projected& project_vertex(const MeshIndex& index, Scratch& s, std::uint32_t v) {
  if (s.vertex_stamp[v] != s.frame) {
    PhaseProbe probe;
    s.vertex_stamp[v] = s.frame;
    s.vertex_slot[v] = static_cast<std::uint32_t>(s.projected.size());
    const glm::vec3& p = index.positions[v];
    s.projected.push_back(s.view.project(p.x, p.y, p.z));
    probe.next(phase_project);
  }
  return s.projected[s.vertex_slot[v]];
}

inline BoxView project_box(const View& view, const Aabb& box) {
  // Clip x, y, w and the near-plane value are affine: the corners are the values at box.min
  // plus any of the three edge vectors' contributions.
  const double q[3] = {double(box.min.x) - view.eye[0], double(box.min.y) - view.eye[1], double(box.min.z) - view.eye[2]};
  const double e[3] = {double(box.max.x) - double(box.min.x), double(box.max.y) - double(box.min.y),
                       double(box.max.z) - double(box.min.z)};
  double base[4], step[3][4], scale[4];
  for (int r = 0; r < 3; ++r) {
    base[r] = view.row[r][0] * q[0] + view.row[r][1] * q[1] + view.row[r][2] * q[2];
    for (int a = 0; a < 3; ++a) step[a][r] = view.row[r][a] * e[a];
  }
  const double* n = view.near_plane;
  base[3] = n[0] * box.min.x + n[1] * box.min.y + n[2] * box.min.z + n[3];
  for (int a = 0; a < 3; ++a) step[a][3] = n[a] * e[a];
  // Tolerances as in View::project, taken at their largest over the box.
  const double reach[3] = {std::max(std::fabs(q[0]), std::fabs(q[0] + e[0])), std::max(std::fabs(q[1]), std::fabs(q[1] + e[1])),
                           std::max(std::fabs(q[2]), std::fabs(q[2] + e[2]))};
  const double far_coord[3] = {std::max(std::fabs(double(box.min.x)), std::fabs(double(box.max.x))),
                               std::max(std::fabs(double(box.min.y)), std::fabs(double(box.max.y))),
                               std::max(std::fabs(double(box.min.z)), std::fabs(double(box.max.z)))};
  scale[2] = std::fabs(view.row[2][0]) * reach[0] + std::fabs(view.row[2][1]) * reach[1] + std::fabs(view.row[2][2]) * reach[2];
  scale[3] = std::fabs(n[0]) * far_coord[0] + std::fabs(n[1]) * far_coord[1] + std::fabs(n[2]) * far_coord[2] + std::fabs(n[3]);
  // Rounding of the sums below is far inside these tolerances (2^-18 relative).
  const double ntol = 0x1p-18 * scale[3] + 0x1p-40 * scale[3];
  const double wtol = 1e-8 * scale[2];
  BoxView b{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL, false};
  for (int k = 0; k < 8; ++k) {
    double c[4] = {base[0], base[1], base[2], base[3]};
    for (int a = 0; a < 3; ++a)
      if ((k >> a) & 1)
        for (int r = 0; r < 4; ++r) c[r] += step[a][r];
    if (!(c[3] > ntol) || !(c[2] > wtol)) return b;
    const double inv = 1.0 / c[2];
    const double x = c[0] * inv * view.scale_x + view.offset_x, y = c[1] * inv * view.scale_y + view.offset_y;
    b.x0 = std::min(b.x0, x);
    b.x1 = std::max(b.x1, x);
    b.y0 = std::min(b.y0, y);
    b.y1 = std::max(b.y1, y);
    b.w_min = std::min(b.w_min, c[2]);
  }
  b.usable = std::isfinite(b.x0) && std::isfinite(b.x1) && std::isfinite(b.y0) && std::isfinite(b.y1) && std::isfinite(b.w_min);
  return b;
}

/// A patch's box seen from the eye, projected once per frame.
inline const BoxView& patch_box(const MeshIndex& index, Scratch& s, std::uint32_t patch) {
  if (s.patch_stamp[patch] != s.frame) {
    s.patch_stamp[patch] = s.frame;
    s.patch_boxes[patch] = project_box(s.view, index.patches.patches[patch].box);
  }
  return s.patch_boxes[patch];
}

/// Grid cells a box view covers on screen (all of them for a box through the near plane: it is
/// near the eye, likely big).
inline double screen_cells(const BoxView& b, const CoverageGrid& grid) {
  if (!b.usable) return double(grid.width()) * double(grid.height());
  const double w = std::min(b.x1, double(grid.width())) - std::max(b.x0, 0.0);
  const double h = std::min(b.y1, double(grid.height())) - std::max(b.y0, 0.0);
  return w > 0.0 && h > 0.0 ? w * h : 0.0;
}

/// Picks occluder patches by size on screen, biggest first, within the triangle budget; fills
/// `s.occluders`. A patch too big for what is left of the budget is skipped, smaller ones still fit.
/// An object of one patch is measured by its own box (already projected).
inline void choose_occluders(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const double grid_cells = double(s.grid.width()) * double(s.grid.height());
  const double min_cells = std::max(1.0, params.min_occluder_screen_fraction * grid_cells);
  const PatchSet& ps = index.patches;
  s.candidates.clear();
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const std::uint32_t o = s.in_frustum[i];
    const std::uint32_t p0 = ps.object_first[o], p1 = ps.object_first[o + 1];
    if (p0 == p1) continue;
    const double object_cells = screen_cells(s.boxes[i], s.grid);
    if (object_cells < min_cells) continue;
    if (p1 - p0 == 1) {
      s.candidates.emplace_back(static_cast<float>(object_cells), p0);
      continue;
    }
    for (std::uint32_t p = p0; p < p1; ++p) {
      // A patch outside the frustum (behind the eye, say) would otherwise count as through the near
      // plane, the biggest of all.
      if (s.frustum.classify(ps.patches[p].box) == Containment::outside) continue;
      const double cells = screen_cells(patch_box(index, s, p), s.grid);
      if (cells >= min_cells) s.candidates.emplace_back(static_cast<float>(cells), p);
    }
  }
  // Biggest first. A full sort of the candidates only (they are the patches above the size floor).
  std::sort(s.candidates.begin(), s.candidates.end(),
            [](const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
              return a.first > b.first || (a.first == b.first && a.second < b.second);
            });
  s.occluders.clear();
  std::uint64_t budget = params.occluder_triangle_budget;
  for (const auto& c : s.candidates) {
    if (s.occluders.size() >= params.max_occluder_objects || budget == 0) break;
    const std::uint32_t n = ps.patches[c.second].count;
    if (n > budget) continue;
    budget -= n;
    s.occluders.emplace_back(0.0, c.second);
  }
}

/// Projects the occluder patches' triangles and keeps those that can occlude: every corner
/// clearly beyond the near plane, clearly front-facing, touching the grid. Fills `s.triangles`
/// with (largest corner depth as float bits, triangle), nearest first.
inline void gather_triangles(const MeshIndex& index, Scratch& s) {
  const int orient = s.view.orient;
  const double gw = s.grid.width(), gh = s.grid.height();
  s.triangles.clear();
  const PatchSet& ps = index.patches;
  for (const auto& o : s.occluders) {
    const Patch& patch = ps.patches[o.second];
    for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
      const std::uint32_t t = ps.triangles[k];
      const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
      // Objects may overlap: a triangle goes in once.
      if (c[0] == none || s.triangle_stamp[t] == s.frame) continue;
      double x[3], y[3], w[3];
      bool usable = true;
      for (int k = 0; k < 3 && usable; ++k) {
        const Projected& p = project_vertex(index, s, c[k]);
        usable = p.usable;
        x[k] = p.x;
        y[k] = p.y;
        w[k] = p.w;
      }
      // A corner not clearly beyond the near plane: the triangle is left out, and its
      // neighbours' edges become outline.
      if (!usable) continue;
      const double xmin = std::min(std::min(x[0], x[1]), x[2]), xmax = std::max(std::max(x[0], x[1]), x[2]);
      const double ymin = std::min(std::min(y[0], y[1]), y[2]), ymax = std::max(std::max(y[0], y[1]), y[2]);
      if (xmax < 0.0 || xmin > gw || ymax < 0.0 || ymin > gh) continue;
      // Clearly front-facing: back-facing and edge-on triangles are left out (their neighbours'
      // edges then stay on the outline, which only covers less).
      const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
      const double extent = std::max(xmax - xmin, ymax - ymin);
      if (!(area2 * orient > 1e-9 * extent * extent)) continue;
      double nearest = std::min(std::min(w[0], w[1]), w[2]);
      // A part of a cut triangle goes in only when all corners of the whole triangle are clearly
      // beyond the near plane, and sorts as the whole (its nearest corner is one of the triangle's
      // corners): the parts then share a band and their inner edges cancel within it. Parts of a
      // triangle through the near plane are left out with it: inserted alone, their inner edges
      // would be outline across cells that nearer occluders cover (measured: fzk_haus kept more).
      if (!index.parts.whole.empty() && index.parts.whole[t] != none) {
        const std::uint32_t* whole = &index.parts.whole_corners[3 * std::size_t(index.parts.whole[t])];
        for (int k = 0; k < 3 && usable; ++k) {
          const Projected p = project_vertex(index, s, whole[k]);
          usable = p.usable;
          nearest = std::min(nearest, p.w);
        }
        if (!usable) continue;
      }
      const float key = static_cast<float>(nearest);
      std::uint32_t bits;
      std::memcpy(&bits, &key, sizeof bits);  // positive floats order as their bits
      s.triangles.emplace_back(bits, t);
      s.triangle_stamp[t] = s.frame;
    }
  }
  radix_sort(s.triangles, s.sort_buffer);
}

/// Inserts the gathered triangles nearest first, in bands of similar depth, so a cell freezes at
/// the depth of the nearest layer that covers it. Within a band, an edge shared by two of its
/// triangles is never touched: it cancels before the band ends. Returns the cells covered.
inline std::size_t insert_triangles(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  CoverageGrid& grid = s.grid;
  PhaseProbe probe;
  const int orient = s.view.orient;
  const float ratio = 1.0f + std::max(0.0f, params.depth_band_ratio);
  // Bands: runs of the sorted triangles whose nearest depth is within `ratio` of the run's first.
  std::uint32_t band = 0;
  float band_start = 0.0f;
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    float key;
    std::memcpy(&key, &s.triangles[i].first, sizeof key);
    if (i == 0 || !(key <= band_start * ratio)) {
      band_start = key;
      ++band;
    }
    s.triangle_band[s.triangles[i].second] = band;
  }
  std::size_t covered = 0;
  const auto corners_of = [&](std::uint32_t t, double* x, double* y, double* w) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
    for (int k = 0; k < 3; ++k) {
      const Projected& p = s.projected[s.vertex_slot[c[k]]];
      x[k] = p.x;
      y[k] = p.y;
      w[k] = p.w;
    }
  };
  for (std::size_t begin = 0, end = 0; begin < s.triangles.size(); begin = end) {
    const std::uint32_t my_band = s.triangle_band[s.triangles[begin].second];
    end = begin;
    while (end < s.triangles.size() && s.triangle_band[s.triangles[end].second] == my_band) ++end;
    // A triangle over cells that are all covered already can change nothing that matters: it is
    // dropped, as if it were no occluder (decided for the whole band before any of its edges
    // cancel against a neighbour's).
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = s.triangles[i].second;
      double x[3], y[3], w[3];
      corners_of(t, x, y, w);
      if (grid.all_frozen(x, y)) s.triangle_stamp[t] = 0;
    }
    probe.next(phase_bands);
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = s.triangles[i].second;
      if (s.triangle_stamp[t] != s.frame) continue;
      ++s.stats.occluder_triangles;
      double x[3], y[3], w[3];
      corners_of(t, x, y, w);
      probe.next(phase_bands);
      grid.add_depth(x, y, w);
      probe.next(phase_depth);
      std::uint32_t twin_band[3];
      unsigned inner = 0;  // edges shared with a triangle of this band
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
        const bool twin_here = twin != none && s.triangle_stamp[twin / 3] == s.frame;
        twin_band[k] = twin_here ? s.triangle_band[twin / 3] : none;
        if (twin_band[k] == my_band) inner |= 1u << k;
      }
      // An edge shared within the band adds crossings from both triangles that cancel bit for bit
      // (the same endpoints, the same arithmetic, opposite signs): both leave them out.
      grid.add_count(x, y, orient, inner);
      probe.next(phase_counts);
      for (int k = 0; k < 3; ++k) {
        const int l = k == 2 ? 0 : k + 1;
        if ((inner >> k) & 1u) continue;  // cancels within the band
        // The twin in an earlier band: its edge (l -> k, as its triangle runs) leaves the
        // outline, and this one never joins it.
        if (twin_band[k] < my_band) grid.touch_edge(x[l], y[l], x[k], y[k], orient, -1);
        else grid.touch_edge(x[k], y[k], x[l], y[l], orient, 1);
      }
      probe.next(phase_edges);
    }
    covered += grid.end_band();
    probe.next(phase_end_band);
  }
  return covered;
}

/// True when every cell the box view's rectangle touches is covered nearer than the box.
inline bool rect_hidden(const CoverageGrid& grid, const BoxView& b) {
  if (!b.usable) return false;
  const CellRect r = grid.cells_of(b.x0, b.y0, b.x1, b.y1);
  // A rectangle that misses the grid meets no ray through the frustum.
  const float threshold = static_cast<float>((1.0 / b.w_min) * (1.0 + 0x1p-20));
  return r.empty() || (std::isfinite(threshold) && grid.all_nearer(r, threshold));
}

/// True when each of the patch's triangles is clearly back-facing (no ray sees its front) or hidden
/// by its own screen rectangle at its own nearest depth. Corners are projected as for occluders.
inline bool patch_triangles_hidden(const MeshIndex& index, Scratch& s, const Patch& patch) {
  for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(index.patches.triangles[k])];
    BoxView b{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL, true};
    double x[3], y[3];
    for (int v = 0; v < 3; ++v) {
      const Projected& p = project_vertex(index, s, c[v]);
      if (!p.usable) return false;  // through the near plane: cannot be measured
      x[v] = p.x;
      y[v] = p.y;
      b.x0 = std::min(b.x0, p.x);
      b.x1 = std::max(b.x1, p.x);
      b.y0 = std::min(b.y0, p.y);
      b.y1 = std::max(b.y1, p.y);
      b.w_min = std::min(b.w_min, p.w);
    }
    // The mirror of the occluders' front-facing rule, with the same margin: only a triangle that is
    // clearly back-facing is passed over; an edge-on one is tested like any other.
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    const double extent = std::max(b.x1 - b.x0, b.y1 - b.y0);
    if (area2 * s.view.orient < -1e-9 * extent * extent) continue;
    if (!rect_hidden(s.grid, b)) return false;
  }
  return true;
}

/// The part of the view frustum nearer than the near plane: the eye and the near rectangle's
/// corners, widened a little (rays 0.1% outside the screen, the rectangle 0.1% beyond the plane).
struct NearPyramid {
  double p[5][3];      // eye, then the 4 corners (in order around the rectangle)
  double plane[5][4];  // outward: 4 sides through the eye, then the far side (the near plane)
  bool ok = false;
};

inline NearPyramid near_pyramid(const Camera& camera, const View& view) {
  NearPyramid py;
  const glm::dmat4 inv = glm::inverse(glm::dmat4(camera.view_proj));
  const double* e = view.eye;
  const double* n = view.near_plane;
  for (int k = 0; k < 3; ++k) py.p[0][k] = e[k];
  const double cx[4] = {-1, 1, 1, -1}, cy[4] = {-1, -1, 1, 1};
  for (int c = 0; c < 4; ++c) {
    // A point on the corner's ray inside the frustum for every depth convention (ndc z = 0.5).
    const glm::dvec4 h = inv * glm::dvec4(cx[c] * 1.001, cy[c] * 1.001, 0.5, 1.0);
    if (!(std::fabs(h.w) > 0.0)) return py;
    const double d[3] = {h.x / h.w - e[0], h.y / h.w - e[1], h.z / h.w - e[2]};
    const double along = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    const double at_eye = n[0] * e[0] + n[1] * e[1] + n[2] * e[2] + n[3];
    if (!(along > 0.0)) return py;
    const double t = -at_eye / along * 1.001;
    for (int k = 0; k < 3; ++k) py.p[c + 1][k] = e[k] + t * d[k];
  }
  const auto plane_of = [&](const double* a, const double* b, const double* c, const double* inside, double* out) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
    out[3] = -(out[0] * a[0] + out[1] * a[1] + out[2] * a[2]);
    if (out[0] * inside[0] + out[1] * inside[1] + out[2] * inside[2] + out[3] > 0.0)
      for (int k = 0; k < 4; ++k) out[k] = -out[k];
  };
  double centre[3];
  for (int k = 0; k < 3; ++k) centre[k] = 0.5 * py.p[0][k] + 0.125 * (py.p[1][k] + py.p[2][k] + py.p[3][k] + py.p[4][k]);
  for (int c = 0; c < 4; ++c) plane_of(py.p[0], py.p[1 + c], py.p[1 + (c + 1) % 4], centre, py.plane[c]);
  plane_of(py.p[1], py.p[2], py.p[3], centre, py.plane[4]);
  py.ok = true;
  for (const auto& q : py.p)
    for (double v : q) py.ok = py.ok && std::isfinite(v);
  return py;
}

/// False only when `box` certainly misses the pyramid: separated by a face of the box or of the
/// pyramid (with a margin far above the rounding of these sums).
inline bool box_meets_pyramid(const Aabb& box, const NearPyramid& py) {
  if (!py.ok) return true;
  double scale = 0.0;
  for (const auto& q : py.p)
    for (double v : q) scale = std::max(scale, std::fabs(v));
  for (int a = 0; a < 3; ++a) scale = std::max(scale, std::max(std::fabs(double(box.min[a])), std::fabs(double(box.max[a]))));
  const double tol = 1e-9 * scale;
  for (int a = 0; a < 3; ++a) {
    bool below = true, above = true;
    for (const auto& q : py.p) {
      below = below && q[a] < box.min[a] - tol;
      above = above && q[a] > box.max[a] + tol;
    }
    if (below || above) return false;
  }
  for (const auto& pl : py.plane) {
    const double len = std::fabs(pl[0]) + std::fabs(pl[1]) + std::fabs(pl[2]);
    bool outside = true;
    for (int k = 0; k < 8 && outside; ++k) {
      const double x = k & 1 ? box.max.x : box.min.x, y = k & 2 ? box.max.y : box.min.y, z = k & 4 ? box.max.z : box.min.z;
      outside = pl[0] * x + pl[1] * y + pl[2] * z + pl[3] > tol * len;
    }
    if (outside) return false;
  }
  return true;
}

/// Fills `s.box_tree` with the biggest solid-box objects on screen. A box is a solid only for rays
/// that enter it beyond the near plane (what lies nearer is clipped: a ray entering there goes on
/// inside it and out through a back face), so a box that may meet the part of the frustum nearer
/// than the near plane is left out; a building beside the eye that reaches behind it stays in.
/// Leaves `s.box_occluders` empty when there are none.
inline void insert_box_occluders(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera,
                                 Scratch& s) {
  s.box_occluders.clear();
  if (params.max_box_occluders == 0) return;
  const double min_cells = std::max(1.0, params.min_occluder_screen_fraction * double(s.grid.width()) * double(s.grid.height()));
  s.box_candidates.clear();
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const std::uint32_t o = s.in_frustum[i];
    if (!index.solid_box[o]) continue;
    const double cells = screen_cells(s.boxes[i], s.grid);
    if (cells >= min_cells) s.box_candidates.emplace_back(static_cast<float>(cells), o);
  }
  if (s.box_candidates.empty()) return;
  if (s.box_candidates.size() > params.max_box_occluders) {
    std::nth_element(s.box_candidates.begin(), s.box_candidates.begin() + params.max_box_occluders, s.box_candidates.end(),
                     [](const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
                       return a.first > b.first || (a.first == b.first && a.second < b.second);
                     });
    s.box_candidates.resize(params.max_box_occluders);
  }
  const NearPyramid pyramid = near_pyramid(camera, s.view);
  for (const auto& c : s.box_candidates)
    if (!box_meets_pyramid(index.bounds[c.second], pyramid)) s.box_occluders.push_back(index.bounds[c.second]);
  if (s.box_occluders.empty()) return;
  s.box_tree.reset(s.view_eye);
  s.box_tree.insert_box_occluders(s.box_occluders.data(), s.box_occluders.size());
}

/// The object test. Its box first (one rectangle, usually enough); else, when the object is cut into
/// patches, each patch by its box or, for a patch of at most `object_test_triangles` triangles, by
/// its triangles. Every triangle that can be seen is in some patch, so the object is hidden when all
/// of its patches are. An object with no patch (only degenerate triangles) rests on its box.
inline bool object_hidden(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s, std::size_t i) {
  const BoxView& b = s.boxes[i];
  if (rect_hidden(s.grid, b)) return true;
  const std::uint32_t o = s.in_frustum[i];
  if (!s.box_occluders.empty() && b.usable && s.box_tree.is_occluded(index.bounds[o])) return true;
  const PatchSet& ps = index.patches;
  const std::uint32_t p0 = ps.object_first[o], p1 = ps.object_first[o + 1];
  if (p0 == p1) return false;
  // One patch whose box is the object's box and too many triangles to test: nothing tighter.
  if (p1 - p0 == 1 && ps.patches[p0].count > params.object_test_triangles) return false;
  for (std::uint32_t p = p0; p < p1; ++p) {
    const Patch& patch = ps.patches[p];
    // No ray through the frustum meets a patch outside it.
    if (p1 - p0 > 1 && (s.frustum.classify(patch.box) == Containment::outside || rect_hidden(s.grid, patch_box(index, s, p))))
      continue;
    if (patch.count > params.object_test_triangles || !patch_triangles_hidden(index, s, patch)) return false;
  }
  return true;
}

inline void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                 std::vector<std::uint32_t>& out) {
  out.clear();
  PhaseProbe probe;
  if (probe.on()) ++phase_times().calls;
  MeshOcclusionStats& stats = s.stats;
  stats = MeshOcclusionStats{};
  s.frustum = frustum_of(camera);
  index.tree.cull(s.frustum, s.in_frustum);
  for (std::uint32_t& i : s.in_frustum) i = index.tree_objects[i];
  stats.objects_in_frustum = s.in_frustum.size();
  out.insert(out.end(), index.unusable.begin(), index.unusable.end());
  stats.objects_unusable_visible = index.unusable.size();

  s.view.setup(camera, params.grid_width, params.grid_height);
  stats.occlusion_enabled = s.view.enabled;
  // One object alone in the frustum has nothing to hide it: an object never hides itself.
  if (!s.view.enabled || s.in_frustum.size() < 2) {
    out.insert(out.end(), s.in_frustum.begin(), s.in_frustum.end());
    probe.next(phase_frustum);
    return;
  }
  probe.next(phase_frustum);
  begin_frame(index, s);
  s.grid.reset(params.grid_width, params.grid_height);
  s.boxes.resize(s.in_frustum.size());
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) s.boxes[i] = project_box(s.view, index.bounds[s.in_frustum[i]]);
  probe.next(phase_boxes);
  choose_occluders(index, params, s);
  probe.next(phase_choose);
  gather_triangles(index, s);
  probe.next(phase_gather);
  stats.occluders_used = s.occluders.size();
  stats.cells_covered = insert_triangles(index, params, s);
  probe.restart();  // insert_triangles charged its own steps
  s.grid.finish();
  probe.next(phase_finish);
  s.view_eye = camera.eye;
  insert_box_occluders(index, params, camera, s);
  probe.next(phase_box_occluders);

  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    if (object_hidden(index, params, s, i)) ++stats.objects_hidden;
    else out.push_back(s.in_frustum[i]);
  }
  probe.next(phase_tests);
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
