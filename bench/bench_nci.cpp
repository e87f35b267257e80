// bench_nci: NormalClassIndex against Embree in one process, same thread count.
//  1. precision (distinct triangles tested / triangles truly visible) for classes x grid (the
//     seed's Figure 10), with memory per triangle and build time against an Embree BVH build (the
//     seed's Table 1 layout). "Truly visible" comes from the test oracle (tests/oracle: a robust
//     Embree scene, front faces only), the same truth the tests check against. A default Embree
//     scene stepping past back faces leaks through shared edges and counts ~12% more triangles
//     as visible (fzk_haus, both views: 421 against the oracle's 374), which flattered the ratio.
//  2. time of select_visible against Embree casting one ray per pixel (rtcIntersect1) and 4x4
//     packets (rtcIntersect16), at 640x480 and 1024x768, 1 and 2 threads (both sides on the same
//     count), on real scenes and two generated ones of >= 10M triangles (full runs only; `--no-big`
//     skips them): the 10.1M-triangle city (outside and inside views) and crowded foliage
//     (support::make_foliage, 10.1M triangles, mostly leaves of 0.12-0.24 m; seen whole from outside,
//     straight down from high above, and from inside among the trunks). The racing peer is a plain Embree scene (default flags: not robust, two-sided): the
//     fast configuration a user would pick. After each race, one `nci_cells` line per crowded path:
//     the (tile, cell) pairs it walked and the tiles it cast through the triangle hierarchy, and its
//     tested count; with two or more paths, one `nci_path_ratio` line per path: its median over the
//     first path's; and one `nci_crowding` line: triangles per pixel of the scene box's rectangle.
// Flags: --no-big, --only-big (both big scenes), --only-foliage, --foliage-trees N (trees per side of
// the forest: default 70, 10.1M triangles; 23 gives 1.1M for quick runs), --no-precision, --quick (precision at the default parameters only,
// timing at 640x480 only), --hash (only a hash of the per-pixel triangle and depth of every view at
// 640x480 and 1024x768 per scene (the forest's inside view last), to check that a change keeps every answer; env CULLKIT_NCI_TILE sets
// NciParams::tile_size for it). --path LIST: the crowded-cell paths raced (comma-separated walk, rays,
// auto; default auto): `--path walk,auto` races the walk alone against the automatic choice in the
// same run; with --hash, the first path of the list answers (every path must print the same hashes).
// --threads LIST: thread counts of the races (default 1,2). --robust: each race also times
// rtcIntersect1 on the same mesh under RTC_SCENE_FLAG_ROBUST (watertight, the guarantee
// select_visible gives; medium quality, built on the same threads), raced last on the same rays, and
// prints one `nci_robust` line per path: select_visible over the default scene's median and over the
// robust one's, the default's over the robust's, the pixels each hit, and the pixels whose first hit
// is another triangle (or none) in one than in the other. CSV on stdout.
// --frame-race SCENE [REPS] [--threads LIST] [--path LIST] [--robust]: see frame_race below (env
// FRAME_VIEWS=1: the outside view only; SCENE as for --profile; --robust adds the robust scene and
// one `frame_robust` line per race: each contestant's median over the robust scene's).
// --profile SCENE VIEW [FRAMES]: for callgrind (instructions per frame: a run of 3 frames minus a run of 1,
// halved; or `--collect-atstart=no --toggle-collect='*process_tile*'` for the tiles alone):
// one thread, select_visible only, at 640x480, FRAMES frames (default 1) of view VIEW (0: outside,
// 1: inside, or from above for the forest; 2: the forest from inside) of SCENE ("city", "bigcity" (10.1M triangles), "foliage"
// (the 10.1M-triangle forest; "foliageN": N trees per side) or a real scene's file name); prints the
// tested count, the call's NciSelectStats (triangles met and those with no pixel centre) and the mean
// wall and processor time per frame (the first frame included; on a loaded machine the processor
// time moves far less between runs) and the index's build time (wall, and processor time over all
// build threads; with env CULLKIT_NCI_EMBREE_BUILD=1 also Embree's build of the mesh, medium quality,
// on the same threads, wall); env CULLKIT_NCI_GRID /
// CULLKIT_NCI_TILE / CULLKIT_NCI_BUILD_THREADS set NciParams::grid / tile_size / build_threads
// (default 1).
// Env CULLKIT_NCI_PATH = walk | rays | auto sets NciParams::crowded_path for --profile, and for --hash
// and the timing races unless --path is given (default: auto).
// CULLKIT_BENCH_SMOKE=1: a tiny city at 64x48, one setting.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <embree_oracle.hpp>

#include <cullkit/normal_class_index.hpp>
#include <cullkit/detail/nci/triangle_bvh.hpp>
#include <cullkit/detail/nci/frame_cast.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

