// cullkit/detail/mesh_occlusion/occluders.hpp: a frame's occluders: the patches chosen by size on
// screen, their triangles clipped at the near plane and sorted nearest first, and their insertion
// into the coverage grid in depth bands.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include <glm/ext/vector_double3.hpp>
#include <glm/geometric.hpp>

#include "coverage.hpp"
#include "frame.hpp"
#include "index.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// True when the plane of every triangle of the patch is farther from `eye` than `limit`: then so is
/// every point of the patch (a point of a triangle is no nearer than its plane). Triangles of zero
/// area never occlude and are passed over.
inline bool patch_farther_than(const MeshIndex& index, const glm::dvec3& eye, const Patch& patch, double limit) {
  const PatchSet& ps = index.patches;
  for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(ps.triangles[k])];
    if (c[0] == none) continue;
    const glm::dvec3 a(index.positions[c[0]]), b(index.positions[c[1]]), d(index.positions[c[2]]);
    const glm::dvec3 n = glm::cross(b - a, d - a);
    const double length = glm::length(n);
    if (!(length > 0.0)) continue;
    // Relative rounding of the cross and dot products, far inside 2^-30.
    if (!(std::fabs(glm::dot(n, eye - a)) > length * limit * (1.0 + 0x1p-30))) return false;
  }
  return true;
}

/// Adds object i of the frustum (its box projected) to `reach`.
inline void measure_reach(const MeshIndex& index, const Scratch& s, std::size_t i, ObjectReach& reach) {
  reach.depth.add(s.boxes[i].w_max, i);
  const Aabb& box = index.bounds[s.in_frustum[i]];
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double r = std::max(std::fabs(double(box.min[a]) - s.view.eye[a]), std::fabs(double(box.max[a]) - s.view.eye[a]));
    d2 += r * r;
  }
  reach.distance.add(std::isfinite(d2) ? std::sqrt(d2) * (1.0 + 0x1p-30) : HUGE_VAL, i);
}

/// Screen cells below which nothing is an occluder (MeshOcclusionParams::min_occluder_screen_fraction).
inline double min_occluder_cells(const MeshOcclusionParams& params, const CoverageGrid& grid) {
  return std::max(1.0, params.min_occluder_screen_fraction * double(grid.width()) * double(grid.height()));
}

/// Appends the patches of object i of the frustum that may be occluders to `out` as (screen cells,
/// patch): those of at least `min_occluder_cells`, not too dense (`min_occluder_cells_per_triangle`)
/// and not beyond every other object (`reach`). An object of one patch is measured by its own box;
/// the patches of bigger ones by theirs: `patch_view(p)` gives patch p's box seen from the eye, or
/// null when the patch is outside the frustum. Reads the frame only.
template <class PatchView>
inline void object_candidates(const MeshIndex& index, const MeshOcclusionParams& params, const Scratch& s, std::size_t i,
                              const ObjectReach& reach, const PatchView& patch_view,
                              std::vector<std::pair<float, std::uint32_t>>& out) {
  const PatchSet& ps = index.patches;
  const std::uint32_t o = s.in_frustum[i];
  const std::uint32_t p0 = ps.object_first[o], p1 = ps.object_first[o + 1];
  if (p0 == p1) return;
  if (!index.objects[o].occludes) return;  // see-through: culled, never an occluder
  const double min_cells = min_occluder_cells(params, s.grid);
  const double object_cells = screen_cells(s.boxes[i], s.grid);
  if (object_cells < min_cells) return;
  // Triangles that average under a cell each cost as much to insert as big ones and fill few cells.
  const double cells_per_triangle = params.min_occluder_cells_per_triangle;
  const auto dense = [&](double cells, const Patch& patch) { return cells < cells_per_triangle * double(patch.count); };
  // A patch whose nearest point is farther, by either measure, than every point of every other
  // object in the frustum hides none of them (a sky dome, the back wall of the view).
  const glm::dvec3 eye(s.view.eye[0], s.view.eye[1], s.view.eye[2]);
  const auto beyond_the_rest = [&](const BoxView& b, const Patch& patch) {
    if (b.usable && b.w_min > reach.depth.without(i)) return true;
    // A curved patch's box may reach far nearer than its surface, up to the eye (a piece of a sky
    // dome around the scene): its triangles' planes are the tighter bound. But a plane through a
    // point of the box is no farther from the eye than the box's farthest point: a box within the
    // limit (rounding far inside the margins) needs no look at its triangles.
    const double limit = reach.distance.without(i);
    if (!std::isfinite(limit)) return false;
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double r = std::max(std::fabs(double(patch.box.min[a]) - eye[a]), std::fabs(double(patch.box.max[a]) - eye[a]));
      d2 += r * r;
    }
    if (std::sqrt(d2) * (1.0 + 0x1p-40) <= limit) return false;
    return patch_farther_than(index, eye, patch, limit);
  };
  if (p1 - p0 == 1) {
    if (!dense(object_cells, ps.patches[p0]) && !beyond_the_rest(s.boxes[i], ps.patches[p0]))
      out.emplace_back(static_cast<float>(object_cells), p0);
    return;
  }
  for (std::uint32_t p = p0; p < p1; ++p) {
    // A patch outside the frustum (behind the eye, say) would otherwise count as through the near
    // plane, the biggest of all.
    const BoxView* b = patch_view(p);
    if (b == nullptr) continue;
    const double cells = screen_cells(*b, s.grid);
    if (cells >= min_cells && !dense(cells, ps.patches[p]) && !beyond_the_rest(*b, ps.patches[p]))
      out.emplace_back(static_cast<float>(cells), p);
  }
}

