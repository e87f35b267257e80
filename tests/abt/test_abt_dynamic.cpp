// AdaptiveBinaryTree insert / remove / update against a brute-force model over seeded random
// operation sequences. After every batch of operations: validate(), and every cull (frustum,
// ConvexVolume, cull_views, occlusion culls with an empty occlusion tree, node traversal) is compared
// with the model: no live object that meets the view is missing, no removed id is ever reported,
// every id at most once, objects with bad bounds always reported. Bad input: unknown ids, double
// removes, NaN bounds on insert and update. Non-vacuity: the views do cut, and removed objects
// whose last box met the view existed (so "never reports removed ids" was tested).
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <check.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "abt_oracle.hpp"

using namespace cullkit;

namespace {

constexpr float nan_f = std::numeric_limits<float>::quiet_NaN();

struct Model {
  std::vector<Aabb> box;     // by id
  std::vector<bool> live;    // by id
  std::vector<bool> ever;    // by id: was held once (so its last box is known)
};

Aabb random_box(support::Rng& rng, float world, float size) {
  const glm::vec3 c(rng.uniform(-world, world), rng.uniform(-world, world), rng.uniform(-world, world));
  const glm::vec3 h(rng.uniform(0.1f, size), rng.uniform(0.1f, size), rng.uniform(0.1f, size));
  return Aabb{c - h, c + h};
}

struct Totals {
  std::size_t kept = 0, meets = 0, removed_in_view = 0, unbounded_seen = 0;
};

// Every cull of `tree` against the model for one random view.
void check_culls(const AdaptiveBinaryTree<Aabb>& tree, const Model& m, support::Rng& rng, int k, Totals& t) {
  CHECK_MSG(tree.validate(), "validate after batch %d", k);
  std::size_t live = 0;
  for (bool l : m.live) live += l;
  CHECK_MSG(tree.size() == live, "size %zu, model %zu", tree.size(), live);
  const abt_test::View view = abt_test::random_view(rng, Aabb{glm::vec3(-130), glm::vec3(130)}, k);
  const Frustum f = Frustum::from_matrix(view.view_proj, view.depth);
  const abt_test::OracleFrustum oracle(view.view_proj, view.depth);
  const auto judge = [&](const std::vector<std::uint32_t>& out, const char* what, bool exact_all) {
    std::vector<std::uint8_t> seen(m.box.size(), 0);
    std::size_t bad = 0, missing = 0;
    for (std::uint32_t id : out) {
      bad += id >= m.box.size() || !m.live[id] || seen[id];
      if (id < m.box.size()) seen[id] = 1;
    }
    for (std::uint32_t id = 0; id < m.box.size(); ++id) {
      if (!m.live[id]) continue;
      const bool must = exact_all || !is_valid(m.box[id]) || oracle.meets(m.box[id]);
      missing += must && !seen[id];
    }
    CHECK_MSG(bad == 0 && missing == 0, "batch %d %s: %zu bad entries, %zu missing", k, what, bad, missing);
  };
  std::vector<std::uint32_t> out, bits, single;
  tree.cull(f, out);
  judge(out, "cull", false);
  t.kept += out.size();
  for (std::uint32_t id = 0; id < m.box.size(); ++id) {
    if (m.live[id]) {
      t.meets += is_valid(m.box[id]) && oracle.meets(m.box[id]);
      t.unbounded_seen += !is_valid(m.box[id]);
    } else if (m.ever[id] && is_valid(m.box[id])) {
      t.removed_in_view += oracle.meets(m.box[id]);
    }
  }
  tree.cull(ConvexVolume(f), out);
  judge(out, "cull(ConvexVolume)", false);
  tree.cull(ConvexVolume{}, out);
  judge(out, "cull(no planes)", true);
  CHECK(out.size() == live);
  // Visitor form with early stop after 10 ranges must not crash and must report live ids only.
  int ranges = 0;
  tree.cull(f, [&](std::uint32_t b, std::uint32_t e, Containment) {
    for (std::uint32_t p = b; p < e; ++p) CHECK(tree.order()[p] < m.box.size() && m.live[tree.order()[p]]);
    return ++ranges < 10;
  });
  // Two eyes (a family of equal normals) and the view itself: bits equal to single culls.
  const glm::vec3 shift(0.032f, 0.0f, 0.0f);
  const Frustum frusta[3] = {f, Frustum::from_matrix(view.view_proj * glm::translate(glm::mat4(1.0f), shift), view.depth),
                             Frustum::from_matrix(view.view_proj * glm::translate(glm::mat4(1.0f), -shift), view.depth)};
  tree.cull_views(frusta, 3, out, bits);
  judge(out, "cull_views", false);
  for (int v = 0; v < 3; ++v) {
    tree.cull(frusta[v], single);
    std::vector<std::uint8_t> in_single(m.box.size(), 0);
    for (std::uint32_t id : single) in_single[id] = 1;
    std::size_t differ = 0, with_bit = 0;
    for (std::size_t j = 0; j < out.size(); ++j) {
      const bool bit = (bits[j] >> v) & 1u;
      with_bit += bit;
      differ += bit != bool(in_single[out[j]]);
    }
    CHECK_MSG(differ == 0 && with_bit == single.size(), "batch %d view %d: bits differ from a single cull", k, v);
  }
  // Occlusion cull with nothing occluding: the frustum cull's set, front to back.
  const OcclusionTree nothing(view.eye);
  tree.cull(f, nothing, out);
  judge(out, "cull(occlusion)", false);
  // cull_with_occlusion walks nodes() and order() itself: holes skipped, pending objects tested.
  OcclusionTree growing(view.eye);
  cull_with_occlusion(tree, f, growing, [](std::uint32_t, OcclusionTree&) {}, out);
  judge(out, "cull_with_occlusion", false);
  // Traversal: leaves (and the pending leaf) cover every live id once.
  std::vector<std::uint32_t> covered;
  tree.traverse_front_to_back(view.eye, [&](std::uint32_t, const AbtNode& node) {
    if (node.is_leaf())
      for (std::uint32_t p = node.begin; p < node.end; ++p)
        if (tree.order()[p] != detail::abt_removed_slot) covered.push_back(tree.order()[p]);
  });
  judge(covered, "traverse", true);
}

void random_sequences() {
  Totals t;
  std::size_t rejected = 0, maintained = 0;
  for (int seq = 0; seq < 6; ++seq) {
    support::Rng rng(500 + std::uint64_t(seq));
    const std::size_t n0 = seq == 0 ? 0 : std::size_t(rng.range(1, 2500));
    Model m;
    for (std::size_t i = 0; i < n0; ++i) m.box.push_back(random_box(rng, 100, 4));
    if (n0 > 3) m.box[3] = Aabb{glm::vec3(nan_f), glm::vec3(1)};
    m.live.assign(n0, true);
    m.ever.assign(n0, true);
    AbtParams params;
    params.max_leaf_size = std::uint32_t(rng.range(1, 16));
    params.scan_below = seq % 2 ? 0u : 64u;
    AdaptiveBinaryTree<Aabb> tree(m.box.data(), m.box.size(), params);
    for (int batch = 0; batch < 14; ++batch) {
      const int ops = rng.range(1, 400);
      for (int o = 0; o < ops; ++o) {
        const int kind = rng.range(0, 9);
        const std::uint32_t any_id = std::uint32_t(rng.range(0, int(m.box.size()) + 5));
        if (kind <= 2) {  // insert, sometimes with bad bounds
          Aabb b = random_box(rng, 100, 4);
          if (rng.range(0, 30) == 0) b.max.y = nan_f;
          if (rng.range(0, 60) == 0) b = Aabb{glm::vec3(1), glm::vec3(0)};  // inverted
          const std::uint32_t id = tree.insert(b);
          CHECK(id != AdaptiveBinaryTree<Aabb>::invalid_id);
          if (id >= m.box.size()) {
            CHECK(id == m.box.size());
            m.box.resize(id + 1);
            m.live.resize(id + 1, false);
            m.ever.resize(id + 1, false);
          }
          CHECK(!m.live[id]);
          m.box[id] = b;
          m.live[id] = m.ever[id] = true;
        } else if (kind <= 5) {  // remove: live, unknown or already removed ids
          const bool expect = any_id < m.box.size() && m.live[any_id];
          const bool got = tree.remove(any_id);
          CHECK(got == expect);
          rejected += !got;
          if (got) m.live[any_id] = false;
        } else {  // update (move), sometimes to NaN and back
          Aabb b = any_id < m.box.size() && is_valid(m.box[any_id]) ? m.box[any_id] : random_box(rng, 100, 4);
          const glm::vec3 d(rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(-8, 8));
          b = Aabb{b.min + d, b.max + d};
          if (rng.range(0, 40) == 0) b.min.x = nan_f;
          const bool expect = any_id < m.box.size() && m.live[any_id];
          const bool got = tree.update(any_id, b);
          CHECK(got == expect);
          rejected += !got;
          if (got) m.box[any_id] = b;
        }
      }
      maintained += tree.stats().subtrees_rebuilt;
      check_culls(tree, m, rng, seq * 100 + batch, t);
    }
    // All removed: culls answer nothing; the ids come back.
    for (std::uint32_t id = 0; id < m.box.size(); ++id)
      if (m.live[id]) CHECK(tree.remove(id));
    std::vector<std::uint32_t> out;
    tree.cull(ConvexVolume{}, out);
    CHECK(out.empty() && tree.empty() && tree.validate());
    CHECK(!tree.remove(0) && !tree.update(0, Aabb{glm::vec3(0), glm::vec3(1)}));
    const std::uint32_t again = tree.insert(Aabb{glm::vec3(0), glm::vec3(1)});
    CHECK(again < m.box.size());
    tree.cull(ConvexVolume{}, out);
    CHECK(out.size() == 1 && out[0] == again);
  }
  // Non-vacuity: views cut, removed objects were in view, bad ids were offered.
  CHECK(t.meets > 0 && t.kept < 40 * t.meets + 1);
  CHECK(t.removed_in_view > 0 && t.unbounded_seen > 0 && rejected > 0);
  std::printf("dynamic: %zu kept, %zu meet, %zu removed ids in view never reported, %zu unbounded, %zu bad ids, "
              "%zu rebuilds seen\n", t.kept, t.meets, t.removed_in_view, t.unbounded_seen, rejected, maintained);
}

// Quality after 10,000 random insert / remove / move operations against a fresh build.
void churn_quality() {
  support::Rng rng(42);
  std::vector<Aabb> boxes;
  for (int i = 0; i < 4000; ++i) boxes.push_back(random_box(rng, 100, 2));
  AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  std::vector<std::uint32_t> ids;
  for (std::uint32_t i = 0; i < boxes.size(); ++i) ids.push_back(i);
  for (int o = 0; o < 10000; ++o) {
    const int kind = rng.range(0, 2);
    const std::size_t j = std::size_t(rng.range(0, int(ids.size()) - 1));
    if (kind == 0) {
      ids.push_back(tree.insert(random_box(rng, 100, 2)));
    } else if (kind == 1 && ids.size() > 100) {
      CHECK(tree.remove(ids[j]));
      ids[j] = ids.back();
      ids.pop_back();
    } else {
      CHECK(tree.update(ids[j], random_box(rng, 100, 2)));
    }
  }
  CHECK(tree.validate() && tree.size() == ids.size());
  double area = 0, fresh_area = 0;
  for (const AbtNode& n : tree.nodes()) area += detail::abt_measured_area(n.bounds);
  std::vector<Aabb> now;
  for (std::size_t p = 0; p < tree.order().size(); ++p)
    if (tree.order()[p] != detail::abt_removed_slot) now.push_back(tree.object_bounds()[p]);
  const AdaptiveBinaryTree<Aabb> fresh(now.data(), now.size());
  for (const AbtNode& n : fresh.nodes()) fresh_area += detail::abt_measured_area(n.bounds);
  std::printf("churn: %zu objects, node area after 10,000 operations / fresh build %.3f\n", now.size(), area / fresh_area);
  CHECK(area / fresh_area < 1.5);
}

}  // namespace

int main() {
  random_sequences();
  churn_quality();
  return cullkit_test::report("test_abt_dynamic");
}