std::atomic<long long> g_embree_bytes{0};
bool memory_monitor(void*, ssize_t bytes, bool) {
  g_embree_bytes += bytes;
  return true;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A plain Embree scene for racing: default (two-sided) triangles, medium build quality. With
// `robust`, the same scene under RTC_SCENE_FLAG_ROBUST: watertight hits (no ray slips between two
// triangles sharing an edge) and no traversal shortcuts that lose accuracy, the guarantee
// select_visible gives.
struct Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  double build_seconds = 0;
  long long bytes = 0;
  Embree(const Scene& s, unsigned threads, bool robust = false) {
    const std::string cfg = "threads=" + std::to_string(threads);
    device = rtcNewDevice(cfg.c_str());
    rtcSetDeviceMemoryMonitorFunction(device, memory_monitor, nullptr);
    const long long before = g_embree_bytes.load();
    const auto t0 = std::chrono::steady_clock::now();
    scene = rtcNewScene(device);
    if (robust) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), s.positions.size()));
    std::memcpy(v, s.positions.data(), s.positions.size() * 3 * sizeof(float));
    auto* ix = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                              3 * sizeof(unsigned), s.triangle_count()));
    std::memcpy(ix, s.indices.data(), s.indices.size() * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    build_seconds = seconds_since(t0);
    bytes = g_embree_bytes.load() - before;
  }
  ~Embree() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }

  // One ray per pixel; returns the number of hits (so the work cannot be dropped). Directions come
  // from PixelRays::directions, a row at a time (the same bits as ray(), at the cost select_visible
  // pays for them).
  long long render1(const Camera& cam, unsigned threads) const {
    std::atomic<long long> hits{0};
    const PixelRays rays(cam);
    auto work = [&](unsigned k) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      long long n = 0;
      std::vector<float> dx(static_cast<std::size_t>(cam.width)), dy(dx.size()), dz(dx.size());
      for (int y = static_cast<int>(k); y < cam.height; y += static_cast<int>(threads)) {
        rays.directions(0, y, cam.width, dx.data(), dy.data(), dz.data());
        for (int x = 0; x < cam.width; ++x) {
          const std::size_t i = static_cast<std::size_t>(x);
          RTCRayHit rh = pixel_ray(cam, dx[i], dy[i], dz[i]);
          rtcIntersect1(scene, &ctx, &rh);
          n += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
      }
      hits += n;
    };
    run_threads(threads, work);
    return hits.load();
  }

  static RTCRayHit pixel_ray(const Camera& cam, float dx, float dy, float dz) {
    RTCRayHit rh;
    rh.ray.org_x = cam.eye.x;
    rh.ray.org_y = cam.eye.y;
    rh.ray.org_z = cam.eye.z;
    rh.ray.dir_x = dx;
    rh.ray.dir_y = dy;
    rh.ray.dir_z = dz;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = 3.0e38f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.time = 0.0f;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
  }

  // The triangle render1 hits at each pixel, row by row (RTC_INVALID_GEOMETRY_ID for none); one
  // thread, untimed.
  std::vector<unsigned> first_hits(const Camera& cam) const {
    const PixelRays rays(cam);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    const std::size_t w = static_cast<std::size_t>(cam.width);
    std::vector<unsigned> prim(w * static_cast<std::size_t>(cam.height), RTC_INVALID_GEOMETRY_ID);
    std::vector<float> dx(w), dy(w), dz(w);
    for (int y = 0; y < cam.height; ++y) {
      rays.directions(0, y, cam.width, dx.data(), dy.data(), dz.data());
      for (std::size_t x = 0; x < w; ++x) {
        RTCRayHit rh = pixel_ray(cam, dx[x], dy[x], dz[x]);
        rtcIntersect1(scene, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) prim[static_cast<std::size_t>(y) * w + x] = rh.hit.primID;
      }
    }
    return prim;
  }

  // 4x4 pixel packets.
  long long render16(const Camera& cam, unsigned threads) const {
    std::atomic<long long> hits{0};
    const PixelRays rays(cam);
    const int bx = (cam.width + 3) / 4, by = (cam.height + 3) / 4;
    auto work = [&](unsigned k) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      long long n = 0;
      for (int b = static_cast<int>(k); b < bx * by; b += static_cast<int>(threads)) {
        alignas(64) RTCRayHit16 rh;
        alignas(64) int valid[16];
        const int x0 = (b % bx) * 4, y0 = (b / bx) * 4;
        float dx[16], dy[16], dz[16];  // 4 rows of 4 (rows past the image repeat the last one)
        const int cols = std::min(4, cam.width - x0);
        for (int row = 0; row < 4; ++row)
          rays.directions(x0, std::min(y0 + row, cam.height - 1), cols, dx + 4 * row, dy + 4 * row, dz + 4 * row);
        for (int i = 0; i < 16; ++i) {
          const int x = x0 + (i & 3), y = y0 + (i >> 2);
          valid[i] = (x < cam.width && y < cam.height) ? -1 : 0;
          const int j = (i & ~3) + std::min(i & 3, cols - 1);
          rh.ray.org_x[i] = cam.eye.x;
          rh.ray.org_y[i] = cam.eye.y;
          rh.ray.org_z[i] = cam.eye.z;
          rh.ray.dir_x[i] = dx[j];
          rh.ray.dir_y[i] = dy[j];
          rh.ray.dir_z[i] = dz[j];
          rh.ray.tnear[i] = 0.0f;
          rh.ray.tfar[i] = 3.0e38f;
          rh.ray.mask[i] = 0xFFFFFFFFu;
          rh.ray.time[i] = 0.0f;
          rh.ray.flags[i] = 0;
          rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, scene, &ctx, &rh);
        for (int i = 0; i < 16; ++i) n += valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
      }
      hits += n;
    };
    run_threads(threads, work);
    return hits.load();
  }

  template <class F>
  static void run_threads(unsigned threads, F& work) {
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(work, k);
    work(0);
    for (auto& t : pool) t.join();
  }
};

// The eye among a forest's trunks (objects named "trunk_*"): beside the trunk nearest `spot` (ground
// level and position), 1.6 m above its foot, looking across the forest toward `across` and slightly
// up, under and into the crowns (the usual game camera in a forest). The spot itself when the
// scene has no trunk.
Camera forest_inside_view(const Scene& s, glm::vec3 spot, glm::vec3 across, int w, int h) {
  const support::SceneObject* nearest = nullptr;
  float best = std::numeric_limits<float>::infinity();
  for (const support::SceneObject& o : s.objects) {
    if (o.name.rfind("trunk_", 0) != 0) continue;
    const glm::vec3 c = o.bounds.center();
    const float d = (c.x - spot.x) * (c.x - spot.x) + (c.z - spot.z) * (c.z - spot.z);
    if (d < best) best = d, nearest = &o;
  }
  glm::vec3 eye = spot;
  if (nearest) {
    // Trunks stand 0.5 m into the ground; the eye 1.5 m aside, clear of the trunk (radius <= 0.3 m).
    const glm::vec3 c = nearest->bounds.center();
    eye = glm::vec3(c.x + 1.5f, nearest->bounds.min.y + 0.5f + 1.6f, c.z + 1.0f);
  }
  const glm::vec3 target(across.x, eye.y + 0.08f * glm::length(glm::vec2(across.x - eye.x, across.z - eye.z)), across.z);
  return support::make_camera(eye, target, 70, w, h, 0.1f, 0.0f);
}

