// cullkit/box_proxy.hpp: a solid box occluder reduced to its outline as seen from one eye.
//
// Seed: 基于主要遮挡物的动态可见性算法 (dynamic visibility with major occluders), §3.3 (see
// docs/papers.md), corrected as below. The eye's position against the three slabs of a box picks
// one of 27 regions; a constant 26-entry table (detail/box_proxy/table.hpp) then names the 4 or 6
// outline corners and the 1 to 3 front faces directly, so building a proxy costs six comparisons
// and a table read.
//
// What a proxy hides. The outline spans a beam from the eye (one plane through the eye and each
// outline edge). A point inside that beam is hidden exactly when it lies behind every front-face
// plane: the ray to it has then entered the box. The seed instead closes the beam with one plane
// through the box centre, perpendicular to the view line; that plane cuts through the box, so seen
// obliquely it hides things resting on the box's far end (a rooftop antenna) that the eye sees. It
// is kept as `ProxyClosure::center_plane` for comparison only; never use it to cull.
//
// Conventions. Corner ids as `cullkit::corner` (bit 0 x, bit 1 y, bit 2 z; set = max). "Counter-
// clockwise seen from the eye" means the polygon's Newell normal points toward the eye, the same
// winding rule as a front-facing triangle (cullkit::Camera). A face the eye sees exactly edge-on
// (eye coordinate equal to the face's min or max) counts as facing away.
//
// Degenerate input (documented answers, never a crash, never a proxy that hides too much):
//  * invalid box (`!is_valid(box)`: NaN, infinite, min > max) or non-finite eye: region 13, no proxy;
//  * eye inside or on the closed box: region 13, no proxy;
//  * flat box (zero extent on exactly one axis, a rectangle): seen from one side of its plane, the
//    proxy is that rectangle (4 corners, 1 front face, in whatever region the eye is); with the eye
//    in the rectangle's plane (outside it) it has no area as seen from the eye: no proxy;
//  * box flat on two or three axes (a segment or a point): no proxy.
// A proxy never has repeated corners.
//
// All functions are pure, allocate nothing, and are safe to call concurrently.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "config.hpp"
#include "detail/box_proxy/table.hpp"
#include "geometry/aabb.hpp"
#include "geometry/plane.hpp"

namespace cullkit {

/// How a proxy closes the beam of its outline (what counts as "behind" the box).
enum class ProxyClosure : std::uint8_t {
  /// Default and exact: a point in the beam is hidden iff it is behind every front-face plane
  /// (1 to 3 axis-aligned planes, exact in float).
  front_faces,
  /// The seed's single plane through the box centre, perpendicular to the eye-to-centre line.
  /// NOT conservative: seen obliquely, part of the box's front surface lies behind that plane, so
  /// objects resting on the far end of the box are hidden although visible. Comparison only.
  center_plane,
};

/// The outline of a box as seen from one eye, and the planes that close its beam. A trivially
/// copyable value (about 140 bytes); build it with `make_box_proxy`.
struct BoxProxy {
  /// Region of the eye (see `box_region`); 13 when there is no proxy for an invalid input.
  int region = 13;
  /// Outline corners: 0 (no proxy), 4 (one front face) or 6 (two or three front faces).
  std::uint8_t corner_count = 0;
  /// Closure planes in `faces`: 1..3 front faces (front_faces), 1 (center_plane), 0 without proxy.
  std::uint8_t face_count = 0;
  /// The outline, counter-clockwise seen from the eye; the corners are exact box corners. Entries
  /// past `corner_count` hold filler (a box corner), never read them as outline.
  glm::vec3 corners[6] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f),
                          glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)};
  /// Closure planes, unit normals pointing INTO the box (away from the eye): `signed_distance >= 0`
  /// means behind that plane. Front-face planes are axis-aligned and exact. With center_plane,
  /// faces[0] is the seed's plane through the centre. Entries past `face_count` hold filler.
  Plane faces[3] = {Plane{glm::vec3(0.0f), 0.0f}, Plane{glm::vec3(0.0f), 0.0f},
                    Plane{glm::vec3(0.0f), 0.0f}};
  /// The axis (0, 1, 2) each front face is perpendicular to; 3 for the seed's centre plane.
  std::uint8_t face_axis[3] = {0, 0, 0};
  /// The closure this proxy was built with.
  ProxyClosure closure = ProxyClosure::front_faces;

  /// True if there is an outline (the eye is strictly outside a box with area as seen from it).
  [[nodiscard]] bool valid() const { return corner_count != 0; }
};

