// cullkit/detail/abt/validate.hpp: the invariant check behind AdaptiveBinaryTree::validate (users
// never name this; tests and debugging call validate()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../abt_params.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/sphere.hpp"
#include "dynamic.hpp"
#include "split.hpp"

namespace cullkit::detail {

inline bool abt_sphere_encloses(const Sphere& s, const Aabb& b) {
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 p = corner(b, c);
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double d = double(p[a]) - double(s.center[a]);
      d2 += d * d;
    }
    if (!(d2 <= double(s.radius) * double(s.radius))) return false;
  }
  return true;
}
/// See AdaptiveBinaryTree::validate.
inline bool abt_validate(const std::vector<AbtNode>& nodes, const std::vector<std::uint32_t>& order,
                         const std::vector<Aabb>& bounds, const AbtDynamic& dyn, std::size_t input_count,
                         const AbtStats& stats, bool refitted, std::uint32_t depth_limit) {
  if (bounds.size() != order.size() || dyn.pos_of.size() != input_count) return false;
  std::vector<std::uint8_t> seen(input_count, 0);
  std::uint32_t holes = 0;
  for (std::uint32_t p = 0; p < order.size(); ++p) {
    const std::uint32_t idx = order[p];
    if (dyn.is_hole(p)) {
      holes += idx == abt_removed_slot;
      continue;
    }
    if (idx >= input_count || seen[idx] || dyn.pos_of[idx] != p) return false;
    seen[idx] = 1;
  }
  if (holes != dyn.dead || order.size() - dyn.dead != stats.objects) return false;
  const std::uint32_t n = dyn.tree_end;
  if (nodes.empty()) return n == 0;
  if (nodes[0].begin != 0 || nodes[0].end != n) return false;
  std::vector<std::uint32_t> depth(nodes.size(), 0);
  std::uint32_t leaves = 0, max_depth = 0;
  std::vector<std::uint8_t> reached(nodes.size(), 0);
  reached[0] = 1;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const AbtNode& node = nodes[k];
    if (!reached[k]) return false;
    if (node.begin >= node.end || node.end > n) return false;
    if (!abt_sphere_encloses(node.sphere, node.bounds)) return false;
    max_depth = std::max(max_depth, depth[k]);
    if (node.is_leaf()) {
      ++leaves;
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        if (!contains(node.bounds, bounds[i])) return false;
      }
      continue;
    }
    const std::size_t l = node.left;
    if (l <= k || l + 1 >= nodes.size() || reached[l] || reached[l + 1]) return false;
    reached[l] = reached[l + 1] = 1;
    depth[l] = depth[l + 1] = depth[k] + 1;
    const AbtNode& a = nodes[l];
    const AbtNode& b = nodes[l + 1];
    if (a.begin != node.begin || a.end != b.begin || b.end != node.end) return false;
    if (!contains(node.bounds, a.bounds) || !contains(node.bounds, b.bounds)) return false;
    if (node.axis > 2) return false;
    if (!refitted) {
      for (std::uint32_t i = a.begin; i < a.end; ++i) {
        if (!(abt_centroid(bounds[i])[node.axis] < node.split)) return false;
      }
      for (std::uint32_t i = b.begin; i < b.end; ++i) {
        if (abt_centroid(bounds[i])[node.axis] < node.split) return false;
      }
    }
  }
  if (max_depth > depth_limit) return false;
  return leaves == stats.leaves && max_depth == stats.depth && nodes.size() == stats.nodes;
}

}  // namespace cullkit::detail
