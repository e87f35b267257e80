// cullkit/detail/mesh_occlusion/coverage_rows.hpp: the row kernels of CoverageGrid (coverage.hpp),
// the loops that run over the cells of one grid row: freezing covered cells, accumulating crossings
// (and freezing in the same pass), adding a patch's grid into the union (ending its last band,
// freezing and taking its nearer bounds in the same pass), seeding a patch's covered bits, lowering
// depth bounds along a row and the per-tile minimum. Each has its scalar form and, where the
// compiler targets them, SSE2 and AVX2 forms with the same comparisons and float operations, so the
// answers never depend on the build.
// Included by coverage.hpp after the class; not on its own.
#pragma once

#include <cstddef>
#include <cstdint>

#include "coverage.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

inline std::size_t CoverageGrid::freeze(int j, int a, int b) {
  const std::size_t base = static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
  const std::int32_t* net = net_.data() + base;
  const float* bound = bound_.data() + base;
  float* depth = depth_.data() + base;
  std::uint64_t* frozen = frozen_bits_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(words_);
  std::size_t covered = 0;
  // A cell is covered once its bit is set: by freezing, by a nearer patch bound, or by seed_frozen
  // (whose cells keep depth 0 in a patch's grid), so the bit, not the depth, says it is taken.
  const auto one = [&](int i) {
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    if (net[i] >= 1 && (frozen[i >> 6] & bit) == 0) {
      depth[i] = bound[i];
      frozen[i >> 6] |= bit;
      ++covered;
    }
  };
  int i = a;
#if CULLKIT_COVERAGE_AVX2
  for (; i <= b && (i & 7) != 0; ++i) one(i);
  for (; i + 7 <= b; i += 8)
    covered += freeze8(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(net + i)), i, bound, depth, frozen);
#endif
#if CULLKIT_HAS_SSE2
  // Groups of four aligned on the row (a word of frozen bits holds 16 of them): the same
  // comparisons, four at once.
  for (; i <= b && (i & 3) != 0; ++i) one(i);
  for (; i + 3 <= b; i += 4)
    covered += freeze4(_mm_loadu_si128(reinterpret_cast<const __m128i*>(net + i)), i, bound, depth, frozen);
#endif
  for (; i <= b; ++i) one(i);
  return covered;
}

#if CULLKIT_COVERAGE_AVX2
inline std::size_t CoverageGrid::freeze8(__m256i c, int i, const float* bound, float* depth, std::uint64_t* frozen) {
  const int positive = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(c, _mm256_setzero_si256())));
  const int mask = positive & ~static_cast<int>((frozen[i >> 6] >> (i & 63)) & 0xffu);
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256 fresh = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask), lane_bit), lane_bit));
  _mm256_storeu_ps(depth + i, _mm256_blendv_ps(_mm256_loadu_ps(depth + i), _mm256_loadu_ps(bound + i), fresh));
  frozen[i >> 6] |= static_cast<std::uint64_t>(mask) << (i & 63);
  return bits_in_nibble(mask & 15) + bits_in_nibble(mask >> 4);
}
#endif

#if CULLKIT_HAS_SSE2
inline std::size_t CoverageGrid::freeze4(__m128i c, int i, const float* bound, float* depth, std::uint64_t* frozen) {
  const int positive = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(c, _mm_setzero_si128())));
  const int mask = positive & ~static_cast<int>((frozen[i >> 6] >> (i & 63)) & 0xfu);
  if (mask == 0) return 0;
  const __m128i lane_bit = _mm_setr_epi32(1, 2, 4, 8);
  const __m128 fresh = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(mask), lane_bit), lane_bit));
  const __m128 d = _mm_loadu_ps(depth + i);
  _mm_storeu_ps(depth + i, _mm_or_ps(_mm_and_ps(fresh, _mm_loadu_ps(bound + i)), _mm_andnot_ps(fresh, d)));
  frozen[i >> 6] |= static_cast<std::uint64_t>(mask) << (i & 63);
  return bits_in_nibble(mask);
}
#endif

inline std::uint64_t CoverageGrid::nearer_bits(const float* row, int lo, int hi, float limit) {
  std::uint64_t bits = 0;
  int i = lo;
  const auto one = [&](int k) {
    if (row[k] >= limit) bits |= std::uint64_t{1} << (k & 63);
  };
#if CULLKIT_COVERAGE_AVX2
  const __m256 limit8 = _mm256_set1_ps(limit);
  for (; i + 7 <= hi; i += 8)
    bits |= static_cast<std::uint64_t>(_mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(row + i), limit8, _CMP_GE_OQ)))
            << (i & 63);
#endif
#if CULLKIT_HAS_SSE2
  const __m128 limit4 = _mm_set1_ps(limit);
  for (; i + 3 <= hi; i += 4)
    bits |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_cmpge_ps(_mm_loadu_ps(row + i), limit4))) << (i & 63);
