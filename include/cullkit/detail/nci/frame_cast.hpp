// cullkit/detail/nci/frame_cast.hpp: casting packets of up to 64 rays from the eye through the
// triangle hierarchy (triangle_bvh.hpp). Per node, each ray of the packet still reaching it takes one
// 4-wide box test over the children (two rays per 8-wide test in a build for AVX2, the same answers);
// the children reached are entered nearest first, each with the rays that reach it, and a ray
// leaves a subtree once its nearest solid hit lies before the subtree's box. Leaves go to the
// caller's test.
//
// A packet's traversal is a resumable cursor, so that several packets take turns (frame_tile.hpp
// runs four): each step does one node or one phase of a leaf, and what the packet reads at its next
// step is prefetched at this one (children when they are pushed; a leaf's records step by step).
// While one packet waits on memory, the others compute: on the 10.1M-triangle city seen whole this
// took the cast from 1.5-1.7x Embree's rtcIntersect1 time to 0.9-1.0x (docs/nci_internals.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "../bits.hpp"
#include "../../config.hpp"
#include "triangle_bvh.hpp"
#include "tile_state.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#if defined(__AVX2__)
#include <immintrin.h>
#endif
#endif

namespace cullkit::detail::nci {

// The rays of a packet: ray k (bit k of a mask) leaves the eye with inverse direction
// (ix, iy, iz)[k] (finite: a component below 1e-30 in magnitude is taken as +-1e-30) and holds its
// nearest solid hit so far at t[k], which the leaf test lowers.
struct FramePacket {
  alignas(16) float ix[64] = {};  // every lane defined: box tests read groups of four
  alignas(16) float iy[64] = {};
  alignas(16) float iz[64] = {};
  alignas(16) float t[64] = {};  // every lane defined: the depth cut compares four at a time
};

// The inverse of a direction component as FramePacket holds it.
[[nodiscard]] inline float frame_inverse(float d) noexcept {
  const float m = std::fabs(d) < 1e-30f ? std::copysign(1e-30f, d) : d;
  return 1.0f / m;
}

// Growth of a box before its test, relative to its largest coordinate offset from the eye: a hit
// or edge-band record of the float watertight test lies within a few edge bands (about 5e-7 of the
// corners' offsets from the eye) of its triangle; this is twenty times that, so a ray the triangle
// test could report never misses a box above it. The slab products' own rounding (a few 2^-24 of
// t) is far inside the chord that growth gives every such ray through the grown box.
inline constexpr float frame_box_growth = 1e-5f;
// Relative slack of the entry / exit comparison and of the depth cut (rounding of the products).
inline constexpr float frame_t_slack = 0x1p-20f;

// Packets of a tile taking turns (frame_tile.hpp). Measured on the 10.1M-triangle city seen
// whole, one thread, nearest hits only: 4 and 8 within 4 % of each other, both far ahead of 1.
inline constexpr std::size_t frame_turns = 4;

struct FrameCastStats {
  std::uint64_t nodes = 0, leaves = 0;
  std::uint64_t node_rays = 0, leaf_rays = 0;  // the rays of the entries visited, summed over the visits
};

struct FrameCursor {
  struct Entry {
    std::uint32_t code;
    std::uint32_t phase;  // leaves: the preparation steps done (Leaf::phases() before its test)
    std::uint64_t mask;
    float near;  // the smallest entry distance of its rays into its box (a lower bound)
    std::uint32_t carry;  // leaves: what the last preparation step hands to the next one
  };
  // Depth of the tree is at most TriangleBvhBuilder::depth_limit plus a balanced tail (below 64);
  // each level leaves at most three siblings on the stack.
  Entry stack[256];
  int top = 0;
  void start(const TriangleBvh& bvh, std::uint64_t live) noexcept {
    top = 0;
    if (bvh.root != TriangleBvhNode::empty && live) stack[top++] = Entry{bvh.root, 0u, live, 0.0f, 0u};
  }
  [[nodiscard]] bool done() const noexcept { return top == 0; }
};

// One packet's place in the turn-taking: its rays, its cursor and its block of the tile (bx, by in
// pixels, bw x bh).
struct FrameSlot {
  FramePacket p;
  FrameCursor cur;
  int bx = 0, by = 0, bw = 0, bh = 0;
  bool busy = false;
  float dir[3] = {0.0f, 0.0f, 0.0f};  // the packet's mean direction (unnormalized): a leaf's test order
};

// The rays of `mask` whose boxes test the 4 children of `node`: cm[j] the rays reaching child j,
// nv[j] the smallest entry distance among them.
CULLKIT_FORCEINLINE void frame_node_test(const TriangleBvhNode& node, const float eye[3], const FramePacket& p,
                                         std::uint64_t mask, std::uint64_t cm[4], float nv[4]) {
  const float lo_scale = 1.0f - frame_t_slack, hi_scale = 1.0f + frame_t_slack;
#if CULLKIT_HAS_SSE2
  const __m128 sign = _mm_set1_ps(-0.0f);
  // The four bounds of row q on axis a (TriangleBvhNode::bound, four at a time), less the eye.
  const auto row = [&](const std::uint8_t q[4], int a) {
    std::int32_t bits;
    std::memcpy(&bits, q, sizeof bits);
    const __m128i z = _mm_setzero_si128();
    const __m128i wide = _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(bits), z), z);
    const __m128 b = _mm_add_ps(_mm_set1_ps(node.origin[a]), _mm_mul_ps(_mm_cvtepi32_ps(wide), _mm_set1_ps(node.scale[a])));
    return _mm_sub_ps(b, _mm_set1_ps(eye[a]));
  };
  __m128 lx = row(node.qlo[0], 0), hx = row(node.qhi[0], 0);
  __m128 ly = row(node.qlo[1], 1), hy = row(node.qhi[1], 1);
  __m128 lz = row(node.qlo[2], 2), hz = row(node.qhi[2], 2);
  // Grown by frame_box_growth of the largest offset (an empty child may meet rays: its code says
  // it is empty).
  const __m128 far = _mm_max_ps(_mm_max_ps(_mm_max_ps(_mm_andnot_ps(sign, lx), _mm_andnot_ps(sign, hx)),
                                           _mm_max_ps(_mm_andnot_ps(sign, ly), _mm_andnot_ps(sign, hy))),
                                _mm_max_ps(_mm_andnot_ps(sign, lz), _mm_andnot_ps(sign, hz)));
  const __m128 grow = _mm_mul_ps(far, _mm_set1_ps(frame_box_growth));
  lx = _mm_sub_ps(lx, grow), ly = _mm_sub_ps(ly, grow), lz = _mm_sub_ps(lz, grow);
  hx = _mm_add_ps(hx, grow), hy = _mm_add_ps(hy, grow), hz = _mm_add_ps(hz, grow);
  // Which children each ray reaches goes to one byte per ray (bit j: child j), turned into the
  // children's masks sixteen rays at a time after the loop: a store per ray instead of four
  // masked updates.
  alignas(16) std::uint8_t reach[64] = {};
