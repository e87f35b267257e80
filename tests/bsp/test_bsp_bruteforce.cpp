// BspTree against brute force: the ray oracle (bsp_oracle.hpp) on interpenetrating and cyclically
// overlapping triangles and generated scenes from eyes inside and outside; fragments tile their
// triangles exactly (area, plane, winding, barycentrics); bad input is dropped and counted; a deep
// tree walks without recursion; the tree does not depend on the thread count. Mutants: the
// front-to-back order and a centroid sort must fail the same oracle.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>
#include <vector>

#include <cullkit/bsp_tree.hpp>
#include <cullkit/depth_sort.hpp>
#include <cullkit_support/scene.hpp>

#include "bsp_oracle.hpp"
#include "check.hpp"

namespace {

using cullkit::BspParams;
using cullkit::BspTree;
using cullkit::support::Rng;
using cullkit::support::Scene;
using Tree = BspTree<glm::vec3>;

// Painting order by a depth sort of fragment centroids (what a renderer does without a BSP).
std::vector<std::uint32_t> centroid_order(const Tree& tree, const glm::vec3& eye) {
  std::vector<float> depth(tree.fragments().size());
  for (std::size_t f = 0; f < depth.size(); ++f) {
    const auto& fr = tree.fragments()[f];
    glm::vec3 c(0.0f);
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) c += tree.corners()[fr.first_corner + i];
    depth[f] = glm::length(c / float(fr.corner_count) - eye);
  }
  std::vector<std::uint32_t> order;
  cullkit::order_back_to_front(depth.data(), depth.size(), order);
  return order;
}

void check_scene(const char* name, const Scene& scene, const std::vector<glm::vec3>& eyes, std::size_t rays,
                 std::size_t& mutant_violations, std::size_t& sort_violations) {
  const Tree tree(scene.mesh());
  CHECK_MSG(tree.validate(), "%s: validate", name);
  CHECK_MSG(tree.stats().fragments >= scene.triangle_count(), "%s", name);
  std::vector<std::uint32_t> order, reverse;
  for (std::size_t e = 0; e < eyes.size(); ++e) {
    tree.back_to_front(eyes[e], order);
    // Every fragment exactly once.
    std::vector<std::uint8_t> seen(tree.fragments().size(), 0);
    bool once = order.size() == seen.size();
    for (std::uint32_t f : order) once = once && f < seen.size() && !seen[f]++;
    CHECK_MSG(once, "%s eye %zu: every fragment once", name, e);
    const auto res = bsp_test::check_order(tree, eyes[e], order, rays, 100 + e);
    CHECK_MSG(res.violations == 0, "%s eye %zu: %zu of %zu ordered hit pairs painted in the wrong order", name, e,
              res.violations, res.pairs_checked);
    CHECK_MSG(res.pairs_checked > 0, "%s eye %zu: the oracle compared something", name, e);
    tree.front_to_back(eyes[e], reverse);
    std::reverse(reverse.begin(), reverse.end());
    CHECK_MSG(reverse == order, "%s eye %zu: front_to_back is the reverse", name, e);
    std::vector<std::uint32_t> visited_near_first, visited_far_first;
    tree.visit_front_to_back(eyes[e], [&](std::uint32_t f) { visited_near_first.push_back(f); });
    tree.visit_back_to_front(eyes[e], [&](std::uint32_t f) { visited_far_first.push_back(f); });
    std::reverse(visited_near_first.begin(), visited_near_first.end());
    CHECK_MSG(visited_near_first == order && visited_far_first == order, "%s eye %zu: the visitor forms' orders", name, e);
    std::reverse(reverse.begin(), reverse.end());
    mutant_violations += bsp_test::check_order(tree, eyes[e], reverse, rays / 4, 100 + e).violations;
    sort_violations += bsp_test::check_order(tree, eyes[e], centroid_order(tree, eyes[e]), rays, 100 + e).violations;
  }
}

