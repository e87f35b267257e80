// cullkit/detail/mesh_occlusion/query.hpp: one frame of MeshOcclusionCuller::cull, as named steps:
// frustum walk, object boxes on screen, occluder choice (occluders.hpp), the occluder patches into
// the coverage grid strip by strip of its rows (row_strips.hpp), moving occluders into the same grid
// (moving.hpp), object tests (object_tests.hpp). The boxes, the occluder candidates, the corners,
// the gathering of the occluder triangles, the strips and the object tests run on several tasks when
// the parameters ask for threads (parallel_frame.hpp, strip_gather.hpp). The steps are compiled only where the frame's definition is
// (CULLKIT_SEPARATE_CORE, config.hpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "../../config.hpp"
#include "../../geometry/camera.hpp"
#include "frame.hpp"
#include "gather_on_demand.hpp"
#include "index.hpp"
#include "moving.hpp"
#if CULLKIT_CORE_BODIES
#include "object_tests.hpp"
#include "occluders.hpp"
#include "parallel_frame.hpp"
#include "row_strips.hpp"
#endif

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// One frame of MeshOcclusionCuller::cull: clears `out`, then writes every object that may be
/// visible from `camera`, with `moving[0, moving_count)` occluding too (`m`: their working memory,
/// needed only when there are some).
/// Returns true when the frame's grid was filled and finished (box queries may then read `s`). A
/// core entry point (CULLKIT_SEPARATE_CORE, config.hpp): the steps below are compiled only where its
/// definition is.
CULLKIT_CORE_FN bool cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                          std::vector<std::uint32_t>& out, const MovingOccluder* moving, std::size_t moving_count,
                          MovingScratch* m);

/// The frame with the static occluders alone.
inline void cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                 std::vector<std::uint32_t>& out) {
  cull(index, params, camera, s, out, nullptr, 0, nullptr);
}


#if CULLKIT_CORE_BODIES
CULLKIT_CORE_FN bool cull(const MeshIndex& index, const MeshOcclusionParams& params, const Camera& camera, Scratch& s,
                          std::vector<std::uint32_t>& out, const MovingOccluder* moving, std::size_t moving_count,
                          MovingScratch* m) {
  out.clear();
  if (moving == nullptr || m == nullptr) moving_count = 0;
  MeshOcclusionStats& stats = s.stats;
  stats = MeshOcclusionStats{};
  s.frustum = frustum_of(camera);
  index.tree.cull(s.frustum, s.in_frustum);
  for (std::uint32_t& i : s.in_frustum) i = index.tree_objects[i];
  stats.objects_in_frustum = s.in_frustum.size();
  out.insert(out.end(), index.unusable.begin(), index.unusable.end());
  stats.objects_unusable_visible = index.unusable.size();

  s.view.setup(camera, params.grid_width, params.grid_height);
  stats.occlusion_enabled = s.view.enabled;
  // One object alone in the frustum has nothing to hide it but moving occluders: an object never
  // hides itself.
  if (!s.view.enabled || (s.in_frustum.size() < 2 && moving_count == 0)) {
    out.insert(out.end(), s.in_frustum.begin(), s.in_frustum.end());
    return false;
  }
  // Occluders are clipped beyond a level set by the extent of the usable objects (the tree's root).
  if (!index.tree.nodes().empty()) {
    const Aabb& all = index.tree.nodes().front().bounds;
    const double lo[3] = {all.min.x, all.min.y, all.min.z}, hi[3] = {all.max.x, all.max.y, all.max.z};
    s.view.set_clip_level(lo, hi);
  } else {
    s.view.clip_level = s.view.drawable_level = HUGE_VAL;  // no static occluder, no object to test
  }
  begin_frame(index, s);
  s.boxes.resize(s.in_frustum.size());
  const unsigned tasks = frame_tasks(params, s.in_frustum.size());
  // On several tasks, one of them empties the grid while the others project boxes.
  if (tasks == 1 || s.grid.width() != params.grid_width || s.grid.height() != params.grid_height)
    s.grid.reset(params.grid_width, params.grid_height);
  if (tasks > 1) {
    const ObjectReach reach = project_boxes_on_tasks(index, params, s, tasks);
    choose_occluders_on_tasks(index, params, s, tasks, reach);
  } else {
    for (std::size_t i = 0; i < s.in_frustum.size(); ++i) s.boxes[i] = project_box(s.view, index.bounds[s.in_frustum[i]]);
    choose_occluders(index, params, s);
  }
  // One thread gathers on demand (gather_on_demand.hpp), projecting a patch's corners as it gathers
  // it: most of the chosen patches of a frame of many small ones are never gathered. Several threads
  // project every chosen patch's corners and gather those with no lower bound on their keys first;
  // each strip of rows then gathers the others on demand (strip_gather.hpp).
  if (params.threads == 1) {
    gather_on_demand(index, params, s);
  } else {
    project_occluder_corners_on_tasks(index, params, s, tasks, [&] { prepare_strip_gathering(index, s); });
    gather_first_on_tasks(index, params, s, tasks);
  }
  stats.occluders_used = s.occluders.size();
  insert_patches(index, params, s);
  if (moving_count > 0) insert_moving(params, moving, moving_count, s, *m);
  stats.cells_covered = s.grid.covered_count();
  s.grid.finish();
  s.view_eye = camera.eye;
  insert_box_occluders(index, params, camera, s);

  if (tasks > 1) {
    stats.objects_hidden = test_objects_on_tasks(index, params, s, tasks, out);
    return true;
  }
  for (std::size_t i = 0; i < s.in_frustum.size(); ++i) {
    if (object_hidden(index, params, s, i)) ++stats.objects_hidden;
    else out.push_back(s.in_frustum[i]);
  }
  return true;
}

#endif  // CULLKIT_CORE_BODIES

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