// The views of a scene: view 0 outside, seeing it whole; view 1 inside (the walk-through view) or,
// for scenes seen `from_above` (the foliage), straight down from high above with the whole scene in
// the frame, and then view 2 from inside among the trunks, looking across (forest_inside_view).
std::vector<Camera> views(const Scene& s, int w, int h, bool from_above = false) {
  const Aabb b = s.bounds;
  const glm::vec3 c = b.center(), e = b.extent();
  std::vector<Camera> cams;
  // Outside, looking at the centre from a raised diagonal.
  cams.push_back(support::make_camera(c + glm::vec3(0.8f, 0.5f, 0.9f) * glm::length(e) * 0.6f, c, 60, w, h,
                                      0.1f, 0.0f));
  if (from_above) {
    // 60 degrees vertical: the larger ground side spans the shorter screen side.
    const float height = 0.5f * std::max(e.x, e.z) / std::tan(0.5235988f)  /* 30 degrees */;
    cams.push_back(support::make_camera(c + glm::vec3(0.0f, 0.5f * e.y + height, 0.0f), c, 60, w, h, 0.1f, 0.0f));
    cams.push_back(forest_inside_view(s, b.min + e * glm::vec3(0.3f, 0.0f, 0.35f), b.min + e * glm::vec3(0.8f, 0.0f, 0.7f), w, h));
    return cams;
  }
  // Inside the box near the floor, looking across (the walk-through view).
  cams.push_back(support::make_camera(b.min + e * glm::vec3(0.3f, 0.08f, 0.35f),
                                      b.min + e * glm::vec3(0.8f, 0.05f, 0.7f), 70, w, h, 0.1f, 0.0f));
  return cams;
}

// NciParams::crowded_path from env CULLKIT_NCI_PATH (walk, rays, auto), else left as it is.
void path_from_env(NciParams& p) {
  const char* v = std::getenv("CULLKIT_NCI_PATH");
  if (!v) return;
  if (!std::strcmp(v, "walk")) p.crowded_path = NciCrowdedPath::walk_only;
  else if (!std::strcmp(v, "rays")) p.crowded_path = NciCrowdedPath::rays_only;
  else p.crowded_path = NciCrowdedPath::automatic;
}

// Triangles per pixel of the scene box's screen rectangle (the whole screen when a corner is behind
// the eye): how crowded a view is.
double triangles_per_pixel(const Scene& s, const Camera& cam) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec4 p = glm::dmat4(cam.view_proj) *
                         glm::dvec4((k & 1) ? s.bounds.max.x : s.bounds.min.x, (k & 2) ? s.bounds.max.y : s.bounds.min.y,
                                    (k & 4) ? s.bounds.max.z : s.bounds.min.z, 1.0);
    if (!(p.w > 0.0)) return double(s.triangle_count()) / (double(cam.width) * cam.height);
    const double px = (p.x / p.w + 1.0) * 0.5 * cam.width, py = (1.0 - p.y / p.w) * 0.5 * cam.height;
    x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
  }
  const double w = std::max(1.0, std::min<double>(cam.width, x1) - std::max(0.0, x0));
  const double h = std::max(1.0, std::min<double>(cam.height, y1) - std::max(0.0, y0));
  return double(s.triangle_count()) / (w * h);
}

int g_foliage_trees = 70;  // --foliage-trees: trees per side of the generated forest
bool g_quick = false;  // --quick: precision at the default parameters only, timing at 640x480 only
bool g_robust = false;  // --robust: race Embree's robust (watertight) scene too

struct PathChoice {
  NciCrowdedPath path;
  const char* name;
};
std::vector<PathChoice> g_paths = {{NciCrowdedPath::automatic, "auto"}};  // --path
std::vector<unsigned> g_threads = {1, 2};                                  // --threads

// "walk,rays,auto" -> paths; false on an unknown name.
bool parse_paths(const char* list, std::vector<PathChoice>& out) {
  out.clear();
  const std::string s = list;
  for (std::size_t at = 0; at <= s.size();) {
    const std::size_t end = std::min(s.find(',', at), s.size());
    const std::string word = s.substr(at, end - at);
    if (word == "walk") out.push_back({NciCrowdedPath::walk_only, "walk"});
    else if (word == "rays") out.push_back({NciCrowdedPath::rays_only, "rays"});
    else if (word == "auto") out.push_back({NciCrowdedPath::automatic, "auto"});
    else return false;
    at = end + 1;
  }
  return !out.empty();
}

bool parse_threads(const char* list, std::vector<unsigned>& out) {
  out.clear();
  for (const char* c = list; *c;) {
    char* end = nullptr;
    const long v = std::strtol(c, &end, 10);
    if (end == c || v < 1 || v > 256) return false;
    out.push_back(static_cast<unsigned>(v));
    c = *end == ',' ? end + 1 : end;
    if (*end && *end != ',') return false;
  }
  return !out.empty();
}

