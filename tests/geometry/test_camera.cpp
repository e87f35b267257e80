// The pixel-ray rule: every pixel ray projects back onto its pixel centre, and the same view gives
// the same rays whatever the depth range, reversed-Z or an infinite far plane.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

int main() {
  support::Rng rng(3);
  for (int it = 0; it < 40; ++it) {
    const glm::vec3 eye(rng.uniform(-100, 100), rng.uniform(0, 50), rng.uniform(-100, 100));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.9f, 0.9f), rng.uniform(-1, 1));
    const int w = rng.range(1, 300), h = rng.range(1, 200);
    const float fov = rng.uniform(20, 120), n = rng.uniform(0.01f, 1.0f), f = rng.uniform(100, 1000);
    const Camera cams[] = {
        support::make_camera(eye, target, fov, w, h, n, f, DepthRange::negative_one_to_one),
        support::make_camera(eye, target, fov, w, h, n, f, DepthRange::zero_to_one),
        support::make_camera(eye, target, fov, w, h, n, f, DepthRange::zero_to_one, true),
        support::make_camera(eye, target, fov, w, h, n, 0.0f, DepthRange::negative_one_to_one),
        support::make_camera(eye, target, fov, w, h, n, 0.0f, DepthRange::zero_to_one),
        support::make_camera(eye, target, fov, w, h, n, 0.0f, DepthRange::zero_to_one, true),
    };
    const PixelRays reference(cams[0]);
    for (int variant = 0; variant < 6; ++variant) {
      const Camera& cam = cams[variant];
      const PixelRays rays(cam);
      // Reversed-Z puts NDC depth 1 on the near plane, and an infinite far plane makes the rule fall
      // back to the near-plane point, which a float matrix places only to within about
      // |eye| * 1e-6 / near radians: the tolerance follows from that.
      const bool infinite = variant >= 2;
      const double slack = infinite ? 1e-6 * (1.0 + glm::length(eye)) / n : 0.0;
      const double tol_dir = 2e-5 + slack, tol_px = 1e-2 + slack * h / (2.0 * std::tan((double(fov) * 3.14159265358979 / 180.0) / 2));
      for (int k = 0; k < 50; ++k) {
        const int x = rng.range(0, w - 1), y = rng.range(0, h - 1);
        const Ray r = rays.ray(x, y);
        CHECK(r.origin == eye);
        CHECK_NEAR(glm::length(r.direction), 1.0, 1e-5);
        const Ray r0 = reference.ray(x, y);
        CHECK_MSG(glm::length(r.direction - r0.direction) < tol_dir, "iteration %d variant %d pixel %d %d", it, variant, x, y);
        // Project a point along the ray back to the screen: it lands on the pixel centre.
        const glm::dvec4 clip = glm::dmat4(cam.view_proj) * glm::dvec4(glm::dvec3(eye) + 10.0 * glm::dvec3(r.direction), 1.0);
        const double px = (clip.x / clip.w + 1.0) * 0.5 * w, py = (1.0 - clip.y / clip.w) * 0.5 * h;
        CHECK_MSG(std::fabs(px - (x + 0.5)) < tol_px && std::fabs(py - (y + 0.5)) < tol_px,
                  "iteration %d variant %d pixel %d %d projects to %g %g", it, variant, x, y, px, py);
        CHECK(clip.w > 0.0);  // in front of the eye
      }
    }
  }
  // PixelRays::directions is bit for bit ray(x, y).direction: every row segment (odd and even
  // lengths and starts) of the same six kinds of view, an eye far from the origin, a near-singular
  // and a singular matrix, and matrices with NaN or infinite entries.
  {
    support::Rng drng(17);
    std::vector<Camera> cams;
    for (int it = 0; it < 12; ++it) {
      const float scale = it < 6 ? 100.0f : 5e4f;
      const glm::vec3 eye(drng.uniform(-scale, scale), drng.uniform(0, scale), drng.uniform(-scale, scale));
      const glm::vec3 target = eye + glm::vec3(drng.uniform(-1, 1), drng.uniform(-0.9f, 0.9f), drng.uniform(-1, 1));
      const int w = drng.range(1, 90), h = drng.range(1, 60);
      const float fov = it % 3 == 0 ? drng.uniform(0.05f, 1.0f) : drng.uniform(20, 150);
      const float n = drng.uniform(0.01f, 1.0f), f = drng.uniform(100, 1000);
      cams.push_back(support::make_camera(eye, target, fov, w, h, n, f, DepthRange::negative_one_to_one));
      cams.push_back(support::make_camera(eye, target, fov, w, h, n, f, DepthRange::zero_to_one, true));
      cams.push_back(support::make_camera(eye, target, fov, w, h, n, 0.0f, DepthRange::negative_one_to_one));
      cams.push_back(support::make_camera(eye, target, fov, w, h, n, 0.0f, DepthRange::zero_to_one, true));
    }
    glm::mat4 thin(1.0f);
    thin[2][2] = 1e-30f;
    cams.push_back(Camera{glm::vec3(1, 2, 3), thin, 7, 5});
    cams.push_back(Camera{glm::vec3(0), glm::mat4(0.0f), 6, 3});
    glm::mat4 nan_m = cams[0].view_proj, inf_m = cams[0].view_proj;
    nan_m[1][2] = std::numeric_limits<float>::quiet_NaN();
    inf_m[3][0] = std::numeric_limits<float>::infinity();
    cams.push_back(Camera{cams[0].eye, nan_m, 5, 4});
    cams.push_back(Camera{cams[0].eye, inf_m, 5, 4});
    const auto same = [](float a, float b) {  // equal bits (NaN included)
      std::uint32_t ua, ub;
      std::memcpy(&ua, &a, 4);
      std::memcpy(&ub, &b, 4);
      return ua == ub;
    };
    int compared = 0;
    for (std::size_t ci = 0; ci < cams.size(); ++ci) {
      const PixelRays rays(cams[ci]);
      const int w = cams[ci].width, h = cams[ci].height;
      std::vector<float> dx(static_cast<std::size_t>(w)), dy(dx.size()), dz(dx.size());
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; x += 1 + y % 3) {
          const int count = std::min(w - x, 1 + (x * 7 + y) % 17);
          rays.directions(x, y, count, dx.data(), dy.data(), dz.data());
          for (int i = 0; i < count; ++i) {
            const glm::vec3 d = rays.ray(x + i, y).direction;
            ++compared;
            CHECK_MSG(same(d.x, dx[static_cast<std::size_t>(i)]) && same(d.y, dy[static_cast<std::size_t>(i)]) &&
                          same(d.z, dz[static_cast<std::size_t>(i)]),
                      "camera %zu pixel %d %d: directions() %.9g %.9g %.9g, ray() %.9g %.9g %.9g", ci, x + i, y,
                      double(dx[static_cast<std::size_t>(i)]), double(dy[static_cast<std::size_t>(i)]),
                      double(dz[static_cast<std::size_t>(i)]), double(d.x), double(d.y), double(d.z));
          }
        }
      }
    }
    CHECK(compared > 20000);
  }
  // A singular matrix gives zero directions, never NaN.
  const Camera bad{glm::vec3(0), glm::mat4(0.0f), 4, 4};
  const Ray r = PixelRays(bad).ray(1, 1);
  CHECK(!(r.direction.x != r.direction.x) && !(r.direction.y != r.direction.y) && !(r.direction.z != r.direction.z));
  // The centre ray of an odd-sized image looks at the target.
  const Camera c = support::make_camera(glm::vec3(1, 2, 3), glm::vec3(4, 2, 3), 60, 101, 51, 0.1f, 100.0f);
  CHECK(glm::length(PixelRays(c).ray(50, 25).direction - glm::vec3(1, 0, 0)) < 1e-5f);
  // The top-left pixel looks up and left: y runs down from the top row.
  const Ray tl = PixelRays(c).ray(0, 0);
  CHECK(tl.direction.y > 0.0f && tl.direction.z < 0.0f);  // looking down +x: left is -z
  // A NaN or an infinity in any entry, the depth row included (the centre itself does not read
  // it), makes the camera inconsistent and its centre NaN.
  {
    const Camera good = support::make_camera(glm::vec3(3, 4, 5), glm::vec3(0), 60.0f, 64, 48, 0.1f, 100.0f,
                                             DepthRange::negative_one_to_one);
    CHECK(camera_is_consistent(good));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
          Camera cam = good;
          cam.view_proj[c][r] = bad;
          CHECK_MSG(!camera_is_consistent(cam), "entry [%d][%d] = %g accepted", c, r, double(bad));
          CHECK(std::isnan(projection_centre(cam.view_proj).x));
        }
  }
  return cullkit_test::report("test_camera");
}
