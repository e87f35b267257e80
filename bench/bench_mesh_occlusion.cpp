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
//   --reasons      also says why the culler keeps what Embree does not see (see `Reasons`; not with --hash).
//   --hash         the culler only (no Embree check, no peers): per scene, an FNV-1a hash of the kept
//                  sets over the cameras (each sorted), the kept share, and the cull time, median (min-max)
//                  of each camera's fastest of `reps`, in this thread's CPU time where the platform has
//                  it (a shared machine's preemption then does not count). Two builds with the same hash
//                  gave the same answers.
//                  Where the time of `cull` goes: run `perf record -g` on a --hash run (the library
//                  carries no timers of its own).
//   --moc          the culler against Intel's Masked Occlusion Culling (built when CMake's CULLKIT_MOC_DIR
//                  names its sources; otherwise the flag says so and exits), alternately per camera, best
//                  of `reps` each, this thread's CPU time. MOC per frame, as the acceptance race runs it:
//                  ClearBuffer; the frustum-culled objects (AdaptiveBinaryTree) sorted near to far by their
//                  boxes' nearest clip w; all their triangles in one RenderTriangles at the bench
//                  resolution (CLIP_PLANE_ALL, back faces culled, AVX2 at most); TestRect of each object's
//                  projected box (a box reaching the near plane is kept). MOC's time is all of that; the
//                  culler's is `cull` (its own frustum walk included). Per scene: both medians (min-max),
//                  the ratio of medians and both kept shares of the scene's triangles.
//   --threads=N    the culler alone with one thread and with N (N >= 2, through the library's pool),
//                  alternately per camera, best of `reps` each, in wall time: per scene, both answers'
//                  hashes and whether they are the same, both medians (min-max), the ratio of the medians
//                  and of the sums over the cameras, and the N-thread cull's CPU time per frame (all
//                  threads). Then `hot_ratio`: the same N-thread cull through a TaskRunner whose
//                  threads never sleep (an engine's job system mid-frame), over the one-thread time
//                  (meaningful for N up to the cores: its threads spin).
//   --scene=TEXT   only the scenes whose name contains TEXT (each scene keeps the cameras of a full run).
//   --grid=WxH     the culler's grid size; overrides GW and GH.
//   --split-edges=LEN  the real scenes with every edge longer than LEN (scene units) split at its midpoint,
//                  until none is (a conforming subdivision: both triangles of an edge split it at the same
//                  new vertex, so no crack or T-junction appears). The same surfaces in more, smaller
//                  triangles: what an occluder's depth extent costs the culler.
// The environment variables GW, GH, BUDGET, RATIO, MINFRAC, CELLS_PER_TRIANGLE, WIDTH_CELLS, PATCH, OBJTRI and TJUNCTIONS
// override the culler's parameters (grid size, occluder triangle budget, depth band ratio, occluder size floor,
// occluder cells per triangle, occluder width in cells, patch size, triangle-test patch size, T-junction cuts 0/1) in every mode, for measuring alternatives without rebuilding;
// --grid, given too, wins over GW and GH.
//   --engine       an engine frame's parts instead (see `engine_frame`): see-through objects (the
//                  generated scenes with glass panes, fences and foliage cards added; oacmpdm9 with its
//                  own flags), the cost of a moving occluder per triangle against the same wall static,
//                  moving occluders along the walk, and is_hidden per box (median and 99th percentile).
// CULLKIT_BENCH_SMOKE=1: the small generated city, 2 cameras, 320x180, 1 rep.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>

#include <cullkit/occlusion_culling.hpp>

#include "../tests/mesh_occlusion/embree_truth.hpp"
#include "../tests/mesh_occlusion/frame_truth.hpp"
#include "../tests/mesh_occlusion/walk_cameras.hpp"
#include "../tests/occlusion/scene_cull.hpp"
#include "race.hpp"
#if CULLKIT_BENCH_MOC
#include "moc_peer.hpp"
#endif

using namespace cullkit;
using namespace mesh_occlusion_test;
using occlusion_test::CullScene;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

/// The culler's construction time and what its T-junction cuts did (stderr).
void print_build(const std::string& name, const MeshOcclusionBuildStats& b, double ms) {
  std::fprintf(stderr, "%s: culler built in %.1f ms; T-junctions: %zu corners on unpaired edges, %zu triangles cut into %zu more parts; %zu shared edges\n",
               name.c_str(), ms, b.tjunction_corners, b.triangles_cut, b.triangle_parts_added, b.shared_edges);
}

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
  double seconds = 0, build_ms = 0;
  bool has_reasons = false;
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

/// Why the culler keeps objects that Embree does not see, measured by idealised runs of the same
/// algorithm (detail level, so the grid can be read back). Shares of the scene's triangles, summed
/// over the cameras (divided at the end). "Cumulative": each kept-but-unseen object is charged to
/// the first of these steps that hides it, each step keeping the ones before:
///   near    its box reaches through the near plane (hidden only part by part, see object tests);
///   supply  hidden once every in-frustum object occludes (no budget, no size floor, no object cap);
///   depth   then hidden with one band per distinct depth (depth_band_ratio = 0);
///   grid    then hidden on a 4x finer grid (1024 x 576 cells);
///   box     then hidden when tested with its own front-facing triangles instead of its box;
///   other   none of these: seams that do not fuse (cracks, overlapping parts), gaps between
///           pixel centres, the part of an occluder within the clipping margin of the near plane,
///           back faces; or covered cells whose depth bound lies beyond the object. Split by the
///           cells that fail the idealised triangle test: `other_open` when some of them is not
///           covered at all, `other_depth` when all are covered but behind a bound too far.
/// "Alone": each of supply, depth, grid, box applied on its own to the default culler.
struct Reasons {
  double excess = 0, near = 0, supply = 0, depth = 0, grid = 0, box = 0, other = 0, other_open = 0, other_depth = 0;
  double alone_supply = 0, alone_depth = 0, alone_grid = 0, alone_box = 0;
};

namespace dmo = cullkit::detail::mesh_occlusion;

class ReasonProbe {
 public:
  ReasonProbe(const support::Scene& scene, const ObjectMap& map, const MeshOcclusionParams& params)
      : scene_(scene), map_(map), base_(params) {
    const auto mesh = scene.mesh();
    dmo::build_index(
        index_, scene.triangle_count(),
        [&mesh](std::size_t t, glm::vec3 p[3]) { return triangle_positions<VertexTraits<glm::vec3>>(mesh, t, p); },
        map.objects.data(), map.objects.size(), AbtParams{}, dmo::sanitize(params).patch_triangles,
        params.cut_tjunctions);
    supply_ = dmo::sanitize(base_);
    supply_.occluder_triangle_budget = 0xffffffffu;
    supply_.max_occluder_objects = 0xffffffffu;
    supply_.min_occluder_screen_fraction = 0.0f;
    supply_.min_occluder_cells_per_triangle = 0.0f;
    supply_.min_occluder_width_cells = 0.0f;
    depth_ = dmo::sanitize(base_);
    depth_.depth_band_ratio = 0.0f;
    fine_ = dmo::sanitize(base_);
    fine_.grid_width *= 4;
    fine_.grid_height *= 4;
    fine_ = dmo::sanitize(fine_);
    supply_depth_ = supply_;
    supply_depth_.depth_band_ratio = 0.0f;
    all_ = supply_depth_;
    all_.grid_width = fine_.grid_width;
    all_.grid_height = fine_.grid_height;
  }