void precision_table(const std::string& name, const Scene& s, unsigned threads, bool smoke, bool from_above = false) {
  const Embree embree(s, threads);
  std::printf("embree_build,%s,%zu,%.3f,%.1f\n", name.c_str(), s.triangle_count(), embree.build_seconds,
              double(embree.bytes) / double(s.triangle_count()));
  const int w = smoke ? 64 : 640, h = smoke ? 48 : 480;
  auto cams = views(s, w, h, from_above);
  cams.resize(std::min<std::size_t>(cams.size(), 2));  // the table's views (comparable with earlier runs)
  std::vector<std::vector<std::uint32_t>> truth;
  {
    oracle::EmbreeScene robust;
    robust.add_mesh(s.positions.data(), s.positions.size(), s.indices.data(), s.indices.size());
    robust.commit();
    for (const auto& c : cams) truth.push_back(oracle::visible_triangles(robust.render(c, threads)));
  }
  const std::vector<int> classes = smoke || g_quick ? std::vector<int>{NciParams{}.classes} : std::vector<int>{32, 128, 512};
  const std::vector<int> grids = smoke || g_quick ? std::vector<int>{NciParams{}.grid} : std::vector<int>{32, 64, 128};
  for (int k : classes) {
    for (int g : grids) {
      NciParams p;
      p.classes = k;
      p.grid = g;
      p.threads = threads;
      p.build_threads = threads;
      const NormalClassIndex<glm::vec3> index(s.mesh(), p);
      std::size_t tested = 0, visible = 0, ours = 0;
      for (std::size_t i = 0; i < cams.size(); ++i) {
        const VisibleSet v = index.select_visible(cams[i]);
        tested += v.triangles_tested;
        ours += v.triangles.size();
        visible += truth[i].size();
      }
      std::printf("nci_precision,%s,%zu,%d,%d,%.3f,%.2f,%.1f,%zu,%zu,%zu\n", name.c_str(), s.triangle_count(), k, g,
                  index.stats().build_seconds, double(tested) / double(std::max<std::size_t>(1, visible)),
                  double(index.memory_bytes()) / double(s.triangle_count()), tested, visible, ours);
      std::fflush(stdout);
    }
  }
}

// An index per path of --path (the path and the thread count are fixed at build).
std::vector<std::unique_ptr<NormalClassIndex<glm::vec3>>> indices_per_path(const Scene& s, unsigned threads,
                                                                          unsigned build_threads) {
  std::vector<std::unique_ptr<NormalClassIndex<glm::vec3>>> index;
  for (const PathChoice& path : g_paths) {
    NciParams p;
    p.threads = threads;
    p.build_threads = build_threads;
    p.crowded_path = path.path;
    index.push_back(std::make_unique<NormalClassIndex<glm::vec3>>(s.mesh(), p));
  }
  return index;
}

// One race per size x view x thread count: Embree single rays, Embree packets, then select_visible
// on each path of --path (an index per path and thread count: both are fixed at build).
void speed(const std::string& name, const Scene& s, unsigned build_threads, bool smoke, bool from_above = false) {
  const Embree embree(s, build_threads);
  std::optional<Embree> robust;
  if (g_robust) {
    robust.emplace(s, build_threads, true);
    std::printf("embree_build_robust,%s,%zu,%.3f,%.1f\n", name.c_str(), s.triangle_count(), robust->build_seconds,
                double(robust->bytes) / double(s.triangle_count()));
  }
  const std::vector<std::pair<int, int>> sizes =
      smoke     ? std::vector<std::pair<int, int>>{{64, 48}}
      : g_quick ? std::vector<std::pair<int, int>>{{640, 480}}
                : std::vector<std::pair<int, int>>{{640, 480}, {1024, 768}};
  for (const unsigned threads : g_threads) {
    const auto index = indices_per_path(s, threads, build_threads);
    for (auto [w, h] : sizes) {
      const auto cams = views(s, w, h, from_above);
      for (std::size_t ci = 0; ci < cams.size(); ++ci) {
        const Camera cam = cams[ci];
        std::vector<NciContext> ctx(g_paths.size());
        VisibleSet out;
        const std::string race = name + "/" + std::to_string(w) + "x" + std::to_string(h) + "/view" +
                                 std::to_string(ci) + "/threads" + std::to_string(threads);
        std::vector<cullkit_bench::Contestant> field = {
            {"embree_rtcIntersect1", [&] { cullkit_bench::keep(embree.render1(cam, threads)); }},
            {"embree_rtcIntersect16", [&] { cullkit_bench::keep(embree.render16(cam, threads)); }}};
        for (std::size_t k = 0; k < g_paths.size(); ++k) {
          // The default path keeps the contestant's old name, so earlier CSV stays comparable.
          const std::string who = g_paths[k].path == NciCrowdedPath::automatic
                                      ? std::string("nci_select_visible")
                                      : std::string("nci_select_visible_") + g_paths[k].name;
          field.push_back({who, [&, k] {
                             index[k]->select_visible(cam, ctx[k], out, nullptr);
                             cullkit_bench::keep(out.triangles.size());
                           }});
        }
        // Last, so the rows and ratios above keep their places.
        if (robust)
          field.push_back({"embree_rtcIntersect1_robust", [&] { cullkit_bench::keep(robust->render1(cam, threads)); }});
        const auto result = cullkit_bench::race(race, field, smoke ? 2 : 9);
        if (robust) {
          const double robust_ns = result.back().median_ns;
          const long long hits = embree.render1(cam, threads), robust_hits = robust->render1(cam, threads);
          const std::vector<unsigned> first = embree.first_hits(cam), robust_first = robust->first_hits(cam);
          std::size_t differing = 0;
          for (std::size_t i = 0; i < first.size(); ++i) differing += first[i] != robust_first[i];
          for (std::size_t k = 0; k < g_paths.size(); ++k)
            std::printf("nci_robust,%s,%s,%.3f,%.3f,%.3f,%lld,%lld,%zu\n", race.c_str(), g_paths[k].name,
                        result[2 + k].median_ns / result[0].median_ns, result[2 + k].median_ns / robust_ns,
                        result[0].median_ns / robust_ns, hits, robust_hits, differing);
        }
        std::printf("nci_crowding,%s,triangles_per_box_pixel=%.3f\n", race.c_str(), triangles_per_pixel(s, cam));
        for (std::size_t k = 0; k < g_paths.size(); ++k) {
          index[k]->select_visible(cam, ctx[k], out, nullptr);  // the stats of one frame
          const NciSelectStats& st = ctx[k].stats;
          std::printf("nci_cells,%s,%s,%zu,%zu,%zu,%zu,%zu\n", race.c_str(), g_paths[k].name, st.cells_walked,
                      st.tiles_ray_cast, out.triangles_tested, st.triangles_met, st.triangles_no_pixel);
          if (k > 0)
            std::printf("nci_path_ratio,%s,%s_over_%s,%.3f\n", race.c_str(), g_paths[k].name, g_paths[0].name,
                        result[2 + k].median_ns / result[2].median_ns);
        }
        std::fflush(stdout);
      }
    }
  }
}

