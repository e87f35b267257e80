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

#include "../bits.hpp"
#include "../parallel.hpp"
#include "../../config.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

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
      // A flat axis at zero (margin 0): +0 whichever zero the children's bounds kept, since the
      // binning takes its minima in an order that may keep either.
      if (o == 0.0f) o = 0.0f;
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
// the heuristic says a leaf costs less than a split. The top is cut into up to 16 ranges (the bins
// of its long ranges filled, their sides marked and measured on `threads` threads), whose subtrees
// are built on `threads` threads and spliced in range order, so the tree does not depend on the
// thread count. Each range carries
// the box of its centroids, measured by the partition that made it, and a split weighs only the
// planes after occupied bins (the others cut the same sides at the same cost): the tree is the
// plain binned build's, bit for bit, with fewer passes over the ranges.
class TriangleBvhBuilder {
 public:
  TriangleBvhBuilder(const std::vector<TriangleBvhItem>& items, unsigned threads, const TaskRunner& runner)
      : items_(items), threads_(threads), runner_(runner) {}

  // The cost of a traversal step against one triangle test, for the leaf / split choice.
  float traversal_cost = 1.0f;

  TriangleBvh build() {
    TriangleBvh out;
    const std::size_t n = items_.size();
    // The passes over a range read its boxes in order: they travel with their ids. Filled on
    // every thread for large sets (the first touch of the array's pages is a good part of it).
    refs_.resize(n);
    if (n == 0) return out;
    {
      const std::size_t slices = threads_ < 2 || n < parallel_bins ? 1 : std::min<std::size_t>(threads_, 64);
      struct Job {
        TriangleBvhBuilder* self;
        std::size_t n, slices;
      } job{this, n, slices};
      detail::run_tasks(runner_, slices, [](void* j, std::size_t t) {
        const Job& jb = *static_cast<const Job*>(j);
        jb.self->copy_items(jb.n * t / jb.slices, jb.n * (t + 1) / jb.slices);
      }, &job);
    }
    const Range all = bounds_of(0, n);
    for (int a = 0; a < 3; ++a) {
      out.root_lo[a] = all.lo[a];
      out.root_hi[a] = all.hi[a];
    }
    // The top: split the whole set down to at most 16 ranges (the large ranges' bins filled on
    // all threads); then each range's subtree on its own thread, spliced below the top in range order.
    Range cut[16];
    top_ = true;
    const std::vector<Range> tops(cut, cut + split_into(all, 16, cut));
    top_ = false;
    std::vector<std::vector<TriangleBvhNode>> sub(tops.size());
    std::vector<std::uint32_t> sub_root(tops.size());
    struct Job {
      TriangleBvhBuilder* self;
      const std::vector<Range>* tops;
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
  // A run of refs_ with its box and the box of its centroids (doubled: lo + hi per axis), which
  // the split that made it measured while partitioning, so no split reads its range only for them.
  struct Range {
    std::size_t b, e;
    float lo[3], hi[3];
    float cl[3], ch[3];
    bool whole;  // split() kept it whole (a leaf): not asked again
  };
  static constexpr int bins = 16;
  // A triangle's box with its id between the two corners: 32 bytes, each corner and the id or a
  // zero in four lanes (the id's lane masked off before any arithmetic).
  struct alignas(16) Ref {
    float lo[3];
    std::uint32_t id;
    float hi[3];
    float zero;
  };
  // A bin of the heuristic: the union of its triangles' boxes (the fourth lane unused) and their count.
  struct alignas(16) Bin {
    float lo[4], hi[4];
    std::size_t n;
  };
  // While the top is cut (before the subtrees' tasks, which never dispatch tasks of their own),
  // ranges at least this long fill their bins (slices merged in slice order) and mark and measure
  // their sides on all threads; so are the refs filled from the items.
  static constexpr std::size_t parallel_bins = std::size_t{1} << 17;
  // Ranges at least this long fill two sets of bins (fill_bins).
  static constexpr std::size_t two_sets = 64;
  bool top_ = false;
  const std::vector<TriangleBvhItem>& items_;
  std::vector<Ref> refs_;  // the items in the tree's order as it is built
  unsigned threads_;
  TaskRunner runner_;

  // refs_[b, e) from items_[b, e).
  void copy_items(std::size_t b, std::size_t e) noexcept {
    for (std::size_t i = b; i < e; ++i) {
      Ref& ref = refs_[i];
      for (int a = 0; a < 3; ++a) {
        ref.lo[a] = items_[i].lo[a];
        ref.hi[a] = items_[i].hi[a];
      }
      ref.id = static_cast<std::uint32_t>(i);
      ref.zero = 0.0f;
    }
  }

  static float area(const float lo[3], const float hi[3]) noexcept {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x < 0.0f ? 0.0f : x * y + y * z + z * x;
  }

  static void empty_box(float lo[], float hi[], int lanes) noexcept {
    for (int j = 0; j < lanes; ++j) {
      lo[j] = std::numeric_limits<float>::infinity();
      hi[j] = -std::numeric_limits<float>::infinity();
    }
  }

  Range bounds_of(std::size_t b, std::size_t e) const noexcept {
    Range r{b, e, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, false};
    empty_box(r.lo, r.hi, 3);
    empty_box(r.cl, r.ch, 3);
    for (std::size_t i = b; i < e; ++i) {
      const Ref& it = refs_[i];
      for (int a = 0; a < 3; ++a) {
        r.lo[a] = std::min(r.lo[a], it.lo[a]);
        r.hi[a] = std::max(r.hi[a], it.hi[a]);
        const float c = it.lo[a] + it.hi[a];
        r.cl[a] = std::min(r.cl[a], c);
        r.ch[a] = std::max(r.ch[a], c);
      }
    }
    return r;
  }

  // Adds refs_[b, e) to the bins, `scale` and `cl` mapping a centroid to its bin on each axis.
  // The same float operations as the scalar form (the SSE2 min and max equal std::min and
  // std::max on finite values but for the sign of a zero, which no bound or area reads).
  // Consecutive refs mostly fall in the same bins (a range is spatially sorted by the splits
  // above it), so each update would wait on the one before: long ranges fill two sets of bins,
  // even and odd refs, merged at the end (min, max and counts do not depend on the order).
  void fill_bins(std::size_t b, std::size_t e, const float cl[3], const float scale[3], Bin (&bin)[3][bins]) const noexcept {
#if CULLKIT_HAS_SSE2
    const __m128 keep3 = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    const __m128 c0 = _mm_set_ps(0.0f, cl[2], cl[1], cl[0]), s = _mm_set_ps(0.0f, scale[2], scale[1], scale[0]);
    const __m128i last = _mm_set1_epi32(bins - 1), first = _mm_setzero_si128();
    const auto add = [&](const Ref& ref, Bin (&to)[3][bins]) {
      const __m128 lo = _mm_and_ps(_mm_load_ps(ref.lo), keep3), hi = _mm_load_ps(ref.hi);
      __m128i k = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(_mm_add_ps(lo, hi), c0), s));
      // Clamped to [0, bins - 1] (SSE2 has no 32-bit integer min / max).
      const __m128i over = _mm_cmpgt_epi32(k, last);
      k = _mm_or_si128(_mm_and_si128(over, last), _mm_andnot_si128(over, k));
      k = _mm_and_si128(k, _mm_cmpgt_epi32(k, first));
      alignas(16) std::int32_t kk[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(kk), k);
      for (int a = 0; a < 3; ++a) {
        Bin& bb = to[a][kk[a]];
        _mm_store_ps(bb.lo, _mm_min_ps(_mm_load_ps(bb.lo), lo));
        _mm_store_ps(bb.hi, _mm_max_ps(_mm_load_ps(bb.hi), hi));
        ++bb.n;
      }
    };
#else
    const auto add = [&](const Ref& it, Bin (&to)[3][bins]) {
      for (int a = 0; a < 3; ++a) {
        const int k = std::clamp(static_cast<int>((it.lo[a] + it.hi[a] - cl[a]) * scale[a]), 0, bins - 1);
        Bin& bb = to[a][k];
        for (int j = 0; j < 3; ++j) {
          bb.lo[j] = std::min(bb.lo[j], it.lo[j]);
          bb.hi[j] = std::max(bb.hi[j], it.hi[j]);
        }
        ++bb.n;
      }
    };
#endif
    std::size_t i = b;
    if (e - b >= two_sets) {
      Bin odd[3][bins];
      clear_bins(odd);
      for (; i + 1 < e; i += 2) {
        add(refs_[i], bin);
        add(refs_[i + 1], odd);
      }
      merge_bins(bin, odd);
    }
    for (; i < e; ++i) add(refs_[i], bin);
  }

