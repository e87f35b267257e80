// cullkit/detail/mesh_occlusion/strip_gather.hpp: the strips of a cull on several tasks gather their
// occluders on demand, as one thread does (gather_on_demand.hpp): each strip walks the occluders in
// the order of their lowest keys, drops one whose box its own rows already cover nearer, and needs
// the others gathered only when their turn may come. An occluder is gathered once, by the first
// strip that needs it, into its own region of the frame; the strips that need it later find it there.
//
// Why the answer cannot change: a strip inserts the patches it does not drop in the order of a
// gathering of all of them (nearest triangle's key first, ties by occluder), as next_on_demand gives
// it; one it drops has no open cell on the strip's rows nearer than its box, so the strip would have
// skipped it at its turn (insert_strip_in_order), and covered cells never change again. What an
// occluder's gathering writes (its region, its triangles' boxes, owner, bands and extents) is a
// function of the frame's view alone, whichever strip does it.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

#include "../../config.hpp"
#include "coverage.hpp"
#include "frame.hpp"
#include "gather_on_demand.hpp"
#include "index.hpp"
#include "occluders.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// True when every point of `box` lies beyond the occluder clipping level by a wide margin, as
/// View::project computes a point's near-plane value: then no triangle with corners in the box is
/// clipped (each corner is `inside`). The box's smallest value, at its nearest corner, is at least
/// twice the level; a point's value is rounded within 2^-50 of its magnitude sum, and the level is
/// 2^-17 of the largest magnitude sum over the chosen occluders' box, which holds the point.
inline bool beyond_clip_level(const View& view, const Aabb& box) {
  const double* n = view.near_plane;
  double lowest = n[3];
  for (int a = 0; a < 3; ++a) lowest += std::min(n[a] * double(box.min[a]), n[a] * double(box.max[a]));
  return std::isfinite(view.clip_level) && lowest >= 2.0 * view.clip_level;
}

/// Sets up the strips' gathering, after the occluders are chosen (it reads none of their corners, so
/// it runs beside their projection, project_occluder_corners_on_tasks): each occluder either
/// is gathered before the strips (`s.gather_first`: patches sharing triangles, gathered in order;
/// those whose lowest key is not bounded; those a triangle of which may be clipped, whose polygons
/// go into the frame's one list), or waits ungathered in `s.ungathered` (lowest key first, ties by
/// occluder) with its drop test (drop_test). Makes room for every occluder's region.
inline void prepare_strip_gathering(const MeshIndex& index, Scratch& s) {
  const PatchSet& ps = index.patches;
  begin_gather(index, s, true);
  const std::size_t n = s.occluders.size();
  s.gather_first.assign(n, 0);
  s.ungathered.clear();
  s.drop_cells.resize(n);
  s.drop_nearest.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const std::uint32_t patch = s.occluders[q].second;
    const std::uint32_t lowest = ps.shares_triangles[patch] ? 0 : lowest_key(index, s, patch);
    if (lowest == 0 || !beyond_clip_level(s.view, ps.key_box[patch])) {
      s.gather_first[q] = 1;
      continue;
    }
    s.ungathered.emplace_back(lowest, static_cast<std::uint32_t>(q));
    drop_test(s.grid, patch_box(index, s, patch), s.drop_cells[q], s.drop_nearest[q]);
  }
  radix_sort(s.ungathered, s.ungathered_buffer);
  s.gather_claims.reset(n);
}

/// Lists the occluders gathered before the strips that kept triangles, as (key of their nearest,
/// occluder), into `s.gathered_first`: every strip starts from them.
inline void list_gathered_first(Scratch& s) {
  s.gathered_first.clear();
  for (std::size_t q = 0; q < s.occluders.size(); ++q)
    if (s.gather_first[q] && s.gathered_count[q] > 0)
      s.gathered_first.emplace_back(s.triangles[s.region_first[q]].first, static_cast<std::uint32_t>(q));
}

/// Occluder q (one waiting ungathered) gathered by this task, unless another has claimed it (then
/// false): the first task to need it gathers it (corners projected already; never a clipped
/// triangle, see prepare_strip_gathering), sorts its triangles by key, numbers its depth bands and
/// sets their extents. Nothing else of the frame is written, so tasks gather different occluders at
/// once.
inline bool gather_for_strips(const MeshOcclusionParams& params, const MeshIndex& index, Scratch& s, std::uint32_t q,
                              std::vector<ClippedPolygon>& unused) {
  std::atomic<std::uint8_t>& state = s.gather_claims.state[q];
  std::uint8_t seen = state.load(std::memory_order_acquire);
  if (seen != 0 || !state.compare_exchange_strong(seen, 1, std::memory_order_acq_rel)) return seen == 2;
  std::uint32_t kept = gather_patch(index, s, q, unused, nullptr, params.min_occluder_width_cells);
  if (!unused.empty()) {
    // Cannot happen (prepare_strip_gathering gathers such patches first): a polygon clipped here
    // would be in no list the insertion reads, so the patch is then no occluder (covers less).
    unused.clear();
    kept = 0;
  }
  s.gathered_count[q] = kept;
  const std::uint32_t first = s.region_first[q];
  auto* group = s.triangles.data() + first;
  sort_by_key(group, kept, s.sort_buffer.data() + first);
  assign_depth_bands(params, group, group + kept, s.triangle_band);
  for (std::uint32_t k = 0; k < kept; ++k) s.triangle_extents[first + k] = triangle_extent(s.grid, occluder_box(s, group[k].second));
  state.store(2, std::memory_order_release);
  return true;
}