void test_orders() {
  std::size_t mutant = 0, sorted = 0;
  const Scene cyclic = bsp_test::cyclic_scene();
  check_scene("cyclic", cyclic, {{0, 6, 0.3f}, {0.1f, 0.5f, 0.1f}, {4, 2, 4}, {0, -5, 0}, {7, 0.4f, -2}}, 400, mutant,
              sorted);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Scene soup = bsp_test::random_soup(seed, 120, 4.0f, 2.0f);
    Rng rng(seed);
    std::vector<glm::vec3> eyes = {{0, 0, 0}, {15, 3, -2}, {-1, 20, 1}};  // inside the cloud and out
    for (int i = 0; i < 3; ++i) eyes.push_back({rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5)});
    check_scene("soup", soup, eyes, 300, mutant, sorted);
  }
  const Scene office = cullkit::support::make_office(3, 2, 2);  // boxes: many coplanar faces
  check_scene("office", office, {{3, 1.6f, 2.5f}, {-4, 8, -4}}, 300, mutant, sorted);
  // Scenes that stress the on-plane tolerance, from eyes inside, outside and on the mesh (a corner,
  // an edge, a triangle's plane).
  const Scene stress[] = {bsp_test::small_far_cloud(11, 600), bsp_test::sliver_soup(12, 150),
                          bsp_test::near_coplanar_fans(13, 10, 16, 1e-4f),
                          bsp_test::scaled(cullkit::support::make_office(4, 2, 1), 1e-3f, "office_x1e-3"),
                          bsp_test::scaled(bsp_test::random_soup(14, 120, 4.0f, 2.0f), 1e3f, "soup_x1e3")};
  const char* stress_names[] = {"small_far", "slivers", "fans", "office_x1e-3", "soup_x1e3"};
  for (std::size_t i = 0; i < sizeof(stress) / sizeof(stress[0]); ++i) {
    const Scene& s = stress[i];
    const glm::vec3 lo = s.bounds.min, hi = s.bounds.max, size = hi - lo;
    std::vector<glm::vec3> eyes = {lo + size * glm::vec3(0.45f, 0.55f, 0.5f), hi + size * 0.7f};
    for (const glm::vec3& e : bsp_test::eyes_on_mesh(s, s.triangle_count() / 3)) eyes.push_back(e);
    check_scene(stress_names[i], s, eyes, 200, mutant, sorted);
  }
  std::printf("reversed order: %zu violations, centroid sort: %zu violations\n", mutant, sorted);
  CHECK(mutant > 100);  // the oracle sees wrong orders
  CHECK(sorted > 0);    // and a depth sort is not enough on these scenes
}

// The fragments of each triangle cover it exactly: areas add up, every corner lies in the
// triangle's plane, windings agree and barycentrics give back the corner positions.
void test_fragments_tile_triangles() {
  const Scene soup = bsp_test::random_soup(9, 200, 3.0f, 2.5f);
  const Tree tree(soup.mesh());
  CHECK(tree.stats().cuts > 100);  // the soup really is cut
  std::vector<double> area(soup.triangle_count(), 0.0);
  std::size_t bad_corner = 0, bad_winding = 0;
  for (const auto& fr : tree.fragments()) {
    const std::uint32_t* idx = soup.indices.data() + 3 * fr.triangle;
    const glm::dvec3 a(soup.positions[idx[0]]), b(soup.positions[idx[1]]), c(soup.positions[idx[2]]);
    const glm::dvec3 tri_n = glm::cross(b - a, c - a);
    glm::dvec3 n(0.0);
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) {
      const glm::dvec3 p(tree.corners()[fr.first_corner + i]);
      const glm::dvec3 q(tree.corners()[fr.first_corner + (i + 1) % fr.corner_count]);
      n += glm::cross(p, q);
      const glm::dvec2 uv(tree.barycentrics()[fr.first_corner + i]);
      const glm::dvec3 from_uv = (1 - uv.x - uv.y) * a + uv.x * b + uv.y * c;
      if (glm::length(from_uv - p) > 1e-5 || std::fabs(glm::dot(glm::normalize(tri_n), p - a)) > 1e-5) ++bad_corner;
    }
    area[fr.triangle] += 0.5 * glm::length(n);
    if (glm::dot(n, tri_n) < 0) ++bad_winding;
  }
  std::size_t bad_area = 0;
  for (std::size_t t = 0; t < area.size(); ++t) {
    const std::uint32_t* idx = soup.indices.data() + 3 * t;
    const double want = 0.5 * glm::length(glm::cross(glm::dvec3(soup.positions[idx[1]] - soup.positions[idx[0]]),
                                                      glm::dvec3(soup.positions[idx[2]] - soup.positions[idx[0]])));
    if (std::fabs(area[t] - want) > 1e-4 * std::max(1.0, want)) ++bad_area;
  }
  CHECK_MSG(bad_corner == 0, "%zu corners off their triangle or barycentrics", bad_corner);
  CHECK_MSG(bad_winding == 0, "%zu fragments wound against their triangle", bad_winding);
  CHECK_MSG(bad_area == 0, "%zu triangles whose fragments do not add up to their area", bad_area);
}

