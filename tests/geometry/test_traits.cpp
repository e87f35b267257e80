// Traits and getters: user vertex and object types, the provided specializations, interleaved
// buffers, and out-of-range indices.
#include <array>
#include <cstring>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>

namespace engine {
struct Vertex {  // a renderer's own vertex
  float px, py, pz;
  std::uint32_t color;
  float u, v;
};
struct Prop {
  glm::vec3 position;
  float radius;
};
struct NoTraits {};
}  // namespace engine

template <>
struct cullkit::VertexTraits<engine::Vertex> {
  static glm::vec3 position(const engine::Vertex& v) { return {v.px, v.py, v.pz}; }
};
template <>
struct cullkit::BoundsTraits<engine::Prop> {
  static cullkit::Aabb bounds(const engine::Prop& p) {
    return {p.position - glm::vec3(p.radius), p.position + glm::vec3(p.radius)};
  }
};
struct PropBoundsByHeight {  // a second traits class for the same type, passed explicitly
  static cullkit::Aabb bounds(const engine::Prop& p) { return {p.position, p.position + glm::vec3(0, p.radius, 0)}; }
};

using namespace cullkit;

static_assert(has_vertex_traits_v<glm::vec3>);
static_assert(has_vertex_traits_v<glm::vec4>);
static_assert(has_vertex_traits_v<std::array<float, 3>>);
static_assert(has_vertex_traits_v<engine::Vertex>);
static_assert(!has_vertex_traits_v<engine::NoTraits>);
static_assert(has_bounds_traits_v<Aabb>);
static_assert(has_bounds_traits_v<engine::Prop>);
static_assert(has_bounds_traits_v<engine::Prop, PropBoundsByHeight>);
static_assert(!has_bounds_traits_v<engine::NoTraits>);
static_assert(is_position_getter_v<StridedPositions>);
static_assert(!is_position_getter_v<int>);
#if CULLKIT_HAS_CONCEPTS
static_assert(VertexWithTraits<engine::Vertex>);
static_assert(!VertexWithTraits<engine::NoTraits>);
static_assert(ObjectWithBounds<engine::Prop, PropBoundsByHeight>);
static_assert(PositionGetter<StridedPositions>);
#endif
static_assert(std::is_trivially_copyable_v<Aabb> && std::is_aggregate_v<Aabb>);
static_assert(std::is_trivially_copyable_v<Plane> && std::is_trivially_copyable_v<Sphere>);
static_assert(std::is_trivially_copyable_v<Frustum>);

int main() {
  const std::vector<engine::Vertex> verts = {{0, 0, 0, 1, 0, 0}, {1, 0, 0, 2, 0, 0}, {0, 1, 0, 3, 0, 0}};
  const std::vector<std::uint32_t> idx = {0, 1, 2, 0, 1, 7, 2, 1};  // second triangle out of range, 2 trailing
  const MeshView<engine::Vertex> mesh{verts.data(), verts.size(), idx.data(), idx.size()};
  CHECK(mesh.triangle_count() == 2);
  glm::vec3 tri[3];
  CHECK(triangle_positions(mesh, 0, tri));
  CHECK(tri[1] == glm::vec3(1, 0, 0) && tri[2] == glm::vec3(0, 1, 0));
  tri[0] = glm::vec3(42);
  CHECK(!triangle_positions(mesh, 1, tri));
  CHECK(tri[0] == glm::vec3(42));  // untouched on failure

  const std::vector<int> signed_idx = {0, 1, -1};
  const MeshView<engine::Vertex, int> smesh{verts.data(), verts.size(), signed_idx.data(), signed_idx.size()};
  CHECK(!triangle_positions(smesh, 0, tri));

  // An interleaved buffer read through a stateful getter, at an unaligned offset.
  std::vector<unsigned char> buffer(3 * 28 + 1);
  for (std::uint32_t i = 0; i < 3; ++i) {
    const float p[3] = {float(i), float(2 * i), float(3 * i)};
    std::memcpy(buffer.data() + 1 + i * 28 + 8, p, sizeof p);
  }
  const StridedPositions getter{buffer.data() + 1, 28, 8};
  CHECK(getter(2) == glm::vec3(2, 4, 6));

  const engine::Prop prop{glm::vec3(1, 2, 3), 0.5f};
  CHECK(BoundsTraits<engine::Prop>::bounds(prop).min == glm::vec3(0.5f, 1.5f, 2.5f));
  CHECK(PropBoundsByHeight::bounds(prop).max == glm::vec3(1, 2.5f, 3));
  CHECK(VertexTraits<std::array<float, 3>>::position({1, 2, 3}) == glm::vec3(1, 2, 3));
  CHECK(VertexTraits<glm::vec4>::position(glm::vec4(1, 2, 3, 4)) == glm::vec3(1, 2, 3));
  return cullkit_test::report("test_traits");
}