#endif
  for (; i <= hi; ++i) one(i);
  return bits;
}

inline std::size_t CoverageGrid::absorb(CoverageGrid& patch, bool layers) {
  if (patch.dirty_.empty() && patch.used_row_count_ == 0) return 0;
  grow(dirty_, patch.dirty_);
  const bool crossings = patch.band_crossings_;
  std::size_t covered = 0;
  for (int n = 0; n < patch.used_row_count_; ++n) {
    const auto j = static_cast<std::size_t>(patch.used_rows_[static_cast<std::size_t>(n)]);
    const int i0 = patch.used_lo_[j], i1 = patch.used_hi_[j];
    patch.used_lo_[j] = width_;
    patch.used_hi_[j] = -1;
    // Every cell the open band changed is a used cell (`mark` uses it).
    const bool band_row = patch.band_hi_[j] >= 0;
    patch.band_lo_[j] = width_;
    patch.band_hi_[j] = -1;
    AbsorbPass pass{patch, static_cast<int>(j), band_row, band_row && crossings, layers};
    std::int32_t run = 0;
    // The span widened to whole groups of the vector loop (within the row): the patch's cells
    // outside its used ones are empty (no count, crossing, bound or depth), and adding an empty cell
    // changes nothing here (see absorb_span), so the loop needs no cell-by-cell head or tail.
    int a = i0 & ~(row_group - 1), b = std::min(i1 | (row_group - 1), width_ - 1);
    int last = i1;
    for (;;) {
      covered += absorb_span(pass, a, b, run);
      if (run == 0) break;
      // A crossing beyond the last column was dropped: the band's sum is constant on to the row's end.
      last = width_ - 1;
      if (b == last) break;
      a = b + 1;
      b = last;
    }
    grow(dirty_, CellRect{i0, pass.j, last, pass.j});
    grow(patch.dirty_, CellRect{i0, pass.j, last, pass.j});
    use(pass.j, i0, last);
  }
  patch.used_row_count_ = 0;
  patch.band_row_count_ = 0;
  patch.band_crossings_ = false;
  return covered;
}

