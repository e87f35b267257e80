// cullkit/detail/nci/frame_camera.hpp: the camera one frame of NormalClassIndex::select_visible is
// selected with, its matrix in double: the user's Camera, or that camera taken into a moving
// object's local frame (moving.hpp). Rounded to float, the second could move its far plane through
// infinity and turn its pixel rays backwards, so it is never held in a Camera.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "../../geometry/camera.hpp"

namespace cullkit::detail::nci {

struct FrameCamera {
  glm::dmat4 view_proj{1.0};  // world (or local) to clip
  glm::dmat4 inverse{1.0};    // clip to world (or local): what PixelRays aims the pixel rays with
  glm::vec3 eye{0.0f};
  int width = 0, height = 0;
  DepthRange depth = DepthRange::negative_one_to_one;

  [[nodiscard]] PixelRays rays() const noexcept { return PixelRays(inverse, eye, width, height, depth); }
};

// The user's camera as it is: the same double matrices PixelRays(camera) makes.
[[nodiscard]] inline FrameCamera frame_camera(const Camera& camera) noexcept {
  FrameCamera c;
  c.view_proj = glm::dmat4(camera.view_proj);
  c.inverse = glm::inverse(c.view_proj);
  c.eye = camera.eye;
  c.width = camera.width;
  c.height = camera.height;
  c.depth = camera.depth;
  return c;
}

}  // namespace cullkit::detail::nci
