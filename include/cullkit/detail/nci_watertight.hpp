// cullkit/detail/nci_watertight.hpp: the watertight ray/triangle test the NormalClassIndex uses at
// pixel centres (after Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2013).
// Rays sharing an origin (the eye) share the per-triangle work; a ray precomputes its shear once.
#pragma once

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

/// Front-face-only watertight test of one ray against the triangle with corners `a`, `b`, `c`
/// given relative to the ray origin. On a hit (t >= 0, corners counter-clockwise seen from the
/// origin) writes the ray parameter to `t` and returns true. Edges shared by two triangles are
/// never missed by both (the double-precision fallback on zero edge functions, as in the paper).
template <class Real>
[[nodiscard]] inline bool watertight_hit(const WatertightRay<Real>& ray, const Real a[3], const Real b[3],
                                         const Real c[3], Real& t) noexcept {
  if (!ray.valid) return false;
  const Real ax = a[ray.kx] - ray.sx * a[ray.kz];
  const Real ay = a[ray.ky] - ray.sy * a[ray.kz];
  const Real bx = b[ray.kx] - ray.sx * b[ray.kz];
  const Real by = b[ray.ky] - ray.sy * b[ray.kz];
  const Real cx = c[ray.kx] - ray.sx * c[ray.kz];
  const Real cy = c[ray.ky] - ray.sy * c[ray.kz];
  Real u = cx * by - cy * bx;
  Real v = ax * cy - ay * cx;
  Real w = bx * ay - by * ax;
  if (u == Real(0) || v == Real(0) || w == Real(0)) {
    u = Real(double(cx) * double(by) - double(cy) * double(bx));
    v = Real(double(ax) * double(cy) - double(ay) * double(cx));
    w = Real(double(bx) * double(ay) - double(by) * double(ax));
  }
  // Counter-clockwise as seen from the origin gives non-negative edge functions in this frame.
  if (u < Real(0) || v < Real(0) || w < Real(0)) return false;
  const Real det = u + v + w;
  if (!(det > Real(0))) return false;  // also rejects NaN
  const Real az = ray.sz * a[ray.kz];
  const Real bz = ray.sz * b[ray.kz];
  const Real cz = ray.sz * c[ray.kz];
  const Real tt = u * az + v * bz + w * cz;
  if (tt < Real(0)) return false;  // behind the origin
  const Real r = tt / det;
  if (!(r >= Real(0)) || !std::isfinite(r)) return false;
  t = r;
  return true;
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
