// AdaptiveBinaryTree build, edge cases and structure: empty, one object, identical objects, bad
// bounds (NaN, inf, inverted), huge values, extreme parameters, determinism across threads and
// seeds, getter and traits builds, triangle builds with reorder_indices, refit (against the brute
// force oracle after moving), progress, and the BSP front-to-back order property.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

#include <cullkit/adaptive_binary_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "abt_oracle.hpp"
#include "check.hpp"

using namespace cullkit;
using Tree = AdaptiveBinaryTree<Aabb>;

// A user type read through traits.
struct Thing {
  float x, y, z, r;
};
template <>
struct cullkit::BoundsTraits<Thing> {
  static Aabb bounds(const Thing& t) { return Aabb{glm::vec3(t.x, t.y, t.z) - t.r, glm::vec3(t.x, t.y, t.z) + t.r}; }
};

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Brute force: every valid box that meets the frustum is in `out`, nothing else invalid, no dups.
bool naive_vs_tree(const Tree& tree, const std::vector<Aabb>& boxes, const abt_test::View& view) {
  const Frustum f = Frustum::from_matrix(view.view_proj, view.depth);
  const abt_test::OracleFrustum oracle(view.view_proj, view.depth);
  std::vector<std::uint32_t> out;
  tree.cull(f, out);
  std::vector<std::uint8_t> mark(boxes.size(), 0);
  for (const std::uint32_t i : out) {
    if (i >= boxes.size() || mark[i]) return false;
    mark[i] = 1;
  }
  // Objects without valid bounds are always reported.
  for (std::size_t i = 0; i < boxes.size(); ++i)
    if ((!is_valid(boxes[i]) || oracle.meets(boxes[i])) && !mark[i]) return false;
  return true;
}

bool same_tree(const Tree& a, const Tree& b) {
  if (a.nodes().size() != b.nodes().size() || a.order() != b.order()) return false;
  for (std::size_t k = 0; k < a.nodes().size(); ++k) {
    const AbtNode &x = a.nodes()[k], &y = b.nodes()[k];
    if (x.begin != y.begin || x.end != y.end || x.left != y.left || x.axis != y.axis ||
        std::memcmp(&x.split, &y.split, sizeof(float)) != 0 || std::memcmp(&x.bounds, &y.bounds, sizeof(Aabb)) != 0)
      return false;
  }
  return true;
}

void empty_and_one() {
  const Tree empty(static_cast<const Aabb*>(nullptr), 0);
  CHECK(empty.empty() && empty.size() == 0 && empty.nodes().empty() && empty.validate());
  std::vector<std::uint32_t> out{1, 2, 3};
  empty.cull(Frustum{}, out);
  CHECK(out.empty());
  int visits = 0;
  empty.traverse_front_to_back(glm::vec3(0), [&](std::uint32_t, const AbtNode&) { return ++visits > 0; });
  CHECK(visits == 0);
  CHECK(empty.refit_quality() == 1.0);

  const Tree dflt;
  CHECK(dflt.empty() && dflt.validate());

  const Aabb one{glm::vec3(1, 2, 3), glm::vec3(2, 3, 4)};
  const Tree t1(&one, 1);
  CHECK(t1.size() == 1 && t1.nodes().size() == 1 && t1.nodes()[0].is_leaf() && t1.validate());
  t1.cull(Frustum{}, out);
  CHECK(out.size() == 1 && out[0] == 0);
  // A frustum looking away from it sees nothing; looking at it sees it.
  const Camera away = support::make_camera(glm::vec3(0, 0, 20), glm::vec3(0, 0, 40), 60, 64, 64, 0.1f, 100);
  t1.cull(frustum_of(away), out);
  CHECK(out.empty());
  const Camera at = support::make_camera(glm::vec3(0, 0, 20), glm::vec3(1.5f, 2.5f, 3.5f), 60, 64, 64, 0.1f, 100);
  t1.cull(frustum_of(at), out);
  CHECK(out.size() == 1);
  // Only invalid objects: all held (with the unbounded box), counted, reported by any view.
  const Aabb bad[3] = {{glm::vec3(kNaN), glm::vec3(1)}, {glm::vec3(0), glm::vec3(kInf)}, {glm::vec3(1), glm::vec3(0)}};
  const Tree tb(bad, 3);
  CHECK(tb.size() == 3 && tb.stats().unbounded == 3 && tb.stats().skipped == 0 && tb.validate() && tb.input_count() == 3);
  tb.cull(Frustum{}, out);
  CHECK(out.size() == 3);
  tb.cull(frustum_of(away), out);
  CHECK(out.size() == 3);
}

