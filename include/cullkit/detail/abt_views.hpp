// cullkit/detail/abt_views.hpp: the multi-view walk of AdaptiveBinaryTree::cull_views (users never
// name this).
//
// Why it is shaped this way. A walk that tests every node and object against each view in turn
// does the arithmetic of separate culls plus the cost of writing a view mask per object: measured,
// no faster than separate culls. The saving comes from views that look alike. The two eyes of a
// headset have the same orientation, so plane i of one eye has the same normal as plane i of the
// other, bit for bit, and only the offset d differs; shadow cascades of one camera share their side
// planes. So planes are grouped by equal normals (per plane index for the leaf test, per group of
// four planes for the node test): the expensive part of a plane test -- dot(n, c) without d,
// |n| . e, and the magnitude that sets the rounding tolerance -- is computed once per box and
// group, and each view then adds its own d and compares (a handful of operations). The sums are
// formed in exactly the order of the single-view rule (Frustum::classify and the SoA leaf test),
// so every view's answer is the single-view cull's answer, bit for bit. Four planes (node tests) or
// four objects (leaf tests) go through SSE2 at once; without SSE2 the scalar single-view tests run
// per view.
//
// Nodes inside every view still alive are written as one range of `order()` with one mask.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../abt_params.hpp"
#include "../config.hpp"
#include "../geometry/aabb.hpp"
#include "../geometry/frustum.hpp"
#include "abt_dynamic.hpp"
#include "abt_leaf.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail {

/// The planes of up to 32 views as structure-of-arrays, grouped by equal normals (see the file
/// comment): per plane index p, the views whose plane p has the same normal as an earlier view's
/// share that view's arithmetic; the node test shares it per group of four planes (the four side
/// planes; near and far). Built per call on the stack (about 6 KB).
class AbtViewPlanes {
 public:
  static constexpr std::uint32_t width = 8;  // planes per view, padded: two groups of four

  AbtViewPlanes(const Frustum* frusta, std::uint32_t views) noexcept : frusta_(frusta), views_(views) {
    for (std::uint32_t v = 0; v < views; ++v) {
      const Frustum& f = frusta[v];
      for (std::uint32_t i = 0; i < width; ++i) {
        const bool has = i < std::uint32_t(Frustum::max_planes) && f.has_plane(int(i));
        const Plane p = has ? f.plane(int(i)) : Plane{glm::vec3(0.0f), 0.0f};
        n_[v][0][i] = p.normal.x;
        n_[v][1][i] = p.normal.y;
        n_[v][2][i] = p.normal.z;
        d_[v][i] = p.d;
        ad_[v][i] = std::fabs(p.d);
      }
      for (std::uint32_t p = 0; p < std::uint32_t(Frustum::max_planes); ++p) group(v, p, 1u << p, plane_);
      for (std::uint32_t q = 0; q < 2; ++q) group(v, q, 15u << (4 * q), quad_);
    }
  }

  /// Views sharing normals, by key (a plane index, or a group of four planes): `heads` has one bit
  /// per group (its first view), `members[h]` the views of the group headed by h.
  struct Groups {
    std::uint32_t heads = 0;
    std::uint32_t members[32] = {};
  };

  [[nodiscard]] std::uint32_t views() const noexcept { return views_; }
  [[nodiscard]] const Groups& plane_groups(std::uint32_t p) const noexcept { return plane_[p]; }
  [[nodiscard]] const Groups& quad_groups(std::uint32_t q) const noexcept { return quad_[q]; }
  /// Normal component a (0 x, 1 y, 2 z) of the planes of view v, `width` floats.
  [[nodiscard]] const float* normal(std::uint32_t v, int a) const noexcept { return n_[v][a]; }
  [[nodiscard]] const float* d(std::uint32_t v) const noexcept { return d_[v]; }
  [[nodiscard]] const float* abs_d(std::uint32_t v) const noexcept { return ad_[v]; }
  [[nodiscard]] const Frustum& frustum(std::uint32_t v) const noexcept { return frusta_[v]; }

