// Objects whose bounds are NaN, infinite or inverted are reported by every cull of every
// container (frustum, convex volume, several views, occlusion, moving objects), at the build and
// after a refit; a valid refit brings them back under culling; transform_bounds of bad input is
// such a box. Oracle: the brute-force frustum of abt_oracle.hpp, and "always present" for the bad.
#include <algorithm>
#include <limits>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "../abt/abt_oracle.hpp"

using namespace cullkit;

namespace {
const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

// A mock occluder that hides every box with min.x > 50 (and only boxes: never an unbounded one is
// asked, which the counter checks).
struct HalfSpaceOccluder {
  glm::vec3 eye_{0, 0, 0};
  mutable int unbounded_queries = 0;
  [[nodiscard]] const glm::vec3& eye() const { return eye_; }
  [[nodiscard]] bool is_occluded(const Aabb& b) const {
    if (is_unbounded(b)) ++unbounded_queries;
    return b.min.x > 50.0f;
  }
};

bool has(const std::vector<std::uint32_t>& v, std::uint32_t i) { return std::find(v.begin(), v.end(), i) != v.end(); }

void always_reported() {
  support::Rng rng(4242);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 4000, 100.0f, 2.0f);
  const std::vector<std::uint32_t> bad_ids = {0, 17, 999, 2500, 3999};
  boxes[0] = Aabb{glm::vec3(-kInf), glm::vec3(kInf)};  // a skybox
  boxes[17].min.x = kNaN;
  boxes[999] = Aabb{glm::vec3(1), glm::vec3(0)};       // inverted
  boxes[2500].max.z = kInf;
  boxes[3999] = transform_bounds(Aabb{glm::vec3(0), glm::vec3(1)}, glm::mat4(kNaN));
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  CHECK(tree.validate() && tree.size() == boxes.size() && tree.stats().unbounded == bad_ids.size());
  std::vector<std::uint32_t> out, bits;
  int views_without_any_good = 0;
  for (int k = 0; k < 140; ++k) {
    const abt_test::View v = abt_test::random_view(rng, Aabb{glm::vec3(-150), glm::vec3(150)}, k);
    const Frustum f = Frustum::from_matrix(v.view_proj, v.depth);
    const abt_test::OracleFrustum oracle(v.view_proj, v.depth);
    tree.cull(f, out);
    std::size_t missed = 0;
    for (std::uint32_t i = 0; i < boxes.size(); ++i)
      if ((!is_valid(boxes[i]) || oracle.meets(boxes[i])) && !has(out, i)) ++missed;
    CHECK_MSG(missed == 0, "frustum view %d: %zu missed", k, missed);
    views_without_any_good += out.size() == bad_ids.size();
    tree.cull(ConvexVolume(f), out);
    for (std::uint32_t b : bad_ids) CHECK_MSG(has(out, b), "volume view %d misses %u", k, b);
    const Frustum pair[2] = {f, Frustum::from_matrix(glm::mat4(1.0f))};
    tree.cull_views(pair, 2, out, bits);
    for (std::size_t j = 0; j < out.size(); ++j)
      if (std::find(bad_ids.begin(), bad_ids.end(), out[j]) != bad_ids.end()) CHECK(bits[j] == 3u);
    for (std::uint32_t b : bad_ids) CHECK_MSG(has(out, b), "views %d misses %u", k, b);
    HalfSpaceOccluder occ;
    tree.cull(f, occ, out);
    for (std::uint32_t b : bad_ids) CHECK_MSG(has(out, b), "occlusion view %d misses %u", k, b);
    CHECK(occ.unbounded_queries == 0);
  }
  // Non-vacuity: some views see nothing but the bad objects (they are not kept by accident).
  CHECK(views_without_any_good > 0);
  std::printf("bad bounds: %d of 140 views saw only the 5 unbounded objects\n", views_without_any_good);

