// Google Benchmark micro-benchmarks of the geometry core: one box or sphere against a frustum,
// with and without a plane mask, and plane extraction.
#include <benchmark/benchmark.h>

#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

namespace {
std::vector<Aabb> random_boxes(std::size_t n) {
  support::Rng rng(1);
  std::vector<Aabb> boxes(n);
  for (auto& b : boxes) {
    const glm::vec3 c(rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-100, 100));
    b = Aabb{c - glm::vec3(2), c + glm::vec3(2)};
  }
  return boxes;
}
const Camera& camera() {
  static const Camera c = support::make_camera({0, 0, 0}, {0, 0, -1}, 70, 1280, 720, 0.1f, 300.0f);
  return c;
}

void classify_box(benchmark::State& state) {
  const auto boxes = random_boxes(4096);
  const Frustum f = frustum_of(camera());
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(f.classify(boxes[i++ & 4095]));
}
void classify_box_masked(benchmark::State& state) {
  const auto boxes = random_boxes(4096);
  const Frustum f = frustum_of(camera());
  std::size_t i = 0;
  for (auto _ : state) {
    PlaneMask mask = 0x3;  // a parent already inside four of the six planes
    benchmark::DoNotOptimize(f.classify(boxes[i++ & 4095], mask));
  }
}
void classify_sphere(benchmark::State& state) {
  const auto boxes = random_boxes(4096);
  std::vector<Sphere> spheres;
  for (const auto& b : boxes) spheres.push_back(bounding_sphere(b));
  const Frustum f = frustum_of(camera());
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(f.classify(spheres[i++ & 4095]));
}
void from_matrix(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(Frustum::from_matrix(camera().view_proj));
}
}  // namespace

BENCHMARK(classify_box);
BENCHMARK(classify_box_masked);
BENCHMARK(classify_sphere);
BENCHMARK(from_matrix);
BENCHMARK_MAIN();
