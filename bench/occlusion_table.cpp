// bench/occlusion_table.cpp: the occlusion seed's Table 1 (基于主要遮挡物的动态可见性算法, §4) on our
// scenes, with the column the seed could not give (what is exactly visible, from Embree) and a
// false-cull count that must be zero.
//
// The seed reports, per scene, the polygons left after frustum culling and after frustum + occlusion
// culling as a share of all polygons: City, 7,952 polygons, 30.2% and 7.6%; Office, 30,343
// polygons, 25.7% and 6.57%. It does not say how many views or where; we average over many.
//
// Columns (every percentage is the mean over the scene's cameras of a per-camera ratio; the
// denominator is always the scene's total triangle count):
//   polygons   triangles in the scene.
//   objects    objects in the scene (the units the ABT culls; a kept object keeps all its triangles).
//   cameras    views averaged over (placement below).
//   frustum %  triangles of the objects `AdaptiveBinaryTree::cull(frustum, out)` keeps.
//   +occl. %   triangles of the objects `cull_with_occlusion` keeps (ABT walked front to back from
//              the eye, occlusion tree grown from the visible occluders; default parameters).
//   visible %  triangles of the objects Embree really sees: objects with at least one pixel whose
//              first hit (one ray per pixel centre, cullkit::Camera rule, front faces only) is one of
//              their triangles, counted only among objects the frustum pass keeps, because pixel rays
//              are not clipped by the near and far planes while the frustum is. This is the floor any
//              object-level culler can reach at this resolution.
//   tri vis %  distinct triangles hit by some pixel ray (of objects in the frustum set): the floor of
//              a triangle-level culler, for scale.
//   pixels hit %  pixels whose ray hits anything (how much of the view is not sky), for judging
//              the camera placement.
//   occluders/frame  occluders accepted into the occlusion tree per frame (OcclusionStats).
//   false culls  (object, camera) pairs where Embree sees an object of the frustum set that occlusion
//              culling dropped. Must be 0: the program exits with status 1 otherwise.
//   frustum ms, +occl. ms  mean wall time per frame of the ABT frustum cull, and of tree reset +
//              cull_with_occlusion (single thread, Release, measured inside this loop; the Embree
//              render is not timed).
//
// Occluders. Generated city and office: `BoxOccluderSource`, i.e. every object flagged
// `major_occluder && is_box` (buildings; wall pieces) is inserted as a solid box once found visible.
// Real scenes carry no such flags; we use the rule of tests/occlusion/scene_cull.hpp: the "big"
// triangles of each object (area >= (0.03 x scene diagonal)^2) that face the eye are inserted as
// polygon occluders. They are real surfaces, and since a pixel ray hits a triangle from its front
// (Embree here, the cullkit::Camera rule), whatever lies wholly behind a front-facing triangle in its
// beam is hidden; back-facing triangles are never used. No occluder is invented.
//
// Cameras (seeded, so every run gives the same table):
//   city    street level: eye 1.7 m above the ground at a random point of the city that is not
//           within 0.5 m of any object's box (rejection sampling: never inside a building, a car or a
//           lamp post), looking in a random horizontal direction, pitched between -3 and +9 degrees.
//   office  inside a random room (the room's floor tile), 0.4 m clear of the room's edges and not
//           within 0.3 m of any object's box (desks, chairs, cabinets), eye 1.6 m high, random
//           heading, pitched between -17 and +3 degrees.
//   real    as the Embree occlusion test does it (occlusion_test::make_cameras): eyes at 5-25% of
//           the scene's height (one in ten at 30-120%) over random points of the scene box, looking
//           at random points of its lower part; one in ten with a 2 m near plane, one in ten with an
//           infinite far plane.
//   real, ground  for the two outdoor scenes in metres (fzk_haus, lasdunasarena) an extra row with
//           eyes 1.7 m above the first up-facing surface under a random point (ground or roof), the
//           way the scenes' README suggests; heading toward the scene's centre +- 45 degrees,
//           pitched between -10 and +5 degrees.
// Projection: 60 degree vertical field of view, near 0.1, far = the scene box's diagonal for the
// generated scenes (so the frustum is the view cone over the whole scene), OpenGL depth range.
//
// Usage: bench_occlusion_table [cameras=100] [width=640] [height=480] [--skip-big N]
//   --skip-big N leaves out the N biggest real scenes (default 0: all present are run).
// CULLKIT_BENCH_SMOKE=1: one small city, 3 cameras, 160x120.
#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../tests/occlusion/scene_cull.hpp"
#include "race.hpp"

using namespace cullkit;
using occlusion_test::CullScene;

