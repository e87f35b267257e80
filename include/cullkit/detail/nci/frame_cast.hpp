// cullkit/detail/nci/frame_cast.hpp: casting a packet of up to 64 rays from the eye through the
// frame hierarchy (frame_bvh.hpp) together: per node, each live ray's 4-wide box test over the
// children; children entered nearest first with the rays that reach them; a ray leaves a subtree
// once its nearest hit lies before the subtree's box. Leaves are handed to the caller's test.
#pragma once

#include <cstdint>
#include <limits>

#include "../../config.hpp"
#include "frame_bvh.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail::nci {

// The packet: ray k (bit k of a mask) leaves the eye with inverse direction (ix, iy, iz)[k] (a zero
// component as a huge finite value) and holds its nearest hit so far at t[k], which the leaf test
// lowers.
struct FramePacket {
  alignas(16) float ix[64];
  alignas(16) float iy[64];
  alignas(16) float iz[64];
  alignas(16) float t[64];
};

// Casts the rays of `live` through `bvh`; `leaf(first, count, mask)` tests the triangles
// bvh.tris[first, first + count) against the rays of `mask` and lowers their t. Box tests are made
// with the box grown by `slack` of the entry and exit distances (relative), so that a ray the
// float triangle test could report never misses a box on the way.
struct FrameCastStats {
  std::uint64_t nodes = 0, ray_boxes = 0, leaves = 0, leaf_rays = 0;
};

template <class Leaf>
CULLKIT_FORCEINLINE void cast_frame_packet(const FrameBvh& bvh, const float eye[3], FramePacket& p, std::uint64_t live,
                                           float slack, Leaf&& leaf, FrameCastStats* stats = nullptr) {
  struct Entry {
    std::uint32_t code;
    float near;
    std::uint64_t mask;
  };
  Entry stack[256];
  int top = 0;
  if (bvh.root == FrameBvhNode::empty || !live) return;
  stack[top++] = Entry{bvh.root, 0.0f, live};
  const float lo_scale = 1.0f - slack, hi_scale = 1.0f + slack;
#if CULLKIT_HAS_SSE2
  const __m128 ex = _mm_set1_ps(eye[0]), ey = _mm_set1_ps(eye[1]), ez = _mm_set1_ps(eye[2]);
  const __m128 los = _mm_set1_ps(lo_scale), his = _mm_set1_ps(hi_scale), zero = _mm_setzero_ps();
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
#endif
  while (top > 0) {
    const Entry e = stack[--top];
    std::uint64_t mask = e.mask;
    // Rays whose hit now lies before the box leave it.
    for (std::uint64_t m = mask; m; m &= m - 1) {
      const int k = __builtin_ctzll(m);
      if (p.t[k] * hi_scale < e.near) mask &= ~(std::uint64_t{1} << k);
    }
    if (!mask) continue;
    if (FrameBvhNode::is_leaf(e.code)) {
      if (stats) {
        ++stats->leaves;
        stats->leaf_rays += static_cast<std::uint64_t>(__builtin_popcountll(mask)) * FrameBvhNode::leaf_count(e.code);
      }
      leaf(FrameBvhNode::leaf_first(e.code), FrameBvhNode::leaf_count(e.code), mask);
      continue;
    }
    const FrameBvhNode& node = bvh.nodes[e.code];
    if (stats) {
      ++stats->nodes;
      stats->ray_boxes += static_cast<std::uint64_t>(__builtin_popcountll(mask));
    }
    std::uint64_t cm[4] = {0, 0, 0, 0};
#if CULLKIT_HAS_SSE2
    const __m128 lx = _mm_sub_ps(_mm_loadu_ps(node.lo[0]), ex), hx = _mm_sub_ps(_mm_loadu_ps(node.hi[0]), ex);
    const __m128 ly = _mm_sub_ps(_mm_loadu_ps(node.lo[1]), ey), hy = _mm_sub_ps(_mm_loadu_ps(node.hi[1]), ey);
    const __m128 lz = _mm_sub_ps(_mm_loadu_ps(node.lo[2]), ez), hz = _mm_sub_ps(_mm_loadu_ps(node.hi[2]), ez);
    __m128 nearest = inf;
    for (std::uint64_t m = mask; m; m &= m - 1) {
      const int k = __builtin_ctzll(m);
      const __m128 rx = _mm_set1_ps(p.ix[k]), ry = _mm_set1_ps(p.iy[k]), rz = _mm_set1_ps(p.iz[k]);
      const __m128 ax = _mm_mul_ps(lx, rx), bx = _mm_mul_ps(hx, rx);
      const __m128 ay = _mm_mul_ps(ly, ry), by = _mm_mul_ps(hy, ry);
      const __m128 az = _mm_mul_ps(lz, rz), bz = _mm_mul_ps(hz, rz);
      const __m128 tn = _mm_max_ps(_mm_max_ps(_mm_min_ps(ax, bx), _mm_min_ps(ay, by)), _mm_max_ps(_mm_min_ps(az, bz), zero));
      const __m128 tf = _mm_min_ps(_mm_min_ps(_mm_max_ps(ax, bx), _mm_max_ps(ay, by)),
                                   _mm_min_ps(_mm_max_ps(az, bz), _mm_set1_ps(p.t[k])));
      const __m128 hit = _mm_cmple_ps(_mm_mul_ps(tn, los), _mm_mul_ps(tf, his));
      int bits = _mm_movemask_ps(hit);
      nearest = _mm_min_ps(nearest, _mm_or_ps(_mm_and_ps(hit, tn), _mm_andnot_ps(hit, inf)));
      const std::uint64_t rb = std::uint64_t{1} << k;
      while (bits) {
        const int j = __builtin_ctz(static_cast<unsigned>(bits));
        bits &= bits - 1;
        cm[j] |= rb;
      }
    }
    alignas(16) float nv[4];
    _mm_store_ps(nv, nearest);
#else
    float nv[4];
    for (int j = 0; j < 4; ++j) nv[j] = std::numeric_limits<float>::infinity();
    for (std::uint64_t m = mask; m; m &= m - 1) {
      const int k = __builtin_ctzll(m);
      const float r[3] = {p.ix[k], p.iy[k], p.iz[k]};
      for (int j = 0; j < 4; ++j) {
        float tn = 0.0f, tf = p.t[k];
        for (int a = 0; a < 3; ++a) {
          const float t0 = (node.lo[a][j] - eye[a]) * r[a], t1 = (node.hi[a][j] - eye[a]) * r[a];
          tn = std::max(tn, std::min(t0, t1));
          tf = std::min(tf, std::max(t0, t1));
        }
        if (tn * lo_scale <= tf * hi_scale) {
          cm[j] |= std::uint64_t{1} << k;
          nv[j] = std::min(nv[j], tn);
        }
      }
    }
#endif
    // Push the children reached, farthest first (so the nearest is popped next).
    int order[4], count = 0;
    for (int j = 0; j < 4; ++j) {
      if (!cm[j] || node.child[j] == FrameBvhNode::empty) continue;
      int at = count++;
      while (at > 0 && nv[order[at - 1]] < nv[j]) {
        order[at] = order[at - 1];
        --at;
      }
      order[at] = j;
    }
    for (int q = 0; q < count; ++q) {
      const std::uint32_t code = node.child[order[q]];
      if (FrameBvhNode::is_leaf(code)) {
        __builtin_prefetch(bvh.tris.data() + FrameBvhNode::leaf_first(code));
      } else {
        __builtin_prefetch(reinterpret_cast<const char*>(bvh.nodes.data() + code));
        __builtin_prefetch(reinterpret_cast<const char*>(bvh.nodes.data() + code) + 64);
      }
      stack[top++] = Entry{code, nv[order[q]] * lo_scale, cm[order[q]]};
    }
  }
}

