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
#include <cstddef>
#include <cstdint>

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

// The screen rectangle of a box (min xyz, max xyz): the pixels whose centres may see a point of it.
[[nodiscard]] inline Rect box_rect(const ViewSetup& f, const float* box) noexcept {
  glm::vec3 corner[8];
  for (int k = 0; k < 8; ++k) corner[k] = glm::vec3(box[(k & 1) ? 3 : 0], box[(k & 2) ? 4 : 1], box[(k & 4) ? 5 : 2]);
  return project_rect(f, corner, 8);
}

// Whether some live ray of the tile may take a hit (or an edge-band record) from a triangle inside
// the box: not wholly outside the beam, a live pixel under its screen rectangle, and not behind the
// solid hits of every live ray there. `key` gets the box's nearest depth along the tile's mean ray.
[[nodiscard]] inline bool box_reachable(const TileWalk& w, const float* box, float& key) noexcept {
  const TileState& r = w.r;
  const ViewSetup& f = w.f;
  if (r.beam && chunk_outside_beam(r, box, f)) return false;
  int rx0, ry0, rx1, ry1;
  Mask span;
  if (!live_under(box_rect(f, box), w.x0, w.y0, w.tw, w.th, w.live, rx0, ry0, rx1, ry1, span)) return false;
  const float qlo[3] = {box[0] - f.eye_f.x, box[1] - f.eye_f.y, box[2] - f.eye_f.z};
  const float qhi[3] = {box[3] - f.eye_f.x, box[4] - f.eye_f.y, box[5] - f.eye_f.z};
  if (behind_hits(r, qlo, qhi, ry0, ry1, span, w.live)) return false;
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

// The triangles of one leaf, each not yet met by the tile: admitted and ray-tested at once (the
// traversal goes near to far, so their hits can hide the boxes after them).
inline void cast_leaf(TileWalk& w, std::uint16_t k, std::uint32_t code) {
  const IndexData& data = w.data;
  Worker& worker = w.worker;
  const std::uint32_t first = CellBvhNode::leaf_first(code), end = first + CellBvhNode::leaf_count(code);
  for (std::uint32_t j = first; j < end; ++j) {
    const std::uint32_t tri = data.bvh_triangle(j, k);
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

// Casts the tile's live rays through the hierarchy rooted at node `root` of a cell of class k:
// depth first, the reachable children of a node nearest first.
inline void cast_cell(TileWalk& w, std::uint16_t k, std::uint32_t root) {
  const IndexData& data = w.data;
  // Median splits in four keep the depth at log4 of the list: at most 14 levels below the 2^28
  // triangles a hierarchy may hold, each leaving at most 3 siblings waiting (43 entries).
  std::uint32_t stack[64];
  int sp = 0;
  stack[sp++] = root;
  while (sp > 0) {
    const std::uint32_t code = stack[--sp];
    if (CellBvhNode::is_leaf(code)) {
      cast_leaf(w, k, code);
      continue;
    }
    const CellBvhNode& node = data.bvh_nodes[code];
    float keys[4];
    std::uint32_t codes[4];
    int n = 0;
    for (int j = 0; j < 4; ++j) {
      if (node.child[j] == CellBvhNode::empty) continue;
      float box[6], key = 0.0f;
      node.box(j, box);
      if (!box_reachable(w, box, key)) continue;
      // Insertion by decreasing key: pushed far first, so the nearest is popped next.
      int at = n++;
      for (; at > 0 && keys[at - 1] < key; --at) {
        keys[at] = keys[at - 1];
        codes[at] = codes[at - 1];
      }
      keys[at] = key;
      codes[at] = node.child[j];
    }
    for (int j = 0; j < n; ++j) stack[sp++] = codes[j];
  }
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