CULLKIT_FORCEINLINE std::size_t CoverageGrid::absorb_span(const AbsorbPass& pass, int a, int b, std::int32_t& run) {
  CoverageGrid& patch = pass.patch;
  const std::size_t base = static_cast<std::size_t>(pass.j) * static_cast<std::size_t>(width_);
  const std::size_t word_base = static_cast<std::size_t>(pass.j) * static_cast<std::size_t>(words_);
  std::int32_t* net = net_.data() + base;
  float* bound = bound_.data() + base;
  float* depth = depth_.data() + base;
  std::uint64_t* frozen = frozen_bits_.data() + word_base;
  std::int32_t* from_diff = patch.diff_.data() + base;
  std::int32_t* from_net = patch.net_.data() + base;
  float* from_bound = patch.bound_.data() + base;
  float* from_depth = patch.depth_.data() + base;
  std::uint64_t* from_frozen = patch.frozen_bits_.data() + word_base;
  const bool accumulate = pass.accumulate, band = pass.band_row, layers = pass.layers;
  constexpr float empty_bound = std::numeric_limits<float>::infinity();
  std::size_t covered = 0;
  // An empty cell of the patch (no count, crossing, bound or depth) changes nothing in either grid:
  // a cell of this grid counting at least one is covered already (only an open band changes counts,
  // and every band's end and every absorb freezes such cells), its bound stays, a depth of 0 is
  // never nearer, and the patch's cell stays empty.
  //
  // Per cell, in this order: the patch's open band ends (its crossings summed into its count, and
  // the cell freezing in the patch's grid at the patch's bound), then the patch's cell is added
  // into this grid, the cell freezes here at the running bound, takes the patch's bound where that
  // is nearer, and the patch's cell is left empty behind. A cell this grid covers already skips the
  // adding: its count and running bound are never read again (every freeze tests the covered bit
  // first), so only its depth may still change, to the patch's where that is nearer.
  //
  // The AVX2 loop makes every group's stores whatever its masks hold (a blend under an empty mask
  // keeps the cells): which cells freeze or take a nearer bound is data, not a pattern, and a branch
  // on it costs more than the stores. Under SSE2, with no blend instruction, a selection costs three
  // operations and the branches pay (the same stores without them: the city's `absorb` 1.19 times
  // as long). Either takes the short way for a group this grid covers whole (covered cells come in
  // runs), and the SSE2 loop passes over groups the patch left empty.
  const auto one = [&](int i) {
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    if (accumulate) {
      run += from_diff[i];
      from_diff[i] = 0;
      from_net[i] += run;
    }
    if (band && from_net[i] >= 1 && (from_frozen[i >> 6] & bit) == 0) {
      from_depth[i] = from_bound[i];
      from_frozen[i >> 6] |= bit;
    }
    if ((frozen[i >> 6] & bit) == 0) {
      net[i] += from_net[i];
      bound[i] = std::min(bound[i], from_bound[i]);
      if (net[i] >= 1) {
        depth[i] = bound[i];
        frozen[i >> 6] |= bit;
        ++covered;
      }
    }
    if (layers && from_depth[i] > depth[i]) {
      depth[i] = from_depth[i];
      frozen[i >> 6] |= bit;
    }
    from_net[i] = 0;
    from_bound[i] = empty_bound;
    from_depth[i] = 0.0f;
  };
  int i = a;
#if CULLKIT_COVERAGE_AVX2
  for (; i <= b && (i & 7) != 0; ++i) one(i);
  {
    const __m256i zero8 = _mm256_setzero_si256(), last_lane = _mm256_set1_epi32(7);
    const __m256i lane_bit8 = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    const __m256 empty8 = _mm256_set1_ps(empty_bound), zero8_f = _mm256_setzero_ps();
    const auto lanes_of = [&](int mask) {
      return _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(mask), lane_bit8), lane_bit8));
    };
    __m256i carry8 = _mm256_set1_epi32(run);
    for (; i + 7 <= b; i += 8) {
      const auto load_i = [i](const std::int32_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i)); };
      const __m256i own_net = load_i(from_net);
      __m256i own_count = own_net;
      if (accumulate) {
        // A prefix sum within each half, the low half's total added to the high half, plus the
        // carry so far (exact integer sums, as the scalar loop's).
        __m256i d = load_i(from_diff);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(from_diff + i), zero8);
        d = _mm256_add_epi32(d, _mm256_slli_si256(d, 4));
        d = _mm256_add_epi32(d, _mm256_slli_si256(d, 8));
        d = _mm256_add_epi32(d, _mm256_shuffle_epi32(_mm256_permute2x128_si256(d, d, 0x08), 0xFF));
        d = _mm256_add_epi32(d, carry8);
        own_count = _mm256_add_epi32(own_count, d);
        carry8 = _mm256_permutevar8x32_epi32(d, last_lane);
      }
      const __m256 own_bound = _mm256_loadu_ps(from_bound + i);
      __m256 own = _mm256_loadu_ps(from_depth + i);
      if (band) {
        const int positive = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(own_count, zero8)));
        const int mask = positive & ~static_cast<int>((from_frozen[i >> 6] >> (i & 63)) & 0xffu);
        own = _mm256_blendv_ps(own, own_bound, lanes_of(mask));
        from_frozen[i >> 6] |= static_cast<std::uint64_t>(mask) << (i & 63);
      }
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(from_net + i), zero8);
      _mm256_storeu_ps(from_bound + i, empty8);
      _mm256_storeu_ps(from_depth + i, zero8_f);
      if (((frozen[i >> 6] >> (i & 63)) & 0xffu) == 0xffu) {
        // Covered here already: only the depths, each the nearer of the two (max takes its first
        // operand where the comparison holds, as the blend below).
        if (layers) _mm256_storeu_ps(depth + i, _mm256_max_ps(own, _mm256_loadu_ps(depth + i)));
        continue;
      }
      const __m256i c = _mm256_add_epi32(load_i(net), own_count);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(net + i), c);
      const __m256 bd = _mm256_min_ps(own_bound, _mm256_loadu_ps(bound + i));
      _mm256_storeu_ps(bound + i, bd);
      const int positive = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(c, zero8)));
      const int fresh_mask = positive & ~static_cast<int>((frozen[i >> 6] >> (i & 63)) & 0xffu);
      __m256 d = _mm256_blendv_ps(_mm256_loadu_ps(depth + i), bd, lanes_of(fresh_mask));
      covered += bits_in_nibble(fresh_mask & 15) + bits_in_nibble(fresh_mask >> 4);
      int taken = fresh_mask;
      if (layers) {
        const __m256 nearer = _mm256_cmp_ps(own, d, _CMP_GT_OQ);
        d = _mm256_blendv_ps(d, own, nearer);
        taken |= _mm256_movemask_ps(nearer);
      }
      _mm256_storeu_ps(depth + i, d);
      frozen[i >> 6] |= static_cast<std::uint64_t>(taken) << (i & 63);
    }
    run = _mm256_cvtsi256_si32(carry8);
  }
