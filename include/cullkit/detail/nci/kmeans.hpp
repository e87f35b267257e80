// cullkit/detail/nci/kmeans.hpp: spherical k-means for the NormalClassIndex's normal classes.
// Deterministic (seeded splitmix64, no clock), linear in the number of normals: centres are fitted
// on a seeded sample, and every normal is assigned through a cube-map table of nearest centres.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "../splitmix64.hpp"
#include "../../config.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail {

/// Cube-map lookup from a unit vector to the nearest of a set of centres (nearest to the bin's
/// centre direction, so an approximation of the true nearest: fine for classes, whose cones are
/// measured from their actual members afterwards).
class NormalLookup {
 public:
  static constexpr int resolution = 48;

  void build(const std::vector<glm::vec3>& centers) {
    if (directions_.empty()) {
      // The bins' centre directions, the same whatever the centres: made once per lookup.
      directions_.resize(static_cast<std::size_t>(6 * resolution * resolution));
      for (int face = 0; face < 6; ++face) {
        for (int j = 0; j < resolution; ++j) {
          for (int i = 0; i < resolution; ++i) {
            const float u = (2.0f * (static_cast<float>(i) + 0.5f) / resolution) - 1.0f;
            const float v = (2.0f * (static_cast<float>(j) + 0.5f) / resolution) - 1.0f;
            glm::vec3 d(0.0f);
            const int axis = face >> 1;
            d[axis] = (face & 1) ? -1.0f : 1.0f;
            d[(axis + 1) % 3] = u;
            d[(axis + 2) % 3] = v;
            directions_[bin(face, i, j)] = glm::normalize(d);
          }
        }
      }
    }
    // A bin's nearest centre is found when a normal first falls in it: small meshes (few
    // distinct normals) then touch a few bins of the table instead of all of them.
    table_.assign(directions_.size(), unset);
    centers_ = &centers;
#if CULLKIT_HAS_SSE2
    // Four centres at a time, their coordinates by lanes; the dot products are rounded as
    // glm::dot rounds them ((x x' + y y') + z z'), and the first of equal best ones wins, so the
    // table is the scalar nearest()'s.
    groups_ = (centers.size() + 3) / 4;
    lanes_.assign(16 * groups_, 0.0f);
    for (std::size_t c = 0; c < centers.size(); ++c) {
      float* g = &lanes_[16 * (c / 4)];
      g[c % 4] = centers[c].x;
      g[4 + c % 4] = centers[c].y;
      g[8 + c % 4] = centers[c].z;
    }
    for (std::size_t c = centers.size(); c < 4 * groups_; ++c) lanes_[16 * (c / 4) + 12 + c % 4] = 1.0f;  // padding
#endif
  }
  // The centres given to the last build() must outlive the lookups.
  [[nodiscard]] std::uint32_t operator()(const glm::vec3& n) noexcept { return at(bin_of(n)); }
  // The bin of the table a normal falls in (a zero or NaN normal: the first).
  [[nodiscard]] static std::size_t bin_of(const glm::vec3& n) noexcept {
    const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    int axis = 0;
    if (ay > ax) axis = 1;
    if (az > (axis == 0 ? ax : ay)) axis = 2;
    const float m = std::fabs(n[axis]);
    if (!(m > 0.0f)) return 0;
    const int face = axis * 2 + (n[axis] < 0.0f ? 1 : 0);
    const float u = n[(axis + 1) % 3] / m, v = n[(axis + 2) % 3] / m;
    const int i = std::clamp(static_cast<int>((u + 1.0f) * 0.5f * resolution), 0, resolution - 1);
    const int j = std::clamp(static_cast<int>((v + 1.0f) * 0.5f * resolution), 0, resolution - 1);
    return bin(face, i, j);
  }
  // The centre nearest to bin b's direction.
  [[nodiscard]] std::uint32_t at(std::size_t b) noexcept {
    if (table_.empty()) return 0u;
    std::uint32_t& nearest_centre = table_[b];
    if (nearest_centre == unset) {
#if CULLKIT_HAS_SSE2
      nearest_centre = nearest_by_lanes(directions_[b]);
#else
      nearest_centre = nearest(*centers_, directions_[b]);
#endif
    }
    return nearest_centre;
  }
  [[nodiscard]] static std::uint32_t nearest(const std::vector<glm::vec3>& centers, const glm::vec3& d) noexcept {
    std::uint32_t best = 0;
    float best_dot = -2.0f;
    for (std::size_t c = 0; c < centers.size(); ++c) {
      const float dd = glm::dot(centers[c], d);
      if (dd > best_dot) {
        best_dot = dd;
        best = static_cast<std::uint32_t>(c);
      }
    }
    return best;
  }