void identical_and_flat() {
  std::vector<Aabb> same(1000, Aabb{glm::vec3(5), glm::vec3(6)});
  const Tree t(same.data(), same.size());
  CHECK(t.validate() && t.size() == 1000);
  CHECK(t.stats().leaves == 1 && t.stats().max_leaf_objects == 1000);  // nothing can separate them
  std::vector<std::uint32_t> out;
  t.cull(Frustum{}, out);
  CHECK(out.size() == 1000);
  // Point boxes on a line (flat in two axes), and coincident centroids with different sizes.
  std::vector<Aabb> line;
  for (int i = 0; i < 500; ++i) line.push_back(Aabb{glm::vec3(float(i), 0, 0), glm::vec3(float(i), 0, 0)});
  for (int i = 0; i < 100; ++i) line.push_back(Aabb{glm::vec3(-float(i)), glm::vec3(float(i))});
  const Tree tl(line.data(), line.size());
  CHECK(tl.validate() && tl.size() == 600);
  support::Rng rng(5);
  for (int k = 0; k < 200; ++k)
    CHECK_MSG(naive_vs_tree(tl, line, abt_test::random_view(rng, Aabb{glm::vec3(-100), glm::vec3(500, 100, 100)}, k)),
              "flat line, view %d", k);
}

void bad_and_huge() {
  support::Rng rng(99);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 3000, 100.0f, 3.0f);
  std::size_t bad = 0;
  for (std::size_t i = 0; i < boxes.size(); i += 7) {
    switch ((i / 7) % 5) {
      case 0: boxes[i].min.x = kNaN; break;
      case 1: boxes[i].max.y = kInf; break;
      case 2: boxes[i].min.z = -kInf; break;
      case 3: std::swap(boxes[i].min, boxes[i].max); boxes[i].max.x = boxes[i].min.x - 1.0f; break;
      default: boxes[i].max = glm::vec3(kNaN); break;
    }
    ++bad;
  }
  // Huge but finite boxes and far-away objects.
  const float big = std::numeric_limits<float>::max();
  boxes.push_back(Aabb{glm::vec3(-big), glm::vec3(big)});
  boxes.push_back(Aabb{glm::vec3(big * 0.5f), glm::vec3(big)});
  boxes.push_back(Aabb{glm::vec3(-big), glm::vec3(-big * 0.9f)});
  boxes.push_back(Aabb{glm::vec3(1e30f, 0, 0), glm::vec3(1e30f, 1, 1)});
  boxes.push_back(Aabb{glm::vec3(-1e-30f), glm::vec3(1e-30f)});
  for (AbtCandidates cand : {AbtCandidates::binning, AbtCandidates::sampling}) {
    AbtParams p;
    p.candidates = cand;
    const Tree t(boxes.data(), boxes.size(), p);
    CHECK(t.validate());
    CHECK_MSG(t.stats().unbounded == bad && t.stats().skipped == 0 && t.size() == boxes.size(), "unbounded %u of %zu bad",
              t.stats().unbounded, bad);
    for (int k = 0; k < 300; ++k)
      CHECK_MSG(naive_vs_tree(t, boxes, abt_test::random_view(rng, Aabb{glm::vec3(-120), glm::vec3(120)}, k)),
                "bad+huge, candidates %d, view %d (seed 99)", int(cand), k);
    // The box spanning everything is seen by any frustum that has some volume.
    std::vector<std::uint32_t> out;
    t.cull(Frustum::from_matrix(abt_test::random_view(rng, Aabb{glm::vec3(-1), glm::vec3(1)}, 0).view_proj), out);
    CHECK(std::find(out.begin(), out.end(), std::uint32_t(boxes.size() - 5)) != out.end());
  }
  // A NaN / inf matrix gives a frustum with dropped planes: conservative, everything kept.
  const Tree t(boxes.data(), boxes.size());
  std::vector<std::uint32_t> out;
  t.cull(Frustum::from_matrix(glm::mat4(kNaN)), out);
  CHECK(out.size() == t.size());
}