 private:
  // Puts view v in the group of the first earlier view with the same active planes and normals in
  // `planes` (a bit set), or makes it a head.
  template <std::size_t N>
  void group(std::uint32_t v, std::uint32_t key, std::uint32_t planes, Groups (&groups)[N]) noexcept {
    Groups& g = groups[key];
    const std::uint32_t mine = frusta_[v].active_mask() & planes;
    for (std::uint32_t rest = g.heads; rest != 0; rest &= rest - 1u) {
      const auto u = static_cast<std::uint32_t>(abt_lowest_bit(rest));
      if ((frusta_[u].active_mask() & planes) != mine) continue;
      bool same = true;
      for (std::uint32_t m = mine; m != 0 && same; m &= m - 1u) {
        const int i = abt_lowest_bit(m);
        same = n_[u][0][i] == n_[v][0][i] && n_[u][1][i] == n_[v][1][i] && n_[u][2][i] == n_[v][2][i];
      }
      if (same) {
        g.members[u] |= std::uint32_t{1} << v;
        return;
      }
    }
    g.heads |= std::uint32_t{1} << v;
    g.members[v] = std::uint32_t{1} << v;
  }

  const Frustum* frusta_;
  std::uint32_t views_;
  Groups plane_[Frustum::max_planes];
  Groups quad_[2];
  float n_[32][3][width];
  float d_[32][width];
  float ad_[32][width];
};

#if CULLKIT_HAS_SSE2
/// The part of a plane test shared by a group of views, for four planes (or four objects) at once:
/// s = (nx cx + ny cy) + nz cz, and the magnitude |nx cx| + |ny cy| + |nz cz| of the tolerance.
struct AbtShared {
  __m128 s, mag, r;
};

CULLKIT_FORCEINLINE __m128 abt_abs(__m128 x) noexcept { return _mm_andnot_ps(_mm_set1_ps(-0.0f), x); }

CULLKIT_FORCEINLINE AbtShared abt_shared(__m128 nx, __m128 ny, __m128 nz, __m128 cx, __m128 cy, __m128 cz) noexcept {
  const __m128 px = _mm_mul_ps(nx, cx), py = _mm_mul_ps(ny, cy), pz = _mm_mul_ps(nz, cz);
  AbtShared sh;
  sh.s = _mm_add_ps(_mm_add_ps(px, py), pz);
  sh.mag = _mm_add_ps(_mm_add_ps(abt_abs(px), abt_abs(py)), abt_abs(pz));
  sh.r = _mm_setzero_ps();
  return sh;
}

/// One view's verdict from the shared part: bits of `outside` (dc + r < -slack) and of `inside`
/// (dc - r >= slack), with dc = s + d and slack = ((mag + |d|) + r) * 8 eps: the single-view rule.
CULLKIT_FORCEINLINE void abt_verdict(const AbtShared& sh, __m128 d, __m128 ad, __m128 r, std::uint32_t& out,
                                     std::uint32_t& in) noexcept {
  const __m128 k = _mm_set1_ps(8.0f * std::numeric_limits<float>::epsilon());
  const __m128 dc = _mm_add_ps(sh.s, d);
  const __m128 slack = _mm_mul_ps(_mm_add_ps(_mm_add_ps(sh.mag, ad), r), k);
  out = static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(_mm_add_ps(dc, r), _mm_xor_ps(slack, _mm_set1_ps(-0.0f)))));
  in = static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmpge_ps(_mm_sub_ps(dc, r), slack)));
}

