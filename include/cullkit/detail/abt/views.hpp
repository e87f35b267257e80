// cullkit/detail/abt/views.hpp: the multi-view walk of AdaptiveBinaryTree::cull_views (users never
// name this).
//
// Views whose planes fit in 32 distinct ones (up to five views always; stereo pairs and cascades
// of one camera share planes) take the merged walk of views_merged.hpp. The walk below is for
// more: it tests each view's own planes and shares arithmetic only within families.
//
// Why it is shaped this way. A walk that tests every node and object against each view in turn
// does the arithmetic of separate culls plus the cost of writing a view mask per object: measured,
// no faster than separate culls. The saving comes from views that look alike. The two eyes of a
// headset have the same orientation, so plane i of one eye has the same normal as plane i of the
// other, bit for bit, and only the offset d differs; shadow cascades of one camera share theirs
// too. Views whose active planes have the same normals form a *family*. For a family, the
// expensive part of the plane test -- dot(n, c) without d, |n| . e, and the magnitude that sets the
// rounding tolerance -- is computed once per box and plane; each view then adds its own d and
// compares (a handful of operations). The sums are formed in exactly the order of the single-view
// rule (Frustum::classify and the SoA leaf test), so every view's answer is the single-view cull's
// answer, bit for bit. Four planes (node tests) or four objects (leaf tests) go through SSE2 at
// once, without a branch per plane; without SSE2 the scalar single-view tests run per view.
//
// Nodes inside every view still alive are written as one range of `order()` with one mask.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../../abt_params.hpp"
#include "../../config.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/frustum.hpp"
#include "dynamic.hpp"
#include "leaf.hpp"
#include "views_merged.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail {

/// The planes of up to 32 views as structure-of-arrays, with the views grouped into families of
/// equal normals (see the file comment). Built per call on the stack (about 5 KB).
class AbtViewPlanes {
 public:
  static constexpr std::uint32_t width = 8;  // planes per view, padded: two groups of four

  AbtViewPlanes(const Frustum* frusta, std::uint32_t views) noexcept : frusta_(frusta), views_(views) {
    for (std::uint32_t v = 0; v < views; ++v) {
      const Frustum& f = frusta[v];
      for (std::uint32_t i = 0; i < width; ++i) {
        const bool has = i < std::uint32_t(Frustum::max_planes) && f.has_plane(int(i));
        const Plane p = has ? f.plane(int(i)) : Plane{glm::vec3(0.0f), 0.0f};
        d_[v][i] = p.d;
        ad_[v][i] = std::fabs(p.d);
      }
      std::uint32_t head = v;
      for (std::uint32_t u = 0; u < v && head == v; ++u) {
        if (family_of_[u] != u || frusta[u].active_mask() != f.active_mask()) continue;
        bool same = true;
        for (std::uint32_t rest = f.active_mask(); rest != 0 && same; rest &= rest - 1u) {
          const int i = abt_lowest_bit(rest);
          same = frusta[u].plane(i).normal == f.plane(i).normal;
        }
        if (same) head = u;
      }
      family_of_[v] = head;
      if (head == v) {
        heads_ |= std::uint32_t{1} << v;
        for (std::uint32_t i = 0; i < width; ++i) {
          const bool has = i < std::uint32_t(Frustum::max_planes) && f.has_plane(int(i));
          const glm::vec3 n = has ? f.plane(int(i)).normal : glm::vec3(0.0f);
          n_[v][0][i] = n.x;
          n_[v][1][i] = n.y;
          n_[v][2][i] = n.z;
        }
      }
      members_[head] |= std::uint32_t{1} << v;
    }
  }

  [[nodiscard]] std::uint32_t views() const noexcept { return views_; }
  /// One bit per family: its first view.
  [[nodiscard]] std::uint32_t heads() const noexcept { return heads_; }
  /// The views of the family whose first view is `head`.
  [[nodiscard]] std::uint32_t members(std::uint32_t head) const noexcept { return members_[head]; }
  /// Normal component a (0 x, 1 y, 2 z) of the planes of family `head`, `width` floats.
  [[nodiscard]] const float* normal(std::uint32_t head, int a) const noexcept { return n_[head][a]; }
  [[nodiscard]] const float* d(std::uint32_t v) const noexcept { return d_[v]; }
  [[nodiscard]] const float* abs_d(std::uint32_t v) const noexcept { return ad_[v]; }
  [[nodiscard]] const Frustum& frustum(std::uint32_t v) const noexcept { return frusta_[v]; }

 private:
  const Frustum* frusta_;
  std::uint32_t views_;
  std::uint32_t heads_ = 0;
  std::uint32_t family_of_[32] = {};
  std::uint32_t members_[32] = {};
  float n_[32][3][width];
  float d_[32][width];
  float ad_[32][width];
};

#if CULLKIT_HAS_SSE2
/// The part of a plane test shared by a family, for four planes (or four objects) at once:
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

