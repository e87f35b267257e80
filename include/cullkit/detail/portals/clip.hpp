// cullkit/detail/portals/clip.hpp: the geometric step of the portal traversal. A portal polygon is
// clipped, in double precision and with outward margins, by the planes of the current view volume,
// and what is left spans the narrowed volume of the next cell.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "../../geometry/convex_volume.hpp"
#include "../../geometry/plane.hpp"

namespace cullkit::detail {

/// Room for a 16-corner portal cut by all 32 planes of a volume (each cut adds at most one corner).
constexpr std::size_t portal_clip_capacity = 16 + ConvexVolume::max_planes;

/// A convex polygon in double precision, stored inline.
struct PortalPolygon {
  glm::dvec3 v[portal_clip_capacity];
  std::size_t n = 0;
};

/// What the graph stores per portal, computed once when the portal is added.
struct PortalRecord {
  std::uint32_t cells[2] = {0, 0};
  std::uint32_t first_corner = 0;
  std::uint32_t corner_count = 0;
  glm::dvec3 normal{0.0};  ///< unit normal of the best-fit plane (Newell), either orientation
  double d = 0.0;          ///< plane offset: dot(normal, p) + d
  double thickness = 0.0;  ///< largest distance of a corner from that plane, plus rounding
  bool open = false;       ///< unusable polygon: lets every ray through (never narrows)
};

/// Float rounding of a float dot product with magnitude `mag`, generously bounded.
[[nodiscard]] inline double rounding_slack(double mag) noexcept {
  return 32.0 * static_cast<double>(std::numeric_limits<float>::epsilon()) * mag;
}

/// Keeps the part of `poly` where `dot(n, p) + d >= 0` (Sutherland-Hodgman). Corners exactly on
/// the plane are kept; a crossing corner is interpolated from the corner farther from the plane.
inline void clip_polygon(PortalPolygon& poly, const glm::dvec3& n, double d) noexcept {
  if (poly.n == 0) return;
  double dist[portal_clip_capacity];
  bool any_out = false;
  for (std::size_t i = 0; i < poly.n; ++i) {
    dist[i] = glm::dot(n, poly.v[i]) + d;
    if (!(dist[i] >= 0.0)) any_out = true;
  }
  if (!any_out) return;
  PortalPolygon out;
  for (std::size_t i = 0; i < poly.n; ++i) {
    const std::size_t j = i + 1 == poly.n ? 0 : i + 1;
    const bool in_i = dist[i] >= 0.0, in_j = dist[j] >= 0.0;
    if (in_i && out.n < portal_clip_capacity) out.v[out.n++] = poly.v[i];
    if (in_i != in_j && out.n < portal_clip_capacity) {
      const double t = dist[i] / (dist[i] - dist[j]);
      if (std::isfinite(t)) out.v[out.n++] = poly.v[i] + (poly.v[j] - poly.v[i]) * t;
    }
  }
  poly = out;
}

/// Fills `poly` with the portal's corners, then clips it by every plane of `volume`. Each plane is
/// first moved outward so that it holds the eye, unless its bit is set in `crossed` (a portal plane
/// every ray of the chain has already passed: its crossing points are beyond it). A ray from the
/// eye that is outside a plane holding the eye at the portal stays outside it from then on, so
/// every crossing point of a ray that reaches the next cell inside the volume survives the clip.
/// Rounding is covered by a further outward margin.
inline void clip_portal(const glm::vec3* corners, std::size_t count, const glm::dvec3& eye,
                        const ConvexVolume& volume, VolumeMask crossed, PortalPolygon& poly) noexcept {
  poly.n = 0;
  double extent = 0.0;
  for (std::size_t i = 0; i < count && i < 16; ++i) {
    poly.v[poly.n++] = glm::dvec3(corners[i]);
    extent = std::fmax(extent, std::fabs(poly.v[i].x) + std::fabs(poly.v[i].y) + std::fabs(poly.v[i].z));
  }
  const double eye_extent = std::fabs(eye.x) + std::fabs(eye.y) + std::fabs(eye.z);
  for (std::size_t k = 0; k < volume.plane_count() && poly.n > 0; ++k) {
    const Plane& p = volume.plane(k);
    const glm::dvec3 n(p.normal);
    double d = static_cast<double>(p.d);
    const double nmax = std::fmax(std::fabs(n.x), std::fmax(std::fabs(n.y), std::fabs(n.z)));
    if (!((crossed >> k) & 1u)) {
      const double at_eye = glm::dot(n, eye) + d;
      if (at_eye < 0.0) d -= at_eye;
      d += rounding_slack(nmax * eye_extent + std::fabs(d));
    }
    d += rounding_slack(nmax * extent + std::fabs(d));
    clip_polygon(poly, n, d);
  }
}

/// Turns the clipped portal `poly` into the volume of the cell beyond it: the frustum's planes, the
/// portal's plane (inside: the side away from the eye) and one plane through the eye and each edge
/// of `poly` (inside: toward the polygon). Every plane is widened by a rounding margin. Edge planes
/// that are degenerate (an edge of no length, or in line with the eye) are left out, and so are
/// those beyond the volume's 32-plane capacity: both only widen the volume. `crossed` gets the bit
/// of the portal plane. Returns false when `poly` has no area left.
inline bool portal_volume(const PortalRecord& portal, const PortalPolygon& poly, const glm::dvec3& eye,
                          const ConvexVolume& frustum_volume, ConvexVolume& out, VolumeMask& crossed) noexcept {
  if (poly.n < 3) return false;
  out = frustum_volume;
  crossed = 0;
  const double eye_extent = std::fabs(eye.x) + std::fabs(eye.y) + std::fabs(eye.z);
  // The portal plane, facing away from the eye, widened by the polygon's own thickness.
  const double at_eye = glm::dot(portal.normal, eye) + portal.d;
  const double s = at_eye < 0.0 ? 1.0 : -1.0;
  const double pd = s * portal.d + portal.thickness +
                    rounding_slack(std::fabs(portal.d) + eye_extent);
  const std::size_t portal_bit = out.plane_count();
  if (out.add_plane(Plane{glm::vec3(portal.normal * s), static_cast<float>(pd)}) && out.plane_count() > portal_bit)
    crossed |= VolumeMask{1} << portal_bit;
  glm::dvec3 centre(0.0);
  for (std::size_t i = 0; i < poly.n; ++i) centre += poly.v[i];
  centre /= static_cast<double>(poly.n);
  for (std::size_t i = 0; i < poly.n && out.plane_count() < ConvexVolume::max_planes; ++i) {
    const glm::dvec3 a = poly.v[i] - eye;
    const glm::dvec3 b = poly.v[i + 1 == poly.n ? 0 : i + 1] - eye;
    glm::dvec3 n = glm::cross(a, b);
    const double len = glm::length(n);
    const double reach = std::fmax(glm::length(a), glm::length(b));
    if (!(len > 1e-12 * reach * reach)) continue;
    n /= len;
    if (glm::dot(n, centre - eye) < 0.0) n = -n;
    const double nd = -glm::dot(n, eye);
    const double margin = rounding_slack(std::fabs(n.x * eye.x) + std::fabs(n.y * eye.y) +
                                         std::fabs(n.z * eye.z) + reach);
    out.add_plane(Plane{glm::vec3(n), static_cast<float>(nd + margin)});
  }
  return true;
}

}  // namespace cullkit::detail
