// cullkit/detail/nci/cell_bvh.hpp: the compact 4-wide bounding-volume hierarchy kept over the
// entries of a crowded (class, cell) list, and its builder. The select path that walks it is in
// packet_cast.hpp; which lists get one is decided in build.hpp.
//
// The hierarchy is built on the order the list already has (ascending internal ids, which the
// build numbered in Morton order within the cell where each triangle first appears): every node
// holds a run of consecutive entries, cut in four equal runs per level. Leaves are therefore runs
// of the cell's own entry list (no second list of triangles), and the triangles a leaf names are
// mostly consecutive in memory, as on the walk.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace cullkit::detail::nci {

// One node: the boxes of up to four children, by axis over the four lanes (the layout a 4-wide
// box test loads), and what each child is: another node, a leaf (a run of cell entries) or
// nothing (its box is empty: lo = +inf, hi = -inf).
struct CellBvhNode {
  float lo[3][4];
  float hi[3][4];
  std::uint32_t child[4];

  static constexpr std::uint32_t empty = 0xFFFFFFFFu;
  static constexpr std::uint32_t leaf_bit = 0x80000000u;
  // Leaves hold at most leaf_max entries; a leaf's code is leaf_bit | first << 3 | (count - 1),
  // `first` being the leaf's first entry in the index's entry array.
  static constexpr int leaf_max = 8;
  // Runs start below 2^28 - 8 (so no leaf code equals `empty`); a list that would pass it gets
  // no hierarchy.
  static constexpr std::uint32_t first_limit = (1u << 28) - 8u;

  [[nodiscard]] static bool is_leaf(std::uint32_t code) noexcept { return (code & leaf_bit) != 0; }
  [[nodiscard]] static std::uint32_t leaf_first(std::uint32_t code) noexcept { return (code & ~leaf_bit) >> 3; }
  [[nodiscard]] static std::uint32_t leaf_count(std::uint32_t code) noexcept { return (code & 7u) + 1u; }
  [[nodiscard]] static std::uint32_t leaf(std::uint32_t first, std::uint32_t count) noexcept {
    return leaf_bit | first << 3 | (count - 1u);
  }
  // Child j's box as (min xyz, max xyz).
  void box(int j, float out[6]) const noexcept {
    for (int a = 0; a < 3; ++a) {
      out[a] = lo[a][j];
      out[3 + a] = hi[a][j];
    }
  }
};

// The box of one entry (its triangle's corners), handed to the builder in the list's order.
struct CellBvhItem {
  float lo[3], hi[3];
};

// Builds one hierarchy over the list whose entries start at `first_entry` and whose boxes are
// `items` (in list order), appending its nodes to `nodes`; returns the root's code (a node index,
// or a leaf code when the list is short).
class CellBvhBuilder {
 public:
  CellBvhBuilder(std::vector<CellBvhNode>& nodes, const CellBvhItem* items, std::uint32_t first_entry)
      : nodes_(nodes), items_(items), first_entry_(first_entry) {}

  std::uint32_t build(std::size_t count) { return make(0, count); }

 private:
  std::vector<CellBvhNode>& nodes_;
  const CellBvhItem* items_;
  std::uint32_t first_entry_;

  std::uint32_t make(std::size_t b, std::size_t e) {
    if (e - b <= static_cast<std::size_t>(CellBvhNode::leaf_max))
      return CellBvhNode::leaf(first_entry_ + static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(e - b));
    const std::size_t index = nodes_.size();
    nodes_.emplace_back();
    for (int j = 0; j < 4; ++j) {
      const std::size_t cb = b + (e - b) * static_cast<std::size_t>(j) / 4, ce = b + (e - b) * static_cast<std::size_t>(j + 1) / 4;
      float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
      float hi[3] = {-lo[0], -lo[1], -lo[2]};
      for (std::size_t i = cb; i < ce; ++i)
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], items_[i].lo[a]);
          hi[a] = std::max(hi[a], items_[i].hi[a]);
        }
      const std::uint32_t code = cb < ce ? make(cb, ce) : CellBvhNode::empty;
      CellBvhNode& node = nodes_[index];  // the recursion may have moved the array
      for (int a = 0; a < 3; ++a) {
        node.lo[a][j] = lo[a];
        node.hi[a][j] = hi[a];
      }
      node.child[j] = code;
    }
    return static_cast<std::uint32_t>(index);
  }
};

}  // namespace cullkit::detail::nci
