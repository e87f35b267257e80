// cullkit/detail/abt/split.hpp: split-plane choice for AdaptiveBinaryTree (users never name this).
//
// A node's candidates are axis-aligned planes; each is scored with the four weighted criteria of
// the seed paper (基于自适应二叉树的场景视锥体裁剪算法, §1.1.2, after Dickheiser, Game Programming
// Gems 6): f1 prefers the node's longest axis, f2 children of equal volume, f3 children of equal
// object count, f4 few objects straddling the plane. Each term is normalized to [0, 1] here so
// that the weights mean the same thing in every node.
//
// Candidates come either from uniform bins over the centroid range (`binning`) or from centroids
// of objects drawn with a seeded splitmix64 generator (`sampling`, the seed's random sampling).
// Either way one pass over the node's objects fills per-interval histograms, so the cost per node
// is O(n) per axis (O(n log k) for sampling), never O(n * candidates).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "../../config.hpp"
#include "../../geometry/aabb.hpp"
#include "../splitmix64.hpp"

namespace cullkit::detail {

/// One object during the build: its (valid) bounds, its centroid and its input index.
struct AbtBuildItem {
  Aabb box;
  glm::vec3 centroid;
  std::uint32_t index;
};

/// Centroid of a valid box without overflow for huge coordinates.
[[nodiscard]] inline glm::vec3 abt_centroid(const Aabb& b) noexcept { return b.min * 0.5f + b.max * 0.5f; }

/// Volume in double: finite for any box with finite float coordinates.
[[nodiscard]] inline double abt_volume(const Aabb& b) noexcept {
  if (is_empty(b)) return 0.0;
  return (double(b.max.x) - double(b.min.x)) * (double(b.max.y) - double(b.min.y)) *
         (double(b.max.z) - double(b.min.z));
}
/// Surface area in double (0 for an empty box).
[[nodiscard]] inline double abt_area(const Aabb& b) noexcept {
  if (is_empty(b)) return 0.0;
  const double x = double(b.max.x) - double(b.min.x), y = double(b.max.y) - double(b.min.y),
               z = double(b.max.z) - double(b.min.z);
  return 2.0 * (x * y + y * z + z * x);
}

struct AbtSplitConfig {
  float weights[4];            // w1..w4
  std::uint32_t candidates;    // candidate planes per axis
  bool sampling;               // true: seeded sampling; false: uniform binning
  std::uint64_t seed;
  std::uint32_t sample_limit;  // nodes larger than this score on an evenly strided subset
};

struct AbtSplit {
  bool found = false;
  int axis = 0;
  float position = 0.0f;
};

/// Reusable per-thread scratch (sized once per build, no allocation per node).
struct AbtSplitScratch {
  std::vector<float> positions[3];     // candidate positions per axis, ascending
  std::vector<std::uint32_t> count;    // [axis][interval] objects whose centroid falls there
  std::vector<Aabb> box;               // [axis][interval] merged bounds
  std::vector<std::int32_t> straddle;  // [axis][interval] difference array of straddling counts
  std::vector<Aabb> right;             // suffix merges for one axis
  std::uint32_t k = 0;

  void reserve(std::uint32_t candidates) {
    k = candidates;
    for (auto& p : positions) p.reserve(candidates);
    count.resize(3 * std::size_t{k + 2});
    box.resize(3 * std::size_t{k + 2});
    straddle.resize(3 * std::size_t{k + 2});
    right.resize(k + 2);
  }
};

namespace abt_split_impl {

struct AxisBinning {
  float lo = 0.0f;
  float scale = 0.0f;  // > 0: uniform bins; 0: binary search in `pos`
  const float* pos = nullptr;
  std::uint32_t m = 0;  // candidate count on this axis (0: axis unused)