  /// Adds this camera's breakdown of `kept` objects that `seen` does not list.
  void add(const Camera& cam, const std::vector<std::uint32_t>& kept, const std::vector<std::uint8_t>& seen,
           Reasons& r) {
    const double total = static_cast<double>(std::max<std::size_t>(scene_.triangle_count(), 1));
    std::vector<std::uint8_t> hid_supply, hid_depth, hid_fine, hid_sd, hid_all;
    run(cam, supply_, hid_supply);
    run(cam, depth_, hid_depth);
    run(cam, fine_, hid_fine);
    run(cam, supply_depth_, hid_sd);
    run(cam, all_, hid_all);  // leaves s_ with the finest grid for the triangle test
    dmo::Scratch& fine_scratch = s_;
    dmo::Scratch base_scratch;
    std::vector<std::uint32_t> out;
    dmo::cull(index_, dmo::sanitize(base_), cam, base_scratch, out);
    for (std::uint32_t o : kept) {
      if (o >= seen.size() || seen[o]) continue;
      const double share = map_.triangle_count[o] / total;
      r.excess += share;
      const bool box_alone = triangles_hidden(cam, base_scratch, o);
      r.alone_supply += hid_supply[o] ? share : 0.0;
      r.alone_depth += hid_depth[o] ? share : 0.0;
      r.alone_grid += hid_fine[o] ? share : 0.0;
      r.alone_box += box_alone ? share : 0.0;
      const dmo::BoxView b = dmo::project_box(fine_scratch.view, index_.bounds[o]);
      if (!b.usable) r.near += share;
      else if (hid_supply[o]) r.supply += share;
      else if (hid_sd[o]) r.depth += share;
      else if (hid_all[o]) r.grid += share;
      else if (triangles_hidden(cam, fine_scratch, o)) r.box += share;
      else {
        r.other += share;
        (some_cell_open(fine_scratch, o) ? r.other_open : r.other_depth) += share;
      }
    }
  }

 private:
  // hidden[o] = 1 when the culler with `p` leaves object o out.
  void run(const Camera& cam, const MeshOcclusionParams& p, std::vector<std::uint8_t>& hidden) {
    std::vector<std::uint32_t> out;
    dmo::cull(index_, p, cam, s_, out);
    hidden.assign(map_.objects.size(), 1);
    for (std::uint32_t o : out)
      if (o < hidden.size()) hidden[o] = 0;
  }

  // True when every front-facing triangle of object o, tested with its own screen rectangle at its
  // own nearest depth against the grid `s` was left with, is hidden.
  bool triangles_hidden(const Camera& cam, const dmo::Scratch& s, std::uint32_t o) const {
    (void)cam;
    if (!s.view.enabled) return false;
    const auto& so = scene_.objects[o];
    for (std::uint32_t t = so.first_triangle; t < so.first_triangle + so.triangle_count; ++t) {
      double x[3], y[3], w[3];
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = scene_.positions[scene_.indices[3 * std::size_t(t) + std::size_t(k)]];
        const dmo::Projected q = s.view.project(p.x, p.y, p.z);
        if (!q.usable) return false;
        x[k] = q.x;
        y[k] = q.y;
        w[k] = q.w;
      }
      const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
      if (area2 * s.view.orient < 0.0) continue;  // a back face is never seen
      const dmo::CellRect rect = s.grid.cells_of(std::min({x[0], x[1], x[2]}), std::min({y[0], y[1], y[2]}),
                                                 std::max({x[0], x[1], x[2]}), std::max({y[0], y[1], y[2]}));
      const double w_min = std::min({w[0], w[1], w[2]});
      const float threshold = static_cast<float>((1.0 / w_min) * (1.0 + 0x1p-20));
      if (!rect.empty() && !(std::isfinite(threshold) && s.grid.all_nearer(rect, threshold))) return false;
    }
    return true;
  }

  // True when some cell that fails the triangle test of object o (as in triangles_hidden) is not
  // covered at all; false when every such cell is covered, behind a depth bound too far.
  bool some_cell_open(const dmo::Scratch& s, std::uint32_t o) const {
    if (!s.view.enabled) return true;
    const auto& so = scene_.objects[o];
    for (std::uint32_t t = so.first_triangle; t < so.first_triangle + so.triangle_count; ++t) {
      double x[3], y[3], w[3];
      bool usable = true;
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = scene_.positions[scene_.indices[3 * std::size_t(t) + std::size_t(k)]];
        const dmo::Projected q = s.view.project(p.x, p.y, p.z);
        usable = usable && q.usable;
        x[k] = q.x;
        y[k] = q.y;
        w[k] = q.w;
      }
      if (!usable) return true;
      const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
      if (area2 * s.view.orient < 0.0) continue;
      const dmo::CellRect rect = s.grid.cells_of(std::min({x[0], x[1], x[2]}), std::min({y[0], y[1], y[2]}),
                                                 std::max({x[0], x[1], x[2]}), std::max({y[0], y[1], y[2]}));
      const float threshold = static_cast<float>((1.0 / std::min({w[0], w[1], w[2]})) * (1.0 + 0x1p-20));
      if (rect.empty() || !std::isfinite(threshold) || s.grid.all_nearer(rect, threshold)) continue;
      for (int j = rect.y0; j <= rect.y1; ++j)
        for (int i = rect.x0; i <= rect.x1; ++i)
          if (!s.grid.all_nearer(dmo::CellRect{i, j, i, j}, 0.0f)) return true;
    }
    return false;
  }

  const support::Scene& scene_;
  const ObjectMap& map_;
  MeshOcclusionParams base_, supply_, depth_, fine_, supply_depth_, all_;
  dmo::MeshIndex index_;
  dmo::Scratch s_;
};

