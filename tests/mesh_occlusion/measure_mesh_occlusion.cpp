// measure_mesh_occlusion: MeshOcclusionCuller on a real scene, for the numbers in
// docs/mesh_occlusion.md (not a test: it prints, and exits 1 only on a false cull).
//
// Usage: measure_mesh_occlusion <scene.obj> [cameras=30] [width=960]
// Environment: GW, GH, BUDGET, RATIO, MINFRAC override the MeshOcclusionParams fields.
// Cameras (seeded): oacmpdm9 from its info_player_deathmatch origins (eye 40 units up, near 4);
// other scenes at random points 5-25% up the scene box (near 0.1); random heading, slight pitch,
// 60 degree vertical field of view, infinite far plane. Per camera: cull CPU time (median of 5,
// one thread), triangles of the objects kept (frustum only, and with occlusion), triangles of the
// frustum's objects Embree sees (one ray per pixel), and false culls (seen but left out).
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "oracle/embree_oracle.hpp"

using namespace cullkit;

namespace {
std::vector<glm::vec3> openarena_spawns() {
  std::ifstream f(support::scenes_dir() + "/oacmpdm9.json");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  std::vector<glm::vec3> out;
  for (std::size_t p = 0; (p = s.find("info_player_deathmatch", p)) != std::string::npos;) {
    const std::size_t b = s.rfind('{', p), e = s.find('}', p);
    const std::string entity = s.substr(b, e - b);
    const std::size_t o = entity.find("origin");
    if (o != std::string::npos) {
      float x, y, z;
      const std::size_t q = entity.find_first_of("-0123456789", o + 6);
      if (q != std::string::npos && std::sscanf(entity.c_str() + q, "%f %f %f", &x, &y, &z) == 3) out.push_back({x, z + 40, -y});
    }
    p = e;
  }
  return out;
}
double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <scene.obj> [cameras] [width]\n", argv[0]);
    return 2;
  }
  const std::string name = argv[1];
  const int camera_count = argc > 2 ? std::atoi(argv[2]) : 30;
  const int width = argc > 3 ? std::atoi(argv[3]) : 960, height = width * 9 / 16;
  const auto scene = support::load_obj(support::scenes_dir() + "/" + name);
  if (!scene) {
    std::printf("%s: not found, nothing measured\n", name.c_str());
    return 0;
  }
  std::vector<MeshObject> objects;
  for (const auto& o : scene->objects) objects.push_back({o.first_triangle, o.triangle_count});
  MeshOcclusionParams params;
  if (const char* v = std::getenv("GW")) params.grid_width = std::atoi(v);
  if (const char* v = std::getenv("GH")) params.grid_height = std::atoi(v);
  if (const char* v = std::getenv("BUDGET")) params.occluder_triangle_budget = static_cast<std::uint32_t>(std::atoi(v));
  if (const char* v = std::getenv("RATIO")) params.depth_band_ratio = static_cast<float>(std::atof(v));
  if (const char* v = std::getenv("MINFRAC")) params.min_occluder_screen_fraction = static_cast<float>(std::atof(v));
  const double b0 = cpu_ms();
  const MeshOcclusionCuller<glm::vec3> culler(scene->mesh(), objects.data(), objects.size(), params);
  const double build = cpu_ms() - b0;
  const auto& bs = culler.build_stats();
  std::printf("%s: %zu triangles, %zu objects; build %.0f ms; %zu welded vertices, %zu shared edges, %zu degenerate\n",
              name.c_str(), scene->triangle_count(), objects.size(), build, bs.welded_vertices, bs.shared_edges,
              bs.triangles_degenerate);
  oracle::EmbreeScene embree;
  embree.add_mesh(scene->positions.data(), scene->positions.size(), scene->indices.data(), scene->indices.size());
  embree.commit();
  std::vector<std::uint32_t> owner(scene->triangle_count(), 0xffffffffu);
  for (std::uint32_t o = 0; o < objects.size(); ++o)
    for (std::uint32_t t = 0; t < objects[o].triangle_count; ++t) owner[objects[o].first_triangle + t] = o;
  std::vector<Aabb> bounds;
  for (const auto& o : scene->objects) bounds.push_back(o.bounds);
  const AdaptiveBinaryTree<Aabb> tree(bounds.data(), bounds.size());

  support::Rng rng(77);
  const Aabb sb = scene->bounds;
  const bool arena = name == "oacmpdm9.obj";
  const std::vector<glm::vec3> spawns = arena ? openarena_spawns() : std::vector<glm::vec3>{};
  MeshOcclusionContext context;
  std::vector<std::uint32_t> out, frustum_out;
  std::vector<double> times;
  double frustum = 0, kept = 0, visible = 0, occluders = 0, occluder_triangles = 0;
  long false_culls = 0;
  const double total = static_cast<double>(scene->triangle_count());
  for (int i = 0; i < camera_count; ++i) {
    const glm::vec3 eye = !spawns.empty() ? spawns[static_cast<std::size_t>(i) % spawns.size()]
                                          : glm::vec3(rng.uniform(sb.min.x, sb.max.x),
                                                      sb.min.y + rng.uniform(0.05f, 0.25f) * (sb.max.y - sb.min.y),
                                                      rng.uniform(sb.min.z, sb.max.z));
    const float yaw = rng.uniform(0.0f, 6.2831853f), pitch = rng.uniform(-0.2f, 0.1f);
    const glm::vec3 dir(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
    const Camera cam = support::make_camera(eye, eye + dir, 60.0f, width, height, arena ? 4.0f : 0.1f, 0.0f);
    std::vector<double> ts;
    for (int r = 0; r < 5; ++r) {
      const double a = cpu_ms();
      culler.cull(cam, context, out);
      ts.push_back(cpu_ms() - a);
    }
    std::sort(ts.begin(), ts.end());
    times.push_back(ts[2]);
    occluders += static_cast<double>(context.stats().occluders_used);
    occluder_triangles += static_cast<double>(context.stats().occluder_triangles);
    tree.cull(frustum_of(cam), frustum_out);
    std::vector<char> is_kept(objects.size(), 0), in_frustum(objects.size(), 0), seen(objects.size(), 0);
    for (std::uint32_t o : out) {
      is_kept[o] = 1;
      kept += objects[o].triangle_count / total;
    }
    for (std::uint32_t o : frustum_out) {
      in_frustum[o] = 1;
      frustum += objects[o].triangle_count / total;
    }
    const auto hits = embree.render(cam);
    for (std::uint32_t t : hits.triangle)
      if (t != oracle::HitBuffer::miss && owner[t] != 0xffffffffu) seen[owner[t]] = 1;
    for (std::uint32_t o = 0; o < objects.size(); ++o) {
      if (seen[o] && in_frustum[o]) visible += objects[o].triangle_count / total;
      if (seen[o] && !is_kept[o]) {
        ++false_culls;
        std::printf("FALSE CULL: camera %d object %u (%s)\n", i, o, scene->objects[o].name.c_str());
      }
    }
  }
  std::sort(times.begin(), times.end());
  const double n = camera_count;
  std::printf("%d cameras %dx%d, grid %dx%d: visible %.2f%%, frustum %.2f%%, kept %.2f%%, false culls %ld; cull ms median "
              "%.3f, p90 %.3f; occluder objects %.0f, triangles %.0f per frame\n",
              camera_count, width, height, culler.params().grid_width, culler.params().grid_height, 100 * visible / n,
              100 * frustum / n, 100 * kept / n, false_culls, times[times.size() / 2], times[times.size() * 9 / 10],
              occluders / n, occluder_triangles / n);
  return false_culls == 0 ? 0 : 1;
}