#endif
#if CULLKIT_HAS_SSE2
  for (; i <= b && (i & 3) != 0; ++i) one(i);
  {
    const __m128i zero = _mm_setzero_si128();
    const __m128i lane_bit = _mm_setr_epi32(1, 2, 4, 8);
    const __m128 empty4 = _mm_set1_ps(empty_bound), zero_f = _mm_setzero_ps();
    const auto lanes_of = [&](int mask) {
      return _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(mask), lane_bit), lane_bit));
    };
    const auto select = [](__m128 mask, __m128 yes, __m128 no) { return _mm_or_ps(_mm_and_ps(mask, yes), _mm_andnot_ps(mask, no)); };
    __m128i carry = _mm_set1_epi32(run);
    for (; i + 3 <= b; i += 4) {
      const auto load_i = [i](const std::int32_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + i)); };
      const __m128i own_net = load_i(from_net);
      __m128i own_count = own_net;
      if (accumulate) {
        // An in-register prefix sum (two shifted adds) plus the carry so far.
        __m128i d = load_i(from_diff);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(from_diff + i), zero);
        d = _mm_add_epi32(d, _mm_slli_si128(d, 4));
        d = _mm_add_epi32(d, _mm_slli_si128(d, 8));
        d = _mm_add_epi32(d, carry);
        own_count = _mm_add_epi32(own_count, d);
        carry = _mm_shuffle_epi32(d, 0xFF);
      }
      const int union_frozen = static_cast<int>((frozen[i >> 6] >> (i & 63)) & 0xfu);
      if (union_frozen == 0xf) {
        // Four cells this grid covers already: see the AVX2 loop.
        if (band || layers) {
          __m128 own = _mm_loadu_ps(from_depth + i);
          if (band) {
            const int positive = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(own_count, zero)));
            const int mask = positive & ~static_cast<int>((from_frozen[i >> 6] >> (i & 63)) & 0xfu);
            if (mask != 0) {
              own = select(lanes_of(mask), _mm_loadu_ps(from_bound + i), own);
              from_frozen[i >> 6] |= static_cast<std::uint64_t>(mask) << (i & 63);
            }
          }
          if (layers) {
            const __m128 d = _mm_loadu_ps(depth + i);
            const __m128 nearer = _mm_cmpgt_ps(own, d);
            if (_mm_movemask_ps(nearer) != 0) _mm_storeu_ps(depth + i, select(nearer, own, d));
          }
        }
        _mm_storeu_si128(reinterpret_cast<__m128i*>(from_net + i), zero);
        _mm_storeu_ps(from_bound + i, empty4);
        _mm_storeu_ps(from_depth + i, zero_f);
        continue;
      }
      const __m128 own_bound = _mm_loadu_ps(from_bound + i);
      __m128 own = _mm_loadu_ps(from_depth + i);
      // Four empty cells of the patch: nothing to add, nothing to clear.
      if (_mm_movemask_epi8(_mm_cmpeq_epi32(_mm_or_si128(own_net, own_count), zero)) == 0xffff &&
          _mm_movemask_ps(_mm_and_ps(_mm_cmpeq_ps(own_bound, empty4), _mm_cmpeq_ps(own, zero_f))) == 0xf)
        continue;
      if (band) {
        const int positive = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(own_count, zero)));
        const int mask = positive & ~static_cast<int>((from_frozen[i >> 6] >> (i & 63)) & 0xfu);
        if (mask != 0) {
          own = select(lanes_of(mask), own_bound, own);
          from_frozen[i >> 6] |= static_cast<std::uint64_t>(mask) << (i & 63);
        }
      }
      const __m128i c = _mm_add_epi32(load_i(net), own_count);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(net + i), c);
      // min(bound, from) as std::min takes it: `from` where it is smaller, else `bound`.
      const __m128 bd = _mm_min_ps(own_bound, _mm_loadu_ps(bound + i));
      _mm_storeu_ps(bound + i, bd);
      const int positive = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(c, zero)));
      const int fresh_mask = positive & ~static_cast<int>((frozen[i >> 6] >> (i & 63)) & 0xfu);
      __m128 d = _mm_loadu_ps(depth + i);
      if (fresh_mask != 0) {
        d = select(lanes_of(fresh_mask), bd, d);
        covered += bits_in_nibble(fresh_mask);
      }
      int taken = fresh_mask;
      if (layers) {
        const __m128 nearer = _mm_cmpgt_ps(own, d);
        const int nearer_mask = _mm_movemask_ps(nearer);
        if (nearer_mask != 0) d = select(nearer, own, d);
        taken |= nearer_mask;
      }
      if (taken != 0) {
        _mm_storeu_ps(depth + i, d);
        frozen[i >> 6] |= static_cast<std::uint64_t>(taken) << (i & 63);
      }
      _mm_storeu_si128(reinterpret_cast<__m128i*>(from_net + i), zero);
      _mm_storeu_ps(from_bound + i, empty4);
      _mm_storeu_ps(from_depth + i, zero_f);
    }
    run = _mm_cvtsi128_si32(carry);
  }
#endif
  for (; i <= b; ++i) one(i);
  return covered;
}

