// MeshOcclusionCuller against Embree: from every camera, every object that some ray through the view
// frustum sees first (front faces only, between the near and far planes) must be in the culler's
// answer. Rays: all pixel centres at the camera's resolution, all pixel centres at a second
// resolution, and seeded sub-pixel positions (one in eight on the screen's border), so an answer
// tuned to one pixel grid fails. Scenes: the generated city and office and every real scene present;
// cameras: a walk through each scene plus the hard cases (eye nearer a wall than the near plane, eye
// inside an object, grazing views along a wall, a far-out near plane, zero-to-one depth, reversed-Z
// finite and infinite). Also checks that the answer lists valid indices once each, that the oracle's
// near/far segment is right, and (non-vacuity) that dropping one truly visible object from the
// answer is caught. Prints per scene the triangles kept by the frustum alone, by the culler, and
// truly visible, as shares of the scene.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "check.hpp"
#include "embree_truth.hpp"
#include "walk_cameras.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

constexpr int kWidth = MESH_OCC_SLOW ? 160 : 320, kHeight = MESH_OCC_SLOW ? 90 : 180;
constexpr int kWalk = MESH_OCC_SLOW ? 3 : 12;

/// Every object whose bounds meet the frustum: passes the oracle by construction (a check of the
/// harness itself: the oracle never calls such an answer wrong).
struct FrustumOnly {
  const support::Scene* scene;
  void cull(const Camera& cam, std::vector<std::uint32_t>& out) const { out = frustum_objects(*scene, cam); }
};

struct Totals {
  std::size_t cameras = 0;
  long false_culls = 0;
  double frustum = 0, culler = 0, visible = 0;  // sums of per-camera triangle shares
  std::size_t found_by[3] = {0, 0, 0};          // visible objects by the ray family that first saw them
  std::size_t hidden_in_frustum = 0;            // (camera, object) pairs in the frustum but not visible
  std::size_t behind_near_wall = 0;             // objects seen only because the near plane clips a wall
};

/// Every scene's totals, for the checks that the harness can fail at all.
Totals& all_scenes() {
  static Totals t;
  return t;
}

/// Objects the near-plane oracle sees that rays from the eye itself do not (what a culler that lets
/// geometry nearer than the near plane occlude would get wrong).
std::size_t seen_only_past_near(const oracle::EmbreeScene& embree, const ObjectMap& map, const Camera& cam,
                                const std::vector<std::uint8_t>& seen) {
  std::vector<std::uint8_t> from_eye(seen.size(), 0);
  const PixelRays rays(cam);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const glm::vec3 dir = rays.ray(x, y).direction;
      double t0 = 0, t1 = 0;
      if (!depth_segment(cam, dir, t0, t1)) continue;
      const float tfar = std::isfinite(t1) ? static_cast<float>(t1) : std::numeric_limits<float>::infinity();
      const std::uint32_t t = embree.first_hit(Ray{cam.eye, dir}, nullptr, tfar);
      if (t < map.triangle_object.size()) from_eye[map.triangle_object[t]] = 1;
    }
  }
  std::size_t n = 0;
  for (std::size_t o = 0; o < seen.size(); ++o) n += seen[o] && !from_eye[o];
  return n;
}

/// Truly visible objects missing from `out`; also checks `out` holds valid indices once each.
long false_culls(const std::vector<std::uint32_t>& out, const std::vector<std::uint8_t>& seen, const char* what,
                 const std::string& where, bool report) {
  std::vector<std::uint8_t> kept(seen.size(), 0);
  bool valid = true;
  for (std::uint32_t o : out) {
    if (o >= kept.size() || kept[o]) {
      valid = false;
      continue;
    }
    kept[o] = 1;
  }
  if (report) CHECK_MSG(valid, "%s, %s: an index out of range or twice", where.c_str(), what);
  long missing = 0;
  for (std::size_t o = 0; o < seen.size(); ++o) {
    if (!seen[o] || kept[o]) continue;
    ++missing;
    if (report && missing <= 3)
      std::fprintf(stderr, "FALSE CULL %s, %s: object %zu visible (first seen by ray family %d)\n", where.c_str(), what,
                   o, seen[o] - 1);
  }
  return missing;
}

