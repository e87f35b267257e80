// cullkit/geometry/frustum.hpp: view frusta from projection matrices, box and sphere tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "aabb.hpp"
#include "plane.hpp"
#include "sphere.hpp"

namespace cullkit {

namespace detail {
/// The centre of projection of a matrix whose rows are m[row][col]: the homogeneous point where
/// the x, y and w rows all vanish, as (x, y, z, w) in double. w is 0 (up to rounding) for an
/// orthographic projection, and everything is 0 for a singular matrix.
inline void projection_centre(const double m[4][4], double out[4]) noexcept {
  const double* a = m[0];
  const double* b = m[1];
  const double* c = m[3];
  // The generalised cross product of three 4-vectors: cofactors of the 3x4 matrix [a; b; c].
  const auto det3 = [&](int i, int j, int k) {
    return a[i] * (b[j] * c[k] - b[k] * c[j]) - a[j] * (b[i] * c[k] - b[k] * c[i]) + a[k] * (b[i] * c[j] - b[j] * c[i]);
  };
  out[0] = det3(1, 2, 3);
  out[1] = -det3(0, 2, 3);
  out[2] = det3(0, 1, 3);
  out[3] = -det3(0, 1, 2);
}

/// True when a matrix (rows m[row][col]) cannot describe a view: an entry is NaN or infinite, or it
/// is singular or nearly so (|det| at most 1e-12 of the product of its column lengths, a ratio
/// that does not depend on scale: a perspective matrix with any near plane is near 0.7).
/// Every container treats a camera with such a matrix as deciding nothing (all visible).
[[nodiscard]] inline bool degenerate_matrix(const double m[4][4]) noexcept {
  double norms = 1.0;
  for (int c = 0; c < 4; ++c) {
    double sq = 0.0;
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[r][c])) return true;
      sq += m[r][c] * m[r][c];
    }
    norms *= std::sqrt(sq);
  }
  // det by 2x2 minors of rows 0-1 and rows 2-3 (Laplace expansion).
  const auto m2 = [m](int r, int i, int j) { return m[r][i] * m[r + 1][j] - m[r][j] * m[r + 1][i]; };
  const double det = m2(0, 0, 1) * m2(2, 2, 3) - m2(0, 0, 2) * m2(2, 1, 3) + m2(0, 0, 3) * m2(2, 1, 2) +
                     m2(0, 1, 2) * m2(2, 0, 3) - m2(0, 1, 3) * m2(2, 0, 2) + m2(0, 2, 3) * m2(2, 0, 1);
  return !(std::fabs(det) > 1e-12 * norms) || !std::isfinite(det);
}
}  // namespace detail

/// How normalized device depth maps: OpenGL's [-1, 1], or Direct3D/Vulkan/Metal's [0, 1].
/// Reversed-Z (near at 1, far at 0) needs no flag of its own: its planes come out of the same rows.
enum class DepthRange { negative_one_to_one, zero_to_one };

/// A set of active planes, one bit each (bit i for `Frustum::plane(i)`).
using PlaneMask = std::uint8_t;

/// A convex view volume: up to six planes whose normals point inward.
///
/// Plane order is left, right, bottom, top, near, far, and the names are true for every depth
/// convention: `near_plane` is the plane nearest the centre of projection (the eye) and
/// `far_plane` the one across the volume from it, also under reversed-Z, where the depth rows
/// come out the other way round. (For an orthographic matrix there is no eye: the planes keep the
/// order of the depth rows, NDC depth -1 or 0 near.) A plane that could not be extracted (the far
/// plane of an infinite projection, a matrix with NaN) is *dropped*: its bit is absent from
/// `active_mask()` and it never rejects anything. A matrix with a NaN or infinite entry, or a
/// singular one (detail::degenerate_matrix), drops every plane: the frustum then holds all of space, and every cull with it keeps everything (the
/// library's answer for a degenerate camera). Every query is conservative: `outside` is only
/// returned when float rounding cannot have moved the shape across a plane.
///
/// Cost: `classify(Aabb)` tests two corners per active plane (the one farthest along the normal to
/// reject, the nearest to accept). Thread safety: immutable after construction.
class Frustum {
 public:
  static constexpr int max_planes = 6;
  enum PlaneIndex : int { left = 0, right = 1, bottom = 2, top = 3, near_plane = 4, far_plane = 5 };

