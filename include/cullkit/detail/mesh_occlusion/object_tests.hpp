// cullkit/detail/mesh_occlusion/object_tests.hpp: whether an object is hidden once the grid is
// filled: its box (the box test of box_test.hpp), its patches' boxes, their triangles (also those
// through the near plane); and the choice of the solid boxes that fill the occlusion tree.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

#include "../../geometry/camera.hpp"
#include "../../occlusion_tree.hpp"
#include "box_test.hpp"
#include "coverage.hpp"
#include "frame.hpp"
#include "index.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// The object test of a triangle with a corner not clearly beyond the near plane (which cannot be
/// projected whole). True when no ray through the frustum can see it unhidden: it lies outside the
/// frustum, or is clearly back-facing (the eye on its back side, in world space), or its part that
/// can be drawn (near-plane value at least -drawable_level: a margin on the near side this time), cut to
/// the grid's rectangle on screen, has its rectangle hidden at that part's nearest depth. 1/w is
/// affine on screen over the triangle's plane, so the cut interpolates it exactly up to rounding.
template <class Frame>  // Scratch, or a task's view of it (parallel_frame.hpp)
inline bool crossing_triangle_hidden(const MeshIndex& index, const Frame& s, const std::uint32_t* c) {
  const View& view = s.view;
  const glm::vec3 &p0 = index.positions[c[0]], &p1 = index.positions[c[1]], &p2 = index.positions[c[2]];
  const Aabb box{glm::min(p0, glm::min(p1, p2)), glm::max(p0, glm::max(p1, p2))};
  if (s.frustum.classify(box) == Containment::outside) return true;
  double q[3][3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = index.positions[c[k]];
    for (int a = 0; a < 3; ++a) q[k][a] = double(p[a]) - view.eye[a];
  }
  // Front-facing means det[p0 - e, p1 - e, p2 - e] < 0 (see View::setup).
  const double det = q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                     q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
  const auto len = [](const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
  if (det > 1e-9 * len(q[0]) * len(q[1]) * len(q[2])) return true;
  // The drawable part: clipped at -drawable_level, in the triangle's own order (no fusion needed here).
  double x[8], y[8], iw[8];
  int n = 0;
  const double level = -view.drawable_level;
  double value[3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = index.positions[c[k]];
    value[k] = view.near_value(p.x, p.y, p.z);
  }
  // Projects a corner of the drawable part; false (the triangle stays visible) when it is not in
  // front of the eye or so far off screen that the cut below could lose precision.
  const auto put = [&](double px, double py, double pz) {
    const double qx = px - view.eye[0], qy = py - view.eye[1], qz = pz - view.eye[2];
    const double cw = view.row[2][0] * qx + view.row[2][1] * qy + view.row[2][2] * qz;
    if (!(cw > 0.0)) return false;
    x[n] = (view.row[0][0] * qx + view.row[0][1] * qy + view.row[0][2] * qz) / cw * view.scale_x + view.offset_x;
    y[n] = (view.row[1][0] * qx + view.row[1][1] * qy + view.row[1][2] * qz) / cw * view.scale_y + view.offset_y;
    iw[n] = 1.0 / cw;
    const bool ok = std::fabs(x[n]) < 0x1p40 && std::fabs(y[n]) < 0x1p40 && std::isfinite(iw[n]);
    ++n;
    return ok;
  };
  for (int k = 0; k < 3; ++k) {
    const int l = k == 2 ? 0 : k + 1;
    const glm::vec3 &a = index.positions[c[k]], &b = index.positions[c[l]];
    if (value[k] >= level && !put(a.x, a.y, a.z)) return false;
    if ((value[k] >= level) != (value[l] >= level)) {
      const double t = (level - value[k]) / (value[l] - value[k]);
      if (!(t >= 0.0 && t <= 1.0) ||
          !put(a.x + t * (double(b.x) - a.x), a.y + t * (double(b.y) - a.y), a.z + t * (double(b.z) - a.z)))
        return false;
    }
  }
  if (n < 3) return true;  // nothing of it can be drawn
  // Cut to the grid's rectangle widened by a cell, one side at a time.
  for (int side = 0; side < 4; ++side) {
    const double bound = side & 1 ? (side < 2 ? s.grid.width() : s.grid.height()) + 1.0 : -1.0;
    double* u = side < 2 ? x : y;
    const auto keep = [&](int i) { return side & 1 ? u[i] <= bound : u[i] >= bound; };
    double nx[8], ny[8], niw[8];
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const int j = i + 1 == n ? 0 : i + 1;
      if (keep(i)) {
        nx[m] = x[i], ny[m] = y[i], niw[m++] = iw[i];
      }
      if (keep(i) != keep(j)) {
        const double t = (bound - u[i]) / (u[j] - u[i]);
        nx[m] = x[i] + t * (x[j] - x[i]), ny[m] = y[i] + t * (y[j] - y[i]), niw[m++] = iw[i] + t * (iw[j] - iw[i]);
      }
    }
    n = m;
    if (n == 0) return true;  // off the grid: no ray through the frustum meets it
    std::copy(nx, nx + n, x);
    std::copy(ny, ny + n, y);
    std::copy(niw, niw + n, iw);
  }
  BoxView b{x[0], y[0], x[0], y[0], 0.0, true};
  double iw_max = iw[0];
  for (int i = 1; i < n; ++i) {
    b.x0 = std::min(b.x0, x[i]);
    b.x1 = std::max(b.x1, x[i]);
    b.y0 = std::min(b.y0, y[i]);
    b.y1 = std::max(b.y1, y[i]);
    iw_max = std::max(iw_max, iw[i]);
  }
  // Rounding of the interpolation, far inside this margin (rect_hidden adds its own 2^-20).
  b.w_min = 1.0 / (iw_max * (1.0 + 0x1p-30));
  const bool finite = std::isfinite(b.x0) && std::isfinite(b.x1) && std::isfinite(b.y0) && std::isfinite(b.y1);
  if (!finite || !std::isfinite(b.w_min) || !(b.w_min > 0.0)) return false;
  if (rect_hidden(s.grid, b)) return true;
  // Cell by cell, as a fan of triangles in the triangle's plane, with the same rounding margin.
  for (int f = 1; f + 1 < n; ++f) {
    const double fx[3] = {x[0], x[f], x[f + 1]}, fy[3] = {y[0], y[f], y[f + 1]};
    const double fw[3] = {1.0 / (iw[0] * (1.0 + 0x1p-30)), 1.0 / (iw[f] * (1.0 + 0x1p-30)), 1.0 / (iw[f + 1] * (1.0 + 0x1p-30))};
    if (!s.grid.triangle_behind(fx, fy, fw)) return false;
  }
  return true;
}

