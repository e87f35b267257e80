// cullkit/geometry/shadow_caster_volume.hpp: the region where an object can cast a directional
// light's shadow into a view.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "convex_volume.hpp"
#include "frustum.hpp"
#include "plane.hpp"

namespace cullkit {

namespace detail {

struct DVec3 {
  double x, y, z;
};
inline DVec3 dvec(const glm::vec3& v) noexcept { return DVec3{v.x, v.y, v.z}; }
inline double ddot(const DVec3& a, const DVec3& b) noexcept { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline DVec3 dcross(const DVec3& a, const DVec3& b) noexcept {
  return DVec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// A point on the line where planes p and q meet: the point of that line closest to the origin.
// False when the planes are (nearly) parallel.
inline bool plane_pair_point(const Plane& p, const Plane& q, DVec3& point, DVec3& direction) noexcept {
  const DVec3 n1 = dvec(p.normal), n2 = dvec(q.normal);
  const DVec3 u = dcross(n1, n2);
  const double uu = ddot(u, u);
  if (!(uu > 1e-12)) return false;
  // x = ((-d1) (n2 x u) + (-d2) (u x n1)) / |u|^2 lies on both planes (n . x = -d).
  const DVec3 a = dcross(n2, u), b = dcross(u, n1);
  const double d1 = -double(p.d), d2 = -double(q.d);
  point = DVec3{(d1 * a.x + d2 * b.x) / uu, (d1 * a.y + d2 * b.y) / uu, (d1 * a.z + d2 * b.z) / uu};
  direction = u;
  return true;
}

}  // namespace detail

/// For a directional light shining along `light_direction` (from the light into the scene), a
/// convex volume that every object whose shadow can fall on a point inside `view` meets: the view
/// swept towards the light to infinity. Objects outside it can be skipped when drawing that
/// light's shadow map for this view; off-screen objects between the light and the view survive.
///
/// Construction: the planes of `view` that the sweep does not cross (normal . light_direction <= 0)
/// are kept, and for every edge of the view between a kept plane and a crossed one, the plane
/// through that edge parallel to the light direction is added (at most 6 + 12 planes). An infinite
/// far plane (dropped) simply has no edges. Planes are computed in double; the box test's float
/// slack covers their rounding, so the answer is conservative.
/// Degenerate input: a view without planes, or a zero or non-finite direction, gives a volume
/// without planes (everything may cast). A view with some planes dropped keeps the planes it can
/// prove (never fewer objects than the exact set).
/// Tightness, measured in tests/engine (finite views, random boxes against the exact swept-box
/// test): see docs/engine_fit.md. Cost: O(1), no allocation.
[[nodiscard]] inline ConvexVolume shadow_caster_volume(const Frustum& view, const glm::vec3& light_direction) noexcept {
  ConvexVolume out;
  const double len = std::sqrt(double(light_direction.x) * light_direction.x +
                               double(light_direction.y) * light_direction.y +
                               double(light_direction.z) * light_direction.z);
  if (!(len > 0.0) || !std::isfinite(len) || view.active_mask() == 0) return out;
  const detail::DVec3 d{light_direction.x / len, light_direction.y / len, light_direction.z / len};
  bool kept[Frustum::max_planes] = {};
  for (int i = 0; i < Frustum::max_planes; ++i) {
    if (!view.has_plane(i)) continue;
    kept[i] = detail::ddot(detail::dvec(view.plane(i).normal), d) <= 0.0;
    if (kept[i]) out.add_plane(view.plane(i));
  }
  // The 12 edges of a frustum: near and far quads (4 each) and the 4 side edges.
  using F = Frustum;
  static constexpr int edges[12][2] = {{F::near_plane, F::left}, {F::near_plane, F::right},  {F::near_plane, F::bottom},
                                       {F::near_plane, F::top},  {F::far_plane, F::left},    {F::far_plane, F::right},
                                       {F::far_plane, F::bottom}, {F::far_plane, F::top},    {F::left, F::bottom},
                                       {F::left, F::top},        {F::right, F::bottom},      {F::right, F::top}};
  for (const auto& e : edges) {
    const int i = e[0], j = e[1];
    if (!view.has_plane(i) || !view.has_plane(j) || kept[i] == kept[j]) continue;
    detail::DVec3 p, u;
    if (!detail::plane_pair_point(view.plane(i), view.plane(j), p, u)) continue;
    detail::DVec3 n = detail::dcross(u, d);
    const double nn = std::sqrt(detail::ddot(n, n));
    if (!(nn > 1e-9 * std::sqrt(detail::ddot(u, u)))) continue;  // edge parallel to the light
    n = detail::DVec3{n.x / nn, n.y / nn, n.z / nn};
    // The view lies in the wedge of planes i and j, whose inward bisector is n_i + n_j: the new
    // plane faces that way.
    const detail::DVec3 bisector{double(view.plane(i).normal.x) + view.plane(j).normal.x,
                                 double(view.plane(i).normal.y) + view.plane(j).normal.y,
                                 double(view.plane(i).normal.z) + view.plane(j).normal.z};
    const double orient = detail::ddot(n, bisector);
    if (!(std::fabs(orient) > 1e-9)) continue;
    if (orient < 0.0) n = detail::DVec3{-n.x, -n.y, -n.z};
    const Plane plane{glm::vec3(float(n.x), float(n.y), float(n.z)), float(-detail::ddot(n, p))};
    out.add_plane(plane);
  }
  return out;
}

}  // namespace cullkit