/// The node test (`abt_node_outside`: sphere, then box) for every alive view of one family.
/// Views found outside leave `alive`; `masks` lose the planes the node is inside of.
inline void abt_family_node(const AbtViewPlanes& vp, std::uint32_t head, const Aabb& box, const Sphere& sphere,
                            std::uint32_t& alive, std::uint32_t* masks) noexcept {
  std::uint32_t todo = 0;
  for (std::uint32_t rest = alive & vp.members(head); rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    if (masks[v] != 0) todo |= std::uint32_t{1} << v;
  }
  if (todo == 0) return;
  if (!(sphere.radius >= 0.0f)) {
    alive &= ~todo;
    return;
  }
  AbtShared sh[2];
  __m128 ex[3] = {};
  for (int pass = 0; pass < 2 && todo != 0; ++pass) {  // pass 0: the sphere, pass 1: the box
    glm::vec3 c = sphere.center;
    if (pass == 1) {
      c = (box.min + box.max) * 0.5f;
      const glm::vec3 e = (box.max - box.min) * 0.5f;
      ex[0] = _mm_set1_ps(e.x);
      ex[1] = _mm_set1_ps(e.y);
      ex[2] = _mm_set1_ps(e.z);
    }
    const __m128 cx = _mm_set1_ps(c.x), cy = _mm_set1_ps(c.y), cz = _mm_set1_ps(c.z);
    for (std::uint32_t q = 0; q < 2; ++q) {
      const __m128 nx = _mm_loadu_ps(vp.normal(head, 0) + 4 * q);
      const __m128 ny = _mm_loadu_ps(vp.normal(head, 1) + 4 * q);
      const __m128 nz = _mm_loadu_ps(vp.normal(head, 2) + 4 * q);
      sh[q] = abt_shared(nx, ny, nz, cx, cy, cz);
      sh[q].r = pass == 0 ? _mm_set1_ps(sphere.radius)
                          : _mm_add_ps(_mm_add_ps(_mm_mul_ps(abt_abs(nx), ex[0]), _mm_mul_ps(abt_abs(ny), ex[1])),
                                       _mm_mul_ps(abt_abs(nz), ex[2]));
    }
    std::uint32_t next = 0;
    for (std::uint32_t rest = todo; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      std::uint32_t out = 0, in = 0;
      for (std::uint32_t q = 0; q < 2; ++q) {
        std::uint32_t o = 0, i = 0;
        abt_verdict(sh[q], _mm_loadu_ps(vp.d(std::uint32_t(v)) + 4 * q), _mm_loadu_ps(vp.abs_d(std::uint32_t(v)) + 4 * q),
                    sh[q].r, o, i);
        out |= o << (4 * q);
        in |= i << (4 * q);
      }
      if (out & masks[v]) {
        alive &= ~(std::uint32_t{1} << v);
        continue;
      }
      masks[v] &= ~in;
      if (masks[v] != 0) next |= std::uint32_t{1} << v;
    }
    todo = next;
  }
}

/// Leaf test for the straddling views of one family, 16 objects from `base`: bit i of outside[v]
/// set when object base + i is outside view v (the SoA leaf test's rule, bit for bit).
inline void abt_family_lanes(const AbtViewPlanes& vp, std::uint32_t head, const AbtLeafBoxes& boxes,
                             std::uint32_t base, std::uint32_t views, const std::uint32_t* masks,
                             std::uint32_t* outside) noexcept {
  std::uint32_t planes = 0;
  for (std::uint32_t rest = views; rest != 0; rest &= rest - 1u) planes |= masks[abt_lowest_bit(rest)];
  const float* col[6];
  for (int k = 0; k < 6; ++k) col[k] = boxes.column(k) + base;
  for (; planes != 0; planes &= planes - 1u) {
    const int p = abt_lowest_bit(planes);
    const __m128 nx = _mm_set1_ps(vp.normal(head, 0)[p]), ny = _mm_set1_ps(vp.normal(head, 1)[p]);
    const __m128 nz = _mm_set1_ps(vp.normal(head, 2)[p]);
    const __m128 ax = abt_abs(nx), ay = abt_abs(ny), az = abt_abs(nz);
    AbtShared sh[4];
    for (std::uint32_t q = 0; q < 4; ++q) {
      const std::uint32_t o = 4 * q;
      sh[q] = abt_shared(nx, ny, nz, _mm_loadu_ps(col[0] + o), _mm_loadu_ps(col[1] + o), _mm_loadu_ps(col[2] + o));
      sh[q].r = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, _mm_loadu_ps(col[3] + o)), _mm_mul_ps(ay, _mm_loadu_ps(col[4] + o))),
                           _mm_mul_ps(az, _mm_loadu_ps(col[5] + o)));
    }
    for (std::uint32_t rest = views; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      if (!((masks[v] >> p) & 1u)) continue;
      const __m128 d = _mm_set1_ps(vp.d(std::uint32_t(v))[p]), ad = _mm_set1_ps(vp.abs_d(std::uint32_t(v))[p]);
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
#endif

/// The node test of one node for every alive view. Returns the views still alive.
CULLKIT_FORCEINLINE std::uint32_t abt_views_node(const AbtViewPlanes& vp, const AbtNode& node, std::uint32_t alive,
                                                 std::uint32_t* masks) noexcept {
#if CULLKIT_HAS_SSE2
  for (std::uint32_t rest = vp.heads(); rest != 0; rest &= rest - 1u) {
    const auto head = static_cast<std::uint32_t>(abt_lowest_bit(rest));
    if (alive & vp.members(head)) abt_family_node(vp, head, node.bounds, node.sphere, alive, masks);
  }
#else
  for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    if (abt_node_outside(&vp.frustum(std::uint32_t(v)).plane(0), masks[v], node.bounds, node.sphere))
      alive &= ~(std::uint32_t{1} << v);
  }
#endif
  return alive;
}