/// True when each of the patch's triangles is clearly back-facing (no ray sees its front) or hidden
/// by its own screen rectangle at its own nearest depth. Corners are projected as for occluders.
template <class Frame>  // Scratch, or a task's view of it (parallel_frame.hpp)
inline bool patch_triangles_hidden(const MeshIndex& index, Frame& s, const Patch& patch) {
  for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
    const std::uint32_t* c = &index.corners[3 * std::size_t(index.patches.triangles[k])];
    BoxView b{HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL, HUGE_VAL, true};
    double x[3], y[3], w[3];
    bool usable = true;
    for (int v = 0; v < 3 && usable; ++v) {
      const Projected& p = project_vertex(index, s, c[v]);
      usable = p.usable;  // else through the near plane: tested below
      x[v] = p.x;
      y[v] = p.y;
      w[v] = p.w;
      b.x0 = std::min(b.x0, p.x);
      b.x1 = std::max(b.x1, p.x);
      b.y0 = std::min(b.y0, p.y);
      b.y1 = std::max(b.y1, p.y);
      b.w_min = std::min(b.w_min, p.w);
    }
    if (!usable) {
      if (!crossing_triangle_hidden(index, s, c)) return false;
      continue;
    }
    // The mirror of the occluders' front-facing rule, with the same margin: only a triangle that is
    // clearly back-facing is passed over; an edge-on one is tested like any other.
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    const double extent = std::max(b.x1 - b.x0, b.y1 - b.y0);
    if (area2 * s.view.orient < -1e-9 * extent * extent) continue;
    // Its rectangle at its nearest depth first (tile minima make it cheap), then cell by cell.
    if (!rect_hidden(s.grid, b) && !s.grid.triangle_behind(x, y, w)) return false;
  }
  return true;
}

