// cullkit/occlusion_culling.hpp: frustum + occlusion culling of a whole scene for a renderer, with
// the occlusion tree grown on the fly from the major occluders found visible (front to back).
//
// Seed: 基于主要遮挡物的动态可见性算法, §3.4.2 (Algorithm 2 and its two refinements).
// The AdaptiveBinaryTree is walked front to back from the occlusion tree's eye. Each node's box is
// tested against the frustum, then against the occlusion tree; a hidden node drops its subtree. At
// a leaf each object is tested on its own; a visible object is reported and, if the caller's
// occluder source says it is a major occluder, inserted into the occlusion tree at once, so it hides
// what comes behind it. The seed's two refinements, each switchable:
//  1. a node found entirely clear of every hidden region passes its subtree without further
//     occlusion tests (cheaper; may report a little more, since occluders inserted later in the walk
//     are not consulted for that subtree);
//  2. a child's query starts at the occlusion-tree node where its parent's box last went down whole.
// Moving objects are tested last, against the finished tree (`cull_moving`).
//
// Conservative: an object is left out only if its box is outside the frustum (Frustum::classify) or
// entirely hidden (OcclusionTree::query). Allocation: only growth of `out` and of the occlusion tree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "adaptive_binary_tree.hpp"
#include "geometry/aabb.hpp"
#include "geometry/frustum.hpp"
#include "occlusion_tree.hpp"