// FNV-1a over every pixel's triangle and depth bits of both views at 640x480 and 1024x768, plus
// tested counts (printed apart: a precision change keeps the pixels).
void pixel_hash(const std::string& name, const Scene& s, unsigned threads, bool from_above = false) {
  NciParams p;
  p.threads = threads;
  p.build_threads = threads;
  if (const char* tile = std::getenv("CULLKIT_NCI_TILE")) p.tile_size = std::atoi(tile);  // answers must not move
  p.crowded_path = g_paths.front().path;  // neither must they
  const NormalClassIndex<glm::vec3> index(s.mesh(), p);
  // Views 0 and 1 at both sizes, then any later view at both sizes (lines added after the earlier
  // ones, which stay as they were).
  for (const bool later : {false, true})
  for (auto [w, h] : std::vector<std::pair<int, int>>{{640, 480}, {1024, 768}}) {
    const auto cams = views(s, w, h, from_above);
    for (std::size_t ci = later ? 2 : 0; ci < (later ? cams.size() : std::min<std::size_t>(cams.size(), 2)); ++ci) {
      NciContext ctx;
      VisibleSet out;
      NciPixels px;
      index.select_visible(cams[ci], ctx, out, &px);
      std::uint64_t hash = 1469598103934665603ull;
      auto mix = [&](std::uint32_t v) {
        for (int k = 0; k < 4; ++k) {
          hash ^= (v >> (8 * k)) & 0xFFu;
          hash *= 1099511628211ull;
        }
      };
      for (std::size_t i = 0; i < px.triangle.size(); ++i) {
        std::uint32_t bits;
        std::memcpy(&bits, &px.depth[i], sizeof bits);
        mix(px.triangle[i]);
        mix(bits);
      }
      std::printf("nci_hash,%s,%dx%d,view%zu,%016llx,%zu,%zu\n", name.c_str(), w, h, ci,
                  static_cast<unsigned long long>(hash), out.triangles.size(), out.triangles_tested);
      std::fflush(stdout);
    }
  }
}

// --profile: one scene, one view, one thread, select only (instruction counts with callgrind).
int profile(const std::string& name, int view, int frames) {
  std::optional<Scene> s;
  if (name == "city") s = support::make_city(7, 20);
  else if (name == "bigcity") s = support::make_city(8, 284);
  else if (name.rfind("foliage", 0) == 0) s = support::make_foliage(1, name.size() > 7 ? std::atoi(name.c_str() + 7) : 70, 2280);
  else s = support::load_obj(support::scenes_dir() + "/" + name);
  if (!s) {
    std::fprintf(stderr, "profile: no scene %s\n", name.c_str());
    return 1;
  }
  NciParams p;
  p.threads = 1;
  p.build_threads = 1;
  if (const char* g = std::getenv("CULLKIT_NCI_GRID")) p.grid = std::atoi(g);
  if (const char* t = std::getenv("CULLKIT_NCI_TILE")) p.tile_size = std::atoi(t);
  if (const char* b = std::getenv("CULLKIT_NCI_BUILD_THREADS")) p.build_threads = static_cast<unsigned>(std::atoi(b));
  path_from_env(p);
  const auto b0 = std::chrono::steady_clock::now();
  const std::clock_t bc0 = std::clock();
  const NormalClassIndex<glm::vec3> index(s->mesh(), p);
  const double build_ms = seconds_since(b0) * 1e3;
  const double build_cpu_ms = double(std::clock() - bc0) * 1e3 / CLOCKS_PER_SEC;  // all build threads'
  double embree_ms = 0;
  if (std::getenv("CULLKIT_NCI_EMBREE_BUILD")) {  // Embree's build of the same mesh on the same threads, after it
    const Embree embree(*s, std::max(1u, p.build_threads));
    embree_ms = embree.build_seconds * 1e3;
  }
  const auto cams = views(*s, 640, 480, name.rfind("foliage", 0) == 0);
  NciContext ctx;
  VisibleSet out;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (int k = 0; k < frames; ++k) index.select_visible(cams[static_cast<std::size_t>(view) % cams.size()], ctx, out, nullptr);
  const double ms = frames > 0 ? seconds_since(t0) * 1e3 / frames : 0.0;
  // Processor time (the process's, one thread selecting): less moved than wall time by other
  // processes on a loaded machine.
  const double cpu_ms = frames > 0 ? double(std::clock() - c0) * 1e3 / CLOCKS_PER_SEC / frames : 0.0;
  const NciSelectStats& st = ctx.stats;
  std::printf("profile,%s,view%d,grid=%d,frames=%d,ms_per_frame=%.2f,cpu_ms_per_frame=%.2f,selected=%zu,tested=%zu,ray_tests=%zu,cells=%zu,"
              "triangles_met=%zu,triangles_no_pixel=%zu,cells_walked=%zu,tiles_ray_cast=%zu,bytes_per_triangle=%.1f,build_ms=%.1f,"
              "build_cpu_ms=%.1f,embree_build_ms=%.1f\n",
              name.c_str(), view, index.params().grid, frames, ms, cpu_ms, out.triangles.size(), out.triangles_tested,
              st.ray_tests, st.cells_visited, st.triangles_met, st.triangles_no_pixel, st.cells_walked, st.tiles_ray_cast,
              double(index.memory_bytes()) / double(std::max<std::size_t>(1, s->triangle_count())), build_ms, build_cpu_ms,
              embree_ms);
  return 0;
}


// --frame-race SCENE [REPS]: the triangle hierarchy's cast alone (nearest front-facing watertight hit
// per pixel, no edge bands, no screen rectangles: the floor of the crowded path), raced against
// Embree's single rays and select_visible on each path of --path. Its own hierarchy is built over
// the mesh with the index's builder; its leaves hold vertex ids in leaf order and positions
// renumbered by first use along the leaves. One line per race of pixels differing from the index's
// per-pixel answer (frame_agree) and of the cast's work (frame_stats).
struct FrameCaster {
  const Scene& s;
  detail::nci::TriangleBvh bvh;
  std::vector<std::uint32_t> lv;  // 3 vertex ids per leaf slot
  std::vector<glm::vec3> lpos;    // positions in first use along the slots
  double build_seconds = 0;
  mutable detail::nci::FrameCastStats stats;

