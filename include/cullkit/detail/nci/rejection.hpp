// cullkit/detail/nci/rejection.hpp: the cheap tests that keep a triangle (or a chunk of cell
// entries) away from the ray test of a tile: beam planes, screen rectangles, live pixels, depth
// bounds, corner-ray planes and the 2D footprint.
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
#include "beam.hpp"
#include "context.hpp"
#include "index_data.hpp"
#include "tolerances.hpp"
#include "view.hpp"

namespace cullkit::detail::nci {

// A cached screen rectangle clipped to the tile at (x0, y0) of tw x th pixels: the tile-local
// rectangle rx0..rx1 x ry0..ry1 and its column mask `span`. False when the rectangle is empty, off
// the tile, or covers no live pixel (`live`: one bit mask per tile row).
[[nodiscard]] inline bool live_under(const Rect& rect, int x0, int y0, int tw, int th,
                                     const Mask* live, int& rx0, int& ry0, int& rx1, int& ry1,
                                     Mask& span) noexcept {
  if (rect.x0 > rect.x1) return false;
  rx0 = 0, ry0 = 0, rx1 = tw - 1, ry1 = th - 1;
  if (rect.x0 != Rect::full) {
    const int lx0 = rect.x0 - x0, lx1 = rect.x1 - x0, ly0 = rect.y0 - y0, ly1 = rect.y1 - y0;
    if (lx1 < 0 || ly1 < 0 || lx0 > tw - 1 || ly0 > th - 1) return false;
    rx0 = std::max(0, lx0);
    rx1 = std::min(tw - 1, lx1);
    ry0 = std::max(0, ly0);
    ry1 = std::min(th - 1, ly1);
  }
  span = TileState::columns(rx0, rx1);
  Mask under = 0;
  for (int y = ry0; y <= ry1; ++y) under |= live[y] & span;
  return under != 0;
}

// Whether every ray that would test the triangle (live, under its rectangle) already holds a
// hit strictly nearer than any t the watertight test can compute for it: a lower bound on that
// t (see TileState::sz_lo) times (1 - 1e-6), against the farthest of those rays' hits. The
// computed t is tt / det with tt and det sums of non-negative products, so it is at least the
// bound times (1 - 8 2^-24); the margin covers that, and strictness keeps ties (lower index
// wins) with the ray test. Such a triangle is not tested at all.
// `qlo` and `qhi` bound the corners' coordinates relative to the eye as the ray test computes
// them (float differences; rounding is monotone, so the box of the float corners bounds them).
[[nodiscard]] inline bool behind_hits(const TileState& r, const float qlo[3], const float qhi[3], int ry0, int ry1,
                                      Mask span, const Mask* live) noexcept {
  const int stride = r.stride;  // the tile's row pitch (kept in a register)
  double bound = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (r.sz_lo[k] > r.sz_hi[k]) continue;
    const double lo = r.sz_lo[k], hi = r.sz_hi[k];
    bound = std::min({bound, lo * double(qlo[k]), lo * double(qhi[k]), hi * double(qlo[k]), hi * double(qhi[k])});
  }
  bound *= 1.0 - tolerance::float_relative;
  if (!(bound > 1e-30) || !std::isfinite(bound)) return false;
  for (int y = ry0; y <= ry1; ++y) {
    Mask bits = live[y] & span;
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      if (!(double(r.solid_t[y * stride + x]) < bound)) return false;
    }
  }
  return true;
}

// Whether the box (min xyz, max xyz) lies wholly outside one plane of the tile's beam with the
// margin of outside_beam (then so does every triangle inside it): the largest n.x + eps |x|_1
// over the box, x relative to the eye, is below zero. In double with a 1e-12 relative slack, so
// the sign is exact for the float data.
[[nodiscard]] inline bool chunk_outside_beam(const TileState& r, const float* box, const ViewSetup& f) noexcept {
  double lo[3], hi[3], l1 = 0.0, gap[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = double(box[a]) - f.eye[a];
    hi[a] = double(box[3 + a]) - f.eye[a];
    l1 += std::max(std::fabs(lo[a]), std::fabs(hi[a]));
    gap[a] = std::max({lo[a], -hi[a], 0.0});
  }
  if (near_eye(gap[0], gap[1], gap[2])) return false;  // may hold a corner (nearly) at the eye
  const double e = double(r.beam_eps) + 1e-12;
  for (int j = 0; j < 4; ++j) {
    const float* n = r.beam_n[j];
    double top = 0.0;
    for (int a = 0; a < 3; ++a) top += std::max(double(n[a]) * lo[a], double(n[a]) * hi[a]);
    if (top + e * l1 < 0.0) return true;
  }
  return false;
}