/// The objects of a straddling leaf (or small subtree) [begin, end): one output entry per object
/// some alive view keeps, with its view mask.
inline void abt_views_leaf(const AbtViewPlanes& vp, const AbtLeafBoxes& boxes, std::uint32_t alive,
                           std::uint32_t straddling, const std::uint32_t* masks, std::uint32_t begin,
                           std::uint32_t end, const std::uint32_t* order, const AbtDynamic& dyn,
                           AbtViewsOutput& out) {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
  const std::uint32_t inside_views = alive & ~straddling;
  std::uint32_t outside[32];
  for (std::uint32_t base = begin; base < end; base += lanes) {
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) outside[abt_lowest_bit(rest)] = 0;
#if CULLKIT_HAS_SSE2
    for (std::uint32_t rest = vp.heads(); rest != 0; rest &= rest - 1u) {
      const auto head = static_cast<std::uint32_t>(abt_lowest_bit(rest));
      const std::uint32_t views = straddling & vp.members(head);
      if (views != 0) abt_family_lanes(vp, head, boxes, base, views, masks, outside);
    }
#else
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      std::uint32_t cross = 0;
      boxes.classify_lanes(&vp.frustum(std::uint32_t(v)).plane(0), masks[v], base, outside[v], cross);
    }
#endif
    abt_emit_lanes(base, end, straddling, outside, inside_views, order, dyn, out);
  }
}

/// The whole multi-view walk over a tree's arrays. `views` in [1, 32]; `StackSize` bounds depth.
/// Objects [begin, end) of the pending part (inserted since the last rebuild), for every view.
inline void abt_views_pending(const AbtViewPlanes& vp, const AbtLeafBoxes& boxes, std::uint32_t all,
                              std::uint32_t begin, std::uint32_t end, const std::uint32_t* order,
                              const AbtDynamic& dyn, AbtViewsOutput& out) {
  if (begin >= end) return;
  std::uint32_t masks[32];
  std::uint32_t straddling = 0;
  for (std::uint32_t v = 0; v < vp.views(); ++v) {
    masks[v] = vp.frustum(v).active_mask();
    if (masks[v] != 0) straddling |= std::uint32_t{1} << v;
  }
  if (straddling == 0) {
    out.put_range(order, begin, end, all);
    return;
  }
  abt_views_leaf(vp, boxes, all, straddling, masks, begin, end, order, dyn, out);
}

template <std::uint32_t StackSize>
void abt_cull_views_per_view(const std::vector<AbtNode>& tree, const std::vector<std::uint32_t>& order_v,
                             const AbtLeafBoxes& boxes, const AbtDynamic& dyn, std::uint32_t scan_below,
                             const Frustum* frusta, std::uint32_t views, AbtViewsOutput& out) {
  const AbtViewPlanes vp(frusta, views);
  const std::uint32_t all = views >= 32 ? ~std::uint32_t{0} : ((std::uint32_t{1} << views) - 1u);
  const std::uint32_t* order = order_v.data();
  abt_views_pending(vp, boxes, all, dyn.tree_end, static_cast<std::uint32_t>(order_v.size()), order, dyn, out);
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
        out.put_range(order, node.begin, node.end, alive);
      } else {
        dyn.live_runs(node.begin, node.end, [&](std::uint32_t b, std::uint32_t e) {
          out.put_range(order, b, e, alive);
          return true;
        });
      }
      continue;
    }
    if (node.is_leaf() || node.count() <= scan_below) {
      abt_views_leaf(vp, boxes, alive, straddling, masks, node.begin, node.end, order, dyn, out);
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

/// The multi-view cull: the merged walk when the views' planes fit, else the per-view walk.
template <std::uint32_t StackSize>
void abt_cull_views(const std::vector<AbtNode>& tree, const std::vector<std::uint32_t>& order_v,
                    const AbtLeafBoxes& boxes, const AbtDynamic& dyn, std::uint32_t scan_below,
                    const Frustum* frusta, std::uint32_t views, std::vector<std::uint32_t>& out,
                    std::vector<std::uint32_t>& view_bits) {
  AbtViewsOutput writer(out, view_bits);
  AbtMergedPlanes merged;
  if (merged.assign(frusta, views))
    abt_cull_views_merged<StackSize>(merged, views, tree, order_v, boxes, dyn, scan_below, writer);
  else
    abt_cull_views_per_view<StackSize>(tree, order_v, boxes, dyn, scan_below, frusta, views, writer);
  writer.finish();
}

}  // namespace cullkit::detail
