// cullkit/detail/mesh_occlusion/gather_on_demand.hpp: one thread gathers an occluder patch only when
// its turn among the patches may come, and never one whose box the union already covers nearer.
// A patch's turn is its nearest gathered triangle's key; its box bounds that key from below, so the
// patches wait ungathered in the order of their bounds and are gathered as the gathered ones' keys
// reach them: the insertion order is that of gathering all first and sorting the patches by their
// nearest triangle's key, and the answers are the same.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "coverage.hpp"
#include "frame.hpp"
#include "index.hpp"
#include "occluders.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// The depth below which no point of a patch whose box is seen as `b` (usable) lies, as its
/// corners and clip points are computed: the box's nearest corner's depth, 2^-12 of it nearer. Both
/// depths are sums of three products of the same rows and coordinates in double precision, whose
/// rounding is below 2^-50 of the box's depth scale (the sum of the products' magnitudes), and
/// every corner of a usable box lies deeper than 1e-8 of that scale (project_box): the rounding is
/// below 2^-23 of the box's depth. A clip point is on a segment between two corners, rounded in
/// world coordinates (far below that unless they exceed the distance from the eye by 2^35).
inline double depth_floor(const BoxView& b) { return b.w_min * (1.0 - 0x1p-12); }

/// The smallest sort key (gather_patch) a triangle of patch `patch` can get this frame; 0 (no
/// bound) when the patch's key box (PatchSet::key_box: its corners and those of the whole triangles
/// its parts come from) is not usable seen from the eye. A triangle's key is its nearest corner's
/// depth, a clipped polygon's its farthest corner's (a corner beyond the clipping level among
/// them), a part's as its whole's (the nearest or farthest of the whole's corners, or its own):
/// each the depth of a corner in the key box, no nearer than its `depth_floor`; rounded to float
/// (non-decreasing), no key is below that floor's.
inline std::uint32_t lowest_key(const MeshIndex& index, Scratch& s, std::uint32_t patch) {
  const Aabb& key_box = index.patches.key_box[patch];
  const Aabb& box = index.patches.patches[patch].box;
  const bool own_box = key_box.min == box.min && key_box.max == box.max;
  const BoxView b = own_box ? patch_box(index, s, patch) : project_box(s.view, key_box);
  if (!b.usable) return 0;
  const float lowest = static_cast<float>(depth_floor(b));
  if (!(lowest > 0.0f && lowest < 0x1p100f)) return 0;
  std::uint32_t bits;
  std::memcpy(&bits, &lowest, sizeof bits);
  return bits;
}

/// The test that drops a patch whose box is seen as `b` ungathered: the cells it may reach, into
/// `cells`, and the inverse depth, into `nearest`, that the union must cover each of them at
/// (CoverageGrid::covered_nearer). Every triangle gathered from the patch has its screen box and
/// nearest point within (the box's rectangle widened by 2^-16 of its coordinates, far beyond the
/// rounding of a projection, and its `depth_floor`), so when the union passes the test the patch
/// would be skipped at its turn (insert_strip: no open cell to seed), and covered cells stay so.
/// A box that is not usable gets an empty rectangle, which never passes.
inline void drop_test(const CoverageGrid& grid, const BoxView& b, CellRect& cells, float& nearest) {
  if (!b.usable) {
    cells = CellRect{0, 0, -1, -1};
    nearest = 0.0f;
    return;
  }
  const double magnitude = std::max(std::max(std::fabs(b.x0), std::fabs(b.x1)), std::max(std::fabs(b.y0), std::fabs(b.y1)));
  const double m = 0x1p-16 * (1.0 + magnitude);
  cells = grid.cells_of(b.x0 - m, b.y0 - m, b.x1 + m, b.y1 + m);
  nearest = static_cast<float>(1.0 / depth_floor(b));
}

/// Sorts items[0, n) by key, ties in their order (`buffer`: room for n): by insertion when few, else
/// by bytes of the key, skipping a byte all keys share (a patch's depths are close).
inline void sort_by_key(std::pair<std::uint32_t, std::uint32_t>* items, std::uint32_t n,
                        std::pair<std::uint32_t, std::uint32_t>* buffer) {
  if (n <= 24) {
    for (std::uint32_t i = 1; i < n; ++i) {
      const auto item = items[i];
      std::uint32_t j = i;
      for (; j > 0 && items[j - 1].first > item.first; --j) items[j] = items[j - 1];
      items[j] = item;
    }
    return;
  }
  std::uint32_t counts[4][256] = {};
  for (std::uint32_t i = 0; i < n; ++i)
    for (int pass = 0; pass < 4; ++pass) ++counts[pass][(items[i].first >> (8 * pass)) & 255u];
  std::pair<std::uint32_t, std::uint32_t>*from = items, *to = buffer;
  for (int pass = 0; pass < 4; ++pass) {
    const int shift = 8 * pass;
    std::uint32_t* offsets = counts[pass];
    if (offsets[(from[0].first >> shift) & 255u] == n) continue;
    std::uint32_t sum = 0;
    for (int d = 0; d < 256; ++d) {
      const std::uint32_t count = offsets[d];
      offsets[d] = sum;
      sum += count;
    }
    for (std::uint32_t i = 0; i < n; ++i) to[offsets[(from[i].first >> shift) & 255u]++] = from[i];
    std::swap(from, to);
  }
  if (from != items) std::copy(from, from + n, items);
}

