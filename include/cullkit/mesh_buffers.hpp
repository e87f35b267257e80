// cullkit/mesh_buffers.hpp: a triangle mesh given as raw GPU-style buffers, the way engines hold
// it: positions read through a pointer, a byte stride and an offset (an interleaved vertex buffer),
// and an index buffer whose element width (16 or 32 bits) is a run-time value read from the asset.
//
// Every container that reads a mesh (NormalClassIndex, MeshOcclusionCuller, BspTree) takes a
// `StridedMesh` beside its `MeshView` constructor, with the same rules: a triangle with an index
// >= vertex_count is skipped and counted, never read; a trailing partial triangle is ignored; a
// null pointer with a non-zero count is a precondition violation (asserted in debug builds, read
// as an empty buffer in release builds). The buffers need not be aligned: every read is a memcpy.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "config.hpp"
#include "traits.hpp"

namespace cullkit {

/// Width of one element of an index buffer, chosen at run time (Embree's RTC_FORMAT_USHORT3 /
/// RTC_FORMAT_UINT3, Vulkan's VK_INDEX_TYPE_UINT16 / UINT32, D3D's DXGI_FORMAT_R16_UINT / R32_UINT).
enum class IndexFormat : std::uint8_t {
  uint16,  ///< 2 bytes per index, native byte order
  uint32,  ///< 4 bytes per index, native byte order
};

/// Bytes per index of `format`.
[[nodiscard]] constexpr std::size_t index_size(IndexFormat format) noexcept {
  return format == IndexFormat::uint16 ? 2u : 4u;
}

/// A caller-owned index buffer: `count` indices (3 per triangle) of `format` at `data`, any
/// alignment. Not owned; holds no state beyond the three fields (trivially copyable).
struct IndexBufferView {
  const void* data = nullptr;
  std::size_t count = 0;
  IndexFormat format = IndexFormat::uint32;

  /// Index `i`, widened to 32 bits. pre: i < count, data != nullptr. O(1), no allocation.
  [[nodiscard]] std::uint32_t operator[](std::size_t i) const noexcept {
    CULLKIT_ASSERT(data != nullptr && i < count, "index within the index buffer");
    const unsigned char* bytes = static_cast<const unsigned char*>(data);
    if (format == IndexFormat::uint16) {
      std::uint16_t v;
      std::memcpy(&v, bytes + 2 * i, sizeof v);
      return v;
    }
    std::uint32_t v;
    std::memcpy(&v, bytes + 4 * i, sizeof v);
    return v;
  }
};

/// An indexed triangle list in caller-owned buffers: vertex i's position is three floats at
/// `positions.base + i * positions.stride_bytes + positions.offset_bytes` (i < vertex_count);
/// triangle t has corners at indices[3t], indices[3t+1], indices[3t+2], counter-clockwise as seen
/// from its front. Nothing is owned; containers copy what they need while they are built.
///
/// Example, an interleaved vertex { float pos[3]; float normal[3]; float uv[2]; } with 16-bit indices:
///     StridedMesh mesh{{vertex_bytes, 32, 0}, vertex_count, {index_bytes, index_count, IndexFormat::uint16}};
///     NormalClassIndex index(mesh);  // deduces NormalClassIndex<glm::vec3>
struct StridedMesh {
  StridedPositions positions{nullptr, 0, 0};
  std::size_t vertex_count = 0;
  IndexBufferView indices{};

  [[nodiscard]] std::size_t triangle_count() const noexcept { return indices.count / 3; }
};

/// Reads triangle `t` of `mesh` into `out`; false (and `out` untouched) if an index is out of range.
/// pre: t < mesh.triangle_count(). O(1).
[[nodiscard]] inline bool triangle_positions(const StridedMesh& mesh, std::size_t t, glm::vec3 out[3]) noexcept {
  CULLKIT_ASSERT(t < mesh.triangle_count(), "triangle index within the mesh");
  std::uint32_t idx[3];
  for (int k = 0; k < 3; ++k) {
    idx[k] = mesh.indices[3 * t + static_cast<std::size_t>(k)];
    if (idx[k] >= mesh.vertex_count) return false;
  }
  for (int k = 0; k < 3; ++k) out[k] = mesh.positions(idx[k]);
  return true;
}

namespace detail {
// The mesh with null buffers read as empty ones (the release-build answer to a violated
// precondition); asserts the precondition in debug builds.
[[nodiscard]] inline StridedMesh checked_mesh(StridedMesh mesh) noexcept {
  CULLKIT_ASSERT(mesh.positions.base != nullptr || mesh.vertex_count == 0, "positions present when vertex_count > 0");
  CULLKIT_ASSERT(mesh.indices.data != nullptr || mesh.indices.count == 0, "indices present when index count > 0");
  if (mesh.positions.base == nullptr) mesh.vertex_count = 0;
  if (mesh.indices.data == nullptr) mesh.indices.count = 0;
  return mesh;
}

// The same for a MeshView.
template <class Vertex, class Index>
[[nodiscard]] MeshView<Vertex, Index> checked_mesh(MeshView<Vertex, Index> mesh) noexcept {
  CULLKIT_ASSERT(mesh.vertices != nullptr || mesh.vertex_count == 0, "vertices present when vertex_count > 0");
  CULLKIT_ASSERT(mesh.indices != nullptr || mesh.index_count == 0, "indices present when index_count > 0");
  if (mesh.vertices == nullptr) mesh.vertex_count = 0;
  if (mesh.indices == nullptr) mesh.index_count = 0;
  return mesh;
}

}  // namespace detail

/// A mesh placed in the world by a matrix, for building one container from several meshes (a level
/// of prefabs; MeshOcclusionCuller, BspTree): `mesh` in its own space (front faces counter-clockwise
/// there, 16- or 32-bit indices, any stride) and `model`, its affine world matrix, mirrored or not
/// (a negative determinant reverses the apparent winding; the containers compensate, so front faces
/// stay front faces). The instances' triangles are numbered one after another in
/// the order given: instance 0's triangles first.
struct MeshInstance {
  StridedMesh mesh;
  glm::mat4 model;
};

}  // namespace cullkit
