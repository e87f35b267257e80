// MeshOcclusionCuller::cull on several tasks (MeshOcclusionParams::threads and task_runner) gives
// exactly the one-thread answer: the same objects in the same order, the same statistics, and the
// same box queries afterwards, for 2 and 3 threads on the library's pool, on a job system that runs
// each task on a thread of its own, and on job systems that run the tasks on the calling thread in
// reverse or shuffled order. On generated scenes (always: one with objects that overlap) and the
// real scenes when present. A warm context then allocates nothing on several tasks either. The occluder insertion runs on the tasks
// strip by strip of the grid's rows, so this also checks that the strips do not depend on the tasks.
//
// Mutants this test caught (each applied by hand to parallel_frame.hpp, then reverted; with the
// real scenes present, two runs each):
//   a batch one object short (BatchCounter::claim's `last` one less): 992 of 1,010 checks failed;
//   a task's caches not starting a new frame (the last camera's projections): 219 and 223 failed;
//   every task on task 0's caches (a race between the threads' projections): a different answer
//   on oacmpdm9 (pool, 3 threads), then a crash, in both runs;
//   twice the strips when threads != 1 (row_strips.hpp), before strips made the whole grid's
//   decisions: 6 of 16 frames differ on fzk_haus, 8 on oacmpdm9, 14 on the car (since then any
//   strip count gives the one-thread answer, so this is no longer a mutant);
//   a gathering task skipping the last occluder of each batch it takes: 922 of 1,010 checks failed;
//   the tasks' clipped polygons joined in reverse task order with their own list's places: 2 failed;
//   the patches shared by overlapping objects never gathered on several tasks: 336 of 1,351 failed,
//   all on the city with overlapping objects (every frame of every setup). Gathering those patches
//   in reverse order instead (a shared triangle then goes in with its last occluder) changed no
//   answer there: the triangles are the same, only the patch they join differs.
//   a strip seeding a patch's grid with the nearest point of the patch's triangles that reach it
//   (row_strips.hpp): 2 of 48 frames differ on the city, 10 of 16 on fzk_haus, in every setup;
//   a triangle's depth plane set up on the strip's rows of its cells only (CoverageGrid::add_depth):
//   lasdunasarena's camera 6 differs in 3 setups (6 checks).
// One thread gathers on demand (occluders.hpp) and several threads gather all, so these compare the
// two too. Mutants caught there (with the real scenes / the generated ones alone): a patch dropped
// ungathered when ANY cell of its box is covered near enough: 1,224 of 1,351 / 910 of 1,021 checks
// failed; when its box's cells are covered as near as its FARTHEST corner: 640 / 406 failed; the
// ungathered patches ordered by their box's farthest corner: 830 / 546 failed.
// One thread projects a patch's corners as it gathers it, several threads all chosen patches' first.
// Mutants: each patch's last listed corner left unprojected (project_patch_corners): 50 checks
// failed, all on the generated city; the corners not projected first when several threads' frame
// runs on the calling thread alone (query.hpp): a crash on the office of two rooms, the only scene
// with frames of so few objects.
#include <algorithm>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "count_allocations.hpp"

namespace {

using cullkit::support::Scene;

/// Job systems for TaskRunner: the tasks in reverse order on the calling thread, in an order
/// shuffled by a seed on the calling thread, or each on a thread of its own.
void run_reversed(void*, std::size_t count, void (*run)(void*, std::size_t), void* job) {
  for (std::size_t i = count; i > 0; --i) run(job, i - 1);
}

void run_shuffled(void* context, std::size_t count, void (*run)(void*, std::size_t), void* job) {
  auto& rng = *static_cast<cullkit::support::Rng*>(context);
  std::size_t order[64];
  const std::size_t n = std::min<std::size_t>(count, 64);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.next() % i]);
  for (std::size_t i = 0; i < n; ++i) run(job, order[i]);
  for (std::size_t i = n; i < count; ++i) run(job, i);
}

void run_on_threads(void*, std::size_t count, void (*run)(void*, std::size_t), void* job) {
  std::vector<std::thread> threads;
  for (std::size_t i = 1; i < count; ++i) threads.emplace_back([=] { run(job, i); });
  run(job, 0);
  for (auto& t : threads) t.join();
}

