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

#include "../../config.hpp"
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

/// An occluder triangle clipped at the near plane (View::clip_level): its part beyond, a triangle or a
/// quadrilateral in the triangle's own order. Corner k runs to corner k + 1 along the triangle's edge
/// `edge[k]` (0 to 2), or along the clipping line (-1: always outline, never shared).
struct ClippedPolygon {
  double x[4], y[4], w[4];
  int edge[4];
  int n;
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
  std::vector<std::uint32_t> clip_stamp, clip_slot;  // per triangle: its polygon in `clipped`
  std::vector<ClippedPolygon> clipped;                // this frame's clipped occluder triangles
  std::vector<BoxView> patch_boxes;       // per patch, valid where patch_stamp equals `frame`
  std::vector<Projected> projected;
  View view;
  CoverageGrid grid;
  std::vector<std::pair<float, std::uint32_t>> box_candidates;  // (screen cells, object)
  std::vector<Aabb> box_occluders;
  OcclusionTree box_tree{glm::vec3(0.0f)};  // the solid boxes' hidden region, when box_occluders is not empty
};

/// One frame of MeshOcclusionCuller::cull: clears `out`, then writes every object that may be
/// visible from `camera`. A core entry point (CULLKIT_SEPARATE_CORE, config.hpp): the steps below
/// are compiled only where its definition is.
CULLKIT_CORE_FN void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                          std::vector<std::uint32_t>& out);

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
    s.clip_stamp.assign(index.corners.size() / 3, 0);
    s.clip_slot.assign(index.corners.size() / 3, 0);
    s.patch_stamp.assign(index.patches.patches.size(), 0);
    s.patch_boxes.resize(index.patches.patches.size());
    s.frame = 0;
  }
  if (++s.frame == 0) {
    std::fill(s.vertex_stamp.begin(), s.vertex_stamp.end(), 0);
    std::fill(s.triangle_stamp.begin(), s.triangle_stamp.end(), 0);
    std::fill(s.clip_stamp.begin(), s.clip_stamp.end(), 0);
    std::fill(s.patch_stamp.begin(), s.patch_stamp.end(), 0);
    s.frame = 1;
  }
  s.projected.clear();
  s.clipped.clear();
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

/// Clips the occluder triangle of welded corners c (`inside`: a bit per corner beyond the clipping
/// level, neither none nor all of them) to its part beyond the clipping level, into `poly`. False when a
/// clip point cannot be had. Each clip point is computed from its edge's endpoints ordered by welded
/// id, so a neighbour clipped on the same edge gets the same point: the shared part still cancels.
inline bool clip_occluder(const MeshIndex& index, const Scratch& s, const std::uint32_t* c, unsigned inside,
                          ClippedPolygon& poly) {
  poly.n = 0;
  for (int k = 0; k < 3; ++k) {
    const int l = k == 2 ? 0 : k + 1;
    const bool in_k = (inside >> k) & 1u, in_l = (inside >> l) & 1u;
    if (in_k) {
      const Projected& p = s.projected[s.vertex_slot[c[k]]];
      poly.x[poly.n] = p.x;
      poly.y[poly.n] = p.y;
      poly.w[poly.n] = p.w;
      poly.edge[poly.n++] = k;  // on to corner l, or to the clip point of this edge
    }
    if (in_k == in_l) continue;
    const glm::vec3& pa = index.positions[std::min(c[k], c[l])];
    const glm::vec3& pb = index.positions[std::max(c[k], c[l])];
    const double a[3] = {pa.x, pa.y, pa.z}, b[3] = {pb.x, pb.y, pb.z};
    Projected q;
    if (!s.view.clip_point(a, b, q)) return false;
    poly.x[poly.n] = q.x;
    poly.y[poly.n] = q.y;
    poly.w[poly.n] = q.w;
    // Leaving: on along the clipping line; entering: on along this edge to corner l.
    poly.edge[poly.n++] = in_k ? -1 : k;
  }
  return true;
}

