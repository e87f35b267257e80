// cullkit/detail/mesh_occlusion/view.hpp: the per-frame projection through the eye, in double
// precision, onto the coverage grid, with the near-plane test and the depth measure.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "../../geometry/camera.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// A point seen from the eye: grid coordinates (x right, y down, one unit per cell) and depth w
/// (clip-space w measured from the eye, which grows along every ray from it). `usable` is false
/// when the point is not clearly beyond the near plane (or not in front of the eye): such a point
/// may neither occlude nor be hidden. `inside` (implies `usable`) is true when the point is also
/// beyond the occluder clipping level (`View::clip_level`): occluder triangles keep only that part.
struct Projected {
  double x, y, w;
  bool usable;
  bool inside;
};

/// Projection of one frame. Points are projected through `eye` itself with the linear part of
/// the matrix: a ray from the eye then lands on one grid point however far it goes, so coverage
/// and depth reason about the rays exactly (the matrix's own centre of projection may differ from
/// the eye by rounding; that difference widens the grid a little, see `setup`).
struct View {
  bool enabled = false;      // false: no occlusion this frame (orthographic, degenerate, NaN)
  double row[3][3] = {};     // clip x, y, w rows (linear part)
  double eye[3] = {};
  double near_plane[4] = {};  // world plane; beyond the near plane where positive
  double scale_x = 0, scale_y = 0, offset_x = 0, offset_y = 0;  // ndc -> grid
  int width = 0, height = 0;
  int orient = 1;  // front-facing triangles have grid signed area of this sign
  // Near-plane values (see set_clip_level): occluder triangles are clipped where theirs falls below
  // clip_level; an object's triangle counts as drawable down to -drawable_level.
  double clip_level = HUGE_VAL;
  double drawable_level = HUGE_VAL;

