// cullkit/detail/abt/repair.hpp: the repair step of AdaptiveBinaryTree's repairing refit (users
// never name this): the topmost subtrees whose split ratio degraded are rebuilt in place.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../../abt_params.hpp"
#include "build.hpp"
#include "leaf.hpp"
#include "split.hpp"

namespace cullkit::detail {

/// (area of the children) / (own area) of an inner node; 0 for leaves and for nodes without a
/// measurable area (flat, or unbounded).
[[nodiscard]] inline double abt_split_ratio(const std::vector<AbtNode>& nodes, std::uint32_t k) noexcept {
  const AbtNode& node = nodes[k];
  if (node.is_leaf()) return 0.0;
  const double own = abt_measured_area(node.bounds);
  if (!(own > 0.0)) return 0.0;
  return (abt_measured_area(nodes[node.left].bounds) + abt_measured_area(nodes[node.left + 1].bounds)) / own;
}

/// See AdaptiveBinaryTree::repair (the tree has no holes and nothing pending here).
inline void abt_repair(double rebuild_threshold, const AbtBuildContext& build_context, std::vector<AbtNode>& nodes,
                       std::vector<double>& ref_split, std::vector<std::uint32_t>& order, std::vector<Aabb>& bounds,
                       AbtLeafBoxes& leaf_boxes, AbtStats& stats) {
  struct Visit {
    std::uint32_t node, depth;
  };
  std::vector<Visit> roots, stack;
  stack.push_back(Visit{0, 0});
  while (!stack.empty()) {
    const Visit v = stack.back();
    stack.pop_back();
    const AbtNode& node = nodes[v.node];
    if (node.is_leaf()) continue;
    const double ref = ref_split[v.node];
    if (abt_split_ratio(nodes, v.node) > ref + rebuild_threshold * (2.0 - ref)) {
      roots.push_back(v);
      continue;
    }
    stack.push_back(Visit{node.left + 1, v.depth + 1});
    stack.push_back(Visit{node.left, v.depth + 1});
  }
  if (roots.empty()) return;
  std::vector<AbtNode> raw = nodes;
  std::vector<double> raw_ref = ref_split;
  const double fresh = std::numeric_limits<double>::quiet_NaN();  // measured after the layout
  std::vector<AbtBuildItem> items;
  for (const Visit& v : roots) {
    const std::uint32_t b = nodes[v.node].begin, e = nodes[v.node].end;
    items.clear();
    for (std::uint32_t i = b; i < e; ++i)
      items.push_back(AbtBuildItem{bounds[i], abt_centroid(bounds[i]), order[i]});
    AbtBuildContext ctx = build_context;
    ctx.items = items.data();
    std::vector<AbtNode> sub = abt_build_raw(ctx, 0, e - b, v.depth, 1, 0);
    for (AbtNode& nd : sub) {
      nd.begin += b;
      nd.end += b;
    }
    abt_stitch(raw, v.node, sub);
    raw_ref[v.node] = fresh;
    raw_ref.resize(raw.size(), fresh);
    for (std::uint32_t i = b; i < e; ++i) {
      order[i] = items[i - b].index;
      bounds[i] = items[i - b].box;
      leaf_boxes.set(i, bounds[i]);
    }
    ++stats.subtrees_rebuilt;
    stats.objects_rebuilt += e - b;
  }
  std::vector<std::uint32_t> from;
  abt_relayout(raw, nodes, from, stats);
  ref_split.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const double r = raw_ref[from[k]];
    ref_split[k] = std::isnan(r) ? abt_split_ratio(nodes, static_cast<std::uint32_t>(k)) : r;
  }
}

}  // namespace cullkit::detail