  /// An empty frustum with no planes: everything is inside it.
  Frustum() noexcept = default;

  /// Extracts the planes from the rows of `view_proj` (clip = view_proj * world, column vectors,
  /// GLM layout), computed in double precision and normalized. Works for perspective and
  /// orthographic projections, both depth ranges, reversed-Z and infinite far planes. `depth` must
  /// match the projection; GLM's clip-control macros are never read. A plane is dropped (the
  /// frustum grows, never shrinks) when its normal vanishes (an infinite far plane), when it is not
  /// finite, or when a coefficient of the unit plane is below the smallest normal float
  /// (`std::numeric_limits<float>::min()`) without being zero: float could not hold it.
  [[nodiscard]] static Frustum from_matrix(const glm::mat4& view_proj,
                                           DepthRange depth = DepthRange::negative_one_to_one) noexcept {
    double m[4][4];  // m[row][col]
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[r][c] = static_cast<double>(view_proj[c][r]);
    // A matrix that cannot describe a view decides nothing: no planes (one NaN entry would
    // otherwise drop only the planes of its rows, and a singular matrix could keep all six).
    if (detail::degenerate_matrix(m)) return Frustum{};
    double rows[6][4];
    for (int k = 0; k < 4; ++k) {
      rows[left][k] = m[3][k] + m[0][k];
      rows[right][k] = m[3][k] - m[0][k];
      rows[bottom][k] = m[3][k] + m[1][k];
      rows[top][k] = m[3][k] - m[1][k];
      rows[near_plane][k] = depth == DepthRange::zero_to_one ? m[2][k] : m[3][k] + m[2][k];
      rows[far_plane][k] = m[3][k] - m[2][k];
    }
    Frustum f;
    for (int i = 0; i < 6; ++i) {
      const double* r = rows[i];
      const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      // Scale of the row, to tell a vanishing normal (an infinite far plane: row3 - row2 has a
      // normal that is zero up to rounding) from a genuine plane.
      const double scale = std::fabs(r[0]) + std::fabs(r[1]) + std::fabs(r[2]) + std::fabs(r[3]);
      if (!(len > 1e-6 * scale)) continue;
      // unit_plane drops a plane whose unit coefficients lose their precision in float (a plane
      // at infinity, in effect): the frustum only grows.
      Plane p;
      if (!detail::unit_plane(r[0], r[1], r[2], r[3], p) || !is_valid(p)) continue;
      f.planes_[i] = p;
      f.mask_ = static_cast<PlaneMask>(f.mask_ | (1u << i));
    }
    f.name_depth_planes(m);
    return f;
  }

  /// Builds a frustum from up to six inward-facing planes, of any positive normal length (each is
  /// stored scaled to a unit normal, see `normalized`); invalid ones are dropped.
  [[nodiscard]] static Frustum from_planes(const Plane* planes, int count) noexcept {
    Frustum f;
    for (int i = 0; i < count && i < max_planes; ++i) {
      const Plane p = normalized(planes[i]);
      if (!is_valid(p)) continue;
      f.planes_[i] = p;
      f.mask_ = static_cast<PlaneMask>(f.mask_ | (1u << i));
    }
    return f;
  }

  /// Bits of the planes that exist.
  [[nodiscard]] PlaneMask active_mask() const noexcept { return mask_; }
  [[nodiscard]] const Plane& plane(int i) const noexcept { return planes_[i]; }
  [[nodiscard]] bool has_plane(int i) const noexcept { return (mask_ >> i) & 1u; }

  /// Box test. Never `outside` for a box that meets the volume. A box with NaN is `intersecting`.
  [[nodiscard]] Containment classify(const Aabb& box) const noexcept {
    PlaneMask m = mask_;
    return classify(box, m);
  }