  /// Sets up the frame; `enabled` is false when the matrix is not a usable perspective projection
  /// centred (within a small fraction of the near distance) on the eye.
  void setup(const Camera& camera, int grid_width, int grid_height) {
    enabled = false;
    width = grid_width;
    height = grid_height;
    double m[4][4];  // m[row][col]
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[r][c] = static_cast<double>(camera.view_proj[c][r]);
    const double e[3] = {camera.eye.x, camera.eye.y, camera.eye.z};
    for (int k = 0; k < 3; ++k) {
      eye[k] = e[k];
      if (!std::isfinite(e[k])) return;
    }
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c)
        if (!std::isfinite(m[r][c])) return;
    // The two depth planes; the near one has the eye on its outside, the far one (or the plane at
    // infinity, a constant) has it inside.
    double p1[4], p2[4];
    const bool zero_to_one = camera.depth == DepthRange::zero_to_one;
    for (int k = 0; k < 4; ++k) {
      p1[k] = zero_to_one ? m[2][k] : m[3][k] + m[2][k];
      p2[k] = m[3][k] - m[2][k];
    }
    const auto at_eye = [&](const double* p) { return p[0] * e[0] + p[1] * e[1] + p[2] * e[2] + p[3]; };
    const double s1 = at_eye(p1), s2 = at_eye(p2);
    double near_ndc;
    if (s1 < 0.0 && s2 > 0.0) {
      for (int k = 0; k < 4; ++k) near_plane[k] = p1[k];
      near_ndc = zero_to_one ? 0.0 : -1.0;
    } else if (s2 < 0.0 && s1 > 0.0) {
      for (int k = 0; k < 4; ++k) near_plane[k] = p2[k];
      near_ndc = 1.0;
    } else {
      return;
    }
    const int rows[3] = {0, 1, 3};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) row[r][c] = m[rows[r]][c];
    const double det = row[0][0] * (row[1][1] * row[2][2] - row[1][2] * row[2][1]) -
                       row[0][1] * (row[1][0] * row[2][2] - row[1][2] * row[2][0]) +
                       row[0][2] * (row[1][0] * row[2][1] - row[1][1] * row[2][0]);
    const auto norm = [](const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    const double scale = norm(row[0]) * norm(row[1]) * norm(row[2]);
    if (!(std::fabs(det) > 1e-9 * scale)) return;  // orthographic (no w row) or singular
    orient = det > 0.0 ? 1 : -1;
    // Clip coordinates of the eye: zero for the matrix's own centre; what is left is rounding.
    double b[3];
    for (int r = 0; r < 3; ++r)
      b[r] = m[rows[r]][0] * e[0] + m[rows[r]][1] * e[1] + m[rows[r]][2] * e[2] + m[rows[r]][3];
    // Smallest w over the near rectangle of the frustum (w is affine and grows along rays, so its
    // minimum over the part of the frustum beyond the near plane is at one of these corners).
    const glm::dmat4 inv = glm::inverse(glm::dmat4(camera.view_proj));
    double w_min = HUGE_VAL;
    for (int corner = 0; corner < 4; ++corner) {
      const glm::dvec4 h = inv * glm::dvec4(corner & 1 ? 1.0 : -1.0, corner & 2 ? 1.0 : -1.0, near_ndc, 1.0);
      if (!(std::fabs(h.w) > 0.0)) return;
      const double wx = h.x / h.w, wy = h.y / h.w, wz = h.z / h.w;
      const double w = m[3][0] * wx + m[3][1] * wy + m[3][2] * wz + m[3][3];
      if (!std::isfinite(w)) return;
      w_min = std::min(w_min, w);
    }
    // A point p of the frustum beyond the near plane has |x/w| <= 1 for the matrix; seen through
    // the eye its x is (x - b_x) / (w - b_w), at most this far away:
    const double bw = std::fabs(b[2]);
    if (!(w_min > 4.0 * bw) || !(w_min > 0.0)) return;
    const double spread = (std::max(std::fabs(b[0]), std::fabs(b[1])) + bw) / (w_min - bw);
    if (!(spread < 0.01)) return;
    const double half_extent = 1.0 + spread + 1e-9;  // ndc half-extent the grid covers
    scale_x = 0.5 * grid_width / half_extent;
    offset_x = 0.5 * grid_width;
    scale_y = -0.5 * grid_height / half_extent;
    offset_y = 0.5 * grid_height;
    // Grid y runs down: the sign of areas flips against ndc. Front-facing (counter-clockwise seen
    // from the eye) means det[p0-e, p1-e, p2-e] < 0, so ndc area has the sign of -det(rows) and grid
    // area the sign of det(rows).
    enabled = true;
  }

  /// The clipping level for points inside the box [lo, hi]. A point is usable only when its
  /// near-plane value exceeds 2^-18 of its magnitude sum (see `project`), which differs from point
  /// to point; clipping needs one plane, so the level is twice that margin taken at its largest over
  /// the box (the magnitude sum is convex, largest at a corner). Every point of the box beyond the
  /// level is then usable by the per-point rule, with room for the rounding of clip points.
  [[nodiscard]] double level_for(const double* lo, const double* hi) const {
    double sum = std::fabs(near_plane[3]);
    for (int a = 0; a < 3; ++a) sum += std::max(std::fabs(near_plane[a] * lo[a]), std::fabs(near_plane[a] * hi[a]));
    const double level = 0x1p-17 * sum;
    return std::isfinite(level) ? level : HUGE_VAL;  // nothing is inside: no clipping
  }

  /// Sets both levels for the box of the mesh's usable objects: the drawable margin of object
  /// triangles keeps it; occluders may narrow theirs to their own box (`narrow_clip_level`).
  void set_clip_level(const double* lo, const double* hi) {
    clip_level = level_for(lo, hi);
    drawable_level = clip_level;
  }

  /// Clips this frame's occluders at the level of the box holding all of them, when lower: only
  /// their points are clipped, and one plane for all of them keeps shared edges' clip points equal.
  /// A sky dome far around the scene then no longer pushes the level away from the near plane.
  void narrow_clip_level(const double* lo, const double* hi) { clip_level = std::min(clip_level, level_for(lo, hi)); }

  /// Near-plane value of a world point (positive beyond the near plane).
  [[nodiscard]] double near_value(double px, double py, double pz) const {
    return near_plane[0] * px + near_plane[1] * py + near_plane[2] * pz + near_plane[3];
  }

  /// The point of the segment a-b where the near-plane value reaches `clip_level`, projected; false
  /// when the segment does not cross that level with exactly one endpoint inside, or the point is
  /// not usable. The caller passes each edge's endpoints in one fixed order (by welded vertex id), so
  /// the two triangles sharing the edge get bit-identical points and the edge still cancels.
  /// `at`, when given, receives the world point.
  [[nodiscard]] bool clip_point(const double* a, const double* b, Projected& out, double* at = nullptr) const {
    const double na = near_value(a[0], a[1], a[2]), nb = near_value(b[0], b[1], b[2]);
    if ((na >= clip_level) == (nb >= clip_level)) return false;
    const double t = (clip_level - na) / (nb - na);
    if (!(t >= 0.0 && t <= 1.0)) return false;
    const double p[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    if (at) std::copy(p, p + 3, at);
    out = project(p[0], p[1], p[2]);
    // The point's near-plane value is clip_level up to rounding, far above the usable margin.
    return out.usable;
  }

  /// Depth w of a world point, as `project` measures it, for any point (also one not usable).
  [[nodiscard]] double depth(double px, double py, double pz) const {
    const double qx = px - eye[0], qy = py - eye[1], qz = pz - eye[2];
    return row[2][0] * qx + row[2][1] * qy + row[2][2] * qz;
  }

  /// Projects a world point.
  [[nodiscard]] Projected project(double px, double py, double pz) const {
    const double qx = px - eye[0], qy = py - eye[1], qz = pz - eye[2];
    const double cx = row[0][0] * qx + row[0][1] * qy + row[0][2] * qz;
    const double cy = row[1][0] * qx + row[1][1] * qy + row[1][2] * qz;
    const double cw = row[2][0] * qx + row[2][1] * qy + row[2][2] * qz;
    const double wscale = std::fabs(row[2][0] * qx) + std::fabs(row[2][1] * qy) + std::fabs(row[2][2] * qz);
    const double n = near_plane[0] * px + near_plane[1] * py + near_plane[2] * pz + near_plane[3];
    // The renderer clips in float: keep a point only if it is beyond the near plane by far more
    // than float rounding of the clip coordinates could move it.
    const double ntol = 0x1p-18 * (std::fabs(near_plane[0] * px) + std::fabs(near_plane[1] * py) +
                                   std::fabs(near_plane[2] * pz) + std::fabs(near_plane[3]));
    Projected out;
    out.usable = n > ntol && cw > 1e-8 * wscale && cw > 0.0;
    out.inside = false;
    if (!out.usable) {
      out.x = out.y = out.w = 0.0;
      return out;
    }
    out.w = cw;
    out.x = cx / cw * scale_x + offset_x;
    out.y = cy / cw * scale_y + offset_y;
    out.usable = std::isfinite(out.x) && std::isfinite(out.y) && std::isfinite(out.w);
    out.inside = out.usable && n >= clip_level;
    return out;
  }
};

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
