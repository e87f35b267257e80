// cullkit/depth_sort.hpp: back-to-front order of float depth keys by a stable LSD radix sort.
//
// Transparent draws are painted far to near. Sorting their depths is the classic use of a radix
// sort (counting passes over the key bits): linear in the count, no comparisons, stable.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "config.hpp"

namespace cullkit {

namespace detail {
struct DepthSortAccess;
}

/// Reusable buffers for `order_back_to_front`. Keep one per thread (or per sorter) and pass it in:
/// once its buffers have grown to the largest count sorted, sorting allocates nothing. Not safe to
/// share between threads at the same time.
class DepthSortScratch {
 public:
  /// Frees the buffers (the next sort grows them again).
  void release() noexcept {
    std::vector<std::uint64_t>().swap(a_);
    std::vector<std::uint64_t>().swap(b_);
  }
  /// Bytes held by the buffers.
  [[nodiscard]] std::size_t bytes() const noexcept {
    return (a_.capacity() + b_.capacity()) * sizeof(std::uint64_t);
  }

 private:
  friend struct detail::DepthSortAccess;
  std::vector<std::uint64_t> a_, b_;  // (key << 32 | payload) items, ping-pong
};

namespace detail {

/// The sort key of a depth: ascending keys are descending depths, with every NaN first (key 0,
/// which no number reaches: +inf maps to 0x007FFFFF) and -0 equal to +0.
[[nodiscard]] inline std::uint32_t back_to_front_key(float depth) noexcept {
  if (depth != depth) return 0u;
  if (depth == 0.0f) depth = 0.0f;  // -0 sorts with +0
  std::uint32_t bits;
  std::memcpy(&bits, &depth, sizeof bits);
  // The usual order-preserving map (flip all bits of negatives, the sign bit of positives) gives
  // ascending unsigned keys for ascending floats; its complement gives descending.
  const std::uint32_t ascending = (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
  return ~ascending;
}

constexpr int kRadixBits = 11;
constexpr std::uint32_t kRadixSize = 1u << kRadixBits;
constexpr int kRadixPasses = 3;  // 11 + 11 + 10 bits

struct DepthSortAccess {
  static std::vector<std::uint64_t>& a(DepthSortScratch& s) { return s.a_; }
  static std::vector<std::uint64_t>& b(DepthSortScratch& s) { return s.b_; }
};

}  // namespace detail

/// Key-and-payload form: clears `out`, then writes `payload[i]` for every i in 0..count-1, ordered
/// by depth[i] from largest to smallest; equal depths keep their input order, NaN depths come
/// first, -0 equals +0, infinities sort as the largest and smallest numbers. With `payload` null,
/// the payload of item i is i itself (that is `order_back_to_front` below).
///
/// Cost: one read pass computing keys and all three 11-bit digit histograms, then at most three
/// scatter passes (a pass whose digit is the same for every key is skipped). Allocation: `out` and
/// `scratch` grow to `count` (20 bytes per item in all); none once they are that large.
/// Preconditions: `depth` (and `payload` unless null) hold `count` values; count < 2^32.
inline void order_back_to_front(const float* depth, const std::uint32_t* payload, std::size_t count,
                                std::vector<std::uint32_t>& out, DepthSortScratch& scratch) {
  CULLKIT_ASSERT(count <= 0xFFFFFFFFu, "fewer than 2^32 depths");
  CULLKIT_ASSERT(count == 0 || depth != nullptr, "depth holds count values");
  out.resize(count);
  if (count == 0) return;
  auto& buffer_a = detail::DepthSortAccess::a(scratch);
  auto& buffer_b = detail::DepthSortAccess::b(scratch);
  if (buffer_a.size() < count) {
    buffer_a.resize(count);
    buffer_b.resize(count);
  }
  using detail::kRadixPasses;
  using detail::kRadixSize;
  std::uint32_t histogram[kRadixPasses][kRadixSize];
  std::memset(histogram, 0, sizeof histogram);
  // Key in the high half, payload in the low half: each scatter moves one 8-byte item to one place,
  // which keeps half as many write streams open as separate key and payload arrays would.
  std::uint64_t* src = buffer_a.data();
  std::uint64_t* dst = buffer_b.data();
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t k = detail::back_to_front_key(depth[i]);
    const std::uint32_t value = payload ? payload[i] : static_cast<std::uint32_t>(i);
    src[i] = (static_cast<std::uint64_t>(k) << 32) | value;
    ++histogram[0][k & (kRadixSize - 1)];
    ++histogram[1][(k >> 11) & (kRadixSize - 1)];
    ++histogram[2][k >> 22];
  }
  // Passes whose digit is constant move nothing: skip them.
  int active[kRadixPasses];
  int active_count = 0;
  const std::uint32_t first_key = static_cast<std::uint32_t>(src[0] >> 32);
  for (int p = 0; p < kRadixPasses; ++p) {
    if (histogram[p][(first_key >> (11 * p)) & (kRadixSize - 1)] != count) active[active_count++] = p;
  }
  std::uint32_t* const result = out.data();
  for (int a = 0; a < active_count; ++a) {
    const int p = active[a];
    const int shift = 32 + 11 * p;
    std::uint32_t offset[kRadixSize];
    std::uint32_t sum = 0;
    for (std::uint32_t d = 0; d < kRadixSize; ++d) {
      offset[d] = sum;
      sum += histogram[p][d];
    }
    if (a + 1 == active_count) {  // the last pass writes payloads straight into `out`
      for (std::size_t i = 0; i < count; ++i) {
        const std::uint64_t item = src[i];
        result[offset[(item >> shift) & (kRadixSize - 1)]++] = static_cast<std::uint32_t>(item);
      }
      return;
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint64_t item = src[i];
      dst[offset[(item >> shift) & (kRadixSize - 1)]++] = item;
    }
    std::uint64_t* t = src;
    src = dst;
    dst = t;
  }
  // No active pass: every key is equal and the input order is the answer.
  for (std::size_t i = 0; i < count; ++i) result[i] = static_cast<std::uint32_t>(src[i]);
}

/// Clears `order`, then writes 0..count-1 sorted by depth[i] from largest to smallest; equal depths
/// keep their input order; NaN depths come first (in input order); -0 equals +0. Radix sort on the
/// float bits, as the key-and-payload form above. Uses a buffer kept per thread (`thread_local`),
/// so it allocates nothing once warm; pass your own `DepthSortScratch` to control that memory.
/// Thread safety: safe to call from several threads at once (each has its own buffer).
inline void order_back_to_front(const float* depth, std::size_t count, std::vector<std::uint32_t>& order) {
  thread_local DepthSortScratch scratch;
  order_back_to_front(depth, nullptr, count, order, scratch);
}

/// As above with the caller's scratch (no thread-local buffer).
inline void order_back_to_front(const float* depth, std::size_t count, std::vector<std::uint32_t>& order,
                                DepthSortScratch& scratch) {
  order_back_to_front(depth, nullptr, count, order, scratch);
}

}  // namespace cullkit