/// Region of `eye` among the 27 cut by the box's three slabs: ix + 3*iy + 9*iz, with i = 0 below min,
/// 1 within [min, max] inclusive (on a face plane counts as within: that face is seen edge-on), 2
/// above max. 13 means inside or on the box, and is also the answer for an invalid box or a
/// non-finite eye (no proxy). Cost: six comparisons plus finiteness checks.
[[nodiscard]] inline int box_region(const Aabb& box, const glm::vec3& eye) noexcept {
  if (!is_valid(box) || !std::isfinite(eye.x) || !std::isfinite(eye.y) || !std::isfinite(eye.z)) {
    return 13;
  }
  const int ix = int(eye.x >= box.min.x) + int(eye.x > box.max.x);
  const int iy = int(eye.y >= box.min.y) + int(eye.y > box.max.y);
  const int iz = int(eye.z >= box.min.z) + int(eye.z > box.max.z);
  return ix + 3 * iy + 9 * iz;
}

namespace detail {

/// The table entry for `box` seen from `eye` after the degenerate cases (see the file comment), or
/// nullptr when there is no proxy. Writes the eye's region to `region`.
[[nodiscard]] inline const BoxOutlineEntry* box_outline_entry(const Aabb& box, const glm::vec3& eye,
                                                              int& region) noexcept {
  region = box_region(box, eye);
  if (region == 13) return nullptr;
  const int flat_axes = int(box.min.x == box.max.x) + int(box.min.y == box.max.y) + int(box.min.z == box.max.z);
  if (flat_axes == 0) return &box_outline_table[region];  // the common case
  if (flat_axes >= 2) return nullptr;                      // a segment or a point: no area from anywhere
  // A rectangle: only its own two faces have area. Seen from within its plane it has none;
  // otherwise the outline is the one face on the eye's side, which the table holds in the region
  // that is "within" on the two other axes (same face, same winding from that side).
  const int axis = box.min.x == box.max.x ? 0 : (box.min.y == box.max.y ? 1 : 2);
  const int digit = axis == 0 ? region % 3 : (axis == 1 ? (region / 3) % 3 : region / 9);
  if (digit == 1) return nullptr;
  constexpr int stride[3] = {1, 3, 9};
  return &box_outline_table[13 + (digit - 1) * stride[axis]];
}

/// Corner `id` of `box` without branches (the ids come from the table, in no predictable order).
[[nodiscard]] CULLKIT_FORCEINLINE glm::vec3 box_corner_select(const glm::vec3 (&min_max)[2], int id) noexcept {
  return glm::vec3(min_max[id & 1].x, min_max[(id >> 1) & 1].y, min_max[(id >> 2) & 1].z);
}

}  // namespace detail

/// Builds the proxy of `box` seen from `eye`: outline corners from the region table, and the
/// closure planes (`front_faces`: the 1..3 front-face planes; `center_plane`: the seed's plane).
/// Returns a proxy with `valid() == false` (corner_count 0) for the degenerate cases in the file
/// comment. Cost: a handful of comparisons, a table read, 4-6 corner copies, no data-dependent
/// branches in the common case; no allocation.
[[nodiscard]] inline BoxProxy make_box_proxy(const Aabb& box, const glm::vec3& eye,
                                             ProxyClosure closure = ProxyClosure::front_faces) noexcept {
  BoxProxy proxy;
  proxy.closure = closure;
  const detail::BoxOutlineEntry* entry = detail::box_outline_entry(box, eye, proxy.region);
  if (entry == nullptr) return proxy;

  const glm::vec3 min_max[2] = {box.min, box.max};
  proxy.corner_count = entry->corner_count;
  for (int i = 0; i < 6; ++i) proxy.corners[i] = detail::box_corner_select(min_max, entry->corners[i]);

  if (closure == ProxyClosure::center_plane) {
    const glm::vec3 center = box.center();
    proxy.face_count = 1;
    proxy.faces[0] = plane_from_point_normal(center, center - eye);
    proxy.face_axis[0] = 3;
    if (!is_valid(proxy.faces[0])) proxy.corner_count = 0;  // unreachable for an eye outside the box
    return proxy;
  }
  proxy.face_count = entry->face_count;
  for (int f = 0; f < 3; ++f) {  // all three, unused ones as filler: no data-dependent trip count
    const int axis = entry->faces[f] >> 1;
    const int side = entry->faces[f] & 1;  // 1: the max face, its inward normal is -axis
    const float sign = float(1 - 2 * side);
    glm::vec3 n(0.0f);
    n[axis] = sign;
    proxy.faces[f] = Plane{n, -sign * min_max[side][axis]};
    proxy.face_axis[f] = static_cast<std::uint8_t>(axis);
  }
  return proxy;
}