inline unsigned CoverageGrid::row_spans4(const TriangleEdges& e, int j, double m, int* i0, int* i1) const {
#if CULLKIT_COVERAGE_AVX2
  // a + b * c as row_span's `e.xa[k] + (y - e.ya[k]) * e.slope[k]` is compiled: fused under FMA.
  const auto mul_add = [](__m256d b, __m256d c, __m256d a) {
#if defined(__FMA__)
    return _mm256_fmadd_pd(b, c, a);
#else
    return _mm256_add_pd(a, _mm256_mul_pd(b, c));
#endif
  };
  const __m256d rows = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(j)), _mm256_setr_pd(0.0, 1.0, 2.0, 3.0));
  const __m256d margin = _mm256_set1_pd(m);
  const __m256d lo = _mm256_sub_pd(rows, margin);
  const __m256d hi = _mm256_add_pd(_mm256_add_pd(rows, _mm256_set1_pd(1.0)), margin);
  __m256d xl = _mm256_set1_pd(HUGE_VAL), xr = _mm256_set1_pd(-HUGE_VAL);
  for (int k = 0; k < 3; ++k) {
    const __m256d ya = _mm256_set1_pd(e.ya[k]), yb = _mm256_set1_pd(e.yb[k]);
    // row_span's `e.yb[k] < lo || e.ya[k] > hi` skips the edge: its negation, NaN included.
    const __m256d meets = _mm256_and_pd(_mm256_cmp_pd(yb, lo, _CMP_NLT_UQ), _mm256_cmp_pd(ya, hi, _CMP_NGT_UQ));
    __m256d x0, x1;
    if (e.yb[k] > e.ya[k]) {
      const __m256d xa = _mm256_set1_pd(e.xa[k]), slope = _mm256_set1_pd(e.slope[k]);
      // std::max(ya, lo) and std::min(yb, hi): the same values as the lanes' max and min (no NaN;
      // equal operands are equal values).
      x0 = mul_add(_mm256_sub_pd(_mm256_max_pd(lo, ya), ya), slope, xa);
      x1 = mul_add(_mm256_sub_pd(_mm256_min_pd(hi, yb), ya), slope, xa);
    } else {
      x0 = _mm256_set1_pd(e.xa[k]);
      x1 = _mm256_set1_pd(e.xb[k]);
    }
    xl = _mm256_blendv_pd(xl, _mm256_min_pd(xl, _mm256_min_pd(x0, x1)), meets);
    xr = _mm256_blendv_pd(xr, _mm256_max_pd(xr, _mm256_max_pd(x0, x1)), meets);
  }
  const __m256d left = _mm256_sub_pd(xl, margin), right = _mm256_add_pd(xr, margin);
  const __m256d zero = _mm256_setzero_pd(), w = _mm256_set1_pd(static_cast<double>(width_));
  // row_span's `!(xl <= xr) || xr + m < 0.0 || xl - m >= width_` rejects the row.
  const __m256d ok = _mm256_and_pd(_mm256_cmp_pd(xl, xr, _CMP_LE_OQ),
                                   _mm256_and_pd(_mm256_cmp_pd(right, zero, _CMP_NLT_UQ), _mm256_cmp_pd(left, w, _CMP_NGE_UQ)));
  // clamp_cell on the rows kept (finite there): below 0 gives 0, from width - 1 on gives width - 1,
  // else the value truncated.
  const __m256d top = _mm256_set1_pd(static_cast<double>(width_ - 1));
  const __m128i first = _mm256_cvttpd_epi32(_mm256_min_pd(_mm256_max_pd(_mm256_blendv_pd(zero, left, ok), zero), top));
  const __m128i last = _mm256_cvttpd_epi32(_mm256_min_pd(_mm256_max_pd(_mm256_blendv_pd(zero, right, ok), zero), top));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(i0), first);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(i1), last);
  return static_cast<unsigned>(_mm256_movemask_pd(ok));