// A packet's traversal as a resumable cursor, so that several packets can take turns: each step
// does one node or one leaf phase, and what the packet reads at its next step is prefetched at
// this one (children at push; a leaf's records when it is pushed, the data they name when it is
// first popped). While one packet waits on memory, the others compute.
struct FrameCursor {
  struct Entry {
    std::uint32_t code;
    std::uint32_t ready;  // a leaf already prepared (its data prefetched)
    std::uint64_t mask;
    float near;
  };
  Entry stack[256];
  int top = 0;
  void start(const FrameBvh& bvh, std::uint64_t live) noexcept {
    top = 0;
    if (bvh.root != FrameBvhNode::empty && live) stack[top++] = Entry{bvh.root, 0u, live, 0.0f};
  }
  [[nodiscard]] bool done() const noexcept { return top == 0; }
};

// One step of cursor `c` over packet `p`. `leaf.prepare(first, count)` is called on a leaf's first
// pop (load its records, prefetch what they name); `leaf.test(first, count, mask)` on its second.
template <class Leaf>
CULLKIT_FORCEINLINE void frame_cursor_step(const FrameBvh& bvh, const float eye[3], FramePacket& p, FrameCursor& c,
                                           float slack, Leaf& leaf, FrameCastStats* stats = nullptr) {
  const FrameCursor::Entry e = c.stack[--c.top];
  const float lo_scale = 1.0f - slack, hi_scale = 1.0f + slack;
  std::uint64_t mask = e.mask;
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = __builtin_ctzll(m);
    if (p.t[k] * hi_scale < e.near) mask &= ~(std::uint64_t{1} << k);
  }
  if (!mask) return;
  if (FrameBvhNode::is_leaf(e.code)) {
    const std::uint32_t first = FrameBvhNode::leaf_first(e.code), count = FrameBvhNode::leaf_count(e.code);
    if (!e.ready) {
      leaf.prepare(first, count);
      c.stack[c.top++] = FrameCursor::Entry{e.code, 1u, mask, e.near};
      return;
    }
    if (stats) {
      ++stats->leaves;
      stats->leaf_rays += static_cast<std::uint64_t>(__builtin_popcountll(mask)) * count;
    }
    leaf.test(first, count, mask);
    return;
  }
  const FrameBvhNode& node = bvh.nodes[e.code];
  if (stats) {
    ++stats->nodes;
    stats->ray_boxes += static_cast<std::uint64_t>(__builtin_popcountll(mask));
  }
  std::uint64_t cm[4] = {0, 0, 0, 0};
  alignas(16) float nv[4];