/// The candidates' order: biggest on screen first, then by patch number (a total order, so any
/// sort or merge of the same candidates gives the same list).
inline bool bigger_candidate(const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
  return a.first > b.first || (a.first == b.first && a.second < b.second);
}

/// Takes the candidates of `s.candidates` (biggest first) into `s.occluders` within the triangle
/// budget and the occluder count: a patch too big for what is left of the budget is skipped,
/// smaller ones still fit. Then narrows the clipping level to the chosen patches' box.
inline void take_occluders(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const PatchSet& ps = index.patches;
  s.occluders.clear();
  std::uint64_t budget = params.occluder_triangle_budget;
  Aabb chosen = Aabb::empty();
  for (const auto& c : s.candidates) {
    if (s.occluders.size() >= params.max_occluder_objects || budget == 0) break;
    const std::uint32_t n = ps.patches[c.second].count;
    if (n > budget) continue;
    budget -= n;
    s.occluders.emplace_back(0.0, c.second);
    chosen = merge(chosen, ps.patches[c.second].box);
  }
  if (!s.occluders.empty()) {
    const double lo[3] = {chosen.min.x, chosen.min.y, chosen.min.z}, hi[3] = {chosen.max.x, chosen.max.y, chosen.max.z};
    s.view.narrow_clip_level(lo, hi);
  }
}

/// Picks occluder patches by size on screen, biggest first, within the triangle budget, leaving out
/// those with fewer box cells per triangle than `min_occluder_cells_per_triangle`; fills
/// `s.occluders` (object_candidates, take_occluders). On the calling thread; a cull on several
/// tasks does the same on them (parallel_frame.hpp).
inline void choose_occluders(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  ObjectReach reach;
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) measure_reach(index, s, i, reach);
  const PatchSet& ps = index.patches;
  const auto patch_view = [&](std::uint32_t p) -> const BoxView* {
    if (s.frustum.classify(ps.patches[p].box) == Containment::outside) return nullptr;
    return &patch_box(index, s, p);
  };
  s.candidates.clear();
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const std::size_t before = s.candidates.size();
    object_candidates(index, params, s, i, reach, patch_view, s.candidates);
    // An object of one patch lends its box, already projected, to its patch from here on (the
    // object's box holds the patch): the occluders' gathering reads it.
    const std::uint32_t o = s.in_frustum[i], p0 = ps.object_first[o];
    if (s.candidates.size() != before && ps.object_first[o + 1] - p0 == 1) {
      s.patch_stamp[p0] = s.frame;
      s.patch_boxes[p0] = s.boxes[i];
    }
  }
  // A full sort of the candidates only (they are the patches above the size floor).
  std::sort(s.candidates.begin(), s.candidates.end(), bigger_candidate);
  take_occluders(index, params, s);
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

/// A gathered occluder triangle's screen box and nearest depth (set up once when it was gathered).
inline const OccluderBox& occluder_box(const Scratch& s, std::uint32_t t) { return s.occluder_boxes[s.box_slot[t]]; }