/// The node test (`abt_node_outside`: sphere, then box) for every alive view. Views found outside
/// leave `alive`; `masks` lose the planes the node is inside of.
inline void abt_views_node_sse(const AbtViewPlanes& vp, const Aabb& box, const Sphere& sphere, std::uint32_t& alive,
                               std::uint32_t* masks) noexcept {
  std::uint32_t todo = 0;
  for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    if (masks[v] != 0) todo |= std::uint32_t{1} << v;
  }
  if (todo == 0) return;
  if (!(sphere.radius >= 0.0f)) {
    alive &= ~todo;
    return;
  }
  std::uint32_t out[32], in[32];
  for (int pass = 0; pass < 2 && todo != 0; ++pass) {  // pass 0: the sphere, pass 1: the box
    glm::vec3 c = sphere.center, e(0.0f);
    if (pass == 1) {
      c = (box.min + box.max) * 0.5f;
      e = (box.max - box.min) * 0.5f;
    }
    const __m128 cx = _mm_set1_ps(c.x), cy = _mm_set1_ps(c.y), cz = _mm_set1_ps(c.z);
    const __m128 ex = _mm_set1_ps(e.x), ey = _mm_set1_ps(e.y), ez = _mm_set1_ps(e.z);
    for (std::uint32_t rest = todo; rest != 0; rest &= rest - 1u) out[abt_lowest_bit(rest)] = in[abt_lowest_bit(rest)] = 0;
    for (std::uint32_t q = 0; q < 2; ++q) {
      const AbtViewPlanes::Groups& g = vp.quad_groups(q);
      for (std::uint32_t heads = g.heads; heads != 0; heads &= heads - 1u) {
        const auto h = static_cast<std::uint32_t>(abt_lowest_bit(heads));
        std::uint32_t views = 0;
        for (std::uint32_t rest = g.members[h] & todo; rest != 0; rest &= rest - 1u) {
          const int v = abt_lowest_bit(rest);
          if ((masks[v] >> (4 * q)) & 15u) views |= std::uint32_t{1} << v;
        }
        if (views == 0) continue;
        const __m128 nx = _mm_loadu_ps(vp.normal(h, 0) + 4 * q), ny = _mm_loadu_ps(vp.normal(h, 1) + 4 * q);
        const __m128 nz = _mm_loadu_ps(vp.normal(h, 2) + 4 * q);
        AbtShared sh = abt_shared(nx, ny, nz, cx, cy, cz);
        sh.r = pass == 0 ? _mm_set1_ps(sphere.radius)
                         : _mm_add_ps(_mm_add_ps(_mm_mul_ps(abt_abs(nx), ex), _mm_mul_ps(abt_abs(ny), ey)),
                                      _mm_mul_ps(abt_abs(nz), ez));
        for (; views != 0; views &= views - 1u) {
          const auto v = static_cast<std::uint32_t>(abt_lowest_bit(views));
          std::uint32_t o = 0, i = 0;
          abt_verdict(sh, _mm_loadu_ps(vp.d(v) + 4 * q), _mm_loadu_ps(vp.abs_d(v) + 4 * q), sh.r, o, i);
          out[v] |= o << (4 * q);
          in[v] |= i << (4 * q);
        }
      }
    }
    std::uint32_t next = 0;
    for (std::uint32_t rest = todo; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      if (out[v] & masks[v]) {
        alive &= ~(std::uint32_t{1} << v);
        continue;
      }
      masks[v] &= ~in[v];
      if (masks[v] != 0) next |= std::uint32_t{1} << v;
    }
    todo = next;
  }
}

/// Leaf test for the straddling views, 16 objects from `base`: bit i of outside[v] set when
/// object base + i is outside view v (the SoA leaf test's rule, bit for bit).
inline void abt_views_lanes_sse(const AbtViewPlanes& vp, const AbtLeafBoxes& boxes, std::uint32_t base,
                                std::uint32_t straddling, const std::uint32_t* masks, std::uint32_t* outside) noexcept {
  std::uint32_t planes = 0;
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) planes |= masks[abt_lowest_bit(rest)];
  const float* col[6];
  for (int k = 0; k < 6; ++k) col[k] = boxes.column(k) + base;
  for (; planes != 0; planes &= planes - 1u) {
    const auto p = static_cast<std::uint32_t>(abt_lowest_bit(planes));
    const AbtViewPlanes::Groups& g = vp.plane_groups(p);
    for (std::uint32_t heads = g.heads; heads != 0; heads &= heads - 1u) {
      const auto h = static_cast<std::uint32_t>(abt_lowest_bit(heads));
      std::uint32_t views = 0;
      for (std::uint32_t rest = g.members[h] & straddling; rest != 0; rest &= rest - 1u) {
        const int v = abt_lowest_bit(rest);
        if ((masks[v] >> p) & 1u) views |= std::uint32_t{1} << v;
      }
      if (views == 0) continue;
      const __m128 nx = _mm_set1_ps(vp.normal(h, 0)[p]), ny = _mm_set1_ps(vp.normal(h, 1)[p]);
      const __m128 nz = _mm_set1_ps(vp.normal(h, 2)[p]);
      const __m128 ax = abt_abs(nx), ay = abt_abs(ny), az = abt_abs(nz);
      AbtShared sh[4];
      for (std::uint32_t q = 0; q < 4; ++q) {
        const std::uint32_t o = 4 * q;
        sh[q] = abt_shared(nx, ny, nz, _mm_loadu_ps(col[0] + o), _mm_loadu_ps(col[1] + o), _mm_loadu_ps(col[2] + o));
        sh[q].r = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, _mm_loadu_ps(col[3] + o)), _mm_mul_ps(ay, _mm_loadu_ps(col[4] + o))),
                             _mm_mul_ps(az, _mm_loadu_ps(col[5] + o)));
      }
      for (; views != 0; views &= views - 1u) {
        const auto v = static_cast<std::uint32_t>(abt_lowest_bit(views));
        const __m128 d = _mm_set1_ps(vp.d(v)[p]), ad = _mm_set1_ps(vp.abs_d(v)[p]);
        std::uint32_t bits = 0;
        for (std::uint32_t q = 0; q < 4; ++q) {
          std::uint32_t o = 0, in = 0;
          abt_verdict(sh[q], d, ad, sh[q].r, o, in);
          bits |= o << (4 * q);
        }
        outside[v] |= bits;
      }
    }
  }
}
#endif

