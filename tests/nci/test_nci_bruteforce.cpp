// NormalClassIndex against a brute-force oracle: every pixel ray against every triangle with the
// same float watertight test (the index must give the identical per-pixel answer), and against the
// same test in double (every double first hit must be in the set, up to explicit ties).
#include <cstdio>
#include <set>

#include "check.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

int g_ties = 0;

// Runs the index on `cams` and compares with the float brute force pixel by pixel, and the set
// with the double brute force (misses must be ties).
void compare(const char* label, const Scene& scene, const NciParams& params, const std::vector<Camera>& cams,
             std::uint64_t seed) {
  const nci_test::TestIndex<glm::vec3> index(scene.mesh(), params);
  NciContext ctx;
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci];
    VisibleSet set;
    NciPixels px;
    index.select_visible(cam, ctx, set, &px);
    const auto brute = nci_test::brute_force<float>(scene, cam);
    int diff = 0;
    for (std::size_t p = 0; p < brute.tri.size(); ++p) {
      if (px.triangle[p] != brute.tri[p]) {
        if (++diff <= 3)
          std::fprintf(stderr, "  %s cam %zu pixel (%d,%d): index %u t=%g, brute %u t=%g (seed %llu)\n", label, ci,
                       int(p % cam.width), int(p / cam.width), px.triangle[p], double(px.depth[p]), brute.tri[p],
                       double(brute.t[p]), static_cast<unsigned long long>(seed));
      } else if (brute.tri[p] != nci_test::miss) {
        CHECK(px.depth[p] == brute.t[p]);
      }
    }
    CHECK_MSG(diff == 0, "%s cam %zu: %d pixels differ from the float brute force (seed %llu)", label, ci, diff,
              static_cast<unsigned long long>(seed));
    // The set is exactly the per-pixel winners plus the edge-band triangles in front of each
    // pixel's solid hit (and that hit).
    std::set<std::uint32_t> expect(brute.selected.begin(), brute.selected.end());
    for (auto t : brute.tri)
      if (t != nci_test::miss) CHECK(expect.count(t) == 1);
    CHECK_MSG(std::vector<std::uint32_t>(expect.begin(), expect.end()) == set.triangles,
              "%s cam %zu: set differs (%zu vs %zu)", label, ci, set.triangles.size(), expect.size());
    CHECK(std::is_sorted(set.triangles.begin(), set.triangles.end()));
    CHECK(set.triangles_tested >= set.triangles.size());
    // Double oracle: every double first hit in the set, or a tie.
    const auto exact = nci_test::brute_force<double>(scene, cam);
    int missing = 0;
    for (std::size_t p = 0; p < exact.tri.size(); ++p) {
      const auto want = exact.tri[p];
      if (want == nci_test::miss || std::binary_search(set.triangles.begin(), set.triangles.end(), want)) continue;
      const auto have = px.triangle[p];
      float t = 0;
      const int x = int(p % cam.width), y = int(p / cam.width);
      if (have != nci_test::miss && nci_test::own_hit(scene, cam, have, x, y, t) &&
          std::fabs(t - exact.t[p]) <= 1e-5f * std::max(1.0f, exact.t[p])) {
        ++g_ties;
        continue;
      }
      ++missing;
      if (missing <= 3)
        std::fprintf(stderr, "  %s cam %zu pixel (%d,%d): double hit %u t=%g missing; index has %u (seed %llu)\n",
                     label, ci, x, y, want, double(exact.t[p]), have, static_cast<unsigned long long>(seed));
    }
    CHECK_MSG(missing == 0, "%s cam %zu: %d double-oracle misses", label, ci, missing);
  }
}

Scene random_soup(std::uint64_t seed, int count, float thin) {
  Scene s;
  support::Rng rng(seed);
  std::vector<glm::vec3> corners;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 c(rng.uniform(-10, 10), rng.uniform(-3, 3), rng.uniform(-10, 10));
    glm::vec3 a = c + glm::vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
    glm::vec3 b = c + glm::vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
    glm::vec3 d = c + glm::vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
    if (thin > 0 && i % 3 == 0) d = a + (b - a) * 0.5f + glm::vec3(0, thin, 0);  // sliver
    corners.push_back(a);
    corners.push_back(b);
    corners.push_back(d);
  }
  s.add_triangles(corners, "soup");
  return s;
}

}  // namespace

int main() {
  const int W = 48, H = 36;
  {
    const Scene city = support::make_city(11, 2);
    const auto cams = nci_test::cameras_for(city.bounds, 10, W, H, 101);
    compare("city", city, NciParams{}, cams, 101);
    NciParams p;
    p.classes = 128;
    p.grid = 16;
    p.tile_size = 8;
    compare("city/128/16/t8", city, p, cams, 101);
  }
  {
    const Scene office = support::make_office(12, 2, 2);
    const auto cams = nci_test::cameras_for(office.bounds, 10, W, H, 102);
    compare("office", office, NciParams{}, cams, 102);
    NciParams p;
    p.tile_size = 16;  // the default before tiles grew to 32
    compare("office/t16", office, p, cams, 102);
    p.tile_size = 29;  // rows not a multiple of 4 wide, partial tiles on both edges
    compare("office/t29", office, p, cams, 102);
    p.tile_size = 64;  // the largest tile: one partial tile covers the screen
    compare("office/t64", office, p, cams, 102);
    // Wider screen: full 64-pixel rows (the row mask's top bit) beside partial tiles, and a tile
    // above 32 pixels that is not a multiple of 4 (45).
    const auto wide = nci_test::cameras_for(office.bounds, 4, 136, 70, 103);
    p.tile_size = 64;
    compare("office/wide/t64", office, p, wide, 103);
    p.tile_size = 45;
    compare("office/wide/t45", office, p, wide, 103);
  }
  {
    const Scene soup = random_soup(14, 400, 1e-4f);
    const auto cams = nci_test::cameras_for(soup.bounds, 10, W, H, 104);
    compare("soup", soup, NciParams{}, cams, 104);
    NciParams p;
    p.classes = 1;
    p.grid = 1;
    compare("soup/1/1", soup, p, cams, 104);
    p.classes = 512;
    p.grid = 200;
    p.tile_size = 5;
    compare("soup/512/200/t5", soup, p, cams, 104);
  }
  {
    // Far from the origin: float cameras whose matrices put the centre of projection slightly off
    // the eye (the screen rectangles must follow the eye's rays, not the matrix's centre).
    Scene soup = random_soup(15, 300, 0.0f);
    for (auto& p : soup.positions) p += glm::vec3(5000.0f, 20.0f, -7000.0f);
    soup.bounds.min += glm::vec3(5000.0f, 20.0f, -7000.0f);
    soup.bounds.max += glm::vec3(5000.0f, 20.0f, -7000.0f);
    const auto cams = nci_test::cameras_for(soup.bounds, 12, W, H, 105);
    compare("far soup", soup, NciParams{}, cams, 105);
  }
  std::printf("double-oracle ties accepted: %d\n", g_ties);
  return cullkit_test::report("test_nci_bruteforce");
}