  FrameCaster(const Scene& scene, unsigned threads) : s(scene) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<detail::nci::TriangleBvhItem> items(s.triangle_count());
    for (std::size_t i = 0; i < items.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const float a = s.positions[s.indices[3 * i]][k], b = s.positions[s.indices[3 * i + 1]][k],
                    c = s.positions[s.indices[3 * i + 2]][k];
        items[i].lo[k] = std::min({a, b, c});
        items[i].hi[k] = std::max({a, b, c});
      }
    detail::nci::TriangleBvhBuilder builder(items, threads, TaskRunner{});
    builder.traversal_cost = detail::nci::frame_traversal_cost;
    bvh = builder.build();
    build_seconds = seconds_since(t0);
    std::vector<std::uint32_t> remap(s.positions.size(), 0xFFFFFFFFu);
    lv.resize(3 * bvh.tris.size());
    for (std::size_t q = 0; q < bvh.tris.size(); ++q)
      for (std::size_t v = 0; v < 3; ++v) {
        const std::uint32_t old = s.indices[3 * std::size_t{bvh.tris[q]} + v];
        if (remap[old] == 0xFFFFFFFFu) {
          remap[old] = static_cast<std::uint32_t>(lpos.size());
          lpos.push_back(s.positions[old]);
        }
        lv[3 * q + v] = remap[old];
      }
  }

  struct Slot {
    detail::nci::FramePacket p;
    detail::WatertightRay<float> w[64];
    std::uint32_t hit[64];
    detail::nci::FrameCursor cur;
    int x0 = 0, y0 = 0, cw = 0, ch = 0;
    bool busy = false;
  };
  struct LeafOps {
    [[nodiscard]] static std::uint32_t phases() noexcept { return 1; }
    const FrameCaster& fc;
    Slot& sl;
    const float* eye;
    void prefetch(std::uint32_t first, std::uint32_t count) const {
      const char* a = reinterpret_cast<const char*>(fc.lv.data() + 3 * std::size_t{first});
      __builtin_prefetch(a);
      __builtin_prefetch(a + 12 * count - 1);
    }
    std::uint32_t prepare(std::uint32_t first, std::uint32_t count, std::uint32_t, std::uint32_t) const {
      for (std::uint32_t q = 0; q < 3 * count; ++q) __builtin_prefetch(&fc.lpos[fc.lv[3 * std::size_t{first} + q]]);
      return 0;
    }
    void test(std::uint32_t first, std::uint32_t count, std::uint64_t mask, std::uint32_t) const {
      for (std::uint32_t q = first; q < first + count; ++q) {
        const glm::vec3& pa = fc.lpos[fc.lv[3 * std::size_t{q}]];
        const glm::vec3& pb = fc.lpos[fc.lv[3 * std::size_t{q} + 1]];
        const glm::vec3& pc = fc.lpos[fc.lv[3 * std::size_t{q} + 2]];
        const float a[3] = {pa.x - eye[0], pa.y - eye[1], pa.z - eye[2]};
        const float b[3] = {pb.x - eye[0], pb.y - eye[1], pb.z - eye[2]};
        const float c[3] = {pc.x - eye[0], pc.y - eye[1], pc.z - eye[2]};
        for (std::uint64_t m = mask; m; m &= m - 1) {
          const int k = __builtin_ctzll(m);
          float t = 0.0f;
          if (detail::watertight_hit(sl.w[k], a, b, c, t) &&
              (t < sl.p.t[k] ||
               (t == sl.p.t[k] && (sl.hit[k] == 0xFFFFFFFFu || fc.bvh.tris[q] < fc.bvh.tris[sl.hit[k]])))) {
            sl.p.t[k] = t;
            sl.hit[k] = q;
          }
        }
      }
    }
  };

  // Tiles of 8x8 pixels, frame_turns of them taking turns per thread.
  long long render(const Camera& cam, unsigned threads, std::uint32_t* tri_out = nullptr, float* depth_out = nullptr) const {
    const PixelRays rays(cam);
    const int nx = (cam.width + 7) / 8, ny = (cam.height + 7) / 8;
    std::atomic<int> next{0};
    std::atomic<long long> hits{0};
    const float eye[3] = {cam.eye.x, cam.eye.y, cam.eye.z};
    auto work = [&](unsigned) {
      long long n = 0;
      detail::nci::FrameCastStats local;
      std::vector<Slot> slots(detail::nci::frame_turns);
      auto open = [&](Slot& sl) {
        const int t = next++;
        if (t >= nx * ny) return false;
        sl.x0 = (t % nx) * 8;
        sl.y0 = (t / nx) * 8;
        sl.cw = std::min(8, cam.width - sl.x0);
        sl.ch = std::min(8, cam.height - sl.y0);
        float dx[64], dy[64], dz[64];
        std::uint64_t live = 0;
        for (int y = 0; y < sl.ch; ++y) rays.directions(sl.x0, sl.y0 + y, sl.cw, dx + y * 8, dy + y * 8, dz + y * 8);
        for (int y = 0; y < sl.ch; ++y)
          for (int x = 0; x < sl.cw; ++x) {
            const int k = y * 8 + x;
            sl.w[k] = detail::WatertightRay<float>::make(glm::vec3(dx[k], dy[k], dz[k]));
            sl.p.ix[k] = detail::nci::frame_inverse(dx[k]);
            sl.p.iy[k] = detail::nci::frame_inverse(dy[k]);
            sl.p.iz[k] = detail::nci::frame_inverse(dz[k]);
            sl.p.t[k] = std::numeric_limits<float>::infinity();
            sl.hit[k] = 0xFFFFFFFFu;
            live |= std::uint64_t{1} << k;
          }
        sl.cur.start(bvh, live);
        sl.busy = true;
        return true;
      };
      auto close = [&](Slot& sl) {
        for (int y = 0; y < sl.ch; ++y)
          for (int x = 0; x < sl.cw; ++x) {
            const int k = y * 8 + x;
            n += sl.hit[k] != 0xFFFFFFFFu;
            if (tri_out) {
              const std::size_t i = std::size_t(sl.y0 + y) * std::size_t(cam.width) + std::size_t(sl.x0 + x);
              tri_out[i] = sl.hit[k] != 0xFFFFFFFFu ? bvh.tris[sl.hit[k]] : sl.hit[k];
              depth_out[i] = sl.p.t[k];
            }
          }
        sl.busy = false;
      };
      int active = 0;
      for (auto& sl : slots) active += open(sl);
      while (active > 0) {
        for (auto& sl : slots) {
          if (!sl.busy) continue;
          LeafOps ops{*this, sl, eye};
          detail::nci::frame_cursor_step(bvh, eye, sl.p, sl.cur, ops, local);
          if (sl.cur.done()) {
            close(sl);
            if (!open(sl)) --active;
          }
        }
      }
      hits += n;
      if (tri_out) stats = local;
    };
    Embree::run_threads(threads, work);
    return hits.load();
  }
};