/// Cameras from eyes spread through the scene's box at a standing share of its height, looking at
/// the centres of random objects (so most frames have objects in front of others), with every depth
/// convention among them.
std::vector<cullkit::Camera> cameras_for(const Scene& scene, int count, std::uint64_t seed) {
  const cullkit::Aabb& box = scene.bounds;
  const glm::vec3 size = box.max - box.min;
  const float reach = std::max(glm::length(size), 1e-3f);
  cullkit::support::Rng rng(seed);
  std::vector<cullkit::Camera> cams;
  while (static_cast<int>(cams.size()) < count) {
    const glm::vec3 eye = box.min + size * glm::vec3(rng.uniform(0.05f, 0.95f), rng.uniform(0.02f, 0.5f), rng.uniform(0.05f, 0.95f));
    const glm::vec3 target = scene.objects[rng.next() % scene.objects.size()].bounds.center();
    if (glm::length(target - eye) < 1e-3f * reach) continue;
    const int convention = static_cast<int>(cams.size() % 3);
    const auto depth = convention == 1 ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one;
    cams.push_back(cullkit::support::make_camera(eye, target, 70.0f, 1920, 1080, reach * 1e-4f,
                                                 convention == 2 ? 0.0f : reach * 2.0f, depth, false));
  }
  return cams;
}

/// One frame's answer: the kept objects in order, the statistics, and box queries of every object.
struct Answer {
  std::vector<std::uint32_t> kept;
  cullkit::MeshOcclusionStats stats;
  std::vector<bool> box_hidden;
};

// Several tasks insert the occluders strip by strip of the grid's rows, each strip skipping what is
// covered on its own rows as the whole grid does there: every statistic is the same, the triangles
// worked on (`occluder_triangles`, inserted in some strip) and the covered cells included.
bool same_stats(const cullkit::MeshOcclusionStats& a, const cullkit::MeshOcclusionStats& b) {
  return a.objects_in_frustum == b.objects_in_frustum && a.occluders_used == b.occluders_used &&
         a.occluder_triangles == b.occluder_triangles &&
         a.objects_hidden == b.objects_hidden &&
         a.objects_unusable_visible == b.objects_unusable_visible && a.cells_covered == b.cells_covered &&
         a.occlusion_enabled == b.occlusion_enabled;
}

template <class Culler>
Answer answer(const Culler& culler, const cullkit::Camera& camera, cullkit::MeshOcclusionContext& context,
              const std::vector<cullkit::Aabb>& boxes) {
  Answer a;
  culler.cull(camera, context, a.kept);
  a.stats = context.stats();
  for (const auto& b : boxes) a.box_hidden.push_back(context.is_hidden(b));
  return a;
}

struct Setup {
  const char* name;
  unsigned threads;
  cullkit::TaskRunner runner;
};