#if defined(__AVX2__)
  // Two rays per compare: the low half of each register serves one ray, the high half the next
  // (the same ray again when the mask holds an odd count), the same float operations per lane.
  const __m256 los8 = _mm256_set1_ps(lo_scale), his8 = _mm256_set1_ps(hi_scale), zero8 = _mm256_setzero_ps();
  const __m256 inf8 = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 lx8 = _mm256_set_m128(lx, lx), hx8 = _mm256_set_m128(hx, hx), ly8 = _mm256_set_m128(ly, ly);
  const __m256 hy8 = _mm256_set_m128(hy, hy), lz8 = _mm256_set_m128(lz, lz), hz8 = _mm256_set_m128(hz, hz);
  __m256 nearest8 = inf8;
  for (std::uint64_t m = mask; m;) {
    const int k = detail::lowest_bit(m);
    m &= m - 1;
    const int k2 = m ? detail::lowest_bit(m) : k;
    m &= m - 1;
    const auto pair = [&](const float* v) { return _mm256_set_m128(_mm_set1_ps(v[k2]), _mm_set1_ps(v[k])); };
    const __m256 rx = pair(p.ix), ry = pair(p.iy), rz = pair(p.iz);
    const __m256 ax = _mm256_mul_ps(lx8, rx), bx = _mm256_mul_ps(hx8, rx);
    const __m256 ay = _mm256_mul_ps(ly8, ry), by = _mm256_mul_ps(hy8, ry);
    const __m256 az = _mm256_mul_ps(lz8, rz), bz = _mm256_mul_ps(hz8, rz);
    const __m256 tn = _mm256_max_ps(_mm256_max_ps(_mm256_min_ps(ax, bx), _mm256_min_ps(ay, by)),
                                    _mm256_max_ps(_mm256_min_ps(az, bz), zero8));
    const __m256 tf = _mm256_min_ps(_mm256_min_ps(_mm256_max_ps(ax, bx), _mm256_max_ps(ay, by)),
                                    _mm256_min_ps(_mm256_max_ps(az, bz), pair(p.t)));
    const __m256 hit = _mm256_cmp_ps(_mm256_mul_ps(tn, los8), _mm256_mul_ps(tf, his8), _CMP_LE_OQ);
    const int bits = _mm256_movemask_ps(hit);
    nearest8 = _mm256_min_ps(nearest8, _mm256_or_ps(_mm256_and_ps(hit, tn), _mm256_andnot_ps(hit, inf8)));
    reach[k] = static_cast<std::uint8_t>(bits & 0xF);
    reach[k2] = static_cast<std::uint8_t>(bits >> 4);
  }
  const __m128 nearest = _mm_min_ps(_mm256_castps256_ps128(nearest8), _mm256_extractf128_ps(nearest8, 1));
