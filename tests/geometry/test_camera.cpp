// The pixel-ray rule: every pixel ray projects back onto its pixel centre, and the same view gives
// the same rays whatever the depth range, reversed-Z or an infinite far plane.
#include <cmath>

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
  return cullkit_test::report("test_camera");
}
