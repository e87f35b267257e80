// cullkit/detail/nci/select.hpp: select_visible's pipeline: the frame, the tiles spread over the
// workers, and the merge of their answers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <atomic>

#include "../bits.hpp"
#include "../parallel.hpp"
#include "context.hpp"
#include "core.hpp"
#include "index_data.hpp"
#include "frame_tile.hpp"
#include "mixed_tile.hpp"
#include "slice_walk.hpp"
#include "view.hpp"

namespace cullkit::detail::nci {

// The tile edge for a screen: NciParams::tile_size, or when it is 0, 64 from 640x480 pixels up
// and 32 below (bigger tiles pay from there on; see NciParams::tile_size).
[[nodiscard]] inline int tile_edge(const IndexData& data, int width, int height) noexcept {
  if (data.params.tile_size != 0) return data.params.tile_size;
  return static_cast<long long>(width) * height >= 640LL * 480LL ? TileState::max_tile : 32;
}

// The pixels whose centres may see the scene box grown by data.delta (as the per-ray box test),
// its corners rounded outward to float: it holds every triangle's rectangle.
[[nodiscard]] inline Rect scene_box_rect(const IndexData& data, const ViewSetup& frame) {
  const glm::dvec3 lo = glm::dvec3(data.box.min) - data.delta, hi = glm::dvec3(data.box.max) + data.delta;
  const auto down = [](double x) {
    const float v = static_cast<float>(x);
    return double(v) > x ? std::nextafter(v, -std::numeric_limits<float>::infinity()) : v;
  };
  const auto up = [](double x) {
    const float v = static_cast<float>(x);
    return double(v) < x ? std::nextafter(v, std::numeric_limits<float>::infinity()) : v;
  };
  glm::vec3 corner[8];
  for (int k = 0; k < 8; ++k)
    corner[k] = glm::vec3((k & 1) ? up(hi.x) : down(lo.x), (k & 2) ? up(hi.y) : down(lo.y),
                          (k & 4) ? up(hi.z) : down(lo.z));
  return project_rect(frame, corner, 8);
}

// The first `count` worker slots ready for a call: per-triangle and per-chunk records sized to
// the index (their stamps and epochs restarted when they are made or wrap), lists emptied.
inline void prepare_workers(const IndexData& data, Scratch& scratch, unsigned count) {
  if (scratch.workers.size() < count) scratch.workers.resize(count);
  for (unsigned i = 0; i < count; ++i) {
    auto& worker = scratch.workers[i];
    if (worker.tri.size() != data.triangle_count()) {
      worker.tri.assign(data.triangle_count(), Worker::Tri{0u, 0u, Rect{0, 0, -1, -1}});
      worker.stamp_value = 0;
      worker.frame_epoch = 0;
    }
    if (worker.chunk.size() != data.chunk_box.size() / 6) {
      worker.chunk.assign(data.chunk_box.size() / 6, Worker::Chunk{0u, Rect{0, 0, -1, -1}});
      worker.frame_epoch = 0;
      for (auto& t : worker.tri) t.epoch = 0u;
    }
    if (++worker.frame_epoch == 0) {
      for (auto& t : worker.tri) t.epoch = 0u;
      for (auto& c : worker.chunk) c.epoch = 0u;
      worker.frame_epoch = 1;
    }
    worker.tested_count = 0;
    worker.extra.clear();
    worker.edge_hits.clear();
    worker.stats = NciSelectStats{};
  }
}

// Whether the frame's tiles are cast through the triangle hierarchy (frame_tile.hpp) rather than
// walked: never under walk_only, always under rays_only, and under automatic when the view is
// crowded: the eye outside the scene box (grown by the grid's inflation) and at least
// `IndexData::cast_crowding` triangles per pixel of the box's screen rectangle (f.box_rect).
[[nodiscard]] inline bool cast_frame(const IndexData& data, const ViewSetup& f) noexcept {
  if (data.bvh.root == TriangleBvhNode::empty) return false;
  switch (data.params.crowded_path) {
    case NciCrowdedPath::walk_only: return false;
    case NciCrowdedPath::rays_only: return true;
    case NciCrowdedPath::automatic: break;
  }
  const glm::dvec3 lo = glm::dvec3(data.box.min) - data.delta, hi = glm::dvec3(data.box.max) + data.delta;
  const bool outside = f.eye.x < lo.x || f.eye.y < lo.y || f.eye.z < lo.z || f.eye.x > hi.x || f.eye.y > hi.y || f.eye.z > hi.z;
  const Rect& b = f.box_rect;
  if (!outside || b.x0 > b.x1) return false;
  const double pixels = b.x0 == Rect::full ? double(f.width) * double(f.height)
                                           : double(b.x1 - b.x0 + 1) * double(b.y1 - b.y0 + 1);
  return double(data.triangle_count()) >= IndexData::cast_crowding * pixels;
}

// Every tile of the frame, on `count` tasks (the caller's TaskRunner or the library's pool): task
// i uses worker slot i and takes tiles from a shared counter until none is left.
inline void run_tiles(const IndexData& data, const ViewSetup& frame, NciContext& context, Scratch& scratch, unsigned count,
                      int tiles_x, std::size_t tile_count) {
  const int tile = frame.tile, width = frame.width, height = frame.height;
  std::atomic<std::size_t> next{0};
  auto work = [&](unsigned index) {
    auto& worker = scratch.workers[index];
    // Per-tile ray scratch (about 320 KB), made once per worker slot of the context and reused
    // across calls (not per tile, not on the stack); process_tile sets every field it reads.
    if (worker.tile_rays.empty()) worker.tile_rays.resize(1);
    TileState& rays = worker.tile_rays.front();
    const std::size_t words = (data.triangle_count() + 63) / 64;
    worker.tested_bits.assign(words, 0u);
    worker.shown_bits.assign(words, 0u);
    worker.touched.assign((words + 63) / 64, 0u);
    for (;;) {
      const std::size_t t = next.fetch_add(1, std::memory_order_relaxed);
      if (t >= tile_count) break;
      const int tx = static_cast<int>(t % static_cast<std::size_t>(tiles_x));
      const int ty = static_cast<int>(t / static_cast<std::size_t>(tiles_x));
      const std::uint32_t before = worker.tested_count;
      if (frame.cast_frame)
        process_tile_frame(data, frame, tx * tile, ty * tile, std::min(width, (tx + 1) * tile),
                           std::min(height, (ty + 1) * tile), rays, worker, scratch);
      else if (frame.cast_crowded_tiles)
        process_tile_mixed(data, frame, tx * tile, ty * tile, std::min(width, (tx + 1) * tile),
                           std::min(height, (ty + 1) * tile), rays, worker, scratch);
      else
        process_tile(data, frame, tx * tile, ty * tile, std::min(width, (tx + 1) * tile), std::min(height, (ty + 1) * tile),
                     rays, worker, scratch);
      context.tile_tested[t] = worker.tested_count - before;
    }
  };
  using Work = decltype(work);
  detail::run_tasks(data.params.task_runner, count,
                    [](void* job, std::size_t task) { (*static_cast<Work*>(job))(static_cast<unsigned>(task)); }, &work);
}

// Merges the workers' answers: statistics, edge-band extras (in the mesh's numbering), the count
// of distinct tested triangles (the union of the workers' bit sets) and the visible set (pixel
// winners and extras), sorted by mesh id through a bit set over the mesh.
inline void merge_workers(const IndexData& data, NciContext& context, Scratch& scratch, unsigned count, VisibleSet& out) {
  for (unsigned i = 0; i < count; ++i) {
    const auto& worker = scratch.workers[i];
    context.stats.ray_tests += worker.stats.ray_tests;
    context.stats.cells_visited += worker.stats.cells_visited;
    context.stats.slices_walked += worker.stats.slices_walked;
    context.stats.triangles_met += worker.stats.triangles_met;
    context.stats.triangles_no_pixel += worker.stats.triangles_no_pixel;
    context.stats.cells_walked += worker.stats.cells_walked;
    context.stats.tiles_ray_cast += worker.stats.tiles_ray_cast;
    for (const auto& e : worker.extra) scratch.extras.push_back(Extra{data.original(e.tri), e.t, e.pixel});
  }
  {
    // Every worker's lists grow to what any worker needed (the extras to this call's total), so
    // a later frame that spreads the same tiles over the workers differently does not allocate.
    std::size_t cand = 0, unsure = 0, met = 0, buckets = 0;
    bool frames = false;  // some worker cast a tile through the triangle hierarchy: all get its packets
    for (unsigned i = 0; i < count; ++i) {
      cand = std::max(cand, scratch.workers[i].candidates.capacity());
      met = std::max({met, scratch.workers[i].met_in_slice_peak, scratch.workers[i].met_in_slice.capacity(),
                      scratch.workers[i].met_order.capacity()});
      buckets = std::max(buckets, scratch.workers[i].met_bucket.capacity());
      unsure = std::max(unsure, scratch.workers[i].edge_hits.capacity());
      frames = frames || !scratch.workers[i].frame_slots.empty();
    }
    // The buckets of admit_met_in_leaf_order: a power of two at least the count, at most 2^16, + 1.
    std::size_t met_buckets = 1;
    while (met_buckets < met && met_buckets < (std::size_t{1} << 16)) met_buckets <<= 1;
    buckets = std::max(buckets, met > 0 ? met_buckets + 1 : 0);
    for (unsigned i = 0; i < count; ++i) {
      auto& worker = scratch.workers[i];
      worker.candidates.reserve(cand);
      worker.met_in_slice.reserve(met);
      worker.met_order.reserve(met);
      worker.met_bucket.reserve(buckets);
      worker.edge_hits.reserve(unsure);
      worker.extra.reserve(scratch.extras.size());
      worker.active_classes.reserve(data.class_axis.size());
      worker.class_on.reserve(data.class_axis.size());
      if (worker.frame_slots.empty() && frames) worker.frame_slots.resize(frame_turns);
    }
  }
  auto& mesh_bits = scratch.shown_mesh;
  mesh_bits.assign((data.stats.triangles_input + 63) / 64, 0u);
  auto& mesh_touched = scratch.shown_mesh_touched;
  mesh_touched.assign((mesh_bits.size() + 63) / 64, 0u);
  const std::size_t blocks = (data.triangle_count() + 4095) / 4096;
  for (std::size_t b = 0; b < blocks; ++b) {
    std::uint64_t any = 0;
    for (unsigned i = 0; i < count; ++i) any |= scratch.workers[i].touched[b];
    for (; any; any &= any - 1) {
      const std::size_t w = 64 * b + static_cast<std::size_t>(detail::lowest_bit(any));
      std::uint64_t tested = 0, shown = 0;
      for (unsigned i = 0; i < count; ++i) {
        tested |= scratch.workers[i].tested_bits[w];
        shown |= scratch.workers[i].shown_bits[w];
      }
      out.triangles_tested += static_cast<std::size_t>(detail::popcount(tested));
      while (shown) {
        const std::uint32_t m = data.original(static_cast<std::uint32_t>(64 * w) + static_cast<std::uint32_t>(detail::lowest_bit(shown)));
        shown &= shown - 1;
        mesh_bits[m / 64] |= std::uint64_t{1} << (m % 64);
        mesh_touched[m / 4096] |= std::uint64_t{1} << (m / 64 % 64);
      }
    }
  }
  for (std::size_t b = 0; b < mesh_touched.size(); ++b) {
    for (std::uint64_t any = mesh_touched[b]; any; any &= any - 1) {
      const std::size_t w = 64 * b + static_cast<std::size_t>(detail::lowest_bit(any));
      for (std::uint64_t bits = mesh_bits[w]; bits; bits &= bits - 1)
        out.triangles.push_back(static_cast<std::uint32_t>(64 * w) + static_cast<std::uint32_t>(detail::lowest_bit(bits)));
    }
  }
}

// The frame's per-pixel answer in the mesh's numbering.
inline void write_pixels(const IndexData& data, const Scratch& scratch, std::size_t pixel_count, NciPixels& pixels) {
  pixels.triangle.resize(pixel_count);
  pixels.depth.resize(pixel_count);
  for (std::size_t i = 0; i < pixel_count; ++i) {
    const std::uint32_t tri = scratch.pixel_tri[i];
    pixels.triangle[i] = tri == no_triangle ? NciPixels::miss : data.original(tri);
    pixels.depth[i] = tri == no_triangle ? std::numeric_limits<float>::infinity() : scratch.pixel_t[i];
  }
}

#if CULLKIT_CORE_BODIES
// Declared in core.hpp.
CULLKIT_CORE_FN void select_frame(const IndexData& data, const FrameCamera& camera, NciContext& context, VisibleSet& out,
                         NciPixels* pixels, const float* initial_depth, const float* initial_solid) {
  Scratch& scratch = ContextAccess::scratch(context);
  out.triangles.clear();
  out.triangles_tested = 0;
  context.stats = NciSelectStats{};
  const int width = camera.width, height = camera.height;
  if (pixels) {
    pixels->width = std::max(0, width);
    pixels->height = std::max(0, height);
    pixels->triangle.clear();
    pixels->depth.clear();
  }
  if (width <= 0 || height <= 0) return;
  const std::size_t pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  scratch.extras.clear();
  if (data.triangle_count() == 0) {
    scratch.pixel_tri.assign(pixel_count, no_triangle);
    scratch.pixel_t.assign(pixel_count, std::numeric_limits<float>::infinity());
    if (initial_solid) scratch.pixel_solid_t.assign(initial_solid, initial_solid + pixel_count);
    else scratch.pixel_solid_t.assign(pixel_count, std::numeric_limits<float>::infinity());
  } else {
    // Every pixel belongs to one tile, and each tile writes all three for each of its pixels.
    scratch.pixel_tri.resize(pixel_count);
    scratch.pixel_t.resize(pixel_count);
    scratch.pixel_solid_t.resize(pixel_count);
    ViewSetup frame = make_frame(data, camera);
    frame.box_rect = scene_box_rect(data, frame);
    frame.initial_depth = initial_depth;
    frame.initial_solid = initial_solid;
    frame.cast_frame = cast_frame(data, frame);
    frame.cast_crowded_tiles = !frame.cast_frame && data.bvh.root != TriangleBvhNode::empty &&
                               data.params.crowded_path == NciCrowdedPath::automatic;
    const int tile = frame.tile = tile_edge(data, width, height);
    context.stats.axis = frame.axis;
    const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    const std::size_t tile_count = static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y);
    const unsigned count = detail::resolve_threads(data.params.threads, std::min<std::size_t>(tile_count, 1024));
    prepare_workers(data, scratch, count);
    context.tile_tested.assign(tile_count, 0u);
    context.tiles_x = tiles_x;
    context.tile_size = tile;
    run_tiles(data, frame, context, scratch, count, tiles_x, tile_count);
    merge_workers(data, context, scratch, count, out);
  }
  if (pixels) write_pixels(data, scratch, pixel_count, *pixels);
}

#endif

}  // namespace cullkit::detail::nci
