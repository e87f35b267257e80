// cullkit/detail/mesh_occlusion/box_test.hpp: the box test of a finished frame: whether every ray
// that can see a point of a box meets an occluder first. One function serves the culler's object
// boxes and MeshOcclusionContext::is_hidden, so a box query is exactly the culler's box test.
#pragma once

#include <cmath>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/mat4x4.hpp>

#include "../../geometry/aabb.hpp"
#include "coverage.hpp"
#include "frame.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// True when every cell the box view's rectangle touches is covered nearer than the box.
inline bool rect_hidden(const CoverageGrid& grid, const BoxView& b) {
  if (!b.usable) return false;
  const CellRect r = grid.cells_of(b.x0, b.y0, b.x1, b.y1);
  // A rectangle that misses the grid meets no ray through the frustum.
  const float threshold = static_cast<float>((1.0 / b.w_min) * (1.0 + 0x1p-20));
  return r.empty() || (std::isfinite(threshold) && grid.all_nearer(r, threshold));
}

/// The second half of the box test below: clearly beyond the near plane (`b` usable), inside the
/// solid boxes' hidden region.
inline bool solid_boxes_hide(const Scratch& s, const BoxView& b, const Aabb& box) {
  return !s.box_occluders.empty() && b.usable && s.box_tree.is_occluded(box);
}

/// The box test, once the frame's grid is finished and its solid boxes are in the occlusion tree:
/// `b` is `box` projected by the frame's view (project_box). Hidden when its rectangle lies on cells
/// covered nearer than it, or, clearly beyond the near plane, inside the solid boxes' hidden region.
/// Reads only: safe from several threads at once.
inline bool box_hidden(const Scratch& s, const BoxView& b, const Aabb& box) {
  return rect_hidden(s.grid, b) || solid_boxes_hide(s, b, box);
}

/// The box test for any box, against a finished frame (`ready`: the frame's grid was filled). False
/// for a box with NaN, infinite or inverted bounds and for a box not clearly beyond the near plane.
inline bool query_box_hidden(const Scratch& s, bool ready, const Aabb& box) {
  if (!ready || !is_valid(box)) return false;
  return box_hidden(s, project_box(s.view, box), box);
}

/// The world box of `local_box` placed by `model` (affine): the bounds of its 8 corners, computed in
/// double precision and rounded outward to float. False when it cannot be had (invalid box, a
/// non-finite or non-affine matrix, a result beyond float range).
inline bool oriented_bounds(const Aabb& local_box, const glm::mat4& model, Aabb& out) {
  if (!is_valid(local_box)) return false;
  const glm::dmat4 m(model);
  if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) return false;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int k = 0; k < 8; ++k) {
    const glm::dvec4 p = m * glm::dvec4(k & 1 ? local_box.max.x : local_box.min.x, k & 2 ? local_box.max.y : local_box.min.y,
                                        k & 4 ? local_box.max.z : local_box.min.z, 1.0);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    // Outward past the rounding of the products above (2^-40 relative, far above it) and to float.
    const double pad = 0x1p-40 * (std::fabs(lo[a]) + std::fabs(hi[a]));
    const float l = static_cast<float>(lo[a] - pad), h = static_cast<float>(hi[a] + pad);
    out.min[a] = static_cast<double>(l) > lo[a] - pad ? std::nextafter(l, -HUGE_VALF) : l;
    out.max[a] = static_cast<double>(h) < hi[a] + pad ? std::nextafter(h, HUGE_VALF) : h;
  }
  return is_valid(out);
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
