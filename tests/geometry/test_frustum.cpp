// Frustum::from_matrix and classify against a double-precision oracle on the matrix itself, for
// perspective and orthographic projections, both depth ranges, reversed-Z and infinite far planes.
// Built twice: with GLM's clip-control macros unset, and with GLM_FORCE_DEPTH_ZERO_TO_ONE and
// GLM_FORCE_LEFT_HANDED set; cullkit never reads them, so both must pass.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

namespace {

struct TestView {
  std::string name;
  glm::mat4 view_proj;
  DepthRange depth;
  bool infinite_far;
};

// Clip-space rows of the matrix in double: the volume is {x : row_i . (x, 1) >= 0 for all i}.
struct ClipRows {
  double r[6][4];
};
ClipRows clip_rows(const glm::mat4& m, DepthRange depth) {
  ClipRows c{};
  for (int k = 0; k < 4; ++k) {
    const double x = m[k][0], y = m[k][1], z = m[k][2], w = m[k][3];
    c.r[0][k] = w + x;
    c.r[1][k] = w - x;
    c.r[2][k] = w + y;
    c.r[3][k] = w - y;
    c.r[4][k] = depth == DepthRange::zero_to_one ? z : w + z;
    c.r[5][k] = w - z;
  }
  return c;
}
double eval(const double* row, const glm::vec3& p) {
  return row[0] * double(p.x) + row[1] * double(p.y) + row[2] * double(p.z) + row[3];
}

// A point of the view volume for NDC (x, y) at depth fraction s in [0, 1] between near and far
// (for an infinite far plane, s < 1 maps to a finite point along the ray).
glm::dvec3 unproject(const glm::mat4& m, double x, double y, double z) {
  const glm::dvec4 h = glm::inverse(glm::dmat4(m)) * glm::dvec4(x, y, z, 1.0);
  return glm::dvec3(h) / h.w;
}

std::vector<TestView> make_views(support::Rng& rng) {
  std::vector<TestView> views;
#ifdef GLM_FORCE_DEPTH_ZERO_TO_ONE
  const DepthRange glm_default_depth = DepthRange::zero_to_one;
#else
  const DepthRange glm_default_depth = DepthRange::negative_one_to_one;
#endif
  for (int i = 0; i < 12; ++i) {
    const glm::vec3 eye(rng.uniform(-50, 50), rng.uniform(-10, 30), rng.uniform(-50, 50));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.5f, 0.5f), rng.uniform(-1, 1));
    const glm::mat4 view = glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
    const float fov = glm::radians(rng.uniform(30, 100));
    const float aspect = rng.uniform(0.5f, 2.5f);
    const float n = rng.uniform(0.05f, 2.0f), f = rng.uniform(50, 500);
    const std::string s = std::to_string(i);
    views.push_back({"persp_NO_" + s, glm::perspectiveRH_NO(fov, aspect, n, f) * view, DepthRange::negative_one_to_one, false});
    views.push_back({"persp_ZO_" + s, glm::perspectiveRH_ZO(fov, aspect, n, f) * view, DepthRange::zero_to_one, false});
    views.push_back({"persp_reversedZ_" + s, glm::perspectiveRH_ZO(fov, aspect, f, n) * view, DepthRange::zero_to_one, false});
    views.push_back({"ortho_NO_" + s, glm::orthoRH_NO(-20.f, 25.f, -10.f, 15.f, n, f) * view, DepthRange::negative_one_to_one, false});
    views.push_back({"ortho_ZO_" + s, glm::orthoRH_ZO(-20.f, 25.f, -10.f, 15.f, n, f) * view, DepthRange::zero_to_one, false});
    // Infinite far, both depth ranges and reversed-Z, built by the test support.
    const Camera c1 = support::make_camera(eye, target, 60, 64, 48, n, 0.0f, DepthRange::negative_one_to_one);
    const Camera c2 = support::make_camera(eye, target, 60, 64, 48, n, 0.0f, DepthRange::zero_to_one);
    const Camera c3 = support::make_camera(eye, target, 60, 64, 48, n, 0.0f, DepthRange::zero_to_one, true);
    views.push_back({"infinite_NO_" + s, c1.view_proj, DepthRange::negative_one_to_one, true});
    views.push_back({"infinite_ZO_" + s, c2.view_proj, DepthRange::zero_to_one, true});
    views.push_back({"infinite_reversedZ_" + s, c3.view_proj, DepthRange::zero_to_one, true});
    // Whatever GLM's macros make of the unsuffixed functions, with the range we know they chose.
    views.push_back({"glm_default_" + s, glm::perspective(fov, aspect, n, f) * glm::lookAt(eye, target, glm::vec3(0, 1, 0)),
                     glm_default_depth, false});
  }
  return views;
}