/// Projects the occluder patches' triangles and keeps those that can occlude: clearly front-facing,
/// touching the grid, and with some corner beyond the clipping level (a triangle with a corner short
/// of it is clipped to its part beyond). Fills `s.triangles` with (sort key as float bits, triangle),
/// smallest key first, the key being the nearest corner's depth (the farthest corner's for a clipped
/// polygon), and `s.clipped` with the clipped ones' polygons.
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
      double x[4], y[4], w[4];
      int n = 3;
      unsigned inside = 0;
      for (int k = 0; k < 3; ++k) {
        const Projected& p = project_vertex(index, s, c[k]);
        inside |= p.inside ? 1u << k : 0u;
        x[k] = p.x;
        y[k] = p.y;
        w[k] = p.w;
      }
      if (inside != 7u) {
        // Wholly short of the clipping level: nothing of it occludes.
        if (inside == 0u) continue;
        ClippedPolygon poly;
        if (!clip_occluder(index, s, c, inside, poly)) continue;
        n = poly.n;
        std::copy(poly.x, poly.x + n, x);
        std::copy(poly.y, poly.y + n, y);
        std::copy(poly.w, poly.w + n, w);
        s.clip_stamp[t] = s.frame;
        s.clip_slot[t] = static_cast<std::uint32_t>(s.clipped.size());
        s.clipped.push_back(poly);
      }
      double xmin = x[0], xmax = x[0], ymin = y[0], ymax = y[0], wmin = w[0];
      for (int k = 1; k < n; ++k) {
        xmin = std::min(xmin, x[k]);
        xmax = std::max(xmax, x[k]);
        ymin = std::min(ymin, y[k]);
        ymax = std::max(ymax, y[k]);
        wmin = std::min(wmin, w[k]);
      }
      if (xmax < 0.0 || xmin > gw || ymax < 0.0 || ymin > gh) continue;
      // Clearly front-facing: back-facing and edge-on triangles are left out (their neighbours'
      // edges then stay on the outline, which only covers less). A clipped polygon lies in its
      // triangle's plane: it faces the eye as the triangle does.
      double area2 = 0.0;
      for (int k = 1; k + 1 < n; ++k) area2 += (x[k] - x[0]) * (y[k + 1] - y[0]) - (x[k + 1] - x[0]) * (y[k] - y[0]);
      const double extent = std::max(xmax - xmin, ymax - ymin);
      if (!(area2 * orient > 1e-9 * extent * extent)) continue;
      // A clipped polygon's nearest point is on the clipping line, nearer than anything else, and
      // mostly off screen (a floor under the eye): sorted by its nearest depth it would freeze every
      // cell it shares with nearer occluders (a wall standing on the floor) at its own far depth
      // there. It goes in by its farthest depth instead, after what stands on it.
      double wmax = w[0];
      for (int k = 1; k < n; ++k) wmax = std::max(wmax, w[k]);
      double key_w = inside != 7u ? wmax : wmin;
      // A part of a cut triangle goes in only when every corner of the whole triangle is beyond the
      // clipping level (then so is every part, unclipped), and sorts as the whole (by the whole's
      // nearest corner): the parts then share a band and their inner edges cancel within it. Parts
      // of a triangle that reaches the near plane are left out with it: inserted alone, their inner
      // edges would be outline across cells that nearer occluders cover (measured: fzk_haus kept
      // more).
      if (!index.parts.whole.empty() && index.parts.whole[t] != none) {
        const std::uint32_t* whole = &index.parts.whole_corners[3 * std::size_t(index.parts.whole[t])];
        bool whole_inside = true;
        for (int k = 0; k < 3 && whole_inside; ++k) {
          const Projected& p = project_vertex(index, s, whole[k]);
          whole_inside = p.inside;
          key_w = std::min(key_w, p.w);
        }
        if (!whole_inside) continue;
      }
      const float key = static_cast<float>(key_w);
      std::uint32_t bits;
      std::memcpy(&bits, &key, sizeof bits);  // positive floats order as their bits
      s.triangles.emplace_back(bits, t);
      s.triangle_stamp[t] = s.frame;
    }
  }
  radix_sort(s.triangles, s.sort_buffer);
}

