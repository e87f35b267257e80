// Oriented box occluders (OcclusionTree::insert_box_occluder(local_box, model)) against a
// double-precision brute force (segment against the box in its local frame). The rotated building:
// its world bounding box as an occluder hides a car standing in the empty corner of that bounding
// box (the mistake this overload exists for), the oriented box does not, and still hides what is
// behind the building. Then random rotated, scaled and sheared boxes: every hidden answer checked,
// and the identity matrix compared with the axis-aligned overload on the same queries.
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/ext/matrix_transform.hpp>

#include <cullkit/occlusion_tree.hpp>

#include "brute.hpp"
#include "check.hpp"

using namespace cullkit;
using cullkit::support::Rng;
using occlusion_test::Occluders;
using occlusion_test::OrientedBox;

// Random vectors are built with braces: their components are then drawn left to right on every
// compiler (argument order in parentheses is unspecified), so gcc and clang test the same scenes.
namespace {

Aabb around(const glm::vec3& c, const glm::vec3& h) { return Aabb{c - h, c + h}; }

void rotated_building() {
  const Aabb local{{-10, 0, -10}, {10, 20, 10}};
  const glm::mat4 model = glm::rotate(glm::mat4(1.0f), 0.78539816f, glm::vec3(0, 1, 0));
  // Its world bounding box: |x|, |z| <= 14.14; the building itself: |x| + |z| <= 14.14.
  const Aabb world_bounds{{-14.1422f, 0, -14.1422f}, {14.1422f, 20, 14.1422f}};
  const Aabb car{{8, 0, 8}, {10, 1.5f, 10}};  // in the bounding box's empty corner
  const glm::vec3 eye(30, 1.7f, -5);
  Occluders occ;
  occ.oriented.emplace_back(local, model);
  glm::dvec3 witness;
  Rng rng(7);
  CHECK(occlusion_test::find_visible_sample(occ, eye, car, rng, 6, 32, &witness));  // the car is seen

  OcclusionTree wrong(eye);
  wrong.insert_box_occluder(world_bounds);
  CHECK_MSG(wrong.is_occluded(car), "the world bounding box was expected to hide the car (the user's mistake)");

  OcclusionTree tree(eye);
  tree.insert_box_occluder(local, model);
  CHECK(tree.stats().occluders_inserted == 1);
  CHECK_MSG(!tree.is_occluded(car), "the oriented building hides the car in its empty corner");
  // Behind the building, on the line from the eye through its centre.
  const glm::vec3 centre(0, 8, 0);
  const Aabb behind = around(eye + (centre - eye) * 1.8f, glm::vec3(1.0f));
  CHECK(!occlusion_test::find_visible_sample(occ, eye, behind, rng, 6, 32, nullptr));
  CHECK_MSG(tree.is_occluded(behind), "a box behind the building's centre is not hidden");
  // The eye inside the building: skipped.
  OcclusionTree inside(glm::vec3(0, 5, 0));
  inside.insert_box_occluder(local, model);
  CHECK(inside.stats().occluders_skipped == 1 && inside.empty());
  // Invalid input: skipped, never a crash.
  OcclusionTree bad(eye);
  glm::mat4 nan_model = model;
  nan_model[1][2] = std::nanf("");
  bad.insert_box_occluder(local, nan_model);
  glm::mat4 projective = model;
  projective[2][3] = 0.5f;
  bad.insert_box_occluder(local, projective);
  bad.insert_box_occluder(Aabb{{1, 1, 1}, {0, 0, 0}}, model);
  CHECK(bad.stats().occluders_skipped == 3 && bad.empty());
}

glm::mat4 random_model(Rng& rng, const glm::vec3& at) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), at);
  const glm::vec3 axis = glm::normalize(glm::vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)} +
                                        glm::vec3(0.0f, 0.01f, 0.0f));
  m = glm::rotate(m, rng.uniform(0.0f, 6.2831853f), axis);
  if (rng.uniform() < 0.3f) {  // shear
    glm::mat4 shear(1.0f);
    shear[1][0] = rng.uniform(-0.5f, 0.5f);
    shear[2][1] = rng.uniform(-0.5f, 0.5f);
    m = m * shear;
  }
  return glm::scale(m, glm::vec3{rng.uniform(0.5f, 2.0f), rng.uniform(0.5f, 2.0f), rng.uniform(0.5f, 2.0f)});
}

