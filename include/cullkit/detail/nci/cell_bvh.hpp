// cullkit/detail/nci/cell_bvh.hpp: the compact 4-wide bounding-volume hierarchy kept over the
// triangles of a crowded (class, cell) list, and its builder. The select path that walks it is in
// packet_cast.hpp; which (class, cell) lists get one is decided in build.hpp.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace cullkit::detail::nci {

// One node: the boxes of up to four children, by axis over the four lanes (the layout a 4-wide
// box test loads), and what each child is: another node, a leaf (a run of the hierarchy's
// triangle list) or nothing (its box is empty: lo = +inf, hi = -inf).
struct CellBvhNode {
  float lo[3][4];
  float hi[3][4];
  std::uint32_t child[4];

  static constexpr std::uint32_t empty = 0xFFFFFFFFu;
  static constexpr std::uint32_t leaf_bit = 0x80000000u;
  // Leaves hold at most leaf_max triangles; a leaf's code is leaf_bit | first << 3 | (count - 1).
  static constexpr int leaf_max = 4;
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

// A triangle handed to the builder: its box, its centroid (twice: min + max per axis) and the id
// the leaves store.
struct CellBvhItem {
  float lo[3], hi[3];
  float centre2[3];
  std::uint32_t id;
};

// Builds one hierarchy over `items` (reordered), appending its nodes to `nodes` and its leaf
// triangles to `ids`; returns the root's code (a node index, or a leaf code when the list is short),
// positions being those in the two vectors. Splits at the median of the centroids along their
// widest axis, twice per node: four children of equal size, which keeps the depth at log4 of the
// list and the build at n log n.
class CellBvhBuilder {
 public:
  CellBvhBuilder(std::vector<CellBvhNode>& nodes, std::vector<std::uint32_t>& ids) : nodes_(nodes), ids_(ids) {}

  std::uint32_t build(CellBvhItem* items, std::size_t count) { return make(items, 0, count); }

 private:
  std::vector<CellBvhNode>& nodes_;
  std::vector<std::uint32_t>& ids_;

  std::uint32_t make(CellBvhItem* items, std::size_t b, std::size_t e) {
    if (e - b <= static_cast<std::size_t>(CellBvhNode::leaf_max)) {
      const std::uint32_t first = static_cast<std::uint32_t>(ids_.size());
      for (std::size_t i = b; i < e; ++i) ids_.push_back(items[i].id);
      return CellBvhNode::leaf(first, static_cast<std::uint32_t>(e - b));
    }
    int parts = 0;
    const std::size_t mid = split(items, b, e);
    std::size_t ranges[4][2];
    for (const auto& half : {std::pair<std::size_t, std::size_t>{b, mid}, std::pair<std::size_t, std::size_t>{mid, e}}) {
      if (half.second - half.first > static_cast<std::size_t>(CellBvhNode::leaf_max)) {
        const std::size_t q = split(items, half.first, half.second);
        ranges[parts][0] = half.first;
        ranges[parts++][1] = q;
        ranges[parts][0] = q;
        ranges[parts++][1] = half.second;
      } else {
        ranges[parts][0] = half.first;
        ranges[parts++][1] = half.second;
      }
    }
    const std::size_t index = nodes_.size();
    nodes_.emplace_back();
    for (int j = 0; j < 4; ++j) {
      std::uint32_t code = CellBvhNode::empty;
      float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
      float hi[3] = {-lo[0], -lo[1], -lo[2]};
      if (j < parts) {
        for (std::size_t i = ranges[j][0]; i < ranges[j][1]; ++i)
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], items[i].lo[a]);
            hi[a] = std::max(hi[a], items[i].hi[a]);
          }
        code = make(items, ranges[j][0], ranges[j][1]);
      }
      CellBvhNode& node = nodes_[index];  // the recursion may have moved the array
      for (int a = 0; a < 3; ++a) {
        node.lo[a][j] = lo[a];
        node.hi[a][j] = hi[a];
      }
      node.child[j] = code;
    }
    return static_cast<std::uint32_t>(index);
  }

  // Partitions items[b, e) at the median of the centroids along their widest axis (ties by id, so
  // the hierarchy does not depend on the standard library's partition order); returns the cut.
  static std::size_t split(CellBvhItem* items, std::size_t b, std::size_t e) {
    float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                   std::numeric_limits<float>::infinity()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (std::size_t i = b; i < e; ++i)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], items[i].centre2[a]);
        hi[a] = std::max(hi[a], items[i].centre2[a]);
      }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const std::size_t mid = b + (e - b) / 2;
    std::nth_element(items + b, items + mid, items + e, [axis](const CellBvhItem& p, const CellBvhItem& q) {
      return p.centre2[axis] != q.centre2[axis] ? p.centre2[axis] < q.centre2[axis] : p.id < q.id;
    });
    return mid;
  }
};

}  // namespace cullkit::detail::nci