void params_extremes() {
  support::Rng rng(123);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 2000, 50.0f, 2.0f);
  const Aabb region{glm::vec3(-55), glm::vec3(55)};
  AbtParams variants[8];
  variants[0].max_leaf_size = 0;
  variants[1].max_depth = 0;
  variants[2].max_depth = 1000;
  variants[2].max_leaf_size = 1;
  variants[3].candidate_count = 0;
  variants[4].candidate_count = 100000;
  variants[5].weight_axis = kNaN;
  variants[5].weight_volume = -1.0f;
  variants[5].weight_count = kInf;
  variants[5].weight_straddle = 0.0f;
  variants[6].weight_axis = variants[6].weight_volume = variants[6].weight_count = variants[6].weight_straddle = 0.0f;
  variants[7].candidates = AbtCandidates::sampling;
  variants[7].candidate_count = 1;
  for (int v = 0; v < 8; ++v) {
    const Tree t(boxes.data(), boxes.size(), variants[v]);
    CHECK_MSG(t.validate() && t.size() == boxes.size(), "params variant %d", v);
    CHECK(t.stats().depth <= Tree::depth_limit);
    for (int k = 0; k < 60; ++k)
      CHECK_MSG(naive_vs_tree(t, boxes, abt_test::random_view(rng, region, k)), "params variant %d view %d", v, k);
  }
  const Tree root_only(boxes.data(), boxes.size(), variants[1]);
  CHECK(root_only.nodes().size() == 1);
  const Tree leaf1(boxes.data(), boxes.size(), variants[2]);
  CHECK(leaf1.stats().max_leaf_objects == 1 && leaf1.stats().leaves == boxes.size());
  const Tree dflt(boxes.data(), boxes.size());
  CHECK(dflt.stats().max_leaf_objects <= AbtParams{}.max_leaf_size);
  CHECK(dflt.stats().depth < 30);  // balanced-ish: 2000 objects need ~9 levels
}

void determinism() {
  support::Rng rng(4242);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 30000, 300.0f, 3.0f);
  for (AbtCandidates cand : {AbtCandidates::binning, AbtCandidates::sampling}) {
    AbtParams p;
    p.candidates = cand;
    p.threads = 1;
    const Tree serial(boxes.data(), boxes.size(), p);
    p.threads = 4;
    p.parallel_grain = 100;
    const Tree par4(boxes.data(), boxes.size(), p);
    p.threads = 2;
    p.parallel_grain = 5000;
    const Tree par2(boxes.data(), boxes.size(), p);
    CHECK(serial.validate() && par4.validate() && par2.validate());
    CHECK_MSG(same_tree(serial, par4) && same_tree(serial, par2), "threads change the tree (candidates %d)", int(cand));
    // The caller's job system: every task handed to it, run here in reverse order on this thread.
    struct Jobs {
      std::size_t calls = 0, tasks = 0;
    } jobs;
    p.threads = 3;
    p.parallel_grain = 300;
    p.task_runner.context = &jobs;
    p.task_runner.dispatch = [](void* context, std::size_t count, void (*run)(void*, std::size_t), void* job) {
      Jobs& j = *static_cast<Jobs*>(context);
      ++j.calls;
      j.tasks += count;
      for (std::size_t i = count; i-- > 0;) run(job, i);
    };
    const Tree hooked(boxes.data(), boxes.size(), p);
    CHECK_MSG(jobs.calls == 1 && jobs.tasks == 3, "the build's tasks did not go to the task runner (%zu calls, %zu tasks)",
              jobs.calls, jobs.tasks);
    CHECK_MSG(same_tree(serial, hooked), "the task runner changes the tree (candidates %d)", int(cand));
  }
  AbtParams a, b;
  a.candidates = b.candidates = AbtCandidates::sampling;
  b.seed = 777;
  const Tree ta(boxes.data(), boxes.size(), a), ta2(boxes.data(), boxes.size(), a), tb(boxes.data(), boxes.size(), b);
  CHECK(same_tree(ta, ta2));
  CHECK(!same_tree(ta, tb));  // the seed matters (different random candidates)

  // Progress: non-decreasing, ends at 1, called more than once on a large build.
  std::vector<float> seen;
  AbtParams pp;
  pp.progress_min_objects = 1000;
  pp.threads = 3;
  pp.parallel_grain = 512;
  pp.progress = [&](float f) { seen.push_back(f); };
  const Tree tp(boxes.data(), boxes.size(), pp);
  CHECK(seen.size() > 3 && seen.back() == 1.0f && std::is_sorted(seen.begin(), seen.end()));
  CHECK(same_tree(tp, Tree(boxes.data(), boxes.size())));
}

