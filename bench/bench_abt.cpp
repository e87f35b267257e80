// AdaptiveBinaryTree races (CSV on stdout through race.hpp; a summary of the key ratios on stderr).
//
//   cull_*   : frustum culling of 60,000 random boxes at ~38% and ~2% visible, and of the triangles
//              of a real scene; contestants: a branchless SoA brute-force scan (reference), Bullet's
//              btDbvt (optimizeTopDown, collideKDOP with the same six planes), cullkit's ABT built
//              by binning (default) and by seeded sampling (the seed paper's method).
//   build_*  : building over ~1M triangle boxes: Embree 3 rtcCommitScene at medium quality on one
//              thread (reference) vs the ABT (binning, sampling; one thread, and two threads).
//
// Every contestant writes the same output (indices of possibly visible boxes) into a reused vector.
//   ./build/release/bench/bench_abt            (CULLKIT_BENCH_SMOKE=1: tiny sizes)
#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include <cullkit/adaptive_binary_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "dbvt_peer.hpp"
#include "race.hpp"
#include "soa_scan.hpp"

using namespace cullkit;
using cullkit::bench::DbvtPeer;
using cullkit::bench::random_boxes;

namespace {


std::vector<Aabb> triangle_boxes(const support::Scene& s) {
  std::vector<Aabb> out;
  out.reserve(s.triangle_count());
  for (std::size_t t = 0; t < s.triangle_count(); ++t) {
    glm::vec3 p[3] = {};
    if (triangle_positions(s.mesh(), t, p)) out.push_back(merge(merge(Aabb{p[0], p[0]}, p[1]), p[2]));
  }
  return out;
}

struct Summary {
  std::string name;
  double abt_vs_soa, abt_vs_dbvt, sampling_vs_binning;
  double visible;
};
std::vector<Summary> summaries;

void cull_race(const std::string& name, const std::vector<Aabb>& boxes, const Frustum& f) {
  cullkit_bench::SoaBoxes soa(boxes);
  DbvtPeer dbvt(boxes);
  const AdaptiveBinaryTree<Aabb> abt(boxes.data(), boxes.size());
  AbtParams sp;
  sp.candidates = AbtCandidates::sampling;
  const AdaptiveBinaryTree<Aabb> abt_s(boxes.data(), boxes.size(), sp);
  std::vector<std::uint32_t> o1, o2, o3, o4;
  o1.reserve(boxes.size());
  o2.reserve(boxes.size());
  o3.reserve(boxes.size());
  o4.reserve(boxes.size());
  soa.cull(f, o1);
  dbvt.cull(f, o2);
  abt.cull(f, o3);
  abt_s.cull(f, o4);
  const double visible = double(o1.size()) / double(boxes.size());
  std::fprintf(stderr, "%s: %zu boxes, visible: soa %zu, btDbvt %zu, abt %zu, abt_sampling %zu (%.1f%%); abt nodes %u depth %u\n",
               name.c_str(), boxes.size(), o1.size(), o2.size(), o3.size(), o4.size(), 100.0 * visible,
               abt.stats().nodes, abt.stats().depth);
  const auto r = cullkit_bench::race(name, {{"soa_branchless_scan", [&] { soa.cull(f, o1); }},
                                            {"bullet_btdbvt_kdop", [&] { dbvt.cull(f, o2); }},
                                            {"cullkit_abt_binning", [&] { abt.cull(f, o3); }},
                                            {"cullkit_abt_sampling", [&] { abt_s.cull(f, o4); }}});
  summaries.push_back(Summary{name, r[2].median_ns / r[0].median_ns, r[2].median_ns / r[1].median_ns,
                              r[3].median_ns / r[2].median_ns, visible});
}

void build_race(const support::Scene& scene) {
  const MeshView<glm::vec3> mesh = scene.mesh();
  const std::size_t tris = scene.triangle_count();
  RTCDevice device = rtcNewDevice("threads=1");
  auto embree = [&] {
    RTCScene s = rtcNewScene(device);
    rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, scene.positions.data(), 0,
                               sizeof(glm::vec3), scene.positions.size());
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, scene.indices.data(), 0,
                               3 * sizeof(std::uint32_t), tris);
    rtcCommitGeometry(g);
    rtcAttachGeometry(s, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(s);
    rtcReleaseScene(s);
  };
  std::size_t nodes = 0;
  auto abt_with = [&](AbtCandidates c, unsigned threads) {
    return [&, c, threads] {
      AbtParams p;
      p.candidates = c;
      p.threads = threads;
      const AdaptiveBinaryTree<Aabb> t = make_triangle_tree(mesh, p);
      nodes = t.stats().nodes;
      cullkit_bench::keep(t);
    };
  };
  std::fprintf(stderr, "build: %zu triangles\n", tris);
  const auto r = cullkit_bench::race(
      "build_" + std::to_string(tris) + "_triangles",
      {{"embree_commit_medium_1thread", embree},
       {"cullkit_abt_binning_1thread", abt_with(AbtCandidates::binning, 1)},
       {"cullkit_abt_sampling_1thread", abt_with(AbtCandidates::sampling, 1)},
       {"cullkit_abt_binning_2threads", abt_with(AbtCandidates::binning, 2)}},
      5);
  std::fprintf(stderr, "build: abt binning / embree medium = %.3f, sampling / embree = %.3f (abt nodes %zu)\n",
               r[1].median_ns / r[0].median_ns, r[2].median_ns / r[0].median_ns, nodes);
  rtcReleaseDevice(device);
}

}  // namespace

