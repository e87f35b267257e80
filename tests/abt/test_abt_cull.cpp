// AdaptiveBinaryTree culling against a brute-force oracle (naive_vs_tree): random boxes, a
// generated city, real scenes when present (objects and triangles), every projection kind;
// plus the occlusion overload against a mock occluder and the visitor form.
// Asserts: no false negatives, no duplicates, nothing skipped or out of range returned;
// false positives (rounding slack only) are counted and bounded.
#include <cstdio>
#include <string>
#include <vector>

#include <cullkit/adaptive_binary_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "abt_oracle.hpp"
#include "check.hpp"

using namespace cullkit;
using abt_test::OracleFrustum;
using abt_test::View;

namespace {

struct Totals {
  std::size_t views = 0, returned = 0, truly = 0, false_pos = 0;
};

using Tree = AdaptiveBinaryTree<Aabb>;

// One view: tree.cull vs the oracle over `boxes` (input order; invalid ones must never appear).
void check_view(const Tree& tree, const std::vector<Aabb>& boxes, const View& view, const char* label,
                std::uint64_t seed, int k, Totals& totals, std::vector<std::uint32_t>& out,
                std::vector<std::uint8_t>& mark) {
  const Frustum frustum = Frustum::from_matrix(view.view_proj, view.depth);
  const OracleFrustum oracle(view.view_proj, view.depth);
  out.assign(3, 12345u);  // cull must clear it
  tree.cull(frustum, out);
  mark.assign(boxes.size(), 0);
  std::size_t fp = 0, bad = 0, dup = 0;
  for (const std::uint32_t i : out) {
    if (i >= boxes.size() || !is_valid(boxes[i])) {
      ++bad;
      continue;
    }
    if (mark[i]) ++dup;
    mark[i] = 1;
    if (!oracle.meets(boxes[i])) ++fp;
  }
  std::size_t missed = 0, truly = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!is_valid(boxes[i]) || !oracle.meets(boxes[i])) continue;
    ++truly;
    if (!mark[i]) {
      ++missed;
      if (missed == 1)
        std::fprintf(stderr, "    missed object %zu box (%g %g %g)-(%g %g %g)\n", i, double(boxes[i].min.x),
                     double(boxes[i].min.y), double(boxes[i].min.z), double(boxes[i].max.x),
                     double(boxes[i].max.y), double(boxes[i].max.z));
    }
  }
  CHECK_MSG(missed == 0, "%s: %zu false negatives (seed %llu, view %d, %s)", label, missed,
            static_cast<unsigned long long>(seed), k, view.kind);
  CHECK_MSG(dup == 0 && bad == 0, "%s: %zu duplicates, %zu invalid/out-of-range (seed %llu, view %d, %s)", label, dup,
            bad, static_cast<unsigned long long>(seed), k, view.kind);

  // The visitor form covers exactly the same positions, as disjoint ranges.
  std::size_t covered = 0;
  bool ranges_ok = true;
  std::size_t wrong_inside = 0;
  tree.cull(frustum, [&](std::uint32_t b, std::uint32_t e, Containment c) {
    if (!(b < e && e <= tree.size()) || c == Containment::outside) ranges_ok = false;
    covered += e - b;
    // `inside` is a promise: every object of the range lies wholly inside the frustum.
    if (c == Containment::inside)
      for (std::uint32_t i = b; i < e && e <= tree.size(); ++i)
        if (!oracle.contains(boxes[tree.order()[i]])) ++wrong_inside;
  });
  CHECK_MSG(wrong_inside == 0, "%s: %zu objects reported inside are not (seed %llu, view %d, %s)", label,
            wrong_inside, static_cast<unsigned long long>(seed), k, view.kind);
  CHECK_MSG(ranges_ok && covered == out.size(), "%s: visitor ranges cover %zu, out has %zu (seed %llu, view %d)",
            label, covered, out.size(), static_cast<unsigned long long>(seed), k);
  ++totals.views;
  totals.returned += out.size();
  totals.truly += truly;
  totals.false_pos += fp;
}

