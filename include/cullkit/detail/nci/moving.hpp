// cullkit/detail/nci/moving.hpp: NormalClassIndex::select_visible with moving objects. Each object
// has its own index in its local frame and an affine local-to-world transform; the camera is taken
// into the object's frame (its pixel rays mapped there in double, see object_camera), the object
// selected there, and its per-pixel depths brought back to the world before the static scene is
// searched in front of them.
//
// Why depths need bringing back: the object's pixel rays are the world pixel rays mapped by the
// inverse transform, and the index measures t along their *unit* local directions. Under an affine
// map M = (L, b) a world point eye + t u (u the unit world pixel ray) is the local point
// M^-1 eye + t L^-1 u, so the local unit ray reaches it at t_local = t |L^-1 u|: the world depth is
// t_local / |L^-1 u|, one factor per pixel (1 for rotations and translations).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "../../geometry/camera.hpp"
#include "context.hpp"
#include "degenerate_camera.hpp"
#include "frame_camera.hpp"
#include "index_data.hpp"
#include "core.hpp"
#include "../../nci_params.hpp"

namespace cullkit::detail::nci {

// What a moving object's transform allows: usable (finite, affine, condition number at most
// max_condition), and if so the world-to-local map and whether depths need rescaling.
struct ObjectFrame {
  static constexpr double max_condition = 1e6;
  bool usable = false;
  bool rigid = false;              // L orthonormal within 1e-6: local t is world t
  glm::dmat4 local_to_world{1.0};
  glm::dmat4 world_to_local{1.0};
  glm::dmat3 linear_inverse{1.0};  // L^-1
};

// Checks `m` (column vectors, GLM layout). Rejected: a NaN or infinite entry; a bottom row other
// than exactly (0, 0, 0, 1) (projective: rays would not stay rays with the same t); a linear part
// whose 1-norm condition number |L|_1 |L^-1|_1 exceeds max_condition or is not finite (singular,
// or so flat that the object's frame magnifies one direction beyond what float coordinates hold).
[[nodiscard]] inline ObjectFrame object_frame(const glm::mat4& m) noexcept {
  ObjectFrame f;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return f;
  if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f) return f;
  f.local_to_world = glm::dmat4(m);
  const glm::dmat3 linear(f.local_to_world);
  const double det = glm::determinant(linear);
  if (!(det != 0.0) || !std::isfinite(det)) return f;
  f.linear_inverse = glm::inverse(linear);
  double norm = 0.0, norm_inverse = 0.0;  // largest column sum of absolute values
  for (int c = 0; c < 3; ++c) {
    norm = std::max(norm, std::fabs(linear[c][0]) + std::fabs(linear[c][1]) + std::fabs(linear[c][2]));
    norm_inverse = std::max(norm_inverse, std::fabs(f.linear_inverse[c][0]) + std::fabs(f.linear_inverse[c][1]) +
                                              std::fabs(f.linear_inverse[c][2]));
  }
  if (!(norm * norm_inverse <= ObjectFrame::max_condition)) return f;
  f.world_to_local = glm::inverse(f.local_to_world);
  double off = 0.0;  // largest entry of L^T L - I
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) off = std::max(off, std::fabs(glm::dot(linear[i], linear[j]) - (i == j ? 1.0 : 0.0)));
  f.rigid = off <= 1e-6;
  f.usable = true;
  return f;
}

// Every triangle an object's index kept, as (object, triangle) pairs: a rejected object, or any
// object under a degenerate camera, is reported whole.
template <class ObjectIndex>
void report_whole(const ObjectIndex& index, std::uint32_t id, std::vector<NciObjectTriangle>& out) {
  const std::size_t n = index.stats().triangles_input;
  for (std::size_t t = 0; t < n; ++t)
    if (index.triangle_class(static_cast<std::uint32_t>(t)) >= 0) out.push_back(NciObjectTriangle{id, static_cast<std::uint32_t>(t)});
}

// The camera taken into an object's frame: the world pixel rays mapped by world_to_local in double
// (their target points, and the eye, which is rounded to float once there), never a float matrix.
// `eye_error`: the largest coordinate of that rounding of the eye (0 when it is exact). False when
// the mapped eye is not a finite float (the object cannot be selected in its frame).
[[nodiscard]] inline bool object_camera(const Camera& camera, const ObjectFrame& frame, FrameCamera& local,
                                        double& eye_error) noexcept {
  const FrameCamera world = frame_camera(camera);
  local = world;
  local.view_proj = world.view_proj * frame.local_to_world;
  local.inverse = frame.world_to_local * world.inverse;
  const glm::dvec3 eye(frame.world_to_local * glm::dvec4(glm::dvec3(camera.eye), 1.0));
  local.eye = glm::vec3(eye);
  const glm::dvec3 off = glm::abs(glm::dvec3(local.eye) - eye);
  eye_error = std::max({off.x, off.y, off.z});
  return std::isfinite(local.eye.x) && std::isfinite(local.eye.y) && std::isfinite(local.eye.z);
}

// An object's pixel rays start from its eye rounded to float in its frame (object_camera), up to
// `eye_error` beside the true rays in each coordinate. Where that is at most one float rounding
// of the hit depth, the ray test's edge band (8 roundings of the corners' offsets from the eye,
// of which 2 were measured to cover other float tracers) still covers it; elsewhere (the frame's
// origin more than about twice as far from the eye as the hit) the object's solid depth is not
// trusted to hide the static scene: it hides nothing there.
[[nodiscard]] inline bool solid_trusted(float local_t, double eye_error) noexcept {
  return eye_error <= 0x1p-24 * double(local_t);
}

