// An engine-shaped frame with cullkit: draw items with local boxes and world matrices, meshes with
// 16-bit index buffers, two eyes of a headset culled in one walk (cull_views), and the shadow map
// of a directional light drawn only for the objects that can shadow what the eyes see
// (shadow_caster_volume). A skybox with infinite bounds and an object whose transform is NaN on the
// first frame show the rule for bad bounds: such objects are always drawn. The crate mesh also goes
// into NormalClassIndex and BspTree as raw buffers (StridedMesh: interleaved vertex bytes and a
// 16-bit index buffer whose width is chosen at run time).
// The program checks its own answers against brute force and returns non-zero if one is wrong.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include <cullkit/cullkit.hpp>

namespace {

// --- the engine's own types ---
struct Vertex {
  float position[3];
  std::uint32_t packed_normal;
};
struct Mesh {  // a vertex buffer and a 16-bit index buffer
  std::vector<Vertex> vertices;
  std::vector<std::uint16_t> indices;
  cullkit::Aabb local_bounds;
};
struct DrawItem {
  std::uint32_t mesh;
  glm::mat4 world;
  cullkit::Aabb world_bounds;  // refreshed every frame from local_bounds and world
};

Mesh make_box_mesh(const glm::vec3& half) {
  Mesh m;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p((i & 1) ? half.x : -half.x, (i & 2) ? half.y : -half.y, (i & 4) ? half.z : -half.z);
    m.vertices.push_back(Vertex{{p.x, p.y, p.z}, 0u});
  }
  const std::uint16_t faces[36] = {0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4,
                                   2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6};
  m.indices.assign(faces, faces + 36);
  m.local_bounds = cullkit::Aabb{-half, half};
  return m;
}

// Brute-force "meets the frustum": not all 8 corners outside one plane (double).
bool meets(const cullkit::Frustum& f, const cullkit::Aabb& b) {
  if (!cullkit::is_valid(b)) return true;
  for (int p = 0; p < cullkit::Frustum::max_planes; ++p) {
    if (!f.has_plane(p)) continue;
    bool out = true;
    for (int c = 0; c < 8 && out; ++c) {
      const glm::vec3 q = cullkit::corner(b, c);
      const cullkit::Plane& pl = f.plane(p);
      out = double(pl.normal.x) * q.x + double(pl.normal.y) * q.y + double(pl.normal.z) * q.z + double(pl.d) < 0.0;
    }
    if (out) return false;
  }
  return true;
}

}  // namespace

template <>
struct cullkit::VertexTraits<Vertex> {
  static glm::vec3 position(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
};

int main() {
  using namespace cullkit;
  int errors = 0;
  // Scene: 3 meshes, 2,000 draw items on a 40 x 50 grid, a skybox, a car with a NaN transform.
  std::vector<Mesh> meshes = {make_box_mesh(glm::vec3(1.0f)), make_box_mesh(glm::vec3(0.5f, 3.0f, 0.5f)),
                              make_box_mesh(glm::vec3(4.0f, 0.2f, 2.0f))};
  const float inf = std::numeric_limits<float>::infinity();
  meshes.push_back(Mesh{{}, {}, Aabb{glm::vec3(-inf), glm::vec3(inf)}});  // the skybox: no finite bounds
  std::vector<DrawItem> items;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 at(float(i % 40) * 10.0f - 200.0f, 0.0f, float(i / 40) * 10.0f - 250.0f);
    items.push_back(DrawItem{std::uint32_t(i % 3), glm::translate(glm::mat4(1.0f), at), Aabb{}});
  }
  items.push_back(DrawItem{3, glm::mat4(1.0f), Aabb{}});
  const std::uint32_t skybox = std::uint32_t(items.size() - 1);
  items.push_back(DrawItem{0, glm::mat4(std::numeric_limits<float>::quiet_NaN()), Aabb{}});  // not placed yet
  const std::uint32_t car = std::uint32_t(items.size() - 1);

  // World bounds from local boxes and matrices; the tree reads them through a getter.
  const auto update_bounds = [&] {
    for (DrawItem& d : items) d.world_bounds = transform_bounds(meshes[d.mesh].local_bounds, d.world);
  };
  update_bounds();
  auto tree = AdaptiveBinaryTree<Aabb>::from_getter(
      [&](std::uint32_t i) { return items[i].world_bounds; }, items.size());
  std::printf("engine_frame: %zu draw items, %u without valid bounds (skybox, unplaced car)\n", tree.size(),
              tree.stats().unbounded);

  // A mesh's own triangle tree over its 16-bit index buffer, drawn by visible ranges.
  const Mesh& crate = meshes[0];
  const MeshView<Vertex, std::uint16_t> crate_view{crate.vertices.data(), crate.vertices.size(), crate.indices.data(),
                                                   crate.indices.size()};
  const AdaptiveBinaryTree<Aabb> crate_triangles = make_triangle_tree(crate_view);
  std::vector<std::uint16_t> crate_indices;
  crate_triangles.reorder_indices(crate_view, crate_indices);  // upload this buffer once

