// load_obj: real OBJ scenes through tinyobjloader (Debian's packaged library), fan-triangulated here.
//
// The loader is asked not to triangulate: each polygon (c0, c1, ..., cn-1) becomes the fan
// (c0, ci, ci+1), which keeps the file's winding. Every tinyobj shape (started by `o` or `g`) with at
// least one triangle becomes one SceneObject. Faces naming a vertex out of range or a vertex with a
// non-finite coordinate are skipped and counted in ObjLoadStats; nothing is printed.
#include <cmath>
#include <filesystem>

#include <cullkit_support/scene.hpp>

#ifdef CULLKIT_HAVE_TINYOBJLOADER
#include <tiny_obj_loader.h>
#endif

namespace cullkit::support {

std::optional<Scene> load_obj(const std::string& path) { return load_obj(path, nullptr); }

std::optional<Scene> load_obj(const std::string& path, ObjLoadStats* stats_out) {
  ObjLoadStats stats;
  if (stats_out) *stats_out = stats;
#ifndef CULLKIT_HAVE_TINYOBJLOADER
  (void)path;
  return std::nullopt;
#else
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // Materials are irrelevant to visibility: no base dir, so missing .mtl files only add warnings,
  // which are dropped with the rest of the loader's text.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, path.c_str(), nullptr, /*triangulate=*/false))
    return std::nullopt;

  Scene scene;
  scene.name = std::filesystem::path(path).stem().string();
  const std::size_t vertex_count = attrib.vertices.size() / 3;
  scene.positions.resize(vertex_count);
  std::vector<bool> finite(vertex_count, true);
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const glm::vec3 p(static_cast<float>(attrib.vertices[3 * i]), static_cast<float>(attrib.vertices[3 * i + 1]),
                      static_cast<float>(attrib.vertices[3 * i + 2]));
    scene.positions[i] = p;
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      finite[i] = false;
      ++stats.nonfinite_vertices;
    }
  }
  auto usable = [&](int v) { return v >= 0 && static_cast<std::size_t>(v) < vertex_count && finite[v]; };

  for (const tinyobj::shape_t& shape : shapes) {
    SceneObject obj;
    obj.name = shape.name;
    obj.first_triangle = static_cast<std::uint32_t>(scene.indices.size() / 3);
    std::size_t offset = 0;
    for (const auto corners_raw : shape.mesh.num_face_vertices) {
      const std::size_t corners = corners_raw;
      ++stats.faces;
      bool ok = corners >= 3 && offset + corners <= shape.mesh.indices.size();
      for (std::size_t k = 0; ok && k < corners; ++k) ok = usable(shape.mesh.indices[offset + k].vertex_index);
      if (!ok) {
        ++stats.skipped_faces;
        offset += corners;
        continue;
      }
      const auto c0 = static_cast<std::uint32_t>(shape.mesh.indices[offset].vertex_index);
      for (std::size_t k = 1; k + 1 < corners; ++k) {
        const auto a = static_cast<std::uint32_t>(shape.mesh.indices[offset + k].vertex_index);
        const auto b = static_cast<std::uint32_t>(shape.mesh.indices[offset + k + 1].vertex_index);
        scene.indices.insert(scene.indices.end(), {c0, a, b});
      }
      for (std::size_t k = 0; k < corners; ++k)
        obj.bounds = merge(obj.bounds, scene.positions[shape.mesh.indices[offset + k].vertex_index]);
      offset += corners;
    }
    obj.triangle_count = static_cast<std::uint32_t>(scene.indices.size() / 3) - obj.first_triangle;
    if (obj.triangle_count == 0) {
      ++stats.empty_shapes;
      continue;
    }
    scene.bounds = merge(scene.bounds, obj.bounds);
    scene.objects.push_back(std::move(obj));
  }
  if (stats_out) *stats_out = stats;
  return scene;
#endif
}

}  // namespace cullkit::support