void check_view(const TestView& v, support::Rng& rng) {
  const Frustum fr = Frustum::from_matrix(v.view_proj, v.depth);
  const ClipRows rows = clip_rows(v.view_proj, v.depth);
  const int planes = __builtin_popcount(fr.active_mask());
  CHECK_MSG(planes == (v.infinite_far ? 5 : 6), "%s: %d planes", v.name.c_str(), planes);
  for (int i = 0; i < 6; ++i) {
    if (!fr.has_plane(i)) continue;
    const Plane& p = fr.plane(i);
    CHECK_MSG(std::isfinite(p.d) && std::fabs(glm::length(p.normal) - 1.0f) < 1e-5f, "%s plane %d not unit", v.name.c_str(), i);
  }

  // Points strictly inside the volume (from NDC) are inside; the corners of the volume lie on the planes.
  const double zlo = v.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
  for (int k = 0; k < 400; ++k) {
    const double x = rng.uniform(-0.999f, 0.999f), y = rng.uniform(-0.999f, 0.999f);
    double z = zlo + (1.0 - zlo) * rng.uniform(0.001f, 0.999f);
    if (v.infinite_far) z = zlo + (1.0 - zlo) * rng.uniform(0.001f, 0.9f);
    const glm::vec3 p(unproject(v.view_proj, x, y, z));
    CHECK_MSG(fr.contains(p), "%s: inside point (%g %g %g) rejected", v.name.c_str(), x, y, z);
    CHECK_MSG(fr.classify(Sphere{p, 0.0f}) != Containment::outside, "%s", v.name.c_str());
  }

  // Boxes and spheres near the boundary: an `outside` answer must be proven by some clip row in
  // double (all eight corners strictly outside it); an `inside` answer must hold for all corners.
  int outside = 0, inside = 0, clearly_outside = 0, clearly_outside_found = 0;
  for (int k = 0; k < 4000; ++k) {
    const double x = rng.uniform(-1.3f, 1.3f), y = rng.uniform(-1.3f, 1.3f);
    const double z = zlo + (1.0 - zlo) * rng.uniform(-0.2f, v.infinite_far ? 0.95f : 1.2f);
    const glm::dvec3 c = unproject(v.view_proj, x, y, z);
    const float size = rng.uniform(0.0f, 3.0f) * (rng.uniform() < 0.3f ? 0.001f : 1.0f);
    const Aabb box{glm::vec3(c) - glm::vec3(size * rng.uniform(), size * rng.uniform(), size),
                   glm::vec3(c) + glm::vec3(size, size * rng.uniform(), size * rng.uniform())};
    const Containment got = fr.classify(box);
    bool proven_out = false, far_out = false;
    bool all_in = true;
    for (int i = 0; i < 6; ++i) {
      double hi = -1e300, lo = 1e300, mag = 0;
      for (int j = 0; j < 8; ++j) {
        const double e = eval(rows.r[i], corner(box, j));
        hi = std::max(hi, e);
        lo = std::min(lo, e);
      }
      for (int j = 0; j < 3; ++j) mag = std::max(mag, std::fabs(rows.r[i][j]));
      if (hi < 0) proven_out = true;
      // "Clearly" outside: by a margin that no float rounding explains (relative to the row scale).
      if (hi < -1e-2 * (mag * (1.0 + glm::length(glm::dvec3(c))) + std::fabs(rows.r[i][3]))) far_out = true;
      if (lo < 0 && (i < 5 || !v.infinite_far)) all_in = false;
    }
    if (got == Containment::outside) {
      ++outside;
      CHECK_MSG(proven_out, "%s: box %d classified outside but meets the volume", v.name.c_str(), k);
    }
    if (got == Containment::inside) {
      ++inside;
      CHECK_MSG(all_in, "%s: box %d classified inside but crosses a plane", v.name.c_str(), k);
    }
    if (far_out) {
      ++clearly_outside;
      clearly_outside_found += got == Containment::outside;
    }
    // Plane masks: a child box tested only against the planes its parent straddles can only keep
    // an answer at least as conservative.
    PlaneMask mask = fr.active_mask();
    const Aabb parent{box.min - glm::vec3(1.0f), box.max + glm::vec3(1.0f)};
    if (fr.classify(parent, mask) != Containment::outside) {
      const Containment masked = fr.classify(box, mask);
      if (masked == Containment::outside) CHECK_MSG(proven_out, "%s: masked classify rejected box %d", v.name.c_str(), k);
    }
    const Sphere s = bounding_sphere(box);
    if (fr.classify(s) == Containment::outside) {
      CHECK_MSG(proven_out, "%s: sphere of box %d classified outside but the box meets the volume", v.name.c_str(), k);
    }
  }
  // The test must also show the frustum culls: clearly-outside boxes are rejected.
  CHECK_MSG(clearly_outside_found == clearly_outside, "%s: %d of %d clearly outside boxes rejected", v.name.c_str(),
            clearly_outside_found, clearly_outside);
  CHECK_MSG(outside > 100 && inside > 100, "%s: outside %d inside %d (test not exercising)", v.name.c_str(), outside, inside);
}