#elif CULLKIT_HAS_SSE2 && !defined(__FMA__)
  // Two rows per register, as the AVX2 form above (no FMA here: row_span's products and sums are
  // not fused either).
  unsigned found = 0;
  const __m128d margin = _mm_set1_pd(m), zero = _mm_setzero_pd(), w = _mm_set1_pd(static_cast<double>(width_));
  const __m128d top = _mm_set1_pd(static_cast<double>(width_ - 1));
  const auto select = [](__m128d mask, __m128d yes, __m128d no) { return _mm_or_pd(_mm_and_pd(mask, yes), _mm_andnot_pd(mask, no)); };
  for (int half = 0; half < 2; ++half) {
    const __m128d rows = _mm_add_pd(_mm_set1_pd(static_cast<double>(j + 2 * half)), _mm_setr_pd(0.0, 1.0));
    const __m128d lo = _mm_sub_pd(rows, margin);
    const __m128d hi = _mm_add_pd(_mm_add_pd(rows, _mm_set1_pd(1.0)), margin);
    __m128d xl = _mm_set1_pd(HUGE_VAL), xr = _mm_set1_pd(-HUGE_VAL);
    for (int k = 0; k < 3; ++k) {
      const __m128d ya = _mm_set1_pd(e.ya[k]), yb = _mm_set1_pd(e.yb[k]);
      const __m128d meets = _mm_and_pd(_mm_cmpnlt_pd(yb, lo), _mm_cmpngt_pd(ya, hi));
      __m128d x0, x1;
      if (e.yb[k] > e.ya[k]) {
        const __m128d xa = _mm_set1_pd(e.xa[k]), slope = _mm_set1_pd(e.slope[k]);
        x0 = _mm_add_pd(xa, _mm_mul_pd(_mm_sub_pd(_mm_max_pd(lo, ya), ya), slope));
        x1 = _mm_add_pd(xa, _mm_mul_pd(_mm_sub_pd(_mm_min_pd(hi, yb), ya), slope));
      } else {
        x0 = _mm_set1_pd(e.xa[k]);
        x1 = _mm_set1_pd(e.xb[k]);
      }
      xl = select(meets, _mm_min_pd(xl, _mm_min_pd(x0, x1)), xl);
      xr = select(meets, _mm_max_pd(xr, _mm_max_pd(x0, x1)), xr);
    }
    const __m128d left = _mm_sub_pd(xl, margin), right = _mm_add_pd(xr, margin);
    const __m128d ok = _mm_and_pd(_mm_cmple_pd(xl, xr), _mm_and_pd(_mm_cmpnlt_pd(right, zero), _mm_cmpnge_pd(left, w)));
    const __m128i first = _mm_cvttpd_epi32(_mm_min_pd(_mm_max_pd(select(ok, left, zero), zero), top));
    const __m128i last = _mm_cvttpd_epi32(_mm_min_pd(_mm_max_pd(select(ok, right, zero), zero), top));
    i0[2 * half] = _mm_cvtsi128_si32(first);
    i0[2 * half + 1] = _mm_cvtsi128_si32(_mm_shuffle_epi32(first, 0x55));
    i1[2 * half] = _mm_cvtsi128_si32(last);
    i1[2 * half + 1] = _mm_cvtsi128_si32(_mm_shuffle_epi32(last, 0x55));
    found |= static_cast<unsigned>(_mm_movemask_pd(ok)) << (2 * half);
  }
  return found;
#else
  unsigned found = 0;
  for (int q = 0; q < 4; ++q)
    if (row_span(e, j + q, m, i0[q], i1[q])) found |= 1u << q;
  return found;
#endif
}

inline float CoverageGrid::tile_minimum(int j0, int j1, int i0, int i1) const {
  float v = std::numeric_limits<float>::infinity();
#if CULLKIT_HAS_SSE2
  static_assert(tile == 8, "a tile row is two groups of four cells");
  if (i1 - i0 == tile) {
    __m128 m = _mm_set1_ps(v);
    for (int j = j0; j < j1; ++j) {
      const float* row = depth_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + i0;
      m = _mm_min_ps(m, _mm_min_ps(_mm_loadu_ps(row), _mm_loadu_ps(row + 4)));
    }
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, 0x4E));  // lanes 2, 3, 0, 1
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, 0xB1));  // lanes 1, 0, 3, 2
    return _mm_cvtss_f32(m);
  }
#endif
  for (int j = j0; j < j1; ++j)
    for (int i = i0; i < i1; ++i)
      v = std::min(v, depth_[static_cast<std::size_t>(j) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(i)]);
  return v;
}

inline void CoverageGrid::lower_row_sloped(float* row, int i0, int i1, int step0, float start, float slope, float lowest) {
  int i = i0;
#if CULLKIT_COVERAGE_AVX2
  // Eight cells at a time, the last 1 to 7 as one masked group (the cells past i1 are neither read
  // nor written): rows run about 9 cells, so a tail of four and then single cells would cost as
  // much as the groups of eight.
  {
    const __m256 low = _mm256_set1_ps(lowest), a = _mm256_set1_ps(slope), s = _mm256_set1_ps(start),
                 eight = _mm256_set1_ps(8.0f);
    __m256 steps = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(step0), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
    for (; i + 7 <= i1; i += 8) {
      const __m256 v = _mm256_max_ps(_mm256_add_ps(s, _mm256_mul_ps(a, steps)), low);
      _mm256_storeu_ps(row + i, _mm256_min_ps(v, _mm256_loadu_ps(row + i)));
      steps = _mm256_add_ps(steps, eight);
    }
    if (i <= i1) {
      const __m256 v = _mm256_max_ps(_mm256_add_ps(s, _mm256_mul_ps(a, steps)), low);
      const __m256i lanes = tail_lanes(i1 - i + 1);
      _mm256_maskstore_ps(row + i, lanes, _mm256_min_ps(v, _mm256_maskload_ps(row + i, lanes)));
      return;
    }
  }
#endif
#if CULLKIT_HAS_SSE2
  if (i + 3 <= i1) {
    const __m128 low = _mm_set1_ps(lowest), a = _mm_set1_ps(slope), s = _mm_set1_ps(start), four = _mm_set1_ps(4.0f);
    __m128 steps = _mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(step0 + (i - i0)), _mm_setr_epi32(0, 1, 2, 3)));
    for (; i + 3 <= i1; i += 4) {
      const __m128 v = _mm_max_ps(_mm_add_ps(s, _mm_mul_ps(a, steps)), low);
      _mm_storeu_ps(row + i, _mm_min_ps(v, _mm_loadu_ps(row + i)));
      steps = _mm_add_ps(steps, four);
    }
  }