  std::vector<std::uint32_t> visible, view_bits, casters;
  const glm::vec3 sun = glm::normalize(glm::vec3(0.4f, -1.0f, 0.3f));
  for (int frame = 0; frame < 3; ++frame) {
    // Motion: every 7th item spins; the car gets a transform from frame 1 on.
    for (std::size_t i = 0; i < 2000; i += 7) items[i].world = glm::rotate(items[i].world, 0.1f, glm::vec3(0, 1, 0));
    if (frame == 1) items[car].world = glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, -300));  // behind the eyes
    update_bounds();
    tree.refit([&](std::uint32_t i) { return items[i].world_bounds; }, AbtRefitParams{});

    // Two eyes of a headset: each eye's camera comes from its matrix (make_camera), so the eye the
    // renderer would use for pixel rays agrees with the matrix.
    const glm::vec3 head(0.0f, 1.7f, -260.0f + 20.0f * float(frame));
    const glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(100.0f), 1.0f, 0.05f, 400.0f);
    Frustum eyes[2];
    for (int e = 0; e < 2; ++e) {
      const glm::vec3 eye = head + glm::vec3(e == 0 ? -0.032f : 0.032f, 0, 0);
      const Camera cam = make_camera(proj * glm::lookAtRH(eye, eye + glm::vec3(0, -0.2f, 1), glm::vec3(0, 1, 0)),
                                     1440, 1600, DepthRange::zero_to_one);
      check_camera(cam);
      eyes[e] = frustum_of(cam);
    }
    tree.cull_views(eyes, 2, visible, view_bits);
    std::size_t left = 0, right = 0;
    for (const std::uint32_t bits : view_bits) {
      left += bits & 1u;
      right += (bits >> 1) & 1u;
    }
    // Shadow map of the sun for what the eyes see: casters of either eye's view.
    const ConvexVolume caster_volume = shadow_caster_volume(eyes[0], sun);
    tree.cull(caster_volume, casters);

    // Checks against brute force (a real renderer would skip this).
    std::vector<std::uint32_t> in_union(items.size(), 0);
    for (std::size_t j = 0; j < visible.size(); ++j) in_union[visible[j]] = view_bits[j];
    std::vector<std::uint8_t> is_caster(items.size(), 0);
    for (const std::uint32_t i : casters) is_caster[i] = 1;
    for (std::uint32_t i = 0; i < items.size(); ++i) {
      for (int e = 0; e < 2; ++e)
        if (meets(eyes[e], items[i].world_bounds) && !((in_union[i] >> e) & 1u)) ++errors;
      if (meets(eyes[0], items[i].world_bounds) && !is_caster[i]) ++errors;  // what is seen can cast
    }
    if (!((in_union[skybox] & 3u) == 3u)) ++errors;   // always drawn
    if (frame == 0 && in_union[car] == 0) ++errors;  // NaN transform: drawn until placed
    if (frame >= 1 && in_union[car] != 0) ++errors;  // placed behind the eyes: culled
    std::printf("frame %d: %zu items for the eyes (left %zu, right %zu), %zu shadow casters (%zu planes), "
                "car %s, %u subtrees rebuilt\n",
                frame, visible.size(), left, right, casters.size(), caster_volume.plane_count(),
                in_union[car] ? "drawn" : "culled", tree.stats().subtrees_rebuilt);
  }
  // The crate drawn by visible triangle ranges of its reordered 16-bit buffer.
  std::size_t ranges = 0, triangles = 0;
  crate_triangles.cull(Frustum{}, [&](std::uint32_t begin, std::uint32_t end, Containment) {
    ++ranges;  // draw(indices = crate_indices[3 * begin, 3 * end))
    triangles += end - begin;
  });
  if (triangles != 12 || crate_indices.size() != 36) ++errors;
  std::printf("crate: %zu triangles in %zu ranges of a 16-bit index buffer\n", triangles, ranges);

  // The same crate as raw GPU-style buffers: bytes of interleaved vertices (position at offset 0
  // of each 16-byte vertex) and an index buffer whose width the asset decides at load time.
  // Every mesh-reading container takes it (StridedMesh) and answers as for the typed MeshView.
  const IndexFormat asset_format = IndexFormat::uint16;  // e.g. read from the file header
  const StridedMesh raw{{reinterpret_cast<const unsigned char*>(crate.vertices.data()), sizeof(Vertex), 0},
                        crate.vertices.size(),
                        {crate.indices.data(), crate.indices.size(), asset_format}};
  const NormalClassIndex from_buffers(raw);  // NormalClassIndex<glm::vec3>: the vertex type is not read
  const NormalClassIndex<Vertex, std::uint16_t> from_view(crate_view);
  const Camera crate_cam = make_camera(glm::perspectiveRH_NO(glm::radians(60.0f), 4.0f / 3.0f, 0.1f, 100.0f) *
                                           glm::lookAtRH(glm::vec3(3, 2, 4), glm::vec3(0), glm::vec3(0, 1, 0)),
                                       64, 48);
  const VisibleSet seen = from_buffers.select_visible(crate_cam);
  if (seen.triangles != from_view.select_visible(crate_cam).triangles || seen.triangles.empty()) ++errors;
  const BspTree glass(raw);  // a transparent crate: painter's order from raw buffers
  std::vector<std::uint32_t> order;
  glass.back_to_front(crate_cam.eye, order);
  if (order.size() != glass.fragments().size() || order.size() < 12) ++errors;
  std::printf("crate from raw buffers: %zu of 12 triangles seen, %zu fragments in back-to-front order\n",
              seen.triangles.size(), order.size());
  std::printf("engine_frame: %s\n", errors == 0 ? "all answers checked" : "WRONG ANSWERS");
  return errors == 0 ? 0 : 1;
}
