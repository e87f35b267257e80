// bench/bench_mesh_occlusion.cpp: MeshOcclusionCuller on walks through real and generated scenes,
// raced in one process against the frustum-only cull, the repository's box/polygon occluder rule
// (cull_with_occlusion over an OcclusionTree, as bench/occlusion_table.cpp builds it) and the exact
// floor (Embree casting the frame), with Embree's answer as the truth.
//
// Per scene, over the walk's cameras (single thread, one camera after another):
//   frustum %   triangles of the objects AdaptiveBinaryTree::cull(frustum) keeps, as a share of all.
//   old %       triangles kept by cull_with_occlusion: generated scenes insert their solid major
//               occluders as boxes (BoxOccluderSource); real scenes insert each visible object's big
//               front-facing triangles (area >= (0.03 x scene diagonal)^2) as polygons.
//   culler %    triangles kept by MeshOcclusionCuller::cull (default parameters).
//   visible %   triangles of the objects Embree sees: one ray per pixel centre at the bench
//               resolution, front faces only, between the near and far planes (embree_truth.hpp).
//   false culls (camera, object) pairs Embree sees that the culler (or the old rule) left out.
//   ms          per frame: median over the cameras, and the range (min - max). Each camera runs the
//               three culls alternately `reps` times and keeps each one's fastest; Embree casts the
//               frame once (one ray per pixel, one thread).
// Ratios are of medians within this run: culler / frustum, culler / old, Embree / culler.
//
// Usage: bench_mesh_occlusion [cameras=60] [width=1920] [height=1080] [reps=3] [flags]
// Flags (anywhere on the line):
//   --hash         the culler only (no Embree check, no peers): per scene, an FNV-1a hash of the kept
//                  sets over the cameras (each sorted), the kept share, and the cull time, median (min-max)
//                  of each camera's fastest of `reps`, in this thread's CPU time where the platform has
//                  it (a shared machine's preemption then does not count). Two builds with the same hash
//                  gave the same answers.
//   --phases       with --hash: also where the time of `cull` goes, per named step (an extra, separately
//                  timed pass with the step probes on; shares of that pass times the median above).
//   --scene=TEXT   only the scenes whose name contains TEXT.
//   --grid=WxH     the culler's grid size (default: MeshOcclusionParams's).
// CULLKIT_BENCH_SMOKE=1: the small generated city, 2 cameras, 320x180, 1 rep.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include <cullkit/occlusion_culling.hpp>

#include "../tests/mesh_occlusion/embree_truth.hpp"
#include "../tests/mesh_occlusion/walk_cameras.hpp"
#include "../tests/occlusion/scene_cull.hpp"
#include "race.hpp"
#include "cullkit/detail/mesh_occlusion/phase_times.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;
using occlusion_test::CullScene;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Spread {
  double median = 0, lo = 0, hi = 0;
};

Spread spread(std::vector<double> v) {
  Spread s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  s.lo = v.front();
  s.hi = v.back();
  return s;
}

struct Row {
  std::string scene;
  std::size_t triangles = 0, objects = 0, cameras = 0;
  double frustum = 0, old_rule = 0, culler = 0, visible = 0;  // mean triangle shares
  double occluders = 0, occluder_triangles = 0;                // culler's, mean per frame
  long culler_false = 0, old_false = 0;
  std::vector<double> frustum_ms, old_ms, culler_ms, embree_ms;
  double seconds = 0;
};

long missing(const std::vector<std::uint32_t>& kept, const std::vector<std::uint8_t>& seen) {
  std::vector<std::uint8_t> in(seen.size(), 0);
  for (std::uint32_t o : kept)
    if (o < in.size()) in[o] = 1;
  long n = 0;
  for (std::size_t o = 0; o < seen.size(); ++o) n += seen[o] && !in[o];
  return n;
}

/// The visible objects by Embree at the camera's resolution, one ray per pixel centre, and the
/// time that took.
std::vector<std::uint8_t> embree_frame(const CullScene& cs, const ObjectMap& map, const Camera& cam, double& ms) {
  const auto t0 = Clock::now();
  RaySet rays;
  rays.second_width = 0;
  rays.jitter = 0;
  auto seen = truly_visible(cs.embree, map, cam, rays);
  ms = ms_since(t0);
  return seen;
}

