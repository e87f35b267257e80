// Scene culling (ABT front to back + occlusion tree grown from visible major occluders) against
// Embree: an object left out must have no pixel whose first hit is one of its triangles. Generated
// city and office, an adversarial scene (touching boxes, 1e-4 gaps, thin walls), and the two
// smallest real scenes when present; every refinement switch; eyes inside and on occluders.
#include <cstdio>
#include <string>

#include "check.hpp"
#include "scene_cull.hpp"

using namespace cullkit;
using namespace occlusion_test;

namespace {

support::Scene adversarial_scene() {
  support::Scene s;
  s.name = "adversarial";
  support::Rng rng(99);
  // Rows of touching wall boxes, and rows with 1e-4-of-scene gaps (the scene is ~100 units).
  for (int row = 0; row < 6; ++row) {
    const float z = -10.0f - 12.0f * row;
    const float gap = row % 2 ? 0.01f : 0.0f;
    float x = -50.0f;
    for (int k = 0; k < 10; ++k) {
      const float w = rng.uniform(4.0f, 12.0f);
      s.add_box(Aabb{{x, 0.0f, z - 0.5f}, {x + w, rng.uniform(3.0f, 9.0f), z}}, "wall", true);
      x += w + gap;
    }
  }
  // Small props everywhere, some right behind gaps.
  for (int k = 0; k < 400; ++k) {
    const glm::vec3 c(rng.uniform(-50, 50), rng.uniform(0.0f, 2.0f), rng.uniform(-80.0f, 0.0f));
    s.add_box(Aabb{c - glm::vec3(0.2f), c + glm::vec3(0.2f)}, "prop", false);
  }
  // A flat ground slab (a box, major occluder; eyes above it).
  s.add_box(Aabb{{-60, -1, -90}, {60, 0, 10}}, "ground", true);
  return s;
}

void run(CullScene& cs, const char* name, int cameras) {
  const auto cams = make_cameras(cs, 1234u, cameras, 96, 72);
  long false_culls = 0, hidden_total = 0, frustum_total = 0;
  for (int variant = 0; variant < 4; ++variant) {
    OcclusionParams params;
    OcclusionCullParams cp;
    if (variant == 1) {
      params.azimuth_planes = 4;
      params.elevation_planes = 2;
    }
    if (variant == 2) cp.skip_clear_subtrees = true;
    if (variant == 3) cp.start_at_parent_node = false;
    std::vector<std::uint32_t> out, frustum_only;
    OcclusionTree tree(glm::vec3(0.0f), params);
    for (std::size_t c = 0; c < cams.size(); ++c) {
      const Camera& cam = cams[c];
      const Frustum frustum = Frustum::from_matrix(cam.view_proj, cam.depth);
      tree.reset(cam.eye);
      cull_with_occlusion(cs.abt, frustum, tree, [&](std::uint32_t o, OcclusionTree& t) { cs.insert_occluders(o, t); },
                          out, nullptr, cp);
      cs.abt.cull(frustum, frustum_only);
      const auto vis = cs.embree_visible(cam);
      // Pixel rays are not clipped by near/far: judge only objects the frustum pass keeps.
      std::vector<std::uint8_t> kept(cs.scene.objects.size(), 0), in_frustum(cs.scene.objects.size(), 0);
      for (auto o : out) kept[o] = 1;
      for (auto o : frustum_only) in_frustum[o] = 1;
      for (std::size_t o = 0; o < vis.size(); ++o) {
        if (vis[o] && in_frustum[o]) {
          false_culls += kept[o] ? 0 : 1;
          CHECK_MSG(kept[o], "%s variant %d camera %zu (eye %.6g %.6g %.6g): object %zu (%s) is visible but culled", name,
                    variant, c, cam.eye.x, cam.eye.y, cam.eye.z, o, cs.scene.objects[o].name.c_str());
        }
      }
      hidden_total += static_cast<long>(frustum_only.size()) - static_cast<long>(out.size());
      frustum_total += static_cast<long>(frustum_only.size());
    }
  }
  std::printf("%-12s %zu cameras x 4 variants: %ld in frustum, %ld occlusion-culled, %ld false culls\n", name,
              cams.size(), frustum_total, hidden_total, false_culls);
  if (cs.scene.objects.size() >= 50) {
    CHECK_MSG(hidden_total > frustum_total / 50, "%s: occlusion culled almost nothing", name);
  }
}

}  // namespace

int main() {
  {
    CullScene cs(support::make_city(7, 5));
    run(cs, "city", 300);
  }
  {
    CullScene cs(support::make_office(8, 4, 3));
    run(cs, "office", 300);
  }
  {
    CullScene cs(adversarial_scene());
    run(cs, "adversarial", 300);
  }
  const auto files = support::real_scene_files();
  for (std::size_t i = 0; i < files.size() && i < 2; ++i) {
    auto s = support::load_obj(support::scenes_dir() + "/" + files[i]);
    if (!s) continue;
    CullScene cs(std::move(*s));
    run(cs, files[i].c_str(), 100);
  }
  return cullkit_test::report("test_occlusion_embree");
}
