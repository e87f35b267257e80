// cullkit/detail/nci/tile_walk.hpp: what one walk of a screen tile shares between its steps
// (slice_walk.hpp): the TileWalk state; test_triangle, the ray test of an admitted triangle against
// the tile's live rays; and test_ray, the per-ray step it shares with the triangle hierarchy's leaves
// (frame_tile.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "context.hpp"
#include "index_data.hpp"
#include "rejection.hpp"
#include "tolerances.hpp"
#include "view.hpp"

namespace cullkit::detail::nci {

// The ray test of triangle `tri` (corners a, b, c relative to the eye, `mag` their largest
// coordinates) on the tile's ray i, and what it changes: the ray's first hit (ties to the lower
// mesh index), its solid hit, and an edge-band record. Both paths (the walk's test_triangle and
// the triangle hierarchy's leaves, frame_tile.hpp) test through it.
CULLKIT_FORCEINLINE void test_ray(const IndexData& data, TileState& r, Worker& worker, int i, std::uint32_t tri,
                                  const float a[3], const float b[3], const float c[3], const float mag[3]) {
  ++worker.stats.ray_tests;
  float t = 0.0f;
  bool near = false;
  const bool hit = detail::watertight_hit_band(r.wray[i], a, b, c, mag, data.band, t, near);
  // Ties go to the lower mesh index (the internal numbering is not the mesh's).
  if (hit && (t < r.best_t[i] ||
              (t == r.best_t[i] && (r.best[i] == no_triangle || data.tri_original[tri] < data.tri_original[r.best[i]])))) {
    r.best_t[i] = t;
    r.best[i] = tri;
  }
  if (near) {
    if (t <= r.solid_t[i]) worker.edge_hits.push_back(EdgeBandHit{tri, t, static_cast<std::uint16_t>(i)});
  } else if (hit && (t < r.solid_t[i] || (t == r.solid_t[i] && (r.solid[i] == no_triangle ||
                                                                data.tri_original[tri] < data.tri_original[r.solid[i]])))) {
    if (t < r.solid_t[i]) {
      r.dirty[i] = true;
      r.any_dirty = true;
    }
    r.solid_t[i] = t;
    r.solid[i] = tri;
  }
}

// The depth reject of behind_hits for ray i alone (its own scale sz on its own dominant axis, the
// same bound and margin): true when the ray already holds a solid hit strictly nearer than any t
// the watertight test could return for a triangle whose corners (relative to the eye) lie in the
// box qlo..qhi. Skipping such a ray changes no answer.
CULLKIT_FORCEINLINE bool ray_behind(const TileState& r, int i, const float qlo[3], const float qhi[3]) {
  if (!(r.solid_t[i] < std::numeric_limits<float>::infinity())) return false;
  const detail::WatertightRay<float>& w = r.wray[i];
  const double sz = w.sz;
  double bound = std::min(sz * double(qlo[w.kz]), sz * double(qhi[w.kz])) * (1.0 - tolerance::float_relative);
  return bound > 1e-30 && std::isfinite(bound) && double(r.solid_t[i]) < bound;
}

// Tests an admitted triangle against the unfinished rays under its rectangle; false when no ray
// was tested (all of them already hold nearer hits, or the triangle passes beside them).
inline bool test_triangle(const IndexData& data, const ViewSetup& f, int x0, int y0, const Candidate& cand, const Mask* live,
                   TileState& r, Worker& worker) {
  const int stride = r.stride;  // the tile's row pitch (kept in a register)
  const std::uint32_t tri = cand.tri;
  const int rx0 = cand.rx0, ry0 = cand.ry0, rx1 = cand.rx1, ry1 = cand.ry1;
  const Mask span = TileState::columns(rx0, rx1);
  const glm::vec3& p0 = data.corner(tri, 0);
  const glm::vec3& p1 = data.corner(tri, 1);
  const glm::vec3& p2 = data.corner(tri, 2);
  const float a[3] = {p0.x - f.eye_f.x, p0.y - f.eye_f.y, p0.z - f.eye_f.z};
  const float b[3] = {p1.x - f.eye_f.x, p1.y - f.eye_f.y, p1.z - f.eye_f.z};
  const float c[3] = {p2.x - f.eye_f.x, p2.y - f.eye_f.y, p2.z - f.eye_f.z};
  const float mag[3] = {std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(a[2])}),
                        std::max({std::fabs(b[0]), std::fabs(b[1]), std::fabs(b[2])}),
                        std::max({std::fabs(c[0]), std::fabs(c[1]), std::fabs(c[2])})};
  const float qlo[3] = {std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}), std::min({a[2], b[2], c[2]})};
  const float qhi[3] = {std::max({a[0], b[0], c[0]}), std::max({a[1], b[1], c[1]}), std::max({a[2], b[2], c[2]})};
  if (behind_hits(r, qlo, qhi, ry0, ry1, span, live)) return false;
  if (f.use_rect && f.affine_rays && (rx1 > rx0 || ry1 > ry0) && beside_rect(r, a, b, c, rx0, ry0, rx1, ry1)) return false;
  // Only the live rays whose pixel centres lie in the triangle's grown 2D footprint can hit it.
  Mask rows[TileState::max_tile];
  for (int y = ry0; y <= ry1; ++y) rows[y] = live[y] & span;
  if (f.footprint) {
    Mask inside[TileState::max_tile];
    if (footprint_mask(f, p0, p1, p2, x0, y0, ry0, ry1, rows, inside, f.tile - 1)) {
      Mask left = 0;
      for (int y = ry0; y <= ry1; ++y) left |= (rows[y] &= inside[y]);
      if (!left) return false;  // no live pixel centre can see it: not tested
    }
  }
  bool any = false;
  for (int y = ry0; y <= ry1; ++y) {
    Mask bits = rows[y];
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      const int i = y * stride + x;
      if (ray_behind(r, i, qlo, qhi)) continue;
      any = true;
      test_ray(data, r, worker, i, tri, a, b, c, mag);
    }
  }
  return any;
}

// One walk of a tile through the slices of its grid, from the eye's slice in one direction: what
// the walk's steps (slice_walk.hpp) share.
struct TileWalk {
  const IndexData& data;
  const ViewSetup& f;
  TileState& r;
  Worker& worker;
  int x0, y0, tw, th;
  Mask* live;  // the tile's live rays (both walks)
  Mask* mask;  // this walk's live rays
  int walk;    // 0: toward +axis, 1: toward -axis
  int a, b, c;  // walk axis, then the grid's row and column axes
  double ea, eb, ec;
  int na, nb, nc;
  std::uint32_t stamp;  // the tile's stamp in Worker::tri (each triangle met once per tile)
  std::size_t met = 0;  // NciSelectStats::triangles_met of this tile (a local: the visit loop is hot)
  std::size_t budget = 0;  // the walk stops once `met` passes it (0: never; see walk_slices)
  // The walk's live rays' slopes across the walk axis (recomputed only after rays finished).
  bool slopes_stale = true, full = false;
  float smin_b = 0.0f, smax_b = 0.0f, smin_c = 0.0f, smax_c = 0.0f;
  int next_finish = 0;  // the earliest slice where some ray may finish
};

}  // namespace cullkit::detail::nci