/// The oracle's near/far segment must start on the near plane: NDC depth there is the near value
/// (z = -1 or 0, 1 for reversed-Z), just past it inside the depth range, just before it outside.
void check_segment(const Camera& cam, const std::string& where) {
  const PixelRays rays(cam);
  const glm::dmat4 m(cam.view_proj);
  const auto depth_at = [&](const glm::vec3& dir, double t) {
    const glm::dvec4 c = m * glm::dvec4(glm::dvec3(cam.eye) + glm::dvec3(dir) * t, 1.0);
    return c.z / c.w;
  };
  const double lo = cam.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
  for (const auto& [px, py] : {std::pair<double, double>{0.5 * cam.width, 0.5 * cam.height}, {0.0, 0.0},
                               {double(cam.width), 0.3 * cam.height}}) {
    const glm::vec3 dir = rays.ray_at(px, py).direction;
    double t0 = 0, t1 = 0;
    const bool has_segment = depth_segment(cam, dir, t0, t1);
    CHECK_MSG(has_segment, "%s: no depth segment", where.c_str());
    if (!has_segment) continue;
    const double in = depth_at(dir, t0 * 1.001), out = depth_at(dir, t0 * 0.999);
    CHECK_MSG(in >= lo && in <= 1.0 && !(out >= lo && out <= 1.0), "%s: segment start %g: depth %g inside, %g before",
              where.c_str(), t0, in, out);
    if (std::isfinite(t1)) {
      const double past = depth_at(dir, t1 * 1.001);
      CHECK_MSG(!(past >= lo && past <= 1.0), "%s: segment end %g: depth %g past it", where.c_str(), t1, past);
    }
  }
}

template <class MakeCuller>
void run_scene(const std::string& name, const support::Scene& scene, MakeCuller&& make, std::uint64_t seed) {
  const auto t_start = std::chrono::steady_clock::now();
  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const ObjectMap map(scene);
  const auto culler = make(scene, map);
  const FrustumOnly frustum_only{&scene};

  const WalkSpec spec = walk_spec(name, scene, embree, seed);
  std::vector<NamedCamera> cams;
  const auto walk_cams = walk(spec, scene, embree, kWalk, 2, kWidth, kHeight, seed + 1);
  for (std::size_t i = 0; i < walk_cams.size(); ++i) cams.push_back({"walk " + std::to_string(i), walk_cams[i]});
  for (auto& h : hard_cameras(spec, scene, embree, walk_cams, kWidth, kHeight)) cams.push_back(h);

  Totals tot;
  const double total = static_cast<double>(std::max<std::size_t>(scene.triangle_count(), 1));
  std::vector<std::uint32_t> out;
  bool mutant_tried = false;
  std::vector<std::vector<std::uint32_t>> answers;  // sorted, per camera
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci].camera;
    char where_buf[256];
    std::snprintf(where_buf, sizeof where_buf, "%s camera %zu (%s, eye %.7g %.7g %.7g, seed %llu)", name.c_str(), ci,
                  cams[ci].name.c_str(), cam.eye.x, cam.eye.y, cam.eye.z, static_cast<unsigned long long>(seed));
    const std::string where = where_buf;
    check_segment(cam, where);
    RaySet rays;
    rays.second_width = MESH_OCC_SLOW ? 127 : 257;
    rays.second_height = MESH_OCC_SLOW ? 71 : 143;
    rays.jitter = MESH_OCC_SLOW ? 1024 : 4096;
    rays.seed = seed * 1000 + ci;
    const auto seen = truly_visible(embree, map, cam, rays);

    std::vector<std::uint32_t> visible;
    for (std::uint32_t o = 0; o < seen.size(); ++o)
      if (seen[o]) visible.push_back(o), ++tot.found_by[seen[o] - 1];

    frustum_only.cull(cam, out);
    CHECK(false_culls(out, seen, "frustum only", where, true) == 0);  // the oracle respects the frustum
    tot.frustum += triangles_of(map, out) / total;
    tot.hidden_in_frustum += out.size() - visible.size();

    culler.cull(cam, out);
    const long fc = false_culls(out, seen, "culler", where, true);
    CHECK_MSG(fc == 0, "%s: %ld false culls", where.c_str(), fc);
    tot.false_culls += fc;
    tot.culler += triangles_of(map, out) / total;
    tot.visible += triangles_of(map, visible) / total;
    ++tot.cameras;

    if (cams[ci].name.rfind("wall nearer", 0) == 0) tot.behind_near_wall += seen_only_past_near(embree, map, cam, seen);
    answers.push_back(out);
    std::sort(answers.back().begin(), answers.back().end());

    // Non-vacuity: the same answer without one truly visible object must be caught.
    if (!mutant_tried && !visible.empty()) {
      mutant_tried = true;
      const std::uint32_t drop = visible[visible.size() / 2];
      std::vector<std::uint32_t> mutant;
      for (std::uint32_t o : out)
        if (o != drop) mutant.push_back(o);
      CHECK_MSG(false_culls(mutant, seen, "mutant", where, false) == 1, "%s: mutant not caught", where.c_str());
    }
  }
  CHECK_MSG(mutant_tried, "%s: no camera saw anything", name.c_str());
  // Safe from several threads at once: two threads culling every camera (each with its own output)
  // give the single-threaded answers.
  std::vector<std::vector<std::uint32_t>> threaded(cams.size());
  const auto worker = [&](std::size_t first) {
    for (std::size_t ci = first; ci < cams.size(); ci += 2) {
      culler.cull(cams[ci].camera, threaded[ci]);
      std::sort(threaded[ci].begin(), threaded[ci].end());
    }
  };
  std::thread other(worker, 1);
  worker(0);
  other.join();
  for (std::size_t ci = 0; ci < cams.size(); ++ci)
    CHECK_MSG(threaded[ci] == answers[ci], "%s camera %zu: two threads disagree with one", name.c_str(), ci);
  all_scenes().found_by[1] += tot.found_by[1];
  all_scenes().found_by[2] += tot.found_by[2];
  all_scenes().behind_near_wall += tot.behind_near_wall;
  // Occlusion must happen on these cameras, or the test proves nothing about hiding (a single-object
  // scene has nothing to hide behind).
  if (scene.objects.size() > 1) CHECK_MSG(tot.hidden_in_frustum > 0, "%s: every object in every frustum is visible", name.c_str());
  const double n = static_cast<double>(std::max<std::size_t>(tot.cameras, 1));
  std::printf("| %s | %zu | %zu | %zu | %.2f | %.2f | %.2f | %ld | %zu / %zu / %zu | %.1f |\n", name.c_str(),
              scene.triangle_count(), scene.objects.size(), tot.cameras, 100.0 * tot.frustum / n,
              100.0 * tot.culler / n, 100.0 * tot.visible / n, tot.false_culls, tot.found_by[0], tot.found_by[1],
              tot.found_by[2], std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
  std::fflush(stdout);
}