  // to: the union of to and from, bin by bin.
  static void merge_bins(Bin (&to)[3][bins], const Bin (&from)[3][bins]) noexcept {
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < bins; ++k) {
        for (int j = 0; j < 3; ++j) {
          to[a][k].lo[j] = std::min(to[a][k].lo[j], from[a][k].lo[j]);
          to[a][k].hi[j] = std::max(to[a][k].hi[j], from[a][k].hi[j]);
        }
        to[a][k].n += from[a][k].n;
      }
  }

  // lo, hi: the union of the box and the bin's (in the first three lanes).
  static void grow(float (&lo)[4], float (&hi)[4], const Bin& bin) noexcept {
#if CULLKIT_HAS_SSE2
    _mm_store_ps(lo, _mm_min_ps(_mm_load_ps(lo), _mm_load_ps(bin.lo)));
    _mm_store_ps(hi, _mm_max_ps(_mm_load_ps(hi), _mm_load_ps(bin.hi)));
#else
    for (int j = 0; j < 3; ++j) {
      lo[j] = std::min(lo[j], bin.lo[j]);
      hi[j] = std::max(hi[j], bin.hi[j]);
    }
#endif
  }

  static void clear_bins(Bin (&bin)[3][bins]) noexcept {
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < bins; ++k) {
        empty_box(bin[a][k].lo, bin[a][k].hi, 4);
        bin[a][k].n = 0;
      }
  }

  // The bins of r: on all threads for long ranges (each slice into its own bins, merged in order).
  void bin_range(const Range& r, const float scale[3], Bin (&bin)[3][bins]) const {
    clear_bins(bin);
    const std::size_t n = r.e - r.b;
    if (!top_ || threads_ < 2 || n < parallel_bins) {
      fill_bins(r.b, r.e, r.cl, scale, bin);
      return;
    }
    struct Slice {
      Bin bin[3][bins];
    };
    const std::size_t slices = std::min<std::size_t>(threads_, 64);
    std::vector<Slice> part(slices);
    for (Slice& sl : part) clear_bins(sl.bin);
    struct Job {
      const TriangleBvhBuilder* self;
      const Range* r;
      const float* scale;
      std::vector<Slice>* part;
    } job{this, &r, scale, &part};
    detail::run_tasks(runner_, slices, [](void* j, std::size_t t) {
      const Job& jb = *static_cast<const Job*>(j);
      const std::size_t len = jb.r->e - jb.r->b, count = jb.part->size();
      jb.self->fill_bins(jb.r->b + len * t / count, jb.r->b + len * (t + 1) / count, jb.r->cl, jb.scale, (*jb.part)[t].bin);
    }, &job);
    for (const Slice& sl : part) merge_bins(bin, sl.bin);
  }

  // Splits r in two by the binned heuristic (the median of the widest centroid axis when the
  // centroids coincide or every plane leaves a side empty); false when r is a leaf.
  bool split(const Range& r, Range& left, Range& right, bool median = false) {
    const std::size_t n = r.e - r.b;
    if (n <= 1) return false;
    if (median && n > static_cast<std::size_t>(TriangleBvhNode::leaf_max)) return median_split(r, left, right);
    float scale[3];
    for (int a = 0; a < 3; ++a) scale[a] = r.ch[a] > r.cl[a] ? float(bins) * 0.99999f / (r.ch[a] - r.cl[a]) : 0.0f;
    Bin bin[3][bins];
    bin_range(r, scale, bin);
    float best = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_plane = 0;
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0.0f) continue;
      // Planes between two bins with no triangle between them cut the same sides at the same
      // cost: only the first plane after each occupied bin is weighed, so the sweeps run over
      // the occupied bins alone (listed first, without a branch per bin).
      int used[bins];
      int m = 0;
      for (int k = 0; k < bins; ++k) {
        used[m] = k;
        m += bin[a][k].n != 0 ? 1 : 0;
      }
      float rarea[bins];
      std::size_t rn[bins];
      alignas(16) float lo[4], hi[4];
      empty_box(lo, hi, 4);
      std::size_t cnt = 0;
      for (int j = m - 1; j > 0; --j) {
        grow(lo, hi, bin[a][used[j]]);
        cnt += bin[a][used[j]].n;
        rarea[j] = area(lo, hi);
        rn[j] = cnt;
      }
      if (m < 2) continue;
      empty_box(lo, hi, 4);
      grow(lo, hi, bin[a][used[0]]);
      cnt = bin[a][used[0]].n;
      float prev_area = area(lo, hi);  // the left side's, up to the occupied bin before j
      for (int j = 1; j < m; ++j) {
        const float cost = prev_area * float(cnt) + rarea[j] * float(rn[j]);
        if (cost < best) {
          best = cost;
          best_axis = a;
          best_plane = used[j - 1] + 1;
        }
        grow(lo, hi, bin[a][used[j]]);
        cnt += bin[a][used[j]].n;
        prev_area = area(lo, hi);
      }
    }
    if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max) && best_axis >= 0 &&
        best + area(r.lo, r.hi) * traversal_cost >= area(r.lo, r.hi) * float(n))
      return false;  // a leaf is cheaper than a split
    if (best_axis < 0) {
      if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max)) return false;
      return median_split(r, left, right);
    }
    left = Range{r.b, r.b, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, false};
    right = Range{r.e, r.e, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, false};
    empty_box(left.lo, left.hi, 3);
    empty_box(right.lo, right.hi, 3);
    const std::size_t mid = partition(r, best_axis, scale[best_axis], best_plane, left, right);
    // The sides' boxes are the unions of their bins' (each triangle lies in one bin of the axis),
    // unless the partition disagreed with the binning (then measured again).
    std::size_t left_count = 0;
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
      const std::size_t cut = mid == r.b || mid == r.e ? r.b + n / 2 : mid;
      left = bounds_of(r.b, cut);
      right = bounds_of(cut, r.e);
    }
    return true;
  }

  // Whether a ref's centroid falls below bin `plane` of axis a: its bin as fill_bins computes it.
  struct SideTest {
#if CULLKIT_HAS_SSE2
    __m128 keep3, c0, scale;
    __m128i plane;
    int a;
    SideTest(const float cl[3], float scale_a, int plane_at, int axis) noexcept : a(axis) {
      // The other lanes' scale is 0; a bin below `plane` is a clamped bin below it, as plane lies
      // in [1, bins - 1].
      alignas(16) float c0_lanes[4] = {0, 0, 0, 0}, scale_lanes[4] = {0, 0, 0, 0};
      c0_lanes[a] = cl[a];
      scale_lanes[a] = scale_a;
      keep3 = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
      c0 = _mm_load_ps(c0_lanes);
      scale = _mm_load_ps(scale_lanes);
      plane = _mm_set1_epi32(plane_at);
    }
    [[nodiscard]] std::uint64_t left(const Ref& it) const noexcept {
      const __m128 c4 = _mm_add_ps(_mm_and_ps(_mm_load_ps(it.lo), keep3), _mm_load_ps(it.hi));
      const __m128i below = _mm_cmplt_epi32(_mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(c4, c0), scale)), plane);
      return static_cast<std::uint64_t>((_mm_movemask_ps(_mm_castsi128_ps(below)) >> a) & 1);
    }
