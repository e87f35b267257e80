// cullkit/detail/abt/views_merged.hpp: the multi-view walk of AdaptiveBinaryTree::cull_views over
// the views' planes merged into one set (users never name this).
//
// Why. Views drawn in one frame share most of their planes. The two eyes of a headset sit apart
// along a direction that their top, bottom, near and far planes contain, so those planes agree up
// to float rounding; the shadow cascades of one camera have the same four side planes bit for bit.
// Each distinct plane is tested once per node and once per object, four planes (node tests) or
// four objects (leaf tests) at a time, and a view's verdict is read off the bits of its own planes.
// A stereo pair then costs about one walk over eight planes instead of two walks over six, and the
// walk carries one plane mask instead of one per view.
//
// Merging. Two planes merge when each component of their (unit) normals differs by at most
// `merge_tolerance` and their offsets differ by at most `merge_tolerance` of the larger one: two
// eyes' view matrices are built by separate float products, so their shared planes' normals often
// differ in the last bits. A merged plane keeps the first copy's normal and records its `tilt`, the
// largest normal component difference of any copy. It uses its largest offset for the outside
// verdict (a box outside it is outside every copy), its smallest for the inside verdict (a box
// inside it is inside every copy), and the largest |d| in the rounding slack, to which it adds
// 2 * tilt * (|cx| + |cy| + |cz| + ex + ey + ez): a bound on how far any copy's distance of the box
// can differ from the kept normal's. Each verdict is otherwise formed with the operations of the
// single-view rule (Frustum::classify, AbtLeafBoxes::classify_lanes) in the same order, so a view's
// answer holds every object a single cull of that view reports, and is that answer exactly where
// the views' copies of a plane are equal (tilt 0).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "../../config.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/frustum.hpp"
#include "../../geometry/sphere.hpp"
#include "dynamic.hpp"
#include "leaf.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail {

/// The distinct planes of up to 32 views as structure-of-arrays, padded to a multiple of four with
/// planes no mask ever names, and for each view the set of distinct planes it is made of.
class AbtMergedPlanes {
 public:
  static constexpr std::uint32_t capacity = 32;
  /// Offsets within this fraction of each other merge (rounding between two eyes is ~2^-23).
  static constexpr float merge_tolerance = 1.0f / 262144.0f;  // 2^-18

  /// Collects the active planes of `frusta[0, views)`; false when they hold more than `capacity`
  /// distinct planes (the caller then takes the per-view walk).
  [[nodiscard]] bool assign(const Frustum* frusta, std::uint32_t views) noexcept {
    count_ = 0;
    all_ = 0;
    tilted_ = false;
    for (std::uint32_t v = 0; v < views; ++v) {
      planes_of_[v] = 0;
      for (std::uint32_t rest = frusta[v].active_mask(); rest != 0; rest &= rest - 1u) {
        const Plane& p = frusta[v].plane(abt_lowest_bit(rest));
        const std::uint32_t u = find_or_add(p, planes_of_[v]);
        if (u == capacity) return false;
        planes_of_[v] |= std::uint32_t{1} << u;
      }
      all_ |= planes_of_[v];
    }
    for (std::uint32_t u = count_; u % 4 != 0; ++u) {
      nx_[u] = ny_[u] = nz_[u] = d_out_[u] = d_in_[u] = abs_d_[u] = tilt_[u] = 0.0f;
    }
    return true;
  }

  [[nodiscard]] std::uint32_t count() const noexcept { return count_; }
  /// Distinct planes (bits) of view v.
  [[nodiscard]] std::uint32_t planes_of(std::uint32_t v) const noexcept { return planes_of_[v]; }
  /// The planes of the views in `views`.
  [[nodiscard]] std::uint32_t planes_of_views(std::uint32_t views) const noexcept {
    std::uint32_t m = 0;
    for (; views != 0; views &= views - 1u) m |= planes_of_[abt_lowest_bit(views)];
    return m;
  }
  /// The views of `views` that still have a plane in `mask` (the others hold the node whole).
  [[nodiscard]] std::uint32_t straddling(std::uint32_t views, std::uint32_t mask) const noexcept {
    std::uint32_t s = 0;
    for (std::uint32_t rest = views; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      if (planes_of_[v] & mask) s |= std::uint32_t{1} << v;
    }
    return s;
  }
  [[nodiscard]] std::uint32_t all_planes() const noexcept { return all_; }

