// The README's drop-in example, compiled and run so it cannot rot: a renderer with its own vertex
// and mesh types asks cullkit each frame which meshes to draw.
#include <cstdio>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

struct Renderer {  // stands in for the engine's draw submission
  std::size_t draws = 0;
  void draw(std::uint32_t /*first_index*/, std::uint32_t /*index_count*/) { ++draws; }
};

// --- README example begins ---
#include <cullkit/cullkit.hpp>

struct MyVertex { float pos[3]; std::uint32_t normal; float uv[2]; };   // your engine's vertex
struct MyMesh   { cullkit::Aabb world_bounds; std::uint32_t first_index, index_count; };

template <> struct cullkit::VertexTraits<MyVertex> {                      // how to read a position
  static glm::vec3 position(const MyVertex& v) { return {v.pos[0], v.pos[1], v.pos[2]}; }
};
template <> struct cullkit::BoundsTraits<MyMesh> {                        // how to read a bound
  static cullkit::Aabb bounds(const MyMesh& m) { return m.world_bounds; }
};

// Once, after loading: the tree copies the bounds it needs.
//   cullkit::AdaptiveBinaryTree<MyMesh> tree(meshes.data(), meshes.size());
// Every frame (`visible` is reused, so the frame does not allocate once warm):
void frame(const std::vector<MyMesh>& meshes, const cullkit::AdaptiveBinaryTree<MyMesh>& tree,
           const glm::mat4& view_proj, std::vector<std::uint32_t>& visible, Renderer& r) {
  const auto frustum = cullkit::Frustum::from_matrix(view_proj, cullkit::DepthRange::zero_to_one);
  tree.cull(frustum, visible);  // indices into `meshes`; a visible mesh is never left out
  for (std::uint32_t i : visible) r.draw(meshes[i].first_index, meshes[i].index_count);
}
// --- README example ends ---

int main() {
  std::vector<MyMesh> meshes;
  for (int i = 0; i < 100; ++i) {
    const glm::vec3 c(float(i % 10) * 10.0f, 0.0f, -float(i / 10) * 10.0f - 5.0f);
    meshes.push_back({{c - glm::vec3(1), c + glm::vec3(1)}, std::uint32_t(i) * 36u, 36u});
  }
  const cullkit::AdaptiveBinaryTree<MyMesh> tree(meshes.data(), meshes.size());
  std::vector<std::uint32_t> visible;
  const glm::mat4 view_proj = glm::perspectiveRH_ZO(glm::radians(60.0f), 16.0f / 9.0f, 0.1f, 500.0f) *
                              glm::lookAtRH(glm::vec3(45, 5, 10), glm::vec3(45, 0, -50), glm::vec3(0, 1, 0));
  Renderer renderer;
  frame(meshes, tree, view_proj, visible, renderer);
  std::printf("drop_in_renderer: drew %zu of %zu meshes\n", renderer.draws, meshes.size());
  return renderer.draws > 0 && renderer.draws < meshes.size() ? 0 : 1;
}
