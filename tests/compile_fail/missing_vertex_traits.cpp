// Must NOT compile: a mesh of a vertex type with no VertexTraits specialization.
#include <cstdint>
#include <cullkit/cullkit.hpp>

struct MyEngineVertexWithoutTraits {
  float x, y, z;
};

int main() {
  const MyEngineVertexWithoutTraits v[3] = {};
  const std::uint32_t i[3] = {0, 1, 2};
  const cullkit::MeshView<MyEngineVertexWithoutTraits> mesh{v, 3, i, 3};
  glm::vec3 out[3];
  return cullkit::triangle_positions(mesh, 0, out) ? 0 : 1;
}