  [[nodiscard]] const float* nx() const noexcept { return nx_; }
  [[nodiscard]] const float* ny() const noexcept { return ny_; }
  [[nodiscard]] const float* nz() const noexcept { return nz_; }
  [[nodiscard]] const float* d_out() const noexcept { return d_out_; }
  [[nodiscard]] const float* d_in() const noexcept { return d_in_; }
  [[nodiscard]] const float* abs_d() const noexcept { return abs_d_; }
  /// Twice the largest normal component difference between a merged plane's copies (0: all equal).
  [[nodiscard]] const float* tilt2() const noexcept { return tilt_; }
  /// Some merged plane has copies whose normals differ (the tests then add the tilt term).
  [[nodiscard]] bool tilted() const noexcept { return tilted_; }

 private:
  static bool close(float a, float b) noexcept {
    return std::fabs(a - b) <= merge_tolerance * std::fmax(std::fabs(a), std::fabs(b));
  }

  // A plane merges only with another view's: two planes of one view stay two (a degenerate matrix
  // can give a view two nearly equal planes, and one view's answer must stay its single cull's).
  std::uint32_t find_or_add(const Plane& p, std::uint32_t own) noexcept {
    for (std::uint32_t u = 0; u < count_; ++u) {
      if ((own >> u) & 1u) continue;
      const float tilt = std::fmax(std::fabs(nx_[u] - p.normal.x),
                                   std::fmax(std::fabs(ny_[u] - p.normal.y), std::fabs(nz_[u] - p.normal.z)));
      if (!(tilt <= merge_tolerance)) continue;
      if (!close(p.d, d_out_[u]) || !close(p.d, d_in_[u])) continue;
      tilt_[u] = std::fmax(tilt_[u], 2.0f * tilt);
      tilted_ = tilted_ || tilt > 0.0f;
      d_out_[u] = std::fmax(d_out_[u], p.d);
      d_in_[u] = std::fmin(d_in_[u], p.d);
      abs_d_[u] = std::fmax(abs_d_[u], std::fabs(p.d));
      return u;
    }
    if (count_ == capacity) return capacity;
    const std::uint32_t u = count_++;
    nx_[u] = p.normal.x;
    ny_[u] = p.normal.y;
    nz_[u] = p.normal.z;
    d_out_[u] = d_in_[u] = p.d;
    abs_d_[u] = std::fabs(p.d);
    tilt_[u] = 0.0f;
    return u;
  }

  std::uint32_t count_ = 0;
  std::uint32_t all_ = 0;
  bool tilted_ = false;
  std::uint32_t planes_of_[32] = {};
  alignas(16) float nx_[capacity];
  alignas(16) float ny_[capacity];
  alignas(16) float nz_[capacity];
  alignas(16) float d_out_[capacity];
  alignas(16) float d_in_[capacity];
  alignas(16) float abs_d_[capacity];
  alignas(16) float tilt_[capacity];
};

/// The box test of a node (centre c, half extent e) over the planes of `mask`: bits of the planes
/// the box is outside of, and of those it is inside of.
CULLKIT_FORCEINLINE void abt_merged_pass(const AbtMergedPlanes& mp, std::uint32_t mask, const glm::vec3& c,
                                         const glm::vec3& e, std::uint32_t& out, std::uint32_t& in) noexcept {
  out = in = 0;
  // What a tilt of one can move a copy's distance by: the centre's and the extent's components.
  float tilt_reach = 0.0f;
  if (mp.tilted()) {
    tilt_reach = std::fabs(c.x) + std::fabs(c.y) + std::fabs(c.z);
    tilt_reach += e.x + e.y + e.z;
  }
#if CULLKIT_HAS_SSE2
  const __m128 k = _mm_set1_ps(8.0f * std::numeric_limits<float>::epsilon());
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 cx = _mm_set1_ps(c.x), cy = _mm_set1_ps(c.y), cz = _mm_set1_ps(c.z);
  const __m128 reach = _mm_set1_ps(tilt_reach);
  const bool tilted = mp.tilted();
  for (std::uint32_t q = 0; q * 4 < mp.count(); ++q) {
    if (((mask >> (4 * q)) & 0xFu) == 0) continue;
    const __m128 nx = _mm_load_ps(mp.nx() + 4 * q), ny = _mm_load_ps(mp.ny() + 4 * q);
    const __m128 nz = _mm_load_ps(mp.nz() + 4 * q);
    const __m128 px = _mm_mul_ps(nx, cx), py = _mm_mul_ps(ny, cy), pz = _mm_mul_ps(nz, cz);
    const __m128 s = _mm_add_ps(_mm_add_ps(px, py), pz);
    const __m128 mag = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, px), _mm_andnot_ps(sign, py)), _mm_andnot_ps(sign, pz));
    const __m128 r = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_andnot_ps(sign, nx), _mm_set1_ps(e.x)),
                                           _mm_mul_ps(_mm_andnot_ps(sign, ny), _mm_set1_ps(e.y))),
                                _mm_mul_ps(_mm_andnot_ps(sign, nz), _mm_set1_ps(e.z)));
    __m128 slack = _mm_mul_ps(_mm_add_ps(_mm_add_ps(mag, _mm_load_ps(mp.abs_d() + 4 * q)), r), k);
    if (tilted) slack = _mm_add_ps(slack, _mm_mul_ps(_mm_load_ps(mp.tilt2() + 4 * q), reach));
    const __m128 far_side = _mm_add_ps(_mm_add_ps(s, _mm_load_ps(mp.d_out() + 4 * q)), r);
    const __m128 near_side = _mm_sub_ps(_mm_add_ps(s, _mm_load_ps(mp.d_in() + 4 * q)), r);
    out |= static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(far_side, _mm_xor_ps(slack, sign)))) << (4 * q);
    in |= static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmpge_ps(near_side, slack))) << (4 * q);
  }