#if CULLKIT_HAS_SSE2
  const __m128 los = _mm_set1_ps(lo_scale), his = _mm_set1_ps(hi_scale), zero = _mm_setzero_ps();
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 lx = _mm_sub_ps(_mm_load_ps(node.lo[0]), _mm_set1_ps(eye[0])), hx = _mm_sub_ps(_mm_load_ps(node.hi[0]), _mm_set1_ps(eye[0]));
  const __m128 ly = _mm_sub_ps(_mm_load_ps(node.lo[1]), _mm_set1_ps(eye[1])), hy = _mm_sub_ps(_mm_load_ps(node.hi[1]), _mm_set1_ps(eye[1]));
  const __m128 lz = _mm_sub_ps(_mm_load_ps(node.lo[2]), _mm_set1_ps(eye[2])), hz = _mm_sub_ps(_mm_load_ps(node.hi[2]), _mm_set1_ps(eye[2]));
  __m128 nearest = inf;
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = __builtin_ctzll(m);
    const __m128 rx = _mm_set1_ps(p.ix[k]), ry = _mm_set1_ps(p.iy[k]), rz = _mm_set1_ps(p.iz[k]);
    const __m128 ax = _mm_mul_ps(lx, rx), bx = _mm_mul_ps(hx, rx);
    const __m128 ay = _mm_mul_ps(ly, ry), by = _mm_mul_ps(hy, ry);
    const __m128 az = _mm_mul_ps(lz, rz), bz = _mm_mul_ps(hz, rz);
    const __m128 tn = _mm_max_ps(_mm_max_ps(_mm_min_ps(ax, bx), _mm_min_ps(ay, by)), _mm_max_ps(_mm_min_ps(az, bz), zero));
    const __m128 tf = _mm_min_ps(_mm_min_ps(_mm_max_ps(ax, bx), _mm_max_ps(ay, by)),
                                 _mm_min_ps(_mm_max_ps(az, bz), _mm_set1_ps(p.t[k])));
    const __m128 hit = _mm_cmple_ps(_mm_mul_ps(tn, los), _mm_mul_ps(tf, his));
    int bits = _mm_movemask_ps(hit);
    nearest = _mm_min_ps(nearest, _mm_or_ps(_mm_and_ps(hit, tn), _mm_andnot_ps(hit, inf)));
    const std::uint64_t rb = std::uint64_t{1} << k;
    while (bits) {
      const int j = __builtin_ctz(static_cast<unsigned>(bits));
      bits &= bits - 1;
      cm[j] |= rb;
    }
  }
  _mm_store_ps(nv, nearest);
#else
  for (int j = 0; j < 4; ++j) nv[j] = std::numeric_limits<float>::infinity();
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = __builtin_ctzll(m);
    const float r[3] = {p.ix[k], p.iy[k], p.iz[k]};
    for (int j = 0; j < 4; ++j) {
      float tn = 0.0f, tf = p.t[k];
      for (int a = 0; a < 3; ++a) {
        const float t0 = (node.lo[a][j] - eye[a]) * r[a], t1 = (node.hi[a][j] - eye[a]) * r[a];
        tn = std::max(tn, std::min(t0, t1));
        tf = std::min(tf, std::max(t0, t1));
      }
      if (tn * lo_scale <= tf * hi_scale) {
        cm[j] |= std::uint64_t{1} << k;
        nv[j] = std::min(nv[j], tn);
      }
    }
  }
#endif
  int order[4], count = 0;
  for (int j = 0; j < 4; ++j) {
    if (!cm[j] || node.child[j] == FrameBvhNode::empty) continue;
    int at = count++;
    while (at > 0 && nv[order[at - 1]] < nv[j]) {
      order[at] = order[at - 1];
      --at;
    }
    order[at] = j;
  }
  for (int q = 0; q < count; ++q) {
    const std::uint32_t code = node.child[order[q]];
    if (FrameBvhNode::is_leaf(code)) {
      leaf.prefetch(FrameBvhNode::leaf_first(code), FrameBvhNode::leaf_count(code));
    } else {
      __builtin_prefetch(reinterpret_cast<const char*>(bvh.nodes.data() + code));
      __builtin_prefetch(reinterpret_cast<const char*>(bvh.nodes.data() + code) + 64);
    }
    c.stack[c.top++] = FrameCursor::Entry{code, 0u, cm[order[q]], nv[order[q]] * lo_scale};
  }
}

}  // namespace cullkit::detail::nci