// `object_data(index)` is an object's IndexData (its index's own frame).
template <class ObjectIndex, class ObjectData>
void select_with_objects(const IndexData& data, const Camera& camera, const NciMovingObject<ObjectIndex>* objects,
                         std::size_t object_count, const ObjectData& object_data, NciContext& context, VisibleSet& out,
                         std::vector<NciObjectTriangle>& object_triangles, NciPixels* pixels) {
  object_triangles.clear();
  const int width = camera.width, height = camera.height;
  if (width <= 0 || height <= 0 || object_count == 0) {
    if (width > 0 && height > 0 && degenerate_camera(camera)) select_everything(data, camera, context, out, pixels);
    else select_frame(data, frame_camera(camera), context, out, pixels, nullptr, nullptr);
    return;
  }
  if (degenerate_camera(camera)) {
    select_everything(data, camera, context, out, pixels);
    for (std::size_t k = 0; k < object_count; ++k)
      if (objects[k].index) report_whole(*objects[k].index, objects[k].object_id, object_triangles);
    std::sort(object_triangles.begin(), object_triangles.end());
    object_triangles.erase(std::unique(object_triangles.begin(), object_triangles.end()), object_triangles.end());
    return;
  }
  const std::size_t pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  auto& scratch = ContextAccess::scratch(context);
  if (!scratch.objects) scratch.objects = std::make_unique<MovingScratch>();
  auto& o = *scratch.objects;
  o.depth.assign(pixel_count, std::numeric_limits<float>::infinity());
  o.solid.assign(pixel_count, std::numeric_limits<float>::infinity());
  o.candidates.clear();
  o.triangle.assign(pixel_count, NciPixels::miss);
  o.object.assign(pixel_count, NciPixels::miss);
  const PixelRays world_rays(camera);
  std::size_t rejected = 0;
  for (std::size_t k = 0; k < object_count; ++k) {
    CULLKIT_ASSERT(objects[k].index != nullptr, "every moving object has an index");
    if (!objects[k].index) continue;
    const std::uint32_t id = objects[k].object_id;
    const ObjectFrame frame = object_frame(objects[k].local_to_world);
    FrameCamera local;
    double eye_error = 0.0;
    if (!frame.usable || !object_camera(camera, frame, local, eye_error)) {
      // Conservative: the object may be anywhere, so all of it may be seen and it hides nothing.
      ++rejected;
      report_whole(*objects[k].index, id, object_triangles);
      continue;
    }
    select_frame(object_data(*objects[k].index), local, o.context, o.set, &o.pixels, nullptr, nullptr);
    const auto& object_scratch = ContextAccess::scratch(o.context);
    const auto& solid = object_scratch.pixel_solid_t;
    // World depth of local depth t at pixel p (see the file comment).
    const auto to_world = [&](float t, std::size_t p) -> float {
      if (frame.rigid || !(t < std::numeric_limits<float>::infinity())) return t;
      const int x = static_cast<int>(p % static_cast<std::size_t>(width)), y = static_cast<int>(p / static_cast<std::size_t>(width));
      const glm::dvec3 u(world_rays.ray(x, y).direction);
      const double stretch = glm::length(frame.linear_inverse * u);
      return stretch > 0.0 ? static_cast<float>(double(t) / stretch) : t;
    };
    for (std::size_t p = 0; p < pixel_count; ++p) {
      const std::uint32_t tri = o.pixels.triangle[p];
      const bool has_solid = solid.size() == pixel_count && solid[p] < std::numeric_limits<float>::infinity() &&
                             solid_trusted(solid[p], eye_error);
      if (tri == NciPixels::miss && !has_solid) continue;
      if (has_solid) o.solid[p] = std::min(o.solid[p], to_world(solid[p], p));
      if (tri == NciPixels::miss) continue;
      const float t = to_world(o.pixels.depth[p], p);
      if (t <= o.solid[p]) o.candidates.push_back(MovingScratch::Candidate{id, tri, t, static_cast<std::uint32_t>(p)});
      if (t < o.depth[p]) {
        o.depth[p] = t;
        o.triangle[p] = tri;
        o.object[p] = id;
      }
    }
    // The object's triangles beside its pixels' first hits (edge bands; see select_visible).
    for (const auto& e : object_scratch.extras) {
      const float t = to_world(e.t, e.pixel);
      if (t <= o.solid[e.pixel]) o.candidates.push_back(MovingScratch::Candidate{id, e.tri, t, e.pixel});
    }
  }
  select_frame(data, frame_camera(camera), context, out, pixels, o.depth.data(), o.solid.data());
  context.stats.moving_objects_rejected = rejected;
  // An object's triangle is reported where it lies no farther than the pixel's solid depth after
  // the static scene (then nothing certain hides it); the pixels keep the objects' first hits
  // where no static triangle came in front.
  const auto& solid = scratch.pixel_solid_t;
  for (const auto& c : o.candidates)
    if (solid.size() == pixel_count && c.t <= solid[c.pixel]) object_triangles.push_back(NciObjectTriangle{c.object, c.triangle});
  for (std::size_t p = 0; p < pixel_count; ++p) {
    if (o.object[p] == NciPixels::miss) continue;
    if (scratch.pixel_tri.size() == pixel_count && scratch.pixel_tri[p] != no_triangle) continue;
    if (pixels && pixels->depth.size() == pixel_count) pixels->depth[p] = o.depth[p];
  }
  std::sort(object_triangles.begin(), object_triangles.end());
  object_triangles.erase(std::unique(object_triangles.begin(), object_triangles.end()), object_triangles.end());
}

}  // namespace cullkit::detail::nci