#else
  constexpr float k = 8.0f * std::numeric_limits<float>::epsilon();
  for (std::uint32_t rest = mask; rest != 0; rest &= rest - 1u) {
    const int u = abt_lowest_bit(rest);
    const float nx = mp.nx()[u], ny = mp.ny()[u], nz = mp.nz()[u];
    const float px = nx * c.x, py = ny * c.y, pz = nz * c.z;
    const float s = px + py + pz;
    const float r = std::fabs(nx) * e.x + std::fabs(ny) * e.y + std::fabs(nz) * e.z;
    const float slack = (std::fabs(px) + std::fabs(py) + std::fabs(pz) + mp.abs_d()[u] + r) * k + mp.tilt2()[u] * tilt_reach;
    if ((s + mp.d_out()[u]) + r < -slack) out |= std::uint32_t{1} << u;
    if ((s + mp.d_in()[u]) - r >= slack) in |= std::uint32_t{1} << u;
  }
#endif
  out &= mask;
  in &= mask;
}

/// The node test for every view of `alive` at once, by the node's box only: the single-view walk
/// tries the bounding sphere first because it is cheaper than the box for one plane at a time, but
/// four planes at once cost the same either way, and the box's verdicts are the tighter (measured:
/// the sphere pass made a stereo cull 8 to 10 % slower). Returns the views not outside the node;
/// `mask` loses the planes the node is inside of and the planes no surviving view is made of.
CULLKIT_FORCEINLINE std::uint32_t abt_merged_node(const AbtMergedPlanes& mp, const Aabb& box, const Sphere& sphere,
                                                  std::uint32_t alive, std::uint32_t& mask) noexcept {
  if (mask == 0) return alive;
  if (!(sphere.radius >= 0.0f)) {  // an empty node is outside every view it is not wholly inside
    alive &= ~mp.straddling(alive, mask);
    mask &= mp.planes_of_views(alive);
    return alive;
  }
  const glm::vec3 c = (box.min + box.max) * 0.5f;
  const glm::vec3 e = (box.max - box.min) * 0.5f;
  std::uint32_t outside = 0, in = 0;
  abt_merged_pass(mp, mask, c, e, outside, in);
  mask &= ~in;
  if (outside != 0) {
    for (std::uint32_t rest = alive; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      if (mp.planes_of(std::uint32_t(v)) & outside) alive &= ~(std::uint32_t{1} << v);
    }
  }
  mask &= mp.planes_of_views(alive);
  return alive;
}

