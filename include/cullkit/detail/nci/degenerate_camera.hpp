// cullkit/detail/nci/degenerate_camera.hpp: NormalClassIndex's answer for a camera that has no
// usable pixel rays (NaN or infinite eye, NaN, infinite or singular matrix): every kept triangle.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/mat4x4.hpp>

#include "../../geometry/camera.hpp"
#include "../../geometry/frustum.hpp"
#include "context.hpp"
#include "index_data.hpp"

namespace cullkit::detail::nci {

// True when the camera's pixel rays are undefined: a non-finite eye coordinate, or a matrix that
// Frustum::from_matrix also treats as deciding nothing (detail::degenerate_matrix: a non-finite
// entry, singular or nearly so). Then no pixel can decide
// anything, and the conservative answer is "every triangle may be visible" (as the frustum of such
// a matrix keeps everything).
[[nodiscard]] inline bool degenerate_camera(const Camera& camera) noexcept {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(camera.eye[k])) return true;
  double m[4][4];
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[r][c] = static_cast<double>(camera.view_proj[c][r]);
  return detail::degenerate_matrix(m);
}

// The answer for a degenerate camera: every kept triangle (mesh numbering, sorted), none tested;
// per-pixel output all misses at infinite depth (no pixel has a ray). Leaves the context's
// per-pixel records as "nothing hit" so that moving-object code reading them stays consistent.
inline void select_everything(const IndexData& data, const Camera& camera, NciContext& context, VisibleSet& out,
                              NciPixels* pixels) {
  out.triangles.clear();
  out.triangles_tested = 0;
  context.stats = NciSelectStats{};
  for (std::size_t t = 0; t < data.class_of.size(); ++t)
    if (data.class_of[t] != skipped_class) out.triangles.push_back(static_cast<std::uint32_t>(t));
  const int width = camera.width > 0 && camera.height > 0 ? camera.width : 0;
  const int height = width > 0 ? camera.height : 0;
  const std::size_t pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  Scratch& scratch = ContextAccess::scratch(context);
  scratch.extras.clear();
  scratch.pixel_tri.assign(pixel_count, no_triangle);
  scratch.pixel_t.assign(pixel_count, std::numeric_limits<float>::infinity());
  scratch.pixel_solid_t.assign(pixel_count, std::numeric_limits<float>::infinity());
  if (pixels) {
    pixels->width = std::max(0, camera.width);
    pixels->height = std::max(0, camera.height);
    pixels->triangle.assign(pixel_count, NciPixels::miss);
    pixels->depth.assign(pixel_count, std::numeric_limits<float>::infinity());
  }
}

}  // namespace cullkit::detail::nci