/// Numbers the depth bands of the sorted triangles [first, last) of one patch into `triangle_band`
/// (1, 2, ...): runs whose nearest depth is within `depth_band_ratio` of the run's first.
inline void assign_depth_bands(const MeshOcclusionParams& params, const std::pair<std::uint32_t, std::uint32_t>* first,
                               const std::pair<std::uint32_t, std::uint32_t>* last,
                               std::vector<std::uint32_t>& triangle_band) {
  const float ratio = 1.0f + std::max(0.0f, params.depth_band_ratio);
  std::uint32_t band = 0;
  float band_start = 0.0f;
  for (const auto* it = first; it != last; ++it) {
    float key;
    std::memcpy(&key, &it->first, sizeof key);
    if (it == first || !(key <= band_start * ratio)) {
      band_start = key;
      ++band;
    }
    triangle_band[it->second] = band;
  }
}

/// A gathered occluder triangle's screen box and nearest depth, and the rows its cells reach with
/// the margin (row_strips.hpp): its depth, its crossings, its edges' marks and the covered test stay
/// within them (each takes its margin from coordinates no larger).
inline TriangleExtent triangle_extent(const CoverageGrid& grid, const OccluderBox& box) {
  TriangleExtent e{box.xmin, box.ymin, box.xmax, box.ymax, box.wmin, 0, -1};
  const CellRect r = grid.cells_of(e.x0, e.y0, e.x1, e.y1);
  if (!r.empty()) {
    e.row0 = r.y0;
    e.row1 = r.y1;
  }
  return e;
}

/// Makes room for the chosen occluders' triangles: occluder q's go in at `s.region_first[q]` (as
/// many places as its patch has triangles), so that each occluder can be gathered on its own, by any
/// task; `extents`: each kept triangle's extent is wanted too (strips of rows, row_strips.hpp).
inline void begin_gather(const MeshIndex& index, Scratch& s, bool extents) {
  const PatchSet& ps = index.patches;
  const std::size_t n = s.occluders.size();
  s.region_first.resize(n + 1);
  s.region_cursor.resize(n);
  s.gathered_count.assign(n, 0);
  std::uint32_t total = 0;
  for (std::size_t q = 0; q < n; ++q) {
    s.region_first[q] = total;
    total += ps.patches[s.occluders[q].second].count;
  }
  s.region_first[n] = total;
  s.on_demand = false;
  // Only grown: what lies past this frame's regions is never read.
  if (s.triangles.size() < total) s.triangles.resize(total);
  if (s.sort_buffer.size() < total) s.sort_buffer.resize(total);
  if (s.occluder_boxes.size() < total) s.occluder_boxes.resize(total);
  if (!extents) s.triangle_extents.clear();
  else if (s.triangle_extents.size() < total) s.triangle_extents.resize(total);
  s.clipped.clear();
}

/// The smallest rectangle holding `r` and [x0, x1] x [y0, y1].
inline OccluderBox merge_rect(const OccluderBox& r, double x0, double y0, double x1, double y1) {
  return OccluderBox{std::min(r.xmin, x0), std::min(r.ymin, y0), std::max(r.xmax, x1), std::max(r.ymax, y1), r.wmin};
}

/// True when a patch whose front-facing triangles have `area2_sum` (twice their area, in cells) on
/// screen within the rectangle `spread` is narrower than `min_width` cells: its area over the
/// rectangle's diagonal (the width of a straight strip along it; a curved or branching one is
/// narrower still) is less. A patch that thin covers few cells by itself, or none (a window
/// frame, a railing, a rod, a trim seen from afar, a closed beam along its length), and costs as
/// much per triangle as a wall. Seen edge-on, any patch is that thin.
inline bool too_narrow(double area2_sum, const OccluderBox& spread, double min_width) {
  const double dx = spread.xmax - spread.xmin, dy = spread.ymax - spread.ymin;
  return 0.5 * area2_sum < min_width * std::sqrt(dx * dx + dy * dy);
}

