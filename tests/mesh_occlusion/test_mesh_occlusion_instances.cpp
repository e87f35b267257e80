// MeshOcclusionCuller built from instances (several meshes placed by world matrices): a level of
// prefabs (houses as closed boxes with interleaved vertices and 16-bit indices, walls as cut panels
// with 32-bit indices, a ground), rotated, scaled non-uniformly and a third mirrored. The culler
// built from the instances must equal, in build statistics and in every answer, the culler built from
// the same level concatenated and transformed by hand (double precision, winding reversed for
// mirrored instances), and make no false cull against Embree. Also: an instance with a non-affine or
// NaN matrix makes its object always visible; object_bounds and cull_frustum against brute force.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include "check.hpp"
#include "frame_truth.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

struct Prefab {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  std::vector<float> interleaved;          // position + normal, when the prefab has them
  std::vector<std::uint16_t> indices16;
  [[nodiscard]] StridedMesh mesh() const {
    if (!interleaved.empty())
      return StridedMesh{{reinterpret_cast<const unsigned char*>(interleaved.data()), 24, 0}, positions.size(),
                         {indices16.data(), indices16.size(), IndexFormat::uint16}};
    return StridedMesh{{reinterpret_cast<const unsigned char*>(positions.data()), sizeof(glm::vec3), 0}, positions.size(),
                       {indices.data(), indices.size(), IndexFormat::uint32}};
  }
};

Prefab house() {
  Prefab p;
  for (int k = 0; k < 8; ++k) p.positions.push_back(corner(Aabb{{-0.5f, 0.0f, -0.5f}, {0.5f, 1.0f, 0.5f}}, k));
  for (std::uint32_t v : support::kBoxTriangleCorners) p.indices.push_back(v);
  for (const glm::vec3& v : p.positions)
    for (float f : {v.x, v.y, v.z, 0.0f, 1.0f, 0.0f}) p.interleaved.push_back(f);
  for (std::uint32_t v : p.indices) p.indices16.push_back(static_cast<std::uint16_t>(v));
  return p;
}

Prefab panel(int n) {
  Prefab p;
  cut_panel(n, p.positions, p.indices);
  return p;
}

/// The instance's triangles placed by hand: double precision, rounded to float, mirrored ones
/// wound back.
std::vector<glm::vec3> by_hand(const Prefab& p, const glm::mat4& model) { return world_triangles(p.positions, p.indices, model); }

Camera camera_at(const glm::vec3& eye, float yaw, float pitch) {
  Camera cam;
  cam.eye = eye;
  cam.width = 320;
  cam.height = 180;
  const glm::vec3 dir(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
  cam.view_proj = glm::perspective(glm::radians(60.0f), 16.0f / 9.0f, 0.1f, 1000.0f) * glm::lookAt(eye, eye + dir, glm::vec3(0, 1, 0));
  return cam;
}

}  // namespace

