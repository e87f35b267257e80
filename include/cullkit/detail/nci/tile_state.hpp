// cullkit/detail/nci/tile_state.hpp: TileState, the per-pixel state of one screen tile while the
// selection walks it (rays, hits, finishing slices, the tile's beam and depth bounds).
#pragma once

#include <cstdint>
#include <type_traits>

#include <glm/vec3.hpp>

#include "../bits.hpp"
#include "watertight.hpp"

namespace cullkit::detail::nci {

// Per-pixel state of one screen tile of NormalClassIndex::select_visible (about 320 KB: kept in
// NciContext, one per worker, made once and reused across calls; every field a tile reads is set
// by that tile first).
struct TileState {
  // The largest tile edge (NciParams::tile_size is clamped to it; a multiple of 4, the make_beam
  // pre-test's width); pixel (x, y) of a tile is entry y * stride + x of every per-pixel array
  // (below 4096: EdgeBandHit::pixel is 16-bit, a Candidate's rectangle 8-bit), bit x of its row's mask.
  static constexpr int max_tile = 64;
  static constexpr int cap = max_tile * max_tile;
  // The current tile's row pitch: its width rounded up to 4 (rows packed: a tile smaller than
  // max_tile touches no more cache lines, nor fewer cache sets, than it needs).
  int stride = max_tile;
  static_assert(max_tile % 4 == 0 && max_tile <= 64, "row masks hold at most 64 pixels");
  // Entries per per-pixel array: cap plus a pad of 32, so that the arrays (whose sizes would all
  // be multiples of 4 KB) do not all start at the same offset within a page (the ray setup and the
  // finishing loop touch a dozen of them at one index: one L1 cache set otherwise).
  static constexpr int slots = cap + 32;
  // A tile row's pixel set: bit x is pixel x.
  using Mask = std::conditional_t<(max_tile > 32), std::uint64_t, std::uint32_t>;
  static constexpr int mask_bits = 8 * static_cast<int>(sizeof(Mask));
  // Lowest and highest set bit of a non-empty mask.
  [[nodiscard]] static int low_bit(Mask m) noexcept { return detail::lowest_bit(m); }
  [[nodiscard]] static int high_bit(Mask m) noexcept { return detail::highest_bit(m); }
  [[nodiscard]] static Mask bit(int x) noexcept { return Mask{1} << x; }
  // Columns x0..x1 (0 <= x0 <= x1 < max_tile): no shift by the mask's width.
  [[nodiscard]] static Mask columns(int x0, int x1) noexcept {
    return static_cast<Mask>(~Mask{0} >> (mask_bits - 1 - (x1 - x0))) << x0;
  }
  // The pixel rays' directions by component (PixelRays::directions, make_beam's 4-wide
  // pre-test); zero beyond the tile's width up to the next multiple of 4.
  alignas(16) float dx[slots];
  alignas(16) float dy[slots];
  alignas(16) float dz[slots];
  [[nodiscard]] glm::dvec3 direction(int i) const noexcept { return glm::dvec3(dx[i], dy[i], dz[i]); }
  WatertightRay<float> wray[slots];
  float best_t[slots];
  std::uint32_t best[slots];
  // The nearest hit that no edge-rounding question hangs over (a hit within rounding of an edge
  // may be a miss for another float ray tracer, which then sees what lies behind): finishing and
  // the depth rejects use it, so the search goes on behind such hits up to a solid one.
  float solid_t[slots];
  std::uint32_t solid[slots];
  float slope_b[slots], slope_c[slots];
  float t_exit[slots];  // where the ray leaves the inflated scene box (rounded up): nothing beyond
  int finish[slots];    // the walk may stop this ray once it has processed this slice
  bool dirty[slots];    // solid_t changed since `finish` was computed
  bool any_dirty = true;  // some ray became dirty since the walk last looked
  int axis = 2;       // the frame's walk axis
  float dir_a[slots];   // dir[i][axis], read by the finishing test (no per-call component switch)
  double lo_a = 0.0;  // the grid's origin on the walk axis
  double inv_h = 1.0; // 1 / cell edge (finish_slice's first estimate only)
  bool flat[slots];
  // The tile's beam: four planes through the eye (unit normals, inside positive) holding every
  // live ray of the tile up to `beam_eps` (the largest measured violation plus rounding).
  float beam_n[4][3];
  float beam_eps = 0.0f;
  bool beam = false;
  int beam_box[4] = {-1, -1, -1, -1};  // live pixels' rectangle the beam was made for
  float mean_dir[3] = {0.0f, 0.0f, 0.0f};  // the live rays' mean direction (sort key of candidates)
  // Depth bound: per dominant axis k of the watertight test, the range of its scale sz = 1 / d[k]
  // over the tile's live rays (sz_lo > sz_hi: no ray has that axis). A ray's computed t is a
  // convex combination of sz times the corners' k coordinates, so it is at least the smallest
  // such product over the range's ends.
  float sz_lo[3], sz_hi[3];
};

}  // namespace cullkit::detail::nci