namespace cullkit {

/// Switches of `cull_with_occlusion`. Every field has a documented default.
struct OcclusionCullParams {
  /// Refinement 1 (seed §3.4.2): a node whose box is entirely clear of hidden regions accepts its
  /// subtree without further occlusion queries. Default false: proving "clear" needs the full walk
  /// of every fragment, and the subtree then never consults occluders found later in the walk;
  /// docs/occlusion.md has the measurement.
  bool skip_clear_subtrees = false;
  /// Refinement 2: a child's occlusion query starts where its parent's box last stayed whole.
  /// Default true.
  bool start_at_parent_node = true;
  /// Insert the occluders of visible objects while walking (the seed's dynamic growth). With false,
  /// the tree is used as given. Default true.
  bool grow = true;
};

/// Counters of one `cull_with_occlusion` / `cull_moving` call (added to, never cleared by them).
struct OcclusionCullStats {
  std::uint64_t nodes_visited = 0;       ///< ABT nodes whose box was looked at
  std::uint64_t frustum_rejected = 0;    ///< nodes and objects outside the frustum
  std::uint64_t occlusion_queries = 0;   ///< calls to OcclusionTree::query
  std::uint64_t hidden = 0;              ///< nodes and objects found hidden
  std::uint64_t clear_subtrees = 0;      ///< nodes found clear (refinement 1)
  std::uint64_t objects_visible = 0;     ///< objects written to `out`
  std::uint64_t occluder_calls = 0;      ///< occluder-source calls (visible objects offered)
  /// Objects reported because their bounds are NaN, infinite or inverted (never queried, never
  /// offered as occluders).
  std::uint64_t unbounded = 0;
};

/// An occluder source that inserts an object's bounds as a solid box occluder when its flag is set.
/// `bounds[i]` and `is_box_occluder[i]` are indexed by input object index; both must outlive use.
struct BoxOccluderSource {
  const Aabb* bounds = nullptr;
  const std::uint8_t* is_box_occluder = nullptr;
  void operator()(std::uint32_t object, OcclusionTree& tree) const {
    if (is_box_occluder[object]) tree.insert_box_occluder(bounds[object]);
  }
};

/// Frustum and occlusion culling with dynamic occluder growth (see the file comment).
///
/// Clears `out`, then appends the input index of every object of `abt` that may meet `frustum` and
/// is not hidden, in front-to-back order from `tree.eye()`. `occluders(object, tree)` is called for
/// every object found visible, in that order; it may insert that object's occluders (polygons with
/// `insert_occluder`, solid boxes with `insert_box_occluder`; see BoxOccluderSource) or nothing.
/// Occluders must be real surfaces of the object (or lie inside a closed object), or culling stops
/// being conservative. `tree` may already hold occluders.
/// pre: `tree` is set up for the eye of the view. Cost: one occlusion query per visited node and
/// object, fewer with the refinements. Allocation: growth of `out` and `tree` only. Not thread-safe
/// on `tree` (it grows); `stats` may be null.
template <class Object, class Traits, class OccluderSource>
void cull_with_occlusion(const AdaptiveBinaryTree<Object, Traits>& abt, const Frustum& frustum, OcclusionTree& tree,
                         OccluderSource&& occluders, std::vector<std::uint32_t>& out,
                         OcclusionCullStats* stats = nullptr, const OcclusionCullParams& params = {}) {
  out.clear();
  OcclusionCullStats local;
  OcclusionCullStats& st = stats ? *stats : local;
  const auto& order = abt.order();

  // Per node: the occlusion-tree node its queries start at (the seed's second refinement), and
  // whether it was proven clear of every hidden region (the first).
  struct State {
    std::uint32_t start;
    bool clear;
  };
  // False if the box is hidden; refines `state` for what lies inside it.
  const auto visible = [&](const Aabb& box, State& state) {
    if (state.clear) return true;
    ++st.occlusion_queries;
    const OcclusionQueryResult r =
        tree.query(box, params.start_at_parent_node ? state.start : OcclusionTree::whole_tree, params.skip_clear_subtrees);
    if (r.answer == OcclusionAnswer::hidden) {
      ++st.hidden;
      return false;
    }
    if (r.answer == OcclusionAnswer::clear) {
      ++st.clear_subtrees;
      state.clear = true;
    }
    if (params.start_at_parent_node) state.start = r.together;
    return true;
  };
  // A visible object is reported, then offered as an occluder at once so it hides what follows.
  const auto report = [&](std::uint32_t pos, const State&) {
    const Aabb& box = abt.object_bounds()[pos];
    out.push_back(order[pos]);
    ++st.objects_visible;
    if (is_unbounded(box)) {
      ++st.unbounded;
      return;
    }
    if (params.grow) {
      ++st.occluder_calls;
      occluders(order[pos], tree);
    }
  };
  // Objects inserted since the last rebuild go last, against the grown tree (they are not in
  // front-to-back order and grow no occluders first).
  detail::AbtOcclusionWalkCounts counts;
  detail::abt_occlusion_walk(abt, frustum, tree.eye(), State{OcclusionTree::whole_tree, false}, false, visible,
                             report, counts);
  st.nodes_visited += counts.nodes_visited;
  st.frustum_rejected += counts.frustum_rejected;
}

/// The same with the parameters before the statistics, so that parameters need no `nullptr`:
/// `cull_with_occlusion(abt, frustum, tree, occluders, out, params)` or `(..., out, params, &stats)`.
template <class Object, class Traits, class OccluderSource>
void cull_with_occlusion(const AdaptiveBinaryTree<Object, Traits>& abt, const Frustum& frustum, OcclusionTree& tree,
                         OccluderSource&& occluders, std::vector<std::uint32_t>& out,
                         const OcclusionCullParams& params, OcclusionCullStats* stats = nullptr) {
  cull_with_occlusion(abt, frustum, tree, occluders, out, stats, params);
}

/// Moving objects, tested last against the finished tree (seed §2.4 (4)): appends to `out` the
/// index i of every `bounds[i]` that may meet the frustum and is not hidden. Boxes that are not
/// `is_valid` (NaN, infinite, inverted) are always appended, without an occlusion query, and
/// counted in `stats->unbounded`. No allocation beyond `out`; `tree` is not changed.
inline void cull_moving(const Frustum& frustum, const OcclusionTree& tree, const Aabb* bounds, std::size_t count,
                        std::vector<std::uint32_t>& out, OcclusionCullStats* stats = nullptr) {
  for (std::size_t i = 0; i < count; ++i) {
    if (!is_valid(bounds[i])) {
      out.push_back(static_cast<std::uint32_t>(i));
      if (stats) {
        ++stats->unbounded;
        ++stats->objects_visible;
      }
      continue;
    }
    if (frustum.classify(bounds[i]) == Containment::outside) {
      if (stats) ++stats->frustum_rejected;
      continue;
    }
    if (stats) ++stats->occlusion_queries;
    if (tree.is_occluded(bounds[i])) {
      if (stats) ++stats->hidden;
      continue;
    }
    out.push_back(static_cast<std::uint32_t>(i));
    if (stats) ++stats->objects_visible;
  }
}

}  // namespace cullkit