int main() {
  const Prefab prefabs[3] = {house(), panel(3), panel(1)};
  support::Rng rng(17);
  std::vector<MeshInstance> instances;
  std::vector<MeshObject> objects;
  support::Scene level;
  std::uint32_t first = 0;
  const auto place = [&](const Prefab& p, const glm::mat4& model) {
    instances.push_back({p.mesh(), model});
    const auto count = static_cast<std::uint32_t>(p.indices.size() / 3);
    objects.push_back({first, count});
    first += count;
    level.add_triangles(by_hand(p, model), "instance_" + std::to_string(instances.size()));
  };
  // The ground: one big panel lying flat, facing up.
  place(prefabs[1], glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, 100)), -1.5707963f, glm::vec3(1, 0, 0)),
                               glm::vec3(200, 200, 1)));
  for (int i = 0; i < 80; ++i) {
    const int kind = i % 3;
    const glm::vec3 at(rng.uniform(-80, 80), 0.0f, rng.uniform(-80, 80));
    glm::mat4 model = glm::rotate(glm::translate(glm::mat4(1.0f), at), rng.uniform(0.0f, 6.2831853f), glm::vec3(0, 1, 0));
    glm::vec3 scale = kind == 0 ? glm::vec3(rng.uniform(6, 20), rng.uniform(5, 30), rng.uniform(6, 20))
                                : glm::vec3(rng.uniform(5, 20), rng.uniform(2, 6), 1.0f);
    if (i % 3 == 1 || rng.range(0, 2) == 0) (rng.range(0, 1) ? scale.x : scale.z) *= -1.0f;  // mirrored
    place(prefabs[kind], glm::scale(model, scale));
  }
  const MeshOcclusionCuller<glm::vec3> from_instances(instances.data(), instances.size(), objects.data(), objects.size());
  const MeshOcclusionCuller<glm::vec3> from_hand(level.mesh(), objects.data(), objects.size());
  const auto& a = from_instances.stats();
  const auto& b = from_hand.stats();
  CHECK_MSG(a.triangles == b.triangles && a.welded_vertices == b.welded_vertices && a.shared_edges == b.shared_edges &&
                a.triangles_unusable == b.triangles_unusable && a.objects_unusable == b.objects_unusable,
            "instances and the same level by hand build differently: %zu/%zu welded, %zu/%zu shared edges", a.welded_vertices,
            b.welded_vertices, a.shared_edges, b.shared_edges);
  const FrameOccluders occluders(level, {});
  const ObjectMap map(level);
  std::vector<std::uint32_t> out_i, out_h, frustum;
  std::size_t cameras = 0, differ = 0, hidden = 0;
  long false_culls = 0;
  for (int c = 0; c < 40; ++c) {
    const Camera cam = camera_at(glm::vec3(rng.uniform(-90, 90), rng.uniform(1.5f, 3.0f), rng.uniform(-90, 90)),
                                 rng.uniform(0.0f, 6.2831853f), rng.uniform(-0.2f, 0.1f));
    from_instances.cull(cam, out_i);
    from_hand.cull(cam, out_h);
    std::sort(out_i.begin(), out_i.end());
    std::sort(out_h.begin(), out_h.end());
    differ += out_i != out_h;
    from_instances.cull_frustum(cam, frustum);
    std::sort(frustum.begin(), frustum.end());
    hidden += frustum.size() - out_i.size();
    CHECK_MSG(std::includes(frustum.begin(), frustum.end(), out_i.begin(), out_i.end()),
              "camera %d: the culler keeps an object the frustum-only answer leaves out", c);
    for (std::uint32_t o : frustum_objects(level, cam))
      CHECK_MSG(std::binary_search(frustum.begin(), frustum.end(), o), "camera %d: cull_frustum misses object %u", c, o);
    RaySet set;
    set.second_width = 127;
    set.second_height = 71;
    set.jitter = 1024;
    set.seed = std::uint64_t(c) + 1;
    const auto seen = seen_objects(level, {}, cast_frame(occluders, map, cam, set), cam);
    for (std::uint32_t o = 0; o < seen.size(); ++o)
      if (seen[o] && !std::binary_search(out_i.begin(), out_i.end(), o)) ++false_culls;
    ++cameras;
  }
  CHECK_MSG(differ == 0, "%zu of %zu cameras: instances and the level by hand answer differently", differ, cameras);
  CHECK_MSG(false_culls == 0, "%ld false culls on the instanced level", false_culls);
  CHECK_MSG(hidden > 0, "nothing hidden on the instanced level: the comparison proves little");
  for (std::uint32_t o = 0; o < objects.size(); ++o) {
    const Aabb bo = from_instances.object_bounds(o), bs = level.objects[o].bounds;
    CHECK_MSG(bo.min == bs.min && bo.max == bs.max, "object %u: object_bounds differs from its triangles' bounds", o);
  }
  CHECK(is_empty(from_instances.object_bounds(static_cast<std::uint32_t>(objects.size()))));
  std::printf("instanced level: %zu instances, %zu triangles, %zu cameras, %zu objects hidden by occlusion, "
              "answers differing from the level by hand: %zu, false culls: %ld\n",
              instances.size(), level.triangle_count(), cameras, hidden, differ, false_culls);
  // A non-affine or NaN matrix: that instance's object is always visible, the others unchanged.
  std::vector<MeshInstance> bad = instances;
  bad[5].model[0][3] = 0.5f;
  bad[9].model = glm::mat4(std::numeric_limits<float>::quiet_NaN());
  const MeshOcclusionCuller<glm::vec3> with_bad(bad.data(), bad.size(), objects.data(), objects.size());
  CHECK(with_bad.stats().objects_unusable == 2);
  CHECK(is_empty(with_bad.object_bounds(5)) && is_empty(with_bad.object_bounds(9)));
  std::vector<std::uint32_t> out;
  with_bad.cull(camera_at(glm::vec3(0, 500, 0), 0.0f, 1.5f), out);
  CHECK(std::count(out.begin(), out.end(), 5u) == 1 && std::count(out.begin(), out.end(), 9u) == 1);
  const MeshOcclusionCuller<glm::vec3> none(nullptr, 0, nullptr, 0);
  none.cull(camera_at(glm::vec3(0, 2, 0), 0.0f, 0.0f), out);
  CHECK(out.empty() && none.object_count() == 0);
  return cullkit_test::report("test_mesh_occlusion_instances");
}
