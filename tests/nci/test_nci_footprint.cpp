// NormalClassIndex: the 2D footprint pre-test (a triangle is ray-tested only at live pixel centres
// inside its projected triangle grown by a margin). Scenes are built in screen space so that
// triangles sit exactly where the pre-test decides: edges through pixel centres, corners on pixel
// centres, sub-pixel triangles, slivers whose rectangle covers a centre their triangle misses.
// Every camera is compared pixel by pixel (triangle and depth) with the float brute force.
#include <cstdio>
#include <set>

#include "check.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

// The world point seen at pixel-centre coordinates (u, v) (pixel i has coordinate i) at distance
// `dist` from the eye, along the camera's own pixel ray.
glm::vec3 at_pixel(const Camera& cam, double u, double v, float dist) {
  const PixelRays rays(cam);
  const Ray r = rays.ray_at(u + 0.5, v + 0.5);
  return r.origin + r.direction * dist;
}

// Appends the triangle with its corners ordered to face the eye.
void push_facing(std::vector<glm::vec3>& out, const Camera& cam, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  if (!detail::faces_eye(a, b, c, glm::dvec3(cam.eye))) std::swap(b, c);
  out.push_back(a);
  out.push_back(b);
  out.push_back(c);
}

// Pixel-exact comparison with the float brute force; returns triangles_tested.
std::size_t compare(const char* label, const Scene& scene, const NciParams& params, const Camera& cam,
                    std::uint64_t seed) {
  const nci_test::TestIndex<glm::vec3> index(scene.mesh(), params);
  NciContext ctx;
  VisibleSet set;
  NciPixels px;
  index.select_visible(cam, ctx, set, &px);
  const auto brute = nci_test::brute_force<float>(scene, cam);
  int diff = 0;
  std::set<std::uint32_t> expect;
  for (std::size_t p = 0; p < brute.tri.size(); ++p) {
    if (brute.tri[p] != nci_test::miss) expect.insert(brute.tri[p]);
    const bool same = px.triangle[p] == brute.tri[p] && (brute.tri[p] == nci_test::miss || px.depth[p] == brute.t[p]);
    if (!same && ++diff <= 3)
      std::fprintf(stderr, "  %s pixel (%d,%d): index %u t=%g, brute %u t=%g (seed %llu)\n", label,
                   int(p % cam.width), int(p / cam.width), px.triangle[p], double(px.depth[p]), brute.tri[p],
                   double(brute.t[p]), static_cast<unsigned long long>(seed));
  }
  CHECK_MSG(diff == 0, "%s: %d pixels differ from the float brute force (seed %llu)", label, diff,
            static_cast<unsigned long long>(seed));
  // The set: the pixels' winners and the edge-band triangles in front of each pixel's solid hit.
  for (std::uint32_t t : brute.selected) expect.insert(t);
  CHECK_MSG(std::vector<std::uint32_t>(expect.begin(), expect.end()) == set.triangles,
            "%s: set differs (%zu, brute force %zu; seed %llu)", label, set.triangles.size(), expect.size(),
            static_cast<unsigned long long>(seed));
  return set.triangles_tested;
}

std::vector<Camera> cameras(std::uint64_t seed, int w, int h) {
  support::Rng rng(seed);
  std::vector<Camera> cams;
  for (int i = 0; i < 6; ++i) {
    const glm::vec3 eye(rng.uniform(-50, 50), rng.uniform(-5, 20), rng.uniform(-50, 50));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.5f, 0.5f), rng.uniform(-1, 1));
    const float fov = i == 5 ? 8.0f : rng.uniform(30.0f, 100.0f);  // one narrow view
    cams.push_back(support::make_camera(eye, target, fov, w, h, 0.05f, i % 2 ? 0.0f : 1e4f,
                                        i == 3 ? DepthRange::zero_to_one : DepthRange::negative_one_to_one, i == 4));
  }
  return cams;
}

}  // namespace

int main() {
  const int W = 48, H = 36;
  const std::uint64_t seed = 601;
  const auto cams = cameras(seed, W, H);
  support::Rng rng(seed + 1);
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci];
    char label[64];
    // 1. Slivers beside pixel centres: the sliver between the lines x - y = 0.7 and 0.8 (pixel
    //    coordinates, from a centre (i, j)) has the centre (i + 1, j) in its rectangle, 0.14 pixel
    //    away from the triangle. Nothing is hit, and with the pre-test nothing is ray-tested.
    {
      std::vector<glm::vec3> corners;
      for (int j = 2; j + 3 < H; j += 4)
        for (int i = 2; i + 3 < W; i += 4) {
          const float dist = rng.uniform(2.0f, 60.0f);
          push_facing(corners, cam, at_pixel(cam, i + 0.3, j - 0.5, dist), at_pixel(cam, i + 1.6, j + 0.8, dist),
                      at_pixel(cam, i + 0.35, j - 0.35, dist));
        }
      Scene s;
      s.add_triangles(corners, "slivers");
      std::snprintf(label, sizeof label, "slivers cam %zu", ci);
      const std::size_t tested = compare(label, s, NciParams{}, cam, seed);
      // The narrow view (8 degrees at 36 pixels: about 260 pixels per radian) keeps the pre-test on.
      CHECK_MSG(tested == 0, "%s: %zu slivers ray-tested; no pixel centre is within 0.14 pixel of one", label, tested);
    }
    // 2. Corners exactly on pixel centres and edges through them (a fan around each centre, and
    //    sub-pixel triangles of random size and place): the watertight test's own rounding decides.
    {
      std::vector<glm::vec3> corners;
      for (int j = 1; j + 2 < H; j += 3)
        for (int i = 1; i + 2 < W; i += 3) {
          const float dist = rng.uniform(1.0f, 80.0f);
          const glm::vec3 c = at_pixel(cam, i, j, dist);
          const double x = i, y = j;
          const double ring[4][2] = {{x + 1.0, y}, {x, y + 1.0}, {x - 1.0, y}, {x, y - 1.0}};
          for (int k = 0; k < 4; ++k)
            push_facing(corners, cam, c, at_pixel(cam, ring[k][0], ring[k][1], dist),
                        at_pixel(cam, ring[(k + 1) % 4][0], ring[(k + 1) % 4][1], dist));
          // A sub-pixel triangle nearby, nearer the eye (may or may not hold a centre).
          const double u = i + rng.uniform(-1, 1), v = j + rng.uniform(-1, 1), sz = rng.uniform(0.005f, 1.5f);
          const float d2 = dist * 0.9f;
          push_facing(corners, cam, at_pixel(cam, u, v, d2), at_pixel(cam, u + sz, v + 0.3 * sz, d2),
                      at_pixel(cam, u + 0.2 * sz, v + sz, d2));
        }
      Scene s;
      s.add_triangles(corners, "edges on centres");
      std::snprintf(label, sizeof label, "centres cam %zu", ci);
      (void)compare(label, s, NciParams{}, cam, seed);
      NciParams p;
      p.tile_size = 5;
      p.classes = 1;
      std::snprintf(label, sizeof label, "centres/t5/1 cam %zu", ci);
      (void)compare(label, s, p, cam, seed);
    }
  }
  return cullkit_test::report("test_nci_footprint");
}