/// Gathers the triangles of occluder q (s.occluders[q]) that can occlude: clearly front-facing,
/// touching the grid, and with some corner beyond the clipping level (a triangle with a corner short
/// of it is clipped to its part beyond, into `clipped`, its place there in `s.clip_slot` and the
/// triangle appended to `clipped_triangles` when given). Writes them in the patch's order at the
/// occluder's region of `s.triangles` as (sort key as float bits, triangle), the key being the
/// nearest corner's depth (the farthest corner's for a clipped polygon), and their boxes at the same
/// places of `s.occluder_boxes`; sets their owner. A triangle of a patch that shares triangles with
/// another goes in once, with the first occluder that keeps it: such patches must be gathered one
/// after another, in order. Keeps none when the kept ones are `too_narrow` on screen for
/// `min_width_cells` (MeshOcclusionParams::min_occluder_width_cells): decided from the patch and the
/// camera alone, like the choice of occluders, so the same on any task.
/// Writes only the slots of the patch's own triangles and region, so occluders whose patches share
/// no triangle can be gathered on several tasks at once. The corners must be projected
/// (project_occluder_corners_on_tasks, or project_patch_corners). Returns the number kept.
inline std::uint32_t gather_patch(const MeshIndex& index, Scratch& s, std::size_t q, std::vector<ClippedPolygon>& clipped,
                                  std::vector<std::uint32_t>* clipped_triangles, double min_width_cells) {
  const auto corner = [&](std::uint32_t v) -> const Projected& { return s.projected[s.vertex_slot[v]]; };
  const int orient = s.view.orient;
  const double gw = s.grid.width(), gh = s.grid.height();
  const PatchSet& ps = index.patches;
  const std::uint32_t patch_id = s.occluders[q].second;
  const Patch& patch = ps.patches[patch_id];
  const bool once = ps.shares_triangles[patch_id] != 0;  // objects may overlap: a triangle goes in once
  const bool any_parts = !index.parts.whole.empty();
  const std::uint32_t region = s.region_first[q];
  std::pair<std::uint32_t, std::uint32_t>* out = s.triangles.data() + region;
  OccluderBox* boxes = s.occluder_boxes.data() + region;
  const std::uint32_t owner = static_cast<std::uint32_t>(q);
  std::uint32_t kept = 0;
  // What it covers on screen: twice the kept triangles' area, and the box of their boxes.
  double area2_sum = 0.0;
  OccluderBox spread{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL};
  for (std::uint32_t member = patch.first; member < patch.first + patch.count; ++member) {
    const std::uint32_t t = ps.triangles[member];
    const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
    if (c[0] == none || (once && s.triangle_stamp[t] == s.frame)) continue;
    double x[4], y[4], w[4];
    int n = 3;
    unsigned inside = 0;
    for (int k = 0; k < 3; ++k) {
      const Projected& p = corner(c[k]);
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
      s.clip_slot[t] = static_cast<std::uint32_t>(clipped.size());
      clipped.push_back(poly);
      if (clipped_triangles) clipped_triangles->push_back(t);
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
    double key_w = wmin;
    if (inside != 7u) {
      key_w = w[0];
      for (int k = 1; k < n; ++k) key_w = std::max(key_w, w[k]);
    }
    // A part of a cut triangle sorts as the whole, so that the parts share a band and their inner
    // edges cancel within it: by the whole's nearest corner, or, when the whole reaches the
    // clipping level (then each part is clipped on its own, at the same points on shared edges),
    // by the whole's farthest corner, as a clipped polygon goes in.
    if (any_parts && index.parts.whole[t] != none) {
      const std::uint32_t* whole = &index.parts.whole_corners[3 * std::size_t(index.parts.whole[t])];
      bool whole_inside = true;
      double whole_far = -HUGE_VAL;
      for (int k = 0; k < 3; ++k) {
        const Projected& p = corner(whole[k]);
        whole_inside = whole_inside && p.inside;
        if (whole_inside) key_w = std::min(key_w, p.w);
        const glm::vec3& at = index.positions[whole[k]];
        whole_far = std::max(whole_far, s.view.depth(at.x, at.y, at.z));
      }
      if (!whole_inside) key_w = whole_far;
    }
    area2_sum += std::fabs(area2);
    spread = merge_rect(spread, xmin, ymin, xmax, ymax);
    const float key = static_cast<float>(key_w);
    std::uint32_t bits;
    std::memcpy(&bits, &key, sizeof bits);  // positive floats order as their bits
    out[kept] = {bits, t};
    boxes[kept] = OccluderBox{xmin, ymin, xmax, ymax, wmin};
    if (once) s.triangle_stamp[t] = s.frame;
    s.triangle_owner[t] = owner;
    s.box_slot[t] = region + kept;
    ++kept;
  }
  if (kept > 0 && too_narrow(area2_sum, spread, min_width_cells)) return 0;
  return kept;
}

/// Sorts the gathered triangles of the occluders qs[0, count) by key within each occluder, ties in
/// the order gathered: one stable radix sort over all of them (through `items` and `buffer`), then
/// each back to its occluder's region in sorted order. Then numbers each occluder's depth bands and
/// sets its triangles' extents when wanted. Touches only those occluders' regions and triangles.
inline void order_gathered(const MeshOcclusionParams& params, Scratch& s, const std::uint32_t* qs, std::size_t count,
                           std::vector<std::pair<std::uint32_t, std::uint32_t>>& items,
                           std::vector<std::pair<std::uint32_t, std::uint32_t>>& buffer) {
  items.clear();
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t q = qs[i];
    const auto* region = s.triangles.data() + s.region_first[q];
    items.insert(items.end(), region, region + s.gathered_count[q]);
    s.region_cursor[q] = s.region_first[q];
  }
  if (buffer.size() < items.size()) buffer.resize(items.size());
  const auto* sorted = radix_sort(items.data(), items.size(), buffer.data());
  for (std::size_t i = 0; i < items.size(); ++i) s.triangles[s.region_cursor[s.triangle_owner[sorted[i].second]]++] = sorted[i];
  const bool extents = !s.triangle_extents.empty();
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t q = qs[i], first = s.region_first[q], kept = s.gathered_count[q];
    const auto* region = s.triangles.data() + first;
    assign_depth_bands(params, region, region + kept, s.triangle_band);
    if (extents)
      for (std::uint32_t k = 0; k < kept; ++k)
        s.triangle_extents[first + k] = triangle_extent(s.grid, occluder_box(s, region[k].second));
  }
}

