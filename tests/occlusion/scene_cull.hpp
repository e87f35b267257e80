// tests/occlusion/scene_cull.hpp: shared by the Embree test and the seed's table: a scene, its
// ABT, occluder flags, cameras, and one culling pass checked against Embree.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit/occlusion_culling.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

namespace occlusion_test {

using namespace cullkit;

/// A scene ready for culling: the ABT over object bounds, per-object occluder data, the Embree scene.
struct CullScene {
  support::Scene scene;
  std::vector<Aabb> bounds;
  std::vector<std::uint8_t> box_occluder;             // object is a major occluder and a solid box
  std::vector<std::vector<std::uint32_t>> big_tris;   // per object: triangles used as polygon occluders
  std::vector<std::uint32_t> triangle_object;         // triangle -> object
  AdaptiveBinaryTree<Aabb> abt;
  oracle::EmbreeScene embree;

  explicit CullScene(support::Scene s, float big_triangle_fraction = 0.03f) : scene(std::move(s)) {
    bounds = scene.object_bounds();
    box_occluder.assign(scene.objects.size(), 0);
    big_tris.resize(scene.objects.size());
    triangle_object.assign(scene.triangle_count(), 0);
    const glm::vec3 ext = scene.bounds.max - scene.bounds.min;
    const float big = glm::length(ext) * big_triangle_fraction;
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      const auto& obj = scene.objects[o];
      for (std::uint32_t t = obj.first_triangle; t < obj.first_triangle + obj.triangle_count; ++t) {
        triangle_object[t] = o;
        if (obj.major_occluder && obj.is_box) continue;
        const glm::vec3 a = scene.positions[scene.indices[3 * t]], b = scene.positions[scene.indices[3 * t + 1]],
                        c = scene.positions[scene.indices[3 * t + 2]];
        if (0.5f * glm::length(glm::cross(b - a, c - a)) >= big * big) big_tris[o].push_back(t);
      }
      box_occluder[o] = obj.major_occluder && obj.is_box;
    }
    abt = AdaptiveBinaryTree<Aabb>(bounds.data(), bounds.size());
    embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
    embree.commit();
  }

  /// Inserts the occluders of a visible object: its box if it is a solid major occluder, else its
  /// big triangles that face the eye (Embree hits only front faces, so back faces must not occlude).
  void insert_occluders(std::uint32_t o, OcclusionTree& tree) const {
    if (box_occluder[o]) {
      tree.insert_box_occluder(bounds[o]);
      return;
    }
    for (std::uint32_t t : big_tris[o]) {
      const glm::vec3 tri[3] = {scene.positions[scene.indices[3 * t]], scene.positions[scene.indices[3 * t + 1]],
                                scene.positions[scene.indices[3 * t + 2]]};
      const glm::vec3 n = glm::cross(tri[1] - tri[0], tri[2] - tri[0]);
      if (glm::dot(n, tree.eye() - tri[0]) > 0.0f) tree.insert_occluder(tri, 3);
    }
  }

  /// Objects with at least one pixel whose first hit is theirs.
  std::vector<std::uint8_t> embree_visible(const Camera& cam) const {
    std::vector<std::uint8_t> vis(scene.objects.size(), 0);
    const auto hits = embree.render(cam, 1);
    for (std::uint32_t t : hits.triangle)
      if (t != oracle::HitBuffer::miss) vis[triangle_object[t]] = 1;
    return vis;
  }
};

/// Seeded cameras: street-level and elevated eyes, eyes inside solid occluders, eyes exactly on a
/// solid occluder's face plane, all looking at random points of the scene.
inline std::vector<Camera> make_cameras(const CullScene& cs, std::uint32_t seed, int count, int width, int height) {
  support::Rng rng(seed);
  std::vector<Camera> cams;
  const Aabb sb = cs.scene.bounds;
  std::vector<std::uint32_t> boxes;
  for (std::uint32_t o = 0; o < cs.box_occluder.size(); ++o)
    if (cs.box_occluder[o]) boxes.push_back(o);
  const float ground = sb.min.y;
  const float height_range = sb.max.y - sb.min.y;
  for (int i = 0; i < count; ++i) {
    glm::vec3 eye(rng.uniform(sb.min.x, sb.max.x), ground + rng.uniform(0.05f, 0.25f) * height_range,
                  rng.uniform(sb.min.z, sb.max.z));
    const int kind = i % 10;
    if (kind == 1) eye.y = ground + rng.uniform(0.3f, 1.2f) * height_range;  // elevated
    if (!boxes.empty() && (kind == 2 || kind == 3)) {
      const Aabb& b = cs.bounds[boxes[rng.next() % boxes.size()]];
      if (kind == 2) {
        eye = b.center();  // inside an occluder
      } else {
        const int axis = rng.range(0, 2);  // exactly on a face plane, beside the box
        eye = b.center();
        eye[axis] = rng.uniform() < 0.5f ? b.min[axis] : b.max[axis];
        const int other = axis == 1 ? 0 : 1;
        eye[other] = b.max[other] + rng.uniform(0.0f, 2.0f);
      }
    }
    const glm::vec3 target(rng.uniform(sb.min.x, sb.max.x), ground + rng.uniform(0.0f, 0.3f) * height_range,
                           rng.uniform(sb.min.z, sb.max.z));
    if (glm::length(target - eye) < 1e-3f) continue;
    const float near_plane = kind == 4 ? 2.0f : 0.1f;  // a far-out near plane cuts through occluders
    cams.push_back(support::make_camera(eye, target, 60.0f, width, height, near_plane, kind == 5 ? 0.0f : 5000.0f));
  }
  return cams;
}

struct CullCount {
  long cameras = 0, in_frustum = 0, after_occlusion = 0, embree_visible = 0, false_culls = 0;
  double tri_total = 0, tri_frustum = 0, tri_occlusion = 0, tri_visible = 0;
};

}  // namespace occlusion_test
