// cullkit/detail/nci/watertight.hpp: the watertight ray/triangle test the NormalClassIndex uses at
// pixel centres (after Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2013).
// Rays sharing an origin (the eye) share the per-triangle work; a ray precomputes its shear once.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace cullkit::detail {

/// Per-ray shear constants of the watertight test, in scalar type `Real` (float for the index,
/// double for the brute-force oracle in the tests).
template <class Real>
struct WatertightRay {
  int kx = 0, ky = 1, kz = 2;  // axis permutation: kz is the dominant direction axis
  Real sx = 0, sy = 0, sz = 0; // shear: x' = x - sx z, y' = y - sy z, t scale sz
  bool valid = false;          // false for a zero or non-finite direction (hits nothing)

  static WatertightRay make(const glm::vec3& direction) noexcept {
    WatertightRay r;
    const Real d[3] = {Real(direction.x), Real(direction.y), Real(direction.z)};
    const Real ax = std::fabs(d[0]), ay = std::fabs(d[1]), az = std::fabs(d[2]);
    if (!(std::isfinite(ax) && std::isfinite(ay) && std::isfinite(az))) return r;
    int kz = 0;
    if (ay > ax) kz = 1;
    if (az > (kz == 0 ? ax : ay)) kz = 2;
    if (!(std::fabs(d[kz]) > Real(0))) return r;
    int kx = kz + 1 == 3 ? 0 : kz + 1;
    int ky = kx + 1 == 3 ? 0 : kx + 1;
    if (d[kz] < Real(0)) {  // keep the winding (handedness) of the projected triangle
      const int tmp = kx;
      kx = ky;
      ky = tmp;
    }
    r.kx = kx;
    r.ky = ky;
    r.kz = kz;
    r.sx = d[kx] / d[kz];
    r.sy = d[ky] / d[kz];
    r.sz = Real(1) / d[kz];
    r.valid = true;
    return r;
  }
};

/// The triangle's corners in the ray's sheared 2D frame (the ray is the origin) and its three
/// edge functions, with the double-precision fallback of the paper when one is exactly zero.
template <class Real>
struct ShearedTriangle {
  Real ax, ay, bx, by, cx, cy;
  Real u, v, w;
};

template <class Real>
[[nodiscard]] inline ShearedTriangle<Real> shear_triangle(const WatertightRay<Real>& ray, const Real a[3],
                                                          const Real b[3], const Real c[3]) noexcept {
  ShearedTriangle<Real> s;
  s.ax = a[ray.kx] - ray.sx * a[ray.kz];
  s.ay = a[ray.ky] - ray.sy * a[ray.kz];
  s.bx = b[ray.kx] - ray.sx * b[ray.kz];
  s.by = b[ray.ky] - ray.sy * b[ray.kz];
  s.cx = c[ray.kx] - ray.sx * c[ray.kz];
  s.cy = c[ray.ky] - ray.sy * c[ray.kz];
  s.u = s.cx * s.by - s.cy * s.bx;
  s.v = s.ax * s.cy - s.ay * s.cx;
  s.w = s.bx * s.ay - s.by * s.ax;
  if (s.u == Real(0) || s.v == Real(0) || s.w == Real(0)) {
    s.u = Real(double(s.cx) * double(s.by) - double(s.cy) * double(s.bx));
    s.v = Real(double(s.ax) * double(s.cy) - double(s.ay) * double(s.cx));
    s.w = Real(double(s.bx) * double(s.ay) - double(s.by) * double(s.ax));
  }
  return s;
}

/// The ray parameter of the point with edge functions (u, v, w) (their sum positive, else false),
/// when finite and not behind the origin.
template <class Real>
[[nodiscard]] inline bool sheared_t(const WatertightRay<Real>& ray, const ShearedTriangle<Real>& s, const Real a[3],
                                    const Real b[3], const Real c[3], Real& t) noexcept {
  const Real det = s.u + s.v + s.w;
  if (!(det > Real(0))) return false;  // also rejects NaN
  const Real az = ray.sz * a[ray.kz];
  const Real bz = ray.sz * b[ray.kz];
  const Real cz = ray.sz * c[ray.kz];
  const Real tt = s.u * az + s.v * bz + s.w * cz;
  if (tt < Real(0)) return false;  // behind the origin
  const Real r = tt / det;
  if (!(r >= Real(0)) || !std::isfinite(r)) return false;
  t = r;
  return true;
}