#endif
  for (; i <= i1; ++i) {
    const float v = std::max(lowest, start + slope * static_cast<float>(step0 + (i - i0)));
    row[i] = std::min(row[i], v);
  }
}

inline void CoverageGrid::touch_centres(std::int32_t* row, int i0, int i1, const EdgeSides& e) {
  const double qy = e.qy, dx = e.dx, dy = e.dy;
  int i = i0;
#if CULLKIT_COVERAGE_AVX2
  {
    const double along = dx * qy;  // rounded on its own, as in the scalar loop
#if defined(__FMA__)
    // s = dx * qy - dy * qx and tol = near_line + rounding * (|qx| + |qy|) as the scalar loop is
    // compiled under FMA: the second product fused into the difference, the sum's product fused.
    const auto side_of = [](__m256d b, __m256d q, __m256d a) { return _mm256_fnmadd_pd(b, q, a); };
    const auto mul_add = [](__m256d b, __m256d c, __m256d a) { return _mm256_fmadd_pd(b, c, a); };
#else
    const auto side_of = [](__m256d b, __m256d q, __m256d a) { return _mm256_sub_pd(a, _mm256_mul_pd(b, q)); };
    const auto mul_add = [](__m256d b, __m256d c, __m256d a) { return _mm256_add_pd(a, _mm256_mul_pd(b, c)); };
#endif
    const __m256d xa = _mm256_set1_pd(e.xa), half = _mm256_set1_pd(0.5), along4 = _mm256_set1_pd(along);
    const __m256d dy4 = _mm256_set1_pd(dy), near_line = _mm256_set1_pd(e.near_line), rounding = _mm256_set1_pd(e.rounding);
    const __m256d side = _mm256_set1_pd(static_cast<double>(e.side)), zero = _mm256_setzero_pd();
    const __m256d magnitude_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffll));
    const __m256d abs_qy = _mm256_set1_pd(std::fabs(qy));
    const __m256d once = _mm256_set1_pd(static_cast<double>(e.delta)), twice = _mm256_set1_pd(static_cast<double>(2 * e.delta));
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    for (;;) {
      const __m256d qx = _mm256_sub_pd(_mm256_add_pd(_mm256_cvtepi32_pd(_mm_add_epi32(_mm_set1_epi32(i), lane)), half), xa);
      const __m256d s = side_of(dy4, qx, along4);  // orient2d(a, b, centre)
      const __m256d tol = mul_add(_mm256_add_pd(_mm256_and_pd(qx, magnitude_mask), abs_qy), rounding, near_line);
      const __m256d inner = _mm256_and_pd(_mm256_cmp_pd(_mm256_mul_pd(s, side), zero, _CMP_GT_OQ), once);
      const __m256d too_close = _mm256_cmp_pd(_mm256_and_pd(s, magnitude_mask), tol, _CMP_LE_OQ);
      const __m128i weight = _mm256_cvttpd_epi32(_mm256_blendv_pd(inner, twice, too_close));
      __m128i* cells = reinterpret_cast<__m128i*>(row + i);
      if (i + 3 < i1) {
        _mm_storeu_si128(cells, _mm_sub_epi32(_mm_loadu_si128(cells), weight));
        i += 4;
        continue;
      }
      const __m128i lanes = _mm_cmpgt_epi32(_mm_set1_epi32(i1 - i + 1), lane);
      _mm_maskstore_epi32(row + i, lanes, _mm_sub_epi32(_mm_maskload_epi32(row + i, lanes), weight));
      return;
    }
  }
#endif
  for (; i <= i1; ++i) {
    const double qx = i + 0.5 - e.xa;
    const double s = dx * qy - dy * qx;  // orient2d(a, b, centre)
    const double tol = e.near_line + e.rounding * (std::fabs(qx) + std::fabs(qy));
    // Branch-free: which side a centre falls on is data, not a pattern.
    const int inner = s * e.side > 0.0 ? e.delta : 0;
    row[i] -= std::fabs(s) <= tol ? 2 * e.delta : inner;
  }
}

