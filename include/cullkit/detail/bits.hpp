// cullkit/detail/bits.hpp: the bit-scan, population-count and prefetch primitives that the hot
// loops use, in one place, with a branch per compiler and a portable fallback. Nothing else in the
// library names a compiler intrinsic. Define CULLKIT_PORTABLE_BITS to force the fallbacks (the
// `portable` preset builds and tests the library that way, so the fallbacks are never dead code).
#pragma once

#include <cstdint>

#if !defined(CULLKIT_PORTABLE_BITS) && defined(_MSC_VER) && !defined(__clang__)
#include <intrin.h>
#if defined(_M_X64) || defined(_M_IX86)
#include <xmmintrin.h>
#endif
#endif

namespace cullkit::detail {

/// Index of the lowest set bit. pre: v != 0.
[[nodiscard]] inline int lowest_bit(std::uint64_t v) noexcept {
#if !defined(CULLKIT_PORTABLE_BITS) && (defined(__GNUC__) || defined(__clang__))
  return __builtin_ctzll(v);
#elif !defined(CULLKIT_PORTABLE_BITS) && defined(_MSC_VER) && defined(_M_X64)
  unsigned long i = 0;
  _BitScanForward64(&i, v);
  return static_cast<int>(i);
#else
  // De Bruijn multiply on the isolated lowest bit: branch-free and exact for every non-zero v.
  static constexpr int table[64] = {0,  1,  2,  53, 3,  7,  54, 27, 4,  38, 41, 8,  34, 55, 48, 28,
                                    62, 5,  39, 46, 44, 42, 22, 9,  24, 35, 59, 56, 49, 18, 29, 11,
                                    63, 52, 6,  26, 37, 40, 33, 47, 61, 45, 43, 21, 23, 58, 17, 10,
                                    51, 25, 36, 32, 60, 20, 57, 16, 50, 31, 19, 15, 30, 14, 13, 12};
  return table[((v & (~v + 1u)) * 0x022fdd63cc95386dull) >> 58];
#endif
}

/// Index of the lowest set bit of a 32-bit mask. pre: v != 0.
[[nodiscard]] inline int lowest_bit(std::uint32_t v) noexcept {
#if !defined(CULLKIT_PORTABLE_BITS) && (defined(__GNUC__) || defined(__clang__))
  return __builtin_ctz(v);
#else
  return lowest_bit(static_cast<std::uint64_t>(v));
#endif
}

/// Index of the highest set bit. pre: v != 0.
[[nodiscard]] inline int highest_bit(std::uint64_t v) noexcept {
#if !defined(CULLKIT_PORTABLE_BITS) && (defined(__GNUC__) || defined(__clang__))
  return 63 - __builtin_clzll(v);
#elif !defined(CULLKIT_PORTABLE_BITS) && defined(_MSC_VER) && defined(_M_X64)
  unsigned long i = 0;
  _BitScanReverse64(&i, v);
  return static_cast<int>(i);
#else
  // Smear the highest bit down, then it is the lowest bit of the complement's successor's half.
  v |= v >> 1;
  v |= v >> 2;
  v |= v >> 4;
  v |= v >> 8;
  v |= v >> 16;
  v |= v >> 32;
  return lowest_bit(v ^ (v >> 1));
#endif
}

/// Number of set bits.
[[nodiscard]] inline int popcount(std::uint64_t v) noexcept {
#if !defined(CULLKIT_PORTABLE_BITS) && (defined(__GNUC__) || defined(__clang__)) && defined(__POPCNT__)
  return __builtin_popcountll(v);
#elif !defined(CULLKIT_PORTABLE_BITS) && defined(_MSC_VER) && !defined(__clang__) && defined(_M_X64) && defined(__AVX__)
  return static_cast<int>(__popcnt64(v));
#else
  // Without the POPCNT instruction (a build without -mpopcnt or -march) the compilers' builtin is
  // a library call; this is as fast inline.
  // The parallel sum of bit fields (no table, no instruction-set requirement such as POPCNT).
  v = v - ((v >> 1) & 0x5555555555555555ull);
  v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
  v = (v + (v >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<int>((v * 0x0101010101010101ull) >> 56);
#endif
}

/// A hint that `p` will be read soon; no effect on answers, and none at all where unsupported.
inline void prefetch(const void* p) noexcept {
#if !defined(CULLKIT_PORTABLE_BITS) && (defined(__GNUC__) || defined(__clang__))
  __builtin_prefetch(p);
#elif !defined(CULLKIT_PORTABLE_BITS) && defined(_MSC_VER) && (defined(_M_X64) || defined(_M_IX86))
  _mm_prefetch(static_cast<const char*>(p), _MM_HINT_T0);
#else
  (void)p;
#endif
}

}  // namespace cullkit::detail