void random_boxes() {
  long queries = 0, hidden = 0, false_culls = 0;
  long aligned_hidden = 0, identity_hidden = 0, disagree = 0, aligned_nodes = 0, identity_nodes = 0;
  for (unsigned seed = 1; seed <= 80; ++seed) {
    Rng rng(seed * 40503u);
    const glm::vec3 eye{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    OcclusionTree tree(eye), aligned(eye), identity(eye);
    Occluders occ;
    const int count = rng.range(1, 25);
    for (int k = 0; k < count; ++k) {
      const glm::vec3 dir = glm::normalize(glm::vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
      const glm::vec3 at = eye + dir * rng.uniform(2.0f, 8.0f);
      const glm::vec3 centre(rng.uniform(-0.5f, 0.5f));
      const Aabb local = around(centre, glm::vec3{rng.uniform(0.2f, 2.0f), rng.uniform(0.2f, 2.0f), rng.uniform(0.2f, 2.0f)});
      const glm::mat4 model = random_model(rng, at);
      occ.oriented.emplace_back(local, model);
      tree.insert_box_occluder(local, model);
      const Aabb placed{local.min + at, local.max + at};
      aligned.insert_box_occluder(placed);
      identity.insert_box_occluder(placed, glm::mat4(1.0f));
    }
    aligned_nodes += aligned.stats().nodes;
    identity_nodes += identity.stats().nodes;
    for (int k = 0; k < 150; ++k) {
      const glm::vec3 dir = glm::normalize(glm::vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
      const glm::vec3 c = eye + dir * rng.uniform(2.0f, 20.0f);
      const float s = rng.uniform() < 0.3f ? 0.02f : rng.uniform(0.05f, 1.5f);
      const Aabb q = around(c, glm::vec3{s * rng.uniform(0.3f, 1.0f), s, s * rng.uniform(0.3f, 1.0f)});
      ++queries;
      const bool a = aligned.is_occluded(q), i = identity.is_occluded(q);
      aligned_hidden += a ? 1 : 0;
      identity_hidden += i ? 1 : 0;
      disagree += a != i ? 1 : 0;
      if (!tree.is_occluded(q)) continue;
      ++hidden;
      glm::dvec3 w;
      const bool visible = occlusion_test::find_visible_sample(occ, eye, q, rng, 6, 24, &w);
      false_culls += visible ? 1 : 0;
      CHECK_MSG(!visible, "seed %u query %d: hidden but (%.9g %.9g %.9g) is visible", seed, k, w.x, w.y, w.z);
    }
  }
  std::printf("oriented boxes: %ld queries, %ld hidden, %ld false culls\n", queries, hidden, false_culls);
  std::printf("identity matrix vs axis-aligned overload: %ld vs %ld hidden (%ld disagree), %ld vs %ld nodes\n",
              identity_hidden, aligned_hidden, disagree, identity_nodes, aligned_nodes);
  CHECK(hidden >= queries / 20);  // the test must exercise hidden answers
  // Faces fused along their shared edges hide what the outline chain hides, up to margin effects
  // (measured: 4,158 vs 4,167 hidden, 49 answers differ, either way).
  CHECK(disagree * 50 <= aligned_hidden);
  CHECK(identity_hidden * 100 >= aligned_hidden * 98);
}

}  // namespace

int main() {
  rotated_building();
  random_boxes();
  return cullkit_test::report("test_occlusion_oriented_box");
}
