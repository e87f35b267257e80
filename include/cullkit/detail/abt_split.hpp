// cullkit/detail/abt_split.hpp: split-plane choice for AdaptiveBinaryTree (users never name this).
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

#include "../geometry/aabb.hpp"

namespace cullkit::detail {

/// One object during the build: its (valid) bounds, its centroid and its input index.
struct AbtBuildItem {
  Aabb box;
  glm::vec3 centroid;
  std::uint32_t index;
};

/// Centroid of a valid box without overflow for huge coordinates.
[[nodiscard]] inline glm::vec3 abt_centroid(const Aabb& b) noexcept { return b.min * 0.5f + b.max * 0.5f; }

/// splitmix64 step: a tiny, well-mixed, platform-independent generator.
[[nodiscard]] inline std::uint64_t splitmix64(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

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
  float weights[4];           // w1..w4
  std::uint32_t candidates;   // candidate planes per axis
  bool sampling;              // true: seeded sampling; false: uniform binning
  std::uint64_t seed;
};

struct AbtSplit {
  bool found = false;
  int axis = 0;
  float position = 0.0f;
};

/// Reusable per-thread scratch (sized once per build, no allocation per node).
struct AbtSplitScratch {
  std::vector<float> positions;        // candidate positions on one axis, ascending
  std::vector<std::uint32_t> count;    // objects whose centroid falls in each interval
  std::vector<Aabb> box;               // merged bounds per interval
  std::vector<std::int64_t> straddle;  // difference array for straddling counts
  std::vector<Aabb> right;             // suffix merges

  void reserve(std::uint32_t k) {
    positions.reserve(k);
    count.resize(k + 1);
    box.resize(k + 1);
    straddle.resize(k + 2);
    right.resize(k + 1);
  }
};

/// Chooses the split of items [begin, end) whose merged bounds are `node_box` and whose centroids
/// span `centroid_box`. `found` is false when no candidate puts objects on both sides.
/// `key` makes the sampling stream depend only on the node (never on threads or visit order).
[[nodiscard]] inline AbtSplit abt_find_split(const AbtBuildItem* items, std::uint32_t begin, std::uint32_t end,
                                             const Aabb& node_box, const Aabb& centroid_box,
                                             const AbtSplitConfig& cfg, std::uint64_t key,
                                             AbtSplitScratch& s) {
  AbtSplit best;
  const std::uint32_t n = end - begin;
  if (n < 2) return best;
  double node_ext[3], max_ext = 0.0;
  for (int a = 0; a < 3; ++a) {
    node_ext[a] = double(node_box.max[a]) - double(node_box.min[a]);
    max_ext = std::max(max_ext, node_ext[a]);
  }
  const double inv_n = 1.0 / double(n);
  double best_score = 0.0;
  std::uint64_t rng = cfg.seed ^ (key * 0xD1B54A32D192ED03ull);
  const std::uint32_t k_max = std::max<std::uint32_t>(1u, cfg.candidates);

  for (int axis = 0; axis < 3; ++axis) {
    const float cmin = centroid_box.min[axis], cmax = centroid_box.max[axis];
    const double ext = double(cmax) - double(cmin);
    if (!(ext > 0.0)) continue;  // all centroids on one plane: nothing separates on this axis

    // Candidate positions; bin(v) must approximate #{candidates <= v} (exact for sampling).
    s.positions.clear();
    float scale = 0.0f;
    if (cfg.sampling) {
      for (std::uint32_t i = 0; i < k_max; ++i) {
        const std::uint32_t pick = begin + static_cast<std::uint32_t>(splitmix64(rng) % n);
        const float p = items[pick].centroid[axis];
        if (p > cmin) s.positions.push_back(p);  // a plane at cmin would leave the left side empty
      }
      std::sort(s.positions.begin(), s.positions.end());
      s.positions.erase(std::unique(s.positions.begin(), s.positions.end()), s.positions.end());
    } else {
      const double step = ext / double(k_max + 1);
      scale = static_cast<float>(double(k_max + 1) / ext);
      if (!(scale > 0.0f) || !std::isfinite(scale)) continue;
      for (std::uint32_t i = 0; i < k_max; ++i) {
        const float p = static_cast<float>(double(cmin) + step * double(i + 1));
        if (p > cmin && p <= cmax && (s.positions.empty() || p > s.positions.back())) s.positions.push_back(p);
      }
      if (s.positions.size() != k_max) {
        // Rounding merged candidates (a tiny range): fall back to exact counting by search.
        scale = 0.0f;
      }
    }
    const auto m = static_cast<std::uint32_t>(s.positions.size());
    if (m == 0) continue;
    const float* pos = s.positions.data();
    auto bin = [&](float v) -> std::uint32_t {
      if (scale > 0.0f) {
        float t = (v - cmin) * scale;  // never NaN: v, cmin finite and scale finite > 0
        t = t < 0.0f ? 0.0f : t;
        t = t > float(m) ? float(m) : t;
        return static_cast<std::uint32_t>(t);
      }
      return static_cast<std::uint32_t>(std::upper_bound(pos, pos + m, v) - pos);
    };
    std::fill(s.count.begin(), s.count.begin() + m + 1, 0u);
    std::fill(s.box.begin(), s.box.begin() + m + 1, Aabb::empty());
    const bool want_straddle = cfg.weights[3] != 0.0f;
    if (want_straddle) std::fill(s.straddle.begin(), s.straddle.begin() + m + 2, std::int64_t{0});
    for (std::uint32_t i = begin; i < end; ++i) {
      const AbtBuildItem& it = items[i];
      const std::uint32_t b = bin(it.centroid[axis]);
      ++s.count[b];
      s.box[b] = merge(s.box[b], it.box);
      if (want_straddle) {
        // Straddles candidate j (between intervals j and j + 1) when bin(min) <= j < bin(max).
        ++s.straddle[bin(it.box.min[axis])];
        --s.straddle[bin(it.box.max[axis])];
      }
    }
    Aabb acc = Aabb::empty();
    for (std::uint32_t j = m + 1; j-- > 0;) {
      acc = merge(acc, s.box[j]);
      s.right[j] = acc;
    }
    Aabb left = Aabb::empty();
    std::uint32_t n_left = 0;
    std::int64_t straddling = 0;
    const double f1 = max_ext > 0.0 ? 1.0 - node_ext[axis] / max_ext : 0.0;
    for (std::uint32_t j = 0; j < m; ++j) {
      left = merge(left, s.box[j]);
      n_left += s.count[j];
      if (want_straddle) straddling += s.straddle[j];
      if (n_left == 0 || n_left == n) continue;
      const double vl = abt_volume(left), vr = abt_volume(s.right[j + 1]);
      const double vsum = vl + vr;
      const double f2 = vsum > 0.0 ? std::fabs(vl - vr) / vsum : 0.0;
      const double f3 = std::fabs(double(n_left) - double(n - n_left)) * inv_n;
      const double f4 = want_straddle ? double(std::max<std::int64_t>(straddling, 0)) * inv_n : 0.0;
      const double score = double(cfg.weights[0]) * f1 + double(cfg.weights[1]) * f2 +
                           double(cfg.weights[2]) * f3 + double(cfg.weights[3]) * std::min(f4, 1.0);
      if (!best.found || score < best_score) {
        best.found = true;
        best.axis = axis;
        best.position = pos[j];
        best_score = score;
      }
    }
  }
  return best;
}

}  // namespace cullkit::detail