#else
    float c0, scale;
    int plane, a;
    SideTest(const float cl[3], float scale_a, int plane_at, int axis) noexcept
        : c0(cl[axis]), scale(scale_a), plane(plane_at), a(axis) {}
    [[nodiscard]] std::uint64_t left(const Ref& it) const noexcept {
      return static_cast<std::uint64_t>(std::clamp(static_cast<int>((it.lo[a] + it.hi[a] - c0) * scale), 0, bins - 1) < plane);
    }
#endif
  };

  // Marks the sides of the refs of words [w0, w1) of a range of n refs from `base` (bit i of
  // word i / 64: ref i goes left); returns how many go left.
  static std::size_t mark_sides(const Ref* base, std::size_t n, std::size_t w0, std::size_t w1, const SideTest& test,
                                std::uint64_t* side) noexcept {
    std::size_t lefts = 0;
    for (std::size_t w = w0; w < w1; ++w) {
      const std::size_t first = 64 * w, count = std::min<std::size_t>(64, n - first);
      std::uint64_t bits = 0;
      for (std::size_t k = 0; k < count; ++k) bits |= test.left(base[first + k]) << k;
      side[w] = bits;
      lefts += static_cast<std::size_t>(detail::popcount(bits));
    }
    return lefts;
  }

  // The box of the centroids (doubled) of refs_[b, e) into cl, ch (empty when b == e).
  void centroid_box(std::size_t b, std::size_t e, float (&cl)[4], float (&ch)[4]) const noexcept {
#if CULLKIT_HAS_SSE2
    const __m128 keep3 = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1));
    __m128 cl4 = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 ch4 = _mm_set1_ps(-std::numeric_limits<float>::infinity());
    for (std::size_t i = b; i < e; ++i) {
      const __m128 c4 = _mm_add_ps(_mm_and_ps(_mm_load_ps(refs_[i].lo), keep3), _mm_load_ps(refs_[i].hi));
      cl4 = _mm_min_ps(cl4, c4);
      ch4 = _mm_max_ps(ch4, c4);
    }
    _mm_storeu_ps(cl, cl4);
    _mm_storeu_ps(ch, ch4);