void run_views(const Tree& tree, const std::vector<Aabb>& boxes, const Aabb& region, const char* label,
               std::uint64_t seed, int views) {
  CHECK_MSG(tree.validate(), "%s: validate failed after build (seed %llu)", label,
            static_cast<unsigned long long>(seed));
  support::Rng rng(seed);
  Totals totals;
  std::vector<std::uint32_t> out;
  std::vector<std::uint8_t> mark;
  for (int k = 0; k < views; ++k) {
    const View view = abt_test::random_view(rng, region, k);
    check_view(tree, boxes, view, label, seed, k, totals, out, mark);
  }
  const double fp_rate = totals.returned ? double(totals.false_pos) / double(totals.returned) : 0.0;
  std::printf("%-28s objects %7zu nodes %7u depth %2u views %5zu visible %5.1f%% false positives %zu (%.4f%%)\n",
              label, tree.size(), tree.stats().nodes, tree.stats().depth, totals.views,
              100.0 * double(totals.truly) / double(std::max<std::size_t>(1, totals.views * boxes.size())),
              totals.false_pos, 100.0 * fp_rate);
  // False positives come only from the rounding slack of the float tests: a sliver near the planes.
  CHECK_MSG(fp_rate <= 0.01, "%s: false-positive rate %.4f%% above 1%% (seed %llu)", label, 100.0 * fp_rate,
            static_cast<unsigned long long>(seed));
  CHECK_MSG(totals.truly > 0 && totals.truly < totals.views * boxes.size(),
            "%s: views saw nothing or everything (seed %llu): the test would prove little", label,
            static_cast<unsigned long long>(seed));
}

Aabb region_of(const std::vector<Aabb>& boxes) {
  Aabb r = Aabb::empty();
  for (const Aabb& b : boxes)
    if (is_valid(b)) r = merge(r, b);
  return r;
}

// A mock occluder: a box is hidden iff it lies entirely at z < k (an infinite wall).
struct HalfSpaceOccluder {
  glm::vec3 eye_;
  float k;
  mutable std::vector<Aabb>* queried = nullptr;
  [[nodiscard]] const glm::vec3& eye() const { return eye_; }
  [[nodiscard]] bool is_occluded(const Aabb& b) const {
    if (queried) queried->push_back(b);
    return b.max.z < k;
  }
};

void occlusion_tests() {
  const std::uint64_t seed = 0xabc0cc;
  support::Rng rng(seed);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 4000, 100.0f, 4.0f);
  const Tree tree(boxes.data(), boxes.size());
  CHECK(tree.validate());
  const Aabb region = region_of(boxes);
  std::vector<std::uint32_t> out;
  std::vector<Aabb> queried;
  std::size_t total_visible = 0, total_frustum = 0;
  for (int k = 0; k < 300; ++k) {
    const View view = abt_test::random_view(rng, region, k);
    const Frustum frustum = Frustum::from_matrix(view.view_proj, view.depth);
    const OracleFrustum oracle(view.view_proj, view.depth);
    HalfSpaceOccluder occ{view.eye, rng.uniform(-100.0f, 100.0f)};
    queried.clear();
    occ.queried = &queried;
    out.assign(2, 7u);
    tree.cull(frustum, occ, out);
    std::vector<std::uint8_t> mark(boxes.size(), 0);
    std::size_t dup = 0, hidden_returned = 0;
    for (const std::uint32_t i : out) {
      if (i >= boxes.size()) {
        ++dup;
        continue;
      }
      if (mark[i]) ++dup;
      mark[i] = 1;
      if (occ.is_occluded(boxes[i])) ++hidden_returned;
    }
    std::size_t missed = 0;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (!oracle.meets(boxes[i])) continue;
      ++total_frustum;
      if (occ.is_occluded(boxes[i])) continue;
      ++total_visible;
      if (!mark[i]) ++missed;
    }
    CHECK_MSG(missed == 0 && dup == 0 && hidden_returned == 0,
              "occlusion: %zu missed, %zu duplicates, %zu hidden returned (seed %llu, view %d, %s)", missed, dup,
              hidden_returned, static_cast<unsigned long long>(seed), k, view.kind);
  }
  std::printf("occlusion mock: %zu in frustum, %zu visible after the mock occluder over 300 views\n", total_frustum,
              total_visible);
  CHECK(total_visible > 0 && total_visible < total_frustum);

  // Empty tree and an occluder that hides everything.
  const Tree empty_tree(static_cast<const Aabb*>(nullptr), 0);
  HalfSpaceOccluder all{glm::vec3(0), 1e30f};
  out.assign(1, 1u);
  empty_tree.cull(Frustum{}, all, out);
  CHECK(out.empty());
  tree.cull(Frustum{}, all, out);
  CHECK(out.empty());
  // Nothing hidden, no planes: everything, in the front-to-back leaf order of the traversal.
  for (int e = 0; e < 5; ++e) {
    HalfSpaceOccluder none{glm::vec3(rng.uniform(-150, 150), rng.uniform(-150, 150), rng.uniform(-150, 150)), -1e30f};
    tree.cull(Frustum{}, none, out);
    std::vector<std::uint32_t> expect;
    tree.traverse_front_to_back(none.eye(), [&](std::uint32_t, const AbtNode& n) {
      if (n.is_leaf())
        for (std::uint32_t i = n.begin; i < n.end; ++i) expect.push_back(tree.order()[i]);
      return true;
    });
    CHECK_MSG(out == expect, "occlusion cull order differs from the front-to-back traversal (eye %d)", e);
  }
}