  [[nodiscard]] CULLKIT_FORCEINLINE std::uint32_t bin(float v) const noexcept {
    if (scale > 0.0f) {
      float t = (v - lo) * scale;  // never NaN: v, lo finite, scale finite > 0
      t = t < 0.0f ? 0.0f : t;
      t = t > float(m) ? float(m) : t;
      return static_cast<std::uint32_t>(t);
    }
    return static_cast<std::uint32_t>(std::upper_bound(pos, pos + m, v) - pos);
  }
};

// One pass over the (possibly strided) items fills all three axes' histograms.
template <bool Straddle>
inline void fill(const AbtBuildItem* items, std::uint32_t begin, std::uint32_t end, std::uint32_t step,
                 const AxisBinning* ax, AbtSplitScratch& s) {
  const std::size_t w = std::size_t{s.k} + 2;
  for (std::uint32_t i = begin; i < end; i += step) {
    const AbtBuildItem& it = items[i];
    for (int a = 0; a < 3; ++a) {
      if (ax[a].m == 0) continue;
      const std::size_t base = std::size_t(a) * w;
      const std::uint32_t b = ax[a].bin(it.centroid[a]);
      ++s.count[base + b];
      Aabb& bb = s.box[base + b];
      bb.min = glm::min(bb.min, it.box.min);
      bb.max = glm::max(bb.max, it.box.max);
      if constexpr (Straddle) {
        // Straddles candidate j (between intervals j and j + 1) when bin(min) <= j < bin(max).
        ++s.straddle[base + ax[a].bin(it.box.min[a])];
        --s.straddle[base + ax[a].bin(it.box.max[a])];
      }
    }
  }
}

}  // namespace abt_split_impl

/// Chooses the split of items [begin, end) whose merged bounds are `node_box` and whose centroids
/// span `centroid_box`. `found` is false when no candidate puts objects on both sides.
/// `key` makes the sampling stream depend only on the node (never on threads or visit order).
/// Nodes with more than `cfg.sample_limit` objects are scored on every (n / limit)-th object: the
/// scores are estimates there, the partition that follows is always exact.
[[nodiscard]] inline AbtSplit abt_find_split(const AbtBuildItem* items, std::uint32_t begin, std::uint32_t end,
                                             const Aabb& node_box, const Aabb& centroid_box,
                                             const AbtSplitConfig& cfg, std::uint64_t key,
                                             AbtSplitScratch& s) {
  AbtSplit best;
  const std::uint32_t n = end - begin;
  if (n < 2) return best;
  if (s.k != cfg.candidates) s.reserve(cfg.candidates);
  double node_ext[3], max_ext = 0.0;
  for (int a = 0; a < 3; ++a) {
    node_ext[a] = double(node_box.max[a]) - double(node_box.min[a]);
    max_ext = std::max(max_ext, node_ext[a]);
  }
  SplitMix64 rng(cfg.seed ^ (key * 0xD1B54A32D192ED03ull));
  const std::uint32_t k_max = std::max<std::uint32_t>(1u, cfg.candidates);

  // Candidate positions per axis; bin(v) approximates #{candidates <= v} (exact for sampling).
  abt_split_impl::AxisBinning ax[3];
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<float>& positions = s.positions[axis];
    positions.clear();
    const float cmin = centroid_box.min[axis], cmax = centroid_box.max[axis];
    const double ext = double(cmax) - double(cmin);
    if (!(ext > 0.0)) continue;  // all centroids on one plane: nothing separates on this axis
    float scale = 0.0f;
    if (cfg.sampling) {
      for (std::uint32_t i = 0; i < k_max; ++i) {
        const std::uint32_t pick = begin + static_cast<std::uint32_t>(rng.below(n));
        const float p = items[pick].centroid[axis];
        if (p > cmin) positions.push_back(p);  // a plane at cmin would leave the left side empty
      }
      std::sort(positions.begin(), positions.end());
      positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
    } else {
      const double step = ext / double(k_max + 1);
      scale = static_cast<float>(double(k_max + 1) / ext);
      for (std::uint32_t i = 0; i < k_max; ++i) {
        const float p = static_cast<float>(double(cmin) + step * double(i + 1));
        if (p > cmin && p <= cmax && (positions.empty() || p > positions.back())) positions.push_back(p);
      }
      // Rounding merged candidates (a tiny range) or an extreme scale: count exactly by search.
      if (positions.size() != k_max || !(scale > 0.0f) || !std::isfinite(scale)) scale = 0.0f;
    }
    ax[axis].lo = cmin;
    ax[axis].scale = scale;
    ax[axis].pos = positions.data();
    ax[axis].m = static_cast<std::uint32_t>(positions.size());
  }
  if (ax[0].m + ax[1].m + ax[2].m == 0) return best;

  const std::size_t w = std::size_t{s.k} + 2;
  std::fill(s.count.begin(), s.count.end(), 0u);
  std::fill(s.box.begin(), s.box.end(), Aabb::empty());
  const bool want_straddle = cfg.weights[3] != 0.0f;
  if (want_straddle) std::fill(s.straddle.begin(), s.straddle.end(), 0);
  const std::uint32_t limit = std::max<std::uint32_t>(cfg.sample_limit, 64u);
  const std::uint32_t step = n > limit ? n / limit : 1u;
  if (want_straddle) abt_split_impl::fill<true>(items, begin, end, step, ax, s);
  else abt_split_impl::fill<false>(items, begin, end, step, ax, s);

  double best_score = 0.0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint32_t m = ax[axis].m;
    if (m == 0) continue;
    const std::uint32_t* count = s.count.data() + std::size_t(axis) * w;
    const Aabb* box = s.box.data() + std::size_t(axis) * w;
    const std::int32_t* straddle = s.straddle.data() + std::size_t(axis) * w;
    std::uint32_t total = 0;
    for (std::uint32_t j = 0; j <= m; ++j) total += count[j];
    if (total < 2) continue;
    const double inv_total = 1.0 / double(total);
    Aabb acc = Aabb::empty();
    for (std::uint32_t j = m + 1; j-- > 0;) {
      acc = merge(acc, box[j]);
      s.right[j] = acc;
    }
    Aabb left = Aabb::empty();
    std::uint32_t n_left = 0;
    std::int64_t straddling = 0;
    const double f1 = max_ext > 0.0 ? 1.0 - node_ext[axis] / max_ext : 0.0;
    for (std::uint32_t j = 0; j < m; ++j) {
      left = merge(left, box[j]);
      n_left += count[j];
      if (want_straddle) straddling += straddle[j];
      if (n_left == 0 || n_left == total) continue;
      const double vl = abt_volume(left), vr = abt_volume(s.right[j + 1]);
      const double vsum = vl + vr;
      const double f2 = vsum > 0.0 ? std::fabs(vl - vr) / vsum : 0.0;
      const double f3 = std::fabs(double(n_left) - double(total - n_left)) * inv_total;
      const double f4 = want_straddle ? double(std::max<std::int64_t>(straddling, 0)) * inv_total : 0.0;
      const double score = double(cfg.weights[0]) * f1 + double(cfg.weights[1]) * f2 +
                           double(cfg.weights[2]) * f3 + double(cfg.weights[3]) * std::min(f4, 1.0);
      if (!best.found || score < best_score) {
        best.found = true;
        best.axis = axis;
        best.position = ax[axis].pos[j];
        best_score = score;
      }
    }
  }
  return best;
}

}  // namespace cullkit::detail