void test_bad_input() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<glm::vec3> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {nan, 0, 0}, {inf, 1, 1}, {0, 0, 1}};
  const std::vector<std::uint32_t> idx = {0, 1, 2,   // good
                                          0, 1, 3,   // collinear: zero area
                                          0, 0, 2,   // repeated corner
                                          0, 4, 2,   // NaN
                                          5, 1, 2,   // infinity
                                          0, 1, 99,  // index out of range
                                          0, 2, 6,   // good
                                          1, 2};     // a trailing partial triangle: ignored
  const Tree tree(cullkit::MeshView<glm::vec3>{v.data(), v.size(), idx.data(), idx.size()});
  const auto& s = tree.stats();
  CHECK(s.triangles == 7);
  CHECK(s.dropped_degenerate == 2);
  CHECK(s.dropped_non_finite == 2);
  CHECK(s.dropped_bad_index == 1);
  CHECK(tree.fragments().size() == 2);
  CHECK(tree.validate());
  std::vector<std::uint32_t> out = {7, 7};
  tree.back_to_front(glm::vec3(nan, 0, 0), out);  // a NaN eye: every fragment once, any order
  CHECK(out.size() == 2 && out[0] != out[1]);
  const Tree empty(cullkit::MeshView<glm::vec3>{nullptr, 0, nullptr, 0});
  empty.back_to_front(glm::vec3(0), out);
  CHECK(out.empty() && empty.nodes().empty() && empty.validate());
  const Tree one(cullkit::MeshView<glm::vec3>{v.data(), v.size(), idx.data(), 3});
  one.back_to_front(glm::vec3(5, 5, 5), out);
  CHECK(out.size() == 1 && one.nodes().size() == 1);
  // A sliver far thinner than the tolerance (1e-8 of its length) still has a plane through its
  // corners: kept whole, beside a normal triangle; a crossing triangle cuts it exactly.
  const std::vector<glm::vec3> sv = {{0, 0, 0}, {1e6f, 0, 0}, {5e5f, 1e-2f, 0}, {0, 1e5f, 0},
                                     {4e5f, -1, -1}, {4e5f, 5, 1}, {4e5f, -1, 1}};
  const std::vector<std::uint32_t> si3 = {0, 1, 2, 0, 1, 3, 4, 5, 6};
  const Tree sliver(cullkit::MeshView<glm::vec3>{sv.data(), sv.size(), si3.data(), si3.size() - 3});
  CHECK(sliver.stats().dropped_degenerate == 0 && sliver.fragments().size() == 2 && sliver.validate());
  const Tree crossed(cullkit::MeshView<glm::vec3>{sv.data(), sv.size(), si3.data(), si3.size()});
  double sliver_area = 0;
  for (const auto& fr : crossed.fragments()) {
    if (fr.triangle != 0) continue;
    for (std::uint32_t i = 1; i + 1 < fr.corner_count; ++i) {
      const glm::dvec3 o(crossed.corners()[fr.first_corner]);
      sliver_area += 0.5 * glm::length(glm::cross(glm::dvec3(crossed.corners()[fr.first_corner + i]) - o,
                                                  glm::dvec3(crossed.corners()[fr.first_corner + i + 1]) - o));
    }
  }
  CHECK_MSG(std::fabs(sliver_area / 5e3 - 1) < 1e-4, "sliver covered %.6f", sliver_area / 5e3);
  CHECK(crossed.stats().dropped_degenerate == 0 && crossed.validate());
  // Signed 16-bit indices and a vertex type read through custom traits.
  struct MyVertex {
    float xyz[3];
    int material;
  };
  struct MyTraits {
    static glm::vec3 position(const MyVertex& m) { return glm::vec3(m.xyz[0], m.xyz[1], m.xyz[2]); }
  };
  const MyVertex mv[] = {{{0, 0, 0}, 1}, {{1, 0, 0}, 1}, {{0, 1, 0}, 1}, {{0, 0, 1}, 2}};
  const std::int16_t si[] = {0, 1, 2, 0, -1, 3, 0, 3, 1};
  const BspTree<MyVertex, std::int16_t, MyTraits> custom(cullkit::MeshView<MyVertex, std::int16_t>{mv, 4, si, 9});
  CHECK(custom.stats().dropped_bad_index == 1 && custom.fragments().size() == 2 && custom.validate());
}