void getters_traits_triangles() {
  support::Rng rng(31);
  std::vector<Thing> things(1500);
  for (auto& t : things) t = Thing{rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(-40, 40), rng.uniform(0, 2)};
  const AdaptiveBinaryTree<Thing> tt(things.data(), things.size());
  std::vector<Aabb> boxes;
  for (const Thing& t : things) boxes.push_back(BoundsTraits<Thing>::bounds(t));
  const Tree tg = Tree::from_getter(boxes.size(), [&boxes](std::uint32_t i) { return boxes[i]; });
  CHECK(tt.validate() && tg.validate() && tt.order() == tg.order() && tt.nodes().size() == tg.nodes().size());

  // Triangles: a city mesh plus one bad triangle (index out of range) and one NaN vertex.
  support::Scene city = support::make_city(3, 4);
  const std::size_t good = city.triangle_count();
  city.positions.push_back(glm::vec3(kNaN));
  const auto nan_vertex = static_cast<std::uint32_t>(city.positions.size() - 1);
  city.indices.insert(city.indices.end(), {0u, 1u, 999999u, 0u, 1u, nan_vertex});
  city.indices.push_back(0);  // a trailing partial triangle is ignored
  const MeshView<glm::vec3> mesh = city.mesh();
  const Tree tri = make_triangle_tree(mesh);
  CHECK_MSG(tri.validate() && tri.size() == good + 2 && tri.stats().unbounded == 2, "size %zu of %zu, unbounded %u",
            tri.size(), good + 2, tri.stats().unbounded);
  std::vector<std::uint32_t> reordered;
  tri.reorder_indices(mesh, reordered);
  CHECK(reordered.size() == 3 * (good + 2));
  bool ranges_ok = true;
  for (const AbtNode& n : tri.nodes()) {
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
      const std::uint32_t t = tri.order()[i];
      for (int c = 0; c < 3; ++c) ranges_ok &= reordered[3 * i + c] == city.indices[3 * t + c];
      // The range's triangles lie inside the node's box (the two bad ones have no position).
      if (t >= good) continue;
      for (int c = 0; c < 3; ++c) ranges_ok &= contains(n.bounds, city.positions[reordered[3 * i + c]]);
    }
  }
  CHECK(ranges_ok);
  // Signed 16-bit indices with a vec4 vertex type.
  std::vector<glm::vec4> v4;
  for (const glm::vec3& p : city.positions) v4.emplace_back(p, 1.0f);
  std::vector<std::int16_t> i16 = {0, 1, 2, 2, 1, -3, 3, 4, 5};
  const Tree t16 = make_triangle_tree(MeshView<glm::vec4, std::int16_t>{v4.data(), v4.size(), i16.data(), i16.size()});
  CHECK(t16.size() == 3 && t16.stats().unbounded == 1 && t16.validate());
}

