// cullkit/detail/mesh_occlusion/frame.hpp: the per-frame state of MeshOcclusionCuller::cull (its
// scratch memory, kept between calls) and the projection of corners and boxes onto the grid.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

#include "../../config.hpp"
#include "../../geometry/camera.hpp"
#include "../../occlusion_tree.hpp"
#include "../default_init_allocator.hpp"
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
  double w_max = HUGE_VAL;  // at least the largest depth of any point of the box, usable or not
};

/// The largest and the runner-up of a measure over the frustum's objects (for the object holding
/// the largest, the farthest of the others is the runner-up). Ties and the order the objects come
/// in change which object is `at`, never what `without` answers.
struct Farthest {
  double first = -HUGE_VAL, second = -HUGE_VAL;
  std::size_t at = ~std::size_t{0};
  void add(double v, std::size_t i) {
    if (v > first) {
      second = first;
      first = v;
      at = i;
    } else if (v > second) {
      second = v;
    }
  }
  /// As if every object `other` saw had been added here too.
  void add(const Farthest& other) {
    if (other.first > first) {
      second = std::max(first, other.second);
      first = other.first;
      at = other.at;
    } else {
      second = std::max(second, other.first);
    }
  }
  [[nodiscard]] double without(std::size_t i) const { return i == at ? second : first; }
};

/// How far the frustum's objects reach from the eye, by depth and by distance: an occluder can only
/// hide what lies beyond it along some ray from the eye, and both measures grow along every such ray.
struct ObjectReach {
  Farthest depth, distance;
  void add(const ObjectReach& other) {
    depth.add(other.depth);
    distance.add(other.distance);
  }
};

/// An occluder triangle clipped at the near plane (View::clip_level): its part beyond, a triangle or a
/// quadrilateral in the triangle's own order. Corner k runs to corner k + 1 along the triangle's edge
/// `edge[k]` (0 to 2), or along the clipping line (-1: always outline, never shared).
struct ClippedPolygon {
  double x[4], y[4], w[4];
  int edge[4];
  int n;
};

/// A gathered occluder triangle's screen box and nearest depth, set up once per frame when it is
/// gathered (over its projected corners, or its clipped polygon's, in their order) and read by the
/// steps of its insertion that need no more than the box.
struct OccluderBox {
  double xmin, ymin, xmax, ymax, wmin;
};

/// A per-frame buffer whose `resize` only makes room (DefaultInitAllocator): its users write every
/// slot they later read.
template <class T>
using ScratchVector = std::vector<T, DefaultInitAllocator<T>>;

/// Working memory of one task of a cull on several threads (parallel_frame.hpp): the corners and
/// patch boxes it projects itself, per vertex and per patch (valid where the stamp equals `frame`).
/// Sized by the index, not by the objects a task happens to take, so a warm context never grows
/// whichever way the objects fall to the tasks.
struct TaskScratch {
  const void* owner = nullptr;  // the index the caches fit
  std::uint32_t frame = 0;
  std::vector<std::uint32_t> vertex_stamp, patch_stamp;
  ScratchVector<Projected> projected;
  std::vector<BoxView> patch_boxes;
  // Gathering occluder triangles (parallel_frame.hpp): the polygons of the triangles this task
  // clipped and those triangles, the occluders it gathered, and room to sort their triangles.
  std::vector<ClippedPolygon> clipped;
  std::vector<std::uint32_t> clipped_triangles, gathered;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> items, sort_buffer;
  // Choosing the occluders: how far the objects this task projected reach, and the candidate
  // patches of the objects it measured, sorted.
  ObjectReach reach;
  std::vector<std::pair<float, std::uint32_t>> candidates;
};

/// A strip of the grid's rows [first_row, last_row] in the occluder insertion (row_strips.hpp):
/// which gathered triangles (by their place in Scratch::triangles) it inserted (1), and the cells
/// it covered.
struct Strip {
  int first_row = 0, last_row = -1;
  std::vector<std::uint8_t> inserted;  // per gathered triangle, inserted here (several strips)
  std::size_t inserted_count = 0;      // triangles inserted (the whole grid as one strip)
};

/// A gathered occluder triangle's screen box and nearest depth, and the rows its cells reach with
/// the margin (row_strips.hpp): every operation of the triangle on the grid stays within them.
struct TriangleExtent {
  double x0, y0, x1, y1, w_min;
  int row0, row1;  // row0 > row1: it reaches no row
};

