// make_camera, camera_is_consistent, transform_bounds and the frustum's plane names.
// Oracles: the eye that built the matrix (glm::lookAt), the 8 corners moved one by one in double,
// and points in front of / behind the eye for the near and far planes.
#include <cmath>
#include <limits>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/gtc/matrix_transform.hpp>

using namespace cullkit;

namespace {

void camera_from_matrix() {
  support::Rng rng(11);
  int inconsistent_caught = 0;
  for (int it = 0; it < 300; ++it) {
    const glm::vec3 eye(rng.uniform(-1000, 1000), rng.uniform(-50, 200), rng.uniform(-1000, 1000));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.9f, 0.9f), rng.uniform(-1, 1)) * 10.0f;
    const bool reversed = it % 3 == 2, infinite = it % 2 == 1;
    const DepthRange depth = it % 3 == 0 ? DepthRange::negative_one_to_one : DepthRange::zero_to_one;
    const Camera ref = support::make_camera(eye, target, rng.uniform(20, 110), 640, 480, rng.uniform(0.01f, 1.0f),
                                            infinite ? 0.0f : rng.uniform(100, 5000), depth, reversed);
    const Camera cam = make_camera(ref.view_proj, 640, 480, depth);
    const float scale = std::fmax(1.0f, std::fmax(std::fabs(eye.x), std::fmax(std::fabs(eye.y), std::fabs(eye.z))));
    const float err = glm::length(cam.eye - eye) / scale;
    CHECK_MSG(err < 1e-5f, "eye off by %g (relative) in case %d", double(err), it);
    CHECK(camera_is_consistent(ref) && camera_is_consistent(cam));
    CHECK(cam.width == 640 && cam.height == 480 && cam.depth == depth);
    // An eye 3.2 cm off (scenes in metres, within a kilometre of the origin) is caught.
    Camera off = ref;
    off.eye.x += 0.032f;
    inconsistent_caught += !camera_is_consistent(off);
  }
  CHECK(inconsistent_caught == 300);
  std::printf("camera: eye 3.2 cm off flagged in %d of 300 cameras\n", inconsistent_caught);
  // Orthographic, singular, NaN: no finite centre.
  const glm::mat4 ortho = glm::orthoRH_NO(-1.0f, 1.0f, -1.0f, 1.0f, 0.1f, 10.0f);
  CHECK(std::isnan(make_camera(ortho, 8, 8).eye.x) && !camera_is_consistent(make_camera(ortho, 8, 8)));
  CHECK(std::isnan(make_camera(glm::mat4(0.0f), 8, 8).eye.x));
  CHECK(std::isnan(make_camera(glm::mat4(std::numeric_limits<float>::quiet_NaN()), 8, 8).eye.x));
  // A consistent camera with an empty pixel grid is not consistent.
  const Camera good = support::make_camera(glm::vec3(1, 2, 3), glm::vec3(0), 60, 64, 64, 0.1f, 100);
  Camera empty = good;
  empty.width = 0;
  CHECK(!camera_is_consistent(empty));
  check_camera(good);  // must not fire
}

