// Frustum classification of 60,000 boxes: cullkit's scalar Frustum::classify loop against a
// structure-of-arrays branchless scan, at two visible fractions. CSV on stdout (race.hpp).
//   ./build/release/bench/bench_frustum
#include <cstdio>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"
#include "soa_scan.hpp"

using namespace cullkit;

int main() {
  const bool smoke = cullkit_bench::smoke();
  const std::size_t n = smoke ? 2000 : 60000;
  support::Rng rng(60000);
  std::vector<Aabb> boxes(n);
  for (auto& b : boxes) {
    const glm::vec3 c(rng.uniform(-500, 500), rng.uniform(0, 50), rng.uniform(-500, 500));
    const glm::vec3 h(rng.uniform(0.5f, 5), rng.uniform(0.5f, 10), rng.uniform(0.5f, 5));
    b = Aabb{c - h, c + h};
  }
  cullkit_bench::SoaBoxes soa(boxes);
  struct View { const char* name; float fov; glm::vec3 eye, target; float far_plane; };
  const View views[] = {{"wide_38pct", 80.0f, {0, 300, 0}, {0, 0, 1}, 2000.0f},
                        {"narrow_2pct", 5.0f, {0, 20, 0}, {300, 20, 0}, 2000.0f}};
  std::vector<std::uint32_t> out_scalar, out_soa;
  for (const View& v : views) {
    const Camera cam = support::make_camera(v.eye, v.target, v.fov, 1280, 720, 0.5f, v.far_plane);
    const Frustum f = frustum_of(cam);
    auto scalar = [&] {
      out_scalar.clear();
      for (std::uint32_t i = 0; i < n; ++i) {
        if (f.classify(boxes[i]) != Containment::outside) out_scalar.push_back(i);
      }
    };
    auto scan = [&] { soa.cull(f, out_soa); };
    scalar();
    scan();
    std::fprintf(stderr, "%s: %zu boxes, %.1f%% visible (scalar), %.1f%% (SoA)\n", v.name, n,
                 100.0 * double(out_scalar.size()) / double(n), 100.0 * double(out_soa.size()) / double(n));
    cullkit_bench::race(std::string("frustum_") + v.name,
                        {{"cullkit_scalar_classify", scalar}, {"soa_branchless_scan", scan}});
  }
  return 0;
}