int main() {
  const bool smoke = cullkit_bench::smoke();
  // 60,000 random boxes: the views of bench_frustum (~38% and ~2% visible).
  {
    const std::vector<Aabb> boxes = random_boxes(smoke ? 2000 : 60000);
    struct View {
      const char* name;
      float fov;
      glm::vec3 eye, target;
    };
    const View views[] = {{"cull_60k_wide_38pct", 80.0f, {0, 300, 0}, {0, 0, 1}},
                          {"cull_60k_narrow_2pct", 5.0f, {0, 20, 0}, {300, 20, 0}}};
    for (const View& v : views) {
      const Camera cam = support::make_camera(v.eye, v.target, v.fov, 1280, 720, 0.5f, 2000.0f);
      cull_race(v.name, boxes, frustum_of(cam));
    }
  }
  // Triangles of a real scene (the arena town when present; the generated city otherwise).
  {
    std::optional<support::Scene> scene;
    if (!smoke) {
      for (const std::string& f : support::real_scene_files())
        if (f == "lasdunasarena.obj") scene = support::load_obj(support::scenes_dir() + "/" + f);
    }
    if (!scene) scene = support::make_city(11, smoke ? 2 : 24);
    const std::vector<Aabb> boxes = triangle_boxes(*scene);
    const Aabb b = scene->bounds;
    const glm::vec3 c = b.center();
    // Street level: the scene's bounds hold far-away backdrop geometry, so stand at the median
    // triangle position, 2 units above the 5th percentile of heights, looking along the ground.
    std::vector<float> xs, ys, zs;
    for (const Aabb& t : boxes) {
      xs.push_back(t.center().x);
      ys.push_back(t.center().y);
      zs.push_back(t.center().z);
    }
    auto quantile = [](std::vector<float>& v, double q) {
      const auto k = static_cast<std::ptrdiff_t>(q * double(v.size() - 1));
      std::nth_element(v.begin(), v.begin() + k, v.end());
      return v[static_cast<std::size_t>(k)];
    };
    const glm::vec3 eye(quantile(xs, 0.5), quantile(ys, 0.05) + 2.0f, quantile(zs, 0.5));
    const Camera street = support::make_camera(eye, eye + glm::vec3(1, -0.05f, 0.3f), 70, 1280, 720, 0.1f,
                                               0.15f * glm::length(b.extent()));
    cull_race("cull_triangles_" + scene->name + "_street", boxes, frustum_of(street));
    const Camera over = support::make_camera(c + glm::vec3(0, b.extent().y + 0.3f * glm::length(b.extent()), 0.01f),
                                             c, 60, 1280, 720, 0.5f, 4.0f * glm::length(b.extent()));
    cull_race("cull_triangles_" + scene->name + "_overview", boxes, frustum_of(over));
  }
  // Build over ~1M triangles (90 x 90 city blocks).
  {
    const support::Scene city = support::make_city(5, smoke ? 2 : 90);  // ~1M triangles
    build_race(city);
  }
  std::fprintf(stderr, "\nsummary (time ratios, lower is better for the ABT):\n");
  for (const Summary& s : summaries)
    std::fprintf(stderr, "  %-44s visible %5.1f%%  abt/soa %.3f  abt/btDbvt %.3f  sampling/binning %.3f\n",
                 s.name.c_str(), 100.0 * s.visible, s.abt_vs_soa, s.abt_vs_dbvt, s.sampling_vs_binning);
  return 0;
}