/// The node test of one node for every alive view. Returns the views still alive.
CULLKIT_FORCEINLINE std::uint32_t abt_views_node(const AbtViewPlanes& vp, const AbtNode& node, std::uint32_t alive,
                                                 std::uint32_t* masks) noexcept {
#if CULLKIT_HAS_SSE2
  abt_views_node_sse(vp, node.bounds, node.sphere, alive, masks);
#else
  for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    if (abt_node_outside(&vp.frustum(std::uint32_t(v)).plane(0), masks[v], node.bounds, node.sphere))
      alive &= ~(std::uint32_t{1} << v);
  }
#endif
  return alive;
}

/// lane_bits[i] = `inside_views` | (bit v for every view v of `straddling` whose `outside[v]` has
/// bit i clear), for the 16 lanes.
CULLKIT_FORCEINLINE void abt_transpose_lanes(std::uint32_t straddling, const std::uint32_t* outside,
                                             std::uint32_t inside_views, std::uint32_t* lane_bits) noexcept {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
#if CULLKIT_HAS_SSE2
  __m128i acc[lanes / 4];
  const __m128i select[lanes / 4] = {_mm_setr_epi32(1, 2, 4, 8), _mm_setr_epi32(16, 32, 64, 128),
                                     _mm_setr_epi32(256, 512, 1024, 2048), _mm_setr_epi32(4096, 8192, 16384, 32768)};
  for (std::uint32_t q = 0; q < lanes / 4; ++q) acc[q] = _mm_set1_epi32(static_cast<int>(inside_views));
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    const __m128i out = _mm_set1_epi32(static_cast<int>(outside[v]));
    const __m128i bit = _mm_set1_epi32(static_cast<int>(std::uint32_t{1} << v));
    for (std::uint32_t q = 0; q < lanes / 4; ++q) {
      const __m128i in_view = _mm_cmpeq_epi32(_mm_and_si128(out, select[q]), _mm_setzero_si128());
      acc[q] = _mm_or_si128(acc[q], _mm_and_si128(in_view, bit));
    }
  }
  for (std::uint32_t q = 0; q < lanes / 4; ++q) _mm_storeu_si128(reinterpret_cast<__m128i*>(lane_bits + 4 * q), acc[q]);
#else
  for (std::uint32_t i = 0; i < lanes; ++i) lane_bits[i] = inside_views;
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    for (std::uint32_t i = 0; i < lanes; ++i) lane_bits[i] |= ((~outside[v] >> i) & 1u) << v;
  }
#endif
}

/// The objects of a straddling leaf (or small subtree) [begin, end): one output entry per object
/// some alive view keeps, with its view mask.
inline void abt_views_leaf(const AbtViewPlanes& vp, const AbtLeafBoxes& boxes, std::uint32_t alive,
                           std::uint32_t straddling, const std::uint32_t* masks, std::uint32_t begin,
                           std::uint32_t end, const std::uint32_t* order, const AbtDynamic& dyn,
                           std::vector<std::uint32_t>& out, std::vector<std::uint32_t>& view_bits) {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
  constexpr std::uint32_t all_lanes = (std::uint32_t{1} << lanes) - 1u;
  const std::uint32_t inside_views = alive & ~straddling;
  std::uint32_t outside[32];
  for (std::uint32_t base = begin; base < end; base += lanes) {
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) outside[abt_lowest_bit(rest)] = 0;
#if CULLKIT_HAS_SSE2
    abt_views_lanes_sse(vp, boxes, base, straddling, masks, outside);
#else
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      std::uint32_t cross = 0;
      boxes.classify_lanes(&vp.frustum(std::uint32_t(v)).plane(0), masks[v], base, outside[v], cross);
    }