template <class Occluders>
Row measure(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, Occluders&& occluders,
            int reps, const MeshOcclusionParams& params, Reasons* reasons) {
  const auto t_start = Clock::now();
  Row row;
  row.scene = name;
  row.triangles = cs.scene.triangle_count();
  row.objects = cs.scene.objects.size();
  row.cameras = cams.size();
  const ObjectMap map(cs.scene);
  const double total = static_cast<double>(std::max<std::size_t>(row.triangles, 1));
  const auto t_build = Clock::now();
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), map.objects.data(), map.objects.size(), params);
  row.build_ms = ms_since(t_build);
  print_build(name, culler.stats(), row.build_ms);
  std::unique_ptr<ReasonProbe> probe;
  if (reasons) probe = std::make_unique<ReasonProbe>(cs.scene, map, params);
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
    if (probe) probe->add(cam, kept, seen, *reasons);
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  row.frustum /= n;
  row.old_rule /= n;
  row.culler /= n;
  row.visible /= n;
  row.occluders /= n;
  row.occluder_triangles /= n;
  if (reasons) {
    double* fields[] = {&reasons->excess,       &reasons->near,        &reasons->supply,      &reasons->depth,
                        &reasons->grid,         &reasons->box,         &reasons->other,       &reasons->other_open,
                        &reasons->other_depth,  &reasons->alone_supply, &reasons->alone_depth, &reasons->alone_grid,
                        &reasons->alone_box};
    for (double* f : fields) *f /= n;
  }
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

/// Parameters from the environment (for measuring alternatives without rebuilding): GW, GH,
/// BUDGET, RATIO, MINFRAC, CELLS_PER_TRIANGLE, WIDTH_CELLS (min_occluder_width_cells), PATCH (patch_triangles), OBJTRI (object_test_triangles), TJUNCTIONS
/// (cut_tjunctions: 0 or 1).
MeshOcclusionParams params_from_environment() {
  MeshOcclusionParams params;
  if (const char* v = std::getenv("GW")) params.grid_width = std::atoi(v);
  if (const char* v = std::getenv("GH")) params.grid_height = std::atoi(v);
  if (const char* v = std::getenv("BUDGET")) params.occluder_triangle_budget = static_cast<std::uint32_t>(std::atol(v));
  if (const char* v = std::getenv("RATIO")) params.depth_band_ratio = static_cast<float>(std::atof(v));
  if (const char* v = std::getenv("MINFRAC")) params.min_occluder_screen_fraction = static_cast<float>(std::atof(v));
  if (const char* v = std::getenv("CELLS_PER_TRIANGLE")) params.min_occluder_cells_per_triangle = static_cast<float>(std::atof(v));
  if (const char* v = std::getenv("WIDTH_CELLS")) params.min_occluder_width_cells = static_cast<float>(std::atof(v));
  if (const char* v = std::getenv("PATCH")) params.patch_triangles = static_cast<std::uint32_t>(std::atol(v));
  if (const char* v = std::getenv("OBJTRI")) params.object_test_triangles = static_cast<std::uint32_t>(std::atol(v));
  if (const char* v = std::getenv("TJUNCTIONS")) params.cut_tjunctions = std::atoi(v) != 0;
  if (const char* v = std::getenv("LAYERS")) params.patch_layers = std::atoi(v) != 0;
  return params;
}

void print_reasons(const std::vector<Row>& rows, const std::vector<Reasons>& reasons) {
  std::printf("\nkept but unseen (excess), by reason, %% of the scene's triangles, mean per camera; cumulative "
              "(first idealised step that hides it) and each step alone:\n\n"
              "| scene | culler | visible | excess | near plane | (a) supply | (c) depth bands | (b) grid | "
              "(d) box | other | alone: supply | depth | grid | box |\n"
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].has_reasons) continue;
    const Reasons& r = reasons[i];
    std::printf("| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n",
                rows[i].scene.c_str(), 100 * rows[i].culler, 100 * rows[i].visible, 100 * r.excess, 100 * r.near,
                100 * r.supply, 100 * r.depth, 100 * r.grid, 100 * r.box, 100 * r.other, 100 * r.alone_supply,
                100 * r.alone_depth, 100 * r.alone_grid, 100 * r.alone_box);
  }
  std::printf("\n\"other\" by the cells that fail the idealised triangle test: some not covered at all, or all covered "
              "behind a depth bound beyond the object:\n\n| scene | other | not covered | covered, bound too far |\n"
              "|---|---:|---:|---:|\n");
  for (std::size_t i = 0; i < rows.size(); ++i)
    if (rows[i].has_reasons)
      std::printf("| %s | %.2f | %.2f | %.2f |\n", rows[i].scene.c_str(), 100 * reasons[i].other,
                  100 * reasons[i].other_open, 100 * reasons[i].other_depth);
  std::fflush(stdout);
}

/// --split-edges: the scene with every edge longer than `len` split at its midpoint, round after
/// round until none is. A triangle splits the edges that are too long and only those (into 2, 3 or 4
/// triangles), and an edge's midpoint is one vertex shared by both its triangles, so the mesh stays
/// as connected as it was. Objects keep their triangles, in more pieces.
support::Scene split_edges(const support::Scene& in, float len) {
  support::Scene out;
  out.name = in.name;
  std::vector<glm::vec3> pos = in.positions;  // the scene's vertices, then the midpoints
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
  const auto too_long = [&](std::uint32_t a, std::uint32_t b) {
    return glm::length(pos[a] - pos[b]) > len;
  };
  const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    const auto it = midpoints.find(key);
    if (it != midpoints.end()) return it->second;
    pos.push_back(0.5f * (pos[key.first] + pos[key.second]));
    const auto v = static_cast<std::uint32_t>(pos.size() - 1);
    midpoints.emplace(key, v);
    return v;
  };
  std::vector<std::array<std::uint32_t, 3>> tris, next;
  for (const support::SceneObject& o : in.objects) {
    tris.clear();
    for (std::uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t)
      tris.push_back({in.indices[3 * std::size_t(t)], in.indices[3 * std::size_t(t) + 1], in.indices[3 * std::size_t(t) + 2]});
    for (bool again = true; again;) {
      again = false;
      next.clear();
      for (std::array<std::uint32_t, 3> c : tris) {
        bool split[3] = {too_long(c[0], c[1]), too_long(c[1], c[2]), too_long(c[2], c[0])};
        const int n = int(split[0]) + int(split[1]) + int(split[2]);
        if (n == 0) {
          next.push_back(c);
          continue;
        }
        again = true;
        if (n == 3) {
          const std::uint32_t ab = midpoint(c[0], c[1]), bc = midpoint(c[1], c[2]), ca = midpoint(c[2], c[0]);
          next.insert(next.end(), {{c[0], ab, ca}, {ab, c[1], bc}, {ca, bc, c[2]}, {ab, bc, ca}});
          continue;
        }
        // Turn the corners so that the split edges come first (edge 0, then edge 1 if two).
        while (!split[0] || (n == 2 && !split[1])) {
          c = {c[1], c[2], c[0]};
          const bool s0 = split[0];
          split[0] = split[1];
          split[1] = split[2];
          split[2] = s0;
        }
        const std::uint32_t ab = midpoint(c[0], c[1]);
        if (n == 1) {
          next.insert(next.end(), {{c[0], ab, c[2]}, {ab, c[1], c[2]}});
        } else {
          const std::uint32_t bc = midpoint(c[1], c[2]);
          next.insert(next.end(), {{ab, c[1], bc}, {c[0], ab, bc}, {c[0], bc, c[2]}});
        }
      }
      tris.swap(next);
    }
    std::vector<glm::vec3> corners;
    for (const auto& c : tris)
      for (std::uint32_t v : c) corners.push_back(pos[v]);
    const std::uint32_t k = out.add_triangles(corners, o.name);
    out.objects[k].major_occluder = o.major_occluder;
  }
  return out;
}

