// cullkit/detail/nci/mixed_tile.hpp: one screen tile walked until it turns out crowded, then its
// unfinished rays cast through the triangle hierarchy. A frame that is not crowded as a whole (the eye
// inside the scene, or few triangles per pixel) may still hold a few tiles that look across many
// small, distant triangles, most of them between pixel centres (an arena's far stands seen from its
// floor); the walk pays for each of them, the hierarchy per ray.
#pragma once

#include <cstddef>

#include "../bits.hpp"
#include "frame_tile.hpp"
#include "slice_walk.hpp"

namespace cullkit::detail::nci {

// A tile's walk hands its unfinished rays to the hierarchy once it has met more than this many
// triangles per live ray of the tile. See tile_cast_budget for what was measured.
inline constexpr double tile_cast_crowding = 4.0;

// The walk's budget of triangles met for a tile with `live_rays` live rays.
[[nodiscard]] inline std::size_t tile_cast_budget(int live_rays) noexcept {
  return static_cast<std::size_t>(tile_cast_crowding * live_rays) + 1;
}

// One screen tile (x0, y0)..(x1, y1): walked, and when the walk has met more than its budget before
// every ray finished, the rest of its live rays cast through the triangle hierarchy from the hits the
// walk found. The same outputs as process_tile: both paths keep every hit a ray can still take.
inline void process_tile_mixed(const IndexData& data, const ViewSetup& f, int x0, int y0, int x1, int y1, TileState& r,
                               Worker& worker, Scratch& scratch) {
  drive_tile(data, f, x0, y0, x1, y1, r, worker, scratch, [&](int tw, int th, TileMasks& m, const glm::dvec3& cone_sum) {
    int live_rays = 0;
    for (int y = 0; y < th; ++y) live_rays += detail::popcount(m.live[y]);
    if (!walk_tile(data, f, x0, y0, tw, th, r, worker, m, cone_sum, tile_cast_budget(live_rays)))
      cast_live_rays(data, f, x0, y0, tw, th, m.live, r, worker);
  });
}

}  // namespace cullkit::detail::nci