/// Working memory of one task of the occluder insertion (row_strips.hpp): the union's rows of the
/// strips it takes (task 0 works in the frame's own grid instead), the grid each patch goes into
/// alone, and per triangle a stamp for the members of the patch going in and one for the
/// triangles the current strip has inserted. Sized by the index, so a warm context never grows
/// however the strips fall to the tasks.
struct StripTask {
  CoverageGrid grid, patch_grid;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> run;  // (place in its region, triangle) of one patch
  std::vector<std::uint32_t> member_stamp, done_stamp;
  std::uint32_t member_value = 0, done_value = 0;
  // The strip's gathered occluders waiting for their turn and those another task is gathering
  // (strip_gather.hpp), and a list gathering clips nothing into there.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> waiting, pending;
  std::vector<ClippedPolygon> unused_clipped;
};

/// Per occluder of a cull on several tasks, whether it is gathered yet (0: no, 1: being gathered,
/// 2: done), claimed by the first strip that needs it (strip_gather.hpp). Copies of a context start
/// with none (it is only working memory).
struct GatherClaims {
  std::unique_ptr<std::atomic<std::uint8_t>[]> state;
  std::size_t capacity = 0;
  GatherClaims() = default;
  GatherClaims(const GatherClaims&) {}
  GatherClaims& operator=(const GatherClaims&) { return *this; }
  GatherClaims(GatherClaims&&) noexcept = default;
  GatherClaims& operator=(GatherClaims&&) noexcept = default;
  ~GatherClaims() = default;
  /// `n` occluders, none gathered; allocates only when there are more than ever before.
  void reset(std::size_t n) {
    if (n > capacity) {
      state.reset(new std::atomic<std::uint8_t>[n]);
      capacity = n;
    }
    for (std::size_t q = 0; q < n; ++q) state[q].store(0, std::memory_order_relaxed);
  }
};

/// Per-thread working memory of a query; only grows.
struct Scratch {
  MeshOcclusionStats stats;
  Frustum frustum;                        // this frame's
  glm::vec3 view_eye{0.0f};               // this frame's eye
  std::vector<std::uint32_t> in_frustum;  // tree positions, then objects
  std::vector<BoxView> boxes;             // parallel to in_frustum
  std::vector<std::pair<float, std::uint32_t>> candidates, candidate_merge;  // (screen cells, patch)
  std::vector<std::pair<double, std::uint32_t>> occluders;  // (depth key, patch)
  // (depth bits, triangle) of the gathered occluder triangles: occluder q's from region_first[q] on,
  // gathered_count[q] of them (gather_patch); and room to sort them.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> triangles, sort_buffer;
  std::vector<std::uint32_t> region_first, gathered_count, region_cursor;
  // Per-frame caches, valid where the stamp equals `frame`.
  const void* owner = nullptr;
  std::uint32_t frame = 0;
  std::vector<std::uint32_t> vertex_stamp, vertex_slot, triangle_stamp, triangle_band, patch_stamp;
  std::vector<std::uint32_t> clip_stamp, clip_slot;  // per triangle: its polygon in `clipped`
  std::vector<ClippedPolygon> clipped;                // this frame's clipped occluder triangles
  // This frame's gathered occluder triangles' boxes, in the order gathered (at their occluder's
  // region, as `triangles`), and per triangle its box's position there (valid for the gathered ones).
  std::vector<OccluderBox> occluder_boxes;
  std::vector<std::uint32_t> box_slot;
  std::vector<BoxView> patch_boxes;       // per patch, valid where patch_stamp equals `frame`
  ScratchVector<Projected> projected;
  View view;
  CoverageGrid grid;
  // Per gathered triangle, the occluder that gathered it (insertion by strips, row_strips.hpp).
  std::vector<std::uint32_t> triangle_owner;
  // One thread gathers an occluder only when its turn may come (gather_on_demand.hpp):
  // those not gathered yet as (lowest key they can have, occluder), lowest first, from
  // `next_ungathered` on; the gathered ones waiting for their turn, a heap of (key, occluder). Per
  // occluder waiting ungathered, the cells its patch's box may reach and the inverse depth the union
  // must cover them at for it to be dropped (drop_test), set up with its lowest key.
  bool on_demand = false;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ungathered, ungathered_buffer, waiting;
  std::size_t next_ungathered = 0;
  std::vector<CellRect> drop_cells;
  std::vector<float> drop_nearest;
  std::vector<std::uint32_t> member_stamp;
  std::uint32_t member_value = 0;
  CoverageGrid patch_grid;
  std::vector<std::pair<float, std::uint32_t>> box_candidates;  // (screen cells, object)
  // Per place in in_frustum, the box's rectangle test on the finished grid when insert_box_occluders
  // took it: 1 hidden, 0 not; 2 not taken.
  std::vector<std::uint8_t> box_rect_hidden;
  std::vector<Aabb> box_occluders;
  OcclusionTree box_tree{glm::vec3(0.0f)};  // the solid boxes' hidden region, when box_occluders is not empty
  // A cull on several threads: each task's own memory, and the object tests' answers by position
  // in `in_frustum` (1: hidden), written by whichever task tests the object.
  std::vector<TaskScratch> tasks;
  std::vector<std::uint8_t> hidden;
  ScratchVector<std::uint32_t> corner_list;  // occluder corners given a slot in `projected`, in slot order
  // The occluder insertion strip by strip: the strips, each task's memory, the gathered triangles'
  // extents (by place in `triangles`, set when gathered), and the order the strips are handed out in
  // (biggest first).
  std::vector<Strip> strips;
  std::vector<StripTask> strip_tasks;
  std::vector<TriangleExtent> triangle_extents;
  std::vector<std::uint32_t> strip_order, strip_work, row_work;
  // The strips gather on demand (strip_gather.hpp): per occluder, 1 when gathered before the
  // strips; those of them that kept triangles as (nearest key, occluder); and who gathers the others.
  std::vector<std::uint8_t> gather_first;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> gathered_first;
  GatherClaims gather_claims;
};