// ---- --hash: the culler alone, its answers as a hash and its time ----

#if defined(CLOCK_THREAD_CPUTIME_ID) && defined(CLOCK_PROCESS_CPUTIME_ID)
/// A POSIX CPU clock in ms.
double clock_ms(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}
/// This thread's CPU time in ms.
double thread_ms() { return clock_ms(CLOCK_THREAD_CPUTIME_ID); }
/// The process's CPU time in ms, all threads.
double process_ms() { return clock_ms(CLOCK_PROCESS_CPUTIME_ID); }
#else
// Wall time where POSIX CPU clocks are missing.
double thread_ms() { return std::chrono::duration<double, std::milli>(Clock::now().time_since_epoch()).count(); }
double process_ms() { return thread_ms(); }
#endif


struct Flags {
  unsigned threads = 0;  // --threads=N: one thread against N
  bool reasons = false, hash = false, engine = false, moc = false;
  std::string scene;
  int grid_width = 0, grid_height = 0;
  float split_edges = 0.0f;
};

void culler_only(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, int reps,
                 const MeshOcclusionParams& given) {
  namespace mo = cullkit::detail::mesh_occlusion;
  const ObjectMap map(cs.scene);
  const auto t_build = Clock::now();
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), map.objects.data(), map.objects.size(), given);
  print_build(name, culler.stats(), ms_since(t_build));
  const MeshOcclusionParams& params = culler.params();  // as clamped
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
}

/// A TaskRunner that runs the tasks one after the other on the calling thread and adds up the
/// thread CPU time spent inside them: the part of a cull that runs on tasks.
struct TimedTasks {
  double ms = 0;
  static void dispatch(void* self, std::size_t count, void (*run)(void*, std::size_t), void* job) {
    const double t0 = thread_ms();
    for (std::size_t i = 0; i < count; ++i) run(job, i);
    static_cast<TimedTasks*>(self)->ms += thread_ms() - t0;
  }
};

/// A TaskRunner whose N - 1 threads spin for as long as it lives, as an engine's job system's
/// workers are running when a query hands out its tasks in the middle of a frame: the split's own
/// cost, without the wake-ups of the library's sleeping pool. Each dispatch is a barrier: it returns
/// once every task ran and every worker has left it, so the next dispatch's fields are not read by a
/// worker still in the last one.
class SpinningWorkers {
 public:
  explicit SpinningWorkers(unsigned threads) {
    for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this] { loop(); });
  }
  SpinningWorkers(const SpinningWorkers&) = delete;
  SpinningWorkers& operator=(const SpinningWorkers&) = delete;
  ~SpinningWorkers() {
    stop_.store(true, std::memory_order_release);
    for (std::thread& t : workers_) t.join();
  }
  TaskRunner runner() { return TaskRunner{dispatch, this}; }

 private:
  static void dispatch(void* self, std::size_t count, void (*run)(void*, std::size_t), void* job) {
    SpinningWorkers& w = *static_cast<SpinningWorkers*>(self);
    w.run_ = run;
    w.job_ = job;
    w.count_ = count;
    w.next_.store(0, std::memory_order_relaxed);
    w.left_.store(0, std::memory_order_relaxed);
    w.generation_.fetch_add(1, std::memory_order_release);
    w.work();
    for (unsigned spins = 0; w.left_.load(std::memory_order_acquire) < w.workers_.size();)
      if ((++spins & 255u) == 0) std::this_thread::yield();
  }
  void work() {
    for (std::size_t i; (i = next_.fetch_add(1, std::memory_order_relaxed)) < count_;) run_(job_, i);
  }
  void loop() {
    std::uint64_t seen = 0;
    for (unsigned spins = 0; !stop_.load(std::memory_order_acquire);) {
      const std::uint64_t g = generation_.load(std::memory_order_acquire);
      if (g == seen) {
        if ((++spins & 255u) == 0) std::this_thread::yield();  // more threads than cores still progress
        continue;
      }
      seen = g;
      work();
      left_.fetch_add(1, std::memory_order_acq_rel);
    }
  }
  std::vector<std::thread> workers_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<std::size_t> next_{0}, left_{0};
  std::atomic<bool> stop_{false};
  void (*run_)(void*, std::size_t) = nullptr;
  void* job_ = nullptr;
  std::size_t count_ = 0;
};

