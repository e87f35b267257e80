// cullkit/detail/nci/triangle_bvh.hpp: one 4-wide bounding-volume hierarchy over every triangle of
// the index (binned surface-area heuristic), for the crowded-frame path: a screen tile's rays are
// cast through it together (frame_cast.hpp) where the walk would meet many triangles per pixel.
//
// Nodes hold four child boxes by axis over the lanes (the layout a 4-wide box test loads). Leaves
// are runs of TriangleBvh::tris, the triangles in the tree's own order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "../parallel.hpp"

namespace cullkit::detail::nci {

// A node: its four children's boxes quantized to 8 bits a bound on a per-axis grid (origin, scale),
// by axis over the lanes (the layout a 4-wide box test loads), and their codes; 64 bytes, one cache
// line. The bounds read back (bound()) contain the children's boxes whatever the rounding of the
// read (see quantize).
struct alignas(64) TriangleBvhNode {
  float origin[3];
  float scale[3];
  std::uint8_t qlo[3][4];
  std::uint8_t qhi[3][4];
  std::uint32_t child[4];

  static constexpr std::uint32_t empty = 0xFFFFFFFFu;
  static constexpr std::uint32_t leaf_bit = 0x80000000u;
  // A leaf's code is leaf_bit | first << 3 | (count - 1), `first` its first entry in tris.
  static constexpr int leaf_max = 8;
  [[nodiscard]] static bool is_leaf(std::uint32_t code) noexcept { return (code & leaf_bit) != 0; }
  [[nodiscard]] static std::uint32_t leaf_first(std::uint32_t code) noexcept { return (code & ~leaf_bit) >> 3; }
  [[nodiscard]] static std::uint32_t leaf_count(std::uint32_t code) noexcept { return (code & 7u) + 1u; }
  [[nodiscard]] static std::uint32_t leaf(std::uint32_t first, std::uint32_t count) noexcept {
    return leaf_bit | first << 3 | (count - 1u);
  }

  // Bound q of axis a as the cast reads it.
  [[nodiscard]] float bound(int a, std::uint8_t q) const noexcept { return origin[a] + static_cast<float>(q) * scale[a]; }

  // Sets the boxes of children 0..count-1 (finite, lo <= hi); the others are empty. Each bound is
  // moved outward to a grid step at least `margin` beyond the box, margin = 2^-20 of the largest
  // coordinate magnitude of the node: origin + q * scale, rounded once or twice (fused or not),
  // lies within about 2^-22 of that magnitude of its exact value, so the bound read back still
  // contains the box.
  void quantize(const float lo[3][4], const float hi[3][4], int count) noexcept {
    for (int a = 0; a < 3; ++a) {
      double ulo = std::numeric_limits<double>::infinity(), uhi = -ulo;
      for (int j = 0; j < count; ++j) {
        ulo = std::min(ulo, double(lo[a][j]));
        uhi = std::max(uhi, double(hi[a][j]));
      }
      if (count == 0) ulo = uhi = 0.0;
      const double margin = std::max(std::fabs(ulo), std::fabs(uhi)) * 0x1p-20;
      const double half_max = 0.5 * double(std::numeric_limits<float>::max());
      if (!(ulo - margin >= -half_max && uhi + margin <= half_max)) {
        // Too near float's limits for the grid's products: the whole axis (bound 0 reads -max,
        // bound 255 +inf, fused or not), every child taking both ends.
        origin[a] = -std::numeric_limits<float>::max();
        scale[a] = std::numeric_limits<float>::max();
        for (int j = 0; j < 4; ++j) {
          qlo[a][j] = 0;
          qhi[a][j] = 255;
        }
        continue;
      }
      float o = static_cast<float>(ulo - margin);
      if (double(o) > ulo - margin) o = std::nextafter(o, -std::numeric_limits<float>::infinity());
      float sc = static_cast<float>((uhi + margin - double(o)) / 255.0);
      for (int guard = 0; guard < 64 && double(o) + 255.0 * double(sc) < uhi + margin; ++guard)
        sc = std::nextafter(sc, std::numeric_limits<float>::infinity());
      origin[a] = o;
      scale[a] = sc;
      const auto at = [&](int q) { return double(o) + double(q) * double(sc); };
      for (int j = 0; j < 4; ++j) {
        if (j >= count) {
          qlo[a][j] = qhi[a][j] = 0;
          continue;
        }
        const double want_lo = double(lo[a][j]) - margin, want_hi = double(hi[a][j]) + margin;
        int ql = sc > 0.0f ? static_cast<int>(std::clamp(std::floor((want_lo - double(o)) / double(sc)), 0.0, 255.0)) : 0;
        while (ql > 0 && at(ql) > want_lo) --ql;
        int qh = sc > 0.0f ? static_cast<int>(std::clamp(std::ceil((want_hi - double(o)) / double(sc)), 0.0, 255.0)) : 255;
        while (qh < 255 && at(qh) < want_hi) ++qh;
        qlo[a][j] = static_cast<std::uint8_t>(ql);
        qhi[a][j] = static_cast<std::uint8_t>(qh);
      }
    }
    for (int j = count; j < 4; ++j) child[j] = empty;
  }
};

struct TriangleBvh {
  std::vector<TriangleBvhNode> nodes;
  std::vector<std::uint32_t> tris;  // the triangles, leaf after leaf
  std::uint32_t root = TriangleBvhNode::empty;
  float root_lo[3] = {0, 0, 0}, root_hi[3] = {0, 0, 0};
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return nodes.capacity() * sizeof(TriangleBvhNode) + tris.capacity() * sizeof(std::uint32_t);
  }
};