/// Inserts a clipped occluder polygon as insert_run does a triangle: its depth and counts as a
/// fan of triangles whose diagonals are left out of the counts (each would cancel its twin in the
/// fan exactly), its edges along the triangle's edges shared with neighbours as the triangle's
/// would be (`inner`, `twin_band`: per triangle edge, as insert_run finds them; the shared
/// part is the same segment on both sides), and its edge along the clipping line as outline.
inline void insert_clipped(CoverageGrid& grid, const ClippedPolygon& poly, int orient, unsigned inner,
                           const std::uint32_t* twin_band, std::uint32_t my_band) {
  const int n = poly.n;
  const auto skipped = [&](int k) { return poly.edge[k] >= 0 && ((inner >> poly.edge[k]) & 1u); };
  for (int f = 1; f + 1 < n; ++f) {
    const double x[3] = {poly.x[0], poly.x[f], poly.x[f + 1]}, y[3] = {poly.y[0], poly.y[f], poly.y[f + 1]};
    const double w[3] = {poly.w[0], poly.w[f], poly.w[f + 1]};
    grid.add_depth(x, y, w);
  }
  // The fan's diagonals are left out of the counts: each would cancel its twin in the fan exactly.
  // So each of the polygon's edges gives its crossings and outline marks once, as its own.
  for (int k = 0; k < n; ++k) {
    if (skipped(k)) continue;
    const int e = poly.edge[k];
    grid.add_outline_edge(poly.x, poly.y, k, k + 1 == n ? 0 : k + 1, orient, e >= 0 && twin_band[e] < my_band);
  }
}

/// The projected corners of occluder triangle t (one not clipped).
inline void triangle_corners(const MeshIndex& index, const Scratch& s, std::uint32_t t, double* x, double* y, double* w) {
  const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
  for (int k = 0; k < 3; ++k) {
    const Projected& p = s.projected[s.vertex_slot[c[k]]];
    x[k] = p.x;
    y[k] = p.y;
    w[k] = p.w;
  }
}

/// A gathered occluder triangle's projected corners, or its clipped polygon's (up to 4); returns
/// their number.
inline int occluder_corners(const MeshIndex& index, const Scratch& s, std::uint32_t t, double* x, double* y, double* w) {
  if (!s.clipped.empty() && s.clip_stamp[t] == s.frame) {
    const ClippedPolygon& poly = s.clipped[s.clip_slot[t]];
    std::copy(poly.x, poly.x + poly.n, x);
    std::copy(poly.y, poly.y + poly.n, y);
    std::copy(poly.w, poly.w + poly.n, w);
    return poly.n;
  }
  triangle_corners(index, s, t, x, y, w);
  return 3;
}

/// Which triangles a run of insertions holds: those whose `stamp` entry equals `value`. An edge is
/// shared within the run only when its twin is a member; a triangle dropped over covered cells
/// stops being one.
struct RunMembers {
  std::vector<std::uint32_t>& stamp;
  std::uint32_t value;
  [[nodiscard]] bool has(std::uint32_t t) const { return stamp[t] == value; }
};

