// The repairing refit and the consistent argument orders.
// 300 frames of random motion: a plain refit's quality (node area over area at build) grows
// without bound; the repairing refit keeps it bounded, the tree valid, and every cull exact
// against brute force. Both from_getter spellings build the same tree; cull_with_occlusion takes
// its parameters without a stats pointer.
#include <algorithm>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "../abt/abt_oracle.hpp"

using namespace cullkit;

namespace {

bool naive_vs_tree(const AdaptiveBinaryTree<Aabb>& tree, const std::vector<Aabb>& boxes, const abt_test::View& view) {
  const Frustum f = Frustum::from_matrix(view.view_proj, view.depth);
  const abt_test::OracleFrustum oracle(view.view_proj, view.depth);
  std::vector<std::uint32_t> out;
  tree.cull(f, out);
  std::vector<std::uint8_t> mark(boxes.size(), 0);
  for (const std::uint32_t i : out) {
    if (i >= boxes.size() || mark[i]) return false;
    mark[i] = 1;
  }
  for (std::size_t i = 0; i < boxes.size(); ++i)
    if ((!is_valid(boxes[i]) || oracle.meets(boxes[i])) && !mark[i]) return false;
  return true;
}

void motion(int frames, std::size_t count) {
  support::Rng rng(31);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, count, 100.0f, 1.5f);
  std::vector<glm::vec3> vel(boxes.size());
  for (auto& v : vel) v = glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
  AdaptiveBinaryTree<Aabb> plain(boxes.data(), boxes.size());
  AdaptiveBinaryTree<Aabb> repaired(boxes.data(), boxes.size());
  double worst_repaired = 1.0;
  std::uint64_t rebuilt_objects = 0;
  for (int frame = 1; frame <= frames; ++frame) {
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      glm::vec3 c = boxes[i].center() + vel[i];
      for (int a = 0; a < 3; ++a)
        if (std::fabs(c[a]) > 100.0f) vel[i][a] = -vel[i][a];  // bounce inside the cube
      boxes[i] = Aabb{boxes[i].min + vel[i], boxes[i].max + vel[i]};
    }
    plain.refit(boxes.data());
    repaired.refit(boxes.data(), AbtRefitParams{});
    rebuilt_objects += repaired.stats().objects_rebuilt;
    worst_repaired = std::max(worst_repaired, repaired.refit_quality());
    if (frame % 50 == 0) {
      CHECK_MSG(repaired.validate() && plain.validate(), "validate at frame %d", frame);
      for (int k = 0; k < 14; ++k)
        CHECK_MSG(naive_vs_tree(repaired, boxes, abt_test::random_view(rng, Aabb{glm::vec3(-130), glm::vec3(130)}, k)),
                  "repaired tree, frame %d view %d", frame, k);
    }
  }
  // A fresh build of the final boxes, as the yardstick of what a rebuild would give.
  const AdaptiveBinaryTree<Aabb> fresh(boxes.data(), boxes.size());
  double fresh_area = 0.0, repaired_area = 0.0, plain_area = 0.0;
  for (const AbtNode& n : fresh.nodes()) fresh_area += detail::abt_area(n.bounds);
  for (const AbtNode& n : repaired.nodes()) repaired_area += detail::abt_area(n.bounds);
  for (const AbtNode& n : plain.nodes()) plain_area += detail::abt_area(n.bounds);
  std::printf("refit over %d frames, %zu objects: plain quality %.2f (area %.2fx a fresh build), repairing %.2f "
              "(worst %.2f, area %.2fx fresh), %.1f%% of objects rebuilt per frame\n",
              frames, count, plain.refit_quality(), plain_area / fresh_area, repaired.refit_quality(), worst_repaired,
              repaired_area / fresh_area, 100.0 * double(rebuilt_objects) / double(frames) / double(count));
  CHECK(plain.refit_quality() > 3.0);  // the problem is real in this setting
  CHECK(repaired.refit_quality() < 1.6 && worst_repaired < 1.8);
  CHECK(repaired_area / fresh_area < 1.6);
}

void argument_orders() {
  support::Rng rng(32);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 3000, 50.0f, 1.0f);
  const auto get = [&boxes](std::uint32_t i) { return boxes[i]; };
  const auto a = AdaptiveBinaryTree<Aabb>::from_getter(boxes.size(), get);
  const auto b = AdaptiveBinaryTree<Aabb>::from_getter(get, boxes.size());
  const AdaptiveBinaryTree<Aabb> c(boxes.data(), boxes.size());
  CHECK(a.order() == b.order() && b.order() == c.order() && a.nodes().size() == b.nodes().size());
  // cull_with_occlusion: params without a stats pointer, and both orders give the same answer.
  const Camera cam = support::make_camera(glm::vec3(0, 0, -80), glm::vec3(0), 60, 64, 64, 0.1f, 500);
  OcclusionCullParams params;
  params.grow = false;
  std::vector<std::uint32_t> out1, out2, out3;
  OcclusionTree t1(cam.eye), t2(cam.eye), t3(cam.eye);
  const auto none = [](std::uint32_t, OcclusionTree&) {};
  OcclusionCullStats s1, s2;
  cull_with_occlusion(c, frustum_of(cam), t1, none, out1, &s1, params);
  cull_with_occlusion(c, frustum_of(cam), t2, none, out2, params, &s2);
  cull_with_occlusion(c, frustum_of(cam), t3, none, out3, params);
  CHECK(out1 == out2 && out2 == out3 && !out1.empty() && s1.objects_visible == s2.objects_visible && s1.occluder_calls == 0);
}
}  // namespace

int main() {
  motion(300, 20000);
  argument_orders();
  return cullkit_test::report("test_engine_refit");
}