/// --threads=N: the culler with one thread and with N (MeshOcclusionParams::threads, the library's
/// pool), alternately per camera, best of `reps` each, in wall time; the hashes of both answers
/// (they must be equal), both medians, the ratio of the medians and of the sums over the cameras,
/// and the N-thread cull's CPU time per frame (all threads, median of each camera's best). Then,
/// in this thread's CPU time (which a loaded machine's preemption does not inflate), the share of
/// a cull that runs on tasks, and the ratio N threads would give if those tasks split perfectly
/// and cost nothing to hand out (serial + tasks / N over the one-thread time, sums over the cameras).
void culler_threads(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, int reps,
                    const MeshOcclusionParams& given, unsigned threads) {
  const ObjectMap map(cs.scene);
  MeshOcclusionParams one = given, many = given;
  one.threads = 1;
  many.threads = threads;
  const MeshOcclusionCuller<glm::vec3> culler_one(cs.scene.mesh(), map.objects.data(), map.objects.size(), one);
  const MeshOcclusionCuller<glm::vec3> culler_many(cs.scene.mesh(), map.objects.data(), map.objects.size(), many);
  MeshOcclusionContext context_one, context_many;
  std::vector<std::uint32_t> kept_one, kept_many;
  std::vector<double> wall_one, wall_many, cpu_many;
  std::uint64_t hash_one = 1469598103934665603ull, hash_many = hash_one;
  bool same = true;
  for (const Camera& cam : cams) {
    double best_one = 1e300, best_many = 1e300, best_cpu = 1e300;
    for (int r = 0; r < reps; ++r) {
      auto t0 = Clock::now();
      culler_one.cull(cam, context_one, kept_one);
      best_one = std::min(best_one, ms_since(t0));
      const double c0 = process_ms();
      t0 = Clock::now();
      culler_many.cull(cam, context_many, kept_many);
      best_many = std::min(best_many, ms_since(t0));
      best_cpu = std::min(best_cpu, process_ms() - c0);
    }
    wall_one.push_back(best_one);
    wall_many.push_back(best_many);
    cpu_many.push_back(best_cpu);
    same = same && kept_one == kept_many;  // the same objects in the same order
    for (std::uint32_t o : kept_one) hash_one = (hash_one ^ o) * 1099511628211ull;
    for (std::uint32_t o : kept_many) hash_many = (hash_many ^ o) * 1099511628211ull;
  }
  double sum_one = 0, sum_many = 0;
  for (std::size_t c = 0; c < cams.size(); ++c) {
    sum_one += wall_one[c];
    sum_many += wall_many[c];
  }
  TimedTasks timed;
  MeshOcclusionParams split = many;
  split.task_runner = TaskRunner{TimedTasks::dispatch, &timed};
  const MeshOcclusionCuller<glm::vec3> culler_split(cs.scene.mesh(), map.objects.data(), map.objects.size(), split);
  MeshOcclusionContext context_split;
  double cpu_one = 0, cpu_split = 0, cpu_tasks = 0;
  for (const Camera& cam : cams) {
    double best_one = 1e300, best_split = 1e300, best_tasks = 0;
    for (int r = 0; r < reps; ++r) {
      double t0 = thread_ms();
      culler_one.cull(cam, context_one, kept_one);
      best_one = std::min(best_one, thread_ms() - t0);
      timed.ms = 0;
      t0 = thread_ms();
      culler_split.cull(cam, context_split, kept_many);
      const double t = thread_ms() - t0;
      if (t < best_split) {
        best_split = t;
        best_tasks = timed.ms;
      }
    }
    cpu_one += best_one;
    cpu_split += best_split;
    cpu_tasks += best_tasks;
  }
  // The same cull through running workers, alternating with one thread again, in wall time.
  SpinningWorkers spinning(threads);
  MeshOcclusionParams hot = many;
  hot.task_runner = spinning.runner();
  const MeshOcclusionCuller<glm::vec3> culler_hot(cs.scene.mesh(), map.objects.data(), map.objects.size(), hot);
  MeshOcclusionContext context_hot;
  std::vector<double> wall_one_again, wall_hot;
  for (const Camera& cam : cams) {
    double best_one = 1e300, best_hot = 1e300;
    for (int r = 0; r < reps; ++r) {
      auto t0 = Clock::now();
      culler_one.cull(cam, context_one, kept_one);
      best_one = std::min(best_one, ms_since(t0));
      t0 = Clock::now();
      culler_hot.cull(cam, context_hot, kept_many);
      best_hot = std::min(best_hot, ms_since(t0));
      same = same && kept_one == kept_many;
    }
    wall_one_again.push_back(best_one);
    wall_hot.push_back(best_hot);
  }
  std::printf("threads,%s,%u,%016llx,%016llx,%s,one_ms=%s,many_ms=%s,median_ratio=%.3f,sum_ratio=%.3f,many_cpu_ms=%s,"
              "task_share=%.3f,ideal_ratio=%.3f,hot_ratio=%.3f\n",
              name.c_str(), threads, static_cast<unsigned long long>(hash_one), static_cast<unsigned long long>(hash_many),
              same ? "same" : "DIFFERENT", ms_text(wall_one).c_str(), ms_text(wall_many).c_str(), ratio(wall_many, wall_one),
              sum_one > 0 ? sum_many / sum_one : 0.0, ms_text(cpu_many).c_str(), cpu_split > 0 ? cpu_tasks / cpu_split : 0.0,
              cpu_one > 0 ? (cpu_split - cpu_tasks + cpu_tasks / threads) / cpu_one : 0.0, ratio(wall_hot, wall_one_again));
}

// ---- --engine: the parts of an engine frame ----

StridedMesh strided(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& indices) {
  return StridedMesh{{reinterpret_cast<const unsigned char*>(positions.data()), sizeof(glm::vec3), 0}, positions.size(),
                     {indices.data(), indices.size(), IndexFormat::uint32}};
}

/// The frame time of `cull` for each camera: the fastest of `reps`, in this thread's CPU time.
template <class Cull>
std::vector<double> frame_times(const std::vector<Camera>& cams, int reps, Cull&& cull) {
  std::vector<double> ms;
  for (const Camera& cam : cams) {
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
      const double t0 = thread_ms();
      cull(cam);
      best = std::min(best, thread_ms() - t0);
    }
    ms.push_back(best);
  }
  return ms;
}

/// A wall of 2,048 triangles 6 m before a camera, static in one culler and moving in another (the
/// rest alike: a crate behind it and one beside it): the frame times and their difference per wall
/// triangle. Printed once.
void moving_against_static(int reps) {
  std::vector<glm::vec3> wall;
  std::vector<std::uint32_t> wall_indices;
  cut_panel(32, wall, wall_indices);
  const glm::mat4 model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0, -3, -6)), glm::vec3(8, 6, 1));
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  const auto add_quad = [&](glm::vec3 c, float h) {
    const auto b = static_cast<std::uint32_t>(positions.size());
    for (glm::vec3 p : {c + glm::vec3(-h, -h, 0), c + glm::vec3(h, -h, 0), c + glm::vec3(h, h, 0), c + glm::vec3(-h, h, 0)})
      positions.push_back(p);
    for (std::uint32_t v : {0u, 1u, 2u, 0u, 2u, 3u}) indices.push_back(b + v);
  };
  add_quad({0, 0, -20}, 1.0f);
  add_quad({30, 0, -20}, 1.0f);
  const std::vector<MeshObject> two = {{0, 2}, {2, 2}};
  std::vector<glm::vec3> with_wall = positions;
  std::vector<std::uint32_t> with_indices = indices;
  for (const glm::vec3& p : wall) with_wall.push_back(glm::vec3(model * glm::vec4(p, 1.0f)));
  for (std::uint32_t v : wall_indices) with_indices.push_back(v + static_cast<std::uint32_t>(positions.size()));
  const std::vector<MeshObject> three = {{0, 2}, {2, 2}, {4, static_cast<std::uint32_t>(wall_indices.size() / 3)}};
  const MeshOcclusionCuller<glm::vec3> static_culler(MeshView<glm::vec3>{with_wall.data(), with_wall.size(), with_indices.data(), with_indices.size()},
                                                     three.data(), three.size());
  const MeshOcclusionCuller<glm::vec3> moving_culler(MeshView<glm::vec3>{positions.data(), positions.size(), indices.data(), indices.size()},
                                                     two.data(), two.size());
  std::vector<Camera> cams;
  for (int k = 0; k < 16; ++k) {
    Camera cam;
    cam.eye = glm::vec3(0.1f * float(k) - 0.8f, 0.05f * float(k % 4), 2.0f);
    cam.width = 1920;
    cam.height = 1080;
    cam.view_proj = glm::perspective(glm::radians(60.0f), 16.0f / 9.0f, 0.1f, 500.0f) *
                    glm::lookAt(cam.eye, cam.eye + glm::vec3(0.02f * float(k % 3), 0, -1), glm::vec3(0, 1, 0));
    cams.push_back(cam);
  }
  const MovingOccluder moving{strided(wall, wall_indices), model};
  MeshOcclusionContext a, b;
  std::vector<std::uint32_t> out;
  std::vector<double> st, mv, st2, mv2;
  // Alternated twice.
  st = frame_times(cams, reps, [&](const Camera& c) { static_culler.cull(c, a, out); });
  mv = frame_times(cams, reps, [&](const Camera& c) { moving_culler.cull(c, b, out, &moving, 1); });
  st2 = frame_times(cams, reps, [&](const Camera& c) { static_culler.cull(c, a, out); });
  mv2 = frame_times(cams, reps, [&](const Camera& c) { moving_culler.cull(c, b, out, &moving, 1); });
  const double wall_triangles = double(wall_indices.size() / 3);
  std::printf("engine,wall_static_vs_moving,triangles=%.0f,static_inserted=%zu,moving_inserted=%zu,static_ms=%s / %s,"
              "moving_ms=%s / %s,moving_over_static=%.2f / %.2f,ns_per_triangle_static=%.1f,ns_per_triangle_moving=%.1f\n",
              wall_triangles, a.stats().occluder_triangles, b.stats().moving_triangles, ms_text(st).c_str(),
              ms_text(st2).c_str(), ms_text(mv).c_str(), ms_text(mv2).c_str(), ratio(mv, st), ratio(mv2, st2),
              1e6 * spread(st2).median / wall_triangles, 1e6 * spread(mv2).median / wall_triangles);
}