/// The part of the view frustum nearer than the near plane: the eye and the near rectangle's
/// corners, widened a little (rays 0.1% outside the screen, the rectangle 0.1% beyond the plane).
struct NearPyramid {
  double p[5][3];      // eye, then the 4 corners (in order around the rectangle)
  double plane[5][4];  // outward: 4 sides through the eye, then the far side (the near plane)
  bool ok = false;
};

inline NearPyramid near_pyramid(const Camera& camera, const View& view) {
  NearPyramid py;
  const glm::dmat4 inv = glm::inverse(glm::dmat4(camera.view_proj));
  const double* e = view.eye;
  const double* n = view.near_plane;
  for (int k = 0; k < 3; ++k) py.p[0][k] = e[k];
  const double cx[4] = {-1, 1, 1, -1}, cy[4] = {-1, -1, 1, 1};
  for (int c = 0; c < 4; ++c) {
    // A point on the corner's ray inside the frustum for every depth convention (ndc z = 0.5).
    const glm::dvec4 h = inv * glm::dvec4(cx[c] * 1.001, cy[c] * 1.001, 0.5, 1.0);
    if (!(std::fabs(h.w) > 0.0)) return py;
    const double d[3] = {h.x / h.w - e[0], h.y / h.w - e[1], h.z / h.w - e[2]};
    const double along = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    const double at_eye = n[0] * e[0] + n[1] * e[1] + n[2] * e[2] + n[3];
    if (!(along > 0.0)) return py;
    const double t = -at_eye / along * 1.001;
    for (int k = 0; k < 3; ++k) py.p[c + 1][k] = e[k] + t * d[k];
  }
  const auto plane_of = [&](const double* a, const double* b, const double* c, const double* inside, double* out) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
    out[3] = -(out[0] * a[0] + out[1] * a[1] + out[2] * a[2]);
    if (out[0] * inside[0] + out[1] * inside[1] + out[2] * inside[2] + out[3] > 0.0)
      for (int k = 0; k < 4; ++k) out[k] = -out[k];
  };
  double centre[3];
  for (int k = 0; k < 3; ++k) centre[k] = 0.5 * py.p[0][k] + 0.125 * (py.p[1][k] + py.p[2][k] + py.p[3][k] + py.p[4][k]);
  for (int c = 0; c < 4; ++c) plane_of(py.p[0], py.p[1 + c], py.p[1 + (c + 1) % 4], centre, py.plane[c]);
  plane_of(py.p[1], py.p[2], py.p[3], centre, py.plane[4]);
  py.ok = true;
  for (const auto& q : py.p)
    for (double v : q) py.ok = py.ok && std::isfinite(v);
  return py;
}

/// False only when `box` certainly misses the pyramid: separated by a face of the box or of the
/// pyramid (with a margin far above the rounding of these sums).
inline bool box_meets_pyramid(const Aabb& box, const NearPyramid& py) {
  if (!py.ok) return true;
  double scale = 0.0;
  for (const auto& q : py.p)
    for (double v : q) scale = std::max(scale, std::fabs(v));
  for (int a = 0; a < 3; ++a) scale = std::max(scale, std::max(std::fabs(double(box.min[a])), std::fabs(double(box.max[a]))));
  const double tol = 1e-9 * scale;
  for (int a = 0; a < 3; ++a) {
    bool below = true, above = true;
    for (const auto& q : py.p) {
      below = below && q[a] < box.min[a] - tol;
      above = above && q[a] > box.max[a] + tol;
    }
    if (below || above) return false;
  }
  for (const auto& pl : py.plane) {
    const double len = std::fabs(pl[0]) + std::fabs(pl[1]) + std::fabs(pl[2]);
    bool outside = true;
    for (int k = 0; k < 8 && outside; ++k) {
      const double x = k & 1 ? box.max.x : box.min.x, y = k & 2 ? box.max.y : box.min.y, z = k & 4 ? box.max.z : box.min.z;
      outside = pl[0] * x + pl[1] * y + pl[2] * z + pl[3] > tol * len;
    }
    if (outside) return false;
  }
  return true;
}

