// cullkit/detail/nci/view.hpp: ViewSetup, what one select_visible call derives from its camera once
// (pixel rays, walk axis, screen projection of points), and the projections it serves.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "../../geometry/camera.hpp"
#include "frame_camera.hpp"
#include "watertight.hpp"
#include "context.hpp"
#include "index_data.hpp"
#include "tolerances.hpp"

namespace cullkit::detail::nci {

// ---------------------------------------------------------------- select
struct ViewSetup {
  PixelRays rays;
  glm::dvec3 eye;
  glm::vec3 eye_f;
  int axis = 2;
  glm::dmat4 view_proj;
  bool use_rect = false;   // screen rectangles of triangles may prune rays
  glm::dvec4 target_plane{0.0};  // plane holding the pixel rays' target points (world space)
  const float* initial_depth = nullptr;  // per pixel: start from this depth (moving objects)
  const float* initial_solid = nullptr;  // per pixel: and from this solid depth (>= initial_depth)
  int width = 0, height = 0;
  double eye_side = 0.0;          // -target_plane . (eye, 1)
  glm::dvec4 eye_clip{0.0};       // view_proj * (eye, 1)
  glm::dvec3 clip_x{0.0}, clip_y{0.0}, clip_w{0.0};  // rows x, y, w of view_proj's 3x3 part
  // The projection of a point eye + dx onto the target plane, in clip coordinates, is
  // (h_x . dx, h_y . dx, h_w . dx) / (plane . dx): one division per point for its pixel.
  glm::dvec3 h_x{0.0}, h_y{0.0}, h_w{0.0}, plane{0.0};
  // Pixel ray directions are positive multiples of an affine function of the pixel position
  // (one target plane whose homogeneous w keeps one sign over the screen): beside_rect may use
  // a rectangle's corner rays for the rays inside it.
  bool affine_rays = false;
  // The 2D footprint pre-test (footprint_mask) may be used: screen rectangles are on and one
  // pixel spans at least 4e-5 radians everywhere on screen (at most 25,000 pixels per radian).
  bool footprint = false;
  // Margin of screen rectangles and footprints in pixels: a twentieth of a pixel for the float
  // rounding of the ray directions, plus the ray test's edge band (tiny unless a pixel spans only
  // a few float roundings: very narrow fields of view).
  double margin = 0.05;
  // The pixels whose centres may see the (inflated) scene box: project_rect of its corners, so it
  // holds every triangle's rectangle. A tile wholly outside it has no ray to set up.
  Rect box_rect{Rect::full, 0, 0, 0};
  int tile = 32;  // the tile edge of this call
  bool cast_frame = false;  // tiles are cast through the triangle hierarchy (frame_tile.hpp), not walked
  bool cast_crowded_tiles = false;  // walked tiles that turn out crowded are cast (mixed_tile.hpp)
};

// Whether a corner lies (nearly) at the eye: its offsets from the eye, as the float ray test takes
// them, are subnormal or their products underflow, so that test has no relative precision near it
// and no rejection whose margin is relative rounding holds for its triangle (screen rectangle,
// footprint, beam planes, corner-ray planes): such a triangle is tested against every live ray.
// Above 1e-15 every product of two offsets stays a normal float (>= 2^24 FLT_MIN). NaN counts as
// near (never rejected).
[[nodiscard]] inline bool near_eye(double x, double y, double z) noexcept {
  return !(std::max({std::fabs(x), std::fabs(y), std::fabs(z)}) >= 1e-15);
}

// A point's pixel-centre coordinates (pixel i has coordinate i): its projection from the eye onto
// the target plane, in double; false when it is not strictly in front of the eye (or w <= 0).
[[nodiscard]] inline bool project_point(const ViewSetup& f, const glm::vec3& p, double& px, double& py) noexcept {
  const glm::dvec3 dx = glm::dvec3(p) - f.eye;
  if (near_eye(dx.x, dx.y, dx.z)) return false;  // no projection: callers test every ray
  // s = eye_side / pd > 0: in front of the eye (not behind it or beside it).
  const double pd = glm::dot(f.plane, dx);
  if (!(pd != 0.0) || (pd > 0.0) != (f.eye_side > 0.0)) return false;
  // Clip w = qw / pd > 0.
  const double qw = glm::dot(f.h_w, dx);
  if (!(qw != 0.0) || (qw > 0.0) != (pd > 0.0)) return false;
  const double inv = 1.0 / qw;
  // Pixel-centre coordinates: pixel i has ndc (2i + 1) / width - 1.
  px = ((glm::dot(f.h_x, dx) * inv + 1.0) * f.width - 1.0) * 0.5;
  py = ((1.0 - glm::dot(f.h_y, dx) * inv) * f.height - 1.0) * 0.5;
  return true;
}

// The pixels whose centres lie in the projected bounds [mnx, mxx] x [mny, mxy] grown by the
// margin (ViewSetup::margin: the float rounding of the ray directions and the ray test's edge
// band), clamped to the screen in double first (projected corners may be far off screen); `full`
// when a bound is not finite.
[[nodiscard]] inline Rect pixels_of_bounds(const ViewSetup& f, double mnx, double mxx, double mny, double mxy) noexcept {
  if (!(std::isfinite(mnx) && std::isfinite(mxx) && std::isfinite(mny) && std::isfinite(mxy)))
    return Rect{Rect::full, 0, 0, 0};
  const double m = f.margin;
  const double lx0 = std::ceil(mnx - m), lx1 = std::floor(mxx + m);
  const double ly0 = std::ceil(mny - m), ly1 = std::floor(mxy + m);
  if (lx1 < 0.0 || ly1 < 0.0 || lx0 > f.width - 1 || ly0 > f.height - 1) return Rect{0, 0, -1, -1};
  return Rect{static_cast<std::int16_t>(std::max(0.0, lx0)), static_cast<std::int16_t>(std::max(0.0, ly0)),
              static_cast<std::int16_t>(std::min(double(f.width - 1), lx1)),
              static_cast<std::int16_t>(std::min(double(f.height - 1), ly1))};
}

// The pixels whose centres may see a point of the convex hull of `p` (count points): the
// bounding rectangle of their projections (the hull projects into the hull of the projected
// points when every point is in front of the eye: the conditions checked are linear in the
// point, so they hold on the whole hull), `full` when the projection cannot be trusted.
[[nodiscard]] inline Rect project_rect(const ViewSetup& f, const glm::vec3* p, int count) noexcept {
  if (!f.use_rect) return Rect{Rect::full, 0, 0, 0};
  double mnx = std::numeric_limits<double>::infinity(), mny = mnx, mxx = -mnx, mxy = -mnx;
  for (int k = 0; k < count; ++k) {
    double px = 0.0, py = 0.0;
    if (!project_point(f, p[k], px, py)) return Rect{Rect::full, 0, 0, 0};
    mnx = std::min(mnx, px);
    mxx = std::max(mxx, px);
    mny = std::min(mny, py);
    mxy = std::max(mxy, py);
  }
  // A pixel centre can see the triangle only inside its projection.
  return pixels_of_bounds(f, mnx, mxx, mny, mxy);
}

// Which pixels may see the triangle: an empty rectangle for a back face (or one seen exactly
// edge-on: the eye in its plane is never a hit), `full` when the projection cannot be trusted.
[[nodiscard]] inline Rect screen_rect(const ViewSetup& f, const glm::vec3& p0, const glm::vec3& p1,
                                                  const glm::vec3& p2) noexcept {
  if (!detail::faces_eye(p0, p1, p2, f.eye)) return Rect{0, 0, -1, -1};
  const glm::vec3 p[3] = {p0, p1, p2};
  return project_rect(f, p, 3);
}

[[nodiscard]] inline ViewSetup make_frame(const IndexData& data, const FrameCamera& camera) {
  ViewSetup f{camera.rays(), glm::dvec3(camera.eye), camera.eye, 2, camera.view_proj, false,
          glm::dvec4(0.0), nullptr, nullptr, camera.width, camera.height};
  const Ray center = f.rays.ray_at(0.5 * camera.width, 0.5 * camera.height);
  const glm::vec3 d = center.direction;
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  f.axis = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  // Screen rectangles. A pixel ray runs from the eye toward a target point on one plane of the
  // projection (far, or near when far is at infinity); the pixel a point X can be seen at is
  // found by projecting X from the eye onto that plane and reading the plane point's pixel. This
  // holds even when `eye` is not exactly the matrix's centre of projection (float matrices).
  // Used only when the same plane serves the whole screen, as PixelRays decides it.
  const glm::dmat4& inv = camera.inverse;
  const glm::dvec4 far_h = inv[2] + inv[3];
  const double near_z = camera.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
  int uses_far = 0, uses_near = 0;
  for (int k = 0; k < 5; ++k) {
    const double u = k == 4 ? 0.0 : ((k & 1) ? 1.0 : -1.0), v = k == 4 ? 0.0 : ((k & 2) ? 1.0 : -1.0);
    const glm::dvec4 h = inv[0] * u + inv[1] * v + far_h;
    const double mag = std::fabs(h.x) + std::fabs(h.y) + std::fabs(h.z);
    // A margin around PixelRays' threshold: pixels near the switch would be ambiguous.
    if (std::fabs(h.w) > tolerance::target_plane_switch * mag && h.w > 0.0) ++uses_far;
    else if (!(std::fabs(h.w) > 1e-12 * mag)) ++uses_near;
  }
  if (uses_far == 5 || uses_near == 5) {
    const double z0 = uses_far == 5 ? 1.0 : near_z;
    {
      // w of the target point is affine over the screen: one sign at the four corners holds
      // everywhere between them.
      int positive = 0, negative = 0;
      for (int k = 0; k < 4; ++k) {
        const double u = (k & 1) ? 1.0 : -1.0, v = (k & 2) ? 1.0 : -1.0;
        const double w = (inv[0] * u + inv[1] * v + inv[2] * z0 + inv[3]).w;
        positive += w > 0.0;
        negative += w < 0.0;
      }
      f.affine_rays = positive == 4 || negative == 4;
    }
    glm::dvec4 row2, row3;
    for (int j = 0; j < 4; ++j) {
      row2[j] = f.view_proj[j][2];
      row3[j] = f.view_proj[j][3];
    }
    f.target_plane = row2 - z0 * row3;
    const double on_eye = glm::dot(f.target_plane, glm::dvec4(f.eye, 1.0));
    f.use_rect = std::isfinite(on_eye) && on_eye != 0.0 && camera.width <= 32000 && camera.height <= 32000;
    f.eye_side = -on_eye;
    f.eye_clip = f.view_proj * glm::dvec4(f.eye, 1.0);
    for (int j = 0; j < 3; ++j) {
      f.clip_x[j] = f.view_proj[j][0];
      f.clip_y[j] = f.view_proj[j][1];
      f.clip_w[j] = f.view_proj[j][3];
    }
    // clip = eye_clip + s view_proj dx with s = eye_side / (plane . dx): multiplied through by
    // plane . dx, each coordinate is linear in dx.
    f.plane = glm::dvec3(f.target_plane);
    f.h_x = f.eye_clip.x * f.plane + f.eye_side * f.clip_x;
    f.h_y = f.eye_clip.y * f.plane + f.eye_side * f.clip_y;
    f.h_w = f.eye_clip.w * f.plane + f.eye_side * f.clip_w;
    if (f.use_rect) {
      // The smallest angle between neighbouring pixel rays, sampled at the centre and the four
      // corners (with one target plane the angle per pixel is smallest at the screen's edges).
      double smallest = std::numeric_limits<double>::infinity();
      const double xs[5] = {0.5, camera.width - 1.5, 0.5, camera.width - 1.5, 0.5 * camera.width};
      const double ys[5] = {0.5, 0.5, camera.height - 1.5, camera.height - 1.5, 0.5 * camera.height};
      for (int k = 0; k < 5; ++k) {
        const glm::dvec3 d0(f.rays.ray_at(xs[k], ys[k]).direction);
        const glm::dvec3 dx(f.rays.ray_at(xs[k] + 1.0, ys[k]).direction);
        const glm::dvec3 dy(f.rays.ray_at(xs[k], ys[k] + 1.0).direction);
        smallest = std::min({smallest, glm::length(glm::cross(d0, dx)), glm::length(glm::cross(d0, dy))});
      }
      f.footprint = camera.width >= 2 && camera.height >= 2 && smallest >= 4e-5;
      // The ray test's edge band (near misses are reported too) as an angle: the band's distance
      // over the depth, at most about 4 band widths near an edge; in pixels at the narrowest spot.
      const double band_angle = 4.0 * double(data.band);
      f.margin = 0.05 + (smallest > 0.0 && std::isfinite(smallest) ? band_angle / smallest : 1e6);
    }
  }
  return f;
}

}  // namespace cullkit::detail::nci