// The build's cost of a traversal step against one triangle test (TriangleBvhBuilder::traversal_cost)
// for the index's hierarchy. On the 10.1M city seen whole (nearest hits only, one thread) 1, 2 and 3
// cast within 3 % of each other; 2 and 3 take half the nodes of 1 (18.0 and 17.2 bytes per
// triangle against 29.6, with the former 128-byte nodes).
inline constexpr float frame_traversal_cost = 3.0f;

// A triangle's box, handed to the builder by triangle id.
struct TriangleBvhItem {
  float lo[3], hi[3];
};

// Binned SAH build (16 bins on each axis) of a 4-wide tree: each node splits its largest child
// until it has four or none can be split. Leaves hold at most leaf_max triangles and are cut where
// the heuristic says a leaf costs less than a split. The two top levels' subtrees are built on
// `threads` threads and spliced in subtree order, so the tree does not depend on the thread count.
class TriangleBvhBuilder {
 public:
  TriangleBvhBuilder(const std::vector<TriangleBvhItem>& items, unsigned threads, const TaskRunner& runner)
      : items_(items), threads_(threads), runner_(runner) {}

  // The cost of a traversal step against one triangle test, for the leaf / split choice.
  float traversal_cost = 1.0f;

  TriangleBvh build() {
    TriangleBvh out;
    const std::size_t n = items_.size();
    // The passes over a range read its boxes in order: they travel with their ids.
    refs_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) {
        refs_[i].lo[a] = items_[i].lo[a];
        refs_[i].hi[a] = items_[i].hi[a];
      }
      refs_[i].id = static_cast<std::uint32_t>(i);
    }
    if (n == 0) return out;
    const Range all = bounds_of(0, n);
    for (int a = 0; a < 3; ++a) {
      out.root_lo[a] = all.lo[a];
      out.root_hi[a] = all.hi[a];
    }
    // The top: split the whole set down to at most 16 ranges, serially; then each range's subtree
    // on its own thread, spliced below the top in range order.
    std::vector<Range> tops;
    split_into(all, 16, tops);
    std::vector<std::vector<TriangleBvhNode>> sub(tops.size());
    std::vector<std::uint32_t> sub_root(tops.size());
    struct Job {
      TriangleBvhBuilder* self;
      std::vector<Range>* tops;
      std::vector<std::vector<TriangleBvhNode>>* sub;
      std::vector<std::uint32_t>* sub_root;
      std::atomic<std::size_t> next{0};  // ranges are taken in turn: their sizes differ
    } job{this, &tops, &sub, &sub_root};
    const std::size_t workers = std::max<std::size_t>(1, std::min<std::size_t>(threads_, tops.size()));
    detail::run_tasks(runner_, workers, [](void* j, std::size_t) {
      Job& b = *static_cast<Job*>(j);
      for (std::size_t t = b.next++; t < b.tops->size(); t = b.next++) (*b.sub_root)[t] = b.self->make((*b.tops)[t], (*b.sub)[t]);
    }, &job);
    out.tris.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.tris[i] = refs_[i].id;
    std::vector<Ref>().swap(refs_);
    // Top nodes: the whole set cut into `tops` by the same rule, rebuilt over the ranges' roots.
    std::vector<TriangleBvhNode>& nodes = out.nodes;
    std::size_t next = 0;
    out.root = make_top(all, tops, sub, sub_root, nodes, next);
    return out;
  }

 private:
  struct Range {
    std::size_t b, e;
    float lo[3], hi[3];
  };
  static constexpr int bins = 16;
  struct Ref {
    float lo[3], hi[3];
    std::uint32_t id;
  };
  const std::vector<TriangleBvhItem>& items_;
  std::vector<Ref> refs_;  // the items in the tree's order as it is built
  unsigned threads_;
  TaskRunner runner_;

  static float area(const float lo[3], const float hi[3]) noexcept {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x < 0.0f ? 0.0f : x * y + y * z + z * x;
  }

  Range bounds_of(std::size_t b, std::size_t e) const noexcept {
    Range r{b, e, {0, 0, 0}, {0, 0, 0}};
    for (int a = 0; a < 3; ++a) {
      r.lo[a] = std::numeric_limits<float>::infinity();
      r.hi[a] = -std::numeric_limits<float>::infinity();
    }
    for (std::size_t i = b; i < e; ++i) {
      const Ref& it = refs_[i];
      for (int a = 0; a < 3; ++a) {
        r.lo[a] = std::min(r.lo[a], it.lo[a]);
        r.hi[a] = std::max(r.hi[a], it.hi[a]);
      }
    }
    return r;
  }

  // Splits r in two by the binned heuristic (the median of the widest centroid axis when the
  // centroids coincide or every plane leaves a side empty); false when r is a leaf.
  bool split(const Range& r, Range& left, Range& right, bool median = false) {
    const std::size_t n = r.e - r.b;
    if (n <= 1) return false;
    if (median && n > static_cast<std::size_t>(TriangleBvhNode::leaf_max)) return median_split(r, left, right);
    float cl[3], ch[3];
    for (int a = 0; a < 3; ++a) {
      cl[a] = std::numeric_limits<float>::infinity();
      ch[a] = -cl[a];
    }
    for (std::size_t i = r.b; i < r.e; ++i) {
      const Ref& it = refs_[i];
      for (int a = 0; a < 3; ++a) {
        const float c = it.lo[a] + it.hi[a];
        cl[a] = std::min(cl[a], c);
        ch[a] = std::max(ch[a], c);
      }
    }
    struct Bin {
      float lo[3], hi[3];
      std::size_t n;
    };
    Bin bin[3][bins];
    float scale[3];
    for (int a = 0; a < 3; ++a) {
      scale[a] = ch[a] > cl[a] ? float(bins) * 0.99999f / (ch[a] - cl[a]) : 0.0f;
      for (int k = 0; k < bins; ++k) {
        for (int j = 0; j < 3; ++j) {
          bin[a][k].lo[j] = std::numeric_limits<float>::infinity();
          bin[a][k].hi[j] = -std::numeric_limits<float>::infinity();
        }
        bin[a][k].n = 0;
      }
    }
    for (std::size_t i = r.b; i < r.e; ++i) {
      const Ref& it = refs_[i];
      for (int a = 0; a < 3; ++a) {
        const int k = std::min(bins - 1, static_cast<int>((it.lo[a] + it.hi[a] - cl[a]) * scale[a]));
        Bin& bb = bin[a][k];
        for (int j = 0; j < 3; ++j) {
          bb.lo[j] = std::min(bb.lo[j], it.lo[j]);
          bb.hi[j] = std::max(bb.hi[j], it.hi[j]);
        }
        ++bb.n;
      }
    }
    float best = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_plane = 0;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      float rarea[bins];
      std::size_t rn[bins];
      float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                     std::numeric_limits<float>::infinity()};
      float hi[3] = {-lo[0], -lo[1], -lo[2]};
      std::size_t cnt = 0;
      for (int k = bins - 1; k > 0; --k) {
        for (int j = 0; j < 3; ++j) {
          lo[j] = std::min(lo[j], bin[a][k].lo[j]);
          hi[j] = std::max(hi[j], bin[a][k].hi[j]);
        }
        cnt += bin[a][k].n;
        rarea[k] = area(lo, hi);
        rn[k] = cnt;
      }
      for (int j = 0; j < 3; ++j) {
        lo[j] = std::numeric_limits<float>::infinity();
        hi[j] = -std::numeric_limits<float>::infinity();
      }
      cnt = 0;
      for (int k = 0; k + 1 < bins; ++k) {
        for (int j = 0; j < 3; ++j) {
          lo[j] = std::min(lo[j], bin[a][k].lo[j]);
          hi[j] = std::max(hi[j], bin[a][k].hi[j]);
        }
        cnt += bin[a][k].n;
        if (cnt == 0 || rn[k + 1] == 0) continue;
        const float cost = area(lo, hi) * float(cnt) + rarea[k + 1] * float(rn[k + 1]);
        if (cost < best) {
          best = cost;
          best_axis = a;
          best_plane = k + 1;
        }
      }
    }
    if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max) && best_axis >= 0 &&
        best + area(r.lo, r.hi) * traversal_cost >= area(r.lo, r.hi) * float(n))
      return false;  // a leaf is cheaper than a split
    if (best_axis < 0) {
      if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max)) return false;
      return median_split(r, left, right);
    }
    std::size_t mid;
    {
      const int a = best_axis;
      const float c0 = cl[a], s = scale[a];
      Ref* const base = refs_.data();
      Ref* m = std::partition(base + r.b, base + r.e, [&](const Ref& it) {
        return std::min(bins - 1, static_cast<int>((it.lo[a] + it.hi[a] - c0) * s)) < best_plane;
      });
      mid = static_cast<std::size_t>(m - base);
    }
    // The sides' boxes are the unions of their bins' (each triangle lies in one bin of the axis),
    // unless the partition disagreed with the binning (then measured again).
    std::size_t left_count = 0;
    left = Range{r.b, mid, {0, 0, 0}, {0, 0, 0}};
    right = Range{mid, r.e, {0, 0, 0}, {0, 0, 0}};
    for (int j = 0; j < 3; ++j) {
      left.lo[j] = right.lo[j] = std::numeric_limits<float>::infinity();
      left.hi[j] = right.hi[j] = -std::numeric_limits<float>::infinity();
    }
    for (int k = 0; k < bins; ++k) {
      const Bin& bb = bin[best_axis][k];
      Range& side = k < best_plane ? left : right;
      if (k < best_plane) left_count += bb.n;
      for (int j = 0; j < 3; ++j) {
        side.lo[j] = std::min(side.lo[j], bb.lo[j]);
        side.hi[j] = std::max(side.hi[j], bb.hi[j]);
      }
    }
    if (mid - r.b != left_count || mid == r.b || mid == r.e) {
      if (mid == r.b || mid == r.e) mid = r.b + n / 2;
      left = bounds_of(r.b, mid);
      right = bounds_of(mid, r.e);
    }
    return true;
  }

  // Cuts r in two halves at the median of its centroids along their widest axis (ties by id).
  bool median_split(const Range& r, Range& left, Range& right) {
    float cl[3], ch[3];
    for (int a = 0; a < 3; ++a) {
      cl[a] = std::numeric_limits<float>::infinity();
      ch[a] = -cl[a];
    }
    for (std::size_t i = r.b; i < r.e; ++i)
      for (int a = 0; a < 3; ++a) {
        const float c = refs_[i].lo[a] + refs_[i].hi[a];
        cl[a] = std::min(cl[a], c);
        ch[a] = std::max(ch[a], c);
      }
    int a = 0;
    for (int j = 1; j < 3; ++j)
      if (ch[j] - cl[j] > ch[a] - cl[a]) a = j;
    const std::size_t mid = r.b + (r.e - r.b) / 2;
    Ref* const base = refs_.data();
    std::nth_element(base + r.b, base + mid, base + r.e, [&](const Ref& x, const Ref& y) {
      const float cx = x.lo[a] + x.hi[a], cy = y.lo[a] + y.hi[a];
      return cx < cy || (cx == cy && x.id < y.id);
    });
    left = bounds_of(r.b, mid);
    right = bounds_of(mid, r.e);
    return true;
  }

  // Cuts r into at most `most` ranges, splitting the largest-area splittable range first.
  void split_into(const Range& r, std::size_t most, std::vector<Range>& out, bool median = false) {
    out.assign(1, r);
    std::vector<bool> done(1, false);
    while (out.size() < most) {
      int pick = -1;
      float big = -1.0f;
      for (std::size_t k = 0; k < out.size(); ++k)
        if (!done[k] && out[k].e - out[k].b > static_cast<std::size_t>(TriangleBvhNode::leaf_max) &&
            area(out[k].lo, out[k].hi) > big) {
          big = area(out[k].lo, out[k].hi);
          pick = static_cast<int>(k);
        }
      if (pick < 0) {  // small ranges: split them too unless the heuristic keeps them whole
        for (std::size_t k = 0; k < out.size() && pick < 0; ++k)
          if (!done[k] && out[k].e - out[k].b > 1) pick = static_cast<int>(k);
        if (pick < 0) break;
      }
      Range a, b;
      if (!split(out[static_cast<std::size_t>(pick)], a, b, median)) {
        done[static_cast<std::size_t>(pick)] = true;
        continue;
      }
      out[static_cast<std::size_t>(pick)] = a;
      done[static_cast<std::size_t>(pick)] = false;
      out.insert(out.begin() + pick + 1, b);
      done.insert(done.begin() + pick + 1, false);
    }
    std::sort(out.begin(), out.end(), [](const Range& x, const Range& y) { return x.b < y.b; });
  }

  std::uint32_t leaf_or_node(const Range& r, std::vector<TriangleBvhNode>& nodes, int depth) {
    const std::size_t n = r.e - r.b;
    if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max)) {
      Range a, b;
      if (!split(r, a, b)) return TriangleBvhNode::leaf(static_cast<std::uint32_t>(r.b), static_cast<std::uint32_t>(n));
    }
    return make(r, nodes, depth);
  }

  // A subtree over r (more than a leaf), its nodes appended to `nodes`; returns its root index.
  // Below depth_limit nodes split at medians (a balanced bound on the depth, which the cast's
  // stack relies on).
  static constexpr int depth_limit = 48;
  std::uint32_t make(const Range& r, std::vector<TriangleBvhNode>& nodes, int depth = 2) {
    std::vector<Range> kids;
    split_into(r, 4, kids, depth >= depth_limit);
    if (kids.size() == 1) {  // cannot be split: one leaf per leaf_max run
      kids.clear();
      const std::size_t n = r.e - r.b, step = std::max<std::size_t>((n + 3) / 4, 1);
      for (std::size_t b = r.b; b < r.e; b += step) kids.push_back(bounds_of(b, std::min(r.e, b + step)));
    }
    const std::size_t index = nodes.size();
    nodes.emplace_back();
    float lo[3][4], hi[3][4];
    std::uint32_t codes[4];
    for (std::size_t j = 0; j < kids.size(); ++j) {
      const Range& k = kids[j];
      codes[j] = leaf_or_node(k, nodes, depth + 1);
      for (int a = 0; a < 3; ++a) {
        lo[a][j] = k.lo[a];
        hi[a][j] = k.hi[a];
      }
    }
    TriangleBvhNode& node = nodes[index];
    node.quantize(lo, hi, static_cast<int>(kids.size()));
    for (std::size_t j = 0; j < kids.size(); ++j) node.child[j] = codes[j];
    return static_cast<std::uint32_t>(index);
  }

  // The top of the tree over the ranges `tops` (in order), whose subtrees are built: the same cut
  // of r into four as make() does, down to the ranges.
  std::uint32_t make_top(const Range& r, const std::vector<Range>& tops, std::vector<std::vector<TriangleBvhNode>>& sub,
                         const std::vector<std::uint32_t>& sub_root, std::vector<TriangleBvhNode>& nodes, std::size_t& /*next*/) {
    // Ranges as the leaves of a top built by equal groups: four groups of up to four tops.
    std::vector<std::uint32_t> codes(tops.size());
    // Splice the subtrees first (their node indices shift by their offset).
    std::vector<std::size_t> offset(tops.size());
    const std::size_t top_nodes = 1 + (tops.size() > 4 ? (tops.size() + 3) / 4 : 0);
    std::size_t at = top_nodes;
    for (std::size_t t = 0; t < tops.size(); ++t) {
      offset[t] = at;
      at += sub[t].size();
    }
    nodes.resize(at);
    for (std::size_t t = 0; t < tops.size(); ++t) {
      std::size_t put = offset[t];
      for (TriangleBvhNode nd : sub[t]) {
        for (int j = 0; j < 4; ++j)
          if (nd.child[j] != TriangleBvhNode::empty && !TriangleBvhNode::is_leaf(nd.child[j]))
            nd.child[j] += static_cast<std::uint32_t>(offset[t]);
        nodes[put++] = nd;
      }
      codes[t] = TriangleBvhNode::is_leaf(sub_root[t]) ? sub_root[t] : sub_root[t] + static_cast<std::uint32_t>(offset[t]);
      std::vector<TriangleBvhNode>().swap(sub[t]);
    }
    auto fill = [&](TriangleBvhNode& nd, const std::uint32_t* c, const Range* rg, std::size_t count) {
      float lo[3][4], hi[3][4];
      for (std::size_t j = 0; j < count; ++j)
        for (int a = 0; a < 3; ++a) {
          lo[a][j] = rg[j].lo[a];
          hi[a][j] = rg[j].hi[a];
        }
      nd.quantize(lo, hi, static_cast<int>(count));
      for (std::size_t j = 0; j < count; ++j) nd.child[j] = c[j];
    };
    if (tops.size() <= 4) {
      fill(nodes[0], codes.data(), tops.data(), tops.size());
      return 0;
    }
    std::vector<Range> groups;
    std::vector<std::uint32_t> gcodes;
    for (std::size_t g = 0; g * 4 < tops.size(); ++g) {
      const std::size_t first = g * 4, count = std::min<std::size_t>(4, tops.size() - first);
      fill(nodes[1 + g], codes.data() + first, tops.data() + first, count);
      Range u = tops[first];
      for (std::size_t k = 1; k < count; ++k)
        for (int a = 0; a < 3; ++a) {
          u.lo[a] = std::min(u.lo[a], tops[first + k].lo[a]);
          u.hi[a] = std::max(u.hi[a], tops[first + k].hi[a]);
        }
      groups.push_back(u);
      gcodes.push_back(static_cast<std::uint32_t>(1 + g));
    }
    (void)r;
    fill(nodes[0], gcodes.data(), groups.data(), groups.size());
    return 0;
  }
};

}  // namespace cullkit::detail::nci