/// Inserts a clipped occluder polygon as insert_triangles does a triangle: its depth and counts as a
/// fan of triangles whose diagonals are left out of the counts (each would cancel its twin in the
/// fan exactly), its edges along the triangle's edges shared with neighbours as the triangle's
/// would be (`inner`, `twin_band`: per triangle edge, as insert_triangles finds them; the shared
/// part is the same segment on both sides), and its edge along the clipping line as outline.
inline void insert_clipped(CoverageGrid& grid, const ClippedPolygon& poly, int orient, unsigned inner,
                           const std::uint32_t* twin_band, std::uint32_t my_band, PhaseProbe& probe) {
  const int n = poly.n;
  const auto skipped = [&](int k) { return poly.edge[k] >= 0 && ((inner >> poly.edge[k]) & 1u); };
  probe.next(phase_bands);
  for (int f = 1; f + 1 < n; ++f) {
    const double x[3] = {poly.x[0], poly.x[f], poly.x[f + 1]}, y[3] = {poly.y[0], poly.y[f], poly.y[f + 1]};
    const double w[3] = {poly.w[0], poly.w[f], poly.w[f + 1]};
    grid.add_depth(x, y, w);
  }
  probe.next(phase_depth);
  for (int f = 1; f + 1 < n; ++f) {
    const double x[3] = {poly.x[0], poly.x[f], poly.x[f + 1]}, y[3] = {poly.y[0], poly.y[f], poly.y[f + 1]};
    // Fan edge 0 -> f is the polygon's edge 0 only for the first triangle, f + 1 -> 0 its last edge
    // only for the last one; otherwise they are diagonals.
    unsigned skip = skipped(f) ? 2u : 0u;
    skip |= f == 1 ? (skipped(0) ? 1u : 0u) : 1u;
    skip |= f + 2 == n ? (skipped(n - 1) ? 4u : 0u) : 4u;
    grid.add_count(x, y, orient, skip);
  }
  probe.next(phase_counts);
  for (int k = 0; k < n; ++k) {
    const int l = k + 1 == n ? 0 : k + 1;
    const int e = poly.edge[k];
    if (e < 0) {
      grid.touch_edge(poly.x[k], poly.y[k], poly.x[l], poly.y[l], orient, 1);
      continue;
    }
    if ((inner >> e) & 1u) continue;
    if (twin_band[e] < my_band) grid.touch_edge(poly.x[l], poly.y[l], poly.x[k], poly.y[k], orient, -1);
    else grid.touch_edge(poly.x[k], poly.y[k], poly.x[l], poly.y[l], orient, 1);
  }
  probe.next(phase_edges);
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
  const bool any_clipped = !s.clipped.empty();
  // The triangle's corners, or its clipped polygon's; returns their number.
  const auto corners_of = [&](std::uint32_t t, double* x, double* y, double* w) {
    if (any_clipped && s.clip_stamp[t] == s.frame) {
      const ClippedPolygon& poly = s.clipped[s.clip_slot[t]];
      std::copy(poly.x, poly.x + poly.n, x);
      std::copy(poly.y, poly.y + poly.n, y);
      std::copy(poly.w, poly.w + poly.n, w);
      return poly.n;
    }
    const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
    for (int k = 0; k < 3; ++k) {
      const Projected& p = s.projected[s.vertex_slot[c[k]]];
      x[k] = p.x;
      y[k] = p.y;
      w[k] = p.w;
    }
    return 3;
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
      double x[4], y[4], w[4];
      const int n = corners_of(t, x, y, w);
      if (grid.all_frozen(x, y, n)) s.triangle_stamp[t] = 0;
    }
    probe.next(phase_bands);
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = s.triangles[i].second;
      if (s.triangle_stamp[t] != s.frame) continue;
      ++s.stats.occluder_triangles;
      std::uint32_t twin_band[3];
      unsigned inner = 0;  // edges shared with a triangle of this band
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
        const bool twin_here = twin != none && s.triangle_stamp[twin / 3] == s.frame;
        twin_band[k] = twin_here ? s.triangle_band[twin / 3] : none;
        if (twin_band[k] == my_band) inner |= 1u << k;
      }
      if (any_clipped && s.clip_stamp[t] == s.frame) {
        insert_clipped(grid, s.clipped[s.clip_slot[t]], orient, inner, twin_band, my_band, probe);
        continue;
      }
      double x[3], y[3], w[3];
      corners_of(t, x, y, w);
      probe.next(phase_bands);
      grid.add_depth(x, y, w);
      probe.next(phase_depth);
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