/// The corners of the box's outline as seen from `eye` (4 or 6; faces seen exactly edge-on count
/// as facing away), counter-clockwise as seen from the eye, written to `out[0..n)`; returns n, or 0
/// if the eye is inside or on the box, the box or eye is invalid, or the box has no area as seen from
/// the eye (see the file comment on flat boxes). `out[n..6)` may be overwritten. Pre: `out` points
/// to room for 6 corners. Cost: as `make_box_proxy` without the planes; no allocation.
inline std::size_t box_silhouette(const Aabb& box, const glm::vec3& eye, glm::vec3 out[6]) noexcept {
  CULLKIT_ASSERT(out != nullptr, "box_silhouette: out must point to room for 6 corners");
  int region = 13;
  const detail::BoxOutlineEntry* entry = detail::box_outline_entry(box, eye, region);
  if (entry == nullptr) return 0;
  const glm::vec3 min_max[2] = {box.min, box.max};
  for (int i = 0; i < 6; ++i) out[i] = detail::box_corner_select(min_max, entry->corners[i]);
  return entry->corner_count;
}

/// The planes of the outline's beam: plane i passes through `eye`, corners[i] and corners[i+1]
/// (cyclically), unit normal pointing into the beam (toward the outline), so a point is inside the
/// beam when every `signed_distance` is >= 0. Computed in double, rounded to float (so a point
/// within float rounding of a beam plane may fall on either side: treat near-zero as outside when
/// culling). Returns the number of planes (= corner_count); an edge the eye is collinear with (not
/// possible in exact arithmetic) yields the zero plane; check `is_valid`. Pre: `eye` is the eye the
/// proxy was made for; `out` has room for 6. Cost: 6 cross products; no allocation.
[[nodiscard]] inline std::size_t proxy_beam_planes(const BoxProxy& proxy, const glm::vec3& eye,
                                                   Plane out[6]) noexcept {
  CULLKIT_ASSERT(out != nullptr, "proxy_beam_planes: out must point to room for 6 planes");
  const std::size_t n = proxy.corner_count;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 e(eye);
    const glm::dvec3 a = glm::dvec3(proxy.corners[i]) - e;
    const glm::dvec3 b = glm::dvec3(proxy.corners[(i + 1) % n]) - e;
    const glm::dvec3 normal = glm::cross(b, a);  // inward for a counter-clockwise outline
    const double len = glm::length(normal);
    if (!(len > 0.0) || !std::isfinite(len)) {
      out[i] = Plane{glm::vec3(0.0f), 0.0f};
      continue;
    }
    const glm::dvec3 u = normal / len;
    out[i] = Plane{glm::vec3(u), static_cast<float>(-glm::dot(u, e))};
  }
  return n;
}

/// Is point `p` hidden from `eye` by the proxy's box? True only when `p` is strictly inside the
/// beam of the outline and strictly behind every closure plane (points on any boundary count as
/// visible), evaluated in double precision. With `front_faces` this is exact up to rounding: it
/// agrees with a ray-box test of the segment eye-p, and points inside the box count as hidden. With
/// `center_plane` it is the seed's answer, which wrongly hides some visible points (see the file
/// comment). False for an invalid proxy or a non-finite point. Pre: `eye` is the eye the proxy was
/// made for. Cost: up to 6 cross products and 9 dot products in double; no allocation.
[[nodiscard]] inline bool proxy_hides(const BoxProxy& proxy, const glm::vec3& eye, const glm::vec3& p) noexcept {
  if (!proxy.valid()) return false;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  const glm::dvec3 point(p);
  for (int f = 0; f < proxy.face_count; ++f) {
    const Plane& plane = proxy.faces[f];
    if (!(glm::dot(glm::dvec3(plane.normal), point) + double(plane.d) > 0.0)) return false;
  }
  const glm::dvec3 e(eye);
  const glm::dvec3 to_p = point - e;
  const int n = proxy.corner_count;
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 a = glm::dvec3(proxy.corners[i]) - e;
    const glm::dvec3 b = glm::dvec3(proxy.corners[(i + 1) % n]) - e;
    if (!(glm::dot(glm::cross(b, a), to_p) > 0.0)) return false;
  }
  return true;
}

}  // namespace cullkit