/// Sorts the (key, value) pairs items[0, n) by key, stable: three passes of 11 bits, between
/// `items` and `buffer` (room for n). Returns where the sorted pairs are (`buffer`).
inline const std::pair<std::uint32_t, std::uint32_t>* radix_sort(std::pair<std::uint32_t, std::uint32_t>* items, std::size_t n,
                                                                 std::pair<std::uint32_t, std::uint32_t>* buffer) {
  std::pair<std::uint32_t, std::uint32_t>*from = items, *to = buffer;
  for (int pass = 0; pass < 3; ++pass) {
    const int shift = 11 * pass;
    std::uint32_t offsets[2048] = {};
    for (std::size_t i = 0; i < n; ++i) ++offsets[(from[i].first >> shift) & 2047u];
    std::uint32_t sum = 0;
    for (std::uint32_t& o : offsets) {
      const std::uint32_t count = o;
      o = sum;
      sum += count;
    }
    for (std::size_t i = 0; i < n; ++i) to[offsets[(from[i].first >> shift) & 2047u]++] = from[i];
    std::swap(from, to);
  }
  return from;
}

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
    s.triangle_owner.assign(index.corners.size() / 3, 0);
    s.clip_slot.assign(index.corners.size() / 3, 0);
    s.box_slot.assign(index.corners.size() / 3, 0);
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
    s.vertex_stamp[v] = s.frame;
    s.vertex_slot[v] = static_cast<std::uint32_t>(s.projected.size());
    const glm::vec3& p = index.positions[v];
    const Projected q = s.view.project(p.x, p.y, p.z);
    // Stored field by field: a copy of the whole would be built on the stack (its flags a byte at
    // a time) and read back in one wide load that waits for those stores to retire.
    Projected& to = s.projected.emplace_back();
    to.x = q.x;
    to.y = q.y;
    to.w = q.w;
    to.usable = q.usable;
    to.inside = q.inside;
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
  // Depth is affine: its largest value over the box is at the corner taking each edge whose step
  // raises it, whatever the other corners do (behind the eye included).
  double far = base[2];
  for (int a = 0; a < 3; ++a) far += std::max(0.0, step[a][2]);
  b.w_max = std::isfinite(far) ? far + wtol : HUGE_VAL;
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

/// A patch's box seen from the eye, projected once per frame (for the patch of an object of one
/// patch chosen as an occluder candidate, the object's box seen from the eye, which holds it).
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

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
