// The second translation unit of the separate-core check: another NormalClassIndex instantiation
// (a user vertex struct, 16-bit-free indices), so that the program links two users of the core.
#include <cullkit/normal_class_index.hpp>

#include "scene.hpp"

namespace {
struct UserVertex {
  float x, y, z, u, v;
};
}  // namespace

template <>
struct cullkit::VertexTraits<UserVertex> {
  static glm::vec3 position(const UserVertex& v) { return glm::vec3(v.x, v.y, v.z); }
};

std::uint64_t separate_core::second_unit_hash(const Scene& scene) {
  std::vector<UserVertex> verts;
  for (const glm::vec3& p : scene.positions) verts.push_back(UserVertex{p.x, p.y, p.z, 0.0f, 0.0f});
  const cullkit::NormalClassIndex<UserVertex> index(
      cullkit::MeshView<UserVertex>{verts.data(), verts.size(), scene.indices.data(), scene.indices.size()});
  cullkit::NciContext context;
  cullkit::VisibleSet seen;
  std::uint64_t h = 0xCBF29CE484222325ull;
  for (const cullkit::Camera& cam : make_cameras()) {
    index.select_visible(cam, context, seen, nullptr);
    h = fnv(h, seen.triangles);
  }
  return h;
}