/// One scene's engine frame: see-through objects (`see_through`: per object), moving occluders
/// along the walk (6 walls, vehicles and doors per frame), is_hidden on random boxes.
void engine_frame(const std::string& name, const CullScene& cs, const std::vector<std::uint8_t>& see_through,
                  const WalkSpec& spec, const std::vector<Camera>& cams, int reps, const MeshOcclusionParams& params) {
  ObjectMap map(cs.scene);
  std::vector<MeshObject> flagged = map.objects;
  std::size_t glass = 0;
  for (std::size_t o = 0; o < flagged.size() && o < see_through.size(); ++o) {
    flagged[o].occludes = !see_through[o];
    glass += see_through[o];
  }
  {
    // Building from instances against building from the concatenated mesh: the scene as instances of
    // its own objects (each object's triangles a mesh of its own, placed by the identity), alternated.
    std::vector<std::vector<std::uint32_t>> pieces;
    std::vector<MeshInstance> instances;
    for (const auto& o : cs.scene.objects) {
      pieces.emplace_back(cs.scene.indices.begin() + std::ptrdiff_t(3 * std::size_t(o.first_triangle)),
                          cs.scene.indices.begin() + std::ptrdiff_t(3 * (std::size_t(o.first_triangle) + o.triangle_count)));
    }
    for (const auto& piece : pieces) instances.push_back({strided(cs.scene.positions, piece), glm::mat4(1.0f)});
    // The same with a matrix that is not the identity (a rotation by a quarter turn, exact in float).
    std::vector<MeshInstance> turned = instances;
    for (MeshInstance& in : turned) in.model = glm::mat4(glm::vec4(0, 0, -1, 0), glm::vec4(0, 1, 0, 0), glm::vec4(1, 0, 0, 0), glm::vec4(0, 0, 0, 1));
    std::vector<double> whole_ms, instance_ms, turned_ms;
    for (int r = 0; r < std::max(reps, 2); ++r) {
      double t0 = thread_ms();
      { const MeshOcclusionCuller<glm::vec3> c(cs.scene.mesh(), map.objects.data(), map.objects.size(), params); }
      whole_ms.push_back(thread_ms() - t0);
      t0 = thread_ms();
      { const MeshOcclusionCuller<glm::vec3> c(instances.data(), instances.size(), map.objects.data(), map.objects.size(), params); }
      instance_ms.push_back(thread_ms() - t0);
      t0 = thread_ms();
      { const MeshOcclusionCuller<glm::vec3> c(turned.data(), turned.size(), map.objects.data(), map.objects.size(), params); }
      turned_ms.push_back(thread_ms() - t0);
    }
    std::printf("engine,%s,build_ms_concatenated=%s,build_ms_instances=%s (%zu instances; turned %s),"
                "instances_over_concatenated=%.2f (turned %.2f)\n",
                name.c_str(), ms_text(whole_ms).c_str(), ms_text(instance_ms).c_str(), instances.size(),
                ms_text(turned_ms).c_str(), ratio(instance_ms, whole_ms), ratio(turned_ms, whole_ms));
  }
  const MeshOcclusionCuller<glm::vec3> opaque(cs.scene.mesh(), map.objects.data(), map.objects.size(), params);
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), flagged.data(), flagged.size(), params);
  const double total = static_cast<double>(std::max<std::size_t>(cs.scene.triangle_count(), 1));
  MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  double kept_opaque = 0, kept_flagged = 0;
  const auto ms_opaque = frame_times(cams, reps, [&](const Camera& c) { opaque.cull(c, context, out); });
  for (const Camera& c : cams) {
    opaque.cull(c, context, out);
    kept_opaque += triangles_of(map, out) / total;
    culler.cull(c, context, out);
    kept_flagged += triangles_of(map, out) / total;
  }
  const auto ms_flagged = frame_times(cams, reps, [&](const Camera& c) { culler.cull(c, context, out); });
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  std::printf("engine,%s,see_through_objects=%zu,kept_pct_all_occluding=%.3f,kept_pct_flagged=%.3f,ms_all_occluding=%s,"
              "ms_flagged=%s\n",
              name.c_str(), glass, 100 * kept_opaque / n, 100 * kept_flagged / n, ms_text(ms_opaque).c_str(),
              ms_text(ms_flagged).c_str());
  // Moving occluders along the walk: 6 per frame, as test_mesh_occlusion_moving places them.
  std::vector<glm::vec3> wall, door;
  std::vector<std::uint32_t> wall_indices, door_indices;
  cut_panel(4, wall, wall_indices);
  cut_panel(1, door, door_indices);
  support::Rng rng(7);
  std::vector<std::vector<MovingOccluder>> per_camera;
  for (const Camera& cam : cams) {
    const PixelRays rays(cam);
    std::vector<MovingOccluder> moving;
    for (int i = 0; i < 6; ++i) {
      const glm::vec3 dir = rays.ray_at(double(rng.uniform()) * cam.width, double(rng.uniform()) * cam.height).direction;
      const glm::vec3 at = cam.eye + dir * (spec.metre * rng.uniform(1.5f, 15.0f)) - glm::vec3(0, spec.eye_height * 0.6f, 0);
      glm::mat4 model = glm::rotate(glm::translate(glm::mat4(1.0f), at), rng.uniform(0.0f, 6.2831853f), glm::vec3(0, 1, 0));
      const bool is_wall = i % 2 == 0;
      glm::vec3 scale = spec.metre * (is_wall ? glm::vec3(rng.uniform(2, 8), rng.uniform(2, 4), 1) : glm::vec3(1, 2.1f, 1));
      if (rng.range(0, 2) == 0) scale.x = -scale.x;
      moving.push_back({is_wall ? strided(wall, wall_indices) : strided(door, door_indices), glm::scale(model, scale)});
    }
    per_camera.push_back(moving);
  }
  std::size_t camera = 0;
  double kept_moving = 0, moving_triangles = 0;
  for (const Camera& c : cams) {
    const auto& m = per_camera[camera++];
    culler.cull(c, context, out, m.data(), m.size());
    kept_moving += triangles_of(map, out) / total;
    moving_triangles += double(context.stats().moving_triangles);
  }
  camera = 0;
  const auto ms_moving = frame_times(cams, reps, [&](const Camera& c) {
    const auto& m = per_camera[camera++ % per_camera.size()];
    culler.cull(c, context, out, m.data(), m.size());
  });
  std::printf("engine,%s,moving_occluders=6,moving_triangles_inserted=%.1f,kept_pct_with_moving=%.3f,ms_with_moving=%s,"
              "ms_without=%s\n",
              name.c_str(), moving_triangles / n, 100 * kept_moving / n, ms_text(ms_moving).c_str(), ms_text(ms_flagged).c_str());
  // is_hidden: 2,000 random boxes per camera inside the view, after the flagged cull.
  std::vector<double> ns;
  std::size_t hidden = 0, asked = 0;
  for (const Camera& cam : cams) {
    culler.cull(cam, context, out);
    const PixelRays rays(cam);
    std::vector<Aabb> boxes;
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 dir = rays.ray_at(double(rng.uniform()) * cam.width, double(rng.uniform()) * cam.height).direction;
      const glm::vec3 c = cam.eye + dir * (spec.near_plane + spec.metre * 60.0f * rng.uniform() * rng.uniform());
      const glm::vec3 h = spec.metre * glm::vec3(rng.uniform(0.05f, 3.0f), rng.uniform(0.05f, 3.0f), rng.uniform(0.05f, 3.0f));
      boxes.push_back(Aabb{c - h, c + h});
    }
    for (const Aabb& b : boxes) {
      const auto t0 = Clock::now();
      const bool h = context.is_hidden(b);
      ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
      hidden += h;
      ++asked;
    }
  }
  std::sort(ns.begin(), ns.end());
  const auto at = [&](double q) { return ns.empty() ? 0.0 : ns[std::min(ns.size() - 1, std::size_t(q * double(ns.size())))]; };
  std::printf("engine,%s,is_hidden_boxes=%zu,hidden_pct=%.1f,ns_median=%.0f,ns_p99=%.0f,ns_max=%.0f (clock read included)\n",
              name.c_str(), asked, 100.0 * double(hidden) / double(std::max<std::size_t>(asked, 1)), at(0.5), at(0.99),
              ns.empty() ? 0.0 : ns.back());
  std::fflush(stdout);
}
#if CULLKIT_BENCH_MOC
/// The clip w of the near plane's centre: MOC clips occluders there.
float near_w_of(const Camera& cam) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.view_proj));
  const double z = cam.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
  const glm::dvec4 h = inv * glm::dvec4(0.0, 0.0, z, 1.0);
  const glm::dvec4 world = h / h.w;
  const glm::dvec4 clip = glm::dmat4(cam.view_proj) * world;
  return static_cast<float>(clip.w);
}

