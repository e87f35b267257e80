// cullkit/detail/nci/slice_walk.hpp: one screen tile of select_visible: its rays set up, the grid
// walked slice by slice outward from the eye, the admitted triangles ray-tested nearest first, rays
// finished as their hits come before the next slice.
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
#include "beam.hpp"
#include "context.hpp"
#include "index_data.hpp"
#include "rejection.hpp"
#include "tile_walk.hpp"
#include "tolerances.hpp"
#include "view.hpp"

namespace cullkit::detail::nci {

// The first slice (in walk order, from `from`) after which ray i may stop: its nearest solid
// hit (or the box exit: nothing lies beyond) comes before where it enters the next slice, with
// margins that only keep it longer (the predicate `done` below; the last slice of a walk always
// qualifies). Rays exactly parallel to the slices never reach another slice. The predicate is
// monotone along the walk; an estimate from the stop coordinate is corrected by the predicate
// itself, so the answer is exactly the first slice where it holds. The predicate's per-ray parts
// (stop coordinate and margin) are computed once, not per evaluation.
[[nodiscard]] inline int finish_slice(const IndexData& data, const TileState& r, int i, int walk, int from, double ea, int na) noexcept {
  const int end = walk == 0 ? na - 1 : 0;
  if (r.dir_a[i] == 0.0f) return from;
  const float t_stop = std::min(r.solid_t[i], r.t_exit[i]);
  const double reach = double(t_stop) * (1.0 + 1e-5) * double(r.dir_a[i]);
  const double pos = ea + reach;
  const double margin = 0.25 * data.delta - tolerance::float_relative * std::fabs(reach);
  const auto done = [&](int k) {
    if (walk == 0 ? k + 1 >= na : k <= 0) return true;
    const double next_plane = walk == 0 ? r.lo_a + (k + 1) * data.h : r.lo_a + k * data.h;
    return walk == 0 ? pos < next_plane + margin : pos > next_plane - margin;
  };
  int s = from;
  const double x = ea + double(t_stop) * double(r.dir_a[i]);
  if (std::isfinite(x)) {
    // Any start gives the same answer (the loops below correct it); starting at the slice
    // holding the stop point usually needs two evaluations of the predicate.
    const double cell = std::clamp((x - r.lo_a) * r.inv_h, -2.0, double(na) + 2.0);
    // The slice holding the stop point: floor (cell is clamped, so an int holds it; no libm
    // call without SSE4.1).
    int cut = static_cast<int>(cell);
    if (double(cut) > cell) --cut;
    const double est = cut;
    if (walk == 0 && est > from) s = static_cast<int>(std::min(est, double(end)));
    if (walk == 1 && est < from) s = static_cast<int>(std::max(est, double(end)));
  } else {
    s = end;
  }
  const int step = walk == 0 ? 1 : -1;
  // Back up while the previous slice already qualifies, then move on until this one does.
  while (s != from && done(s - step)) s -= step;
  while (s != end && !done(s)) s += step;
  return s;
}

inline void write_tile(const ViewSetup& f, const TileState& r, int x0, int y0, int tw, int th, Scratch& scratch,
                       Worker& worker) {
  const int stride = r.stride;  // the tile's row pitch (kept in a register)
  const std::size_t width = static_cast<std::size_t>(f.width);
  for (int y = 0; y < th; ++y) {
    for (int x = 0; x < tw; ++x) {
      const std::size_t p = static_cast<std::size_t>(y0 + y) * width + static_cast<std::size_t>(x0 + x);
      scratch.pixel_tri[p] = r.best[y * stride + x];
      scratch.pixel_t[p] = r.best_t[y * stride + x];
      scratch.pixel_solid_t[p] = r.solid_t[y * stride + x];
      const std::uint32_t tri = r.best[y * stride + x];
      if (tri != no_triangle) worker.mark_shown(tri);
    }
  }
}

// The live rays of a tile as one bit mask per tile row, for both walks and for each.
struct TileMasks {
  Mask live[TileState::max_tile] = {};     // unfinished rays, both walks
  Mask walk[2][TileState::max_tile] = {};  // [0]: toward +axis (and flat), [1]: toward -axis
};

// A tile whose pixels no triangle's rectangle can reach (beside the scene box's rectangle): every
// pixel keeps its initial depth, written straight to the frame's buffers (no pixel state, no
// winner to mark).
[[nodiscard]] inline bool write_if_off_scene(const ViewSetup& f, int x0, int y0, int x1, int y1, Scratch& scratch) {
  const int tw = x1 - x0, th = y1 - y0;
  const Rect& b = f.box_rect;
  if (!(b.x0 > b.x1 || (b.x0 != Rect::full && (b.x1 < x0 || b.x0 > x1 - 1 || b.y1 < y0 || b.y0 > y1 - 1)))) return false;
  for (int y = 0; y < th; ++y) {
    const std::size_t row = static_cast<std::size_t>(y0 + y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(x0);
    for (std::size_t p = row; p < row + static_cast<std::size_t>(tw); ++p) {
      const float t = f.initial_depth ? f.initial_depth[p] : std::numeric_limits<float>::infinity();
      scratch.pixel_tri[p] = no_triangle;
      scratch.pixel_t[p] = t;
      scratch.pixel_solid_t[p] = f.initial_solid ? f.initial_solid[p] : t;
    }
  }
  return true;
}

// Sets up every ray of the tile (directions, initial depths, box entry and exit, slopes across
// the walk axis, depth-bound scales) and marks the rays that reach the scene box live. Returns
// the sum of the live rays' directions (the tile's mean ray, unnormalized).
CULLKIT_FORCEINLINE glm::dvec3 setup_rays(const IndexData& data, const ViewSetup& f, int x0, int y0, int tw, int th,
                                          TileState& r, TileMasks& m) {
  r.any_dirty = true;
  r.beam = false;
  r.beam_eps = 0.0f;
  for (int k = 0; k < 4; ++k) r.beam_box[k] = -1;
  for (int k = 0; k < 3; ++k) r.mean_dir[k] = 0.0f;
  r.axis = f.axis;
  r.lo_a = data.lo[f.axis];
  r.inv_h = 1.0 / data.h;
  const int a = f.axis, b = (a + 1) % 3, c = (a + 2) % 3;
  const int stride = r.stride;
  const glm::dvec3 blo = glm::dvec3(data.box.min) - data.delta, bhi = glm::dvec3(data.box.max) + data.delta;
  // The same per component in plain arrays (the per-ray loop below indexes them by a variable;
  // glm's component access is a switch), and the box relative to the eye.
  const double eye3[3] = {f.eye.x, f.eye.y, f.eye.z};
  const double blo3[3] = {blo.x, blo.y, blo.z}, bhi3[3] = {bhi.x, bhi.y, bhi.z};
  const double rlo3[3] = {blo3[0] - eye3[0], blo3[1] - eye3[1], blo3[2] - eye3[2]};
  const double rhi3[3] = {bhi3[0] - eye3[0], bhi3[1] - eye3[1], bhi3[2] - eye3[2]};
  glm::dvec3 cone_sum(0.0);
  for (int k = 0; k < 3; ++k) {
    r.sz_lo[k] = std::numeric_limits<float>::infinity();
    r.sz_hi[k] = -std::numeric_limits<float>::infinity();
  }
  for (int y = 0; y < th; ++y) {
    for (int x = tw, x_end = (tw + 3) & ~3; x < x_end; ++x) r.dx[y * stride + x] = r.dy[y * stride + x] = r.dz[y * stride + x] = 0.0f;
    const std::size_t row = static_cast<std::size_t>(y0 + y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(x0);
    const float* initial_depth = f.initial_depth ? f.initial_depth + row : nullptr;
    const float* initial_solid = f.initial_solid ? f.initial_solid + row : nullptr;
    f.rays.directions(x0, y0 + y, tw, &r.dx[y * stride], &r.dy[y * stride], &r.dz[y * stride]);
    for (int x = 0; x < tw; ++x) {
      const int i = y * stride + x;
      const glm::vec3 direction(r.dx[i], r.dy[i], r.dz[i]);
      const double d3[3] = {direction.x, direction.y, direction.z};
      r.dir_a[i] = static_cast<float>(d3[a]);
      r.best_t[i] = initial_depth ? initial_depth[x] : std::numeric_limits<float>::infinity();
      r.best[i] = no_triangle;
      r.solid_t[i] = initial_solid ? initial_solid[x] : r.best_t[i];
      r.solid[i] = no_triangle;
      r.dirty[i] = true;
      // WatertightRay::make's validity (finite, not zero) without its shear: a ray that misses
      // the scene box is never tested, only its validity is read (make_beam's corners).
      // (the 1-norm in double cannot overflow; it is NaN or infinite iff a component is).
      const double norm1 = std::fabs(d3[0]) + std::fabs(d3[1]) + std::fabs(d3[2]);
      r.wray[i].valid = norm1 > 0.0 && norm1 < std::numeric_limits<double>::infinity();
      if (!r.wray[i].valid) continue;
      // Does the ray reach the (inflated) scene box at all? Entry and exit per axis (the face
      // by the direction's sign: rlo <= rhi, so that is the smaller and the larger of the two
      // products), each widened by a relative 1e-9. The widening x -> x -/+ 1e-9 |x| is
      // monotone (also after rounding), so it is applied once to the largest entry and the
      // smallest exit: the same values as widening every axis's, in fewer instructions.
      double enter = 0.0, leave = std::numeric_limits<double>::infinity();
      double inv3[3] = {0.0, 0.0, 0.0};
      bool hit = true;
      if (d3[0] != 0.0 && d3[1] != 0.0 && d3[2] != 0.0) {
        for (int k = 0; k < 3; ++k) {  // branch-free: min / max instructions
          const double inv = inv3[k] = 1.0 / d3[k];
          const double t0 = rlo3[k] * inv, t1 = rhi3[k] * inv;
          enter = std::max(enter, std::min(t0, t1));
          leave = std::min(leave, std::max(t0, t1));
        }
      } else {
        for (int k = 0; k < 3; ++k) {
          if (d3[k] == 0.0) {
            hit = hit && !(eye3[k] < blo3[k] || eye3[k] > bhi3[k]);
            continue;
          }
          const double inv = inv3[k] = 1.0 / d3[k];
          const double t0 = rlo3[k] * inv, t1 = rhi3[k] * inv;
          enter = std::max(enter, std::min(t0, t1));
          leave = std::min(leave, std::max(t0, t1));
        }
      }
      const double tmin = enter - tolerance::box_crossing * std::fabs(enter), tmax = leave + tolerance::box_crossing * std::fabs(leave);
      if (!hit || tmin > tmax) continue;
      r.wray[i] = detail::WatertightRay<float>::make(direction);
      r.t_exit[i] = static_cast<float>(tmax * (1.0 + tolerance::float_relative)) * (1.0f + tolerance::float_relative_f);
      const double da = d3[a];
      r.flat[i] = std::fabs(da) < tolerance::flat_direction;
      // Slopes by the reciprocal the box test took (inv3[a] is 1 / da when not flat): within a
      // double rounding of the quotient, far inside the float rounding the beam allows for.
      r.slope_b[i] = r.flat[i] ? 0.0f : static_cast<float>(d3[b] * inv3[a]);
      r.slope_c[i] = r.flat[i] ? 0.0f : static_cast<float>(d3[c] * inv3[a]);
      m.live[y] |= TileState::bit(x);
      const detail::WatertightRay<float>& w = r.wray[i];
      r.sz_lo[w.kz] = std::min(r.sz_lo[w.kz], w.sz);
      r.sz_hi[w.kz] = std::max(r.sz_hi[w.kz], w.sz);
      m.walk[da >= 0.0 ? 0 : 1][y] |= TileState::bit(x);
      cone_sum += glm::dvec3(d3[0], d3[1], d3[2]);
    }
  }
  return cone_sum;
}

// Classes that may face some live ray of the tile into `active`: a class is skipped only when every
// normal of its cone and every live ray direction make an angle below 90 degrees (a back face for
// all of them). Also sets the tile's mean ray (the candidates' sort key).
CULLKIT_FORCEINLINE void select_classes(const IndexData& data, TileState& r, int tw, int th, const Mask* live,
                                        const glm::dvec3& cone_sum, std::vector<std::uint16_t>& active) {
  const int stride = r.stride;
  active.clear();
  const double len = glm::length(cone_sum);
  double cos_psi = -1.0;
  glm::dvec3 axis(0.0);
  if (len > 1e-12) {
    axis = cone_sum / len;
    for (int j = 0; j < 3; ++j) r.mean_dir[j] = static_cast<float>(axis[j]);
    cos_psi = 1.0;
    for (int y = 0; y < th; ++y)
      for (int x = 0; x < tw; ++x)
        if (live[y] & (TileState::bit(x))) cos_psi = std::min(cos_psi, glm::dot(axis, r.direction(y * stride + x)));
  }
  const double psi = std::acos(std::clamp(cos_psi, -1.0, 1.0)) + tolerance::cone_angle;
  const bool can_skip = psi < 1.5707963267948966;
  const double sp = std::sin(psi), cp = std::cos(psi);
  for (std::size_t k = 0; k < data.class_axis.size(); ++k) {
    bool skip = false;
    if (can_skip && data.class_sin[k] <= 1.0f) {
      // angle(axis_k, tile axis) < 90 - theta - psi  <=>  dot > sin(theta + psi), if theta + psi < 90.
      const double st = data.class_sin[k], ct = data.class_cos[k];
      const double cos_sum = ct * cp - st * sp;  // cos(theta + psi)
      if (cos_sum > 0.0) {
        const double sin_sum = st * cp + ct * sp;
        skip = glm::dot(glm::dvec3(data.class_axis[k]), axis) > sin_sum + tolerance::cone_skip;
      }
    }
    if (!skip) active.push_back(static_cast<std::uint16_t>(k));
  }
}

// The slopes of the walk's live rays (`full`: some ray runs parallel to the slices).
CULLKIT_FORCEINLINE void update_slopes(TileWalk& w) {
  const TileState& r = w.r;
  const int stride = r.stride;
  w.slopes_stale = false;
  w.full = false;
  w.smin_b = std::numeric_limits<float>::infinity();
  w.smax_b = -w.smin_b;
  w.smin_c = w.smin_b;
  w.smax_c = -w.smin_b;
  for (int y = 0; y < w.th; ++y) {
    Mask bits = w.mask[y];
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      const int i = y * stride + x;
      if (r.flat[i]) w.full = true;
      w.smin_b = std::min(w.smin_b, r.slope_b[i]);
      w.smax_b = std::max(w.smax_b, r.slope_b[i]);
      w.smin_c = std::min(w.smin_c, r.slope_c[i]);
      w.smax_c = std::max(w.smax_c, r.slope_c[i]);
    }
  }
}

// The rows rlo..rhi and columns clo..chi of the cells the walk's live rays may cross between the
// walk-axis coordinates s0 and s1 (rlo > rhi: none).
CULLKIT_FORCEINLINE void beam_cells(const TileWalk& w, double s0, double s1, int& rlo, int& rhi, int& clo, int& chi) {
  const IndexData& data = w.data;
  const int b = w.b, c = w.c, nb = w.nb, nc = w.nc;
  const double ea = w.ea, eb = w.eb, ec = w.ec;
  rlo = 0, rhi = nb - 1, clo = 0, chi = nc - 1;
  if (w.full) return;
  double bmin = std::numeric_limits<double>::infinity(), bmax = -bmin, cmin = bmin, cmax = -bmin;
  const double ends[2] = {s0 - ea, s1 - ea};
  for (double e : ends) {
    bmin = std::min({bmin, eb + e * double(w.smin_b), eb + e * double(w.smax_b)});
    bmax = std::max({bmax, eb + e * double(w.smin_b), eb + e * double(w.smax_b)});
    cmin = std::min({cmin, ec + e * double(w.smin_c), ec + e * double(w.smax_c)});
    cmax = std::max({cmax, ec + e * double(w.smin_c), ec + e * double(w.smax_c)});
  }
  // Slopes were rounded to float: widen by their relative error over the slab's reach.
  const double reach = std::max(std::fabs(ends[0]), std::fabs(ends[1]));
  const double wb = data.delta + tolerance::float_relative * reach * (1.0 + std::max(std::fabs(double(w.smin_b)), std::fabs(double(w.smax_b))));
  const double wc = data.delta + tolerance::float_relative * reach * (1.0 + std::max(std::fabs(double(w.smin_c)), std::fabs(double(w.smax_c))));
  bmin -= wb;
  bmax += wb;
  cmin -= wc;
  cmax += wc;
  if (bmax < data.lo[b] || cmax < data.lo[c] || bmin > data.lo[b] + nb * data.h || cmin > data.lo[c] + nc * data.h) {
    rlo = 1;
    rhi = 0;  // beam outside the box in this slice
  } else {
    rlo = data.cell_of(bmin, b);
    rhi = data.cell_of(bmax, b);
    clo = data.cell_of(cmin, c);
    chi = data.cell_of(cmax, c);
  }
}

// The entries e..e_end of one cell of class k: each triangle not yet met by the tile goes through
// admit_triangle into the worker's candidates; on crowded indexes a chunk of entries whose box is
// outside the beam, off the live pixels or behind their hits is passed over whole.
CULLKIT_FORCEINLINE void visit_cell(TileWalk& w, std::uint16_t k, std::uint32_t e, std::uint32_t e_end) {
  const IndexData& data = w.data;
  const ViewSetup& f = w.f;
  TileState& r = w.r;
  Worker& worker = w.worker;
  const std::uint32_t stamp = w.stamp;
  std::size_t met = w.met;
  const bool gather = !data.tri_slot.empty();
  auto visit = [&](std::uint32_t tri) {
    if (worker.tri[tri].stamp == stamp) return;
    worker.tri[tri].stamp = stamp;
    ++met;
    if (gather) {
      ++worker.met_in_slice_count;
      // Those rejected by their cached rectangle need no corners and are settled here.
      if (!cached_rect_misses(worker, tri, w.x0, w.y0, w.tw, w.th, w.live))
        worker.met_in_slice.push_back(std::uint64_t{data.tri_slot[tri]} << 32 | tri);
      return;
    }
    Candidate cand;
    if (admit_triangle(data, f, tri, w.x0, w.y0, w.tw, w.th, w.live, r, worker, cand)) worker.candidates.push_back(cand);
  };
  const std::uint32_t tri_base = data.class_tri_begin[k];
  while (e < e_end) {
    std::uint32_t part_end = e_end;
    if (!data.chunk_box.empty() && r.beam) {
      const std::uint32_t j = e / static_cast<std::uint32_t>(data.chunk);
      part_end = std::min(e_end, (j + 1) * static_cast<std::uint32_t>(data.chunk));
      if (chunk_outside_beam(r, &data.chunk_box[6 * std::size_t{j}], f) ||
          chunk_hidden(data, f, j, w.x0, w.y0, w.tw, w.th, w.live, r, worker)) {
        e = part_end;
        continue;
      }
    }
    if (data.wide_tris) {
      for (; e < part_end; ++e) visit(data.cell_tris[e]);
    } else {
      for (; e < part_end; ++e) visit(tri_base + data.cell_tris16[e]);
    }
  }
  w.met = met;
}

// The cells of slice s in rows rlo..rhi and columns clo..chi, class by class (active classes
// only), found by binary search in the sorted rows and columns. False when the tile's triangles
// met passed w.budget (then the rest of the slice is not visited).
CULLKIT_FORCEINLINE bool visit_slice(TileWalk& w, const std::vector<std::uint16_t>& active, int s, int rlo, int rhi,
                                     int clo, int chi) {
  const IndexData& data = w.data;
  const int a = w.a;
  for (std::uint16_t k : active) {
    const std::size_t base = data.grid_base[static_cast<std::size_t>(k) * 3 + static_cast<std::size_t>(a)];
    const std::uint32_t shift = data.grid_shift[static_cast<std::size_t>(k) * 3 + static_cast<std::size_t>(a)];
    const std::uint32_t class_base = data.class_cell_base[k];
    const std::uint32_t row_first = data.slice_rows[base + static_cast<std::size_t>(s)];
    const std::uint32_t row_last = data.slice_rows[base + static_cast<std::size_t>(s) + 1];
    // Rows are sorted: a class whose rows in this slice all lie outside [rlo, rhi] is
    // passed over without a search.
    if (row_first == row_last || data.row_coord[row_first] > rhi || data.row_coord[row_last - 1] < rlo) continue;
    auto row_it = data.row_coord[row_first] >= rlo
                      ? data.row_coord.begin() + row_first
                      : std::lower_bound(data.row_coord.begin() + row_first, data.row_coord.begin() + row_last,
                                         static_cast<std::uint16_t>(rlo));
    for (; row_it != data.row_coord.begin() + row_last && *row_it <= rhi; ++row_it) {
      const std::size_t row = static_cast<std::size_t>(row_it - data.row_coord.begin());
      const std::uint32_t cf = data.row_begin[row], cl = data.row_begin[row + 1];
      if (data.cell_col[cf] > chi || data.cell_col[cl - 1] < clo) continue;  // sorted columns, none in range
      auto cell_it = data.cell_col[cf] >= clo ? data.cell_col.begin() + cf
                                              : std::lower_bound(data.cell_col.begin() + cf, data.cell_col.begin() + cl,
                                                                 static_cast<std::uint16_t>(clo));
      for (; cell_it != data.cell_col.begin() + cl && *cell_it <= chi; ++cell_it) {
        const std::uint32_t pos = static_cast<std::uint32_t>(cell_it - data.cell_col.begin());
        const std::uint32_t cell = a == 0          ? pos - shift
                                   : data.wide_ids ? data.cell_id[pos - shift]
                                                   : class_base + data.cell_id16[pos - shift];
        ++w.worker.stats.cells_visited;
        std::uint32_t e, e_end;
        if (data.cell_begin16.empty()) {
          e = data.cell_tri_begin[cell];
          e_end = data.cell_tri_begin[cell + 1];
        } else {
          e = data.class_entry_base[k] + data.cell_begin16[cell + k];
          e_end = data.class_entry_base[k] + data.cell_begin16[cell + k + 1];
        }
        ++w.worker.stats.cells_walked;
        visit_cell(w, k, e, e_end);
        if (w.budget != 0 && w.met > w.budget) return false;
      }
    }
  }
  return true;
}

// With per-slot corners in the hierarchy's leaf order, the triangles the slice's cells met are
// admitted in leaf order, not class by class: a class's triangles are spread over the leaves
// (their neighbours there belong to other classes), so admitting them cell by cell reads one
// scattered corner line per triangle, while in leaf order the triangles of every class met in the
// slice share the lines they lie on and the reads run forward. Admission does not depend on the
// order (the tile's rays do not change until test_candidates), so the candidates are the same.
CULLKIT_FORCEINLINE void admit_met_in_leaf_order(TileWalk& w) {
  Worker& worker = w.worker;
  auto& met = worker.met_in_slice;
  worker.met_in_slice_peak = std::max(worker.met_in_slice_peak, worker.met_in_slice_count);
  worker.met_in_slice_count = 0;
  const std::size_t n = met.size();
  if (n == 0) return;
  auto admit = [&](std::uint32_t tri) {
    Candidate cand;
    if (admit_triangle(w.data, w.f, tri, w.x0, w.y0, w.tw, w.th, w.live, w.r, worker, cand)) worker.candidates.push_back(cand);
  };
  // One counting pass over about n buckets of the positions' range: the order only needs to be
  // close to the leaves' (triangles a bucket apart seldom share a line), and any order admits the
  // same candidates. A comparison sort of the same lists took more time than the reads it saved.
  std::uint32_t lo = 0xFFFFFFFFu, hi = 0;
  for (const std::uint64_t m : met) {
    const auto pos = static_cast<std::uint32_t>(m >> 32);
    lo = std::min(lo, pos);
    hi = std::max(hi, pos);
  }
  std::uint32_t buckets = 1;
  while (buckets < n && buckets < (1u << 16)) buckets <<= 1;
  int shift = 0;
  while (((hi - lo) >> shift) >= buckets) ++shift;
  auto& count = worker.met_bucket;
  count.assign(buckets + 1, 0u);
  for (const std::uint64_t m : met) ++count[((static_cast<std::uint32_t>(m >> 32) - lo) >> shift) + 1];
  for (std::uint32_t b = 1; b <= buckets; ++b) count[b] += count[b - 1];
  auto& order = worker.met_order;
  order.resize(n);
  for (const std::uint64_t m : met) order[count[(static_cast<std::uint32_t>(m >> 32) - lo) >> shift]++] = static_cast<std::uint32_t>(m);
  for (const std::uint32_t tri : order) admit(tri);
  met.clear();
}

// Ray-tests the slice's candidates nearest first, so hits found early let behind_hits drop the
// triangles behind them.
CULLKIT_FORCEINLINE void test_candidates(TileWalk& w) {
  Worker& worker = w.worker;
  if (worker.candidates.empty()) return;
  std::sort(worker.candidates.begin(), worker.candidates.end(), [](const auto& p, const auto& q) {
    return p.key != q.key ? p.key < q.key : p.tri < q.tri;
  });
  for (const auto& cand : worker.candidates)
    if (test_triangle(w.data, w.f, w.x0, w.y0, cand, w.live, w.r, worker)) {
      ++worker.tested_count;
      worker.mark_tested(cand.tri);
    }
  worker.candidates.clear();
}

// After slice s: finishes the rays whose nearest hit lies before the next slice (with margins
// that only keep rays unfinished longer). Nothing to do while no hit improved and no ray's
// finishing slice is reached.
CULLKIT_FORCEINLINE void finish_rays(TileWalk& w, int s) {
  TileState& r = w.r;
  const int walk = w.walk, na = w.na, stride = r.stride;
  if (!r.any_dirty && (walk == 0 ? s < w.next_finish : s > w.next_finish)) return;
  r.any_dirty = false;
  int next_finish = walk == 0 ? na : -1;
  for (int y = 0; y < w.th; ++y) {
    Mask bits = w.mask[y];
    while (bits) {
      const int x = TileState::low_bit(bits);
      bits &= bits - 1;
      const int i = y * stride + x;
      if (r.dirty[i]) {
        r.finish[i] = finish_slice(w.data, r, i, walk, s, w.ea, na);
        r.dirty[i] = false;
      }
      const bool done = walk == 0 ? s >= r.finish[i] : s <= r.finish[i];
      if (done) {
        w.mask[y] &= ~TileState::bit(x);
        w.live[y] &= ~TileState::bit(x);
        w.slopes_stale = true;
      } else {
        next_finish = walk == 0 ? std::min(next_finish, r.finish[i]) : std::max(next_finish, r.finish[i]);
      }
    }
  }
  w.next_finish = next_finish;
  if (w.slopes_stale) narrow_beam(r, w.tw, w.th, w.live);
}

// Walks the slices from the eye's outward in one direction until every ray of the walk is
// finished or the grid ends (which finishes the rest). False when the tile has met more than
// w.budget triangles (both walks together; 0: no limit) before that: the walk stops at the cell
// where it crossed it (the candidates met so far are still tested; no ray is finished in that
// slice, whose other cells were not visited), and its unfinished rays stay live, hits kept.
CULLKIT_FORCEINLINE bool walk_slices(TileWalk& w, const std::vector<std::uint16_t>& active) {
  const IndexData& data = w.data;
  const int step = w.walk == 0 ? 1 : -1;
  const int start = data.cell_of(w.ea, w.a);
  w.r.any_dirty = true;
  w.next_finish = start;
  for (int s = start; s >= 0 && s < w.na; s += step) {
    Mask unfinished = 0;  // any ray of this walk still live
    for (int y = 0; y < w.th; ++y) unfinished |= w.mask[y];
    if (!unfinished) break;
    ++w.worker.stats.slices_walked;
    // The part of the slab this walk's rays cross, inflated like the cells.
    double s0 = data.lo[w.a] + s * data.h - data.delta, s1 = data.lo[w.a] + (s + 1) * data.h + data.delta;
    if (w.walk == 0) s0 = std::max(s0, w.ea);
    else s1 = std::min(s1, w.ea);
    if (s0 <= s1) {
      if (w.slopes_stale) update_slopes(w);
      int rlo, rhi, clo, chi;
      beam_cells(w, s0, s1, rlo, rhi, clo, chi);
      if (rlo <= rhi && clo <= chi) {
        const bool whole = visit_slice(w, active, s, rlo, rhi, clo, chi);
        admit_met_in_leaf_order(w);
        test_candidates(w);
        if (!whole) return false;
      }
    }
    finish_rays(w, s);
  }
  for (int y = 0; y < w.th; ++y) {  // a walk that ran out of slices finishes its rays
    w.live[y] &= ~w.mask[y];
    w.mask[y] = 0;
  }
  return true;
}

// Beside each pixel's first hit: the triangles within rounding of an edge in front of its solid
// hit, and that solid hit itself, into the worker's extras and selected set.
inline void collect_edge_band(const ViewSetup& f, const TileState& r, int x0, int y0, int tw, int th, Worker& worker) {
  const int stride = r.stride;
  const auto global = [&](int i) {
    return static_cast<std::uint32_t>(y0 + i / stride) * static_cast<std::uint32_t>(f.width) +
           static_cast<std::uint32_t>(x0 + i % stride);
  };
  const auto show = [&](std::uint32_t tri) { worker.mark_shown(tri); };
  for (const auto& u : worker.edge_hits) {
    if (u.t <= r.solid_t[u.pixel] && u.tri != r.best[u.pixel]) {
      worker.extra.push_back(Extra{u.tri, u.t, global(u.pixel)});
      show(u.tri);
    }
  }
  worker.edge_hits.clear();
  for (int y = 0; y < th; ++y)
    for (int x = 0; x < tw; ++x) {
      const int i = y * stride + x;
      if (r.solid[i] != no_triangle && r.solid[i] != r.best[i]) {
        worker.extra.push_back(Extra{r.solid[i], r.solid_t[i], global(i)});
        show(r.solid[i]);
      }
    }
}

// The start of a tile on either path (the walk here, the triangle hierarchy in frame_tile.hpp): false
// when the tile lies off the scene (its pixels are then written); else its rays are set up in `r`
// and `m`, and `cone_sum` is the sum of their directions.
[[nodiscard]] inline bool start_tile(const IndexData& data, const ViewSetup& f, int x0, int y0, int x1, int y1,
                                     TileState& r, Scratch& scratch, TileMasks& m, glm::dvec3& cone_sum) {
  if (write_if_off_scene(f, x0, y0, x1, y1, scratch)) return false;
  r.stride = (x1 - x0 + 3) & ~3;
  cone_sum = setup_rays(data, f, x0, y0, x1 - x0, y1 - y0, r, m);
  return true;
}

// The walk of a tile whose rays start_tile set up: both walk directions, nearest slices first.
// False when the tile met more than `budget` triangles (0: no limit) before every ray finished;
// `m.live` then holds the unfinished rays, whose hits so far stay in `r` (any path may go on from
// there: both only lower a ray's hits). The classes that may face a live ray are left in
// worker.active_classes either way.
inline bool walk_tile(const IndexData& data, const ViewSetup& f, int x0, int y0, int tw, int th, TileState& r,
                      Worker& worker, TileMasks& m, const glm::dvec3& cone_sum, std::size_t budget) {
  auto& active = worker.active_classes;
  bool any = false;
  for (int y = 0; y < th; ++y) any = any || m.live[y] != 0;
  if (!any) {
    active.clear();
    return true;
  }
  make_beam(r, tw, th, m.live);
  select_classes(data, r, tw, th, m.live, cone_sum, active);
  if (++worker.stamp_value == 0) {
    for (auto& t : worker.tri) t.stamp = 0u;
    worker.stamp_value = 1;
  }
  const int a = f.axis, b = (a + 1) % 3, c = (a + 2) % 3;
  std::size_t met = 0;
  bool finished = true;
  for (int walk = 0; walk < 2 && finished; ++walk) {
    TileWalk w{data, f, r, worker, x0, y0, tw, th, m.live, m.walk[walk], walk, a, b, c, f.eye[a], f.eye[b], f.eye[c],
               data.dims[a], data.dims[b], data.dims[c], worker.stamp_value};
    w.met = met;
    w.budget = budget;
    finished = walk_slices(w, active);
    met = w.met;
  }
  worker.stats.triangles_met += met;
  return finished;
}

// The frame of every tile path: the tile's rays set up (start_tile), `find_hits(tw, th, masks,
// cone_sum)` finding their hits, then the edge band collected and the tile written. Each path
// differs only in how it finds the hits.
template <class FindHits>
CULLKIT_FORCEINLINE void drive_tile(const IndexData& data, const ViewSetup& f, int x0, int y0, int x1, int y1, TileState& r,
                                    Worker& worker, Scratch& scratch, FindHits&& find_hits) {
  TileMasks m;
  glm::dvec3 cone_sum;
  if (!start_tile(data, f, x0, y0, x1, y1, r, scratch, m, cone_sum)) return;
  const int tw = x1 - x0, th = y1 - y0;
  find_hits(tw, th, m, cone_sum);
  collect_edge_band(f, r, x0, y0, tw, th, worker);
  write_tile(f, r, x0, y0, tw, th, scratch, worker);
}

// One screen tile (x0, y0)..(x1, y1) of the frame, walked: its pixels' first hits, solid hits and
// edge-band extras into the worker's records and the frame's per-pixel buffers. `r` is the
// worker's scratch (any contents): every field read is set here first.
inline void process_tile(const IndexData& data, const ViewSetup& f, int x0, int y0, int x1, int y1, TileState& r,
                         Worker& worker, Scratch& scratch) {
  drive_tile(data, f, x0, y0, x1, y1, r, worker, scratch, [&](int tw, int th, TileMasks& m, const glm::dvec3& cone_sum) {
    (void)walk_tile(data, f, x0, y0, tw, th, r, worker, m, cone_sum, 0);
  });
}

}  // namespace cullkit::detail::nci
