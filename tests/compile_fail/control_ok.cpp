// Must compile: the control case for the compile-fail tests (same setup, traits provided), so a
// compile-fail test cannot pass merely because the test setup itself is broken.
#include <cstdint>
#include <cullkit/cullkit.hpp>

struct MyEngineVertexWithTraits {
  float x, y, z;
};
template <>
struct cullkit::VertexTraits<MyEngineVertexWithTraits> {
  static glm::vec3 position(const MyEngineVertexWithTraits& v) { return {v.x, v.y, v.z}; }
};

int main() {
  const MyEngineVertexWithTraits v[3] = {};
  const std::uint32_t i[3] = {0, 1, 2};
  const cullkit::MeshView<MyEngineVertexWithTraits> mesh{v, 3, i, 3};
  glm::vec3 out[3];
  return cullkit::triangle_positions(mesh, 0, out) ? 0 : 1;
}