/// Compares every setup with the one-thread culler; returns the objects hidden over the cameras.
std::size_t check_scene(const Scene& scene, int camera_count) {
  std::vector<cullkit::MeshObject> objects;
  std::vector<cullkit::Aabb> boxes;
  for (const auto& o : scene.objects) {
    objects.push_back(cullkit::MeshObject{o.first_triangle, o.triangle_count});
    boxes.push_back(o.bounds);
  }
  const cullkit::MeshOcclusionCuller<glm::vec3> one(scene.mesh(), objects.data(), objects.size());
  CHECK(one.params().threads == 1);  // the documented default
  const std::vector<cullkit::Camera> cams = cameras_for(scene, camera_count, 20261128);
  std::vector<Answer> truth;
  cullkit::MeshOcclusionContext context;
  std::size_t hidden = 0, kept = 0;
  for (const auto& cam : cams) {
    truth.push_back(answer(one, cam, context, boxes));
    hidden += truth.back().stats.objects_hidden;
    kept += truth.back().kept.size();
  }

  cullkit::support::Rng shuffle_rng(77);
  const Setup setups[] = {
      {"pool, 2 threads", 2, {}},
      {"pool, 3 threads", 3, {}},
      {"all hardware threads", 0, {}},
      {"a thread per task, 3 tasks", 3, {run_on_threads, nullptr}},
      {"reversed on the calling thread, 2 tasks", 2, {run_reversed, nullptr}},
      {"reversed on the calling thread, 3 tasks", 3, {run_reversed, nullptr}},
      {"shuffled on the calling thread, 3 tasks", 3, {run_shuffled, &shuffle_rng}},
  };
  // The big scenes (a culler's build is the test's main cost under the sanitizers) take the pool,
  // a thread per task and a shuffled order on the calling thread.
  const bool big = scene.indices.size() / 3 > 100000;
  for (const Setup& setup : setups) {
    const bool warm_check = &setup == &setups[0] || &setup == &setups[5];
    if (big && &setup != &setups[0] && &setup != &setups[3] && &setup != &setups[6]) continue;
    cullkit::MeshOcclusionParams params;
    params.threads = setup.threads;
    params.task_runner = setup.runner;
    const cullkit::MeshOcclusionCuller<glm::vec3> many(scene.mesh(), objects.data(), objects.size(), params);
    cullkit::MeshOcclusionContext many_context;
    std::size_t differ = 0;
    // Twice over the cameras: the second pass reuses the tasks' memory of the first (warm caches).
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t c = 0; c < cams.size(); ++c) {
        const Answer a = answer(many, cams[c], many_context, boxes);
        const bool same = a.kept == truth[c].kept && same_stats(a.stats, truth[c].stats) && a.box_hidden == truth[c].box_hidden;
        differ += same ? 0 : 1;
        CHECK_MSG(same, "%s, %s: camera %zu (pass %d): %zu kept, %zu with one thread", scene.name.c_str(), setup.name, c, pass,
                  a.kept.size(), truth[c].kept.size());
      }
    std::printf("%s, %s: %zu of %zu frames differ\n", scene.name.c_str(), setup.name, differ, 2 * cams.size());
    if (!warm_check) continue;
    // A warm context allocates nothing on several tasks (the pool's threads, started by the passes
    // above, are kept).
    std::vector<std::uint32_t> out;
    out.reserve(objects.size());
    const long long before = cullkit_test::allocations().load();
    for (const auto& cam : cams) many.cull(cam, many_context, out);
    const long long allocations = cullkit_test::allocations().load() - before;
    CHECK_MSG(allocations == 0, "%s, %s: %lld allocations in %zu warm frames", scene.name.c_str(), setup.name, allocations,
              cams.size());
  }
  std::printf("%s: %zu cameras, %zu objects hidden, %zu kept with one thread\n", scene.name.c_str(), cams.size(), hidden, kept);
  return hidden;
}

}  // namespace

int main() {
  // The generated frames hide objects: the comparisons can see a difference.
  CHECK(check_scene(cullkit::support::make_city(5, 10), 24) > 0);
  CHECK(check_scene(cullkit::support::make_office(2, 6, 5), 24) > 0);
  // Few objects in view: several threads then cull on the calling thread alone, yet insert by
  // strips, gathering every occluder at once (its corners projected first), where one thread
  // gathers on demand, projecting corners as it goes.
  CHECK(check_scene(cullkit::support::make_office(3, 1, 2), 24) > 0);
  {
    // Objects that overlap: every third building also gets an object spanning it and the next one,
    // so their triangles are in two patches each, and a triangle goes in once, with the first
    // occluder that keeps it; the tasks leave those patches to the calling thread, in order.
    Scene overlapping = cullkit::support::make_city(5, 10);
    overlapping.name = "city, overlapping objects";
    const std::size_t n = overlapping.objects.size();
    for (std::size_t i = 0; i + 1 < n; i += 3) {
      cullkit::support::SceneObject both = overlapping.objects[i];
      const cullkit::support::SceneObject& next = overlapping.objects[i + 1];
      if (next.first_triangle != both.first_triangle + both.triangle_count) continue;
      both.triangle_count += next.triangle_count;
      both.bounds = cullkit::merge(both.bounds, next.bounds);
      overlapping.objects.push_back(both);
    }
    CHECK(overlapping.objects.size() > n);
    CHECK(check_scene(overlapping, 24) > 0);
  }
  int real = 0;
  for (const std::string& file : cullkit::support::real_scene_files()) {
    const auto scene = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + file);
    if (!scene || scene->objects.size() < 2) continue;
    ++real;
    check_scene(*scene, 8);
  }
  if (real == 0) std::printf("no real scenes found: the generated ones only\n");
  return cullkit_test::report("test_mesh_occlusion_threads");
}
