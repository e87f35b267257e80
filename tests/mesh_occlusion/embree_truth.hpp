// tests/mesh_occlusion/embree_truth.hpp: what is truly visible from a camera, by Embree, under the
// MeshOcclusionCuller rule: an object is visible when some ray from the eye through the view frustum
// meets one of its front-facing triangles first, counting only what lies between the near and the
// far plane (the renderer clips the rest, so it is neither seen nor hides anything).
//
// Rays: every pixel centre at the camera's resolution, every pixel centre at a second resolution,
// and seeded sub-pixel positions anywhere on the screen rectangle, some of them exactly on its
// border. A culler answers for all rays through the frustum, not for one pixel grid.
//
// Shared by the Embree test, the benchmark and the picture example.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

#include <cullkit/mesh_occlusion_culler.hpp>

// Smaller screens and fewer cameras under sanitizers and in unoptimized builds (the suite runs
// three times in CI, once under ASan): MESH_OCC_SLOW is 1 there.
#ifndef MESH_OCC_SLOW
#if defined(__SANITIZE_ADDRESS__)
#define MESH_OCC_SLOW 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MESH_OCC_SLOW 1
#endif
#endif
#if !defined(MESH_OCC_SLOW) && !defined(__OPTIMIZE__)
#define MESH_OCC_SLOW 1
#endif
#ifndef MESH_OCC_SLOW
#define MESH_OCC_SLOW 0
#endif
#endif

namespace mesh_occlusion_test {

using namespace cullkit;

constexpr std::uint32_t no_object = 0xFFFFFFFFu;

/// The part [t0, t1] of the ray eye + t * dir (unit dir) that lies between the camera's near and far
/// planes, in clip space: the depth constraints (z + w >= 0 or z >= 0, and w - z >= 0) are linear in
/// t. Works for OpenGL and zero-to-one depth, reversed-Z and an infinite far plane (t1 = inf). False
/// if the ray has no such part.
inline bool depth_segment(const Camera& cam, const glm::vec3& dir, double& t0, double& t1) {
  const glm::dmat4 m(cam.view_proj);
  const glm::dvec4 c0 = m * glm::dvec4(glm::dvec3(cam.eye), 1.0);
  const glm::dvec4 c1 = m * glm::dvec4(glm::dvec3(dir), 0.0);
  t0 = 0.0;
  t1 = std::numeric_limits<double>::infinity();
  bool ok = true;
  const auto keep = [&](double g0, double g1) {  // g0 + t g1 >= 0
    if (g1 > 0.0) t0 = std::max(t0, -g0 / g1);
    else if (g1 < 0.0) t1 = std::min(t1, -g0 / g1);
    else if (!(g0 >= 0.0)) ok = false;
  };
  if (cam.depth == DepthRange::zero_to_one) keep(c0.z, c1.z);
  else keep(c0.z + c0.w, c1.z + c1.w);
  keep(c0.w - c0.z, c1.w - c1.z);
  return ok && t0 < t1 && std::isfinite(t0);
}

/// A scene with its objects in the culler's form and the triangle -> object map.
struct ObjectMap {
  std::vector<MeshObject> objects;
  std::vector<std::uint32_t> triangle_object;
  std::vector<std::uint32_t> triangle_count;  ///< per object

  explicit ObjectMap(const support::Scene& scene) {
    triangle_object.assign(scene.triangle_count(), no_object);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      const auto& so = scene.objects[o];
      objects.push_back(MeshObject{so.first_triangle, so.triangle_count});
      triangle_count.push_back(so.triangle_count);
      for (std::uint32_t t = so.first_triangle; t < so.first_triangle + so.triangle_count; ++t) triangle_object[t] = o;
    }
  }
};