/// One strip's walk over the occluders (next_on_demand, on the strip's rows): `waiting` holds the
/// gathered occluders whose turn may come, a heap of (key, occluder); `pending` those it needs that
/// another task is gathering, as (lowest key, occluder) in that order; `next` is the first of
/// `s.ungathered` not yet looked at.
struct StripWalk {
  std::vector<std::pair<std::uint32_t, std::uint32_t>>& waiting;
  std::vector<std::pair<std::uint32_t, std::uint32_t>>& pending;
  std::size_t next = 0;
};

/// Starts a strip's walk: the occluders gathered before the strips wait for their turn.
inline void begin_strip_walk(const Scratch& s, StripWalk& walk) {
  walk.waiting.assign(s.gathered_first.begin(), s.gathered_first.end());
  std::make_heap(walk.waiting.begin(), walk.waiting.end(), std::greater<>());
  walk.pending.clear();
  walk.next = 0;
}

/// Adds gathered occluder q to the walk's waiting ones when it kept triangles.
inline void wait_for_turn(const Scratch& s, StripWalk& walk, std::uint32_t q) {
  if (s.gathered_count[q] == 0) return;
  walk.waiting.emplace_back(s.triangles[s.region_first[q]].first, q);
  std::push_heap(walk.waiting.begin(), walk.waiting.end(), std::greater<>());
}

/// Moves the pending occluders that are gathered now to the waiting ones; true when any was.
inline bool take_gathered(const Scratch& s, StripWalk& walk) {
  std::size_t kept = 0;
  for (const auto& p : walk.pending) {
    if (s.gather_claims.state[p.second].load(std::memory_order_acquire) == 2) wait_for_turn(s, walk, p.second);
    else walk.pending[kept++] = p;
  }
  const bool any = kept != walk.pending.size();
  walk.pending.resize(kept);
  return any;
}

/// The next occluder a strip inserts, into q, in the order of a gathering of all of them: before
/// taking the nearest waiting occluder, each ungathered one whose lowest key is not above its key
/// (nor above a pending one's lowest key) is looked at, and dropped when its box misses the strip's
/// rows or `grid` (the union, worked on the strip's rows) covers its box's cells there nearer than
/// its box, else gathered here or, when another task gathers it, left pending. Looking at one
/// sooner than a gathering of all would is harmless: it is dropped only when covered, which it
/// stays. The nearest is taken only once none is pending (the strip waits for those only when it
/// has nothing else to look at). False when none is left.
inline bool next_in_strip(const MeshOcclusionParams& params, const MeshIndex& index, Scratch& s, const Strip& strip,
                          const CoverageGrid& grid, StripWalk& walk, std::vector<ClippedPolygon>& unused,
                          std::uint32_t& q) {
  for (unsigned spins = 1;;) {
    if (walk.next < s.ungathered.size()) {
      const std::uint32_t lowest = s.ungathered[walk.next].first;
      const bool before_waiting = walk.waiting.empty() || lowest <= walk.waiting.front().first;
      const bool before_pending = walk.pending.empty() || lowest <= walk.pending.front().first;
      if (before_waiting && before_pending) {
        const std::uint32_t u = s.ungathered[walk.next++].second;
        const CellRect& cells = s.drop_cells[u];
        if (cells.empty() || cells.y1 < strip.first_row || cells.y0 > strip.last_row) continue;
        if (grid.covered_nearer(cells, s.drop_nearest[u])) continue;
        if (gather_for_strips(params, index, s, u, unused)) wait_for_turn(s, walk, u);
        else walk.pending.emplace_back(lowest, u);
        continue;
      }
    }
    if (!walk.pending.empty()) {
      if (take_gathered(s, walk)) continue;
      // Nothing else to look at: the task gathering one of them is a few microseconds from done.
#if CULLKIT_HAS_SSE2
      _mm_pause();
#endif
      if ((++spins & 255u) == 0) std::this_thread::yield();  // unless it lost its core
      continue;
    }
    if (walk.waiting.empty()) return false;
    std::pop_heap(walk.waiting.begin(), walk.waiting.end(), std::greater<>());
    q = walk.waiting.back().second;
    walk.waiting.pop_back();
    return true;
  }
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
