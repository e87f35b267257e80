// The separate-core check: the same program built twice, once with every core inline (the default)
// and once with CULLKIT_SEPARATE_CORE, its cores compiled in cullkit::core and used from two
// translation units. Each build prints one hash per container; the test compares the two outputs,
// so the modes must give the same answers (and the separate build must link: one definition each).
#include <algorithm>
#include <cstdio>
#include <vector>

#include <cullkit/cullkit.hpp>

#include "scene.hpp"

int main() {
  using namespace separate_core;
  const Scene scene = make_scene();
  const std::vector<cullkit::Camera> cams = make_cameras();
  const cullkit::MeshView<glm::vec3> mesh{scene.positions.data(), scene.positions.size(), scene.indices.data(),
                                          scene.indices.size()};

  cullkit::NciParams params;
  params.threads = 2;  // through the worker pool (run_tasks)
  params.build_threads = 2;
  const cullkit::NormalClassIndex<glm::vec3> index(mesh, params);
  cullkit::NciContext context;
  cullkit::VisibleSet seen;
  std::uint64_t nci = 0xCBF29CE484222325ull;
  for (const cullkit::Camera& cam : cams) {
    index.select_visible(cam, context, seen, nullptr);
    nci = fnv(nci, seen.triangles);
  }

  std::vector<cullkit::Aabb> boxes;
  for (std::size_t b = 0; b + 8 <= scene.positions.size(); b += 8)
    boxes.push_back(cullkit::Aabb{scene.positions[b], scene.positions[b + 7]});
  cullkit::AbtParams abt_params;
  abt_params.threads = 2;
  const cullkit::AdaptiveBinaryTree<cullkit::Aabb> tree(boxes.data(), boxes.size(), abt_params);
  std::vector<std::uint32_t> out, bits;
  std::uint64_t abt = 0xCBF29CE484222325ull;
  std::vector<cullkit::Frustum> frusta;
  for (const cullkit::Camera& cam : cams) {
    frusta.push_back(cullkit::Frustum::from_matrix(cam.view_proj));
    tree.cull(frusta.back(), out);
    abt = fnv(abt, out);
  }
  tree.cull_views(frusta.data(), frusta.size(), out, bits);
  abt = fnv(fnv(abt, out), bits);

  // The BSP over the first 30 boxes (360 triangles).
  const cullkit::MeshView<glm::vec3> few{scene.positions.data(), scene.positions.size(), scene.indices.data(),
                                         30 * 36};
  cullkit::BspParams bsp_params;
  bsp_params.threads = 2;
  const cullkit::BspTree<glm::vec3> bsp(few, bsp_params);
  std::uint64_t order = 0xCBF29CE484222325ull;
  for (const cullkit::Camera& cam : cams) {
    bsp.back_to_front(cam.eye, out);
    order = fnv(order, out);
  }

  // Mesh occlusion: each box one object of 12 triangles (the floor is object 0).
  std::vector<cullkit::MeshObject> objects;
  for (std::uint32_t b = 0; b < scene.indices.size() / 36; ++b) objects.push_back(cullkit::MeshObject{12 * b, 12});
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(mesh, objects.data(), objects.size());
  cullkit::MeshOcclusionContext occlusion_context;
  std::uint64_t occlusion = 0xCBF29CE484222325ull;
  std::size_t hidden = 0;
  for (const cullkit::Camera& cam : cams) {
    culler.cull(cam, occlusion_context, out);
    std::sort(out.begin(), out.end());
    occlusion = fnv(occlusion, out);
    hidden += occlusion_context.stats().objects_hidden;
  }

  std::printf("nci %016llx (%zu triangles selected last)\n", static_cast<unsigned long long>(nci), seen.triangles.size());
  std::printf("abt %016llx\n", static_cast<unsigned long long>(abt));
  std::printf("bsp %016llx\n", static_cast<unsigned long long>(order));
  std::printf("mesh occlusion %016llx (%zu objects hidden)\n", static_cast<unsigned long long>(occlusion), hidden);
  std::printf("second unit %016llx\n", static_cast<unsigned long long>(second_unit_hash(scene)));
  // Non-vacuity: the scene is seen, and not whole; occlusion hides something.
  return seen.triangles.empty() || seen.triangles.size() >= scene.indices.size() / 3 || hidden == 0 ? 1 : 0;
}