template <class Occluders>
Row measure(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, Occluders&& occluders,
            int reps) {
  const auto t_start = Clock::now();
  Row row;
  row.scene = name;
  row.triangles = cs.scene.triangle_count();
  row.objects = cs.scene.objects.size();
  row.cameras = cams.size();
  const ObjectMap map(cs.scene);
  const double total = static_cast<double>(std::max<std::size_t>(row.triangles, 1));
  const auto t_build = Clock::now();
  MeshOcclusionParams params;
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), map.objects.data(), map.objects.size(), params);
  std::fprintf(stderr, "%s: culler built in %.1f ms\n", name.c_str(), ms_since(t_build));
  MeshOcclusionContext context;
  std::vector<std::uint32_t> in_frustum, old_kept, kept;
  OcclusionTree tree(glm::vec3(0.0f));
  for (std::size_t c = 0; c < cams.size(); ++c) {
    const Camera& cam = cams[c];
    double best[3] = {1e300, 1e300, 1e300};
    for (int r = 0; r < reps; ++r) {
      auto t0 = Clock::now();
      const Frustum frustum = frustum_of(cam);
      cs.abt.cull(frustum, in_frustum);
      best[0] = std::min(best[0], ms_since(t0));
      t0 = Clock::now();
      tree.reset(cam.eye);
      cull_with_occlusion(cs.abt, frustum, tree, occluders, old_kept);
      best[1] = std::min(best[1], ms_since(t0));
      t0 = Clock::now();
      culler.cull(cam, context, kept);
      best[2] = std::min(best[2], ms_since(t0));
    }
    double embree_ms = 0;
    const auto seen = embree_frame(cs, map, cam, embree_ms);
    std::vector<std::uint32_t> visible;
    for (std::uint32_t o = 0; o < seen.size(); ++o)
      if (seen[o]) visible.push_back(o);
    row.frustum_ms.push_back(best[0]);
    row.old_ms.push_back(best[1]);
    row.embree_ms.push_back(embree_ms);
    row.frustum += triangles_of(map, in_frustum) / total;
    row.old_rule += triangles_of(map, old_kept) / total;
    row.visible += triangles_of(map, visible) / total;
    row.old_false += missing(old_kept, seen);
    row.culler_ms.push_back(best[2]);
    row.culler += triangles_of(map, kept) / total;
    row.occluders += static_cast<double>(context.stats().occluders_used);
    row.occluder_triangles += static_cast<double>(context.stats().occluder_triangles);
    const long fc = missing(kept, seen);
    if (fc)
      std::fprintf(stderr, "FALSE CULL: %s camera %zu (eye %.7g %.7g %.7g): %ld visible objects left out\n",
                   name.c_str(), c, cam.eye.x, cam.eye.y, cam.eye.z, fc);
    row.culler_false += fc;
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  row.frustum /= n;
  row.old_rule /= n;
  row.culler /= n;
  row.visible /= n;
  row.occluders /= n;
  row.occluder_triangles /= n;
  row.seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
  std::fprintf(stderr, "%s: %zu cameras, %.1f s\n", name.c_str(), cams.size(), row.seconds);
  return row;
}

std::string ms_text(const std::vector<double>& v) {
  if (v.empty()) return "n/a";
  const Spread s = spread(v);
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.3f (%.3f-%.3f)", s.median, s.lo, s.hi);
  return buf;
}

double ratio(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || b.empty()) return 0.0;
  const double d = spread(b).median;
  return d > 0 ? spread(a).median / d : 0.0;
}

