// cullkit/detail/nci/context.hpp: NciContext, the caller's reusable scratch for
// NormalClassIndex::select_visible, and the per-worker records the selection keeps in it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "frame_cast.hpp"
#include "tile_state.hpp"
#include "../../nci_params.hpp"

namespace cullkit {
class NciContext;
}

namespace cullkit::detail::nci {

// A triangle selected at a pixel beside its first hit (edge bands), and its depth there.
struct Extra {
  std::uint32_t tri;
  float t;
  std::uint32_t pixel;
};

// A triangle's pixel rectangle (inclusive); x0 > x1: none; x0 == full: every pixel.
struct Rect {
  static constexpr std::int16_t full = -32768;
  std::int16_t x0, y0, x1, y1;
};

// A hit or near miss within rounding of an edge (detail::watertight_hit_band) in the current
// tile: reported when nearer than its pixel's solid hit (see TileState::solid_t).
struct EdgeBandHit {
  std::uint32_t tri;
  float t;
  std::uint16_t pixel;
};

// A triangle of the current slice that passed the tile's cheap rejections; tested nearest first.
struct Candidate {
  float key;  // smallest depth of a corner along the tile's mean ray
  std::uint32_t tri;
  std::int8_t rx0, ry0, rx1, ry1;  // the tile pixels under its rectangle
};

// One worker's scratch: what a task of select_visible reads and writes besides the index.
struct Worker {
  // Per triangle, one 16-byte record (one cache line touch per triangle met by a tile): the
  // last tile that looked at it, the frame of its cached rectangle, and that rectangle.
  struct Tri {
    std::uint32_t stamp;
    std::uint32_t epoch;
    Rect rect;
  };
  std::vector<Tri> tri;
  // Per chunk of cell entries (crowded indexes only): the frame of its cached rectangle and it.
  struct Chunk {
    std::uint32_t epoch;
    Rect rect;
  };
  std::vector<Chunk> chunk;
  std::uint32_t stamp_value = 0;
  std::uint32_t frame_epoch = 0;
  // Bit sets over the internal triangle ids, cleared by their worker at the start of a call: the
  // triangles it tested and the ones it selected (pixel winners and edge-band extras). The merge
  // ORs them: no serial pass over the pixels, no sort.
  std::vector<std::uint64_t> tested_bits, shown_bits;
  // One bit per 64 words of tested_bits and shown_bits, set with any bit of those words, so that
  // the merge reads only the words a frame wrote instead of all of them (their count grows with
  // the index, the written ones with the frame).
  std::vector<std::uint64_t> touched;
  void mark_tested(std::uint32_t t) noexcept {
    tested_bits[t / 64] |= std::uint64_t{1} << (t % 64);
    touched[t / 4096] |= std::uint64_t{1} << (t / 64 % 64);
  }
  void mark_shown(std::uint32_t t) noexcept {
    shown_bits[t / 64] |= std::uint64_t{1} << (t % 64);
    touched[t / 4096] |= std::uint64_t{1} << (t / 64 % 64);
  }
  std::uint32_t tested_count = 0;  // ray-tested (triangle, tile) pairs so far in this call
  std::vector<EdgeBandHit> edge_hits;
  std::vector<Extra> extra;  // selected beside the pixels' first hits (edge hits, solid)
  std::vector<Candidate> candidates;
  // With per-slot corners in leaf order: the triangles a tile met in the slice being walked, as
  // (leaf position << 32 | internal id), admitted in position order (slice_walk.hpp,
  // admit_met_in_leaf_order), with that pass's buckets and ordered ids.
  std::vector<std::uint64_t> met_in_slice;
  std::vector<std::uint32_t> met_bucket, met_order;
  // Triangles met in the slice being walked, those settled by their cached rectangle included, and
  // the most met in one slice so far: what the three lists above may need. Unlike their sizes it
  // does not depend on which tiles this worker walked before (the cached rectangles do), so
  // reserving it for every worker keeps a warm frame from allocating under any schedule.
  std::size_t met_in_slice_count = 0, met_in_slice_peak = 0;
  std::vector<std::uint16_t> active_classes;
  std::vector<TileState> tile_rays;  // empty or one: the worker's tile scratch
  std::vector<FrameSlot> frame_slots;  // the packets of a tile cast through the triangle hierarchy
  std::vector<std::uint8_t> class_on;  // per class: active in the tile being cast (frame_tile.hpp)
  NciSelectStats stats;
};

struct MovingScratch;

// NciContext's private part: per-worker records and the frame's per-pixel answer.
struct Scratch {
  std::vector<Worker> workers;
  std::vector<std::uint32_t> pixel_tri;  // internal ids per pixel
  std::vector<float> pixel_t;
  std::vector<float> pixel_solid_t;       // per pixel: the nearest hit outside every edge band
  std::vector<Extra> extras;              // the last call's Worker::extra, in the mesh's numbering
  std::vector<std::uint64_t> shown_mesh;  // the merge's selected set as a bit set over mesh ids
  std::vector<std::uint64_t> shown_mesh_touched;  // one bit per 64 words of shown_mesh that hold some
  std::unique_ptr<MovingScratch> objects;  // moving objects' scratch, made on first use
};

struct ContextAccess;

}  // namespace cullkit::detail::nci

namespace cullkit {

/// Reusable scratch for select_visible: keeps per-thread buffers between frames so a frame does
/// not allocate once the buffers have grown (every worker's lists grow to the largest any worker
/// needed, so the same views spread differently over the workers do not allocate either). One
/// context per concurrent caller; not thread-safe.
/// Size: 16 bytes per indexed triangle per worker thread (test stamps and cached screen
/// rectangles), about 320 KB of tile scratch per worker thread (made on first use), on crowded
/// indexes 12 bytes per 16 cell entries per worker thread (chunk rectangles), on meshes of unshared
/// triangles (such as foliage) about 16 bytes per triangle a tile meets in one slice of its walk
/// (the order they are admitted in) per worker thread, 2 bits per indexed
/// triangle per worker thread and 1 bit per mesh triangle for the merge, 12 bytes per pixel, and
/// 12 bytes per edge-band triangle selected beside a pixel's first hit (rare outside very narrow
/// views), kept by every worker.
class NciContext {
 public:
  NciSelectStats stats;  ///< statistics of the last call that used this context
  /// Triangles ray-tested per screen tile in the last call (row-major tiles of `tile_size`
  /// pixels; `tiles_x` tiles per row): the heat map of the method's work.
  std::vector<std::uint32_t> tile_tested;
  int tiles_x = 0;  ///< tiles per row of `tile_tested`
  int tile_size = 0;  ///< edge in pixels of the tiles of `tile_tested` (NciParams::tile_size, or its automatic choice)

 private:
  friend struct detail::nci::ContextAccess;
  detail::nci::Scratch scratch_;
};

}  // namespace cullkit

namespace cullkit::detail::nci {

struct ContextAccess {
  [[nodiscard]] static Scratch& scratch(NciContext& context) noexcept { return context.scratch_; }
};

// Moving objects' scratch: the objects' own selection and the per-pixel depths they leave.
struct MovingScratch {
  NciContext context;
  VisibleSet set;
  NciPixels pixels;
  std::vector<float> depth, solid;
  std::vector<std::uint32_t> triangle, object;
  struct Candidate {  // an object's triangle selected at a pixel, at depth t
    std::uint32_t object, triangle;
    float t;
    std::uint32_t pixel;
  };
  std::vector<Candidate> candidates;
};

}  // namespace cullkit::detail::nci
