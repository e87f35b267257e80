// cullkit/detail/abt/occlusion_walk.hpp: the one front-to-back walk of an AdaptiveBinaryTree with
// an occlusion test, behind both AdaptiveBinaryTree::cull(frustum, occlusion, out) and
// cull_with_occlusion (users never name this).
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/vec3.hpp>

#include "../../abt_params.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/frustum.hpp"
#include "../../geometry/plane.hpp"
#include "leaf.hpp"

namespace cullkit::detail {

/// What the walk met, for the callers' statistics.
struct AbtOcclusionWalkCounts {
  std::uint64_t nodes_visited = 0;     ///< nodes whose box was looked at
  std::uint64_t frustum_rejected = 0;  ///< nodes and objects outside the frustum
};

/// Walks `abt` front to back from `eye`. A node is tested against the frustum (sphere, box, plane
/// masks), then with `visible(box, state)`: false drops its subtree as hidden; `visible` may refine
/// `state`, which the node's children and objects inherit (a query's start node, a proven-clear
/// subtree). The child on the eye's side of the split comes first. At a leaf each object is tested
/// against the planes its node straddles, then with `visible` unless it is alone in its leaf (its
/// box was the node's), and `report(position, state)` is called for each object kept. Objects
/// inserted since the last rebuild (no place in the tree's order) are tested one by one with
/// `root`, before the walk when `pending_first`, else after it. Boxes that are `is_unbounded` are
/// never given to `visible`: such nodes and objects always pass.
template <class Tree, class State, class Visible, class Report>
void abt_occlusion_walk(const Tree& abt, const Frustum& frustum, const glm::vec3& eye, const State& root,
                        bool pending_first, Visible&& visible, Report&& report, AbtOcclusionWalkCounts& counts) {
  const auto& nodes = abt.nodes();
  const auto& order = abt.order();
  const auto& bounds = abt.object_bounds();
  const Plane* planes = &frustum.plane(0);
  const auto consider = [&](std::uint32_t pos, std::uint32_t mask, bool query, State state) {
    if (order[pos] == Tree::removed_slot) return;
    const Aabb& box = bounds[pos];
    if (mask != 0 && abt_box_outside(planes, mask, box)) {
      ++counts.frustum_rejected;
      return;
    }
    if (query && !is_unbounded(box) && !visible(box, state)) return;
    report(pos, state);
  };
  const auto pending = [&] {
    for (std::size_t pos = abt.pending_begin(); pos < order.size(); ++pos)
      consider(static_cast<std::uint32_t>(pos), frustum.active_mask(), true, root);
  };
  if (pending_first) pending();
  if (!nodes.empty()) {
    struct Entry {
      std::uint32_t node;
      std::uint32_t mask;
      State state;
    };
    Entry stack[2 * static_cast<std::size_t>(Tree::depth_limit) + 4];
    std::size_t top = 0;
    stack[top++] = Entry{0, frustum.active_mask(), root};
    while (top > 0) {
      Entry entry = stack[--top];
      const AbtNode& node = nodes[entry.node];
      ++counts.nodes_visited;
      if (abt_node_outside(planes, entry.mask, node.bounds, node.sphere)) {
        ++counts.frustum_rejected;
        continue;
      }
      if (!is_unbounded(node.bounds) && !visible(node.bounds, entry.state)) continue;
      if (node.is_leaf()) {
        for (std::uint32_t pos = node.begin; pos < node.end; ++pos) consider(pos, entry.mask, node.count() > 1, entry.state);
        continue;
      }
      const bool left_first = eye[node.axis] < node.split;
      // The far child is pushed first, so the near one is popped (visited) first.
      stack[top++] = Entry{left_first ? node.left + 1 : node.left, entry.mask, entry.state};
      stack[top++] = Entry{left_first ? node.left : node.left + 1, entry.mask, entry.state};
    }
  }
  if (!pending_first) pending();
}

}  // namespace cullkit::detail