inline void CoverageGrid::lower_row_flat(float* row, int i0, int i1, float lowest) {
  int i = i0;
#if CULLKIT_COVERAGE_AVX2
  const __m256 low8 = _mm256_set1_ps(lowest);
  for (; i + 7 <= i1; i += 8) _mm256_storeu_ps(row + i, _mm256_min_ps(low8, _mm256_loadu_ps(row + i)));
  if (i <= i1) {  // the last 1 to 7 cells, as lower_row_sloped
    const __m256i lanes = tail_lanes(i1 - i + 1);
    _mm256_maskstore_ps(row + i, lanes, _mm256_min_ps(low8, _mm256_maskload_ps(row + i, lanes)));
    return;
  }
#endif
#if CULLKIT_HAS_SSE2
  const __m128 low = _mm_set1_ps(lowest);
  for (; i + 3 <= i1; i += 4) _mm_storeu_ps(row + i, _mm_min_ps(low, _mm_loadu_ps(row + i)));
#endif
  for (; i <= i1; ++i) row[i] = std::min(row[i], lowest);
}

inline std::size_t CoverageGrid::accumulate_freeze_row(int j, int i0, int i1, int& last) {
  const std::size_t base = static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
  std::int32_t* diff = diff_.data() + base;
  std::int32_t* count = net_.data() + base;
  const float* bound = bound_.data() + base;
  float* depth = depth_.data() + base;
  std::uint64_t* frozen = frozen_bits_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(words_);
  std::size_t covered = 0;
  std::int32_t run = 0;
  const auto freeze_cell = [&](int i) {
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    if (count[i] >= 1 && (frozen[i >> 6] & bit) == 0) {
      depth[i] = bound[i];
      frozen[i >> 6] |= bit;
      ++covered;
    }
  };
  const auto one = [&](int i) {
    run += diff[i];
    diff[i] = 0;
    count[i] += run;
    freeze_cell(i);
  };
  const int end = std::min(i1 | (row_group - 1), width_ - 1);
  int i = i0 & ~(row_group - 1);
#if CULLKIT_COVERAGE_AVX2
  // Eight cells at a time: a prefix sum within each half, the low half's total added to the high
  // half, plus the carry so far (exact integer sums, as the scalar loop's).
  for (; i <= end && (i & 7) != 0; ++i) one(i);
  __m256i carry8 = _mm256_set1_epi32(run);
  const __m256i zero8 = _mm256_setzero_si256(), last_lane = _mm256_set1_epi32(7);
  for (; i + 7 <= end; i += 8) {
    __m256i d = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(diff + i));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(diff + i), zero8);
    d = _mm256_add_epi32(d, _mm256_slli_si256(d, 4));
    d = _mm256_add_epi32(d, _mm256_slli_si256(d, 8));
    d = _mm256_add_epi32(d, _mm256_shuffle_epi32(_mm256_permute2x128_si256(d, d, 0x08), 0xFF));
    d = _mm256_add_epi32(d, carry8);
    const __m256i c = _mm256_add_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(count + i)), d);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(count + i), c);
    covered += freeze8(c, i, bound, depth, frozen);
    carry8 = _mm256_permutevar8x32_epi32(d, last_lane);
  }
  run = _mm256_cvtsi256_si32(carry8);
#endif
#if CULLKIT_HAS_SSE2
  // Four cells at a time: an in-register prefix sum (two shifted adds) plus the carry so far.
  for (; i <= end && (i & 3) != 0; ++i) one(i);
  __m128i carry = _mm_set1_epi32(run);
  const __m128i zero = _mm_setzero_si128();
  for (; i + 3 <= end; i += 4) {
    __m128i d = _mm_loadu_si128(reinterpret_cast<const __m128i*>(diff + i));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(diff + i), zero);
    d = _mm_add_epi32(d, _mm_slli_si128(d, 4));
    d = _mm_add_epi32(d, _mm_slli_si128(d, 8));
    d = _mm_add_epi32(d, carry);
    const __m128i c = _mm_add_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(count + i)), d);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(count + i), c);
    covered += freeze4(c, i, bound, depth, frozen);
    carry = _mm_shuffle_epi32(d, 0xFF);
  }
  run = _mm_cvtsi128_si32(carry);
#endif
  for (; i <= end; ++i) one(i);
  if (run == 0) {
    last = i1;
    return covered;
  }
  // Past the band's last crossing the sum is constant: it is added on to the row's end.
  const auto shift = [&](int k) {
    count[k] += run;
    freeze_cell(k);
  };
#if CULLKIT_COVERAGE_AVX2
  for (; i < width_ && (i & 7) != 0; ++i) shift(i);
  const __m256i add8 = _mm256_set1_epi32(run);
  for (; i + 8 <= width_; i += 8) {
    const __m256i c = _mm256_add_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(count + i)), add8);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(count + i), c);
    covered += freeze8(c, i, bound, depth, frozen);
  }
#endif
#if CULLKIT_HAS_SSE2
  for (; i < width_ && (i & 3) != 0; ++i) shift(i);
  const __m128i add = _mm_set1_epi32(run);
  for (; i + 4 <= width_; i += 4) {
    const __m128i c = _mm_add_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(count + i)), add);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(count + i), c);
    covered += freeze4(c, i, bound, depth, frozen);
  }
#endif
  for (; i < width_; ++i) shift(i);
  last = width_ - 1;
  return covered;
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