/// The object test of a triangle with a corner not clearly beyond the near plane (which cannot be
/// projected whole). True when no ray through the frustum can see it unhidden: it lies outside the
/// frustum, or is clearly back-facing (the eye on its back side, in world space), or its part that
/// can be drawn (near-plane value at least -clip_level: a margin on the near side this time), cut to
/// the grid's rectangle on screen, has its rectangle hidden at that part's nearest depth. 1/w is
/// affine on screen over the triangle's plane, so the cut interpolates it exactly up to rounding.
inline bool crossing_triangle_hidden(const MeshIndex& index, const Scratch& s, const std::uint32_t* c) {
  const View& view = s.view;
  const glm::vec3 &p0 = index.positions[c[0]], &p1 = index.positions[c[1]], &p2 = index.positions[c[2]];
  const Aabb box{glm::min(p0, glm::min(p1, p2)), glm::max(p0, glm::max(p1, p2))};
  if (s.frustum.classify(box) == Containment::outside) return true;
  double q[3][3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = index.positions[c[k]];
    for (int a = 0; a < 3; ++a) q[k][a] = double(p[a]) - view.eye[a];
  }
  // Front-facing means det[p0 - e, p1 - e, p2 - e] < 0 (see View::setup).
  const double det = q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                     q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
  const auto len = [](const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
  if (det > 1e-9 * len(q[0]) * len(q[1]) * len(q[2])) return true;
  // The drawable part: clipped at -clip_level, in the triangle's own order (no fusion needed here).
  double x[8], y[8], iw[8];
  int n = 0;
  const double level = -view.clip_level;
  double value[3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = index.positions[c[k]];
    value[k] = view.near_value(p.x, p.y, p.z);
  }
  // Projects a corner of the drawable part; false (the triangle stays visible) when it is not in
  // front of the eye or so far off screen that the cut below could lose precision.
  const auto put = [&](double px, double py, double pz) {
    const double qx = px - view.eye[0], qy = py - view.eye[1], qz = pz - view.eye[2];
    const double cw = view.row[2][0] * qx + view.row[2][1] * qy + view.row[2][2] * qz;
    if (!(cw > 0.0)) return false;
    x[n] = (view.row[0][0] * qx + view.row[0][1] * qy + view.row[0][2] * qz) / cw * view.scale_x + view.offset_x;
    y[n] = (view.row[1][0] * qx + view.row[1][1] * qy + view.row[1][2] * qz) / cw * view.scale_y + view.offset_y;
    iw[n] = 1.0 / cw;
    const bool ok = std::fabs(x[n]) < 0x1p40 && std::fabs(y[n]) < 0x1p40 && std::isfinite(iw[n]);
    ++n;
    return ok;
  };
  for (int k = 0; k < 3; ++k) {
    const int l = k == 2 ? 0 : k + 1;
    const glm::vec3 &a = index.positions[c[k]], &b = index.positions[c[l]];
    if (value[k] >= level && !put(a.x, a.y, a.z)) return false;
    if ((value[k] >= level) != (value[l] >= level)) {
      const double t = (level - value[k]) / (value[l] - value[k]);
      if (!(t >= 0.0 && t <= 1.0) ||
          !put(a.x + t * (double(b.x) - a.x), a.y + t * (double(b.y) - a.y), a.z + t * (double(b.z) - a.z)))
        return false;
    }
  }
  if (n < 3) return true;  // nothing of it can be drawn
  // Cut to the grid's rectangle widened by a cell, one side at a time.
  for (int side = 0; side < 4; ++side) {
    const double bound = side & 1 ? (side < 2 ? s.grid.width() : s.grid.height()) + 1.0 : -1.0;
    double* u = side < 2 ? x : y;
    const auto keep = [&](int i) { return side & 1 ? u[i] <= bound : u[i] >= bound; };
    double nx[8], ny[8], niw[8];
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const int j = i + 1 == n ? 0 : i + 1;
      if (keep(i)) {
        nx[m] = x[i], ny[m] = y[i], niw[m++] = iw[i];
      }
      if (keep(i) != keep(j)) {
        const double t = (bound - u[i]) / (u[j] - u[i]);
        nx[m] = x[i] + t * (x[j] - x[i]), ny[m] = y[i] + t * (y[j] - y[i]), niw[m++] = iw[i] + t * (iw[j] - iw[i]);
      }
    }
    n = m;
    if (n == 0) return true;  // off the grid: no ray through the frustum meets it
    std::copy(nx, nx + n, x);
    std::copy(ny, ny + n, y);
    std::copy(niw, niw + n, iw);
  }
  BoxView b{x[0], y[0], x[0], y[0], 0.0, true};
  double iw_max = iw[0];
  for (int i = 1; i < n; ++i) {
    b.x0 = std::min(b.x0, x[i]);
    b.x1 = std::max(b.x1, x[i]);
    b.y0 = std::min(b.y0, y[i]);
    b.y1 = std::max(b.y1, y[i]);
    iw_max = std::max(iw_max, iw[i]);
  }
  // Rounding of the interpolation, far inside this margin (rect_hidden adds its own 2^-20).
  b.w_min = 1.0 / (iw_max * (1.0 + 0x1p-30));
  const bool finite = std::isfinite(b.x0) && std::isfinite(b.x1) && std::isfinite(b.y0) && std::isfinite(b.y1);
  return finite && std::isfinite(b.w_min) && b.w_min > 0.0 && rect_hidden(s.grid, b);
}