  // cull_with_occlusion and cull_moving, with a real OcclusionTree and a big box occluder.
  OcclusionTree occ(glm::vec3(0, 0, -300));
  occ.insert_box_occluder(Aabb{glm::vec3(-1000, -1000, -250), glm::vec3(1000, 1000, -240)});
  const Frustum f = frustum_of(support::make_camera(glm::vec3(0, 0, -300), glm::vec3(0, 0, 0), 60, 64, 64, 0.1f, 1000));
  OcclusionCullStats stats;
  cull_with_occlusion(tree, f, occ, [](std::uint32_t, OcclusionTree&) {}, out, OcclusionCullParams{}, &stats);
  for (std::uint32_t b : bad_ids) CHECK_MSG(has(out, b), "cull_with_occlusion misses %u", b);
  CHECK(out.size() == bad_ids.size() && stats.unbounded == bad_ids.size());  // all good ones are hidden
  out.clear();
  OcclusionCullStats ms;
  cull_moving(f, occ, boxes.data(), boxes.size(), out, &ms);
  for (std::uint32_t b : bad_ids) CHECK_MSG(has(out, b), "cull_moving misses %u", b);
  CHECK(ms.unbounded == bad_ids.size());
}

void after_refit() {
  support::Rng rng(77);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 3000, 100.0f, 2.0f);
  std::vector<Aabb> moved = boxes;
  moved[5].min.y = kNaN;  // a NaN transform at load
  AdaptiveBinaryTree<Aabb> tree(moved.data(), moved.size());
  const Frustum away = frustum_of(support::make_camera(glm::vec3(0, 0, 500), glm::vec3(0, 0, 1000), 40, 64, 64, 1, 100));
  std::vector<std::uint32_t> out;
  tree.cull(away, out);
  CHECK(out.size() == 1 && out[0] == 5u);
  // Valid at the next refit: culled by its bounds (not reported by the view that sees nothing).
  moved[5] = boxes[5];
  tree.refit(moved.data());
  CHECK(tree.stats().unbounded == 0 && tree.validate());
  tree.cull(away, out);
  CHECK(out.empty());
  // It moves into a view: reported (the refitted box, not a stale one).
  const Frustum at = frustum_of(support::make_camera(glm::vec3(0, 0, 500), glm::vec3(0, 0, 800), 40, 64, 64, 1, 1000));
  moved[5] = Aabb{glm::vec3(-1, -1, 700), glm::vec3(1, 1, 702)};
  tree.refit(moved.data());
  tree.cull(at, out);
  CHECK(out.size() == 1 && out[0] == 5u);
  // A valid object turning NaN at a refit: reported by every view, also with the repairing refit.
  moved[9].max.x = -kInf;
  tree.refit(moved.data(), AbtRefitParams{});
  CHECK(tree.stats().unbounded == 1 && tree.stats().refit_invalid == 1 && tree.validate());
  tree.cull(away, out);
  CHECK(out.size() == 1 && out[0] == 9u);
}

void degenerate_camera() {
  // A NaN matrix: the frustum drops every plane and every cull keeps everything.
  support::Rng rng(8);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 500, 50.0f, 1.0f);
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  const Frustum f = Frustum::from_matrix(glm::mat4(kNaN));
  CHECK(f.active_mask() == 0);
  std::vector<std::uint32_t> out;
  tree.cull(f, out);
  CHECK(out.size() == boxes.size());
  const Frustum zero = Frustum::from_matrix(glm::mat4(0.0f));
  tree.cull(zero, out);
  CHECK(out.size() == boxes.size());
  // transform_bounds: bad input gives a box that is not valid.
  CHECK(!is_valid(transform_bounds(Aabb{glm::vec3(0), glm::vec3(kInf)}, glm::mat4(1.0f))));
  CHECK(!is_valid(transform_bounds(Aabb{glm::vec3(1), glm::vec3(0)}, glm::mat4(1.0f))));
  glm::mat4 m(1.0f);
  m[3][0] = kNaN;
  CHECK(!is_valid(transform_bounds(Aabb{glm::vec3(0), glm::vec3(1)}, m)));
  m = glm::mat4(1.0f);
  m[0][0] = 3e38f;
  CHECK(!is_valid(transform_bounds(Aabb{glm::vec3(0), glm::vec3(10)}, m)));  // overflows float
}
}  // namespace

int main() {
  always_reported();
  after_refit();
  degenerate_camera();
  return cullkit_test::report("test_engine_bad_bounds");
}