/// Leaf test: bit i of plane_out[u] set when object base + i is outside merged plane u, for the
/// planes of `planes`, 16 objects from `base` (the SoA leaf test's rule with the outside offset).
inline void abt_merged_lanes(const AbtMergedPlanes& mp, const AbtLeafBoxes& boxes, std::uint32_t base,
                             std::uint32_t planes, std::uint32_t* plane_out) noexcept {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
  const float* col[6];
  for (int k = 0; k < 6; ++k) col[k] = boxes.column(k) + base;
  // Per lane, what a tilt of one can move a copy's distance by (see AbtMergedPlanes).
  alignas(16) float reach[lanes] = {};
  const bool tilted = mp.tilted();
  if (tilted)
    for (std::uint32_t i = 0; i < lanes; ++i)
      reach[i] = std::fabs(col[0][i]) + std::fabs(col[1][i]) + std::fabs(col[2][i]) + col[3][i] + col[4][i] + col[5][i];
#if CULLKIT_HAS_SSE2
  const __m128 k = _mm_set1_ps(8.0f * std::numeric_limits<float>::epsilon());
  const __m128 sign = _mm_set1_ps(-0.0f);
  for (; planes != 0; planes &= planes - 1u) {
    const int u = abt_lowest_bit(planes);
    const __m128 nx = _mm_set1_ps(mp.nx()[u]), ny = _mm_set1_ps(mp.ny()[u]), nz = _mm_set1_ps(mp.nz()[u]);
    const __m128 ax = _mm_andnot_ps(sign, nx), ay = _mm_andnot_ps(sign, ny), az = _mm_andnot_ps(sign, nz);
    const __m128 d = _mm_set1_ps(mp.d_out()[u]), ad = _mm_set1_ps(mp.abs_d()[u]), tilt = _mm_set1_ps(mp.tilt2()[u]);
    std::uint32_t bits = 0;
    for (std::uint32_t q = 0; q < lanes / 4; ++q) {
      const std::uint32_t o = 4 * q;
      const __m128 px = _mm_mul_ps(nx, _mm_loadu_ps(col[0] + o)), py = _mm_mul_ps(ny, _mm_loadu_ps(col[1] + o));
      const __m128 pz = _mm_mul_ps(nz, _mm_loadu_ps(col[2] + o));
      const __m128 dc = _mm_add_ps(_mm_add_ps(_mm_add_ps(px, py), pz), d);
      const __m128 r = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, _mm_loadu_ps(col[3] + o)), _mm_mul_ps(ay, _mm_loadu_ps(col[4] + o))),
                                  _mm_mul_ps(az, _mm_loadu_ps(col[5] + o)));
      const __m128 mag = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, px), _mm_andnot_ps(sign, py)), _mm_andnot_ps(sign, pz));
      __m128 slack = _mm_mul_ps(_mm_add_ps(_mm_add_ps(mag, ad), r), k);
      if (tilted) slack = _mm_add_ps(slack, _mm_mul_ps(tilt, _mm_load_ps(reach + o)));
      bits |= static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(_mm_add_ps(dc, r), _mm_xor_ps(slack, sign)))) << o;
    }
    plane_out[u] = bits;
  }
#else
  constexpr float k = 8.0f * std::numeric_limits<float>::epsilon();
  for (; planes != 0; planes &= planes - 1u) {
    const int u = abt_lowest_bit(planes);
    const float nx = mp.nx()[u], ny = mp.ny()[u], nz = mp.nz()[u], d = mp.d_out()[u], ad = mp.abs_d()[u];
    const float tilt = mp.tilt2()[u];
    std::uint32_t bits = 0;
    for (std::uint32_t i = 0; i < lanes; ++i) {
      const float px = nx * col[0][i], py = ny * col[1][i], pz = nz * col[2][i];
      const float dc = px + py + pz + d;
      const float r = std::fabs(nx) * col[3][i] + std::fabs(ny) * col[4][i] + std::fabs(nz) * col[5][i];
      const float slack = (std::fabs(px) + std::fabs(py) + std::fabs(pz) + ad + r) * k + tilt * reach[i];
      bits |= static_cast<std::uint32_t>(dc + r < -slack) << i;
    }
    plane_out[u] = bits;
  }
#endif
}

/// lane_bits[i] = `inside_views` | (bit v for every view v of `straddling` whose `outside[v]` has
/// bit i clear), for the 16 lanes.
CULLKIT_FORCEINLINE void abt_transpose_lanes(std::uint32_t straddling, const std::uint32_t* outside,
                                             std::uint32_t inside_views, std::uint32_t* lane_bits) noexcept {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
#if CULLKIT_HAS_SSE2
  __m128i acc[lanes / 4];
  const __m128i select[lanes / 4] = {_mm_setr_epi32(1, 2, 4, 8), _mm_setr_epi32(16, 32, 64, 128),
                                     _mm_setr_epi32(256, 512, 1024, 2048), _mm_setr_epi32(4096, 8192, 16384, 32768)};
  for (std::uint32_t q = 0; q < lanes / 4; ++q) acc[q] = _mm_set1_epi32(static_cast<int>(inside_views));
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    const __m128i out = _mm_set1_epi32(static_cast<int>(outside[v]));
    const __m128i bit = _mm_set1_epi32(static_cast<int>(std::uint32_t{1} << v));
    for (std::uint32_t q = 0; q < lanes / 4; ++q) {
      const __m128i in_view = _mm_cmpeq_epi32(_mm_and_si128(out, select[q]), _mm_setzero_si128());
      acc[q] = _mm_or_si128(acc[q], _mm_and_si128(in_view, bit));
    }
  }
  for (std::uint32_t q = 0; q < lanes / 4; ++q) _mm_storeu_si128(reinterpret_cast<__m128i*>(lane_bits + 4 * q), acc[q]);