template <class MakeCuller>
void run_all(MakeCuller&& make) {
  std::printf("| scene | triangles | objects | cameras | frustum %% | culler %% | visible %% | false culls | "
              "visible objects first seen by centres / 2nd grid / sub-pixel | s |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---|---:|\n");
  {
    const auto city = support::make_city(3, MESH_OCC_SLOW ? 4 : 8);
    run_scene("city", city, make, 31);
  }
  {
    const auto office = support::make_office(3, MESH_OCC_SLOW ? 5 : 10, MESH_OCC_SLOW ? 4 : 8);
    run_scene("office", office, make, 37);
  }
  const auto files = support::real_scene_files();
  if (files.empty()) std::printf("real scenes absent: skipped\n");
  std::uint64_t seed = 41;
  for (const auto& file : files) {
    const auto scene = support::load_obj(support::scenes_dir() + "/" + file);
    if (!scene) {
      std::printf("%s: could not load, skipped\n", file.c_str());
      continue;
    }
    if (MESH_OCC_SLOW && scene->triangle_count() > 100000) {
      std::printf("%s: large, skipped in slow builds\n", file.c_str());
      continue;
    }
    run_scene(file, *scene, make, seed++);
  }
}

}  // namespace

int main() {
  std::printf("MeshOcclusionCuller (default parameters), %dx%d:\n", kWidth, kHeight);
  run_all([](const support::Scene& s, const ObjectMap& map) {
    return MeshOcclusionCuller<glm::vec3>(s.mesh(), map.objects.data(), map.objects.size());
  });
  // The harness can fail: an answer built from the camera's pixel centres alone misses objects the
  // second grid and the sub-pixel rays find, and one that lets a wall nearer than the near plane
  // hide what is behind it misses objects seen past the clipped wall.
  std::printf("visible objects no pixel centre found: %zu by the second grid, %zu by sub-pixel rays; "
              "objects seen only past a wall nearer than the near plane: %zu\n",
              all_scenes().found_by[1], all_scenes().found_by[2], all_scenes().behind_near_wall);
  CHECK(all_scenes().found_by[1] > 0 && all_scenes().found_by[2] > 0);
  CHECK(all_scenes().behind_near_wall > 0);
  return cullkit_test::report("test_mesh_occlusion_embree");
}
