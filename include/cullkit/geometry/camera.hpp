// cullkit/geometry/camera.hpp: a view with pixels, and the one rule that turns a pixel into a ray.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

#include "frustum.hpp"

namespace cullkit {

/// A perspective view with a pixel grid. `view_proj` maps world to clip space (column vectors) and
/// its center of projection is `eye`; `depth` is the projection's depth range.
///
/// Pixel rule (every cullkit component and the test oracle use exactly this): pixel (x, y) has x to
/// the right and y down from the top row. Its ray starts at `eye` and points at the point that
/// inverse(view_proj), in double precision, maps from normalized device coordinates
/// ((2x+1)/width - 1, 1 - (2y+1)/height, 1); if that point is at infinity (an infinite far plane),
/// the near-plane depth (-1, or 0 for zero_to_one) is used instead. Near and far planes do not clip
/// the ray. A triangle is hit only from its front: corners counter-clockwise as seen from the eye.
struct Camera {
  glm::vec3 eye;
  glm::mat4 view_proj;
  int width;
  int height;
  DepthRange depth = DepthRange::negative_one_to_one;
};

/// A ray `origin + t * direction`, t >= 0.
struct Ray {
  glm::vec3 origin;
  glm::vec3 direction;
};

/// Generates pixel rays by the rule documented on `Camera`. Build once per frame, then call
/// `ray(x, y)` for any pixel (or sub-pixel position); no allocation, thread-safe after construction.
class PixelRays {
 public:
  explicit PixelRays(const Camera& camera) noexcept
      : eye_(camera.eye), width_(camera.width), height_(camera.height) {
    const glm::dmat4 inv = glm::inverse(glm::dmat4(camera.view_proj));
    // Homogeneous point for ndc (u, v, z): inv * (u, v, z, 1) = u*c0 + v*c1 + z*c2 + c3.
    col_x_ = inv[0];
    col_y_ = inv[1];
    far_ = inv[2] + inv[3];  // z = 1
    const double near_z = camera.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
    near_ = inv[2] * near_z + inv[3];
  }

  /// The ray through pixel center (x + 0.5, y + 0.5). Direction is unit length (zero if the
  /// matrix is singular or non-finite; such rays hit nothing).
  [[nodiscard]] Ray ray(int x, int y) const noexcept {
    return ray_at(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5);
  }

  /// The ray through a continuous pixel position (pixel centers are at half-integers).
  [[nodiscard]] Ray ray_at(double px, double py) const noexcept {
    const double u = 2.0 * px / width_ - 1.0;
    const double v = 1.0 - 2.0 * py / height_;
    const glm::dvec4 xy = col_x_ * u + col_y_ * v;
    glm::dvec4 h = xy + far_;
    // At (or, after rounding, numerically near) infinity: take the near-plane point of the ray.
    const double mag = std::fabs(h.x) + std::fabs(h.y) + std::fabs(h.z);
    if (!(std::fabs(h.w) > 1e-9 * mag)) h = xy + near_;
    const glm::dvec3 target = glm::dvec3(h) / h.w;
    glm::dvec3 dir = target - glm::dvec3(eye_);
    const double len = std::sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    if (len > 0.0 && std::isfinite(len)) dir /= len;
    else dir = glm::dvec3(0.0);
    return Ray{eye_, glm::vec3(dir)};
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }

 private:
  glm::vec3 eye_;
  int width_, height_;
  glm::dvec4 col_x_, col_y_, far_, near_;
};

/// The frustum of a camera (convenience for `Frustum::from_matrix(camera.view_proj, camera.depth)`).
[[nodiscard]] inline Frustum frustum_of(const Camera& camera) noexcept {
  return Frustum::from_matrix(camera.view_proj, camera.depth);
}

}  // namespace cullkit