#else
  for (std::uint32_t i = 0; i < lanes; ++i) lane_bits[i] = inside_views;
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
    const int v = abt_lowest_bit(rest);
    for (std::uint32_t i = 0; i < lanes; ++i) lane_bits[i] |= ((~outside[v] >> i) & 1u) << v;
  }
#endif
}

/// The output of a multi-view cull: object ids and their view bits, staged in two small arrays and
/// appended to the caller's vectors a block at a time. Appending each object to both vectors costs
/// two capacity checks whose pointers the compiler must reload after every store (the vectors may
/// alias); sizing the vectors ahead costs a zero fill as large as the output.
class AbtViewsOutput {
 public:
  static constexpr std::size_t block = 256;

  AbtViewsOutput(std::vector<std::uint32_t>& ids, std::vector<std::uint32_t>& bits) noexcept : ids_(ids), bits_(bits) {}
  AbtViewsOutput(const AbtViewsOutput&) = delete;
  AbtViewsOutput& operator=(const AbtViewsOutput&) = delete;

  /// Room for `count` (at most `block`) more entries through `put`.
  CULLKIT_FORCEINLINE void reserve_more(std::size_t count) {
    if (staged_ + count > block) flush();
  }
  /// Appends one entry; pre: room was reserved.
  CULLKIT_FORCEINLINE void put(std::uint32_t id, std::uint32_t views) noexcept {
    staged_ids_[staged_] = id;
    staged_bits_[staged_] = views;
    ++staged_;
  }
  /// Appends the ids of positions [b, e) of `order`, all with the view bits `views`.
  void put_range(const std::uint32_t* order, std::uint32_t b, std::uint32_t e, std::uint32_t views) {
    const std::size_t count = e - b;
    if (count <= 16) {
      reserve_more(count);
      for (std::uint32_t i = b; i < e; ++i) put(order[i], views);
      return;
    }
    flush();
    ids_.insert(ids_.end(), order + b, order + e);
    fill(staged_bits_, std::min(count, block), views);
    for (std::size_t done = 0; done < count; done += block)
      bits_.insert(bits_.end(), staged_bits_, staged_bits_ + std::min(block, count - done));
  }
  /// Appends what is staged.
  void finish() { flush(); }

 private:
  void flush() {
    ids_.insert(ids_.end(), staged_ids_, staged_ids_ + staged_);
    bits_.insert(bits_.end(), staged_bits_, staged_bits_ + staged_);
    staged_ = 0;
  }
  static void fill(std::uint32_t* bits, std::size_t count, std::uint32_t views) noexcept {
    std::size_t i = 0;
#if CULLKIT_HAS_SSE2
    const __m128i value = _mm_set1_epi32(static_cast<int>(views));
    for (; i + 4 <= count; i += 4) _mm_storeu_si128(reinterpret_cast<__m128i*>(bits + i), value);
#endif
    for (; i < count; ++i) bits[i] = views;
  }

  std::vector<std::uint32_t>& ids_;
  std::vector<std::uint32_t>& bits_;
  std::size_t staged_ = 0;
  std::uint32_t staged_ids_[block];
  std::uint32_t staged_bits_[block];
};