void plane_names() {
  support::Rng rng(12);
  for (int it = 0; it < 200; ++it) {
    const glm::vec3 eye(rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-100, 100));
    const glm::vec3 dir = glm::normalize(glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.9f, 0.9f), rng.uniform(-1, 1)) +
                                         glm::vec3(0.01f, 0, 0));
    const float n = rng.uniform(0.05f, 1.0f), f = rng.uniform(50, 500);
    const int kind = it % 6;
    const bool reversed = kind >= 3, infinite = kind % 3 == 2;
    const DepthRange depth = kind % 3 == 0 ? DepthRange::negative_one_to_one : DepthRange::zero_to_one;
    const Camera cam = support::make_camera(eye, eye + dir, 60, 64, 64, n, infinite ? 0.0f : f, depth, reversed);
    const Frustum fr = frustum_of(cam);
    // The near plane exists and separates the eye (outside) from a point just past it (inside).
    CHECK_MSG(fr.has_plane(Frustum::near_plane), "kind %d: no near plane", kind);
    if (!fr.has_plane(Frustum::near_plane)) continue;
    const Plane& np = fr.plane(Frustum::near_plane);
    CHECK_MSG(signed_distance(np, eye) < 0.0f && signed_distance(np, eye + dir * (2.0f * n)) > 0.0f,
              "kind %d: near plane at %g from the eye", kind, double(signed_distance(np, eye)));
    CHECK_MSG(std::fabs(signed_distance(np, eye) + n) < 1e-3f * (1.0f + glm::length(eye)), "kind %d near distance", kind);
    if (infinite) {
      CHECK_MSG(!fr.has_plane(Frustum::far_plane), "kind %d: far plane of an infinite projection", kind);
    } else {
      CHECK(fr.has_plane(Frustum::far_plane));
      const Plane& fp = fr.plane(Frustum::far_plane);
      CHECK_MSG(signed_distance(fp, eye) > 0.0f && signed_distance(fp, eye + dir * (2.0f * f)) < 0.0f,
                "kind %d: far plane", kind);
    }
  }
}

void bounds() {
  support::Rng rng(13);
  for (int it = 0; it < 2000; ++it) {
    const glm::vec3 c(rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-100, 100));
    const glm::vec3 h(rng.uniform(0, 5), rng.uniform(0, 5), rng.uniform(0, 5));
    const Aabb local{c - h, c + h};
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(rng.uniform(-500, 500), rng.uniform(-500, 500), rng.uniform(-500, 500)));
    m = glm::rotate(m, rng.uniform(0, 6.3f), glm::normalize(glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), 1.0f)));
    m = glm::scale(m, glm::vec3(rng.uniform(0.1f, 3), rng.uniform(0.1f, 3), rng.uniform(-3, 3)));
    if (it % 10 == 9) m[2][3] = 0.001f;  // projective: the corner path
    const Aabb b = transform_bounds(local, m);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 p = corner(local, k);
      double q[4];
      for (int r = 0; r < 4; ++r) q[r] = double(m[0][r]) * p.x + double(m[1][r]) * p.y + double(m[2][r]) * p.z + double(m[3][r]);
      for (int r = 0; r < 3; ++r) {
        lo[r] = std::fmin(lo[r], q[r] / q[3]);
        hi[r] = std::fmax(hi[r], q[r] / q[3]);
      }
    }
    bool holds = is_valid(b), tight = true;
    for (int r = 0; r < 3; ++r) {
      holds = holds && double(b.min[r]) <= lo[r] + 1e-9 * (1 + std::fabs(lo[r])) && double(b.max[r]) >= hi[r] - 1e-9 * (1 + std::fabs(hi[r]));
      // Tight: within a few float ulps of the exact extremes.
      tight = tight && std::fabs(double(b.min[r]) - lo[r]) <= 4e-7 * (1 + std::fabs(lo[r])) &&
              std::fabs(double(b.max[r]) - hi[r]) <= 4e-7 * (1 + std::fabs(hi[r]));
    }
    CHECK_MSG(holds && tight, "transform_bounds case %d", it);
  }
  const Aabb unit{glm::vec3(-1.5f, 0, 2), glm::vec3(3, 0.25f, 7)};
  const Aabb same = transform_bounds(unit, glm::mat4(1.0f));
  CHECK(same.min == unit.min && same.max == unit.max);
  // Behind a projective matrix's w = 0: not valid.
  glm::mat4 p(1.0f);
  p[0][3] = 1.0f;  // w = x + 1
  CHECK(!is_valid(transform_bounds(Aabb{glm::vec3(-2), glm::vec3(2)}, p)));
}
}  // namespace

int main() {
  camera_from_matrix();
  plane_names();
  bounds();
  return cullkit_test::report("test_engine_camera");
}