/// Front-face-only watertight test of one ray against the triangle with corners `a`, `b`, `c`
/// given relative to the ray origin. On a hit (t >= 0, corners counter-clockwise seen from the
/// origin) writes the ray parameter to `t` and returns true. Edges shared by two triangles are
/// never missed by both (the double-precision fallback on zero edge functions, as in the paper).
template <class Real>
[[nodiscard]] inline bool watertight_hit(const WatertightRay<Real>& ray, const Real a[3], const Real b[3],
                                         const Real c[3], Real& t) noexcept {
  if (!ray.valid) return false;
  const ShearedTriangle<Real> s = shear_triangle(ray, a, b, c);
  // Counter-clockwise as seen from the origin gives non-negative edge functions in this frame.
  if (s.u < Real(0) || s.v < Real(0) || s.w < Real(0)) return false;
  return sheared_t(ray, s, a, b, c, t);
}

/// Relative width of the edge band of `watertight_hit_band`, in units of the float rounding 2^-24.
/// Measured with tests/nci/test_nci_narrow.cpp (fzk_haus and a generated forest, 0.2 to 5 degree
/// views from up to 6 km, scenes up to 5e4 from the origin, 1024x768, Embree 3 robust as the other
/// tracer): with 1 unit 6 pixels still miss a triangle Embree sees, with 0.5 units 11, from 2
/// units on none. 8 keeps a factor of four over that.
inline constexpr float edge_band_units = 8.0f;

/// The watertight test of `watertight_hit` (the same hit decision and the same t, bit for bit)
/// that also reports whether the ray passes within rounding of an edge of the triangle, where
/// another correct float ray tracer may decide the other way. `mag[k]` is the largest absolute
/// coordinate of corner k (relative to the ray origin, as passed); `band` is
/// edge_band_units * 2^-24 (a parameter so the tests can vary it). The band of an edge grows with
/// the rounding its edge function can carry: the sheared 2D corners are off by a few roundings of
/// their 3D size, the products by one rounding of theirs. On return `near` is true when every
/// edge function is above minus its band and one is below plus it; then `t` holds the ray
/// parameter of the triangle's plane (also for a near miss, where the function returns false),
/// unless the plane is behind the origin or seen edge-on (then `near` is false).
template <class Real>
[[nodiscard]] inline bool watertight_hit_band(const WatertightRay<Real>& ray, const Real a[3], const Real b[3],
                                              const Real c[3], const Real mag[3], Real band, Real& t,
                                              bool& near) noexcept {
  near = false;
  if (!ray.valid) return false;
  const ShearedTriangle<Real> s = shear_triangle(ray, a, b, c);
  const bool inside = s.u >= Real(0) && s.v >= Real(0) && s.w >= Real(0);
  const Real sa = std::fabs(s.ax) + std::fabs(s.ay), sb = std::fabs(s.bx) + std::fabs(s.by),
             sc = std::fabs(s.cx) + std::fabs(s.cy);
  const Real bu = band * (mag[2] * sb + mag[1] * sc + sb * sc);
  const Real bv = band * (mag[0] * sc + mag[2] * sa + sc * sa);
  const Real bw = band * (mag[1] * sa + mag[0] * sb + sa * sb);
  // Near an edge, and not beside the triangle's 2D bounding box grown by the corners' rounding
  // (where thin triangles would otherwise have bands reaching far along their carrier line).
  const Real grow = band * std::max({mag[0], mag[1], mag[2]});
  const bool in_band = (s.u < bu || s.v < bv || s.w < bw) && s.u > -bu && s.v > -bv && s.w > -bw &&
                       std::min({s.ax, s.bx, s.cx}) <= grow && std::max({s.ax, s.bx, s.cx}) >= -grow &&
                       std::min({s.ay, s.by, s.cy}) <= grow && std::max({s.ay, s.by, s.cy}) >= -grow;
  if (!inside && !in_band) return false;
  if (!sheared_t(ray, s, a, b, c, t)) return false;
  near = in_band;
  return inside;
}

/// The NormalClassIndex's front-face rule beside the ray test: the eye lies strictly on the front
/// side of the triangle's plane, evaluated in double. A triangle whose plane passes through the
/// eye is seen exactly edge-on and is never a hit, whatever the rounding of the ray test says
/// (this keeps the per-class cone skipping and the per-triangle test in agreement).
[[nodiscard]] inline bool faces_eye(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                                    const glm::dvec3& eye) noexcept {
  const glm::dvec3 q0(p0);
  const glm::dvec3 n = glm::cross(glm::dvec3(p1) - q0, glm::dvec3(p2) - q0);
  return glm::dot(n, eye - q0) > 0.0;
}

}  // namespace cullkit::detail
