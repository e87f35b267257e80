// Scene building blocks: boxes, raw triangles, indexed meshes as objects.
#include <cassert>
#include <cmath>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

// Corner bits: 1 = x, 2 = y, 4 = z (set = max). Each face counter-clockwise seen from outside.
const std::uint32_t kBoxTriangleCorners[36] = {
    0, 4, 6, 0, 6, 2,  // -x
    1, 3, 7, 1, 7, 5,  // +x
    0, 1, 5, 0, 5, 4,  // -y
    2, 6, 7, 2, 7, 3,  // +y
    0, 2, 3, 0, 3, 1,  // -z
    4, 5, 7, 4, 7, 6,  // +z
};

namespace {
bool finite3(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }
}  // namespace

std::vector<Aabb> Scene::object_bounds() const {
  std::vector<Aabb> out;
  out.reserve(objects.size());
  for (const SceneObject& o : objects) out.push_back(o.bounds);
  return out;
}

std::uint32_t Scene::add_box(const Aabb& box, const std::string& name, bool major_occluder) {
  const auto base = static_cast<std::uint32_t>(positions.size());
  for (int i = 0; i < 8; ++i) positions.push_back(corner(box, i));
  SceneObject o;
  o.name = name;
  o.first_triangle = static_cast<std::uint32_t>(indices.size() / 3);
  o.triangle_count = 12;
  for (std::uint32_t k : kBoxTriangleCorners) indices.push_back(base + k);
  o.bounds = box;
  o.major_occluder = major_occluder;
  o.is_box = true;
  bounds = merge(bounds, box);
  objects.push_back(std::move(o));
  return static_cast<std::uint32_t>(objects.size() - 1);
}

std::uint32_t Scene::add_triangles(const std::vector<glm::vec3>& corners, const std::string& name) {
  std::vector<std::uint32_t> local(corners.size() / 3 * 3);
  for (std::size_t i = 0; i < local.size(); ++i) local[i] = static_cast<std::uint32_t>(i);
  return add_mesh(corners, local, name);
}

std::uint32_t Scene::add_mesh(const std::vector<glm::vec3>& mesh_positions,
                              const std::vector<std::uint32_t>& mesh_indices, const std::string& name) {
  const auto base = static_cast<std::uint32_t>(positions.size());
  positions.insert(positions.end(), mesh_positions.begin(), mesh_positions.end());
  SceneObject o;
  o.name = name;
  o.first_triangle = static_cast<std::uint32_t>(indices.size() / 3);
  // Without positions there is nothing the indices could name: the object stays empty.
  const std::size_t n = mesh_positions.empty() ? 0 : mesh_indices.size() / 3 * 3;
  o.triangle_count = static_cast<std::uint32_t>(n / 3);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t k = mesh_indices[i];
    assert(k < mesh_positions.size() && "Scene::add_mesh: index out of range");
    if (k >= mesh_positions.size()) k = 0;
    indices.push_back(base + k);
    const glm::vec3& p = mesh_positions[k];
    if (finite3(p)) o.bounds = merge(o.bounds, p);
  }
  if (!is_empty(o.bounds)) bounds = merge(bounds, o.bounds);
  objects.push_back(std::move(o));
  return static_cast<std::uint32_t>(objects.size() - 1);
}

}  // namespace cullkit::support