/// Fills `s.box_tree` with the biggest solid-box objects on screen. A box is a solid only for rays
/// that enter it beyond the near plane (what lies nearer is clipped: a ray entering there goes on
/// inside it and out through a back face), so a box that may meet the part of the frustum nearer
/// than the near plane is left out; a building beside the eye that reaches behind it stays in.
/// A box the finished grid hides already (its rectangle on cells covered nearer than it) is left
/// out too: every ray it could stop is stopped nearer on the grid, so it is taken neither into the
/// tree's work nor among the `max_box_occluders`, whose places go to boxes the grid leaves open.
/// Leaving an occluder out only hides less: conservative either way.
/// Leaves `s.box_occluders` empty when there are none. Keeps, per object, the answer of the
/// rectangle test when it took it (`s.box_rect_hidden`), for the object test to reuse.
inline void insert_box_occluders(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera,
                                 Scratch& s) {
  s.box_occluders.clear();
  s.box_rect_hidden.assign(s.in_frustum.size(), 2);
  if (params.max_box_occluders == 0) return;
  const double min_cells = std::max(1.0, params.min_occluder_screen_fraction * double(s.grid.width()) * double(s.grid.height()));
  s.box_candidates.clear();
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    const std::uint32_t o = s.in_frustum[i];
    if (!index.solid_box[o] || !index.objects[o].occludes) continue;
    const bool hidden = rect_hidden(s.grid, s.boxes[i]);
    s.box_rect_hidden[i] = hidden ? 1 : 0;
    if (hidden) continue;
    const double cells = screen_cells(s.boxes[i], s.grid);
    if (cells >= min_cells) s.box_candidates.emplace_back(static_cast<float>(cells), o);
  }
  if (s.box_candidates.empty()) return;
  if (s.box_candidates.size() > params.max_box_occluders) {
    std::nth_element(s.box_candidates.begin(), s.box_candidates.begin() + params.max_box_occluders, s.box_candidates.end(),
                     [](const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
                       return a.first > b.first || (a.first == b.first && a.second < b.second);
                     });
    s.box_candidates.resize(params.max_box_occluders);
  }
  const NearPyramid pyramid = near_pyramid(camera, s.view);
  for (const auto& c : s.box_candidates)
    if (!box_meets_pyramid(index.bounds[c.second], pyramid)) s.box_occluders.push_back(index.bounds[c.second]);
  if (s.box_occluders.empty()) return;
  s.box_tree.reset(s.view_eye);
  s.box_tree.insert_box_occluders(s.box_occluders.data(), s.box_occluders.size());
}

/// The frame's own scratch memory (a task's view of it has its own overload, parallel_frame.hpp).
inline const Scratch& frame_scratch(const Scratch& s) { return s; }

/// The object test. Its box first (one rectangle, usually enough); else, when the object is cut into
/// patches, each patch by its box or, for a patch of at most `object_test_triangles` triangles, by
/// its triangles. Every triangle that can be seen is in some patch, so the object is hidden when all
/// of its patches are. An object with no patch (only degenerate triangles) rests on its box.
template <class Frame>  // Scratch, or a task's view of it (parallel_frame.hpp)
inline bool object_hidden(const MeshIndex& index, const MeshOcclusionParams& params, Frame& s, std::size_t i) {
  const std::uint32_t o = s.in_frustum[i];
  // Its box: the rectangle test's answer when insert_box_occluders took it, else the whole test.
  const std::uint8_t rect = frame_scratch(s).box_rect_hidden[i];
  if (rect == 1 || (rect == 0 ? solid_boxes_hide(frame_scratch(s), s.boxes[i], index.bounds[o])
                              : box_hidden(s, s.boxes[i], index.bounds[o])))
    return true;
  const PatchSet& ps = index.patches;
  const std::uint32_t p0 = ps.object_first[o], p1 = ps.object_first[o + 1];
  if (p0 == p1) return false;
  // One patch whose box is the object's box and too many triangles to test: nothing tighter.
  if (p1 - p0 == 1 && ps.patches[p0].count > params.object_test_triangles) return false;
  for (std::uint32_t p = p0; p < p1; ++p) {
    const Patch& patch = ps.patches[p];
    // No ray through the frustum meets a patch outside it.
    if (p1 - p0 > 1 && (s.frustum.classify(patch.box) == Containment::outside || rect_hidden(s.grid, patch_box(index, s, p))))
      continue;
    if (patch.count > params.object_test_triangles || !patch_triangles_hidden(index, s, patch)) return false;
  }
  return true;
}


}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
