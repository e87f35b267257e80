// cullkit/detail/splitmix64.hpp: the library's seeded generator for sampling in builds.
// Tiny, well mixed and the same on every platform, so a seed names one build everywhere (the
// standard engines' distributions are not portable).
#pragma once

#include <cstdint>

namespace cullkit::detail {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) noexcept : state_(seed) {}
  [[nodiscard]] std::uint64_t next() noexcept {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// A value in [0, n) (0 when n is 0); the modulo bias is irrelevant for sampling.
  [[nodiscard]] std::uint64_t below(std::uint64_t n) noexcept { return n == 0 ? 0 : next() % n; }

 private:
  std::uint64_t state_;
};

}  // namespace cullkit::detail