// 4,000 parallel triangles with one candidate per node: a chain 4,000 nodes deep. The walk has
// no recursion; on each side of the eye the triangles come farthest first (the two sides never
// overlap along a ray, so how they interleave does not matter).
void test_deep_tree() {
  std::vector<glm::vec3> v;
  std::vector<std::uint32_t> idx;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const float z = float(i);
    v.push_back({0, 0, z});
    v.push_back({1, 0, z});
    v.push_back({0, 1, z});
    for (int k = 0; k < 3; ++k) idx.push_back(static_cast<std::uint32_t>(3 * i + k));
  }
  BspParams params;
  params.candidates = 1;
  params.threads = 1;
  const Tree tree(cullkit::MeshView<glm::vec3>{v.data(), v.size(), idx.data(), idx.size()}, params);
  CHECK(tree.stats().depth == std::size_t(n));
  CHECK(tree.fragments().size() == std::size_t(n));
  std::vector<std::uint32_t> order;
  const glm::vec3 eye(0.2f, 0.2f, 12345.5f);
  tree.back_to_front(eye, order);
  bool decreasing = order.size() == std::size_t(n);
  float last_below = -1.0f, last_above = float(n);
  for (std::size_t i = 0; decreasing && i < order.size(); ++i) {
    const float z = float(tree.fragments()[order[i]].triangle);
    float& last = z < eye.z ? last_below : last_above;
    decreasing = std::fabs(z - eye.z) < std::fabs(last - eye.z);
    last = z;
  }
  CHECK(decreasing);
}

// Worker threads change nothing; the progress callback runs and ends with nothing pending.
void test_threads_and_progress() {
  const Scene soup = bsp_test::random_soup(21, 3000, 20.0f, 1.5f);
  BspParams one;
  one.threads = 1;
  BspParams many;
  many.threads = 4;
  many.parallel_min_triangles = 100;
  std::size_t calls = 0;
  cullkit::BspProgress last;
  // The workers come from the shared pool; reports still come from the calling thread only.
  const auto builder = std::this_thread::get_id();
  bool on_builder = true;
  many.progress = [&](const cullkit::BspProgress& p) {
    ++calls;
    last = p;
    on_builder = on_builder && std::this_thread::get_id() == builder;
  };
  const Tree a(soup.mesh(), one);
  const Tree b(soup.mesh(), many);
  CHECK(calls > 1 && on_builder);
  CHECK(last.fragments_pending == 0 && last.fragments_placed == b.fragments().size());
  CHECK(a.validate() && b.validate());
  bool same = a.fragments().size() == b.fragments().size() && a.corners() == b.corners() &&
              a.barycentrics() == b.barycentrics() && a.nodes().size() == b.nodes().size();
  for (std::size_t i = 0; same && i < a.fragments().size(); ++i)
    same = a.fragments()[i].triangle == b.fragments()[i].triangle &&
           a.fragments()[i].first_corner == b.fragments()[i].first_corner;
  for (std::size_t i = 0; same && i < a.nodes().size(); ++i)
    same = a.nodes()[i].front == b.nodes()[i].front && a.nodes()[i].back == b.nodes()[i].back &&
           a.nodes()[i].normal == b.nodes()[i].normal;
  CHECK(same);
  // The caller's job system: the build's tasks go to it (run here in reverse order), same tree.
  struct Jobs {
    std::size_t calls = 0;
  } jobs;
  BspParams hooked = many;
  hooked.progress = nullptr;
  hooked.task_runner.context = &jobs;
  hooked.task_runner.dispatch = [](void* context, std::size_t count, void (*run)(void*, std::size_t), void* job) {
    ++static_cast<Jobs*>(context)->calls;
    for (std::size_t i = count; i-- > 0;) run(job, i);
  };
  const Tree h(soup.mesh(), hooked);
  CHECK_MSG(jobs.calls > 0, "the build's tasks did not go to the task runner");
  CHECK(h.corners() == a.corners() && h.fragments().size() == a.fragments().size() && h.nodes().size() == a.nodes().size());
  // One thread with a callback: it still reports on the way, from the calling thread only.
  BspParams single;
  single.threads = 1;
  std::size_t single_calls = 0;
  const auto caller = std::this_thread::get_id();
  bool same_thread = true;
  single.progress = [&](const cullkit::BspProgress&) {
    ++single_calls;
    same_thread = same_thread && std::this_thread::get_id() == caller;
  };
  const Tree c(soup.mesh(), single);
  CHECK(single_calls > 1 && same_thread && c.fragments().size() == a.fragments().size());
  std::printf("soup of %zu triangles: %zu fragments, %zu nodes, depth %zu\n", soup.triangle_count(),
              a.fragments().size(), a.nodes().size(), a.stats().depth);
}