/// One MOC frame as the acceptance race runs it (see --moc); `kept` gets the objects MOC keeps.
class MocFrame {
 public:
  MocFrame(const CullScene& cs, int width, int height, float near_w) : cs_(cs), moc_(width, height, near_w), near_w_(near_w) {}
  const char* implementation() const { return moc_.implementation(); }

  void run(const Camera& cam, std::vector<std::uint32_t>& kept) {
    moc_.clear();
    cs_.abt.cull(frustum_of(cam), in_frustum_);
    const glm::mat4& m = cam.view_proj;
    rects_.clear();
    for (std::uint32_t o : in_frustum_) {
      const Aabb& b = cs_.bounds[o];
      Rect r{o, HUGE_VALF, HUGE_VALF, -HUGE_VALF, -HUGE_VALF, HUGE_VALF, false};
      for (int k = 0; k < 8; ++k) {
        const glm::vec4 p(k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y, k & 4 ? b.max.z : b.min.z, 1.0f);
        const glm::vec4 c = m * p;
        if (!(c.w > near_w_)) r.near = true;
        const float x = c.x / c.w, y = c.y / c.w;
        r.x0 = std::min(r.x0, x);
        r.y0 = std::min(r.y0, y);
        r.x1 = std::max(r.x1, x);
        r.y1 = std::max(r.y1, y);
        r.w = std::min(r.w, c.w);
      }
      rects_.push_back(r);
    }
    std::sort(rects_.begin(), rects_.end(), [](const Rect& a, const Rect& b) { return a.w < b.w; });
    indices_.clear();
    for (const Rect& r : rects_) {
      const auto& so = cs_.scene.objects[r.object];
      const auto* first = cs_.scene.indices.data() + 3 * std::size_t(so.first_triangle);
      indices_.insert(indices_.end(), first, first + 3 * std::size_t(so.triangle_count));
    }
    if (!indices_.empty())
      moc_.render(&cs_.scene.positions[0].x, static_cast<int>(sizeof(glm::vec3)), indices_.data(),
                  static_cast<int>(indices_.size() / 3), &m[0][0]);
    kept.clear();
    for (const Rect& r : rects_)
      if (r.near || moc_.rect_visible(r.x0, r.y0, r.x1, r.y1, r.w)) kept.push_back(r.object);
  }

 private:
  struct Rect {
    std::uint32_t object;
    float x0, y0, x1, y1, w;
    bool near;
  };
  const CullScene& cs_;
  cullkit_bench::MocPeer moc_;
  float near_w_;
  std::vector<std::uint32_t> in_frustum_, indices_;
  std::vector<Rect> rects_;
};