void degenerate_matrices() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const Aabb unit{glm::vec3(-1), glm::vec3(1)};
  for (float bad : {nan, inf, 0.0f}) {
    glm::mat4 m(bad);
    const Frustum f = Frustum::from_matrix(m, DepthRange::zero_to_one);
    for (int i = 0; i < 6; ++i) {
      if (f.has_plane(i)) CHECK(is_valid(f.plane(i)));
    }
    CHECK(f.classify(unit) != Containment::outside);
  }
  glm::mat4 m = glm::perspectiveRH_NO(1.0f, 1.0f, 0.1f, 100.0f);
  m[1][1] = nan;  // one poisoned entry removes the planes that use it, never produces NaN planes
  const Frustum f = Frustum::from_matrix(m);
  for (int i = 0; i < 6; ++i) {
    if (f.has_plane(i)) CHECK(is_valid(f.plane(i)));
  }
  CHECK(f.classify(Aabb{glm::vec3(-1, -1, -10), glm::vec3(1, 1, -5)}) != Containment::outside);
  // A box with NaN coordinates is never reported outside (it cannot be proven outside).
  const Frustum g = Frustum::from_matrix(glm::perspectiveRH_NO(1.0f, 1.0f, 0.1f, 100.0f));
  CHECK(g.classify(Aabb{glm::vec3(nan), glm::vec3(nan)}) != Containment::outside);
  // The default frustum has no planes: everything is inside.
  CHECK(Frustum().classify(unit) == Containment::inside);
  CHECK(Frustum().active_mask() == 0);
  // A plane whose unit normal has a component too small for a float (found by fuzz_abt): row
  // (0, 1.3e7, -1.56e-39, -1.16e-10) has the unit normal (0, 1, -1.2e-46), which rounds to (0, 1, 0);
  // at z = -1.8e38 the lost component moves the plane by 0.28, far beyond the float tolerance, and a
  // box straddling the true plane was reported outside. Such a plane is now dropped (as at infinity).
  {
    glm::mat4 thin(0.0f);
    thin[1][0] = 1.3e7f;
    thin[2][0] = -1.56e-39f;
    thin[3][0] = -1.16e-10f;
    const Frustum ft = Frustum::from_matrix(thin);
    const Aabb slab{glm::vec3(-1.0f, 0.0f, -1.8e38f), glm::vec3(1.0f, 1e-20f, 0.0f)};
    // The true planes: row0 >= 0 and -row0 >= 0 (the others vanish); the box has corners on both sides.
    const double lo = 1.3e7 * 0.0 - double(-1.56e-39f) * 0.0 - double(1.16e-10f);
    const double hi = 1.3e7 * 0.0 + double(-1.56e-39f) * -1.8e38 + double(-1.16e-10f);
    CHECK(lo < 0.0 && hi > 0.0);
    CHECK(ft.classify(slab) != Containment::outside);
    for (int i = 0; i < 6; ++i) {
      if (ft.has_plane(i)) CHECK(is_valid(ft.plane(i)));
    }
  }
  // An empty sphere (negative radius) is outside everything.
  CHECK(g.classify(Sphere{glm::vec3(0, 0, -5), -1.0f}) == Containment::outside);
}

}  // namespace

int main() {
  support::Rng rng(20261121);
  for (const TestView& v : make_views(rng)) check_view(v, rng);
  degenerate_matrices();
#ifdef GLM_FORCE_DEPTH_ZERO_TO_ONE
  return cullkit_test::report("test_frustum_glm_zo_lh");
#else
  return cullkit_test::report("test_frustum");
#endif
}
