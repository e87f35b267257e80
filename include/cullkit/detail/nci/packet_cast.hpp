// cullkit/detail/nci/packet_cast.hpp: the crowded-cell path of a tile. Instead of meeting every
// entry of a crowded (class, cell) list, the tile's live rays go through the list's hierarchy
// (cell_bvh.hpp) as one packet: a child box is entered only when it is not wholly outside the
// tile's beam, its screen rectangle covers a live pixel, and not every live ray under that
// rectangle already holds a solid hit in front of it (the walk's chunk tests, so every cut is as
// conservative as the walk's); the triangles of the leaves reached go through the walk's own
// admit_triangle and test_triangle. Both paths therefore give the same per-pixel answers: the
// same ray test, ties and edge-band records, on every (ray, triangle) pair that could change one.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "../../config.hpp"
#include "beam.hpp"
#include "cell_bvh.hpp"
#include "context.hpp"
#include "index_data.hpp"
#include "rejection.hpp"
#include "tile_walk.hpp"
#include "view.hpp"

namespace cullkit::detail::nci {

// A box over at most this many live pixels is tested against each of their rays.
inline constexpr int few_rays = 16;

// The screen rectangle of a box (min xyz, max xyz): the pixels whose centres may see a point of
// it. project_rect's arithmetic with the four linear forms of a corner's offset from the eye summed
// from per-axis terms (24 products for 8 corners instead of 96); the sums round differently, by a
// relative 1e-15, far inside the rectangle's margin of a twentieth of a pixel. A box with a corner
// (nearly) at the eye goes through project_rect itself.
[[nodiscard]] inline Rect box_rect(const ViewSetup& f, const float* box) noexcept {
  if (!f.use_rect) return Rect{Rect::full, 0, 0, 0};
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = double(box[a]) - f.eye[a];
    hi[a] = double(box[3 + a]) - f.eye[a];
  }
  if (near_eye(std::min(std::fabs(lo[0]), std::fabs(hi[0])), std::min(std::fabs(lo[1]), std::fabs(hi[1])),
               std::min(std::fabs(lo[2]), std::fabs(hi[2])))) {
    glm::vec3 corner[8];
    for (int k = 0; k < 8; ++k) corner[k] = glm::vec3(box[(k & 1) ? 3 : 0], box[(k & 2) ? 4 : 1], box[(k & 4) ? 5 : 2]);
    return project_rect(f, corner, 8);
  }
  const glm::dvec3* form[4] = {&f.plane, &f.h_w, &f.h_x, &f.h_y};
  double part[4][3][2];
  for (int g = 0; g < 4; ++g)
    for (int a = 0; a < 3; ++a) {
      part[g][a][0] = (*form[g])[a] * lo[a];
      part[g][a][1] = (*form[g])[a] * hi[a];
    }
  double mnx = std::numeric_limits<double>::infinity(), mny = mnx, mxx = -mnx, mxy = -mnx;
  for (int k = 0; k < 8; ++k) {
    const int sx = k & 1, sy = (k >> 1) & 1, sz = (k >> 2) & 1;
    double v[4];
    for (int g = 0; g < 4; ++g) v[g] = part[g][0][sx] + part[g][1][sy] + part[g][2][sz];
    // project_point's conditions: strictly in front of the eye, and clip w > 0.
    const double pd = v[0], qw = v[1];
    if (!(pd != 0.0) || (pd > 0.0) != (f.eye_side > 0.0) || !(qw != 0.0) || (qw > 0.0) != (pd > 0.0))
      return Rect{Rect::full, 0, 0, 0};
    const double inv = 1.0 / qw;
    const double px = ((v[2] * inv + 1.0) * f.width - 1.0) * 0.5;
    const double py = ((1.0 - v[3] * inv) * f.height - 1.0) * 0.5;
    mnx = std::min(mnx, px);
    mxx = std::max(mxx, px);
    mny = std::min(mny, py);
    mxy = std::max(mxy, py);
  }
  return pixels_of_bounds(f, mnx, mxx, mny, mxy);
}

// The inverse directions of the tile's rays (TileState::ix), made once per tile.
inline void make_inverse(TileState& r, int th) noexcept {
  if (r.inverse_ready) return;
  r.inverse_ready = true;
  const auto inv = [](float d) { return 1.0f / (std::fabs(d) >= 1e-30f ? d : 1e-30f); };
  for (int i = 0, n = th * r.stride; i < n; ++i) {
    r.ix[i] = inv(r.dx[i]);
    r.iy[i] = inv(r.dy[i]);
    r.iz[i] = inv(r.dz[i]);
  }
}