// Whether no live ray of the tile can take a hit from chunk j: its box's screen rectangle
// (cached per frame and thread) covers no live pixel of the tile, or every live ray under it
// already holds a hit strictly nearer than any t the ray test could give a point of the box.
[[nodiscard]] inline bool chunk_hidden(const IndexData& data, const ViewSetup& f, std::uint32_t j, int x0, int y0, int tw, int th,
                                const Mask* live, const TileState& r, Worker& worker) noexcept {
  const float* box = &data.chunk_box[6 * std::size_t{j}];
  auto& slot = worker.chunk[j];
  if (slot.epoch != worker.frame_epoch) {
    slot.epoch = worker.frame_epoch;
    glm::vec3 corner[8];
    for (int k = 0; k < 8; ++k)
      corner[k] = glm::vec3(box[(k & 1) ? 3 : 0], box[(k & 2) ? 4 : 1], box[(k & 4) ? 5 : 2]);
    slot.rect = project_rect(f, corner, 8);
  }
  int rx0, ry0, rx1, ry1;
  Mask span;
  if (!live_under(slot.rect, x0, y0, tw, th, live, rx0, ry0, rx1, ry1, span)) return true;  // no live pixel
  const float qlo[3] = {box[0] - f.eye_f.x, box[1] - f.eye_f.y, box[2] - f.eye_f.z};
  const float qhi[3] = {box[3] - f.eye_f.x, box[4] - f.eye_f.y, box[5] - f.eye_f.z};
  return behind_hits(r, qlo, qhi, ry0, ry1, span, live);
}

// Whether triangle `tri` lies wholly outside one plane of the tile's beam with margin: every
// corner x (relative to the eye, in float as the ray test takes it) has n.x + eps |x|_1 < 0.
// That set is convex, so it holds the whole triangle; a ray direction d (unit) with
// n.d >= -eps |d|_1 meets no point of it.
[[nodiscard]] inline bool outside_beam(const IndexData& data, const TileState& r, std::uint32_t tri, const ViewSetup& f) noexcept {
  float x[3][3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = data.corner(tri, k);
    x[k][0] = p.x - f.eye_f.x;
    x[k][1] = p.y - f.eye_f.y;
    x[k][2] = p.z - f.eye_f.z;
    if (near_eye(x[k][0], x[k][1], x[k][2])) return false;
  }
  const float e = r.beam_eps;
  for (int j = 0; j < 4; ++j) {
    const float* n = r.beam_n[j];
    bool out = true;
    for (int k = 0; k < 3 && out; ++k) {
      const float l1 = std::fabs(x[k][0]) + std::fabs(x[k][1]) + std::fabs(x[k][2]);
      out = n[0] * x[k][0] + n[1] * x[k][1] + n[2] * x[k][2] + e * l1 < 0.0f;
    }
    if (out) return true;
  }
  return false;
}

// Whether the triangle lies wholly beside the pixel rectangle [rx0, rx1] x [ry0, ry1] of the tile:
// all four corner rays outside the plane through the eye and one of its edges, by a margin of
// 1e-5 (relative). With one target plane for the whole screen (affine_rays) the pixel rays'
// directions are positive multiples of an affine function of the pixel position, so every pixel ray of the
// rectangle is a positive combination of the corner rays and lies outside that plane as well;
// the margin covers the float rounding of the directions and of the ray test (about 1e-7).
[[nodiscard]] inline bool beside_rect(const TileState& r, const float a[3], const float b[3], const float c[3], int rx0,
                                      int ry0, int rx1, int ry1) noexcept {
  const int stride = r.stride;  // the tile's row pitch (kept in a register)
  const glm::dvec3 p[3] = {glm::dvec3(a[0], a[1], a[2]), glm::dvec3(b[0], b[1], b[2]), glm::dvec3(c[0], c[1], c[2])};
  for (const glm::dvec3& q : p)
    if (near_eye(q.x, q.y, q.z)) return false;
  const int corner[4] = {ry0 * stride + rx0, ry0 * stride + rx1, ry1 * stride + rx1, ry1 * stride + rx0};
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3 n = glm::cross(p[k], p[(k + 1) % 3]);
    const double side = glm::dot(n, p[(k + 2) % 3]);  // the inside holds the third corner
    const double len = glm::length(n);
    if (!(std::fabs(side) > 0.0) || !(len > 0.0) || !std::isfinite(side) || !std::isfinite(len)) continue;
    const glm::dvec3 m = side > 0.0 ? n : -n;
    bool out = true;
    for (int j = 0; j < 4 && out; ++j) {
      const glm::dvec3 d = r.direction(corner[j]);
      out = glm::dot(m, d) < -1e-5 * len * glm::length(d);
    }
    if (out) return true;
  }
  return false;
}