/// The output of one lane group of a straddling range: every live object in [base, min(base +
/// 16, end)) that a view keeps (a view of `inside_views`, or one of `straddling` whose outside[v]
/// has its bit clear), with its view bits.
CULLKIT_FORCEINLINE void abt_emit_lanes(std::uint32_t base, std::uint32_t end, std::uint32_t straddling,
                                        const std::uint32_t* outside, std::uint32_t inside_views,
                                        const std::uint32_t* order, const AbtDynamic& dyn, AbtViewsOutput& out) {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
  constexpr std::uint32_t all_lanes = (std::uint32_t{1} << lanes) - 1u;
  const std::uint32_t valid = end - base < lanes ? (std::uint32_t{1} << (end - base)) - 1u : all_lanes;
  std::uint32_t any = inside_views != 0 ? valid : 0u;
  for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) any |= ~outside[abt_lowest_bit(rest)];
  any &= valid & ~dyn.holes16(base);
  if (any == 0) return;
  std::uint32_t lane_bits[lanes];
  abt_transpose_lanes(straddling, outside, inside_views, lane_bits);
  out.reserve_more(lanes);
  for (; any != 0; any &= any - 1u) {
    const int i = abt_lowest_bit(any);
    out.put(order[base + std::uint32_t(i)], lane_bits[i]);
  }
}

/// The objects of [begin, end) (a straddling leaf, a small subtree, or the pending part): one
/// output entry per object that some view of `alive` keeps, with its view bits. Views of `alive`
/// without a plane in `mask` hold every object.
inline void abt_merged_leaf(const AbtMergedPlanes& mp, const AbtLeafBoxes& boxes, std::uint32_t alive,
                            std::uint32_t mask, std::uint32_t begin, std::uint32_t end, const std::uint32_t* order,
                            const AbtDynamic& dyn, AbtViewsOutput& out) {
  constexpr std::uint32_t lanes = AbtLeafBoxes::lanes;
  const std::uint32_t straddling = mp.straddling(alive, mask);
  const std::uint32_t inside_views = alive & ~straddling;
  std::uint32_t plane_out[AbtMergedPlanes::capacity];
  std::uint32_t outside[32];
  for (std::uint32_t base = begin; base < end; base += lanes) {
    abt_merged_lanes(mp, boxes, base, mask, plane_out);
    for (std::uint32_t rest = straddling; rest != 0; rest &= rest - 1u) {
      const int v = abt_lowest_bit(rest);
      std::uint32_t o = 0;
      for (std::uint32_t p = mp.planes_of(std::uint32_t(v)) & mask; p != 0; p &= p - 1u) o |= plane_out[abt_lowest_bit(p)];
      outside[v] = o;
    }
    abt_emit_lanes(base, end, straddling, outside, inside_views, order, dyn, out);
  }
}

/// The whole walk over a tree's arrays for the views of `mp` (`views` in [1, 32]); `StackSize`
/// bounds the depth. Objects inserted since the last rebuild are tested first, one by one.
template <std::uint32_t StackSize>
void abt_cull_views_merged(const AbtMergedPlanes& mp, std::uint32_t views, const std::vector<AbtNode>& tree,
                           const std::vector<std::uint32_t>& order_v, const AbtLeafBoxes& boxes,
                           const AbtDynamic& dyn, std::uint32_t scan_below, AbtViewsOutput& out) {
  const std::uint32_t all = views >= 32 ? ~std::uint32_t{0} : ((std::uint32_t{1} << views) - 1u);
  const std::uint32_t* order = order_v.data();
  const auto n = static_cast<std::uint32_t>(order_v.size());
  if (dyn.tree_end < n) abt_merged_leaf(mp, boxes, all, mp.all_planes(), dyn.tree_end, n, order, dyn, out);
  if (tree.empty()) return;
  const AbtNode* nodes = tree.data();
  struct Entry {
    std::uint32_t node, alive, mask;
  };
  Entry stack[StackSize];
  std::uint32_t top = 0;
  stack[top++] = Entry{0, all, mp.all_planes()};
  while (top > 0) {
    const Entry entry = stack[--top];
    const AbtNode& node = nodes[entry.node];
    std::uint32_t mask = entry.mask;
    const std::uint32_t alive = abt_merged_node(mp, node.bounds, node.sphere, entry.alive, mask);
    if (alive == 0) continue;
    if (mask == 0) {  // inside every view still alive: one range, one set of bits
      const auto emit = [&](std::uint32_t b, std::uint32_t e) {
        out.put_range(order, b, e, alive);
        return true;
      };
      if (!dyn.node_has_holes(entry.node)) emit(node.begin, node.end);
      else dyn.live_runs(node.begin, node.end, emit);
      continue;
    }
    if (node.is_leaf() || node.count() <= scan_below) {
      abt_merged_leaf(mp, boxes, alive, mask, node.begin, node.end, order, dyn, out);
      continue;
    }
    stack[top++] = Entry{node.left + 1, alive, mask};
    stack[top++] = Entry{node.left, alive, mask};
  }
}

}  // namespace cullkit::detail