// Whether the line of pixel ray i meets the box q (relative to the eye: min xyz, max xyz) grown by
// m. A ray that the float watertight test reports as a hit or an edge-band record for a triangle
// passes within a few edge bands (each 8 roundings of the corners' size, about 5e-7 of it) of that
// triangle, in the 2D frame the test shears to; `m` is 1e-5 of the box's size from the eye, twenty
// times more, and covers the float slabs' rounding (a few 1e-7 relative) besides. A zero direction
// component is taken as 1e-30 (TileState::ix): the line then moves 1e-30 per unit of t, nothing
// against the margin. The line, not the ray: the sign of t is left to the other tests.
[[nodiscard]] inline bool line_meets_box(const TileState& r, int i, const float q[6], float m) noexcept {
  const float inv[3] = {r.ix[i], r.iy[i], r.iz[i]};
  float tn = -std::numeric_limits<float>::infinity(), tf = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {
    const float t0 = (q[a] - m) * inv[a], t1 = (q[3 + a] + m) * inv[a];
    tn = std::max(tn, std::min(t0, t1));
    tf = std::min(tf, std::max(t0, t1));
  }
  return tn <= tf;
}

// Whether some ray of the live pixels under a box's rectangle (rows ry0..ry1, columns `span`) may
// take a hit from the box: not holding a solid hit in front of it (test_triangle's per-ray depth
// reject, on the box's corner offsets qlo..qhi from the eye) and with a line meeting it.
[[nodiscard]] inline bool some_ray_meets(const TileWalk& w, const float qlo[3], const float qhi[3], int ry0, int ry1,
                                         Mask span) noexcept {
  const TileState& r = w.r;
  const int stride = r.stride;
  const float q[6] = {qlo[0], qlo[1], qlo[2], qhi[0], qhi[1], qhi[2]};
  float size = 0.0f;
  for (float v : q) size = std::max(size, std::fabs(v));
  const float m = 1e-5f * size + 1e-30f;
  for (int y = ry0; y <= ry1; ++y) {
    Mask bits = w.live[y] & span;
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      const int i = y * stride + x;
      // test_triangle's per-ray depth reject, on the box (a lower bound for every triangle in it).
      if (r.solid_t[i] < std::numeric_limits<float>::infinity()) {
        const detail::WatertightRay<float>& wr = r.wray[i];
        const double sz = wr.sz;
        const double bound = std::min(sz * double(qlo[wr.kz]), sz * double(qhi[wr.kz])) * (1.0 - tolerance::float_relative);
        if (bound > 1e-30 && std::isfinite(bound) && double(r.solid_t[i]) < bound) continue;
      }
      if (line_meets_box(r, i, q, m)) return true;
    }
  }
  return false;
}

// Whether some live ray of the tile may take a hit (or an edge-band record) from a triangle inside
// the box: not wholly outside the beam, a live pixel under its screen rectangle, and not behind the
// solid hits of every live ray there. `key` gets the box's nearest depth along the tile's mean ray.
[[nodiscard]] inline bool box_reachable(const TileWalk& w, const float* box, float& key) noexcept {
  const TileState& r = w.r;
  const ViewSetup& f = w.f;
  const Rect rect = box_rect(f, box);
  // The beam only where the rectangle cannot be trusted (a rectangle off the beam is off the tile).
  if (rect.x0 == Rect::full && r.beam && chunk_outside_beam(r, box, f)) return false;
  int rx0, ry0, rx1, ry1;
  Mask span;
  if (!live_under(rect, w.x0, w.y0, w.tw, w.th, w.live, rx0, ry0, rx1, ry1, span)) return false;
  const float qlo[3] = {box[0] - f.eye_f.x, box[1] - f.eye_f.y, box[2] - f.eye_f.z};
  const float qhi[3] = {box[3] - f.eye_f.x, box[4] - f.eye_f.y, box[5] - f.eye_f.z};
  if (behind_hits(r, qlo, qhi, ry0, ry1, span, w.live)) return false;
  // Few live pixels under it (the box is small on screen): its own rays, one by one.
  int few = 0;
  for (int y = ry0; y <= ry1 && few <= few_rays; ++y) few += __builtin_popcountll(static_cast<unsigned long long>(w.live[y] & span));
  if (few <= few_rays && !some_ray_meets(w, qlo, qhi, ry0, ry1, span)) return false;
  key = 0.0f;
  for (int a = 0; a < 3; ++a) key += std::min(r.mean_dir[a] * qlo[a], r.mean_dir[a] * qhi[a]);
  return true;
}

// The live pixels of the tile under the screen rectangle of a hierarchy's root (its children's
// boxes together): the packet the cell would cast.
[[nodiscard]] inline int live_under_root(const TileWalk& w, const CellBvhNode& root) noexcept {
  float box[6] = {root.lo[0][0], root.lo[1][0], root.lo[2][0], root.hi[0][0], root.hi[1][0], root.hi[2][0]};
  for (int j = 1; j < 4; ++j)
    for (int a = 0; a < 3; ++a) {
      box[a] = std::min(box[a], root.lo[a][j]);
      box[3 + a] = std::max(box[3 + a], root.hi[a][j]);
    }
  int rx0, ry0, rx1, ry1;
  Mask span;
  if (!live_under(box_rect(w.f, box), w.x0, w.y0, w.tw, w.th, w.live, rx0, ry0, rx1, ry1, span)) return 0;
  int count = 0;
  for (int y = ry0; y <= ry1; ++y) count += __builtin_popcountll(static_cast<unsigned long long>(w.live[y] & span));
  return count;
}

