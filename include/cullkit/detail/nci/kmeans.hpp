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

namespace cullkit::detail {

/// Cube-map lookup from a unit vector to the nearest of a set of centres (nearest to the bin's
/// centre direction, so an approximation of the true nearest: fine for classes, whose cones are
/// measured from their actual members afterwards).
class NormalLookup {
 public:
  static constexpr int resolution = 48;

  void build(const std::vector<glm::vec3>& centers) {
    table_.assign(static_cast<std::size_t>(6 * resolution * resolution), 0u);
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
          d = glm::normalize(d);
          table_[bin(face, i, j)] = nearest(centers, d);
        }
      }
    }
  }
  [[nodiscard]] std::uint32_t operator()(const glm::vec3& n) const noexcept {
    const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    int axis = 0;
    if (ay > ax) axis = 1;
    if (az > (axis == 0 ? ax : ay)) axis = 2;
    const float m = std::fabs(n[axis]);
    if (!(m > 0.0f)) return table_.empty() ? 0u : table_[0];
    const int face = axis * 2 + (n[axis] < 0.0f ? 1 : 0);
    const float u = n[(axis + 1) % 3] / m, v = n[(axis + 2) % 3] / m;
    const int i = std::clamp(static_cast<int>((u + 1.0f) * 0.5f * resolution), 0, resolution - 1);
    const int j = std::clamp(static_cast<int>((v + 1.0f) * 0.5f * resolution), 0, resolution - 1);
    return table_[bin(face, i, j)];
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
  static std::size_t bin(int face, int i, int j) noexcept {
    return static_cast<std::size_t>((face * resolution + j) * resolution + i);
  }
  std::vector<std::uint32_t> table_;
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
  for (int iter = 0; iter < 12; ++iter) {
    lookup.build(centers);
    std::fill(sum.begin(), sum.end(), glm::dvec3(0.0));
    std::fill(count.begin(), count.end(), 0u);
    for (const auto& n : sample) {
      const std::uint32_t c = lookup(n);
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
