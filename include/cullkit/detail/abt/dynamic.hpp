// cullkit/detail/abt/dynamic.hpp: the bookkeeping behind AdaptiveBinaryTree::insert, remove and
// update (users never name this).
//
// Why this shape. The tree keeps every node's objects in one contiguous range of `order()`, which
// is what lets a visible subtree be drawn (or copied to the output) as one range. Putting an object
// into the middle of that array, or taking one out, would shift every later range: O(n). So:
//  - a removed object leaves a *hole*: its slot in `order()` holds `abt_removed_slot`, a bit marks
//    the position, and every node on its path counts its holes. Walks copy ranges without holes as
//    before and split the few ranges with holes around them;
//  - an inserted object is appended after the tree's range, in the *pending* part of the arrays,
//    which every cull scans 16 objects at a time with the leaf test (and a pending object that is
//    removed again is replaced by the last pending one: no hole);
//  - an update rewrites the object's box and refits the boxes on its path to the root.
// Once the operations since the last maintenance reach an eighth of the objects, the tree is
// rebuilt from the live objects (holes or pending objects present), or repaired (updates only).
// A rebuild costs O(n log n) every n/8 operations: O(log n) amortized per operation, and the
// pending scan and the holes never cost more than an eighth of the tree's size.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "../../abt_params.hpp"
#include "../../geometry/aabb.hpp"
#include "leaf.hpp"

namespace cullkit::detail {

/// What a removed object's slot of `order()` holds until the next rebuild.
inline constexpr std::uint32_t abt_removed_slot = 0xFFFFFFFFu;
/// `pos_of` of an id that is not held.
inline constexpr std::uint32_t abt_no_position = 0xFFFFFFFFu;

/// Holes, pending objects, ids. Empty vectors until the first insert or remove.
struct AbtDynamic {
  std::vector<std::uint32_t> pos_of;     // id -> position in order(), or abt_no_position
  std::vector<std::uint32_t> dead_bits;  // bit p: the slot at position p is a hole
  std::vector<std::uint32_t> dead_in;    // per node: holes in its range
  std::vector<std::uint32_t> free_ids;   // removed ids, reused last in, first out
  std::uint32_t tree_end = 0;            // positions [0, tree_end) are under the nodes
  std::uint32_t dead = 0;                // holes
  std::uint32_t ops = 0;                 // operations since the last maintenance
  Aabb pending_box = Aabb::empty();      // encloses every pending object (grows until a rebuild)

  /// After a build: no holes, nothing pending, ids = the build's input indices.
  void reset(const std::vector<std::uint32_t>& order, std::size_t id_count) {
    tree_end = static_cast<std::uint32_t>(order.size());
    dead = ops = 0;
    pending_box = Aabb::empty();
    dead_bits.clear();
    dead_in.clear();
    free_ids.clear();
    pos_of.assign(id_count, abt_no_position);
    for (std::size_t p = 0; p < order.size(); ++p) pos_of[order[p]] = static_cast<std::uint32_t>(p);
  }
  /// Ensures the per-position and per-node arrays exist (first remove).
  void prepare_holes(std::size_t positions, std::size_t nodes) {
    if (dead_bits.size() < positions / 32 + 2) dead_bits.resize(positions / 32 + 2, 0u);
    if (dead_in.size() < nodes) dead_in.resize(nodes, 0u);
  }
  [[nodiscard]] bool node_has_holes(std::uint32_t node) const noexcept {
    return dead != 0 && node < dead_in.size() && dead_in[node] != 0;
  }
  [[nodiscard]] bool is_hole(std::uint32_t p) const noexcept {
    return dead != 0 && p < tree_end && ((dead_bits[p >> 5] >> (p & 31u)) & 1u);
  }
  /// Bits of the 16 positions from `base` that are holes.
  [[nodiscard]] std::uint32_t holes16(std::uint32_t base) const noexcept {
    if (dead == 0 || base >= tree_end) return 0;
    const std::uint32_t w = base >> 5, s = base & 31u;
    std::uint64_t bits = dead_bits[w];
    if (w + 1 < dead_bits.size()) bits |= std::uint64_t{dead_bits[w + 1]} << 32;
    return static_cast<std::uint32_t>(bits >> s) & 0xFFFFu;
  }
  /// Calls f(b, e) for the runs of [begin, end) without holes; stops when f returns false.
  /// pre: end <= tree_end. Skips 32 positions per step where there are no holes.
  template <class F>
  bool live_runs(std::uint32_t begin, std::uint32_t end, F&& f) const {
    std::uint32_t run = begin;
    for (std::uint32_t p = begin; p < end && dead != 0;) {
      const std::uint32_t w = p >> 5;
      const std::uint32_t bits = dead_bits[w] & (~std::uint32_t{0} << (p & 31u));
      if (bits == 0) {
        p = (w + 1) << 5;
        continue;
      }
      const std::uint32_t hole = (w << 5) + static_cast<std::uint32_t>(abt_lowest_bit(bits));
      if (hole >= end) break;
      if (hole > run && !f(run, hole)) return false;
      run = p = hole + 1;
    }
    return run >= end || f(run, end);
  }
};

/// Turns tree position p into a hole, counted on its path (`path`, `len` from abt_path_to).
inline void abt_make_hole(AbtDynamic& dyn, std::vector<std::uint32_t>& order, std::size_t nodes, std::uint32_t p,
                          const std::uint32_t* path, std::uint32_t len) {
  dyn.prepare_holes(order.size(), nodes);
  order[p] = abt_removed_slot;
  dyn.dead_bits[p >> 5] |= std::uint32_t{1} << (p & 31u);
  ++dyn.dead;
  for (std::uint32_t i = 0; i < len; ++i) ++dyn.dead_in[path[i]];
}

/// The nodes from the root to the leaf whose range holds position p (p < the root's end), root
/// first. Returns how many.
inline std::uint32_t abt_path_to(const std::vector<AbtNode>& nodes, std::uint32_t p, std::uint32_t* path) noexcept {
  std::uint32_t n = 0, k = 0;
  for (;;) {
    path[n++] = k;
    const AbtNode& node = nodes[k];
    if (node.is_leaf()) return n;
    k = p < nodes[node.left].end ? node.left : node.left + 1;
  }
}

}  // namespace cullkit::detail
