// cullkit/detail/nci/beam.hpp: the beam of a tile: four planes through the eye holding every live
// ray of the tile, made from the live pixels' rectangle and re-made as it shrinks.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "../../config.hpp"
#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif
#include "tile_state.hpp"

namespace cullkit::detail::nci {

using Mask = TileState::Mask;  // one bit per pixel of a tile row

// The beam of the tile's live rays: planes through the eye and consecutive corner rays, then
// measured against every live ray so that the margin covers whatever the projection did.
// The corners are those of the live pixels' bounding rectangle (widened to two pixels where it
// is one wide), so the beam narrows as rays finish; `box` records that rectangle.
// The live pixels' bounding rectangle (x0, y0, x1, y1), widened to two pixels where it is one
// wide; false when no pixel is live or the tile is narrower than two pixels.
inline bool live_box(int tw, int th, const Mask* live, int box[4]) noexcept {
  if (tw < 2 || th < 2) return false;
  int y0 = -1, y1 = -1;
  Mask cols = 0;
  for (int y = 0; y < th; ++y) {
    if (!live[y]) continue;
    if (y0 < 0) y0 = y;
    y1 = y;
    cols |= live[y];
  }
  if (y0 < 0) return false;
  int x0 = TileState::low_bit(cols), x1 = TileState::high_bit(cols);
  if (x0 == x1) x1 < tw - 1 ? ++x1 : --x0;
  if (y0 == y1) y1 < th - 1 ? ++y1 : --y0;
  box[0] = x0;
  box[1] = y0;
  box[2] = x1;
  box[3] = y1;
  return true;
}

inline void make_beam(TileState& r, int tw, int th, const Mask* live) noexcept {
  const int stride = r.stride;  // the tile's row pitch (kept in a register)
  r.beam = false;
  int box[4];
  if (!live_box(tw, th, live, box)) return;
  for (int k = 0; k < 4; ++k) r.beam_box[k] = box[k];
  const int corner[4] = {box[1] * stride + box[0], box[1] * stride + box[2], box[3] * stride + box[2], box[3] * stride + box[0]};
  glm::dvec3 d[4], centre(0.0);
  for (int k = 0; k < 4; ++k) {
    d[k] = r.direction(corner[k]);
    if (!r.wray[corner[k]].valid) return;
    centre += d[k];
  }
  for (int k = 0; k < 4; ++k) {
    glm::dvec3 n = glm::cross(d[k], d[(k + 1) % 4]);
    const double len = glm::length(n);
    if (!(len > 1e-12) || !std::isfinite(len)) return;
    n /= len;
    if (glm::dot(n, centre) < 0.0) n = -n;
    for (int j = 0; j < 3; ++j) r.beam_n[k][j] = static_cast<float>(n[j]);
  }
  double worst = 0.0;
  for (int y = 0; y < th; ++y) {
    Mask bits = live[y];
    if (!bits) continue;
#if CULLKIT_HAS_SSE2
    // Pre-test, 4 rays at a time in float: a ray with n.d > 5e-7 |d|_1 in float for all four
    // planes has exact n.d > 0 (the float dot product is within 3 2^-24 |d|_1 of it, |n| <= 1),
    // so its double value below is not negative and cannot raise `worst`: only the other rays
    // are measured. The same `worst`, bit for bit.
    {
      Mask maybe = 0;
      const __m128 sign = _mm_set1_ps(-0.0f), lim = _mm_set1_ps(5e-7f);
      for (int q = TileState::low_bit(bits) / 4, q_end = TileState::high_bit(bits) / 4; q <= q_end; ++q) {
        if (!((bits >> (4 * q)) & 15u)) continue;
        const int i0 = y * stride + 4 * q;
        const __m128 vx = _mm_load_ps(&r.dx[i0]), vy = _mm_load_ps(&r.dy[i0]), vz = _mm_load_ps(&r.dz[i0]);
        const __m128 dl = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, vx), _mm_andnot_ps(sign, vy)), _mm_andnot_ps(sign, vz));
        const __m128 bound = _mm_mul_ps(lim, dl);
        __m128 doubt = _mm_setzero_ps();
        for (int k = 0; k < 4; ++k) {
          const __m128 v = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(r.beam_n[k][0]), vx),
                                                 _mm_mul_ps(_mm_set1_ps(r.beam_n[k][1]), vy)),
                                      _mm_mul_ps(_mm_set1_ps(r.beam_n[k][2]), vz));
          doubt = _mm_or_ps(doubt, _mm_cmple_ps(v, bound));
        }
        maybe |= static_cast<Mask>(_mm_movemask_ps(doubt)) << (4 * q);
      }
      bits &= maybe;
    }
#endif
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      const glm::dvec3 dir = r.direction(y * stride + x);
      const double dl = std::fabs(dir.x) + std::fabs(dir.y) + std::fabs(dir.z);
      for (int k = 0; k < 4; ++k) {
        const double v = double(r.beam_n[k][0]) * dir.x + double(r.beam_n[k][1]) * dir.y + double(r.beam_n[k][2]) * dir.z;
        if (-v > worst * dl) worst = std::max(worst, -v / std::max(dl, 1e-30));
      }
    }
  }
  // Rounding of the float plane test below (relative to the corner's 1-norm) on top.
  const double eps = worst * 1.01 + 1e-5;
  if (!(eps < 0.25)) return;
  r.beam_eps = static_cast<float>(eps);
  r.beam = true;
}

// Re-makes the beam when the live pixels' rectangle has shrunk since it was made (a beam that
// cannot be made for the smaller rectangle leaves the old one, which still holds every live ray).
inline void narrow_beam(TileState& r, int tw, int th, const Mask* live) noexcept {
  int box[4];
  if (!r.beam || !live_box(tw, th, live, box)) return;
  // Re-made only when the rectangle lost at least half its pixels (the re-make visits every
  // live ray).
  const int area = (box[2] - box[0] + 1) * (box[3] - box[1] + 1);
  const int old_area = (r.beam_box[2] - r.beam_box[0] + 1) * (r.beam_box[3] - r.beam_box[1] + 1);
  if (2 * area > old_area) return;
  float n[4][3];
  std::memcpy(n, r.beam_n, sizeof n);
  const float eps = r.beam_eps;
  int old_box[4];
  std::memcpy(old_box, r.beam_box, sizeof old_box);
  make_beam(r, tw, th, live);
  if (!r.beam) {
    std::memcpy(r.beam_n, n, sizeof n);
    r.beam_eps = eps;
    std::memcpy(r.beam_box, old_box, sizeof old_box);
    r.beam = true;
  }
}

}  // namespace cullkit::detail::nci
