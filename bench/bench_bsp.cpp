// bench_bsp: BspTree on the real scenes and generated ones.
//  1. build: triangles, fragments per triangle, nodes, depth, build seconds with 1 thread and with
//     all hardware threads (the same tree either way).
//  2. splitter choice (--splitters): fragments per triangle and build time for candidate counts and
//     cut weights, on the scenes up to 100k triangles.
//  3. per frame: back_to_front from eyes inside and outside the scene, raced against what a renderer
//     does without a BSP: order_back_to_front (radix) and std::sort of the triangles by the distance
//     of their centroids from the eye (each computes the distances itself). Race CSV (median, ratio).
// Flags: --splitters, --scene NAME (only that real scene, e.g. fzk_haus.obj), --no-real,
// --epsilon E (BspParams::epsilon for every build), --no-frames (builds only).
// CULLKIT_BENCH_SMOKE=1: a small generated office only.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <cullkit/bsp_tree.hpp>
#include <cullkit/depth_sort.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"

namespace {

using cullkit::support::Scene;
using Tree = cullkit::BspTree<glm::vec3>;

void build_row(const Scene& scene, unsigned threads, const cullkit::BspParams& base, const char* label) {
  cullkit::BspParams params = base;
  params.threads = threads;
  const Tree tree(scene.mesh(), params);
  const auto& s = tree.stats();
  const std::size_t kept = s.triangles - s.dropped_bad_index - s.dropped_non_finite - s.dropped_degenerate;
  std::printf("build,%s,%s,%u,%zu,%zu,%zu,%.3f,%zu,%zu,%.3f\n", scene.name.c_str(), label, threads, s.triangles, kept,
              s.fragments, double(s.fragments) / double(std::max<std::size_t>(1, kept)), s.nodes, s.depth, s.seconds);
  std::fflush(stdout);
}

void frame_race(const Scene& scene) {
  const Tree tree(scene.mesh());
  const cullkit::Aabb b = scene.bounds;
  const glm::vec3 centre = (b.min + b.max) * 0.5f;
  const glm::vec3 size = b.max - b.min;
  const glm::vec3 eyes[2] = {centre + glm::vec3(0.1f, 0.05f, 0.13f) * size,  // inside
                             centre + glm::vec3(0.9f, 0.6f, 0.7f) * size};   // outside
  const std::size_t nt = scene.triangle_count();
  std::vector<glm::vec3> centroids(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* i = scene.indices.data() + 3 * t;
    centroids[t] = (scene.positions[i[0]] + scene.positions[i[1]] + scene.positions[i[2]]) / 3.0f;
  }
  std::vector<std::uint32_t> order, sort_order;
  std::vector<float> depth(nt);
  cullkit::DepthSortScratch scratch;
  std::vector<std::pair<float, std::uint32_t>> pairs(nt);
  for (int e = 0; e < 2; ++e) {
    const glm::vec3 eye = eyes[e];
    cullkit_bench::race(
        "frame_" + scene.name + (e == 0 ? "_inside" : "_outside"),
        {{"bsp_back_to_front", [&] {
            tree.back_to_front(eye, order);
            cullkit_bench::keep(order[0]);
          }},
         {"radix_centroid_sort", [&] {
            for (std::size_t t = 0; t < nt; ++t) {
              const glm::vec3 d = centroids[t] - eye;
              depth[t] = d.x * d.x + d.y * d.y + d.z * d.z;
            }
            cullkit::order_back_to_front(depth.data(), nt, sort_order, scratch);
            cullkit_bench::keep(sort_order[0]);
          }},
         {"std_sort_centroid", [&] {
            for (std::size_t t = 0; t < nt; ++t) {
              const glm::vec3 d = centroids[t] - eye;
              pairs[t] = {d.x * d.x + d.y * d.y + d.z * d.z, static_cast<std::uint32_t>(t)};
            }
            std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& x) { return a.first > x.first; });
            cullkit_bench::keep(pairs[0]);
          }}},
        cullkit_bench::smoke() ? 2 : 21);
    std::printf("frame_info,%s,%s,%zu fragments,%zu triangles\n", scene.name.c_str(), e == 0 ? "inside" : "outside",
                tree.fragments().size(), nt);
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool splitters = false, real = true, frames = true;
  cullkit::BspParams defaults;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--splitters") == 0) splitters = true;
    if (std::strcmp(argv[i], "--no-real") == 0) real = false;
    if (std::strcmp(argv[i], "--no-frames") == 0) frames = false;
    if (std::strcmp(argv[i], "--scene") == 0 && i + 1 < argc) only = argv[++i];
    if (std::strcmp(argv[i], "--epsilon") == 0 && i + 1 < argc) defaults.epsilon = std::strtof(argv[++i], nullptr);
  }
  std::vector<Scene> scenes;
  if (cullkit_bench::smoke()) {
    scenes.push_back(cullkit::support::make_office(1, 2, 2));
    scenes.back().name = "office_2x2";
  } else {
    if (only.empty()) {
      scenes.push_back(cullkit::support::make_office(1, 10, 8));
      scenes.back().name = "office_10x8";
      scenes.push_back(cullkit::support::make_city(1, 8));
      scenes.back().name = "city_8";
    }
    if (real) {
      for (const auto& f : cullkit::support::real_scene_files()) {
        if (!only.empty() && f != only) continue;
        auto s = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + f);
        if (!s) continue;
        s->name = f;
        scenes.push_back(std::move(*s));
      }
    }
  }
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  std::printf("build,scene,params,threads,triangles,kept,fragments,fragments_per_triangle,nodes,depth,seconds\n");
  for (const auto& scene : scenes) {
    build_row(scene, 1, defaults, "default");
    if (hw > 1 && !cullkit_bench::smoke()) build_row(scene, hw, defaults, "default");
  }
  if (splitters) {
    struct Variant {
      const char* label;
      unsigned candidates;
      float split_weight;
    };
    const Variant variants[] = {{"first_polygon", 1, 8}, {"c4_w8", 4, 8}, {"c16_w2", 16, 2},
                                {"c16_w8", 16, 8},       {"c16_w32", 16, 32}, {"c64_w8", 64, 8}};
    for (const auto& scene : scenes) {
      if (scene.triangle_count() > 100000) continue;
      for (const auto& v : variants) {
        cullkit::BspParams p = defaults;
        p.candidates = v.candidates;
        p.split_weight = v.split_weight;
        build_row(scene, hw, p, v.label);
      }
    }
  }
  if (frames)
    for (const auto& scene : scenes) frame_race(scene);
  return 0;
}