 private:
#if CULLKIT_HAS_SSE2
  // nearest() over the centres as lanes_ holds them (x, y, z and a padding flag per group of four).
  [[nodiscard]] std::uint32_t nearest_by_lanes(const glm::vec3& d) const noexcept {
    const __m128 dx = _mm_set1_ps(d.x), dy = _mm_set1_ps(d.y), dz = _mm_set1_ps(d.z), never = _mm_set1_ps(-3.0f);
    __m128 best = _mm_set1_ps(-2.0f);
    __m128i best_id = _mm_setzero_si128(), id = _mm_set_epi32(3, 2, 1, 0);
    const __m128i step = _mm_set1_epi32(4);
    for (std::size_t g = 0; g < groups_; ++g, id = _mm_add_epi32(id, step)) {
      const float* c = &lanes_[16 * g];
      __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(c), dx), _mm_mul_ps(_mm_loadu_ps(c + 4), dy)),
                              _mm_mul_ps(_mm_loadu_ps(c + 8), dz));
      const __m128 padding = _mm_cmpgt_ps(_mm_loadu_ps(c + 12), _mm_setzero_ps());
      dot = _mm_or_ps(_mm_and_ps(padding, never), _mm_andnot_ps(padding, dot));
      const __m128 better = _mm_cmpgt_ps(dot, best);
      best = _mm_or_ps(_mm_and_ps(better, dot), _mm_andnot_ps(better, best));
      const __m128i take = _mm_castps_si128(better);
      best_id = _mm_or_si128(_mm_and_si128(take, id), _mm_andnot_si128(take, best_id));
    }
    alignas(16) float value[4];
    alignas(16) std::int32_t which[4];
    _mm_store_ps(value, best);
    _mm_store_si128(reinterpret_cast<__m128i*>(which), best_id);
    int pick = 0;  // the largest value, the lowest centre among equal ones
    for (int j = 1; j < 4; ++j)
      if (value[j] > value[pick] || (value[j] == value[pick] && which[j] < which[pick])) pick = j;
    return static_cast<std::uint32_t>(which[pick]);
  }
  std::vector<float> lanes_;
  std::size_t groups_ = 0;
#endif
  static std::size_t bin(int face, int i, int j) noexcept {
    return static_cast<std::size_t>((face * resolution + j) * resolution + i);
  }
  static constexpr std::uint32_t unset = 0xFFFFFFFFu;
  std::vector<std::uint32_t> table_;
  std::vector<glm::vec3> directions_;
  const std::vector<glm::vec3>* centers_ = nullptr;
};

/// Clusters unit `normals` into at most `k` classes. Writes each normal's class to `class_of` and
/// the class axes to `centers` (only non-empty classes survive; ids are dense). Deterministic for
/// a given input and seed.
inline void cluster_normals(const std::vector<glm::vec3>& normals, int k, std::uint64_t seed,
                            std::vector<std::uint32_t>& class_of, std::vector<glm::vec3>& centers) {
  class_of.assign(normals.size(), 0u);
  centers.clear();
  if (normals.empty()) return;
  k = std::max(1, k);

  // Initial centres: a Fibonacci spiral covers the sphere evenly whatever the data.
  const double golden = 2.39996322972865332;  // pi * (3 - sqrt(5))
  for (int i = 0; i < k; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / k;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    centers.push_back(glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)));
  }

  // A seeded sample to fit on.
  SplitMix64 rng(seed);
  const std::size_t sample_size = std::min<std::size_t>(normals.size(), 65536);
  std::vector<glm::vec3> sample;
  sample.reserve(sample_size);
  if (sample_size == normals.size()) {
    sample = normals;
  } else {
    for (std::size_t i = 0; i < sample_size; ++i) sample.push_back(normals[rng.below(normals.size())]);
  }

  NormalLookup lookup;
  std::vector<glm::dvec3> sum(static_cast<std::size_t>(k));
  std::vector<std::uint32_t> count(static_cast<std::size_t>(k));
  std::vector<std::uint32_t> sample_bin(sample.size());  // a normal's bin does not depend on the centres
  for (std::size_t i = 0; i < sample.size(); ++i)
    sample_bin[i] = static_cast<std::uint32_t>(NormalLookup::bin_of(sample[i]));
  for (int iter = 0; iter < 12; ++iter) {
    lookup.build(centers);
    std::fill(sum.begin(), sum.end(), glm::dvec3(0.0));
    std::fill(count.begin(), count.end(), 0u);
    for (std::size_t i = 0; i < sample.size(); ++i) {
      const glm::vec3& n = sample[i];
      const std::uint32_t c = lookup.at(sample_bin[i]);
      sum[c] += glm::dvec3(n);
      ++count[c];
    }
    for (int c = 0; c < k; ++c) {
      const double len = glm::length(sum[static_cast<std::size_t>(c)]);
      if (count[static_cast<std::size_t>(c)] > 0 && len > 1e-12) {
        centers[static_cast<std::size_t>(c)] = glm::vec3(sum[static_cast<std::size_t>(c)] / len);
      } else {
        // Empty (or cancelling) class: re-seed it at a random sample normal.
        centers[static_cast<std::size_t>(c)] = sample[rng.below(sample.size())];
      }
    }
  }

  lookup.build(centers);
  std::vector<std::uint32_t> remap(static_cast<std::size_t>(k), 0xFFFFFFFFu);
  std::vector<glm::vec3> used;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    std::uint32_t c = lookup(normals[i]);
    if (remap[c] == 0xFFFFFFFFu) {
      remap[c] = static_cast<std::uint32_t>(used.size());
      used.push_back(centers[c]);
    }
    class_of[i] = remap[c];
  }
  centers = std::move(used);
}

}  // namespace cullkit::detail