// The entries of one leaf (a run of the cell's list), each triangle not yet met by the tile: admitted and ray-tested at once (the
// traversal goes near to far, so their hits can hide the boxes after them).
inline void cast_leaf(TileWalk& w, std::uint16_t k, std::uint32_t code) {
  const IndexData& data = w.data;
  Worker& worker = w.worker;
  const std::uint32_t first = CellBvhNode::leaf_first(code), end = first + CellBvhNode::leaf_count(code);
  for (std::uint32_t j = first; j < end; ++j) __builtin_prefetch(&worker.tri[data.entry_triangle(j, k)]);
  for (std::uint32_t j = first; j < end; ++j) {
    const std::uint32_t tri = data.entry_triangle(j, k);
    if (worker.tri[tri].stamp == w.stamp) continue;
    worker.tri[tri].stamp = w.stamp;
    ++w.met;
    Candidate cand;
    if (!admit_triangle(data, w.f, tri, w.x0, w.y0, w.tw, w.th, w.live, w.r, worker, cand)) continue;
    if (test_triangle(data, w.f, w.x0, w.y0, cand, w.live, w.r, worker)) {
      ++worker.tested_count;
      worker.tested_bits[tri / 64] |= std::uint64_t{1} << (tri % 64);
    }
  }
}

// Casts the tile's live rays through the hierarchies queued in the worker's `cast_queue` (the
// crowded cells of the current slice, all classes together): nodes and leaves are taken nearest
// first along the tile's mean ray, whatever cell and class they belong to, so the hits of the near
// surface are in place before the boxes behind it are looked at (and then behind_hits drops them
// whole).
inline void cast_queued(TileWalk& w) {
  const IndexData& data = w.data;
  auto& queue = w.worker.cast_queue;
  if (queue.empty()) return;
  make_inverse(w.r, w.th);
  const auto later = [](const CastItem& p, const CastItem& q) {
    return p.key != q.key ? p.key > q.key : (p.code != q.code ? p.code > q.code : p.k > q.k);
  };
  while (!queue.empty()) {
    std::pop_heap(queue.begin(), queue.end(), later);
    const CastItem item = queue.back();
    queue.pop_back();
    if (CellBvhNode::is_leaf(item.code)) {
      cast_leaf(w, item.k, item.code);
      continue;
    }
    const CellBvhNode& node = data.bvh_nodes[item.code];
    for (int j = 0; j < 4; ++j) {
      if (node.child[j] == CellBvhNode::empty) continue;
      float box[6], key = 0.0f;
      node.box(j, box);
      if (!box_reachable(w, box, key)) continue;
      // What the child will read is fetched while the queue is worked on (the hierarchy is
      // visited out of memory order: its loads are what the packet path waits on).
      const std::uint32_t code = node.child[j];
      if (CellBvhNode::is_leaf(code)) {
        const std::uint32_t first = CellBvhNode::leaf_first(code);
        if (data.wide_tris) __builtin_prefetch(&data.cell_tris[first]);
        else __builtin_prefetch(&data.cell_tris16[first]);
      } else {
        __builtin_prefetch(&data.bvh_nodes[code]);
        __builtin_prefetch(reinterpret_cast<const char*>(&data.bvh_nodes[code]) + 64);
      }
      queue.push_back(CastItem{key, code, item.k});
      std::push_heap(queue.begin(), queue.end(), later);
    }
  }
}

// Queues the hierarchy rooted at node `root` of a cell of class k for cast_queued.
inline void queue_cell(TileWalk& w, std::uint16_t k, std::uint32_t root) {
  auto& queue = w.worker.cast_queue;
  queue.push_back(CastItem{-std::numeric_limits<float>::infinity(), root, k});
  std::push_heap(queue.begin(), queue.end(), [](const CastItem& p, const CastItem& q) {
    return p.key != q.key ? p.key > q.key : (p.code != q.code ? p.code > q.code : p.k > q.k);
  });
}

// Whether the (tile, cell) pair takes the packet path: NciParams::crowded_path, and when automatic
// the cell's entries against the live pixels under its root's rectangle (the rays the packet would
// carry): the walk costs per entry, the packet per ray.
[[nodiscard]] inline bool cast_pays(const TileWalk& w, std::uint32_t root, std::uint32_t entries) noexcept {
  switch (w.data.params.crowded_path) {
    case NciCrowdedPath::walk_only: return false;
    case NciCrowdedPath::rays_only: return true;
    case NciCrowdedPath::automatic: break;
  }
  const int live = live_under_root(w, w.data.bvh_nodes[root]);
  return static_cast<double>(entries) > IndexData::cast_ratio * live;
}

}  // namespace cullkit::detail::nci