/// True when each of the patch's triangles is clearly back-facing (no ray sees its front) or hidden
/// by its own screen rectangle at its own nearest depth. Corners are projected as for occluders.
inline bool patch_triangles_hidden(const MeshIndex& index, Scratch& s, const Patch& patch) {
  for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(index.patches.triangles[k])];
    BoxView b{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL, true};
    double x[3], y[3];
    bool usable = true;
    for (int v = 0; v < 3 && usable; ++v) {
      const Projected& p = project_vertex(index, s, c[v]);
      usable = p.usable;  // else through the near plane: tested below
      x[v] = p.x;
      y[v] = p.y;
      b.x0 = std::min(b.x0, p.x);
      b.x1 = std::max(b.x1, p.x);
      b.y0 = std::min(b.y0, p.y);
      b.y1 = std::max(b.y1, p.y);
      b.w_min = std::min(b.w_min, p.w);
    }
    if (!usable) {
      if (!crossing_triangle_hidden(index, s, c)) return false;
      continue;
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

#if CULLKIT_CORE_BODIES
CULLKIT_CORE_FN void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
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
  // Occluders are clipped beyond a level set by the extent of the usable objects (the tree's root).
  const Aabb& all = index.tree.nodes().front().bounds;
  const double lo[3] = {all.min.x, all.min.y, all.min.z}, hi[3] = {all.max.x, all.max.y, all.max.z};
  s.view.set_clip_level(lo, hi);
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

#endif  // CULLKIT_CORE_BODIES

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