/// Inserts the sorted triangles [first, last) (each a member of `members`, depth bands numbered by
/// assign_depth_bands) into `grid` nearest first, in bands of similar depth, so a cell freezes at
/// the depth of the nearest layer that covers it. Within a band, an edge shared by two of its
/// triangles is never touched: it cancels before the band ends. The last band is left open:
/// `CoverageGrid::absorb`, which adds the grid into the union next, ends it in the same pass (or
/// the caller calls `end_band`). Counts the inserted triangles into `inserted`. Only reads `s`, so
/// several tasks may insert into grids of their own at once.
inline void insert_run(const MeshIndex& index, const Scratch& s, CoverageGrid& grid,
                       const std::pair<std::uint32_t, std::uint32_t>* first,
                       const std::pair<std::uint32_t, std::uint32_t>* last, RunMembers members,
                       std::size_t& inserted) {
  const int orient = s.view.orient;
  const std::size_t count = static_cast<std::size_t>(last - first);
  const bool any_clipped = !s.clipped.empty();
  const std::uint8_t* reach = index.patches.twin_reach.empty() ? nullptr : index.patches.twin_reach.data();
  for (std::size_t begin = 0, end = 0; begin < count; begin = end) {
    const std::uint32_t my_band = s.triangle_band[first[begin].second];
    end = begin;
    while (end < count && s.triangle_band[first[end].second] == my_band) ++end;
    // A triangle over cells that are all covered already can change nothing that matters: it is
    // dropped, as if it were no occluder (decided for the whole band before any of its edges
    // cancel against a neighbour's).
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = first[i].second;
      const OccluderBox& r = occluder_box(s, t);
      if (grid.all_frozen(r.xmin, r.ymin, r.xmax, r.ymax)) members.stamp[t] = 0;
    }
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t t = first[i].second;
      if (!members.has(t)) continue;
      ++inserted;
      std::uint32_t twin_band[3] = {none, none, none};
      unsigned inner = 0;  // edges shared with a triangle of this band
      // Only the edges whose twin may be in the patch (PatchSet::twin_reach) can have it in the run;
      // an index without patches (a moving occluder's, one run) looks up all three.
      const unsigned in_patch = reach != nullptr ? reach[t] & twin_in_patch : twin_in_patch;
      for (int k = 0; k < 3; ++k) {
        if (!((in_patch >> k) & 1u)) continue;
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
        if (twin == none || !members.has(twin / 3)) continue;
        twin_band[k] = s.triangle_band[twin / 3];
        if (twin_band[k] == my_band) inner |= 1u << k;
      }
      if (any_clipped && s.clip_stamp[t] == s.frame) {
        insert_clipped(grid, s.clipped[s.clip_slot[t]], orient, inner, twin_band, my_band);
        continue;
      }
      double x[3], y[3], w[3];
      triangle_corners(index, s, t, x, y, w);
      // An edge shared within the band (`inner`) adds crossings from both triangles that cancel bit
      // for bit (the same endpoints, the same arithmetic, opposite signs), and outline marks that
      // cancel too: both leave it out. An edge whose twin is in an earlier band (`leaves`): the
      // twin's edge (l -> k, as its triangle runs) leaves the outline, and this one never joins it.
      unsigned leaves = 0;
      for (int k = 0; k < 3; ++k)
        if (twin_band[k] < my_band) leaves |= 1u << k;
      grid.add_triangle(x, y, w, orient, inner, leaves);
    }
    if (end < count) grid.end_band();
  }
}

/// The segment of occluder triangle t along its edge k (0 to 2), as the triangle runs, into (x0, y0)
/// -> (x1, y1): the triangle's corners, or its clipped polygon's part of that edge. False when the
/// clipped polygon keeps nothing of the edge.
inline bool edge_segment(const MeshIndex& index, const Scratch& s, std::uint32_t t, int k, double& x0, double& y0,
                         double& x1, double& y1) {
  if (!s.clipped.empty() && s.clip_stamp[t] == s.frame) {
    const ClippedPolygon& poly = s.clipped[s.clip_slot[t]];
    for (int c = 0; c < poly.n; ++c) {
      if (poly.edge[c] != k) continue;
      const int d = c + 1 == poly.n ? 0 : c + 1;
      x0 = poly.x[c];
      y0 = poly.y[c];
      x1 = poly.x[d];
      y1 = poly.y[d];
      return true;
    }
    return false;
  }
  const std::uint32_t* c = &index.corners[3 * std::size_t(t)];
  const Projected& a = s.projected[s.vertex_slot[c[k]]];
  const Projected& b = s.projected[s.vertex_slot[c[k == 2 ? 0 : k + 1]]];
  x0 = a.x;
  y0 = a.y;
  x1 = b.x;
  y1 = b.y;
  return true;
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
