// bench_occlusion: OcclusionTree speed. (1) per-query ns and per-insertion us against the number of
// box occluders (10..1000), plain tree vs two-level top planes, insertion near-to-far and far-to-near
// (adversarial); (2) whole-scene culling of a generated city: frustum only (the ABT) vs frustum +
// occlusion with each seed refinement on and off; (3) the generated city culled with box occluders
// only and with polygon occluders added (occluder fusion). CSV (race.hpp) plus summary lines.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <cstdio>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"

using namespace cullkit;
using cullkit::support::Rng;

namespace {

std::vector<Aabb> city_boxes(int n, Rng& rng, float radius) {
  std::vector<Aabb> out;
  while (static_cast<int>(out.size()) < n) {
    const glm::vec3 c(rng.uniform(-radius, radius), 0.0f, rng.uniform(-radius, radius));
    if (std::max(std::fabs(c.x), std::fabs(c.z)) < 6.0f) continue;
    out.push_back(Aabb{c - glm::vec3(rng.uniform(1, 4), 0, rng.uniform(1, 4)),
                       c + glm::vec3(rng.uniform(1, 4), rng.uniform(3, 25), rng.uniform(1, 4))});
  }
  return out;
}

// Per-query latency: every query timed on its own (clock overhead, the fastest empty timing,
// subtracted), `passes` times over the whole set in order, so caches and branch predictors see the
// same mixed stream as in the race. Prints percentiles: the mean above hides a long tail (queries
// whose box straddles occluder boundaries split into pieces).
void query_latency(const OcclusionTree& tree, const std::vector<Aabb>& queries, int passes, const char* tag) {
  using clock = std::chrono::steady_clock;
  double overhead = 1e30;
  for (int i = 0; i < 2000; ++i) {
    const auto a = clock::now();
    const auto b = clock::now();
    overhead = std::min(overhead, std::chrono::duration<double, std::nano>(b - a).count());
  }
  std::vector<double> ns;
  ns.reserve(queries.size() * static_cast<std::size_t>(passes));
  int hidden = 0;
  for (int p = 0; p < passes; ++p) {
    for (const Aabb& q : queries) {
      const auto a = clock::now();
      hidden += tree.is_occluded(q) ? 1 : 0;
      const auto b = clock::now();
      ns.push_back(std::max(0.0, std::chrono::duration<double, std::nano>(b - a).count() - overhead));
    }
  }
  cullkit_bench::keep(hidden);
  std::sort(ns.begin(), ns.end());
  const auto at = [&ns](double f) { return ns[std::min(ns.size() - 1, static_cast<std::size_t>(f * ns.size()))]; };
  std::printf("# query latency, %s occluders: p10 %.0f ns, median %.0f ns, p90 %.0f ns, p99 %.0f ns "
              "(%zu timings, clock overhead %.0f ns subtracted)\n",
              tag, at(0.1), at(0.5), at(0.9), at(0.99), ns.size(), overhead);
}

void micro() {
  const bool smoke = cullkit_bench::smoke();
  const glm::vec3 eye(0.0f, 1.7f, 0.0f);
  const int counts[] = {10, 100, 1000};
  for (int n : counts) {
    if (smoke && n > 100) break;
    Rng rng(42u + n);
    std::vector<Aabb> occ = city_boxes(n, rng, 20.0f + 2.0f * std::sqrt(float(n)) * 4.0f);
    std::vector<Aabb> far_first = occ;
    std::sort(far_first.begin(), far_first.end(), [&](const Aabb& a, const Aabb& b) {
      return glm::length(a.center() - eye) > glm::length(b.center() - eye);
    });
    std::vector<Aabb> queries;
    for (int k = 0; k < (smoke ? 50 : 2000); ++k) {
      const glm::vec3 c(rng.uniform(-80, 80), rng.uniform(0, 4), rng.uniform(-80, 80));
      queries.push_back(Aabb{c - glm::vec3(0.4f), c + glm::vec3(0.4f)});
    }
    OcclusionParams top;
    top.azimuth_planes = 8;
    top.elevation_planes = 2;
    OcclusionTree plain_tree(eye), top_tree(eye, top), adv_plain(eye), adv_top(eye, top);
    for (auto& b : occ) plain_tree.insert_box_occluder(b), top_tree.insert_box_occluder(b);
    for (auto& b : far_first) adv_plain.insert_box_occluder(b), adv_top.insert_box_occluder(b);
    int hidden = 0;
    for (auto& q : queries) hidden += plain_tree.is_occluded(q);
    const char* tag = n == 10 ? "10" : n == 100 ? "100" : "1000";
    std::printf("# %d occluders: nodes plain %u (depth %u), top %u (depth %u); far-to-near plain depth %u, top "
                "depth %u; %d of %zu queries hidden\n",
                n, plain_tree.stats().nodes, plain_tree.stats().depth, top_tree.stats().nodes, top_tree.stats().depth,
                adv_plain.stats().depth, adv_top.stats().depth, hidden, queries.size());
    auto query_all = [&queries](const OcclusionTree& t) {
      return [&queries, &t] {
        int h = 0;
        for (auto& q : queries) h += t.is_occluded(q);
        cullkit_bench::keep(h);
      };
    };
    const auto qr = cullkit_bench::race(std::string("query_x") + std::to_string(queries.size()) + "_occ" + tag,
                                        {{"plain", query_all(plain_tree)},
                                         {"two_level", query_all(top_tree)},
                                         {"plain_far_to_near", query_all(adv_plain)},
                                         {"two_level_far_to_near", query_all(adv_top)}});
    for (auto& r : qr) std::printf("# query %s: %.1f ns per query\n", r.name.c_str(), r.median_ns / queries.size());
    query_latency(plain_tree, queries, smoke ? 1 : 20, tag);
    OcclusionTree t1(eye), t2(eye, top);
    auto insert_all = [&eye](OcclusionTree& t, const std::vector<Aabb>& boxes) {
      return [&eye, &t, &boxes] {
        t.reset(eye);
        for (auto& b : boxes) t.insert_box_occluder(b);
        cullkit_bench::keep(t.stats().nodes);
      };
    };
    const auto ir = cullkit_bench::race(std::string("insert_occ") + tag,
                                        {{"plain", insert_all(t1, occ)},
                                         {"two_level", insert_all(t2, occ)},
                                         {"plain_far_to_near", insert_all(t1, far_first)},
                                         {"two_level_far_to_near", insert_all(t2, far_first)}});
    for (auto& r : ir)
      std::printf("# insert %s: %.2f us for %d boxes (%.3f us each)\n", r.name.c_str(), r.median_ns / 1000.0, n,
                  r.median_ns / 1000.0 / n);
  }
}

// A street-level setting: N box occluders all in view (a 90-degree wedge in front of the eye, 8-120 m
// away, random order) and query boxes in the same wedge, so most occluders overlap others on screen.
void in_view() {
  const bool smoke = cullkit_bench::smoke();
  const glm::vec3 eye(0.0f, 1.7f, 0.0f);
  for (int n : {10, 100, 1000}) {
    if (smoke && n > 100) break;
    Rng rng(7u + n);
    const auto in_wedge = [&rng](float r0, float r1) {
      const float a = rng.uniform(-0.785f, 0.785f), d = rng.uniform(r0, r1);
      return glm::vec3(d * std::sin(a), 0.0f, -d * std::cos(a));
    };
    std::vector<Aabb> occ;
    while (static_cast<int>(occ.size()) < n) {
      const glm::vec3 c = in_wedge(8.0f, 120.0f);
      occ.push_back(Aabb{c - glm::vec3(rng.uniform(1, 4), 0, rng.uniform(1, 4)),
                         c + glm::vec3(rng.uniform(1, 4), rng.uniform(3, 25), rng.uniform(1, 4))});
    }
    std::vector<Aabb> queries;
    for (int k = 0; k < (smoke ? 50 : 2000); ++k) {
      const glm::vec3 c = in_wedge(5.0f, 140.0f) + glm::vec3(0.0f, rng.uniform(0, 4), 0.0f);
      queries.push_back(Aabb{c - glm::vec3(0.4f), c + glm::vec3(0.4f)});
    }
    OcclusionParams top;
    top.azimuth_planes = 8;
    top.elevation_planes = 2;
    OcclusionTree plain_tree(eye), top_tree(eye, top);
    for (auto& b : occ) plain_tree.insert_box_occluder(b), top_tree.insert_box_occluder(b);
    int hidden = 0;
    for (auto& q : queries) hidden += plain_tree.is_occluded(q);
    const std::string tag = std::to_string(n);
    std::printf("# in view, %d occluders: nodes %u (depth %u); %d of %zu queries hidden\n", n, plain_tree.stats().nodes,
                plain_tree.stats().depth, hidden, queries.size());
    const auto query_all = [&queries](const OcclusionTree& t) {
      return [&queries, &t] {
        int h = 0;
        for (auto& q : queries) h += t.is_occluded(q);
        cullkit_bench::keep(h);
      };
    };
    const auto qr = cullkit_bench::race("in_view_query_occ" + tag,
                                        {{"plain", query_all(plain_tree)}, {"two_level", query_all(top_tree)}});
    for (auto& r : qr)
      std::printf("# in view query %s: %.1f ns per query\n", r.name.c_str(), r.median_ns / queries.size());
    query_latency(plain_tree, queries, smoke ? 1 : 20, ("in view, " + tag).c_str());
    // Near to far is the order cull_with_occlusion inserts in (front-to-back walk).
    std::vector<Aabb> near_first = occ;
    std::sort(near_first.begin(), near_first.end(), [&](const Aabb& a, const Aabb& b) {
      return glm::length(a.center() - eye) < glm::length(b.center() - eye);
    });
    OcclusionTree t1(eye), t2(eye, top), sorted_tree(eye);
    for (auto& b : near_first) sorted_tree.insert_box_occluder(b);
    std::printf("# in view, %d occluders inserted near to far: nodes %u (depth %u)\n", n, sorted_tree.stats().nodes,
                sorted_tree.stats().depth);
    const auto insert_all = [&eye](OcclusionTree& t, const std::vector<Aabb>& boxes) {
      return [&eye, &boxes, &t] {
        t.reset(eye);
        for (auto& b : boxes) t.insert_box_occluder(b);
        cullkit_bench::keep(t.stats().nodes);
      };
    };
    const auto sq = cullkit_bench::race("in_view_query_near_to_far_occ" + tag, {{"plain", query_all(sorted_tree)}});
    std::printf("# in view query near-to-far tree: %.1f ns per query\n", sq.front().median_ns / queries.size());
    query_latency(sorted_tree, queries, smoke ? 1 : 20, ("in view near-to-far, " + tag).c_str());
    const auto ir = cullkit_bench::race("in_view_insert_occ" + tag,
                                        {{"plain", insert_all(t1, occ)},
                                         {"two_level", insert_all(t2, occ)},
                                         {"plain_near_to_far", insert_all(t1, near_first)},
                                         {"batch_insert_box_occluders", [&eye, &occ, &t1] {
                                            t1.reset(eye);
                                            t1.insert_box_occluders(occ.data(), occ.size());
                                            cullkit_bench::keep(t1.stats().nodes);
                                          }}});
    for (auto& r : ir)
      std::printf("# in view insert %s: %.2f us for %d boxes\n", r.name.c_str(), r.median_ns / 1000.0, n);
  }
}

void scene_cull() {
  const bool smoke = cullkit_bench::smoke();
  for (int blocks : {6, 18}) {
    if (smoke && blocks > 6) break;
    const support::Scene scene = support::make_city(3, smoke ? 2 : blocks);
    const std::vector<Aabb> bounds = scene.object_bounds();
    std::vector<std::uint8_t> is_box(scene.objects.size());
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
      is_box[i] = scene.objects[i].major_occluder && scene.objects[i].is_box;
    const AdaptiveBinaryTree<Aabb> abt(bounds.data(), bounds.size());
    const BoxOccluderSource source{bounds.data(), is_box.data()};
    Rng rng(5);
    std::vector<Camera> cams;
    const Aabb sb = scene.bounds;
    for (int i = 0; i < (smoke ? 2 : 32); ++i) {
      const glm::vec3 eye(rng.uniform(sb.min.x, sb.max.x), sb.min.y + 1.7f, rng.uniform(sb.min.z, sb.max.z));
      const glm::vec3 target(rng.uniform(sb.min.x, sb.max.x), sb.min.y + 1.7f, rng.uniform(sb.min.z, sb.max.z));
      cams.push_back(support::make_camera(eye, target, 60.0f, 1280, 720, 0.1f, 5000.0f));
    }
    std::vector<std::uint32_t> out;
    OcclusionTree tree(glm::vec3(0.0f));
    std::size_t sums[5] = {};
    auto run = [&](int mode) {
      return [&, mode] {
        for (const Camera& cam : cams) {
          const Frustum f = Frustum::from_matrix(cam.view_proj, cam.depth);
          if (mode == 0) {
            abt.cull(f, out);
          } else {
            OcclusionCullParams p;
            p.skip_clear_subtrees = mode == 1 || mode == 2;
            p.start_at_parent_node = mode == 1 || mode == 3;
            tree.reset(cam.eye);
            cull_with_occlusion(abt, f, tree, source, out, nullptr, p);
          }
          sums[mode] += out.size();
        }
      };
    };
    const auto res = cullkit_bench::race("city" + std::to_string(blocks) + "_cull_x" + std::to_string(cams.size()),
                                         {{"frustum_only", run(0)},
                                          {"occlusion_both_refinements", run(1)},
                                          {"occlusion_clear_skip_only", run(2)},
                                          {"occlusion_start_at_parent_only", run(3)},
                                          {"occlusion_no_refinement", run(4)}});
    const double reps = res.front().reps + 1;
    std::printf("# city %d blocks, %zu objects: mean objects kept per view: frustum %.1f, occlusion %.1f / %.1f / "
                "%.1f / %.1f (both / clear-skip / start-at-parent / none)\n",
                blocks, scene.objects.size(), sums[0] / reps / cams.size(), sums[1] / reps / cams.size(),
                sums[2] / reps / cams.size(), sums[3] / reps / cams.size(), sums[4] / reps / cams.size());
    for (auto& r : res) std::printf("# %s: %.1f us per view\n", r.name.c_str(), r.median_ns / 1000.0 / cams.size());
  }
}

// The generated city (make_city(1, 8), the cameras of bench_occlusion_table: street level, seed 11)
// culled with its buildings as box occluders, then with its other big surfaces (area >= (0.03 x the
// scene diagonal)^2, facing the eye: the ground and street tiles) added as polygon occluders, the
// rule of tests/occlusion/scene_cull.hpp. More occluders must not hide less: without fusion the
// polygons' seams cut the hidden region into pieces no query box can fit in whole. Prints the mean
// share of triangles kept, the frames where the polygons made it worse, and the time per frame.
void city_fusion() {
  const bool smoke = cullkit_bench::smoke();
  const support::Scene scene = support::make_city(1, smoke ? 3 : 8);
  const std::vector<Aabb> bounds = scene.object_bounds();
  std::vector<std::uint8_t> is_box(scene.objects.size());
  std::vector<std::vector<std::uint32_t>> big(scene.objects.size());
  const float big_edge = glm::length(scene.bounds.max - scene.bounds.min) * 0.03f;
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
    const auto& obj = scene.objects[o];
    is_box[o] = obj.major_occluder && obj.is_box;
    if (is_box[o]) continue;
    for (std::uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
      const glm::vec3 a = scene.positions[scene.indices[3 * t]], b = scene.positions[scene.indices[3 * t + 1]],
                      c = scene.positions[scene.indices[3 * t + 2]];
      if (0.5f * glm::length(glm::cross(b - a, c - a)) >= big_edge * big_edge) big[o].push_back(t);
    }
  }
  const AdaptiveBinaryTree<Aabb> abt(bounds.data(), bounds.size());
  const BoxOccluderSource boxes{bounds.data(), is_box.data()};
  const auto boxes_and_polygons = [&](std::uint32_t o, OcclusionTree& tree) {
    if (is_box[o]) return tree.insert_box_occluder(bounds[o]);
    for (std::uint32_t t : big[o]) {
      const glm::vec3 tri[3] = {scene.positions[scene.indices[3 * t]], scene.positions[scene.indices[3 * t + 1]],
                                scene.positions[scene.indices[3 * t + 2]]};
      if (glm::dot(glm::cross(tri[1] - tri[0], tri[2] - tri[0]), tree.eye() - tri[0]) > 0.0f)
        tree.insert_occluder(tri, 3);
    }
  };
  // The cameras of bench_occlusion_table's city row.
  Rng rng(11u);
  std::vector<Camera> cams;
  const Aabb sb = scene.bounds;
  const int wanted = smoke ? 3 : 100;
  for (int tries = 0; static_cast<int>(cams.size()) < wanted && tries < 1000 * wanted; ++tries) {
    const glm::vec3 eye(rng.uniform(sb.min.x, sb.max.x), sb.min.y + 1.7f, rng.uniform(sb.min.z, sb.max.z));
    bool near = false;
    for (const Aabb& b : bounds)
      near = near || (eye.x >= b.min.x - 0.5f && eye.x <= b.max.x + 0.5f && eye.y >= b.min.y - 0.5f &&
                      eye.y <= b.max.y + 0.5f && eye.z >= b.min.z - 0.5f && eye.z <= b.max.z + 0.5f);
    if (near) continue;
    const float yaw = rng.uniform(0.0f, 6.2831853f);
    const float pitch = rng.uniform(-3.0f, 9.0f) * (3.14159265f / 180.0f);
    const glm::vec3 dir(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
    cams.push_back(support::make_camera(eye, eye + dir, 60.0f, 640, 480, 0.1f, glm::length(sb.max - sb.min)));
  }
  const double total = static_cast<double>(scene.triangle_count());
  double kept[2] = {0, 0}, ms[2] = {0, 0}, nodes[2] = {0, 0};
  int worse = 0;
  std::vector<std::uint32_t> out;
  OcclusionTree tree(glm::vec3(0.0f));
  for (const Camera& cam : cams) {
    const Frustum f = Frustum::from_matrix(cam.view_proj, cam.depth);
    double frame[2] = {0, 0};
    for (int step = 0; step < 2; ++step) {  // alternate the contenders and their order frame by frame
      const int mode = (step + static_cast<int>(&cam - cams.data())) % 2;
      const auto t0 = std::chrono::steady_clock::now();
      tree.reset(cam.eye);
      if (mode == 0) cull_with_occlusion(abt, f, tree, boxes, out);
      else cull_with_occlusion(abt, f, tree, boxes_and_polygons, out);
      const auto t1 = std::chrono::steady_clock::now();
      ms[mode] += std::chrono::duration<double, std::milli>(t1 - t0).count();
      nodes[mode] += tree.stats().nodes;
      for (std::uint32_t o : out) frame[mode] += scene.objects[o].triangle_count;
      kept[mode] += frame[mode] / total;
    }
    worse += frame[1] > frame[0] ? 1 : 0;
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  std::printf("# city fusion (make_city(1, %d), %zu triangles, %zu cameras): triangles kept: boxes %.2f%%, "
              "boxes + polygons %.2f%%; polygons worse in %d frames; tree nodes %.0f / %.0f; %.3f / %.3f ms per "
              "frame\n",
              smoke ? 3 : 8, scene.triangle_count(), cams.size(), 100.0 * kept[0] / n, 100.0 * kept[1] / n, worse,
              nodes[0] / n, nodes[1] / n, ms[0] / n, ms[1] / n);
}

}  // namespace

int main() {
  city_fusion();
  micro();
  in_view();
  scene_cull();
  return 0;
}