namespace {

struct Row {
  std::string scene;
  std::size_t triangles = 0, objects = 0, cameras = 0;
  double frustum = 0, occlusion = 0, visible = 0, tri_visible = 0;  // sums of per-camera fractions
  double occluders = 0, pixels_hit = 0;
  long false_culls = 0;
  double frustum_ms = 0, occlusion_ms = 0;
  double seconds = 0;
};

double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

bool near_any_box(const std::vector<Aabb>& boxes, const glm::vec3& p, float margin) {
  for (const Aabb& b : boxes) {
    if (p.x >= b.min.x - margin && p.x <= b.max.x + margin && p.y >= b.min.y - margin && p.y <= b.max.y + margin &&
        p.z >= b.min.z - margin && p.z <= b.max.z + margin)
      return true;
  }
  return false;
}

float diagonal(const Aabb& b) { return glm::length(b.max - b.min); }

glm::vec3 heading(support::Rng& rng, float pitch_lo_deg, float pitch_hi_deg) {
  const float yaw = rng.uniform(0.0f, 6.2831853f);
  const float pitch = rng.uniform(pitch_lo_deg, pitch_hi_deg) * (3.14159265f / 180.0f);
  return glm::vec3(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
}

std::vector<Camera> city_cameras(const CullScene& cs, std::uint32_t seed, int count, int width, int height) {
  support::Rng rng(seed);
  std::vector<Camera> cams;
  const Aabb sb = cs.scene.bounds;
  const float far_plane = diagonal(sb);
  for (int tries = 0; static_cast<int>(cams.size()) < count && tries < 1000 * count; ++tries) {
    const glm::vec3 eye(rng.uniform(sb.min.x, sb.max.x), sb.min.y + 1.7f, rng.uniform(sb.min.z, sb.max.z));
    if (near_any_box(cs.bounds, eye, 0.5f)) continue;
    cams.push_back(support::make_camera(eye, eye + heading(rng, -3.0f, 9.0f), 60.0f, width, height, 0.1f, far_plane));
  }
  return cams;
}

std::vector<Camera> office_cameras(const CullScene& cs, std::uint32_t seed, int count, int width, int height) {
  support::Rng rng(seed);
  std::vector<Aabb> rooms;
  for (const auto& o : cs.scene.objects)
    if (o.name.rfind("floor_", 0) == 0) rooms.push_back(o.bounds);
  std::vector<Camera> cams;
  if (rooms.empty()) return cams;
  const float far_plane = diagonal(cs.scene.bounds);
  for (int tries = 0; static_cast<int>(cams.size()) < count && tries < 1000 * count; ++tries) {
    const Aabb& r = rooms[rng.next() % rooms.size()];
    const glm::vec3 eye(rng.uniform(r.min.x + 0.4f, r.max.x - 0.4f), r.max.y + 1.6f,
                        rng.uniform(r.min.z + 0.4f, r.max.z - 0.4f));
    if (near_any_box(cs.bounds, eye, 0.3f)) continue;
    cams.push_back(support::make_camera(eye, eye + heading(rng, -17.0f, 3.0f), 60.0f, width, height, 0.1f, far_plane));
  }
  return cams;
}

// Outdoor real scenes in metres (README of the scenes: cast a ray down, put the eye 1.7 m above
// what it hits): eyes 1.7 m over the first up-facing surface below a random point of the scene box
// (the ground, or a roof: pixel rays hit front faces only, so a downward ray stops on surfaces that
// face up), heading toward the scene's centre turned by up to 45 degrees either way, pitched between
// -10 and +5 degrees.
std::vector<Camera> ground_cameras(const CullScene& cs, std::uint32_t seed, int count, int width, int height) {
  support::Rng rng(seed);
  std::vector<Camera> cams;
  const Aabb sb = cs.scene.bounds;
  const float far_plane = diagonal(sb);
  for (int tries = 0; static_cast<int>(cams.size()) < count && tries < 100 * count; ++tries) {
    const Ray down{glm::vec3(rng.uniform(sb.min.x, sb.max.x), sb.max.y + 1.0f, rng.uniform(sb.min.z, sb.max.z)),
                   glm::vec3(0.0f, -1.0f, 0.0f)};
    float t = 0;
    if (cs.embree.first_hit(down, &t) == oracle::HitBuffer::miss) continue;
    const glm::vec3 eye = down.origin + glm::vec3(0.0f, 1.7f - t, 0.0f);
    // Heading: toward the scene's centre, turned by up to 45 degrees either way.
    const glm::vec3 to_centre = sb.center() - eye;
    const float yaw = std::atan2(to_centre.z, to_centre.x) + rng.uniform(-0.785398f, 0.785398f);
    const float pitch = rng.uniform(-10.0f, 5.0f) * (3.14159265f / 180.0f);
    const glm::vec3 dir(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
    cams.push_back(support::make_camera(eye, eye + dir, 60.0f, width, height, 0.1f, far_plane));
  }
  return cams;
}

// One scene, every camera: the frustum pass, the occlusion pass, Embree, and the comparison.
template <class Occluders>
Row measure(const std::string& name, const CullScene& cs, const std::vector<Camera>& cams, Occluders&& occluders) {
  const auto t_start = std::chrono::steady_clock::now();
  Row row;
  row.scene = name;
  row.triangles = cs.scene.triangle_count();
  row.objects = cs.scene.objects.size();
  row.cameras = cams.size();
  const double total = static_cast<double>(std::max<std::size_t>(row.triangles, 1));

  std::vector<std::uint32_t> in_frustum, kept;
  std::vector<std::uint8_t> frustum_flag(row.objects, 0), kept_flag(row.objects, 0), seen(row.objects, 0);
  OcclusionTree tree(glm::vec3(0.0f));
  const auto tris_of = [&](const std::vector<std::uint32_t>& objects) {
    double n = 0;
    for (std::uint32_t o : objects) n += cs.scene.objects[o].triangle_count;
    return n;
  };

  for (std::size_t c = 0; c < cams.size(); ++c) {
    const Camera& cam = cams[c];
    const Frustum frustum = Frustum::from_matrix(cam.view_proj, cam.depth);

    const auto t0 = std::chrono::steady_clock::now();
    cs.abt.cull(frustum, in_frustum);
    const auto t1 = std::chrono::steady_clock::now();
    tree.reset(cam.eye);
    cull_with_occlusion(cs.abt, frustum, tree, occluders, kept);
    const auto t2 = std::chrono::steady_clock::now();
    row.frustum_ms += ms_between(t0, t1);
    row.occlusion_ms += ms_between(t1, t2);
    row.occluders += tree.stats().occluders_inserted;

    row.frustum += tris_of(in_frustum) / total;
    row.occlusion += tris_of(kept) / total;

    std::fill(frustum_flag.begin(), frustum_flag.end(), 0);
    std::fill(kept_flag.begin(), kept_flag.end(), 0);
    std::fill(seen.begin(), seen.end(), 0);
    for (std::uint32_t o : in_frustum) frustum_flag[o] = 1;
    for (std::uint32_t o : kept) kept_flag[o] = 1;

    const auto hits = cs.embree.render(cam, 0);
    std::vector<std::uint32_t> hit_tris;
    hit_tris.reserve(hits.triangle.size());
    for (std::uint32_t t : hits.triangle)
      if (t != oracle::HitBuffer::miss) hit_tris.push_back(t);
    row.pixels_hit += static_cast<double>(hit_tris.size()) / static_cast<double>(std::max<std::size_t>(hits.triangle.size(), 1));
    std::sort(hit_tris.begin(), hit_tris.end());
    hit_tris.erase(std::unique(hit_tris.begin(), hit_tris.end()), hit_tris.end());
    double tri_visible = 0;
    for (std::uint32_t t : hit_tris) {
      const std::uint32_t o = cs.triangle_object[t];
      if (!frustum_flag[o]) continue;  // rays are not clipped by near/far; the frustum is
      seen[o] = 1;
      tri_visible += 1;
    }
    double obj_visible = 0;
    for (std::uint32_t o = 0; o < row.objects; ++o) {
      if (!seen[o]) continue;
      obj_visible += cs.scene.objects[o].triangle_count;
      if (!kept_flag[o]) {
        ++row.false_culls;
        std::fprintf(stderr, "FALSE CULL: %s camera %zu (eye %.7g %.7g %.7g): object %u (%s) is visible but culled\n",
                     name.c_str(), c, cam.eye.x, cam.eye.y, cam.eye.z, o, cs.scene.objects[o].name.c_str());
      }
    }
    row.visible += obj_visible / total;
    row.tri_visible += tri_visible / total;
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  row.frustum /= n;
  row.occlusion /= n;
  row.visible /= n;
  row.tri_visible /= n;
  row.occluders /= n;
  row.pixels_hit /= n;
  row.frustum_ms /= n;
  row.occlusion_ms /= n;
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return row;
}

void print_header() {
  std::printf("| scene | polygons | objects | cameras | frustum %% | +occlusion %% | visible %% (objects) | "
              "visible %% (triangles) | pixels hit %% | occluders/frame | false culls | frustum ms | +occlusion ms |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

void print_row(const Row& r) {
  std::printf("| %s | %zu | %zu | %zu | %.1f | %.2f | %.2f | %.3f | %.1f | %.1f | %ld | %.3f | %.3f |\n", r.scene.c_str(),
              r.triangles, r.objects, r.cameras, 100.0 * r.frustum, 100.0 * r.occlusion, 100.0 * r.visible,
              100.0 * r.tri_visible, 100.0 * r.pixels_hit, r.occluders, r.false_culls, r.frustum_ms, r.occlusion_ms);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  const bool smoke = cullkit_bench::smoke();
  int cameras = smoke ? 3 : 100, width = smoke ? 160 : 640, height = smoke ? 120 : 480;
  int skip_big = 0;
  float big_fraction = 0.03f;
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--skip-big") == 0 && i + 1 < argc) {
      skip_big = std::atoi(argv[++i]);
      continue;
    }
    if (std::strcmp(argv[i], "--big-fraction") == 0 && i + 1 < argc) {
      big_fraction = static_cast<float>(std::atof(argv[++i]));
      continue;
    }
    const int v = std::atoi(argv[i]);
    if (v <= 0) {
      std::fprintf(stderr, "usage: %s [cameras] [width] [height] [--skip-big N]\n", argv[0]);
      return 2;
    }
    if (positional == 0) cameras = v;
    else if (positional == 1) width = v;
    else if (positional == 2) height = v;
    ++positional;
  }
  const auto t_all = std::chrono::steady_clock::now();
  std::printf("Seed (基于主要遮挡物的动态可见性算法, Table 1): City 7,952 polygons, 30.2%% after frustum culling, "
              "7.6%% after occlusion; Office 30,343 polygons, 25.7%% and 6.57%%.\n");
  std::printf("Ours: %d cameras per scene (fewer if placement ran out), visibility at %dx%d, one ray per pixel.\n\n",
              cameras, width, height);

  std::vector<Row> rows;
  long false_culls = 0;
  const auto box_run = [&](const std::string& label, support::Scene scene, bool city, std::uint32_t seed) {
    const CullScene cs(std::move(scene));
    const auto cams = city ? city_cameras(cs, seed, cameras, width, height) : office_cameras(cs, seed, cameras, width, height);
    const BoxOccluderSource source{cs.bounds.data(), cs.box_occluder.data()};
    rows.push_back(measure(label, cs, cams, source));
    false_culls += rows.back().false_culls;
    std::fprintf(stderr, "%s: %.1f s\n", label.c_str(), rows.back().seconds);
  };

  if (smoke) {
    box_run("city (3 blocks, smoke)", support::make_city(1, 3), true, 11u);
  } else {
    box_run("city (make_city(1, 8))", support::make_city(1, 8), true, 11u);
    box_run("city 10x (make_city(1, 26))", support::make_city(1, 26), true, 12u);
    box_run("office (make_office(1, 10, 8))", support::make_office(1, 10, 8), false, 13u);
    box_run("office 10x (make_office(1, 32, 25))", support::make_office(1, 32, 25), false, 14u);

    auto files = support::real_scene_files();  // smallest first
    const std::size_t run_count = files.size() > static_cast<std::size_t>(skip_big) ? files.size() - skip_big : 0;
    for (std::size_t i = 0; i < files.size(); ++i) {
      if (i >= run_count) {
        std::fprintf(stderr, "%s: skipped (--skip-big)\n", files[i].c_str());
        continue;
      }
      auto s = support::load_obj(support::scenes_dir() + "/" + files[i]);
      if (!s) {
        std::fprintf(stderr, "%s: could not be loaded, skipped\n", files[i].c_str());
        continue;
      }
      const CullScene cs(std::move(*s), big_fraction);
      const auto cams = occlusion_test::make_cameras(cs, 1234u + static_cast<std::uint32_t>(i), cameras, width, height);
      rows.push_back(measure(files[i], cs, cams,
                             [&](std::uint32_t o, OcclusionTree& t) { cs.insert_occluders(o, t); }));
      false_culls += rows.back().false_culls;
      std::fprintf(stderr, "%s: %.1f s\n", files[i].c_str(), rows.back().seconds);
      if (files[i] == "lasdunasarena.obj" || files[i] == "fzk_haus.obj") {  // metres, Y up, outdoors
        const auto ground = ground_cameras(cs, 4321u + static_cast<std::uint32_t>(i), cameras, width, height);
        rows.push_back(measure(files[i] + " (eyes 1.7 m above ground)", cs, ground,
                               [&](std::uint32_t o, OcclusionTree& t) { cs.insert_occluders(o, t); }));
        false_culls += rows.back().false_culls;
        std::fprintf(stderr, "%s (ground): %.1f s\n", files[i].c_str(), rows.back().seconds);
      }
    }
  }

  print_header();
  for (const Row& r : rows) print_row(r);
  std::printf("\ntotal false culls: %ld; wall time %.1f s\n", false_culls,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t_all).count());
  return false_culls == 0 ? 0 : 1;
}