// Built from instances (a soup as it is, and the same soup 16-bit, rotated, scaled and mirrored):
// the same tree as the level concatenated by hand (corners placed in double and rounded to float,
// the mirrored instance's triangles wound back).
void test_instances() {
  const Scene soup = bsp_test::random_soup(31, 200, 4.0f, 1.5f);
  std::vector<std::uint16_t> idx16(soup.indices.begin(), soup.indices.end());
  const cullkit::StridedMesh mesh32{{reinterpret_cast<const unsigned char*>(soup.positions.data()), sizeof(glm::vec3), 0}, soup.positions.size(),
                                    {soup.indices.data(), soup.indices.size(), cullkit::IndexFormat::uint32}};
  const cullkit::StridedMesh mesh16{{reinterpret_cast<const unsigned char*>(soup.positions.data()), sizeof(glm::vec3), 0}, soup.positions.size(),
                                    {idx16.data(), idx16.size(), cullkit::IndexFormat::uint16}};
  glm::mat4 mirrored(1.0f);
  mirrored[0] = glm::vec4(0.0f, 0.0f, -1.5f, 0.0f);  // x -> -1.5 z
  mirrored[1] = glm::vec4(0.0f, 0.8f, 0.0f, 0.0f);
  mirrored[2] = glm::vec4(-1.0f, 0.0f, 0.0f, 0.0f);  // z -> -x: with the above, a reflection
  mirrored[3] = glm::vec4(9.0f, 1.0f, -3.0f, 1.0f);
  const cullkit::MeshInstance instances[2] = {{mesh32, glm::mat4(1.0f)}, {mesh16, mirrored}};
  const Tree from_instances(instances, 2);

  Scene by_hand;
  for (int which = 0; which < 2; ++which) {
    const glm::dmat4 m(which == 0 ? glm::mat4(1.0f) : mirrored);
    for (std::size_t t = 0; t < soup.triangle_count(); ++t) {
      glm::vec3 c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = glm::vec3(m * glm::dvec4(glm::dvec3(soup.positions[soup.indices[3 * t + static_cast<std::size_t>(k)]]), 1.0));
      if (which == 1) std::swap(c[1], c[2]);
      for (int k = 0; k < 3; ++k) {
        by_hand.indices.push_back(static_cast<std::uint32_t>(by_hand.positions.size()));
        by_hand.positions.push_back(c[k]);
      }
    }
  }
  const Tree reference(by_hand.mesh());
  CHECK(glm::determinant(glm::mat3(mirrored)) < 0.0f);
  CHECK(from_instances.stats().triangles == 2 * soup.triangle_count());
  CHECK_MSG(from_instances.corners() == reference.corners() && from_instances.fragments().size() == reference.fragments().size(),
            "instances: %zu fragments, by hand %zu", from_instances.fragments().size(), reference.fragments().size());
  bool same_triangles = true;
  for (std::size_t i = 0; same_triangles && i < reference.fragments().size(); ++i)
    same_triangles = from_instances.fragments()[i].triangle == reference.fragments()[i].triangle;
  CHECK(same_triangles);
  // A matrix that is not affine drops that instance's triangles, counted.
  cullkit::MeshInstance projective[1] = {{mesh32, glm::mat4(1.0f)}};
  projective[0].model[0][3] = 0.5f;
  const Tree dropped(projective, 1);
  CHECK(dropped.fragments().empty() && dropped.stats().dropped_bad_index == soup.triangle_count());
  const Tree none(static_cast<const cullkit::MeshInstance*>(nullptr), 0);
  CHECK(none.fragments().empty());
}

}  // namespace

int main() {
  test_instances();
  test_orders();
  test_fragments_tile_triangles();
  test_bad_input();
  test_deep_tree();
  test_threads_and_progress();
  return cullkit_test::report("test_bsp_bruteforce");
}
