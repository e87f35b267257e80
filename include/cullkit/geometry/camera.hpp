// cullkit/geometry/camera.hpp: a view with pixels, and the one rule that turns a pixel into a ray.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

#include "../config.hpp"
#include "frustum.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

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
      : PixelRays(glm::inverse(glm::dmat4(camera.view_proj)), camera.eye, camera.width, camera.height, camera.depth) {}

  /// The same rule for a camera known in double precision: `inverse_view_proj` is the inverse of
  /// its matrix (clip to world). For a camera taken into another frame (the world pixel rays mapped
  /// into an object's local frame by an affine map A: A * inverse(view_proj), with `eye` the mapped
  /// eye), whose matrix rounded to float could move its far plane through infinity.
  PixelRays(const glm::dmat4& inverse_view_proj, const glm::vec3& eye, int width, int height,
            DepthRange depth) noexcept
      : eye_(eye), width_(width), height_(height) {
    const glm::dmat4& inv = inverse_view_proj;
    // Homogeneous point for ndc (u, v, z): inv * (u, v, z, 1) = u*c0 + v*c1 + z*c2 + c3.
    col_x_ = inv[0];
    col_y_ = inv[1];
    far_ = inv[2] + inv[3];  // z = 1
    const double near_z = depth == DepthRange::zero_to_one ? 0.0 : -1.0;
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

  /// The directions of `count` consecutive pixels of row y, from pixel (x, y) on: component by
  /// component into dx, dy, dz (each `count` floats). Bit for bit `ray(x + i, y).direction`, at about
  /// half its cost on x86-64: two pixels per SSE2 instruction (the same IEEE operations in the
  /// same order; like `ray`, it must not be compiled with floating-point contraction into FMA,
  /// e.g. -ffp-contract=fast with -mfma, or the two may differ in the last bit).
  void directions(int x, int y, int count, float* dx, float* dy, float* dz) const noexcept {
    int i = 0;
#if CULLKIT_HAS_SSE2
    const double py = static_cast<double>(y) + 0.5;
    const __m128d v = _mm_set1_pd(1.0 - 2.0 * py / height_);
    const __m128d two = _mm_set1_pd(2.0), one = _mm_set1_pd(1.0), half = _mm_set1_pd(0.5);
    const __m128d width = _mm_set1_pd(static_cast<double>(width_)), tiny = _mm_set1_pd(1e-9);
    const __m128d sign = _mm_set1_pd(-0.0), zero = _mm_setzero_pd();
    const __m128d inf = _mm_set1_pd(std::numeric_limits<double>::infinity());
    const __m128d ex = _mm_set1_pd(double(eye_.x)), ey = _mm_set1_pd(double(eye_.y)), ez = _mm_set1_pd(double(eye_.z));
    // Rows of the homogeneous map with v already applied: xy = col_x u + col_y v.
    __m128d cx[4], cyv[4], fr[4], nr[4];
    for (int k = 0; k < 4; ++k) {
      cx[k] = _mm_set1_pd(col_x_[k]);
      cyv[k] = _mm_mul_pd(_mm_set1_pd(col_y_[k]), v);
      fr[k] = _mm_set1_pd(far_[k]);
      nr[k] = _mm_set1_pd(near_[k]);
    }
    for (; i + 2 <= count; i += 2) {
      const __m128d px = _mm_add_pd(_mm_set_pd(double(x + i + 1), double(x + i)), half);
      const __m128d u = _mm_sub_pd(_mm_div_pd(_mm_mul_pd(two, px), width), one);
      __m128d xy[4], h[4];
      for (int k = 0; k < 4; ++k) {
        xy[k] = _mm_add_pd(_mm_mul_pd(cx[k], u), cyv[k]);
        h[k] = _mm_add_pd(xy[k], fr[k]);
      }
      const __m128d mag = _mm_add_pd(_mm_add_pd(_mm_andnot_pd(sign, h[0]), _mm_andnot_pd(sign, h[1])),
                                     _mm_andnot_pd(sign, h[2]));
      // !(|w| > 1e-9 mag): the near-plane point instead.
      const __m128d use_far = _mm_cmpgt_pd(_mm_andnot_pd(sign, h[3]), _mm_mul_pd(tiny, mag));
      for (int k = 0; k < 4; ++k)
        h[k] = _mm_or_pd(_mm_and_pd(use_far, h[k]), _mm_andnot_pd(use_far, _mm_add_pd(xy[k], nr[k])));
      const __m128d gx = _mm_sub_pd(_mm_div_pd(h[0], h[3]), ex);
      const __m128d gy = _mm_sub_pd(_mm_div_pd(h[1], h[3]), ey);
      const __m128d gz = _mm_sub_pd(_mm_div_pd(h[2], h[3]), ez);
      const __m128d len = _mm_sqrt_pd(_mm_add_pd(_mm_add_pd(_mm_mul_pd(gx, gx), _mm_mul_pd(gy, gy)), _mm_mul_pd(gz, gz)));
      // len > 0 and finite (NaN fails both compares): unit; else zero.
      const __m128d ok = _mm_and_pd(_mm_cmpgt_pd(len, zero), _mm_cmplt_pd(len, inf));
      const __m128 fx = _mm_cvtpd_ps(_mm_and_pd(ok, _mm_div_pd(gx, len)));
      const __m128 fy = _mm_cvtpd_ps(_mm_and_pd(ok, _mm_div_pd(gy, len)));
      const __m128 fz = _mm_cvtpd_ps(_mm_and_pd(ok, _mm_div_pd(gz, len)));
      _mm_storel_pi(reinterpret_cast<__m64*>(dx + i), fx);
      _mm_storel_pi(reinterpret_cast<__m64*>(dy + i), fy);
      _mm_storel_pi(reinterpret_cast<__m64*>(dz + i), fz);
    }
#endif
    for (; i < count; ++i) {
      const glm::vec3 d = ray(x + i, y).direction;
      dx[i] = d.x;
      dy[i] = d.y;
      dz[i] = d.z;
    }
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }

 private:
  glm::vec3 eye_;
  int width_, height_;
  glm::dvec4 col_x_, col_y_, far_, near_;
};