#else
  const __m128 los = _mm_set1_ps(lo_scale), his = _mm_set1_ps(hi_scale), zero = _mm_setzero_ps();
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 nearest = inf;
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = detail::lowest_bit(m);
    const __m128 rx = _mm_set1_ps(p.ix[k]), ry = _mm_set1_ps(p.iy[k]), rz = _mm_set1_ps(p.iz[k]);
    const __m128 ax = _mm_mul_ps(lx, rx), bx = _mm_mul_ps(hx, rx);
    const __m128 ay = _mm_mul_ps(ly, ry), by = _mm_mul_ps(hy, ry);
    const __m128 az = _mm_mul_ps(lz, rz), bz = _mm_mul_ps(hz, rz);
    const __m128 tn = _mm_max_ps(_mm_max_ps(_mm_min_ps(ax, bx), _mm_min_ps(ay, by)), _mm_max_ps(_mm_min_ps(az, bz), zero));
    const __m128 tf = _mm_min_ps(_mm_min_ps(_mm_max_ps(ax, bx), _mm_max_ps(ay, by)),
                                 _mm_min_ps(_mm_max_ps(az, bz), _mm_set1_ps(p.t[k])));
    const __m128 hit = _mm_cmple_ps(_mm_mul_ps(tn, los), _mm_mul_ps(tf, his));
    nearest = _mm_min_ps(nearest, _mm_or_ps(_mm_and_ps(hit, tn), _mm_andnot_ps(hit, inf)));
    reach[k] = static_cast<std::uint8_t>(_mm_movemask_ps(hit));
  }
#endif
  // Bit j of each byte to the top of its byte (shifting 16-bit lanes: the low byte's bits land
  // below bit 7 of the high one), sixteen rays' bits per movemask.
  for (int c = 0; c < 4; ++c) {
    if (!((mask >> (16 * c)) & 0xFFFFu)) continue;
    const __m128i v = _mm_load_si128(reinterpret_cast<const __m128i*>(reach + 16 * c));
    cm[0] |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(_mm_slli_epi16(v, 7)))) << (16 * c);
    cm[1] |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(_mm_slli_epi16(v, 6)))) << (16 * c);
    cm[2] |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(_mm_slli_epi16(v, 5)))) << (16 * c);
    cm[3] |= static_cast<std::uint64_t>(static_cast<unsigned>(_mm_movemask_epi8(_mm_slli_epi16(v, 4)))) << (16 * c);
  }
  _mm_storeu_ps(nv, nearest);