/// --moc: the culler and MOC on the same cameras, alternately.
void moc_race(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, int reps,
              const MeshOcclusionParams& given) {
  if (cams.empty()) return;
  const ObjectMap map(cs.scene);
  const MeshOcclusionCuller<glm::vec3> culler(cs.scene.mesh(), map.objects.data(), map.objects.size(), given);
  MeshOcclusionContext context;
  MocFrame moc(cs, cams[0].width, cams[0].height, near_w_of(cams[0]));
  std::vector<std::uint32_t> kept, moc_kept;
  std::vector<double> culler_ms, moc_ms;
  double culler_share = 0, moc_share = 0;
  const double total = static_cast<double>(std::max<std::size_t>(cs.scene.triangle_count(), 1));
  for (const Camera& cam : cams) {
    double best[2] = {1e300, 1e300};
    for (int r = 0; r < reps; ++r) {
      double t0 = thread_ms();
      culler.cull(cam, context, kept);
      best[0] = std::min(best[0], thread_ms() - t0);
      t0 = thread_ms();
      moc.run(cam, moc_kept);
      best[1] = std::min(best[1], thread_ms() - t0);
    }
    culler_ms.push_back(best[0]);
    moc_ms.push_back(best[1]);
    culler_share += triangles_of(map, kept) / total;
    moc_share += triangles_of(map, moc_kept) / total;
  }
  const double n = static_cast<double>(cams.size());
  std::printf("moc,%s,%zu,%s,%s,%s,%.2f,%.2f,%.2f\n", name.c_str(), cs.scene.triangle_count(), moc.implementation(),
              ms_text(culler_ms).c_str(), ms_text(moc_ms).c_str(), ratio(culler_ms, moc_ms), 100 * culler_share / n,
              100 * moc_share / n);
  std::fflush(stdout);
}
#endif

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
      if (arg == "--reasons") flags.reasons = true;
      else if (arg == "--hash") flags.hash = true;
      else if (arg == "--engine") flags.engine = true;
      else if (arg == "--moc") flags.moc = true;
      else if (arg.rfind("--scene=", 0) == 0) flags.scene = arg.substr(8);
      else if (arg.rfind("--threads=", 0) == 0 && std::atoi(arg.c_str() + 10) >= 2)
        flags.threads = static_cast<unsigned>(std::atoi(arg.c_str() + 10));
      else if (arg.rfind("--split-edges=", 0) == 0 && (flags.split_edges = std::strtof(arg.c_str() + 14, nullptr)) > 0.0f) {
      }
      else if (arg.rfind("--grid=", 0) == 0 && std::sscanf(arg.c_str() + 7, "%dx%d", &flags.grid_width, &flags.grid_height) == 2 &&
               flags.grid_width > 0 && flags.grid_height > 0) {
      } else {
        std::fprintf(stderr, "unknown flag %s\n", arg.c_str());
        return 2;
      }
      continue;
    }
    const int v = std::atoi(argv[i]);
    if (v <= 0 || positional >= 4) {
      std::fprintf(stderr,
                   "usage: %s [cameras=60] [width=1920] [height=1080] [reps=3] [--reasons] [--hash] "
                   "[--moc] [--threads=N] [--scene=TEXT] [--grid=WxH] [--split-edges=LEN] [--engine]\n",
                   argv[0]);
      return 2;
    }
    *slots[positional++] = v;
  }
  MeshOcclusionParams params = params_from_environment();
  if (flags.grid_width > 0) {  // the command line wins over GW and GH
    params.grid_width = flags.grid_width;
    params.grid_height = flags.grid_height;
  }
  std::printf("%d walk cameras per scene, %dx%d, %d alternating reps per camera, one thread.\n", cameras, width, height,
              reps);
  const auto t_all = Clock::now();
  std::vector<Row> rows;
  std::vector<Reasons> reasons;
  const auto wanted = [&](const std::string& name) { return name.find(flags.scene) != std::string::npos; };
#if !CULLKIT_BENCH_MOC
  if (flags.moc) {
    std::printf("--moc: this build has no MOC (configure with -DCULLKIT_MOC_DIR=<folder of its sources>); skipped\n");
    return 0;
  }
#else
  if (flags.moc)
    std::printf("\nmoc,scene,triangles,moc_isa,culler_ms,moc_ms,culler_over_moc,culler_kept_pct,moc_kept_pct\n");
#endif
  const auto run = [&](const std::string& name, support::Scene scene, std::uint64_t seed) {
    if (!wanted(name)) return;
    if (flags.engine) {
      std::vector<std::uint8_t> see_through;
      if (name == "city" || name == "office")
        see_through = add_see_through(scene, 200, name == "city" ? 6.0f : 1.5f, 5);
      else if (name.find("oacmpdm9") != std::string::npos)
        see_through = quake_see_through(scene, support::scenes_dir() + "/oacmpdm9.json");
      const CullScene cs(std::move(scene));
      const WalkSpec spec = walk_spec(name, cs.scene, cs.embree, seed);
      const auto cams = walk(spec, cs.scene, cs.embree, cameras, 4, width, height, seed + 1);
      engine_frame(name, cs, see_through, spec, cams, reps, params);
      return;
    }
    // The culler alone (--hash) or against MOC (--moc), on the walk's cameras.
    if (flags.hash || flags.moc || flags.threads > 0) {
      const CullScene cs(std::move(scene));
      const auto cams = walk(walk_spec(name, cs.scene, cs.embree, seed), cs.scene, cs.embree, cameras, 4, width, height,
                             seed + 1);
#if CULLKIT_BENCH_MOC
      if (flags.moc) {
        moc_race(name, cs, cams, reps, params);
        return;
      }
#endif
      if (flags.threads > 0) culler_threads(name, cs, cams, reps, params, flags.threads);
      else culler_only(name, cs, cams, reps, params);
      return;
    }
    const bool generated = name == "city" || name == "office";
    const CullScene cs(std::move(scene));
    const WalkSpec spec = walk_spec(name, cs.scene, cs.embree, seed);
    const auto cams = walk(spec, cs.scene, cs.embree, cameras, 4, width, height, seed + 1);
    reasons.emplace_back();
    Reasons* r = flags.reasons ? &reasons.back() : nullptr;
    if (generated) {
      const BoxOccluderSource source{cs.bounds.data(), cs.box_occluder.data()};
      rows.push_back(measure(name, cs, cams, source, reps, params, r));
    } else {
      rows.push_back(measure(
          name, cs, cams, [&](std::uint32_t o, OcclusionTree& t) { cs.insert_occluders(o, t); }, reps, params, r));
    }
    rows.back().has_reasons = flags.reasons;
  };
  if (flags.engine) moving_against_static(reps);
  if (smoke) {
    run("city", support::make_city(1, 3), 11);
  } else {
    if (wanted("city")) run("city", support::make_city(1, 8), 11);
    if (wanted("office")) run("office", support::make_office(1, 10, 8), 13);
    std::uint64_t seed = 101;
    for (const auto& file : support::real_scene_files()) {
      const std::uint64_t scene_seed = seed++;  // the same cameras whichever scenes run
      if (!wanted(file)) continue;
      auto s = support::load_obj(support::scenes_dir() + "/" + file);
      if (!s) {
        std::fprintf(stderr, "%s: could not be loaded, skipped\n", file.c_str());
        continue;
      }
      run(file, flags.split_edges > 0.0f ? split_edges(*s, flags.split_edges) : std::move(*s), scene_seed);
    }
  }
  if (flags.hash || flags.engine || flags.moc || flags.threads > 0) return 0;
  print(rows);
  if (flags.reasons) print_reasons(rows, reasons);
  long false_culls = 0;
  for (const Row& r : rows) false_culls += r.culler_false;
  std::printf("\nculler false culls in total: %ld; wall time %.1f s\n", false_culls,
              std::chrono::duration<double>(Clock::now() - t_all).count());
  return false_culls == 0 ? 0 : 1;
}