void refit_tests() {
  const std::uint64_t seed = 555;
  support::Rng rng(seed);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 5000, 100.0f, 2.0f);
  Tree t(boxes.data(), boxes.size());
  CHECK(t.refit_quality() == 1.0);
  t.refit(boxes.data());  // nothing moved
  CHECK(t.validate() && t.refit_quality() == 1.0 && t.stats().refit_invalid == 0);
  const Aabb region{glm::vec3(-160), glm::vec3(160)};
  double last_quality = 1.0;
  for (int step = 1; step <= 4; ++step) {
    for (Aabb& b : boxes) {
      const glm::vec3 d(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-10, 10));
      b = Aabb{b.min + d, b.max + d};
    }
    if (step == 3) boxes[17].min.x = kNaN;  // held unbounded, counted, reported by every view
    t.refit(boxes.data());
    CHECK_MSG(t.validate(), "validate after refit step %d", step);
    CHECK(t.stats().refit_invalid == (step == 3 ? 1u : 0u));
    const double q = t.refit_quality();
    CHECK_MSG(q > 1.0 && q >= last_quality * 0.98, "refit quality %f after step %d", q, step);
    last_quality = q;
    if (step == 3) {
      const auto pos = static_cast<std::size_t>(std::find(t.order().begin(), t.order().end(), 17u) - t.order().begin());
      CHECK(pos < t.size() && is_unbounded(t.object_bounds()[pos]) && t.stats().unbounded == 1);
    }
    for (int k = 0; k < 120; ++k)
      CHECK_MSG(naive_vs_tree(t, boxes, abt_test::random_view(rng, region, k)),
                "refit step %d view %d (seed %llu)", step, k, static_cast<unsigned long long>(seed));
    if (step == 3) boxes[17].min.x = boxes[17].max.x - 1.0f;  // valid again at the next refit
  }
  std::printf("refit: quality after 4 random moves of up to 10 units: %.3f\n", last_quality);
  // An object NaN at the build (a transform not ready at load) is reported while it has no
  // bounds, and culled by its bounds after the first refit that gives it valid ones.
  std::vector<Aabb> with_bad = boxes;
  with_bad[3].max.y = kNaN;
  Tree tb(with_bad.data(), with_bad.size());
  CHECK(tb.validate() && tb.size() == boxes.size() && tb.stats().unbounded == 1);
  const Frustum far_away = frustum_of(support::make_camera(glm::vec3(5000), glm::vec3(6000), 60, 64, 64, 0.1f, 100));
  std::vector<std::uint32_t> out;
  tb.cull(far_away, out);
  CHECK(out.size() == 1 && out[0] == 3u);
  with_bad[3] = Aabb{glm::vec3(0), glm::vec3(1)};
  tb.refit_from_getter([&](std::uint32_t i) { return with_bad[i]; });
  CHECK(tb.validate() && tb.size() == boxes.size() && tb.stats().unbounded == 0);
  tb.cull(far_away, out);
  CHECK(out.empty());
  // The `refit(getter)` spelling; moving everything far away is seen by the refitted tree.
  tb.refit([&](std::uint32_t i) { return Aabb{with_bad[i].min + 1000.0f, with_bad[i].max + 1000.0f}; });
  CHECK(tb.validate() && tb.nodes()[0].bounds.min.x > 800.0f);
  tb.cull(Frustum{}, out);
  CHECK(std::find(out.begin(), out.end(), 3u) != out.end() && out.size() == boxes.size());
}

