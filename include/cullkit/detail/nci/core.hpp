// cullkit/detail/nci/core.hpp: the entry points of NormalClassIndex's core, the part that does not
// depend on the vertex type (users never name this). The core is compiled once per translation unit
// by default, or once per program with CULLKIT_SEPARATE_CORE (config.hpp): then only the unit that
// defines CULLKIT_IMPLEMENTATION includes the build and select headers below.
#pragma once

#include <vector>

#include <glm/vec3.hpp>

#include "../../config.hpp"
#include "../../geometry/camera.hpp"
#include "context.hpp"
#include "frame_camera.hpp"
#include "index_data.hpp"
#include "../../nci_params.hpp"

namespace cullkit::detail::nci {

/// Reports build progress `f` in [0, 1] to the user's callback, if any.
inline void report(const IndexData& data, float f) {
  if (data.params.progress) data.params.progress(f, data.params.progress_user);
}

/// Builds the index from the valid triangles `gather` left in `data` (vertices, tri_vertices,
/// tri_original, box, the skip counts) and their unit normals.
CULLKIT_CORE_FN void build(IndexData& data, std::vector<glm::vec3>& normals);

/// NormalClassIndex::select_visible for the static scene. `initial_depth` and `initial_solid`
/// (per pixel, or null): the depths the pixels start from (moving objects selected before).
/// pre: `camera` is not degenerate (see degenerate_camera) unless it has no pixel.
CULLKIT_CORE_FN void select_frame(const IndexData& data, const FrameCamera& camera, NciContext& context, VisibleSet& out,
                                  NciPixels* pixels, const float* initial_depth, const float* initial_solid);

}  // namespace cullkit::detail::nci

#if CULLKIT_CORE_BODIES
#include "build.hpp"
#include "select.hpp"
#endif