// The 2D footprint pre-test: which live pixels of `bits` (rows ry0..ry1 of the
// tile at (x0, y0)) have their centre inside the projected triangle grown by a margin; only
// those rays can hit it. False when the test does not apply (a corner not strictly in front of
// the eye, a projection that is not finite or has no area): then every ray is tested as before.
// Why a skipped ray cannot hit (the watertight test stays the only hit decision):
//  * Exact geometry: the ray through a pixel centre q meets the triangle iff q lies in the
//    projection of the triangle from the eye onto the target plane (PixelRays aims at that plane,
//    and with every corner in front the projection of the triangle is the triangle of the
//    projected corners).
//  * The float ray test differs from the exact one by (a) angular errors of a few ulp: the unit
//    direction rounded to float, the shear constants d[kx] / d[kz], the corners' float offsets
//    from the eye and the sheared coordinates (each relative error <= 2^-24 of a length at most
//    sqrt(3) times the depth along the ray, together well below 1e-6 rad); at most 25,000 pixels
//    per radian (ViewSetup::footprint) makes that < 0.025 pixel, inside the margin m = 0.05 pixel
//    per axis (the screen rectangles' margin ViewSetup::margin, which adds the ray test's edge band
//    so near misses are tested too; an edge grows by m times the 1-norm of its normal); (b) the rounding of the edge products cx * by - cy * bx, at most about 4 * 2^-24 |B| |C|:
//    in pixel units (the map from the shear plane to the screen is a projective map close to a
//    similarity near the ray, condition number well below 10) at most 1e-5 R^2, R bounding the
//    distance from a tested pixel centre to the corners; an edge grows by that much too (more
//    for short edges: the distance slack is 1e-5 R^2 / length). The double arithmetic here adds
//    a relative 1e-12 of the coordinates.
//  A pixel centre outside the grown triangle has one exact edge function below -(margin), so its
//  float ray sees that edge function negative and the watertight test rejects it.
[[nodiscard]] CULLKIT_FORCEINLINE bool footprint_mask(const ViewSetup& f, const glm::vec3& p0, const glm::vec3& p1,
                                         const glm::vec3& p2, int x0, int y0, int ry0, int ry1,
                                         const Mask* bits, Mask* mask, int x_last) noexcept {
  double px[3], py[3];
  if (!project_point(f, p0, px[0], py[0]) || !project_point(f, p1, px[1], py[1]) ||
      !project_point(f, p2, px[2], py[2]))
    return false;
  const double area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
  if (!(std::fabs(area) > 0.0) || !std::isfinite(area)) return false;
  const double sgn = area > 0.0 ? 1.0 : -1.0;
  double lox = x0, hix = x0 + x_last, loy = y0 + ry0, hiy = y0 + ry1;
  for (int k = 0; k < 3; ++k) {
    lox = std::min(lox, px[k]);
    hix = std::max(hix, px[k]);
    loy = std::min(loy, py[k]);
    hiy = std::max(hiy, py[k]);
  }
  const double reach = (hix - lox) + (hiy - loy) + 1.0;
  double nx[3], ny[3], off[3];
  for (int k = 0; k < 3; ++k) {
    const int j = k == 2 ? 0 : k + 1;
    // e(q) = nx (qx - px[k]) + ny (qy - py[k]) >= 0 inside (orientation from the area's sign).
    nx[k] = -(py[j] - py[k]) * sgn;
    ny[k] = (px[j] - px[k]) * sgn;
    const double n1 = std::fabs(nx[k]) + std::fabs(ny[k]);
    const double slack = f.margin * n1 + 1e-5 * reach * reach +
                         1e-12 * n1 * (reach + std::fabs(px[k]) + std::fabs(py[k]) + f.width + f.height);
    off[k] = -nx[k] * px[k] - ny[k] * py[k] + slack;
    if (!std::isfinite(off[k])) return false;
  }
#if CULLKIT_HAS_SSE2
  // Two pixel centres at a time, the same double expressions (so the same mask) as below.
  const __m128d nx0 = _mm_set1_pd(nx[0]), nx1 = _mm_set1_pd(nx[1]), nx2 = _mm_set1_pd(nx[2]);
  const __m128d of0 = _mm_set1_pd(off[0]), of1 = _mm_set1_pd(off[1]), of2 = _mm_set1_pd(off[2]);
  const __m128d zero = _mm_setzero_pd();
  for (int y = ry0; y <= ry1; ++y) {
    const Mask b = bits[y];
    if (!b) {
      mask[y] = 0;
      continue;
    }
    const double qy = y0 + y;
    const __m128d ey0 = _mm_set1_pd(ny[0] * qy), ey1 = _mm_set1_pd(ny[1] * qy), ey2 = _mm_set1_pd(ny[2] * qy);
    Mask m = 0;
    for (int x = TileState::low_bit(b), x_end = TileState::high_bit(b); x <= x_end; x += 2) {
      const __m128d qx = _mm_set_pd(double(x0 + x + 1), double(x0 + x));
      const __m128d e0 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx0, qx), ey0), of0);
      const __m128d e1 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx1, qx), ey1), of1);
      const __m128d e2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx2, qx), ey2), of2);
      const __m128d in = _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(e0, zero), _mm_cmpge_pd(e1, zero)), _mm_cmpge_pd(e2, zero));
      m |= static_cast<Mask>(_mm_movemask_pd(in)) << x;
    }
    mask[y] = m & b;
  }