#else
  float lo[3][4], hi[3][4];
  for (int j = 0; j < 4; ++j) {
    float far = 0.0f;
    for (int a = 0; a < 3; ++a) {
      lo[a][j] = node.bound(a, node.qlo[a][j]) - eye[a];
      hi[a][j] = node.bound(a, node.qhi[a][j]) - eye[a];
      far = std::max({far, std::fabs(lo[a][j]), std::fabs(hi[a][j])});
    }
    for (int a = 0; a < 3; ++a) {
      lo[a][j] -= far * frame_box_growth;
      hi[a][j] += far * frame_box_growth;
    }
    nv[j] = std::numeric_limits<float>::infinity();
  }
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = detail::lowest_bit(m);
    const float r[3] = {p.ix[k], p.iy[k], p.iz[k]};
    for (int j = 0; j < 4; ++j) {
      float tn = 0.0f, tf = p.t[k];
      for (int a = 0; a < 3; ++a) {
        const float t0 = lo[a][j] * r[a], t1 = hi[a][j] * r[a];
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
}

// Whether ray k of the packet meets the box lo..hi (relative to the eye, already grown), before
// its solid hit: the test of frame_node_test for one box.
[[nodiscard]] CULLKIT_FORCEINLINE bool frame_ray_meets(const FramePacket& p, int k, const float lo[3], const float hi[3]) {
  const float r[3] = {p.ix[k], p.iy[k], p.iz[k]};
  float tn = 0.0f, tf = p.t[k];
  for (int a = 0; a < 3; ++a) {
    const float t0 = lo[a] * r[a], t1 = hi[a] * r[a];
    tn = std::max(tn, std::min(t0, t1));
    tf = std::min(tf, std::max(t0, t1));
  }
  return tn * (1.0f - frame_t_slack) <= tf * (1.0f + frame_t_slack);
}

// The rays of `mask` that meet the box lo..hi: frame_ray_meets for each, four rays per compare
// where SSE is available, eight with AVX2 (the same float operations in the same order, so the same
// answer; the std::min / std::max operand order is kept by the order of the SIMD operands).
[[nodiscard]] CULLKIT_FORCEINLINE std::uint64_t frame_rays_meet(const FramePacket& p, std::uint64_t mask, const float lo[3],
                                                                const float hi[3]) {
  std::uint64_t out = 0;
#if CULLKIT_HAS_SSE2 && defined(__AVX2__)
  const __m256 l[3] = {_mm256_set1_ps(lo[0]), _mm256_set1_ps(lo[1]), _mm256_set1_ps(lo[2])};
  const __m256 h[3] = {_mm256_set1_ps(hi[0]), _mm256_set1_ps(hi[1]), _mm256_set1_ps(hi[2])};
  const __m256 lo_scale = _mm256_set1_ps(1.0f - frame_t_slack), hi_scale = _mm256_set1_ps(1.0f + frame_t_slack);
  const float* inv[3] = {p.ix, p.iy, p.iz};
  for (std::uint64_t m = mask; m;) {
    const int g = detail::lowest_bit(m) & ~7;  // the first lane of the group of eight
    m &= ~(std::uint64_t{0xFF} << g);
    __m256 tn = _mm256_setzero_ps(), tf = _mm256_loadu_ps(p.t + g);
    for (int a = 0; a < 3; ++a) {
      const __m256 r = _mm256_loadu_ps(inv[a] + g);
      const __m256 t0 = _mm256_mul_ps(l[a], r), t1 = _mm256_mul_ps(h[a], r);
      tn = _mm256_max_ps(_mm256_min_ps(t1, t0), tn);
      tf = _mm256_min_ps(_mm256_max_ps(t1, t0), tf);
    }
    const int in = _mm256_movemask_ps(_mm256_cmp_ps(_mm256_mul_ps(tn, lo_scale), _mm256_mul_ps(tf, hi_scale), _CMP_LE_OQ));
    out |= static_cast<std::uint64_t>(in) << g;
  }
  return out & mask;
#elif CULLKIT_HAS_SSE2
  const __m128 l[3] = {_mm_set1_ps(lo[0]), _mm_set1_ps(lo[1]), _mm_set1_ps(lo[2])};
  const __m128 h[3] = {_mm_set1_ps(hi[0]), _mm_set1_ps(hi[1]), _mm_set1_ps(hi[2])};
  const __m128 lo_scale = _mm_set1_ps(1.0f - frame_t_slack), hi_scale = _mm_set1_ps(1.0f + frame_t_slack);
  const float* inv[3] = {p.ix, p.iy, p.iz};
  for (std::uint64_t m = mask; m;) {
    const int g = detail::lowest_bit(m) & ~3;  // the first lane of the group of four
    m &= ~(std::uint64_t{0xF} << g);
    __m128 tn = _mm_setzero_ps(), tf = _mm_load_ps(p.t + g);
    for (int a = 0; a < 3; ++a) {
      const __m128 r = _mm_load_ps(inv[a] + g);
      const __m128 t0 = _mm_mul_ps(l[a], r), t1 = _mm_mul_ps(h[a], r);
      tn = _mm_max_ps(_mm_min_ps(t1, t0), tn);  // std::max(tn, std::min(t0, t1))
      tf = _mm_min_ps(_mm_max_ps(t1, t0), tf);  // std::min(tf, std::max(t0, t1))
    }
    const int in = _mm_movemask_ps(_mm_cmple_ps(_mm_mul_ps(tn, lo_scale), _mm_mul_ps(tf, hi_scale)));
    out |= static_cast<std::uint64_t>(in) << g;
  }
  return out & mask;
#else
  for (std::uint64_t m = mask; m; m &= m - 1) {
    const int k = detail::lowest_bit(m);
    if (frame_ray_meets(p, k, lo, hi)) out |= std::uint64_t{1} << k;
  }
  return out;
#endif
}

// One step of cursor `c` over packet `p`: pops an entry, drops the rays whose solid hit now lies
// before its box; a leaf is prepared (`carry = leaf.prepare(first, count, phase, carry)`,
// leaf.phases() times: load what the previous phase prefetched, prefetch what it names) and then
// tested (`leaf.test(first, count, mask, carry)`, which lowers p.t); a node pushes the children its
// rays reach, nearest last (popped first), prefetching them (`leaf.prefetch(first, count)` for
// leaves).
template <class Leaf>
CULLKIT_FORCEINLINE void frame_cursor_step(const TriangleBvh& bvh, const float eye[3], FramePacket& p, FrameCursor& c,
                                           Leaf& leaf, FrameCastStats& stats) {
  const FrameCursor::Entry e = c.stack[--c.top];
  std::uint64_t mask = e.mask;
  // A leaf's later phases skip the depth cut: only this packet's own leaf tests lower its p.t, and
  // none ran since the cut of its first phase.
  const bool cut = !TriangleBvhNode::is_leaf(e.code) || e.phase == 0;
#if CULLKIT_HAS_SSE2
  if (cut) {
    // Four rays per compare, over the groups of four that hold rays of the entry (deep in the
    // tree an entry holds a few rays of its packet, near the root most of them).
    const __m128 near = _mm_set1_ps(e.near), scale = _mm_set1_ps(1.0f + frame_t_slack);
    std::uint64_t drop = 0;
    for (std::uint64_t m = mask; m;) {
      const int g = detail::lowest_bit(m) & ~3;
      m &= ~(std::uint64_t{0xF} << g);
      const __m128 before = _mm_cmplt_ps(_mm_mul_ps(_mm_load_ps(p.t + g), scale), near);
      drop |= static_cast<std::uint64_t>(_mm_movemask_ps(before)) << g;
    }
    mask &= ~drop;
  }
#else
  for (std::uint64_t m = cut ? mask : 0; m; m &= m - 1) {
    const int k = detail::lowest_bit(m);
    if (p.t[k] * (1.0f + frame_t_slack) < e.near) mask &= ~(std::uint64_t{1} << k);
  }
#endif
  if (!mask) return;
  if (TriangleBvhNode::is_leaf(e.code)) {
    const std::uint32_t first = TriangleBvhNode::leaf_first(e.code), count = TriangleBvhNode::leaf_count(e.code);
    if (e.phase < leaf.phases()) {
      const std::uint32_t carry = leaf.prepare(first, count, e.phase, e.carry);
      c.stack[c.top++] = FrameCursor::Entry{e.code, e.phase + 1u, mask, e.near, carry};
      return;
    }
    ++stats.leaves;
    stats.leaf_rays += static_cast<std::uint64_t>(detail::popcount(mask));
    leaf.test(first, count, mask, e.carry);
    return;
  }
  const TriangleBvhNode& node = bvh.nodes[e.code];
  ++stats.nodes;
  stats.node_rays += static_cast<std::uint64_t>(detail::popcount(mask));
  std::uint64_t cm[4] = {0, 0, 0, 0};
  float nv[4];
  frame_node_test(node, eye, p, mask, cm, nv);
  // The children reached, pushed farthest first (equal distances: the lower child first), so the
  // nearest is popped next. Each child's place is counted rather than found by an insertion sort:
  // which children a packet reaches, and in what order, is noise to a branch predictor.
  int reached[4], place[4];
  for (int j = 0; j < 4; ++j)
    reached[j] = static_cast<int>(cm[j] != 0) & static_cast<int>(node.child[j] != TriangleBvhNode::empty);
  for (int j = 0; j < 4; ++j) {
    int before = 0;
    for (int i = 0; i < 4; ++i)
      before += reached[i] & (static_cast<int>(nv[i] > nv[j]) |
                              (static_cast<int>(nv[i] == nv[j]) & static_cast<int>(i < j)));
    place[j] = before;
  }
  for (int j = 0; j < 4; ++j) {
    if (!reached[j]) continue;
    const std::uint32_t code = node.child[j];
    if (TriangleBvhNode::is_leaf(code)) {
      leaf.prefetch(TriangleBvhNode::leaf_first(code), TriangleBvhNode::leaf_count(code));
    } else {
      detail::prefetch(bvh.nodes.data() + code);  // one cache line
    }
    c.stack[c.top + place[j]] = FrameCursor::Entry{code, 0u, cm[j], nv[j] * (1.0f - frame_t_slack), 0u};
  }
  c.top += reached[0] + reached[1] + reached[2] + reached[3];
}

}  // namespace cullkit::detail::nci
