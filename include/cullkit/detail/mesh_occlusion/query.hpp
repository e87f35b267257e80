// cullkit/detail/mesh_occlusion/query.hpp: one frame of MeshOcclusionCuller::cull.
#pragma once

#include <cstdint>
#include <vector>

#include "../../geometry/camera.hpp"
#include "index.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// Per-thread working memory of a query.
struct Scratch {
  MeshOcclusionStats stats;
  std::vector<std::uint32_t> in_frustum;
};

inline void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& scratch,
                 std::vector<std::uint32_t>& out) {
  (void)params;
  out.clear();
  scratch.stats = MeshOcclusionStats{};
  index.tree.cull(frustum_of(camera), scratch.in_frustum);
  for (std::uint32_t i : scratch.in_frustum) out.push_back(index.tree_objects[i]);
  scratch.stats.objects_in_frustum = out.size();
  out.insert(out.end(), index.unusable.begin(), index.unusable.end());
  scratch.stats.objects_unusable_visible = index.unusable.size();
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