#endif
    const std::uint32_t valid = end - base < lanes ? (std::uint32_t{1} << (end - base)) - 1u : all_lanes;
    std::uint32_t any = inside_views != 0 ? valid : 0u;
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) any |= ~outside[abt_lowest_bit(rest)];
    any &= valid & ~dyn.holes16(base);
    if (any == 0) continue;
    std::uint32_t lane_bits[lanes];
    abt_transpose_lanes(straddling, outside, inside_views, lane_bits);
    for (; any != 0; any &= any - 1u) {
      const int i = abt_lowest_bit(any);
      out.push_back(order[base + std::uint32_t(i)]);
      view_bits.push_back(lane_bits[i]);
    }
  }
}

/// The whole multi-view walk over a tree's arrays. `views` in [1, 32]; `StackSize` bounds depth.
/// Objects [begin, end) of the pending part (inserted since the last rebuild), for every view.
inline void abt_views_pending(const AbtViewPlanes& vp, const AbtLeafBoxes& boxes, std::uint32_t all,
                              std::uint32_t begin, std::uint32_t end, const std::uint32_t* order,
                              const AbtDynamic& dyn, std::vector<std::uint32_t>& out,
                              std::vector<std::uint32_t>& view_bits) {
  if (begin >= end) return;
  std::uint32_t masks[32];
  std::uint32_t straddling = 0;
  for (std::uint32_t v = 0; v < vp.views(); ++v) {
    masks[v] = vp.frustum(v).active_mask();
    if (masks[v] != 0) straddling |= std::uint32_t{1} << v;
  }
  if (straddling == 0) {
    out.insert(out.end(), order + begin, order + end);
    view_bits.insert(view_bits.end(), end - begin, all);
    return;
  }
  abt_views_leaf(vp, boxes, all, straddling, masks, begin, end, order, dyn, out, view_bits);
}

template <std::uint32_t StackSize>
void abt_cull_views(const std::vector<AbtNode>& tree, const std::vector<std::uint32_t>& order_v,
                    const AbtLeafBoxes& boxes, const AbtDynamic& dyn, std::uint32_t scan_below,
                    const Frustum* frusta, std::uint32_t views, std::vector<std::uint32_t>& out,
                    std::vector<std::uint32_t>& view_bits) {
  const AbtViewPlanes vp(frusta, views);
  const std::uint32_t all = views >= 32 ? ~std::uint32_t{0} : ((std::uint32_t{1} << views) - 1u);
  const std::uint32_t* order = order_v.data();
  abt_views_pending(vp, boxes, all, dyn.tree_end, static_cast<std::uint32_t>(order_v.size()), order, dyn, out,
                    view_bits);
  if (tree.empty()) return;
  const AbtNode* nodes = tree.data();
  struct Entry {
    std::uint32_t node;
    std::uint32_t alive;
    PlaneMask masks[32];
  };
  Entry stack[StackSize];
  std::uint32_t top = 0;
  Entry& root = stack[top++];
  root.node = 0;
  root.alive = all;
  for (std::uint32_t v = 0; v < views; ++v) root.masks[v] = frusta[v].active_mask();
  while (top > 0) {
    --top;
    const std::uint32_t k = stack[top].node;
    const AbtNode& node = nodes[k];
    std::uint32_t alive = stack[top].alive;
    std::uint32_t masks[32];
    for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      masks[v] = stack[top].masks[v];
    }
    alive = abt_views_node(vp, node, alive, masks);
    if (alive == 0) continue;
    std::uint32_t straddling = 0;
    for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      if (masks[v] != 0) straddling |= std::uint32_t{1} << v;
    }
    if (straddling == 0) {  // inside every view still alive: one range, one mask
      if (!dyn.node_has_holes(k)) {
        out.insert(out.end(), order + node.begin, order + node.end);
        view_bits.insert(view_bits.end(), node.count(), alive);
      } else {
        dyn.live_runs(node.begin, node.end, [&](std::uint32_t b, std::uint32_t e) {
          out.insert(out.end(), order + b, order + e);
          view_bits.insert(view_bits.end(), e - b, alive);
          return true;
        });
      }
      continue;
    }
    if (node.is_leaf() || node.count() <= scan_below) {
      abt_views_leaf(vp, boxes, alive, straddling, masks, node.begin, node.end, order, dyn, out, view_bits);
      continue;
    }
    const std::uint32_t left = node.left;
    Entry& r = stack[top++];  // reuses the popped slot: everything needed was read above
    r.node = left + 1;
    r.alive = alive;
    Entry& l = stack[top++];
    l.node = left;
    l.alive = alive;
    for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      r.masks[v] = l.masks[v] = static_cast<PlaneMask>(masks[v]);
    }
  }
}

}  // namespace cullkit::detail