// The BSP order: for two objects met one after the other in a front-to-back walk, at the split of
// their lowest common ancestor the earlier one's centroid is on the eye's side. Checked against
// centroids recomputed from the input (not from the tree's own arrays). Back-to-front is the
// exact reverse. Boxes are disjoint cells of a jittered grid, shuffled.
void front_to_back() {
  support::Rng rng(8080);
  std::vector<Aabb> boxes;
  for (int x = 0; x < 16; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 16; ++z) {
        const glm::vec3 c(float(x) * 4.0f + rng.uniform(-1, 1), float(y) * 4.0f + rng.uniform(-1, 1),
                          float(z) * 4.0f + rng.uniform(-1, 1));
        boxes.push_back(Aabb{c - rng.uniform(0.2f, 0.9f), c + rng.uniform(0.2f, 0.9f)});
      }
  for (std::size_t i = boxes.size(); i > 1; --i) std::swap(boxes[i - 1], boxes[rng.next() % i]);
  for (AbtCandidates cand : {AbtCandidates::binning, AbtCandidates::sampling}) {
    AbtParams p;
    p.candidates = cand;
    p.max_leaf_size = 1;
    const Tree t(boxes.data(), boxes.size(), p);
    CHECK(t.validate());
    std::vector<std::uint32_t> parent(t.nodes().size(), 0), leaf_of(boxes.size(), 0), depth(t.nodes().size(), 0);
    for (std::uint32_t k = 0; k < t.nodes().size(); ++k) {
      const AbtNode& n = t.nodes()[k];
      if (n.is_leaf()) {
        for (std::uint32_t i = n.begin; i < n.end; ++i) leaf_of[t.order()[i]] = k;
      } else {
        parent[n.left] = parent[n.left + 1] = k;
        depth[n.left] = depth[n.left + 1] = depth[k] + 1;
      }
    }
    for (int e = 0; e < 40; ++e) {
      const glm::vec3 eye(rng.uniform(-20, 80), rng.uniform(-20, 50), rng.uniform(-20, 80));
      std::vector<std::uint32_t> seq, rev;
      std::size_t visited = 0;
      t.traverse_front_to_back(eye, [&](std::uint32_t, const AbtNode& n) {
        ++visited;
        if (n.is_leaf())
          for (std::uint32_t i = n.begin; i < n.end; ++i) seq.push_back(t.order()[i]);
        return true;
      });
      t.traverse_back_to_front(eye, [&](std::uint32_t, const AbtNode& n) {
        if (n.is_leaf())
          for (std::uint32_t i = n.end; i > n.begin; --i) rev.push_back(t.order()[i - 1]);
      });
      CHECK(visited == t.nodes().size() && seq.size() == boxes.size());
      std::reverse(rev.begin(), rev.end());
      CHECK(rev == seq);
      std::size_t violations = 0;
      for (std::size_t s = 0; s + 1 < seq.size(); ++s) {
        // Every later object against this one would be O(n^2); consecutive pairs plus a stride.
        for (std::size_t later : {s + 1, std::min(seq.size() - 1, s + 37), seq.size() - 1}) {
          if (later <= s) continue;
          const std::uint32_t a = seq[s], b = seq[later];
          std::uint32_t x = leaf_of[a], y = leaf_of[b];
          std::uint32_t cx = x, cy = y;
          while (x != y) {
            if (depth[x] >= depth[y]) {
              cx = x;
              x = parent[x];
            } else {
              cy = y;
              y = parent[y];
            }
          }
          const AbtNode& lca = t.nodes()[x];
          const float ca = detail::abt_centroid(boxes[a])[lca.axis], cb = detail::abt_centroid(boxes[b])[lca.axis];
          const bool eye_left = eye[lca.axis] < lca.split;
          const bool a_left = ca < lca.split, b_left = cb < lca.split;
          if (a_left != eye_left || b_left == eye_left || cx == cy) ++violations;
        }
      }
      CHECK_MSG(violations == 0, "front-to-back order: %zu violations (eye %d, candidates %d)", violations, e,
                int(cand));
    }
    // Early exit: a visitor refusing to descend sees only the root.
    int calls = 0;
    t.traverse_front_to_back(glm::vec3(0), [&](std::uint32_t, const AbtNode&) { return ++calls < 0; });
    CHECK(calls == 1);
  }
}

}  // namespace

int main() {
  empty_and_one();
  identical_and_flat();
  bad_and_huge();
  params_extremes();
  determinism();
  getters_traits_triangles();
  refit_tests();
  front_to_back();
  return cullkit_test::report("test_abt_build");
}