/// One thread: projects the corners of patch `patch` (PatchSet::vertices) not yet projected this
/// frame into the frame's cache (project_vertex), as gather_patch wants them. One pass over the
/// patch's list costs less than looking up each triangle's three as it is gathered (triangles share
/// corners): sportsCar, which gathers nearly every chosen patch, took 4 % longer so.
inline void project_patch_corners(const MeshIndex& index, Scratch& s, std::uint32_t patch) {
  const PatchSet& ps = index.patches;
  for (std::uint32_t i = ps.vertex_first[patch]; i < ps.vertex_first[patch + 1]; ++i) project_vertex(index, s, ps.vertices[i]);
}

/// One thread: gathers occluder q (gather_patch, its corners projected first: an occluder never
/// gathered costs no projection) into its region, sorts its triangles by key (ties
/// in the order gathered, as one sort of all of them leaves them), numbers its depth bands and,
/// when it keeps any, adds it to the occluders waiting for their turn.
inline void gather_waiting(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s, std::uint32_t q) {
  project_patch_corners(index, s, s.occluders[q].second);
  const std::uint32_t kept = gather_patch(index, s, q, s.clipped, nullptr, params.min_occluder_width_cells);
  s.gathered_count[q] = kept;
  if (kept == 0) return;
  const std::uint32_t first = s.region_first[q];
  auto* group = s.triangles.data() + first;
  sort_by_key(group, kept, s.sort_buffer.data() + first);
  assign_depth_bands(params, group, group + kept, s.triangle_band);
  s.waiting.emplace_back(group[0].first, q);
  std::push_heap(s.waiting.begin(), s.waiting.end(), std::greater<>());
}

/// One thread: prepares gathering on demand (next_on_demand). Occluders with no lowest key (and
/// those whose patches share triangles, gathered in order so that a triangle goes in with the
/// first occluder keeping it) are gathered now; the others wait ungathered, lowest key first, ties
/// by occluder.
inline void gather_on_demand(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const PatchSet& ps = index.patches;
  begin_gather(index, s, false);
  s.on_demand = true;
  s.waiting.clear();
  s.ungathered.clear();
  s.next_ungathered = 0;
  s.drop_cells.resize(s.occluders.size());
  s.drop_nearest.resize(s.occluders.size());
  for (std::size_t q = 0; q < s.occluders.size(); ++q) {
    const std::uint32_t patch = s.occluders[q].second;
    const std::uint32_t lowest = ps.shares_triangles[patch] ? 0 : lowest_key(index, s, patch);
    if (lowest == 0) {
      gather_waiting(index, params, s, static_cast<std::uint32_t>(q));
      continue;
    }
    s.ungathered.emplace_back(lowest, static_cast<std::uint32_t>(q));
    // Set up now, while the patch's box is at hand, not at its turn.
    drop_test(s.grid, patch_box(index, s, patch), s.drop_cells[q], s.drop_nearest[q]);
  }
  radix_sort(s.ungathered, s.ungathered_buffer);
}

/// One thread: the next occluder to insert into the union `s.grid`, in the order of a gathering of
/// all of them (nearest triangle's key first, ties by occluder), into q. Before
/// taking the nearest waiting occluder, gathers each ungathered one whose lowest key is not above
/// that key (it may come first), except that one whose box's cells the union covers already at
/// least as near (drop_test) is dropped ungathered: at its turn insert_strip would have skipped
/// it. False when none is left.
inline bool next_on_demand(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s, std::uint32_t& q) {
  for (;;) {
    const bool any_waiting = !s.waiting.empty();
    if (s.next_ungathered < s.ungathered.size() &&
        (!any_waiting || s.ungathered[s.next_ungathered].first <= s.waiting.front().first)) {
      const std::uint32_t u = s.ungathered[s.next_ungathered++].second;
      if (!s.grid.covered_nearer(s.drop_cells[u], s.drop_nearest[u])) gather_waiting(index, params, s, u);
      continue;
    }
    if (!any_waiting) return false;
    std::pop_heap(s.waiting.begin(), s.waiting.end(), std::greater<>());
    q = s.waiting.back().second;
    s.waiting.pop_back();
    return true;
  }
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