#else
    empty_box(cl, ch, 4);
    for (std::size_t i = b; i < e; ++i)
      for (int j = 0; j < 3; ++j) {
        cl[j] = std::min(cl[j], refs_[i].lo[j] + refs_[i].hi[j]);
        ch[j] = std::max(ch[j], refs_[i].lo[j] + refs_[i].hi[j]);
      }
#endif
  }

  // Moves the refs of r whose centroid falls below bin `plane` of axis a to its front, in the order
  // of the two-ended exchange of std::partition (the k-th ref going right from the front trades
  // places with the k-th ref going left from the back), and measures each side's centroid box; left.e
  // and right.b become the cut, which it returns. Each ref's side is first marked in a bit set
  // without a branch, so the exchanges are found a word of 64 refs at a time: the side of a ref
  // deep in the tree is hard to predict, and branching on it per ref cost more than the test. While
  // the top is cut, long ranges mark and measure on all threads (slices of whole words).
  std::size_t partition(const Range& r, int a, float scale, int plane, Range& left, Range& right) {
    const std::size_t n = r.e - r.b;
    Ref* const base = refs_.data() + r.b;
    const SideTest test(r.cl, scale, plane, a);
    const std::size_t words = (n + 63) / 64;
    thread_local std::vector<std::uint64_t> side_bits;
    if (side_bits.size() < words) side_bits.resize(words);
    std::uint64_t* const side = side_bits.data();
    const std::size_t slices = top_ && threads_ >= 2 && n >= parallel_bins ? std::min<std::size_t>(threads_, 64) : 1;
    struct Slice {
      std::size_t lefts;
      alignas(16) float box[4][4];  // left cl, ch; right cl, ch
    };
    Slice part[64];
    struct Job {
      TriangleBvhBuilder* self;
      const Ref* base;
      std::size_t first, n, words, mid;
      const SideTest* test;
      std::uint64_t* side;
      Slice* part;
      std::size_t slices;
    } job{this, base, r.b, n, words, 0, &test, side, part, slices};
    const auto each_slice = [&](ParallelTask task) {
      if (slices == 1) task(&job, 0);
      else detail::run_tasks(runner_, slices, task, &job);
    };
    each_slice([](void* j, std::size_t t) {
      Job& jb = *static_cast<Job*>(j);
      const std::size_t count = jb.slices;
      jb.part[t].lefts = mark_sides(jb.base, jb.n, jb.words * t / count, jb.words * (t + 1) / count, *jb.test, jb.side);
    });
    std::size_t lefts = 0;
    for (std::size_t t = 0; t < slices; ++t) lefts += part[t].lefts;
    // Refs going right below the cut (from the front) trade places with refs going left above it
    // (from the back); there are as many of each.
    const auto below_cut = [&](std::size_t w) {  // bits of word w before the cut
      return lefts >= 64 * (w + 1) ? ~std::uint64_t{0} : lefts <= 64 * w ? 0 : (std::uint64_t{1} << (lefts - 64 * w)) - 1;
    };
    if (lefts > 0 && lefts < n) {
      std::size_t lw = 0, rw = words;
      std::uint64_t front = ~side[0] & below_cut(0), back = 0;  // the words' refs still to exchange
      for (;;) {
        while (front == 0 && 64 * ++lw < lefts) front = ~side[lw] & below_cut(lw);
        if (front == 0) break;
        while (back == 0) {
          --rw;
          back = side[rw] & ~below_cut(rw);
        }
        const int i = detail::lowest_bit(front), j = detail::highest_bit(back);
        front &= front - 1;
        back &= ~(std::uint64_t{1} << j);
        std::swap(base[64 * lw + static_cast<std::size_t>(i)], base[64 * rw + static_cast<std::size_t>(j)]);
      }
    }
    const std::size_t mid = r.b + lefts;
    left.e = right.b = mid;
    // Each side's centroid box, merged over the slices (minima and maxima do not depend on the
    // order but for the sign of a zero, which no bin reads: a centroid minus either zero falls in
    // the same bin).
    job.mid = lefts;
    each_slice([](void* j, std::size_t t) {
      Job& jb = *static_cast<Job*>(j);
      Slice& sl = jb.part[t];
      const std::size_t count = jb.slices, b = jb.first;
      const auto cut = [&](std::size_t e, std::size_t k) { return jb.mid + (e - jb.mid) * k / count; };
      jb.self->centroid_box(b + jb.mid * t / count, b + jb.mid * (t + 1) / count, sl.box[0], sl.box[1]);
      jb.self->centroid_box(b + cut(jb.n, t), b + cut(jb.n, t + 1), sl.box[2], sl.box[3]);
    });
    empty_box(left.cl, left.ch, 3);
    empty_box(right.cl, right.ch, 3);
    for (std::size_t t = 0; t < slices; ++t)
      for (int j = 0; j < 3; ++j) {
        const Slice& sl = part[t];
        left.cl[j] = std::min(left.cl[j], sl.box[0][j]);
        left.ch[j] = std::max(left.ch[j], sl.box[1][j]);
        right.cl[j] = std::min(right.cl[j], sl.box[2][j]);
        right.ch[j] = std::max(right.ch[j], sl.box[3][j]);
      }
    return mid;
  }

  // Cuts r in two halves at the median of its centroids along their widest axis (ties by id).
  bool median_split(const Range& r, Range& left, Range& right) {
    int a = 0;
    for (int j = 1; j < 3; ++j)
      if (r.ch[j] - r.cl[j] > r.ch[a] - r.cl[a]) a = j;
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

  // Cuts r into at most `most` (at most 16) ranges, into `out` in range order, splitting the
  // largest-area splittable range first; returns how many. `first`, when given, is r's split,
  // already made.
  std::size_t split_into(const Range& r, std::size_t most, Range* out, bool median = false, const Range* first = nullptr) {
    std::size_t count = 1;
    out[0] = r;
    while (count < most) {
      std::size_t pick = count;
      float big = -1.0f;
      for (std::size_t k = 0; k < count; ++k)
        if (!out[k].whole && out[k].e - out[k].b > static_cast<std::size_t>(TriangleBvhNode::leaf_max) &&
            area(out[k].lo, out[k].hi) > big) {
          big = area(out[k].lo, out[k].hi);
          pick = k;
        }
      if (pick == count) {  // small ranges: split them too unless the heuristic keeps them whole
        for (std::size_t k = 0; k < count && pick == count; ++k)
          if (!out[k].whole && out[k].e - out[k].b > 1) pick = k;
        if (pick == count) break;
      }
      Range a, b;
      if (first != nullptr) {  // the first pick is r itself
        a = first[0];
        b = first[1];
        first = nullptr;
      } else if (!split(out[pick], a, b, median)) {
        out[pick].whole = true;
        continue;
      }
      for (std::size_t k = count; k > pick + 1; --k) out[k] = out[k - 1];
      out[pick] = a;
      out[pick + 1] = b;
      ++count;
    }
    for (std::size_t k = 1; k < count; ++k)  // in range order (the starts differ)
      for (std::size_t j = k; j > 0 && out[j].b < out[j - 1].b; --j) std::swap(out[j], out[j - 1]);
    return count;
  }

  std::uint32_t leaf_or_node(const Range& r, std::vector<TriangleBvhNode>& nodes, int depth) {
    const std::size_t n = r.e - r.b;
    if (n <= static_cast<std::size_t>(TriangleBvhNode::leaf_max)) {
      Range halves[2];
      if (r.whole || !split(r, halves[0], halves[1]))
        return TriangleBvhNode::leaf(static_cast<std::uint32_t>(r.b), static_cast<std::uint32_t>(n));
      return make(r, nodes, depth, halves);
    }
    return make(r, nodes, depth);
  }

  // A subtree over r (more than a leaf), its nodes appended to `nodes`; returns its root index.
  // Below depth_limit nodes split at medians (a balanced bound on the depth, which the cast's
  // stack relies on). `first`, when given, is r's split, already made.
  static constexpr int depth_limit = 48;
  std::uint32_t make(const Range& r, std::vector<TriangleBvhNode>& nodes, int depth = 2, const Range* first = nullptr) {
    Range kids[4];
    std::size_t count = split_into(r, 4, kids, depth >= depth_limit, first);
    if (count == 1) {  // cannot be split: one leaf per leaf_max run
      count = 0;
      const std::size_t n = r.e - r.b, step = std::max<std::size_t>((n + 3) / 4, 1);
      for (std::size_t b = r.b; b < r.e; b += step) kids[count++] = bounds_of(b, std::min(r.e, b + step));
    }
    const std::size_t index = nodes.size();
    nodes.emplace_back();
    float lo[3][4], hi[3][4];
    std::uint32_t codes[4];
    for (std::size_t j = 0; j < count; ++j) {
      const Range& k = kids[j];
      codes[j] = leaf_or_node(k, nodes, depth + 1);
      for (int a = 0; a < 3; ++a) {
        lo[a][j] = k.lo[a];
        hi[a][j] = k.hi[a];
      }
    }
    TriangleBvhNode& node = nodes[index];
    node.quantize(lo, hi, static_cast<int>(count));
    for (std::size_t j = 0; j < count; ++j) node.child[j] = codes[j];
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