void print(const std::vector<Row>& rows) {
  std::printf("\ncsv,scene,triangles,objects,cameras,visible_pct,frustum_pct,old_pct,culler_pct,culler_false_culls,"
              "old_false_culls,frustum_ms_median,old_ms_median,culler_ms_median,embree_ms_median,culler_over_frustum,"
              "culler_over_old,embree_over_culler\n");
  for (const Row& r : rows)
    std::printf("csv,%s,%zu,%zu,%zu,%.2f,%.2f,%.2f,%.2f,%ld,%ld,%.4f,%.4f,%.4f,%.2f,%.2f,%.2f,%.1f\n", r.scene.c_str(),
                r.triangles, r.objects, r.cameras, 100 * r.visible, 100 * r.frustum, 100 * r.old_rule, 100 * r.culler,
                r.culler_false, r.old_false, spread(r.frustum_ms).median, spread(r.old_ms).median,
                spread(r.culler_ms).median, spread(r.embree_ms).median, ratio(r.culler_ms, r.frustum_ms),
                ratio(r.culler_ms, r.old_ms), ratio(r.embree_ms, r.culler_ms));
  std::printf("\n| scene | triangles | objects | cameras | truly visible %% | frustum only %% | old cullkit %% | "
              "culler %% | culler false culls | old false culls | occluders / frame | occluder triangles / frame |\n"
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows)
    std::printf("| %s | %zu | %zu | %zu | %.2f | %.2f | %.2f | %.2f | %ld | %ld | %.0f | %.0f |\n", r.scene.c_str(),
                r.triangles, r.objects, r.cameras, 100 * r.visible, 100 * r.frustum, 100 * r.old_rule,
                100 * r.culler, r.culler_false, r.old_false, r.occluders, r.occluder_triangles);
  std::printf("\nms per frame, median (min-max) over the cameras, one thread:\n\n"
              "| scene | frustum only | old cullkit | culler | Embree frame | culler / frustum | culler / old | "
              "Embree / culler |\n|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const Row& r : rows)
    std::printf("| %s | %s | %s | %s | %s | %.2f | %.2f | %.1f |\n", r.scene.c_str(), ms_text(r.frustum_ms).c_str(),
                ms_text(r.old_ms).c_str(), ms_text(r.culler_ms).c_str(), ms_text(r.embree_ms).c_str(),
                ratio(r.culler_ms, r.frustum_ms), ratio(r.culler_ms, r.old_ms), ratio(r.embree_ms, r.culler_ms));
  std::fflush(stdout);
}

// ---- --hash / --phases: the culler alone, its answers as a hash and its time per step ----

/// This thread's CPU time in ms (wall time where POSIX thread clocks are missing).
double thread_ms() {
#if defined(CLOCK_THREAD_CPUTIME_ID)
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
#else
  return std::chrono::duration<double, std::milli>(Clock::now().time_since_epoch()).count();
#endif
}

struct Flags {
  bool hash = false, phases = false;
  std::string scene;
  int grid_width = 0, grid_height = 0;
};

void culler_only(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, int reps,
                 const Flags& flags) {
  namespace mo = cullkit::detail::mesh_occlusion;
  const ObjectMap map(cs.scene);
  MeshOcclusionParams params;
  if (flags.grid_width > 0) {
    params.grid_width = flags.grid_width;
    params.grid_height = flags.grid_height;
  }
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), map.objects.data(), map.objects.size(), params);
  MeshOcclusionContext context;
  std::vector<std::uint32_t> kept;
  std::vector<double> ms;
  std::uint64_t hash = 1469598103934665603ull;
  double share = 0, occluder_triangles = 0;
  std::size_t pairs = 0;
  const double total = static_cast<double>(std::max<std::size_t>(cs.scene.triangle_count(), 1));
  for (const Camera& cam : cams) {
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
      const double t0 = thread_ms();
      culler.cull(cam, context, kept);
      best = std::min(best, thread_ms() - t0);
    }
    ms.push_back(best);
    std::sort(kept.begin(), kept.end());
    for (std::uint32_t o : kept) hash = (hash ^ o) * 1099511628211ull;
    hash = (hash ^ 0xffffffffull) * 1099511628211ull;
    pairs += kept.size();
    share += triangles_of(map, kept) / total;
    occluder_triangles += static_cast<double>(context.stats().occluder_triangles);
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  std::printf("hash,%s,%dx%d,%016llx,kept_pairs=%zu,kept_pct=%.3f,occluder_triangles=%.0f,culler_ms=%s\n", name.c_str(),
              params.grid_width, params.grid_height, static_cast<unsigned long long>(hash), pairs, 100 * share / n,
              occluder_triangles / n, ms_text(ms).c_str());
  if (!flags.phases) return;
  mo::PhaseTimes& times = mo::phase_times();
  times = mo::PhaseTimes{};
  times.enabled = true;
  for (const Camera& cam : cams)
    for (int r = 0; r < reps; ++r) culler.cull(cam, context, kept);
  times.enabled = false;
  static const char* const names[mo::phase_count] = {"frustum walk", "object boxes", "occluder choice",
                                                     "triangle setup and sort", "vertex projection", "bands",
                                                     "depths", "counts", "edge marking", "band ends",
                                                     "finish", "object tests"};
  std::uint64_t sum = 0;
  for (std::uint64_t t : times.ticks) sum += t;
  const double median = spread(ms).median;
  for (int p = 0; p < mo::phase_count; ++p) {
    // The triangle setup's time includes the vertex projection it calls: shown apart.
    const std::uint64_t t = p == mo::phase_gather ? times.ticks[p] - times.ticks[mo::phase_project] : times.ticks[p];
    const double part = sum ? static_cast<double>(t) / static_cast<double>(sum) : 0.0;
    std::printf("phase,%s,%s,%.1f%%,%.3f ms\n", name.c_str(), names[p], 100 * part, part * median);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool smoke = cullkit_bench::smoke();
  int cameras = smoke ? 2 : 60, width = smoke ? 320 : 1920, height = smoke ? 180 : 1080, reps = smoke ? 1 : 3;
  int* slots[4] = {&cameras, &width, &height, &reps};
  Flags flags;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0) {
      if (arg == "--hash") flags.hash = true;
      else if (arg == "--phases") flags.hash = flags.phases = true;
      else if (arg.rfind("--scene=", 0) == 0) flags.scene = arg.substr(8);
      else if (arg.rfind("--grid=", 0) == 0 && std::sscanf(arg.c_str() + 7, "%dx%d", &flags.grid_width, &flags.grid_height) == 2 &&
               flags.grid_width > 0 && flags.grid_height > 0) {
      } else {
        std::fprintf(stderr, "unknown flag %s\n", arg.c_str());
        return 2;
      }
      continue;
    }
    if (positional >= 4) continue;
    const int v = std::atoi(argv[i]);
    if (v <= 0) {
      std::fprintf(stderr, "usage: %s [cameras=60] [width=1920] [height=1080] [reps=3]\n", argv[0]);
      return 2;
    }
    *slots[positional++] = v;
  }
  std::printf("%d walk cameras per scene, %dx%d, %d alternating reps per camera, one thread.\n", cameras, width, height,
              reps);
  const auto t_all = Clock::now();
  std::vector<Row> rows;
  const auto run = [&](const std::string& name, support::Scene scene, std::uint64_t seed) {
    if (name.find(flags.scene) == std::string::npos) return;
    if (flags.hash) {
      const CullScene cs(std::move(scene));
      const auto cams = walk(walk_spec(name, cs.scene, cs.embree, seed), cs.scene, cs.embree, cameras, 4, width, height,
                             seed + 1);
      culler_only(name, cs, cams, reps, flags);
      return;
    }
    const bool generated = name == "city" || name == "office";
    const CullScene cs(std::move(scene));
    const WalkSpec spec = walk_spec(name, cs.scene, cs.embree, seed);
    const auto cams = walk(spec, cs.scene, cs.embree, cameras, 4, width, height, seed + 1);
    if (generated) {
      const BoxOccluderSource source{cs.bounds.data(), cs.box_occluder.data()};
      rows.push_back(measure(name, cs, cams, source, reps));
    } else {
      rows.push_back(measure(name, cs, cams, [&](std::uint32_t o, OcclusionTree& t) { cs.insert_occluders(o, t); }, reps));
    }
  };
  if (smoke) {
    run("city", support::make_city(1, 3), 11);
  } else {
    run("city", support::make_city(1, 8), 11);
    run("office", support::make_office(1, 10, 8), 13);
    std::uint64_t seed = 101;
    for (const auto& file : support::real_scene_files()) {
      if (file.find(flags.scene) == std::string::npos) {
        ++seed;  // the other scenes keep their cameras
        continue;
      }
      auto s = support::load_obj(support::scenes_dir() + "/" + file);
      if (!s) {
        std::fprintf(stderr, "%s: could not be loaded, skipped\n", file.c_str());
        continue;
      }
      run(file, std::move(*s), seed++);
    }
  }
  if (flags.hash) return 0;
  print(rows);
  long false_culls = 0;
  for (const Row& r : rows) false_culls += r.culler_false;
  std::printf("\nculler false culls in total: %ld; wall time %.1f s\n", false_culls,
              std::chrono::duration<double>(Clock::now() - t_all).count());
  return false_culls == 0 ? 0 : 1;
}