#else
  for (int y = ry0; y <= ry1; ++y) {
    Mask b = bits[y];
    Mask m = 0;
    const double qy = y0 + y;
    while (b) {
      const int x = TileState::low_bit(b);
      b &= b - 1;
      const double qx = x0 + x;
      if (nx[0] * qx + ny[0] * qy + off[0] >= 0.0 && nx[1] * qx + ny[1] * qy + off[1] >= 0.0 &&
          nx[2] * qx + ny[2] * qy + off[2] >= 0.0)
        m |= TileState::bit(x);
    }
    mask[y] = m;
  }
#endif
  return true;
}

// Whether admit_triangle would reject `tri` from its cached rectangle alone, reading neither its
// corners nor anything else: a rectangle of this frame, not empty (an empty one is counted in
// NciSelectStats::triangles_no_pixel after a beam test), with no live pixel of the tile under it.
[[nodiscard]] inline bool cached_rect_misses(const Worker& worker, std::uint32_t tri, int x0, int y0, int tw, int th,
                                             const Mask* live) noexcept {
  const auto& slot = worker.tri[tri];
  if (slot.epoch != worker.frame_epoch || slot.rect.x0 > slot.rect.x1) return false;
  int rx0, ry0, rx1, ry1;
  Mask span;
  return !live_under(slot.rect, x0, y0, tw, th, live, rx0, ry0, rx1, ry1, span);
}

// Tests `tri` against the unfinished rays of the tile inside its screen rectangle; false when no
// ray was tested (a back face seen from the eye, or no live pixel under its rectangle).
// Whether `tri` may be hit by an unfinished ray of the tile (beam, screen rectangle, live
// pixels under it); when it may, `out` gets the pixels under its rectangle and its sort key.
inline bool admit_triangle(const IndexData& data, const ViewSetup& f, std::uint32_t tri, int x0, int y0, int tw, int th, const Mask* live,
                    const TileState& r, Worker& worker, Candidate& out) {
  // The triangle's screen rectangle, computed once per frame and thread (cached: a triangle is
  // met by many tiles).
  auto& slot = worker.tri[tri];
  bool in_beam = !r.beam;
  if (slot.epoch != worker.frame_epoch) {
    // Not yet met this frame: a triangle wholly outside the tile's beam is rejected without
    // computing its rectangle (most triangles of a big scene met by a tile are).
    if (r.beam && outside_beam(data, r, tri, f)) return false;
    in_beam = true;
    slot.epoch = worker.frame_epoch;
    slot.rect = screen_rect(f, data.corner(tri, 0), data.corner(tri, 1), data.corner(tri, 2));
  }
  // None (back face, edge-on from the eye, off screen) or no live pixel under it: not tested.
  int rx0, ry0, rx1, ry1;
  Mask span;
  if (!live_under(slot.rect, x0, y0, tw, th, live, rx0, ry0, rx1, ry1, span)) {
    // Counted only inside the beam, so the count does not depend on which thread met it first.
    if (slot.rect.x0 > slot.rect.x1 && (in_beam || !outside_beam(data, r, tri, f))) ++worker.stats.triangles_no_pixel;
    return false;
  }
  // The same beam test when the rectangle came from the cache, so what is tested does not depend
  // on which thread met the triangle first.
  if (!in_beam && outside_beam(data, r, tri, f)) return false;
  float key = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 3; ++k) {
    const glm::vec3 d = data.corner(tri, k) - f.eye_f;
    key = std::min(key, d.x * r.mean_dir[0] + d.y * r.mean_dir[1] + d.z * r.mean_dir[2]);
  }
  out = Candidate{key, tri, static_cast<std::int8_t>(rx0), static_cast<std::int8_t>(ry0),
                                 static_cast<std::int8_t>(rx1), static_cast<std::int8_t>(ry1)};
  return true;
}

}  // namespace cullkit::detail::nci
