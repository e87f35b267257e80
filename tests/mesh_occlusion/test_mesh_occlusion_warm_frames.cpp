// MeshOcclusionCuller::cull on a per-frame path: once a MeshOcclusionContext (and the caller's output
// vector) has seen a set of cameras, culling them again allocates nothing (global operator new is
// replaced here to count) and gives the same answers. On the generated city (solid-box occluders and
// per-patch layers), the generated office, and the real scenes when present; with each of the four
// depth conventions among the cameras, eyes anywhere in the scene (inside objects included).
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "count_allocations.hpp"

namespace {

using cullkit::support::Scene;

std::vector<cullkit::Camera> cameras_in(const Scene& scene, int count, std::uint64_t seed) {
  cullkit::Aabb box = cullkit::Aabb::empty();
  for (const auto& o : scene.objects) box = cullkit::merge(box, o.bounds);
  const glm::vec3 size = box.max - box.min;
  const float reach = std::max(glm::length(size), 1e-3f);
  cullkit::support::Rng rng(seed);
  std::vector<cullkit::Camera> cams;
  for (int c = 0; c < count; ++c) {
    // Eyes in the box's middle 80% at a standing height share, looking anywhere.
    const glm::vec3 eye(box.min.x + size.x * rng.uniform(0.1f, 0.9f), box.min.y + size.y * rng.uniform(0.05f, 0.6f),
                        box.min.z + size.z * rng.uniform(0.1f, 0.9f));
    const glm::vec3 dir(rng.uniform(-1.0f, 1.0f), rng.uniform(-0.4f, 0.2f), rng.uniform(-1.0f, 1.0f));
    const glm::vec3 target = eye + (glm::length(dir) > 1e-3f ? dir : glm::vec3(1, 0, 0));
    const int convention = c % 4;
    const auto depth = convention == 1 ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one;
    const bool reversed = convention == 2;
    const float far_plane = convention == 3 ? 0.0f : reach * 2.0f;  // 3: infinite far plane
    cams.push_back(cullkit::support::make_camera(eye, target, 60.0f, 1280, 720, reach * 1e-4f, far_plane,
                                                 reversed ? cullkit::DepthRange::zero_to_one : depth, reversed));
  }
  return cams;
}

void check_scene(const Scene& scene, int cameras) {
  std::vector<cullkit::MeshObject> objects;
  for (const auto& o : scene.objects) objects.push_back(cullkit::MeshObject{o.first_triangle, o.triangle_count});
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), objects.data(), objects.size());
  const std::vector<cullkit::Camera> cams = cameras_in(scene, cameras, 20261127);
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  std::vector<std::vector<std::uint32_t>> first(cams.size());
  // The counter sees the cold frames' allocations (buffers growing): it can fail.
  const long long before_cold = cullkit_test::allocations().load();
  for (std::size_t c = 0; c < cams.size(); ++c) {
    culler.cull(cams[c], context, out);
    first[c] = out;
  }
  CHECK_MSG(cullkit_test::allocations().load() > before_cold, "%s: the cold frames allocated nothing?", scene.name.c_str());
  std::size_t kept = 0, hidden_somewhere = 0, occluders = 0;
  bool same = true;
  const long long before = cullkit_test::allocations().load();
  for (std::size_t c = 0; c < cams.size(); ++c) {
    culler.cull(cams[c], context, out);
    same = same && out == first[c];
    kept += out.size();
    occluders += context.stats().occluder_triangles;
    hidden_somewhere += context.stats().objects_hidden > 0 ? 1 : 0;
  }
  const long long warm = cullkit_test::allocations().load() - before;
  CHECK_MSG(warm == 0, "%s: %lld allocations in %zu warm frames", scene.name.c_str(), warm, cams.size());
  CHECK_MSG(same, "%s: a warm frame answered differently from the cold one", scene.name.c_str());
  // The frames did occlusion work (occluders went in, something was hidden): not a frustum-only path.
  CHECK_MSG(occluders > 0 && hidden_somewhere > 0, "%s: %zu occluder triangles, %zu frames hiding anything",
            scene.name.c_str(), occluders, hidden_somewhere);
  std::printf("%s: %zu cameras, %zu objects kept, %zu occluder triangles, %zu frames hiding something, %lld warm allocations\n",
              scene.name.c_str(), cams.size(), kept, occluders, hidden_somewhere, warm);
}

}  // namespace

int main() {
  check_scene(cullkit::support::make_city(7, 12), 48);
  check_scene(cullkit::support::make_office(3, 6, 5), 48);
  // The real scenes, smallest first; the three smallest keep the test short.
  int real = 0;
  for (const std::string& file : cullkit::support::real_scene_files()) {
    if (real == 3) break;
    const auto scene = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + file);
    if (!scene || scene->objects.size() < 2) continue;
    ++real;
    check_scene(*scene, 24);
  }
  if (real == 0) std::printf("no real scenes found: the generated ones only\n");
  return cullkit_test::report("test_mesh_occlusion_warm_frames");
}