void visitor_early_exit() {
  support::Rng rng(77);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 1000, 50.0f, 2.0f);
  const Tree tree(boxes.data(), boxes.size());
  int calls = 0;
  tree.cull(Frustum{}, [&](std::uint32_t, std::uint32_t, Containment) {
    ++calls;
    return false;
  });
  CHECK(calls == 1);
  // No planes: the root is inside, one range with everything.
  std::uint32_t b0 = 1, e0 = 0;
  Containment c0 = Containment::outside;
  tree.cull(Frustum{}, [&](std::uint32_t b, std::uint32_t e, Containment c) {
    b0 = b;
    e0 = e;
    c0 = c;
  });
  CHECK(b0 == 0 && e0 == 1000 && c0 == Containment::inside);
}

}  // namespace

int main() {
  // Random boxes: small, varied and a few large ones.
  {
    const std::uint64_t seed = 1001;
    support::Rng rng(seed);
    std::vector<Aabb> boxes = abt_test::random_boxes(rng, 5000, 200.0f, 6.0f);
    for (int i = 0; i < 20; ++i) boxes.push_back(abt_test::random_boxes(rng, 1, 200.0f, 80.0f)[0]);
    const Tree tree(boxes.data(), boxes.size());
    run_views(tree, boxes, region_of(boxes), "random_boxes", seed, 1400);
    AbtParams p;
    p.candidates = AbtCandidates::sampling;
    p.max_leaf_size = 1;
    p.scan_below = 0;  // descend to every leaf
    const Tree tree_s(boxes.data(), boxes.size(), p);
    run_views(tree_s, boxes, region_of(boxes), "random_boxes_sampl_leaf1_s0", seed + 1, 700);
    p.max_leaf_size = 32;
    p.candidates = AbtCandidates::binning;
    p.candidate_count = 3;
    p.scan_below = 8;  // leaves larger than the scan threshold
    const Tree tree_b(boxes.data(), boxes.size(), p);
    run_views(tree_b, boxes, region_of(boxes), "random_boxes_bin3_leaf32_s8", seed + 2, 700);
  }
  // A generated city: objects, then triangles.
  {
    const std::uint64_t seed = 2002;
    const support::Scene city = support::make_city(7, 8);
    const std::vector<Aabb> boxes = city.object_bounds();
    const Tree tree(boxes.data(), boxes.size());
    run_views(tree, boxes, city.bounds, "city_objects", seed, 1400);
    const Tree tri = make_triangle_tree(city.mesh());
    std::vector<Aabb> tri_boxes(city.triangle_count());
    for (std::size_t t = 0; t < tri_boxes.size(); ++t) {
      glm::vec3 p[3] = {};
      CHECK(triangle_positions(city.mesh(), t, p));
      tri_boxes[t] = merge(merge(Aabb{p[0], p[0]}, p[1]), p[2]);
    }
    CHECK(tri.size() == tri_boxes.size() && tri.stats().skipped == 0);
    run_views(tri, tri_boxes, city.bounds, "city_triangles", seed + 1, 300);
  }
  // Real scenes (the two smallest), when present.
  {
    const std::vector<std::string> files = support::real_scene_files();
    if (files.empty()) std::printf("real scenes absent: skipped\n");
    for (std::size_t f = 0; f < files.size() && f < 2; ++f) {
      const auto scene = support::load_obj(support::scenes_dir() + "/" + files[f]);
      if (!scene) {
        std::printf("%s: could not load, skipped\n", files[f].c_str());
        continue;
      }
      const std::vector<Aabb> boxes = scene->object_bounds();
      const Tree tree(boxes.data(), boxes.size());
      run_views(tree, boxes, scene->bounds, (files[f] + "_objects").c_str(), 3003 + f, 600);
      const Tree tri = make_triangle_tree(scene->mesh());
      std::vector<Aabb> tri_boxes(scene->triangle_count());
      for (std::size_t t = 0; t < tri_boxes.size(); ++t) {
        glm::vec3 p[3] = {};
        if (triangle_positions(scene->mesh(), t, p) && std::isfinite(p[0].x + p[1].x + p[2].x))
          tri_boxes[t] = merge(merge(Aabb{p[0], p[0]}, p[1]), p[2]);
        else
          tri_boxes[t] = Aabb::empty();
      }
      run_views(tri, tri_boxes, scene->bounds, (files[f] + "_triangles").c_str(), 4004 + f, 150);
    }
  }
  occlusion_tests();
  visitor_early_exit();
  return cullkit_test::report("test_abt_cull");
}