/// The centre of projection of `view_proj` (column vectors, GLM layout): the point whose clip-space
/// x, y and w are all zero, computed in double. For a perspective matrix this is the eye that the
/// matrix was built from (within the matrix's own float rounding). An orthographic, singular or
/// non-finite matrix has no finite centre: the answer is NaN in every component.
/// Cost: a few dozen flops; no allocation.
[[nodiscard]] inline glm::vec3 projection_centre(const glm::mat4& view_proj) noexcept {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  double m[4][4];
  bool finite = true;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      m[r][c] = static_cast<double>(view_proj[c][r]);
      finite = finite && std::isfinite(m[r][c]);
    }
  // The centre does not depend on the depth row, but a matrix with a NaN or an infinity anywhere is
  // not a usable camera: its depth planes (and so the frustum) are undefined.
  if (!finite) return glm::vec3(nan);
  double h[4];
  detail::projection_centre(m, h);
  const double scale = std::fabs(h[0]) + std::fabs(h[1]) + std::fabs(h[2]);
  if (!(std::fabs(h[3]) > 1e-12 * scale) || !std::isfinite(scale)) return glm::vec3(nan);
  const glm::vec3 eye(static_cast<float>(h[0] / h[3]), static_cast<float>(h[1] / h[3]), static_cast<float>(h[2] / h[3]));
  if (!std::isfinite(eye.x) || !std::isfinite(eye.y) || !std::isfinite(eye.z)) return glm::vec3(nan);
  return eye;
}

/// A Camera whose eye is the centre of projection of `view_proj`, so the eye and the matrix can
/// never disagree (an eye a few centimetres off the matrix's centre makes pixel rays miss what the
/// matrix shows). `view_proj` should be a perspective projection times a view matrix; `depth` its
/// depth range. For a matrix without a finite centre (orthographic, singular, NaN) the eye is NaN:
/// the frustum of such a camera keeps everything, and `camera_is_consistent` says false.
/// Cost: O(1), no allocation.
[[nodiscard]] inline Camera make_camera(const glm::mat4& view_proj, int width, int height,
                                        DepthRange depth = DepthRange::negative_one_to_one) noexcept {
  return Camera{projection_centre(view_proj), view_proj, width, height, depth};
}

/// True when `camera.eye` is the centre of projection of `camera.view_proj` within
/// `relative_tolerance` times max(1, largest coordinate of the centre), and the pixel grid is not
/// empty. False for a matrix without a finite centre. Use it where a caller supplies both an eye
/// and a matrix (the default tolerance is far above float rounding of a consistent pair and far
/// below a centimetre for scenes within a kilometre of the origin).
[[nodiscard]] inline bool camera_is_consistent(const Camera& camera, float relative_tolerance = 1e-5f) noexcept {
  const glm::vec3 c = projection_centre(camera.view_proj);
  if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return false;
  if (camera.width <= 0 || camera.height <= 0) return false;
  const float scale = std::fmax(1.0f, std::fmax(std::fabs(c.x), std::fmax(std::fabs(c.y), std::fabs(c.z))));
  const float tol = relative_tolerance * scale;
  return std::fabs(camera.eye.x - c.x) <= tol && std::fabs(camera.eye.y - c.y) <= tol &&
         std::fabs(camera.eye.z - c.z) <= tol;
}

/// Debug-build check of a caller-assembled camera: `CULLKIT_ASSERT(camera_is_consistent(camera))`.
/// Compiles to nothing where CULLKIT_ASSERT does (NDEBUG with the default hook).
inline void check_camera(const Camera& camera, float relative_tolerance = 1e-5f) noexcept {
  (void)camera;
  (void)relative_tolerance;
  CULLKIT_ASSERT(camera_is_consistent(camera, relative_tolerance),
                 "camera.eye is the centre of projection of camera.view_proj (use make_camera)");
}

/// The frustum of a camera (convenience for `Frustum::from_matrix(camera.view_proj, camera.depth)`).
[[nodiscard]] inline Frustum frustum_of(const Camera& camera) noexcept {
  return Frustum::from_matrix(camera.view_proj, camera.depth);
}

}  // namespace cullkit
