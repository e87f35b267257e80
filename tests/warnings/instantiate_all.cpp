// Every container instantiated with an engine's own types (a vertex with its position inside, 16-bit
// indices, objects read through traits), compiled with the warnings engines raise
// (-Wconversion -Wsign-conversion -Wshadow, as errors): the headers' template code is only checked
// by a compiler where it is instantiated, so this unit instantiates it. It is compiled, not run.
#include <cstdint>
#include <vector>

#include <cullkit/cullkit.hpp>

namespace engine {

struct EngineVertex {
  float position[3];
  std::uint32_t packed_normal;
};
struct EngineObject {
  cullkit::Aabb world;
};

}  // namespace engine

using engine::EngineObject;
using engine::EngineVertex;

template <>
struct cullkit::VertexTraits<EngineVertex> {
  static glm::vec3 position(const EngineVertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
};
template <>
struct cullkit::BoundsTraits<EngineObject> {
  static cullkit::Aabb bounds(const EngineObject& o) { return o.world; }
};

// Called by nothing: its body only has to compile.
void cullkit_instantiate_all(const std::vector<EngineVertex>& vertices, const std::vector<std::uint16_t>& indices,
                             const std::vector<EngineObject>& objects, const cullkit::Camera& camera);
void cullkit_instantiate_all(const std::vector<EngineVertex>& vertices, const std::vector<std::uint16_t>& indices,
                             const std::vector<EngineObject>& objects, const cullkit::Camera& camera) {
  using namespace cullkit;
  const MeshView<EngineVertex, std::uint16_t> mesh{vertices.data(), vertices.size(), indices.data(), indices.size()};
  std::vector<std::uint32_t> out, bits;

  const AdaptiveBinaryTree<EngineObject> tree(objects.data(), objects.size());
  const Frustum frustum = frustum_of(camera);
  tree.cull(frustum, out);
  tree.cull(ConvexVolume(frustum), out);
  tree.cull_views(&frustum, 1, out, bits);
  OcclusionTree occlusion(camera.eye);
  tree.cull(frustum, occlusion, out);
  std::vector<Aabb> bounds;
  std::vector<std::uint8_t> solid;
  cull_with_occlusion(tree, frustum, occlusion, BoxOccluderSource{bounds.data(), solid.data()}, out);

  const NormalClassIndex<EngineVertex, std::uint16_t> index(mesh);
  NciContext context;
  VisibleSet seen;
  index.select_visible(camera, context, seen, nullptr);

  const MeshObject whole{0, static_cast<std::uint32_t>(indices.size() / 3)};
  const MeshOcclusionCuller<EngineVertex, std::uint16_t> culler(mesh, &whole, 1);
  MeshOcclusionContext occlusion_context;
  culler.cull(camera, occlusion_context, out);

  const BspTree<EngineVertex, std::uint16_t> bsp(mesh);
  bsp.back_to_front(camera.eye, out);

  PortalGraph graph;
  const std::uint32_t room = graph.add_cell();
  graph.set_cell_bounds(room, objects.empty() ? Aabb{} : objects.front().world);
  PortalScratch portal_scratch;
  std::vector<PortalView> cells;
  graph.visible_cells(room, camera.eye, frustum, cells, portal_scratch);

  std::vector<float> depth(objects.size(), 0.0f);
  order_back_to_front(depth.data(), depth.size(), out);
}