int frame_race(const std::string& name, int reps) {
  std::optional<Scene> s;
  if (name == "city") s = support::make_city(7, 20);
  else if (name == "bigcity") s = support::make_city(8, 284);
  else if (name.rfind("foliage", 0) == 0) s = support::make_foliage(1, name.size() > 7 ? std::atoi(name.c_str() + 7) : 70, 2280);
  else s = support::load_obj(support::scenes_dir() + "/" + name);
  if (!s) return 1;
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const Embree embree(*s, hw);
  std::printf("frame_build,%s,triangles=%zu,embree_s=%.3f,embree_bytes_per_tri=%.1f\n", name.c_str(), s->triangle_count(),
              embree.build_seconds, double(embree.bytes) / double(s->triangle_count()));
  std::optional<Embree> robust;
  if (g_robust) {
    robust.emplace(*s, hw, true);
    std::printf("frame_build,%s,embree_robust_s=%.3f,embree_robust_bytes_per_tri=%.1f\n", name.c_str(),
                robust->build_seconds, double(robust->bytes) / double(s->triangle_count()));
  }
  const FrameCaster fc(*s, hw);
  std::printf("frame_build,%s,frame_bvh_s=%.3f,nodes=%zu,bytes_per_tri=%.2f\n", name.c_str(), fc.build_seconds,
              fc.bvh.nodes.size(), double(fc.bvh.memory_bytes()) / double(s->triangle_count()));
  std::fflush(stdout);
  const int views_wanted = std::getenv("FRAME_VIEWS") ? std::atoi(std::getenv("FRAME_VIEWS")) : 2;
  for (const unsigned threads : g_threads) {
    const auto index = indices_per_path(*s, threads, hw);
    for (std::size_t k = 0; k < g_paths.size(); ++k)
      std::printf("nci_build,%s,%s,build_s=%.3f,bytes_per_tri=%.2f\n", name.c_str(), g_paths[k].name,
                  index[k]->stats().build_seconds, double(index[k]->memory_bytes()) / double(s->triangle_count()));
    for (auto [w, h] : std::vector<std::pair<int, int>>{{640, 480}, {1024, 768}}) {
      const auto cams = views(*s, w, h, name.rfind("foliage", 0) == 0);
      for (int ci = 0; ci < views_wanted; ++ci) {
        const Camera cam = cams[static_cast<std::size_t>(ci)];
        std::vector<NciContext> ctx(g_paths.size());
        VisibleSet out;
        const std::string race = name + "/" + std::to_string(w) + "x" + std::to_string(h) + "/view" +
                                 std::to_string(ci) + "/threads" + std::to_string(threads);
        if (threads == g_threads.front()) {  // agreement with the index's per-pixel first hits
          NciPixels px;
          index.front()->select_visible(cam, ctx.front(), out, &px);
          std::vector<std::uint32_t> tri(std::size_t(w) * std::size_t(h));
          std::vector<float> depth(tri.size());
          fc.render(cam, 1, tri.data(), depth.data());
          std::size_t differ = 0;
          for (std::size_t i = 0; i < tri.size(); ++i)
            differ += tri[i] != px.triangle[i] || (tri[i] != NciPixels::miss && depth[i] != px.depth[i]);
          std::printf("frame_agree,%s,pixels_differing=%zu\n", race.c_str(), differ);
          std::printf("frame_stats,%s,nodes=%llu,leaves=%llu,rays_per_node=%.2f,rays_per_leaf=%.2f\n", race.c_str(),
                      static_cast<unsigned long long>(fc.stats.nodes), static_cast<unsigned long long>(fc.stats.leaves),
                      double(fc.stats.node_rays) / double(std::max<std::uint64_t>(fc.stats.nodes, 1)),
                      double(fc.stats.leaf_rays) / double(std::max<std::uint64_t>(fc.stats.leaves, 1)));
        }
        std::vector<cullkit_bench::Contestant> field = {
            {"embree_rtcIntersect1", [&] { cullkit_bench::keep(embree.render1(cam, threads)); }},
            {"frame_cast_nearest", [&] { cullkit_bench::keep(fc.render(cam, threads)); }}};
        for (std::size_t k = 0; k < g_paths.size(); ++k)
          field.push_back({std::string("nci_select_visible_") + g_paths[k].name, [&, k] {
                             index[k]->select_visible(cam, ctx[k], out, nullptr);
                             cullkit_bench::keep(out.triangles.size());
                           }});
        if (robust)  // last, so the rows above keep their places
          field.push_back({"embree_rtcIntersect1_robust", [&] { cullkit_bench::keep(robust->render1(cam, threads)); }});
        const auto result = cullkit_bench::race(race, field, reps);
        if (robust) {  // each contestant over the robust scene's median
          std::printf("frame_robust,%s", race.c_str());
          for (std::size_t k = 0; k + 1 < result.size(); ++k)
            std::printf(",%s=%.3f", result[k].name.c_str(), result[k].median_ns / result.back().median_ns);
          std::printf("\n");
        }
        for (std::size_t k = 0; k < g_paths.size(); ++k) {
          index[k]->select_visible(cam, ctx[k], out, nullptr);
          const NciSelectStats& st = ctx[k].stats;
          std::printf("nci_cells,%s,%s,%zu,%zu,%zu,%zu,%zu\n", race.c_str(), g_paths[k].name, st.cells_walked,
                      st.tiles_ray_cast, out.triangles_tested, st.triangles_met, st.triangles_no_pixel);
        }
        std::fflush(stdout);
      }
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 4 && !std::strcmp(argv[1], "--profile"))
    return profile(argv[2], std::atoi(argv[3]), argc >= 5 ? std::max(1, std::atoi(argv[4])) : 1);
  if (argc >= 3 && !std::strcmp(argv[1], "--frame-race")) {
    for (int i = 3; i < argc; ++i) {
      if (!std::strcmp(argv[i], "--robust")) g_robust = true;
      if (i < 4 || i + 1 >= argc) continue;
      if (!std::strcmp(argv[i], "--threads") && !parse_threads(argv[i + 1], g_threads)) return 2;
      if (!std::strcmp(argv[i], "--path") && !parse_paths(argv[i + 1], g_paths)) return 2;
    }
    return frame_race(argv[2], argc >= 4 && argv[3][0] != '-' ? std::max(1, std::atoi(argv[3])) : 5);
  }
  const bool smoke = cullkit_bench::smoke();
  bool big = !smoke, small = true, precision = true, timing = true, hash = false, no_precision = false;
  bool foliage = !smoke;
  if (std::getenv("CULLKIT_NCI_PATH")) {  // the environment's path, unless --path says otherwise
    NciParams env;
    path_from_env(env);
    g_paths = {{env.crowded_path, env.crowded_path == NciCrowdedPath::walk_only   ? "walk"
                                  : env.crowded_path == NciCrowdedPath::rays_only ? "rays"
                                                                                   : "auto"}};
  }
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--no-big")) big = foliage = false;
    if (!std::strcmp(argv[i], "--only-big")) small = precision = timing = false;
    if (!std::strcmp(argv[i], "--only-foliage")) small = precision = timing = big = false, foliage = true;
    if (!std::strcmp(argv[i], "--no-precision")) precision = false, no_precision = true;
    if (!std::strcmp(argv[i], "--quick")) g_quick = true;
    if (!std::strcmp(argv[i], "--robust")) g_robust = true;
    if (!std::strcmp(argv[i], "--foliage-trees") && (i + 1 >= argc || (g_foliage_trees = std::atoi(argv[++i])) < 1)) {
      std::fprintf(stderr, "--foliage-trees: a positive count of trees per side\n");
      return 2;
    }
    if (!std::strcmp(argv[i], "--hash")) hash = true;
    if (!std::strcmp(argv[i], "--path") && (i + 1 >= argc || !parse_paths(argv[++i], g_paths))) {
      std::fprintf(stderr, "--path: a comma-separated list of walk, rays, auto\n");
      return 2;
    }
    if (!std::strcmp(argv[i], "--threads") && (i + 1 >= argc || !parse_threads(argv[++i], g_threads))) {
      std::fprintf(stderr, "--threads: a comma-separated list of thread counts\n");
      return 2;
    }
  }
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::printf("# threads=%u\n", threads);
  std::printf("# nci_precision,scene,triangles,classes,grid,build_s,tested_per_visible,bytes_per_triangle,tested,"
              "visible,selected\n# embree_build,scene,triangles,build_s,bytes_per_triangle\n");
  std::vector<std::pair<std::string, Scene>> scenes;
  scenes.emplace_back("city", support::make_city(7, smoke ? 3 : 20));
  if (!smoke) {
    for (const auto& f : support::real_scene_files()) {
      auto s = support::load_obj(support::scenes_dir() + "/" + f);
      if (s) scenes.emplace_back(f, std::move(*s));
    }
  }
  if (hash) precision = timing = false;
  if (!hash && (timing || big)) {
    std::printf("# races at");
    for (unsigned t : g_threads) std::printf(" %u", t);
    std::printf(" threads (build and precision at %u); paths", threads);
    for (const PathChoice& p : g_paths) std::printf(" %s", p.name);
    std::printf("\n# nci_cells,race,path,cells_walked,tiles_ray_cast,tested,triangles_met,triangles_no_pixel\n"
                "# nci_path_ratio,race,path_over_first_path,median_ratio\n");
    if (g_robust)
      std::printf("# embree_build_robust,scene,triangles,build_s,bytes_per_triangle\n"
                  "# nci_robust,race,path,select_over_rtcIntersect1,select_over_robust,rtcIntersect1_over_robust,"
                  "pixels_hit,pixels_hit_robust,pixels_hitting_another_triangle\n");
  }
  for (const auto& [name, s] : scenes) {
    if (hash && small) pixel_hash(name, s, threads);
    if (precision) precision_table(name, s, threads, smoke);
    if (timing) speed(name, s, threads, smoke);
  }
  if (big) {
    // >= 10M triangles: a large generated city.
    Scene s = support::make_city(8, 284);
    std::printf("# big scene: %zu triangles\n", s.triangle_count());
    if (hash) {
      pixel_hash("bigcity", s, threads);
    } else {
      if (!no_precision) precision_table("bigcity", s, threads, smoke);
      speed("bigcity", s, threads, smoke);
    }
  }
  if (big || foliage) {
    // >= 10M triangles of crowded foliage: trees of small leaves, seen whole and from above.
    Scene s = support::make_foliage(1, g_foliage_trees, 2280);
    std::printf("# foliage scene: %zu triangles\n", s.triangle_count());
    if (hash) {
      pixel_hash("foliage", s, threads, true);
    } else {
      if (!no_precision) precision_table("foliage", s, threads, smoke, true);
      speed("foliage", s, threads, smoke, true);
    }
  }
  return 0;
}