  /// Box test against the planes in `mask` only. On return `mask` holds the planes the box
  /// straddles; planes it is fully inside of are cleared, so children of this box can pass the
  /// result down and skip them. If the answer is `outside`, `mask` is unspecified.
  [[nodiscard]] Containment classify(const Aabb& box, PlaneMask& mask) const noexcept {
    const glm::vec3 c = (box.min + box.max) * 0.5f;
    const glm::vec3 e = (box.max - box.min) * 0.5f;
    PlaneMask out = mask;
    for (int i = 0; i < max_planes; ++i) {
      if (((mask >> i) & 1) == 0) continue;
      const Plane& p = planes_[i];
      const float dc = glm::dot(p.normal, c) + p.d;
      const float r = std::fabs(p.normal.x) * e.x + std::fabs(p.normal.y) * e.y +
                      std::fabs(p.normal.z) * e.z;
      // Farthest corner along the normal is at dc + r, nearest at dc - r. The slack covers the
      // rounding of both sums, so a touching box is never rejected.
      const float slack = tolerance(p, c, r);
      if (dc + r < -slack) return Containment::outside;
      if (dc - r >= slack) out = static_cast<PlaneMask>(out & ~(1u << i));
      // NaN: neither comparison holds; the plane stays in the mask (intersecting).
    }
    mask = out;
    return out == 0 ? Containment::inside : Containment::intersecting;
  }

  /// Sphere test, same guarantees as the box test.
  [[nodiscard]] Containment classify(const Sphere& s) const noexcept {
    PlaneMask m = mask_;
    return classify(s, m);
  }
  [[nodiscard]] Containment classify(const Sphere& s, PlaneMask& mask) const noexcept {
    if (!(s.radius >= 0.0f)) return Containment::outside;  // the empty sphere
    PlaneMask out = mask;
    for (int i = 0; i < max_planes; ++i) {
      if (((mask >> i) & 1) == 0) continue;
      const Plane& p = planes_[i];
      const float dc = glm::dot(p.normal, s.center) + p.d;
      const float slack = tolerance(p, s.center, s.radius);
      if (dc + s.radius < -slack) return Containment::outside;
      if (dc - s.radius >= slack) out = static_cast<PlaneMask>(out & ~(1u << i));
    }
    mask = out;
    return out == 0 ? Containment::inside : Containment::intersecting;
  }

  /// Point test: true unless the point is clearly outside some plane.
  [[nodiscard]] bool contains(const glm::vec3& p) const noexcept {
    return classify(Sphere{p, 0.0f}) != Containment::outside;
  }

  /// The rounding slack used for a plane at a point with a given radius: a bound on the float
  /// error of `dot(n, c) + d ± r`, plus the error of the plane itself (rounded to float).
  [[nodiscard]] static float tolerance(const Plane& p, const glm::vec3& c, float r) noexcept {
    const float mag = std::fabs(p.normal.x * c.x) + std::fabs(p.normal.y * c.y) +
                      std::fabs(p.normal.z * c.z) + std::fabs(p.d) + r;
    return mag * (8.0f * std::numeric_limits<float>::epsilon());
  }

 private:
  // Reversed-Z puts NDC depth 1 on the near plane, so the rows extracted as "near" and "far" are
  // the other way round: swap them when the eye (the centre of projection) is on the inside of
  // the "near" one, or when only the "far" one exists and the eye is on its outside. A centre at
  // infinity (orthographic) or undefined leaves the order as extracted.
  void name_depth_planes(const double m[4][4]) noexcept {
    double c[4];
    detail::projection_centre(m, c);
    const double scale = std::fabs(c[0]) + std::fabs(c[1]) + std::fabs(c[2]);
    if (!(std::fabs(c[3]) > 1e-12 * scale) || !std::isfinite(scale)) return;
    const double eye[3] = {c[0] / c[3], c[1] / c[3], c[2] / c[3]};
    const auto side = [&](int i) {
      const Plane& p = planes_[i];
      return double(p.normal.x) * eye[0] + double(p.normal.y) * eye[1] + double(p.normal.z) * eye[2] + double(p.d);
    };
    const bool has_near = has_plane(near_plane), has_far = has_plane(far_plane);
    const bool swap = has_near ? side(near_plane) > 0.0 : (has_far && side(far_plane) < 0.0);
    if (!swap) return;
    const Plane t = planes_[near_plane];
    planes_[near_plane] = planes_[far_plane];
    planes_[far_plane] = t;
    const unsigned nb = (mask_ >> near_plane) & 1u, fb = (mask_ >> far_plane) & 1u;
    mask_ = static_cast<PlaneMask>((mask_ & ~((1u << near_plane) | (1u << far_plane))) | (nb << far_plane) |
                                   (fb << near_plane));
  }

  Plane planes_[max_planes] = {};
  PlaneMask mask_ = 0;
};

}  // namespace cullkit