/// The object whose front-facing triangle the ray meets first between the near and far planes,
/// or `no_object`. `hit_triangle` (optional) gets the triangle.
inline std::uint32_t first_object(const oracle::EmbreeScene& embree, const ObjectMap& map, const Camera& cam,
                                  const glm::vec3& dir, std::uint32_t* hit_triangle = nullptr) {
  if (hit_triangle) *hit_triangle = oracle::HitBuffer::miss;
  double t0 = 0, t1 = 0;
  if (!depth_segment(cam, dir, t0, t1)) return no_object;
  const glm::dvec3 origin = glm::dvec3(cam.eye) + glm::dvec3(dir) * t0;
  const float tfar = std::isfinite(t1) ? static_cast<float>(t1 - t0) : std::numeric_limits<float>::infinity();
  const std::uint32_t t = embree.first_hit(Ray{glm::vec3(origin), dir}, nullptr, tfar);
  if (t == oracle::HitBuffer::miss || t >= map.triangle_object.size()) return no_object;
  if (hit_triangle) *hit_triangle = t;
  return map.triangle_object[t];
}

/// Which rays to cast.
struct RaySet {
  int second_width = 257, second_height = 143;  ///< a second pixel grid (0: none)
  int jitter = 4096;                            ///< seeded sub-pixel positions; one in 8 on the border
  std::uint64_t seed = 1;
};

/// Calls `visit(direction, family)` for every ray of `rays` from `cam` (family 0 centres, 1 second
/// grid, 2 jitter, one in 8 of those on the screen's border).
template <class Visit>
void for_each_ray(const Camera& cam, const RaySet& rays, Visit&& visit) {
  const PixelRays centres(cam);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) visit(centres.ray(x, y).direction, std::uint8_t{0});
  if (rays.second_width > 0 && rays.second_height > 0) {
    Camera second = cam;
    second.width = rays.second_width;
    second.height = rays.second_height;
    const PixelRays grid(second);
    for (int y = 0; y < second.height; ++y)
      for (int x = 0; x < second.width; ++x) visit(grid.ray(x, y).direction, std::uint8_t{1});
  }
  support::Rng rng(rays.seed);
  for (int i = 0; i < rays.jitter; ++i) {
    double px = static_cast<double>(rng.uniform()) * cam.width;
    double py = static_cast<double>(rng.uniform()) * cam.height;
    if (i % 8 == 7) {  // on the screen's border: the frustum's side planes
      switch (rng.range(0, 3)) {
        case 0: px = 0.0; break;
        case 1: px = cam.width; break;
        case 2: py = 0.0; break;
        default: py = cam.height; break;
      }
    }
    visit(centres.ray_at(px, py).direction, std::uint8_t{2});
  }
}

/// Per object: 0 not seen, else 1 + the first ray family that saw it (0 centres, 1 second grid,
/// 2 jitter). Cost: one Embree ray per pixel of both grids plus `jitter` rays, single thread.
inline std::vector<std::uint8_t> truly_visible(const oracle::EmbreeScene& embree, const ObjectMap& map,
                                               const Camera& cam, const RaySet& rays) {
  std::vector<std::uint8_t> seen(map.objects.size(), 0);
  for_each_ray(cam, rays, [&](const glm::vec3& dir, std::uint8_t family) {
    if (dir == glm::vec3(0.0f)) return;
    const std::uint32_t o = first_object(embree, map, cam, dir);
    if (o != no_object && !seen[o]) seen[o] = static_cast<std::uint8_t>(1 + family);
  });
  return seen;
}

/// Objects whose bounds meet the camera's frustum (the frustum-only answer; brute force).
inline std::vector<std::uint32_t> frustum_objects(const support::Scene& scene, const Camera& cam) {
  const Frustum f = frustum_of(cam);
  std::vector<std::uint32_t> out;
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
    if (f.classify(scene.objects[o].bounds) != Containment::outside) out.push_back(o);
  return out;
}

/// Triangles of the listed objects.
inline double triangles_of(const ObjectMap& map, const std::vector<std::uint32_t>& objects) {
  double n = 0;
  for (std::uint32_t o : objects) n += map.triangle_count[o];
  return n;
}

}  // namespace mesh_occlusion_test
