// cullkit/normal_class_index.hpp: NormalClassIndex, pixel-driven near-to-far selection of the
// triangles a camera sees (seed: Wei, Wang, Wu, "Fast selecting visible surfaces in high
// precision", Journal of Software 17(10), 2006; DESIGN.md §8 gives the corrected algorithm).
//
// Preprocess: triangle normals are clustered on the unit sphere (spherical k-means, fixed seed);
// each class keeps its normal cone and three sparse grids over the scene box, one per axis
// (slices -> rows -> cells as sorted coordinates in flat arrays; only non-empty cells exist; a
// triangle is listed in every cell it really overlaps, by a separating-axis test on slightly
// inflated cells).
//
// Select: the grid whose axis the view looks along most is walked slice by slice outward from the
// eye (two walks when the eye is inside the scene box). The screen is cut into tiles; each tile
// keeps its unfinished pixels, finds the cells of the current slice inside the beam of those
// pixels' rays by binary search, skips classes whose cone faces away from every ray of the tile,
// and tests the cells' triangles against the rays with a watertight front-face test at pixel
// centres (each triangle once per tile). A pixel is finished once its nearest hit lies before the
// point where its ray enters the next slice; a tile is finished when all its pixels are.
// Per-triangle work in a tile is kept small: a triangle wholly outside one of the four planes of
// the tile's beam (made around the live pixels, its margin measured against their rays) is dropped
// with a few float products; the others are checked against their screen rectangle (computed once
// per frame). Those with live pixels under it are sorted nearest first (smallest corner depth
// along the tile's mean ray) and then ray-tested, unless every live ray under the rectangle
// already holds a hit strictly nearer than any t the ray test could return for the triangle (a
// bound from the corners along each ray's dominant axis), or the triangle lies beside the
// rectangle's four corner rays (outside the plane through the eye and one of its edges), or no
// live pixel centre lies in its projected triangle grown by a proven margin (footprint_mask):
// such a triangle is not tested; otherwise only the rays inside that footprint are. On crowded indexes (8 or more entries per cell on average) every 16
// consecutive cell entries have a box, and a tile skips a box outside its beam, off its live
// pixels, or behind their hits. The beam's extent and each ray's finishing slice are recomputed
// only when a ray finishes or improves its hit.
//
// Memory (memory_bytes()): vertices (12 bytes each, bitwise-equal positions merged), 3 vertex
// ids per kept triangle (2 bytes each with at most 65536 vertices, else 4), its mesh number (4
// bytes), a 16-bit class per mesh triangle, 2 bytes per cell entry (4 when some class has more
// than 65536 triangles), and per cell 2 bytes (entry range, relative to its class; 4 when some
// class has more than 65535 entries) + 6 bytes (column in each axis grid) + 4 bytes (its ids in
// the Y and Z grids, 16-bit each while every class has at most 65536 cells, else 8 bytes; the X
// grids list cells in id order and need none), plus 6 bytes per grid row, plus 24 bytes per 16
// cell entries on crowded indexes (chunk boxes).
// Internally triangles are renumbered class by class in the order of their first cell in the X
// grid, so the triangles of a cell (and their vertices and per-thread records) are mostly one run
// of consecutive memory; answers are always given in the mesh's numbering.
//
// Conservative by construction: every pixel's reported triangle is its true first hit under the
// watertight test (ties broken by the lower triangle index), so the visible set contains the first
// hit of every pixel centre. Rounding is absorbed by inflating cells and slice bounds.
//
// Hit rule (what "first hit" means here): the ray of the pixel centre (PixelRays), the watertight
// test in float on corners taken relative to the eye, front faces only, and the eye strictly on
// the front side of the triangle's plane in double (a triangle seen exactly edge-on is never hit).
// Known limit: a triangle whose plane passes within float rounding of the eye (the eye touching
// the surface: detail::touches_eye, within 2^-20 of its farthest corner's distance) gets noise from
// the float ray test, up to hits at depth about 0 on rays the exact geometry sends away from it. The
// index keeps such hits only where its exact rejections (class cones, beams, screen rectangles, edge
// planes) allow them, so there its answer may differ from a plain float ray caster's and may depend
// on the grid and tile size (never on the thread count). Elsewhere it equals the float test's.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>


#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "config.hpp"
#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif
#include "geometry/aabb.hpp"
#include "geometry/camera.hpp"
#include "task_runner.hpp"
#include "traits.hpp"
#include "detail/worker_pool.hpp"
#include "detail/nci_kmeans.hpp"
#include "detail/nci_overlap.hpp"
#include "detail/nci_watertight.hpp"

namespace cullkit {

/// Configuration of a NormalClassIndex. Every field has a usable default.
struct NciParams {
  /// Normal classes (k of the spherical k-means). More classes: tighter cones, so more classes are
  /// skipped per tile, but more grids to search. The seed measures 32, 128 and 512. Clamped to
  /// [1, 4096]; classes that end up empty are dropped.
  int classes = 32;
  /// Cells along the scene box's longest axis (cubic cells). Finer: fewer triangles met per tile
  /// (not fewer tested: the screen rectangles already keep the tests down), more memory, and more
  /// cells and slices to walk. Clamped to [1, 4096]. 32 (the default since session 5; 64 before):
  /// against 64, bench_nci at 2 threads on six scenes x two views x 640x480 and 1024x768, minimum of
  /// three alternating runs, the time ratio is 0.96 in geometric mean (0.85-1.07; sportsCar from
  /// outside at 640x480 is the one loss above 3 %), with 1-37 % less memory and the same precision
  /// within 0.06 (README, NormalClassIndex, round 7).
  int grid = 32;
  /// Worker threads for select_visible; 0: all hardware threads. Never changes the result. The
  /// threads come from the library's persistent pool (started on first use, never per call) or,
  /// with `task_runner`, from the caller's job system; 1 runs on the calling thread only.
  unsigned threads = 0;
  /// Worker threads for the build (per class); 0: all hardware threads. Never changes the index.
  unsigned build_threads = 0;
  /// Where select_visible's parallel work runs: `threads` tasks (0: as many as hardware threads,
  /// at most one per screen tile) handed to `task_runner.dispatch` when it is set, else to the
  /// library's pool. Each task owns one worker's scratch in the NciContext and pulls screen tiles
  /// from a shared counter, so the answer is the same however the tasks are run.
  TaskRunner task_runner{};
  /// Screen tile edge in pixels, clamped to [2, 64]; 0 (the default): 64 for screens of at least
  /// 640x480 pixels, 32 below. Each tile walks the slices on its own and pays the per-triangle work
  /// (cell entry visits, screen-rectangle tests) once, so bigger tiles amortize it over more pixels;
  /// the answer (per-pixel triangle and depth, selected set) does not depend on it, the count of
  /// ray-tested triangles does (bigger tiles test a few more). Measured on six scenes, both views,
  /// 2 threads, 2-core machine (README, NormalClassIndex, rounds 6 and 7):
  ///  * with the old grid of 64 cells, 32 against 16 was 4.5-15 % faster on one thread at 640x480;
  ///    64 against 32 was 0.97 (geometric mean of the time ratio) at 640x480 and 0.91 at 1024x768;
  ///  * with the grid of 32 cells, 64 against 32 at 640x480 is 0.95 (48: 0.955), one loss (fzk_haus
  ///    from outside, +8 %), and tests 0-12 % more triangles (fzk_haus 2.49 -> 2.78 tested per
  ///    visible triangle). Below 640x480 nothing was measured, so 32 stays there (more tiles to share
  ///    between threads). Many threads on a small screen may prefer smaller tiles than the default.
  int tile_size = 0;
  /// Seed of the k-means (sampling and re-seeding of empty classes). Same seed, same index.
  std::uint64_t seed = 0x6e63692d6b6dULL;
  /// Optional build progress report, called from the building thread with a fraction in [0, 1]
  /// (monotone, 1 at the end). `progress_user` is passed through. nullptr: no reports.
  void (*progress)(float fraction, void* user) = nullptr;
  /// Passed to `progress` unchanged.
  void* progress_user = nullptr;
};

/// The result of NormalClassIndex::select_visible.
struct VisibleSet {
  /// Sorted, unique triangle indices (the mesh's numbering): every pixel's first hit, and where a
  /// ray passes within float rounding of a triangle's edge also the triangles another correct
  /// float ray tracer could see there (see NormalClassIndex::select_visible).
  std::vector<std::uint32_t> triangles;
  std::size_t triangles_tested = 0;      ///< distinct triangles tested against at least one ray
};

/// Optional per-pixel output of select_visible: row-major from the top row, as the pixel rule.
struct NciPixels {
  static constexpr std::uint32_t miss = 0xFFFFFFFFu;
  int width = 0, height = 0;
  std::vector<std::uint32_t> triangle;  ///< first-hit triangle (mesh numbering) or `miss`
  std::vector<float> depth;             ///< ray parameter t along the unit pixel ray; +inf on a miss
};

/// Build statistics of a NormalClassIndex.
struct NciStats {
  std::size_t triangles_input = 0;       ///< index_count / 3
  std::size_t triangles_indexed = 0;     ///< triangles kept
  std::size_t skipped_out_of_range = 0;  ///< an index >= vertex_count (or negative)
  std::size_t skipped_non_finite = 0;    ///< a NaN or infinite coordinate
  std::size_t skipped_degenerate = 0;    ///< zero area (collinear or repeated corners)
  std::size_t classes = 0;               ///< non-empty normal classes
  std::size_t cells = 0;                 ///< non-empty (class, cell) pairs
  std::size_t cell_entries = 0;          ///< triangle references over all cells
  int dims[3] = {0, 0, 0};               ///< cells along x, y, z
  double cell_size = 0;                  ///< edge of a (cubic) cell
  double build_seconds = 0;              ///< wall time of the constructor
};

/// Per-call statistics of select_visible (filled into an NciContext).
struct NciSelectStats {
  std::size_t ray_tests = 0;       ///< ray/triangle tests performed
  std::size_t cells_visited = 0;   ///< cells whose triangles were looked at
  std::size_t slices_walked = 0;   ///< (tile, slice) steps
  /// (tile, triangle) pairs met: cell entries looked at by a tile, a triangle listed in several
  /// cells counted once per tile.
  std::size_t triangles_met = 0;
  /// Of those, the triangles inside the tile's beam whose screen rectangle holds no pixel centre
  /// at all: back faces, triangles seen edge-on, and small triangles lying between pixel centres.
  /// They are never ray-tested, but each costs a projection. When this is most of
  /// `triangles_met`, the view is sub-pixel dense (many triangles per pixel), where the method
  /// meets every front-facing triangle near the visible surface and casting one ray per pixel
  /// through a BVH does less work (README, NormalClassIndex: "When it pays and when it does not").
  std::size_t triangles_no_pixel = 0;
  int axis = 0;                    ///< grid axis walked
};

/// A moving object for NormalClassIndex::select_visible: an index of its triangles in its local
/// frame, a rigid transform (rotation and translation) to the world, and the id it is reported with.
template <class ObjectIndex>
struct NciMovingObject {
  const ObjectIndex* index = nullptr;  ///< not owned; must outlive the call
  glm::mat4 local_to_world{1.0f};      ///< rigid: rotation and translation only
  std::uint32_t object_id = 0;         ///< reported in NciObjectTriangle::object
};

/// A visible triangle of a moving object.
struct NciObjectTriangle {
  std::uint32_t object = 0;    ///< NciMovingObject::object_id
  std::uint32_t triangle = 0;  ///< index in that object's mesh
  friend bool operator<(const NciObjectTriangle& a, const NciObjectTriangle& b) noexcept {
    return a.object != b.object ? a.object < b.object : a.triangle < b.triangle;
  }
  friend bool operator==(const NciObjectTriangle& a, const NciObjectTriangle& b) noexcept {
    return a.object == b.object && a.triangle == b.triangle;
  }
};

namespace detail {
// Per-pixel state of one screen tile of NormalClassIndex::select_visible (about 320 KB: kept in
// NciContext, one per worker, made once and reused across calls; every field a tile reads is set
// by that tile first).
struct NciTileRays {
  // The largest tile edge (NciParams::tile_size is clamped to it; a multiple of 4, the make_beam
  // pre-test's width); pixel (x, y) of a tile is entry y * stride + x of every per-pixel array
  // (below 4096: Unsure::pixel is 16-bit, Cand's rectangle 8-bit), bit x of its row's mask.
  static constexpr int max_tile = 64;
  static constexpr int cap = max_tile * max_tile;
  // The current tile's row pitch: its width rounded up to 4 (rows packed: a tile smaller than
  // max_tile touches no more cache lines, nor fewer cache sets, than it needs).
  int stride = max_tile;
  static_assert(max_tile % 4 == 0 && max_tile <= 64, "row masks hold at most 64 pixels");
  // Entries per per-pixel array: cap plus a pad of 32, so that the arrays (whose sizes would all
  // be multiples of 4 KB) do not all start at the same offset within a page (the ray setup and the
  // finishing loop touch a dozen of them at one index: one L1 cache set otherwise).
  static constexpr int slots = cap + 32;
  // A tile row's pixel set: bit x is pixel x.
  using Mask = std::conditional_t<(max_tile > 32), std::uint64_t, std::uint32_t>;
  static constexpr int mask_bits = 8 * static_cast<int>(sizeof(Mask));
  // Lowest and highest set bit of a non-empty mask.
  [[nodiscard]] static int low_bit(Mask m) noexcept { return __builtin_ctzll(m); }
  [[nodiscard]] static int high_bit(Mask m) noexcept { return 63 - __builtin_clzll(m); }
  [[nodiscard]] static Mask bit(int x) noexcept { return Mask{1} << x; }
  // Columns x0..x1 (0 <= x0 <= x1 < max_tile): no shift by the mask's width.
  [[nodiscard]] static Mask columns(int x0, int x1) noexcept {
    return static_cast<Mask>(~Mask{0} >> (mask_bits - 1 - (x1 - x0))) << x0;
  }
  // The pixel rays' directions by component (PixelRays::directions, make_beam's 4-wide
  // pre-test); zero beyond the tile's width up to the next multiple of 4.
  alignas(16) float dx[slots];
  alignas(16) float dy[slots];
  alignas(16) float dz[slots];
  [[nodiscard]] glm::dvec3 direction(int i) const noexcept { return glm::dvec3(dx[i], dy[i], dz[i]); }
  detail::WatertightRay<float> wray[slots];
  float best_t[slots];
  std::uint32_t best[slots];
  // The nearest hit that no edge-rounding question hangs over (a hit within rounding of an edge
  // may be a miss for another float ray tracer, which then sees what lies behind): finishing and
  // the depth rejects use it, so the search goes on behind such hits up to a solid one.
  float solid_t[slots];
  std::uint32_t solid[slots];
  float slope_b[slots], slope_c[slots];
  float t_exit[slots];  // where the ray leaves the inflated scene box (rounded up): nothing beyond
  int finish[slots];    // the walk may stop this ray once it has processed this slice
  bool dirty[slots];    // solid_t changed since `finish` was computed
  bool any_dirty = true;  // some ray became dirty since the walk last looked
  int axis = 2;       // the frame's walk axis
  float dir_a[slots];   // dir[i][axis], read by the finishing test (no per-call component switch)
  double lo_a = 0.0;  // the grid's origin on the walk axis
  double inv_h = 1.0; // 1 / cell edge (finish_slice's first estimate only)
  bool flat[slots];
  // The tile's beam: four planes through the eye (unit normals, inside positive) holding every
  // live ray of the tile up to `beam_eps` (the largest measured violation plus rounding).
  float beam_n[4][3];
  float beam_eps = 0.0f;
  bool beam = false;
  int beam_box[4] = {-1, -1, -1, -1};  // live pixels' rectangle the beam was made for
  float mean_dir[3] = {0.0f, 0.0f, 0.0f};  // the live rays' mean direction (sort key of candidates)
  // Depth bound: per dominant axis k of the watertight test, the range of its scale sz = 1 / d[k]
  // over the tile's live rays (sz_lo > sz_hi: no ray has that axis). A ray's computed t is a
  // convex combination of sz times the corners' k coordinates, so it is at least the smallest
  // such product over the range's ends.
  float sz_lo[3], sz_hi[3];
};
}  // namespace detail

class NciContext;

/// Reusable scratch for select_visible: keeps per-thread buffers between frames so a frame does
/// not allocate once the buffers have grown. One context per concurrent caller; not thread-safe.
/// Size: 16 bytes per indexed triangle per worker thread (test stamps and cached screen
/// rectangles), about 320 KB of tile scratch per worker thread (made on first use), on crowded
/// indexes 12 bytes per 16 cell entries per worker thread (chunk rectangles), 2 bits per indexed
/// triangle per worker thread and 1 bit per mesh triangle for the merge, 12 bytes per pixel, and
/// 12 bytes per edge-band triangle selected beside a pixel's first hit (rare outside very narrow
/// views).
class NciContext {
 public:
  NciSelectStats stats;  ///< statistics of the last call that used this context
  /// Triangles ray-tested per screen tile in the last call (row-major tiles of `tile_size`
  /// pixels; `tiles_x` tiles per row): the heat map of the method's work.
  std::vector<std::uint32_t> tile_tested;
  int tiles_x = 0;  ///< tiles per row of `tile_tested`
  int tile_size = 0;  ///< edge in pixels of the tiles of `tile_tested` (NciParams::tile_size, or its automatic choice)

 private:
  template <class, class, class>
  friend class NormalClassIndex;
  struct Extra {  // a triangle selected at a pixel beside its first hit, and its depth there
    std::uint32_t tri;
    float t;
    std::uint32_t pixel;
  };
  struct Rect {  // a triangle's pixel rectangle (inclusive); x0 > x1: none; x0 == full: every pixel
    static constexpr std::int16_t full = -32768;
    std::int16_t x0, y0, x1, y1;
  };
  struct Thread {
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
    std::uint32_t tested_count = 0;  // ray-tested (triangle, tile) pairs so far in this call
    // Hits and near misses within rounding of an edge (detail::watertight_hit_band) in the current
    // tile: reported when nearer than their pixel's solid hit (see TileRays::solid_t).
    struct Unsure {
      std::uint32_t tri;
      float t;
      std::uint16_t pixel;
    };
    std::vector<Unsure> unsure;
    std::vector<Extra> extra;  // selected beside the pixels' first hits (unsure, solid)
    // Triangles of the current slice that passed the tile's cheap rejects, tested nearest first.
    struct Cand {
      float key;  // smallest depth of a corner along the tile's mean ray
      std::uint32_t tri;
      std::int8_t rx0, ry0, rx1, ry1;  // the tile pixels under its rectangle
    };
    std::vector<Cand> cand;
    std::vector<std::uint16_t> active_classes;
    std::vector<detail::NciTileRays> tile_rays;  // empty or one: the worker's tile scratch
    NciSelectStats stats;
  };
  std::vector<Thread> threads_;
  std::vector<std::uint32_t> pixel_tri_;  // internal ids per pixel
  std::vector<float> pixel_t_;
  std::vector<float> pixel_solid_t_;       // per pixel: the nearest hit outside every edge band
  std::vector<Extra> extras_;              // the last call's Thread::extra, in the mesh's numbering
  std::vector<std::uint64_t> shown_mesh_;  // the merge's selected set as a bit set over mesh ids
  struct Objects;
  std::unique_ptr<Objects> objects_;  // moving objects' scratch, made on first use
};

struct NciContext::Objects {
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

/// Index of a static triangle mesh that answers "which triangles does this camera see", with the
/// exact per-pixel answer (first hit of each pixel-centre ray, front faces only; a triangle within
/// float rounding of an edge keeps its pixel searching behind it, see select_visible).
///
/// Build cost: O(n log n) for n triangles plus the separating-axis tests of triangles spanning
/// cells; memory is reported by memory_bytes() (vertices, triangle corners, cell lists, grids).
/// The index copies what it needs: the mesh need not outlive it. Queries are const and may run
/// concurrently, each with its own NciContext.
template <class Vertex, class Index = std::uint32_t, class Traits = VertexTraits<Vertex>>
class NormalClassIndex {
  static_assert(require_vertex_traits<Vertex, Traits>::value, "");
  static_assert(std::is_integral_v<Index>, "cullkit: NormalClassIndex needs an integral Index type");

 public:
  /// Builds the index. Triangles with an out-of-range index, a non-finite coordinate or zero area
  /// are skipped and counted in stats(); an empty or all-invalid mesh gives an index that selects
  /// nothing. pre: mesh.vertices != nullptr when vertex_count > 0, mesh.indices likewise.
  explicit NormalClassIndex(MeshView<Vertex, Index> mesh, const NciParams& params = {}) : params_(params) {
    CULLKIT_ASSERT(mesh.vertices != nullptr || mesh.vertex_count == 0, "vertices present when vertex_count > 0");
    CULLKIT_ASSERT(mesh.indices != nullptr || mesh.index_count == 0, "indices present when index_count > 0");
    params_.classes = std::clamp(params_.classes, 1, 4096);
    params_.grid = std::clamp(params_.grid, 1, 4096);
    if (params_.tile_size != 0) params_.tile_size = std::clamp(params_.tile_size, 2, max_tile_);
    const auto t0 = std::chrono::steady_clock::now();
    build(mesh);
    stats_.build_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  /// The triangles that are the first front-facing surface hit by the ray of some pixel centre
  /// (pixel rule on Camera), sorted and unique, and how many distinct triangles were tested.
  /// Edge bands: where a pixel ray passes within float rounding of a triangle's edge (a few
  /// 2^-24 of the corners' distances from the eye; detail::watertight_hit_band), another float
  /// ray tracer such as Embree may decide that triangle the other way and see what lies behind.
  /// Such a triangle (hit or near miss) does not finish its pixel: the search goes on to the first
  /// hit outside every band, and the set holds that hit and every band triangle in front of it.
  /// So the set may be a little larger than the pixels' first hits (in ordinary views a few
  /// triangles in ten thousand; in views a few degrees wide from kilometres away up to +60%),
  /// never smaller. The per-pixel output stays the plain first hit of the watertight test.
  /// A camera with a non-positive width or height gives an empty set. Allocates a context.
  [[nodiscard]] VisibleSet select_visible(const Camera& camera) const {
    NciContext context;
    VisibleSet out;
    select_visible(camera, context, out, nullptr);
    return out;
  }

  /// The same, reusing `context` (no allocation once its buffers have grown), writing `out`, and
  /// when `pixels` is not null also the per-pixel first-hit triangle and depth. The result never
  /// depends on NciParams::threads. Cost: proportional to the rays times the triangles met near
  /// the visible surfaces, divided over the threads.
  void select_visible(const Camera& camera, NciContext& context, VisibleSet& out, NciPixels* pixels) const {
    select_impl(camera, context, out, pixels, nullptr, nullptr);
  }

  /// With moving objects (DESIGN.md §8): each object has its own index, built in its local frame,
  /// and a rigid `local_to_world` transform (rotation and translation only: ray parameters t stay
  /// the same in both frames). The objects are selected first, each with the camera taken into its
  /// local frame; then the static scene, whose pixels stay unfinished but start from the objects'
  /// depths, so only static triangles in front of the objects are searched. `out` holds the static
  /// triangles; `object_triangles` (cleared first) the objects' visible triangles as sorted unique
  /// (object id, triangle) pairs. `pixels`, when given, holds static triangle ids, or for a pixel
  /// won by an object NciPixels::miss with the object's depth (see `object_pixels`). Edge bands
  /// (see above) span objects and scene: an object's triangle is reported where it lies no farther
  /// than its pixel's first hit outside every band, whichever mesh that hit belongs to.
  /// pre: every `objects[k].index` is not null. Allocates a second context inside `context`.
  template <class ObjectIndex>
  void select_visible(const Camera& camera, const NciMovingObject<ObjectIndex>* objects, std::size_t object_count,
                      NciContext& context, VisibleSet& out, std::vector<NciObjectTriangle>& object_triangles,
                      NciPixels* pixels = nullptr) const {
    object_triangles.clear();
    const int width = camera.width, height = camera.height;
    if (width <= 0 || height <= 0 || object_count == 0) {
      select_impl(camera, context, out, pixels, nullptr, nullptr);
      return;
    }
    const std::size_t pixel_count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    if (!context.objects_) context.objects_ = std::make_unique<NciContext::Objects>();
    auto& o = *context.objects_;
    o.depth.assign(pixel_count, std::numeric_limits<float>::infinity());
    o.solid.assign(pixel_count, std::numeric_limits<float>::infinity());
    o.candidates.clear();
    o.triangle.assign(pixel_count, NciPixels::miss);
    o.object.assign(pixel_count, NciPixels::miss);
    for (std::size_t k = 0; k < object_count; ++k) {
      CULLKIT_ASSERT(objects[k].index != nullptr, "every moving object has an index");
      if (!objects[k].index) continue;
      const glm::dmat4 m(objects[k].local_to_world);
      Camera local = camera;
      local.eye = glm::vec3(glm::inverse(m) * glm::dvec4(glm::dvec3(camera.eye), 1.0));
      local.view_proj = glm::mat4(glm::dmat4(camera.view_proj) * m);
      objects[k].index->select_visible(local, o.context, o.set, &o.pixels);
      const std::uint32_t id = objects[k].object_id;
      const auto& solid = o.context.pixel_solid_t_;
      for (std::size_t p = 0; p < pixel_count; ++p) {
        if (solid.size() == pixel_count) o.solid[p] = std::min(o.solid[p], solid[p]);
        const std::uint32_t tri = o.pixels.triangle[p];
        if (tri == NciPixels::miss) continue;
        if (o.pixels.depth[p] <= o.solid[p])
          o.candidates.push_back(NciContext::Objects::Candidate{id, tri, o.pixels.depth[p], static_cast<std::uint32_t>(p)});
        if (o.pixels.depth[p] < o.depth[p]) {
          o.depth[p] = o.pixels.depth[p];
          o.triangle[p] = tri;
          o.object[p] = id;
        }
      }
      // The object's triangles beside its pixels' first hits (edge bands; see select_visible).
      for (const auto& e : o.context.extras_)
        if (e.t <= o.solid[e.pixel]) o.candidates.push_back(NciContext::Objects::Candidate{id, e.tri, e.t, e.pixel});
    }
    select_impl(camera, context, out, pixels, o.depth.data(), o.solid.data());
    // An object's triangle is reported where it lies no farther than the pixel's solid depth after
    // the static scene (then nothing certain hides it); the pixels keep the objects' first hits
    // where no static triangle came in front.
    const auto& solid = context.pixel_solid_t_;
    for (const auto& c : o.candidates)
      if (solid.size() == pixel_count && c.t <= solid[c.pixel]) object_triangles.push_back(NciObjectTriangle{c.object, c.triangle});
    for (std::size_t p = 0; p < pixel_count; ++p) {
      if (o.object[p] == NciPixels::miss) continue;
      if (context.pixel_tri_.size() == pixel_count && context.pixel_tri_[p] != none_) continue;
      if (pixels && pixels->depth.size() == pixel_count) pixels->depth[p] = o.depth[p];
    }
    std::sort(object_triangles.begin(), object_triangles.end());
    object_triangles.erase(std::unique(object_triangles.begin(), object_triangles.end()), object_triangles.end());
  }

 private:
  void select_impl(const Camera& camera, NciContext& context, VisibleSet& out, NciPixels* pixels,
                   const float* initial_depth, const float* initial_solid) const {
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
    context.extras_.clear();
    if (triangle_count() == 0) {
      context.pixel_tri_.assign(pixel_count, none_);
      context.pixel_t_.assign(pixel_count, std::numeric_limits<float>::infinity());
      if (initial_solid) context.pixel_solid_t_.assign(initial_solid, initial_solid + pixel_count);
      else context.pixel_solid_t_.assign(pixel_count, std::numeric_limits<float>::infinity());
    } else {
      // Every pixel belongs to one tile, and each tile writes all three for each of its pixels.
      context.pixel_tri_.resize(pixel_count);
      context.pixel_t_.resize(pixel_count);
      context.pixel_solid_t_.resize(pixel_count);
    }
    if (triangle_count() > 0) {
      Frame frame = make_frame(camera);
      {
        // The box grown by delta_ (as the per-ray box test), rounded outward to float.
        const glm::dvec3 lo = glm::dvec3(box_.min) - delta_, hi = glm::dvec3(box_.max) + delta_;
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
        frame.box_rect = project_rect(frame, corner, 8);
      }
      frame.initial_depth = initial_depth;
      frame.initial_solid = initial_solid;
      const int tile = frame.tile = tile_edge(width, height);
      context.stats.axis = frame.axis;
      const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
      const std::size_t tile_count = static_cast<std::size_t>(tiles_x) * static_cast<std::size_t>(tiles_y);
      const unsigned thread_count = detail::resolve_threads(params_.threads, std::min<std::size_t>(tile_count, 1024));
      if (context.threads_.size() < thread_count) context.threads_.resize(thread_count);
      for (unsigned i = 0; i < thread_count; ++i) {
        auto& th = context.threads_[i];
        if (th.tri.size() != triangle_count()) {
          th.tri.assign(triangle_count(), NciContext::Thread::Tri{0u, 0u, NciContext::Rect{0, 0, -1, -1}});
          th.stamp_value = 0;
          th.frame_epoch = 0;
        }
        if (th.chunk.size() != chunk_box_.size() / 6) {
          th.chunk.assign(chunk_box_.size() / 6, NciContext::Thread::Chunk{0u, NciContext::Rect{0, 0, -1, -1}});
          th.frame_epoch = 0;
          for (auto& t : th.tri) t.epoch = 0u;
        }
        if (++th.frame_epoch == 0) {
          for (auto& t : th.tri) t.epoch = 0u;
          for (auto& c : th.chunk) c.epoch = 0u;
          th.frame_epoch = 1;
        }
        th.tested_count = 0;
        th.extra.clear();
        th.unsure.clear();
        th.stats = NciSelectStats{};
      }
      context.tile_tested.assign(tile_count, 0u);
      context.tiles_x = tiles_x;
      context.tile_size = tile;
      std::atomic<std::size_t> next{0};
      auto work = [&](unsigned index) {
        auto& th = context.threads_[index];
        // Per-tile ray scratch (about 320 KB), made once per worker slot of the context and reused
        // across calls (not per tile, not on the stack); process_tile sets every field it reads.
        if (th.tile_rays.empty()) th.tile_rays.resize(1);
        TileRays& rays = th.tile_rays.front();
        const std::size_t words = (triangle_count() + 63) / 64;
        th.tested_bits.assign(words, 0u);
        th.shown_bits.assign(words, 0u);
        for (;;) {
          const std::size_t t = next.fetch_add(1, std::memory_order_relaxed);
          if (t >= tile_count) break;
          const int tx = static_cast<int>(t % static_cast<std::size_t>(tiles_x));
          const int ty = static_cast<int>(t / static_cast<std::size_t>(tiles_x));
          const std::uint32_t before = th.tested_count;
          process_tile(frame, tx * tile, ty * tile, std::min(width, (tx + 1) * tile),
                       std::min(height, (ty + 1) * tile), rays, th, context);
          context.tile_tested[t] = th.tested_count - before;
        }
      };
      using Work = decltype(work);
      detail::run_tasks(params_.task_runner, thread_count,
                        [](void* job, std::size_t task) { (*static_cast<Work*>(job))(static_cast<unsigned>(task)); }, &work);
      // Merge: distinct tested triangles (the union of the workers' bit sets) and the visible set
      // (pixel winners and edge-band extras), sorted by mesh id through a bit set over the mesh.
      for (unsigned i = 0; i < thread_count; ++i) {
        const auto& th = context.threads_[i];
        context.stats.ray_tests += th.stats.ray_tests;
        context.stats.cells_visited += th.stats.cells_visited;
        context.stats.slices_walked += th.stats.slices_walked;
        context.stats.triangles_met += th.stats.triangles_met;
        context.stats.triangles_no_pixel += th.stats.triangles_no_pixel;
        for (const auto& e : th.extra) context.extras_.push_back(NciContext::Extra{original(e.tri), e.t, e.pixel});
      }
      {
        // Every worker's lists grow to what any worker needed (the extras to this call's total), so
        // a later frame that spreads the same tiles over the workers differently does not allocate.
        std::size_t cand = 0, unsure = 0;
        for (unsigned i = 0; i < thread_count; ++i) {
          cand = std::max(cand, context.threads_[i].cand.capacity());
          unsure = std::max(unsure, context.threads_[i].unsure.capacity());
        }
        for (unsigned i = 0; i < thread_count; ++i) {
          auto& th = context.threads_[i];
          th.cand.reserve(cand);
          th.unsure.reserve(unsure);
          th.extra.reserve(context.extras_.size());
          th.active_classes.reserve(class_axis_.size());
        }
      }
      auto& mesh_bits = context.shown_mesh_;
      mesh_bits.assign((stats_.triangles_input + 63) / 64, 0u);
      const std::size_t words = (triangle_count() + 63) / 64;
      for (std::size_t w = 0; w < words; ++w) {
        std::uint64_t tested = 0, shown = 0;
        for (unsigned i = 0; i < thread_count; ++i) {
          tested |= context.threads_[i].tested_bits[w];
          shown |= context.threads_[i].shown_bits[w];
        }
        out.triangles_tested += static_cast<std::size_t>(__builtin_popcountll(tested));
        while (shown) {
          const std::uint32_t m = original(static_cast<std::uint32_t>(64 * w) + static_cast<std::uint32_t>(__builtin_ctzll(shown)));
          shown &= shown - 1;
          mesh_bits[m / 64] |= std::uint64_t{1} << (m % 64);
        }
      }
      for (std::size_t w = 0; w < mesh_bits.size(); ++w) {
        for (std::uint64_t bits = mesh_bits[w]; bits; bits &= bits - 1)
          out.triangles.push_back(static_cast<std::uint32_t>(64 * w) + static_cast<std::uint32_t>(__builtin_ctzll(bits)));
      }
    }
    if (pixels) {
      pixels->triangle.resize(pixel_count);
      pixels->depth.resize(pixel_count);
      for (std::size_t i = 0; i < pixel_count; ++i) {
        const std::uint32_t tri = context.pixel_tri_[i];
        pixels->triangle[i] = tri == none_ ? NciPixels::miss : original(tri);
        pixels->depth[i] = tri == none_ ? std::numeric_limits<float>::infinity() : context.pixel_t_[i];
      }
    }
  }


 public:
  /// Build statistics (skipped triangles, classes, cells, build time).
  [[nodiscard]] const NciStats& stats() const noexcept { return stats_; }
  /// Bytes held by the index (capacity of every array).
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return sizeof(*this) + bytes(vertices_) + bytes(tri_vertices_) + bytes(tri_vertices16_) + bytes(cell_begin16_) + bytes(class_entry_base_) + bytes(tri_original_) + bytes(class_axis_) +
           bytes(class_sin_) + bytes(class_cos_) + bytes(cell_tri_begin_) + bytes(cell_tris_) + bytes(cell_tris16_) + bytes(chunk_box_) +
           bytes(class_tri_begin_) + bytes(grid_base_) +
           bytes(slice_rows_) + bytes(row_coord_) + bytes(row_begin_) + bytes(cell_col_) + bytes(cell_id_) + bytes(cell_id16_) +
           bytes(grid_shift_) + bytes(class_cell_base_) +
           bytes(class_of_);
  }
  /// Triangles kept by the build.
  [[nodiscard]] std::size_t triangle_count() const noexcept { return stats_.triangles_indexed; }
  /// Normal class of a kept triangle, by the mesh's numbering; -1 for a skipped triangle.
  [[nodiscard]] int triangle_class(std::uint32_t mesh_triangle) const noexcept {
    if (mesh_triangle >= class_of_.size() || class_of_[mesh_triangle] == skipped_class_) return -1;
    return static_cast<int>(class_of_[mesh_triangle]);
  }
  /// Number of (non-empty) normal classes.
  [[nodiscard]] std::size_t class_count() const noexcept { return class_axis_.size(); }
  /// The parameters in use (after clamping).
  [[nodiscard]] const NciParams& params() const noexcept { return params_; }
  /// The scene box (of the kept triangles); Aabb::empty() when nothing was kept.
  [[nodiscard]] Aabb bounds() const noexcept { return box_; }

 private:
  static constexpr std::uint32_t none_ = 0xFFFFFFFFu;

  static constexpr std::uint16_t skipped_class_ = 0xFFFFu;

  [[nodiscard]] std::uint32_t original(std::uint32_t tri) const noexcept { return tri_original_[tri]; }
  // Corner k of internal triangle tri.
  [[nodiscard]] const glm::vec3& corner(std::uint32_t tri, int k) const noexcept {
    const std::size_t i = 3 * std::size_t{tri} + static_cast<std::size_t>(k);
    return vertices_[tri_vertices_.empty() ? tri_vertices16_[i] : tri_vertices_[i]];
  }

  template <class T>
  static std::size_t bytes(const std::vector<T>& v) noexcept {
    return v.capacity() * sizeof(T);
  }

  // ---------------------------------------------------------------- build
  void report(float f) const {
    if (params_.progress) params_.progress(f, params_.progress_user);
  }

  void build(const MeshView<Vertex, Index>& mesh) {
    stats_.triangles_input = mesh.triangle_count();
    report(0.0f);
    // 1. Valid triangles, their vertices (deduplicated through a remap) and normals.
    std::vector<std::uint32_t> remap;
    std::vector<glm::vec3> normals;
    for (std::size_t t = 0; t < stats_.triangles_input; ++t) {
      std::size_t idx[3];
      bool in_range = true;
      for (int k = 0; k < 3; ++k) {
        const auto i = mesh.indices[3 * t + static_cast<std::size_t>(k)];
        if constexpr (std::is_signed_v<Index>) {
          if (i < 0) in_range = false;
        }
        idx[k] = static_cast<std::size_t>(i);
        if (!in_range || idx[k] >= mesh.vertex_count) in_range = false;
      }
      if (!in_range) {
        ++stats_.skipped_out_of_range;
        continue;
      }
      glm::vec3 p[3];
      bool finite = true;
      for (int k = 0; k < 3; ++k) {
        p[k] = glm::vec3(Traits::position(mesh.vertices[idx[k]]));
        finite = finite && std::isfinite(p[k].x) && std::isfinite(p[k].y) && std::isfinite(p[k].z);
      }
      if (!finite) {
        ++stats_.skipped_non_finite;
        continue;
      }
      const glm::dvec3 e1 = glm::dvec3(p[1]) - glm::dvec3(p[0]);
      const glm::dvec3 e2 = glm::dvec3(p[2]) - glm::dvec3(p[0]);
      const glm::dvec3 n = glm::cross(e1, e2);
      const double len = glm::length(n);
      if (!(len > 0.0) || !std::isfinite(len)) {
        ++stats_.skipped_degenerate;
        continue;
      }
      if (remap.empty()) remap.assign(mesh.vertex_count, none_);
      for (int k = 0; k < 3; ++k) {
        std::uint32_t& r = remap[idx[k]];
        if (r == none_) {
          r = static_cast<std::uint32_t>(vertices_.size());
          vertices_.push_back(p[k]);
        }
        tri_vertices_.push_back(r);
      }
      tri_original_.push_back(static_cast<std::uint32_t>(t));
      normals.push_back(glm::vec3(n / len));
      box_ = merge(box_, p[0]);
      box_ = merge(box_, p[1]);
      box_ = merge(box_, p[2]);
    }
    remap.clear();
    remap.shrink_to_fit();
    stats_.triangles_indexed = tri_original_.size();
    const std::size_t n = tri_original_.size();
    report(0.1f);
    if (n == 0) {
      class_of_.assign(stats_.triangles_input, skipped_class_);
      report(1.0f);
      return;
    }

    // 2. The grid: cubic cells, `grid` along the longest axis.
    const glm::dvec3 lo(box_.min), hi(box_.max);
    const glm::dvec3 ext = hi - lo;
    const double longest = std::max({ext.x, ext.y, ext.z});
    h_ = longest > 0 ? longest / params_.grid : 1.0;
    for (int a = 0; a < 3; ++a) {
      int d = std::max(1, static_cast<int>(std::ceil(ext[a] / h_)));
      while (lo[a] + d * h_ < hi[a]) ++d;
      dims_[a] = std::min(d, 65535);
      stats_.dims[a] = dims_[a];
    }
    stats_.cell_size = h_;
    lo_ = lo;
    const double max_abs = std::max({std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x),
                                     std::fabs(hi.y), std::fabs(hi.z)});
    delta_ = std::max(1e-3 * h_, 64.0 * double(std::numeric_limits<float>::epsilon()) * max_abs);

    // 3. Normal classes.
    std::vector<std::uint16_t> class_of;  // kept triangle (input order) -> class
    {
      std::vector<std::uint32_t> cls;
      detail::cluster_normals(normals, params_.classes, params_.seed, cls, class_axis_);
      class_of.assign(cls.begin(), cls.end());  // at most 4096 classes: 16 bits
    }
    const std::size_t classes = class_axis_.size();
    stats_.classes = classes;
    {
      // Recompute each axis as the mean of its members and measure the cone around it.
      std::vector<glm::dvec3> sum(classes, glm::dvec3(0.0));
      for (std::size_t i = 0; i < n; ++i) sum[class_of[i]] += glm::dvec3(normals[i]);
      for (std::size_t c = 0; c < classes; ++c) {
        const double len = glm::length(sum[c]);
        if (len > 1e-9) class_axis_[c] = glm::vec3(sum[c] / len);
      }
      std::vector<double> min_dot(classes, 1.0);
      for (std::size_t i = 0; i < n; ++i) {
        const double d = glm::dot(glm::dvec3(normals[i]), glm::dvec3(class_axis_[class_of[i]]));
        min_dot[class_of[i]] = std::min(min_dot[class_of[i]], d);
      }
      class_sin_.resize(classes);
      class_cos_.resize(classes);
      for (std::size_t c = 0; c < classes; ++c) {
        // Half-angle plus a margin for the float normals and the float ray test.
        const double angle = std::acos(std::clamp(min_dot[c], -1.0, 1.0)) + 2e-3;
        if (angle >= 1.5707963267948966) {
          class_sin_[c] = 2.0f;  // never skipped
          class_cos_[c] = 0.0f;
        } else {
          class_sin_[c] = static_cast<float>(std::sin(angle));
          class_cos_[c] = static_cast<float>(std::cos(angle));
        }
      }
    }
    normals.clear();
    normals.shrink_to_fit();
    report(0.2f);

    // 4. Per class: cells by separating axes, then the three grids. Classes in parallel, merged in
    // class order so the index does not depend on the thread count.
    std::vector<std::uint32_t> class_begin(classes + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++class_begin[class_of[i] + 1];
    for (std::size_t c = 0; c < classes; ++c) class_begin[c + 1] += class_begin[c];
    std::vector<std::uint32_t> by_class(n);
    {
      std::vector<std::uint32_t> fill(class_begin.begin(), class_begin.end() - 1);
      for (std::size_t i = 0; i < n; ++i) by_class[fill[class_of[i]]++] = static_cast<std::uint32_t>(i);
    }
    std::vector<ClassGrids> parts(classes);
    std::atomic<std::size_t> next{0}, done{0};
    const unsigned build_threads = detail::resolve_threads(params_.build_threads, std::min<std::size_t>(classes, 64));
    // Task 0 runs on the building thread (WorkerPool::run): the one that reports progress.
    auto work = [&](bool reporter) {
      for (;;) {
        const std::size_t c = next.fetch_add(1, std::memory_order_relaxed);
        if (c >= classes) break;
        build_class(by_class.data() + class_begin[c], class_begin[c + 1] - class_begin[c], parts[c]);
        const std::size_t d = done.fetch_add(1) + 1;
        if (reporter) report(0.2f + 0.7f * static_cast<float>(d) / static_cast<float>(classes));
      }
    };
    using Work = decltype(work);
    detail::WorkerPool::shared().run(build_threads, [](void* job, std::size_t task) { (*static_cast<Work*>(job))(task == 0); },
                                     &work);

    // 4b. Internal numbering (memory locality of the select walk): class by class, each class's
    // triangles in the order their first cell comes in its X grid, so a cell's triangles are
    // mostly one run of consecutive ids (and so are their vertices and per-thread records).
    // tri_original_ maps back to the mesh; cell lists are rewritten and sorted in the new ids.
    {
      std::vector<std::uint32_t> new_id(n, none_), order;
      order.reserve(n);
      class_tri_begin_.assign(classes + 1, 0u);
      for (std::size_t c = 0; c < classes; ++c) {
        class_tri_begin_[c] = static_cast<std::uint32_t>(order.size());
        for (std::uint32_t old : parts[c].cell_tris) {
          if (new_id[old] == none_) {
            new_id[old] = static_cast<std::uint32_t>(order.size());
            order.push_back(old);
          }
        }
        for (std::uint32_t k = class_begin[c]; k < class_begin[c + 1]; ++k) {  // in no cell (never met)
          if (new_id[by_class[k]] == none_) {
            new_id[by_class[k]] = static_cast<std::uint32_t>(order.size());
            order.push_back(by_class[k]);
          }
        }
        auto& p = parts[c];
        for (auto& e : p.cell_tris) e = new_id[e];
        for (std::size_t k = 0; k + 1 < p.cell_tri_begin.size(); ++k)
          std::sort(p.cell_tris.begin() + p.cell_tri_begin[k], p.cell_tris.begin() + p.cell_tri_begin[k + 1]);
      }
      class_tri_begin_[classes] = static_cast<std::uint32_t>(n);
      // Triangles, their mesh numbers and vertices in the new order; vertices renumbered by first
      // use and merged when their positions are bitwise equal (OBJ files often repeat a position
      // per normal or texture coordinate).
      std::vector<std::uint32_t> canon(vertices_.size());
      {
        struct Key {
          std::uint32_t bits[3];
          std::uint32_t id;
        };
        std::vector<Key> keys(vertices_.size());
        for (std::size_t v = 0; v < vertices_.size(); ++v) {
          std::memcpy(keys[v].bits, &vertices_[v], sizeof keys[v].bits);
          keys[v].id = static_cast<std::uint32_t>(v);
        }
        std::sort(keys.begin(), keys.end(), [](const Key& x, const Key& y) {
          if (x.bits[0] != y.bits[0]) return x.bits[0] < y.bits[0];
          if (x.bits[1] != y.bits[1]) return x.bits[1] < y.bits[1];
          if (x.bits[2] != y.bits[2]) return x.bits[2] < y.bits[2];
          return x.id < y.id;
        });
        for (std::size_t v = 0; v < keys.size(); ++v) {
          const bool same = v > 0 && std::memcmp(keys[v].bits, keys[v - 1].bits, sizeof keys[v].bits) == 0;
          canon[keys[v].id] = same ? canon[keys[v - 1].id] : keys[v].id;
        }
      }
      std::vector<std::uint32_t> vmap(vertices_.size(), none_);
      std::vector<glm::vec3> vertices;
      std::vector<std::uint32_t> tri_vertices(3 * n), tri_original(n);
      for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t old = order[k];
        tri_original[k] = tri_original_[old];
        for (std::size_t j = 0; j < 3; ++j) {
          const std::uint32_t v = canon[tri_vertices_[3 * old + j]];
          if (vmap[v] == none_) {
            vmap[v] = static_cast<std::uint32_t>(vertices.size());
            vertices.push_back(vertices_[v]);
          }
          tri_vertices[3 * k + j] = vmap[v];
        }
      }
      class_of_.assign(stats_.triangles_input, skipped_class_);
      for (std::size_t i = 0; i < n; ++i) class_of_[tri_original_[i]] = class_of[i];
      vertices_ = std::move(vertices);
      tri_vertices_ = std::move(tri_vertices);
      tri_original_ = std::move(tri_original);
      wide_tris_ = false;
      for (std::size_t c = 0; c < classes; ++c) wide_tris_ = wide_tris_ || class_tri_begin_[c + 1] - class_tri_begin_[c] > 65536;
    }

    // 5. Merge into flat arrays.
    std::size_t total_cells = 0, total_entries = 0, total_rows = 0, total_grid_cells = 0, total_slices = 0;
    wide_ids_ = false;
    for (const auto& p : parts) {
      total_cells += p.cell_tri_begin.size() - 1;
      wide_ids_ = wide_ids_ || p.cell_tri_begin.size() - 1 > 65536;
      total_entries += p.cell_tris.size();
      for (int a = 0; a < 3; ++a) {
        total_rows += p.row_coord[a].size();
        total_grid_cells += p.cell_col[a].size();
        total_slices += p.slice_rows[a].size();
      }
    }
    stats_.cells = total_cells;
    stats_.cell_entries = total_entries;
    cell_tri_begin_.reserve(total_cells + 1);
    if (wide_tris_) cell_tris_.reserve(total_entries);
    else cell_tris16_.reserve(total_entries);
    slice_rows_.reserve(total_slices);
    row_coord_.reserve(total_rows);
    row_begin_.reserve(total_rows + 1);
    cell_col_.reserve(total_grid_cells);
    if (wide_ids_) cell_id_.reserve(total_grid_cells - total_cells);
    else cell_id16_.reserve(total_grid_cells - total_cells);
    class_cell_base_.reserve(classes);
    grid_base_.reserve(classes * 3);
    grid_shift_.reserve(classes * 3);
    cell_tri_begin_.push_back(0);
    std::vector<std::uint32_t> class_entry_end;  // per class: one past its last cell entry
    class_entry_end.reserve(classes);
    for (std::size_t c = 0; c < classes; ++c) {
      auto& p = parts[c];
      const std::uint32_t cell_base = static_cast<std::uint32_t>(cell_tri_begin_.size() - 1);
      class_cell_base_.push_back(wide_ids_ ? 0u : cell_base);
      const std::uint32_t entry_base = static_cast<std::uint32_t>(wide_tris_ ? cell_tris_.size() : cell_tris16_.size());
      for (std::size_t k = 1; k < p.cell_tri_begin.size(); ++k) cell_tri_begin_.push_back(entry_base + p.cell_tri_begin[k]);
      if (wide_tris_) {
        cell_tris_.insert(cell_tris_.end(), p.cell_tris.begin(), p.cell_tris.end());
      } else {
        for (std::uint32_t t : p.cell_tris) cell_tris16_.push_back(static_cast<std::uint16_t>(t - class_tri_begin_[c]));
      }
      class_entry_end.push_back(static_cast<std::uint32_t>(wide_tris_ ? cell_tris_.size() : cell_tris16_.size()));
      for (int a = 0; a < 3; ++a) {
        grid_base_.push_back(static_cast<std::uint32_t>(slice_rows_.size()));
        const std::uint32_t row_base = static_cast<std::uint32_t>(row_coord_.size());
        const std::uint32_t col_base = static_cast<std::uint32_t>(cell_col_.size());
        for (std::uint32_t s : p.slice_rows[a]) slice_rows_.push_back(row_base + s);
        row_coord_.insert(row_coord_.end(), p.row_coord[a].begin(), p.row_coord[a].end());
        for (std::uint32_t b : p.row_begin[a]) row_begin_.push_back(col_base + b);
        cell_col_.insert(cell_col_.end(), p.cell_col[a].begin(), p.cell_col[a].end());
        if (a == 0) {
          // The X grid lists the class's cells in id order: the id is the position, shifted.
          grid_shift_.push_back(col_base - cell_base);
        } else {
          // Y and Z grids: the class's own cell number, in 16 bits when every class has at most
          // 65536 cells (2 bytes per grid cell saved), else the global cell in 32 bits.
          if (wide_ids_) {
            grid_shift_.push_back(col_base - static_cast<std::uint32_t>(cell_id_.size()));
            for (std::uint32_t id : p.cell_id[a]) cell_id_.push_back(cell_base + id);
          } else {
            grid_shift_.push_back(col_base - static_cast<std::uint32_t>(cell_id16_.size()));
            for (std::uint32_t id : p.cell_id[a]) cell_id16_.push_back(static_cast<std::uint16_t>(id));
          }
        }
      }
      p = ClassGrids{};
    }
    row_begin_.push_back(static_cast<std::uint32_t>(cell_col_.size()));
    // 6. Chunk boxes when cells are crowded (mean entries per cell >= chunk_min_mean_): one box
    // per chunk_ consecutive entries (chunks cut the entry array at fixed positions, so a chunk
    // may span two cells: its box bounds both parts). A tile skips a chunk lying wholly outside
    // its beam instead of meeting its triangles one by one.
    if (total_cells > 0 && total_entries >= chunk_min_mean_ * total_cells) {
      const std::size_t chunks = (total_entries + chunk_ - 1) / chunk_;
      chunk_box_.assign(6 * chunks, 0.0f);
      std::size_t e = 0;
      for (std::size_t c = 0; c < classes; ++c) {
        const std::size_t e_end = class_entry_end[c];
        for (; e < e_end; ++e) {
          const std::uint32_t tri = entry_triangle(static_cast<std::uint32_t>(e), static_cast<std::uint32_t>(c));
          float* box = &chunk_box_[6 * (e / chunk_)];
          for (int k = 0; k < 3; ++k) {
            const glm::vec3& q = vertices_[tri_vertices_[3 * tri + static_cast<std::uint32_t>(k)]];
            for (int a = 0; a < 3; ++a) {
              if (e % chunk_ == 0 && k == 0) {
                box[a] = q[a];
                box[3 + a] = q[a];
              }
              box[a] = std::min(box[a], q[a]);
              box[3 + a] = std::max(box[3 + a], q[a]);
            }
          }
        }
      }
    }
    // 7. Narrow forms: 16-bit vertex ids when there are at most 65536 vertices; cell entry ranges
    // in 16 bits relative to their class when every class has at most 65535 entries (one extra
    // end per class: class k's cells c read ranges at c + k and c + k + 1).
    if (vertices_.size() <= 65536) {
      tri_vertices16_.assign(tri_vertices_.begin(), tri_vertices_.end());
      std::vector<std::uint32_t>().swap(tri_vertices_);
    }
    {
      bool narrow = !wide_ids_;  // class_cell_base_ holds each class's first cell
      for (std::size_t c = 0; c < classes && narrow; ++c) {
        const std::uint32_t first = class_cell_base_[c];
        const std::uint32_t last = c + 1 < classes ? class_cell_base_[c + 1] : static_cast<std::uint32_t>(total_cells);
        narrow = cell_tri_begin_[last] - cell_tri_begin_[first] <= 65535u;
      }
      if (narrow) {
        class_entry_base_.resize(classes);
        cell_begin16_.reserve(total_cells + classes);
        for (std::size_t c = 0; c < classes; ++c) {
          const std::uint32_t first = class_cell_base_[c];
          const std::uint32_t last = c + 1 < classes ? class_cell_base_[c + 1] : static_cast<std::uint32_t>(total_cells);
          class_entry_base_[c] = cell_tri_begin_[first];
          for (std::uint32_t cell = first; cell <= last; ++cell)
            cell_begin16_.push_back(static_cast<std::uint16_t>(cell_tri_begin_[cell] - cell_tri_begin_[first]));
        }
        std::vector<std::uint32_t>().swap(cell_tri_begin_);
      }
    }
    vertices_.shrink_to_fit();
    tri_vertices_.shrink_to_fit();
    tri_original_.shrink_to_fit();
    class_of_.shrink_to_fit();
    report(1.0f);
  }

  // The internal triangle of entry e, which belongs to a cell of class c.
  [[nodiscard]] std::uint32_t entry_triangle(std::uint32_t e, std::uint32_t c) const noexcept {
    return wide_tris_ ? cell_tris_[e] : class_tri_begin_[c] + cell_tris16_[e];
  }

  // One class's cells and grids, with offsets local to the class.
  struct ClassGrids {
    std::vector<std::uint32_t> cell_tri_begin{0};
    std::vector<std::uint32_t> cell_tris;
    std::vector<std::uint32_t> slice_rows[3];  // dims[a] + 1 entries: row ranges per slice
    std::vector<std::uint16_t> row_coord[3];
    std::vector<std::uint32_t> row_begin[3];   // one per row (no sentinel; the next row's begin ends it)
    std::vector<std::uint16_t> cell_col[3];
    std::vector<std::uint32_t> cell_id[3];
  };

  [[nodiscard]] int cell_of(double x, int a) const noexcept {
    const double f = std::floor((x - lo_[a]) / h_);
    if (!(f >= 0.0)) return 0;
    if (f >= dims_[a] - 1) return dims_[a] - 1;
    return static_cast<int>(f);
  }

  void build_class(const std::uint32_t* tris, std::size_t count, ClassGrids& out) const {
    struct Pair {
      std::uint64_t key;
      std::uint32_t place;  // Morton code of the centroid (clamped into the cell) within the cell
      std::uint32_t tri;
    };
    std::vector<Pair> pairs;
    pairs.reserve(count + count / 2);
    const std::uint64_t ny = static_cast<std::uint64_t>(dims_[1]), nz = static_cast<std::uint64_t>(dims_[2]);
    const double half[3] = {0.5 * h_ + delta_, 0.5 * h_ + delta_, 0.5 * h_ + delta_};
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t tri = tris[i];
      double v[3][3];
      double mn[3], mx[3];
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = vertices_[tri_vertices_[3 * tri + static_cast<std::uint32_t>(k)]];
        for (int a = 0; a < 3; ++a) v[k][a] = p[a];
      }
      int c0[3], c1[3];
      for (int a = 0; a < 3; ++a) {
        mn[a] = std::min({v[0][a], v[1][a], v[2][a]});
        mx[a] = std::max({v[0][a], v[1][a], v[2][a]});
        c0[a] = cell_of(mn[a] - delta_, a);
        c1[a] = cell_of(mx[a] + delta_, a);
      }
      const bool single = c0[0] == c1[0] && c0[1] == c1[1] && c0[2] == c1[2];
      for (int x = c0[0]; x <= c1[0]; ++x) {
        for (int y = c0[1]; y <= c1[1]; ++y) {
          for (int z = c0[2]; z <= c1[2]; ++z) {
            if (!single) {
              const double center[3] = {lo_[0] + (x + 0.5) * h_, lo_[1] + (y + 0.5) * h_, lo_[2] + (z + 0.5) * h_};
              if (!detail::triangle_box_overlap(center, half, v)) continue;
            }
            const std::uint64_t key = (static_cast<std::uint64_t>(x) * ny + static_cast<std::uint64_t>(y)) * nz +
                                      static_cast<std::uint64_t>(z);
            double u[3];
            const int cell[3] = {x, y, z};
            for (int a = 0; a < 3; ++a) {
              const double cen = (v[0][a] + v[1][a] + v[2][a]) / 3.0;
              u[a] = std::clamp((cen - (lo_[a] + cell[a] * h_)) / h_, 0.0, 1.0);
            }
            pairs.push_back(Pair{key, detail::nci_morton(u), tri});
          }
        }
      }
    }
    std::sort(pairs.begin(), pairs.end(),
              [](const Pair& a, const Pair& b) {
                if (a.key != b.key) return a.key < b.key;
                return a.place != b.place ? a.place < b.place : a.tri < b.tri;
              });
    // Cells in (x, y, z) order.
    std::vector<std::uint64_t> cell_key;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (i == 0 || pairs[i].key != pairs[i - 1].key) {
        if (i > 0) out.cell_tri_begin.push_back(static_cast<std::uint32_t>(out.cell_tris.size()));
        cell_key.push_back(pairs[i].key);
      }
      out.cell_tris.push_back(pairs[i].tri);
    }
    if (!pairs.empty()) out.cell_tri_begin.push_back(static_cast<std::uint32_t>(out.cell_tris.size()));
    pairs.clear();
    pairs.shrink_to_fit();
    const std::size_t cells = cell_key.size();
    std::vector<std::array<std::uint16_t, 3>> coord(cells);
    for (std::size_t i = 0; i < cells; ++i) {
      const std::uint64_t k = cell_key[i];
      coord[i][2] = static_cast<std::uint16_t>(k % nz);
      coord[i][1] = static_cast<std::uint16_t>((k / nz) % ny);
      coord[i][0] = static_cast<std::uint16_t>(k / nz / ny);
    }
    std::vector<std::uint32_t> order(cells);
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (std::size_t i = 0; i < cells; ++i) order[i] = static_cast<std::uint32_t>(i);
      if (a != 0) {
        std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
          const auto& u = coord[p];
          const auto& w = coord[q];
          if (u[a] != w[a]) return u[a] < w[a];
          if (u[b] != w[b]) return u[b] < w[b];
          return u[c] < w[c];
        });
      }
      auto& slice_rows = out.slice_rows[a];
      slice_rows.assign(static_cast<std::size_t>(dims_[a]) + 1, 0u);
      std::size_t i = 0;
      for (int s = 0; s < dims_[a]; ++s) {
        slice_rows[static_cast<std::size_t>(s)] = static_cast<std::uint32_t>(out.row_coord[a].size());
        while (i < cells && coord[order[i]][a] == s) {
          const std::uint16_t row = coord[order[i]][b];
          out.row_coord[a].push_back(row);
          out.row_begin[a].push_back(static_cast<std::uint32_t>(out.cell_col[a].size()));
          while (i < cells && coord[order[i]][a] == s && coord[order[i]][b] == row) {
            out.cell_col[a].push_back(coord[order[i]][c]);
            out.cell_id[a].push_back(order[i]);
            ++i;
          }
        }
      }
      slice_rows[static_cast<std::size_t>(dims_[a])] = static_cast<std::uint32_t>(out.row_coord[a].size());
    }
  }

  // ---------------------------------------------------------------- select
  struct Frame {
    PixelRays rays;
    glm::dvec3 eye;
    glm::vec3 eye_f;
    int axis = 2;
    glm::dmat4 view_proj;
    bool use_rect = false;   // screen rectangles of triangles may prune rays
    glm::dvec4 target_plane{0.0};  // plane holding the pixel rays' target points (world space)
    const float* initial_depth = nullptr;  // per pixel: start from this depth (moving objects)
    const float* initial_solid = nullptr;  // per pixel: and from this solid depth (>= initial_depth)
    int width = 0, height = 0;
    double eye_side = 0.0;          // -target_plane . (eye, 1)
    glm::dvec4 eye_clip{0.0};       // view_proj * (eye, 1)
    glm::dvec3 clip_x{0.0}, clip_y{0.0}, clip_w{0.0};  // rows x, y, w of view_proj's 3x3 part
    // The projection of a point eye + dx onto the target plane, in clip coordinates, is
    // (h_x . dx, h_y . dx, h_w . dx) / (plane . dx): one division per point for its pixel.
    glm::dvec3 h_x{0.0}, h_y{0.0}, h_w{0.0}, plane{0.0};
    // Pixel ray directions are positive multiples of an affine function of the pixel position
    // (one target plane whose homogeneous w keeps one sign over the screen): beside_rect may use
    // a rectangle's corner rays for the rays inside it.
    bool affine_rays = false;
    // The 2D footprint pre-test (footprint_mask) may be used: screen rectangles are on and one
    // pixel spans at least 4e-5 radians everywhere on screen (at most 25,000 pixels per radian).
    bool footprint = false;
    // Margin of screen rectangles and footprints in pixels: a twentieth of a pixel for the float
    // rounding of the ray directions, plus the ray test's edge band (tiny unless a pixel spans only
    // a few float roundings: very narrow fields of view).
    double margin = 0.05;
    // The pixels whose centres may see the (inflated) scene box: project_rect of its corners, so it
    // holds every triangle's rectangle. A tile wholly outside it has no ray to set up.
    NciContext::Rect box_rect{NciContext::Rect::full, 0, 0, 0};
    int tile = 32;  // the tile edge of this call
  };

  [[nodiscard]] Frame make_frame(const Camera& camera) const {
    Frame f{PixelRays(camera), glm::dvec3(camera.eye), camera.eye, 2, glm::dmat4(camera.view_proj), false,
            glm::dvec4(0.0), nullptr, nullptr, camera.width, camera.height};
    const Ray center = f.rays.ray_at(0.5 * camera.width, 0.5 * camera.height);
    const glm::vec3 d = center.direction;
    const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
    f.axis = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    // Screen rectangles. A pixel ray runs from the eye toward a target point on one plane of the
    // projection (far, or near when far is at infinity); the pixel a point X can be seen at is
    // found by projecting X from the eye onto that plane and reading the plane point's pixel. This
    // holds even when `eye` is not exactly the matrix's centre of projection (float matrices).
    // Used only when the same plane serves the whole screen, as PixelRays decides it.
    const glm::dmat4 inv = glm::inverse(f.view_proj);
    const glm::dvec4 far_h = inv[2] + inv[3];
    const double near_z = camera.depth == DepthRange::zero_to_one ? 0.0 : -1.0;
    int uses_far = 0, uses_near = 0;
    for (int k = 0; k < 5; ++k) {
      const double u = k == 4 ? 0.0 : ((k & 1) ? 1.0 : -1.0), v = k == 4 ? 0.0 : ((k & 2) ? 1.0 : -1.0);
      const glm::dvec4 h = inv[0] * u + inv[1] * v + far_h;
      const double mag = std::fabs(h.x) + std::fabs(h.y) + std::fabs(h.z);
      // A margin around PixelRays' threshold: pixels near the switch would be ambiguous.
      if (std::fabs(h.w) > 1e-6 * mag && h.w > 0.0) ++uses_far;
      else if (!(std::fabs(h.w) > 1e-12 * mag)) ++uses_near;
    }
    if (uses_far == 5 || uses_near == 5) {
      const double z0 = uses_far == 5 ? 1.0 : near_z;
      {
        // w of the target point is affine over the screen: one sign at the four corners holds
        // everywhere between them.
        int positive = 0, negative = 0;
        for (int k = 0; k < 4; ++k) {
          const double u = (k & 1) ? 1.0 : -1.0, v = (k & 2) ? 1.0 : -1.0;
          const double w = (inv[0] * u + inv[1] * v + inv[2] * z0 + inv[3]).w;
          positive += w > 0.0;
          negative += w < 0.0;
        }
        f.affine_rays = positive == 4 || negative == 4;
      }
      glm::dvec4 row2, row3;
      for (int j = 0; j < 4; ++j) {
        row2[j] = f.view_proj[j][2];
        row3[j] = f.view_proj[j][3];
      }
      f.target_plane = row2 - z0 * row3;
      const double on_eye = glm::dot(f.target_plane, glm::dvec4(f.eye, 1.0));
      f.use_rect = std::isfinite(on_eye) && on_eye != 0.0 && camera.width <= 32000 && camera.height <= 32000;
      f.eye_side = -on_eye;
      f.eye_clip = f.view_proj * glm::dvec4(f.eye, 1.0);
      for (int j = 0; j < 3; ++j) {
        f.clip_x[j] = f.view_proj[j][0];
        f.clip_y[j] = f.view_proj[j][1];
        f.clip_w[j] = f.view_proj[j][3];
      }
      // clip = eye_clip + s view_proj dx with s = eye_side / (plane . dx): multiplied through by
      // plane . dx, each coordinate is linear in dx.
      f.plane = glm::dvec3(f.target_plane);
      f.h_x = f.eye_clip.x * f.plane + f.eye_side * f.clip_x;
      f.h_y = f.eye_clip.y * f.plane + f.eye_side * f.clip_y;
      f.h_w = f.eye_clip.w * f.plane + f.eye_side * f.clip_w;
      if (f.use_rect) {
        // The smallest angle between neighbouring pixel rays, sampled at the centre and the four
        // corners (with one target plane the angle per pixel is smallest at the screen's edges).
        double smallest = std::numeric_limits<double>::infinity();
        const double xs[5] = {0.5, camera.width - 1.5, 0.5, camera.width - 1.5, 0.5 * camera.width};
        const double ys[5] = {0.5, 0.5, camera.height - 1.5, camera.height - 1.5, 0.5 * camera.height};
        for (int k = 0; k < 5; ++k) {
          const glm::dvec3 d0(f.rays.ray_at(xs[k], ys[k]).direction);
          const glm::dvec3 dx(f.rays.ray_at(xs[k] + 1.0, ys[k]).direction);
          const glm::dvec3 dy(f.rays.ray_at(xs[k], ys[k] + 1.0).direction);
          smallest = std::min({smallest, glm::length(glm::cross(d0, dx)), glm::length(glm::cross(d0, dy))});
        }
        f.footprint = camera.width >= 2 && camera.height >= 2 && smallest >= 4e-5;
        // The ray test's edge band (near misses are reported too) as an angle: the band's distance
        // over the depth, at most about 4 band widths near an edge; in pixels at the narrowest spot.
        const double band_angle = 4.0 * double(band_);
        f.margin = 0.05 + (smallest > 0.0 && std::isfinite(smallest) ? band_angle / smallest : 1e6);
      }
    }
    return f;
  }

  using TileRays = detail::NciTileRays;
  static constexpr int max_tile_ = TileRays::max_tile;
  using Mask = TileRays::Mask;  // one bit per pixel of a tile row

  // Which pixels may see the triangle: an empty rectangle for a back face (or one seen exactly
  // edge-on: the eye in its plane is never a hit), `full` when the projection cannot be trusted.
  [[nodiscard]] static NciContext::Rect screen_rect(const Frame& f, const glm::vec3& p0, const glm::vec3& p1,
                                                    const glm::vec3& p2) noexcept {
    if (!detail::faces_eye(p0, p1, p2, f.eye)) return NciContext::Rect{0, 0, -1, -1};
    const glm::vec3 p[3] = {p0, p1, p2};
    return project_rect(f, p, 3);
  }

  // The tile edge for a screen: NciParams::tile_size, or when it is 0, 64 from 640x480 pixels up
  // and 32 below (bigger tiles pay from there on; see NciParams::tile_size).
  [[nodiscard]] int tile_edge(int width, int height) const noexcept {
    if (params_.tile_size != 0) return params_.tile_size;
    return static_cast<long long>(width) * height >= 640LL * 480LL ? max_tile_ : 32;
  }

  // Whether a corner lies (nearly) at the eye: its offsets from the eye, as the float ray test takes
  // them, are subnormal or their products underflow, so that test has no relative precision near it
  // and no rejection whose margin is relative rounding holds for its triangle (screen rectangle,
  // footprint, beam planes, corner-ray planes): such a triangle is tested against every live ray.
  // Above 1e-15 every product of two offsets stays a normal float (>= 2^24 FLT_MIN). NaN counts as
  // near (never rejected).
  [[nodiscard]] static bool near_eye(double x, double y, double z) noexcept {
    return !(std::max({std::fabs(x), std::fabs(y), std::fabs(z)}) >= 1e-15);
  }

  // A point's pixel-centre coordinates (pixel i has coordinate i): its projection from the eye onto
  // the target plane, in double; false when it is not strictly in front of the eye (or w <= 0).
  [[nodiscard]] static bool project_point(const Frame& f, const glm::vec3& p, double& px, double& py) noexcept {
    const glm::dvec3 dx = glm::dvec3(p) - f.eye;
    if (near_eye(dx.x, dx.y, dx.z)) return false;  // no projection: callers test every ray
    // s = eye_side / pd > 0: in front of the eye (not behind it or beside it).
    const double pd = glm::dot(f.plane, dx);
    if (!(pd != 0.0) || (pd > 0.0) != (f.eye_side > 0.0)) return false;
    // Clip w = qw / pd > 0.
    const double qw = glm::dot(f.h_w, dx);
    if (!(qw != 0.0) || (qw > 0.0) != (pd > 0.0)) return false;
    const double inv = 1.0 / qw;
    // Pixel-centre coordinates: pixel i has ndc (2i + 1) / width - 1.
    px = ((glm::dot(f.h_x, dx) * inv + 1.0) * f.width - 1.0) * 0.5;
    py = ((1.0 - glm::dot(f.h_y, dx) * inv) * f.height - 1.0) * 0.5;
    return true;
  }

  // The pixels whose centres may see a point of the convex hull of `p` (count points): the
  // bounding rectangle of their projections (the hull projects into the hull of the projected
  // points when every point is in front of the eye: the conditions checked are linear in the
  // point, so they hold on the whole hull), `full` when the projection cannot be trusted.
  [[nodiscard]] static NciContext::Rect project_rect(const Frame& f, const glm::vec3* p, int count) noexcept {
    using Rect = NciContext::Rect;
    if (!f.use_rect) return Rect{Rect::full, 0, 0, 0};
    double mnx = std::numeric_limits<double>::infinity(), mny = mnx, mxx = -mnx, mxy = -mnx;
    for (int k = 0; k < count; ++k) {
      double px = 0.0, py = 0.0;
      if (!project_point(f, p[k], px, py)) return Rect{Rect::full, 0, 0, 0};
      mnx = std::min(mnx, px);
      mxx = std::max(mxx, px);
      mny = std::min(mny, py);
      mxy = std::max(mxy, py);
    }
    if (!(std::isfinite(mnx) && std::isfinite(mxx) && std::isfinite(mny) && std::isfinite(mxy)))
      return Rect{Rect::full, 0, 0, 0};
    // A pixel centre can see the triangle only inside its projection; the margin (Frame::margin)
    // covers the float rounding of the ray directions and the ray test's edge band. Clamped to the screen (in double
    // first: projected corners may be far off screen).
    const double m = f.margin;
    const double lx0 = std::ceil(mnx - m), lx1 = std::floor(mxx + m);
    const double ly0 = std::ceil(mny - m), ly1 = std::floor(mxy + m);
    if (lx1 < 0.0 || ly1 < 0.0 || lx0 > f.width - 1 || ly0 > f.height - 1) return Rect{0, 0, -1, -1};
    return Rect{static_cast<std::int16_t>(std::max(0.0, lx0)), static_cast<std::int16_t>(std::max(0.0, ly0)),
                static_cast<std::int16_t>(std::min(double(f.width - 1), lx1)),
                static_cast<std::int16_t>(std::min(double(f.height - 1), ly1))};
  }

  // The beam of the tile's live rays: planes through the eye and consecutive corner rays, then
  // measured against every live ray so that the margin covers whatever the projection did.
  // The corners are those of the live pixels' bounding rectangle (widened to two pixels where it
  // is one wide), so the beam narrows as rays finish; `box` records that rectangle.
  // The live pixels' bounding rectangle (x0, y0, x1, y1), widened to two pixels where it is one
  // wide; false when no pixel is live or the tile is narrower than two pixels.
  static bool live_box(int tw, int th, const Mask* live, int box[4]) noexcept {
    if (tw < 2 || th < 2) return false;
    int y0 = -1, y1 = -1;
    Mask cols = 0;
    for (int y = 0; y < th; ++y) {
      if (!live[y]) continue;
      if (y0 < 0) y0 = y;
      y1 = y;
      cols |= live[y];
    }
    if (y0 < 0) return false;
    int x0 = TileRays::low_bit(cols), x1 = TileRays::high_bit(cols);
    if (x0 == x1) x1 < tw - 1 ? ++x1 : --x0;
    if (y0 == y1) y1 < th - 1 ? ++y1 : --y0;
    box[0] = x0;
    box[1] = y0;
    box[2] = x1;
    box[3] = y1;
    return true;
  }

  static void make_beam(TileRays& r, int tw, int th, const Mask* live) noexcept {
    const int stride = r.stride;  // the tile's row pitch (kept in a register)
    r.beam = false;
    int box[4];
    if (!live_box(tw, th, live, box)) return;
    for (int k = 0; k < 4; ++k) r.beam_box[k] = box[k];
    const int corner[4] = {box[1] * stride + box[0], box[1] * stride + box[2], box[3] * stride + box[2], box[3] * stride + box[0]};
    glm::dvec3 d[4], centre(0.0);
    for (int k = 0; k < 4; ++k) {
      d[k] = r.direction(corner[k]);
      if (!r.wray[corner[k]].valid) return;
      centre += d[k];
    }
    for (int k = 0; k < 4; ++k) {
      glm::dvec3 n = glm::cross(d[k], d[(k + 1) % 4]);
      const double len = glm::length(n);
      if (!(len > 1e-12) || !std::isfinite(len)) return;
      n /= len;
      if (glm::dot(n, centre) < 0.0) n = -n;
      for (int j = 0; j < 3; ++j) r.beam_n[k][j] = static_cast<float>(n[j]);
    }
    double worst = 0.0;
    for (int y = 0; y < th; ++y) {
      Mask bits = live[y];
      if (!bits) continue;
#if CULLKIT_HAS_SSE2
      // Pre-test, 4 rays at a time in float: a ray with n.d > 5e-7 |d|_1 in float for all four
      // planes has exact n.d > 0 (the float dot product is within 3 2^-24 |d|_1 of it, |n| <= 1),
      // so its double value below is not negative and cannot raise `worst`: only the other rays
      // are measured. The same `worst`, bit for bit.
      {
        Mask maybe = 0;
        const __m128 sign = _mm_set1_ps(-0.0f), lim = _mm_set1_ps(5e-7f);
        for (int q = TileRays::low_bit(bits) / 4, q_end = TileRays::high_bit(bits) / 4; q <= q_end; ++q) {
          if (!((bits >> (4 * q)) & 15u)) continue;
          const int i0 = y * stride + 4 * q;
          const __m128 vx = _mm_load_ps(&r.dx[i0]), vy = _mm_load_ps(&r.dy[i0]), vz = _mm_load_ps(&r.dz[i0]);
          const __m128 dl = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, vx), _mm_andnot_ps(sign, vy)), _mm_andnot_ps(sign, vz));
          const __m128 bound = _mm_mul_ps(lim, dl);
          __m128 doubt = _mm_setzero_ps();
          for (int k = 0; k < 4; ++k) {
            const __m128 v = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(r.beam_n[k][0]), vx),
                                                   _mm_mul_ps(_mm_set1_ps(r.beam_n[k][1]), vy)),
                                        _mm_mul_ps(_mm_set1_ps(r.beam_n[k][2]), vz));
            doubt = _mm_or_ps(doubt, _mm_cmple_ps(v, bound));
          }
          maybe |= static_cast<Mask>(_mm_movemask_ps(doubt)) << (4 * q);
        }
        bits &= maybe;
      }
#endif
      while (bits) {
        const int x = TileRays::low_bit(bits);
        bits &= bits - 1;
        const glm::dvec3 dir = r.direction(y * stride + x);
        const double dl = std::fabs(dir.x) + std::fabs(dir.y) + std::fabs(dir.z);
        for (int k = 0; k < 4; ++k) {
          const double v = double(r.beam_n[k][0]) * dir.x + double(r.beam_n[k][1]) * dir.y + double(r.beam_n[k][2]) * dir.z;
          if (-v > worst * dl) worst = std::max(worst, -v / std::max(dl, 1e-30));
        }
      }
    }
    // Rounding of the float plane test below (relative to the corner's 1-norm) on top.
    const double eps = worst * 1.01 + 1e-5;
    if (!(eps < 0.25)) return;
    r.beam_eps = static_cast<float>(eps);
    r.beam = true;
  }

  // Re-makes the beam when the live pixels' rectangle has shrunk since it was made (a beam that
  // cannot be made for the smaller rectangle leaves the old one, which still holds every live ray).
  static void narrow_beam(TileRays& r, int tw, int th, const Mask* live) noexcept {
    int box[4];
    if (!r.beam || !live_box(tw, th, live, box)) return;
    // Re-made only when the rectangle lost at least half its pixels (the re-make visits every
    // live ray).
    const int area = (box[2] - box[0] + 1) * (box[3] - box[1] + 1);
    const int old_area = (r.beam_box[2] - r.beam_box[0] + 1) * (r.beam_box[3] - r.beam_box[1] + 1);
    if (2 * area > old_area) return;
    float n[4][3];
    std::memcpy(n, r.beam_n, sizeof n);
    const float eps = r.beam_eps;
    int old_box[4];
    std::memcpy(old_box, r.beam_box, sizeof old_box);
    make_beam(r, tw, th, live);
    if (!r.beam) {
      std::memcpy(r.beam_n, n, sizeof n);
      r.beam_eps = eps;
      std::memcpy(r.beam_box, old_box, sizeof old_box);
      r.beam = true;
    }
  }

  // Whether no live ray of the tile can take a hit from chunk j: its box's screen rectangle
  // (cached per frame and thread) covers no live pixel of the tile, or every live ray under it
  // already holds a hit strictly nearer than any t the ray test could give a point of the box.
  [[nodiscard]] bool chunk_hidden(const Frame& f, std::uint32_t j, int x0, int y0, int tw, int th,
                                  const Mask* live, const TileRays& r, NciContext::Thread& thread) const noexcept {
    const float* box = &chunk_box_[6 * std::size_t{j}];
    auto& slot = thread.chunk[j];
    if (slot.epoch != thread.frame_epoch) {
      slot.epoch = thread.frame_epoch;
      glm::vec3 corner[8];
      for (int k = 0; k < 8; ++k)
        corner[k] = glm::vec3(box[(k & 1) ? 3 : 0], box[(k & 2) ? 4 : 1], box[(k & 4) ? 5 : 2]);
      slot.rect = project_rect(f, corner, 8);
    }
    int rx0, ry0, rx1, ry1;
    Mask span;
    if (!live_under(slot.rect, x0, y0, tw, th, live, rx0, ry0, rx1, ry1, span)) return true;  // no live pixel
    const float qlo[3] = {box[0] - f.eye_f.x, box[1] - f.eye_f.y, box[2] - f.eye_f.z};
    const float qhi[3] = {box[3] - f.eye_f.x, box[4] - f.eye_f.y, box[5] - f.eye_f.z};
    return behind_hits(r, qlo, qhi, ry0, ry1, span, live);
  }

  // A cached screen rectangle clipped to the tile at (x0, y0) of tw x th pixels: the tile-local
  // rectangle rx0..rx1 x ry0..ry1 and its column mask `span`. False when the rectangle is empty, off
  // the tile, or covers no live pixel (`live`: one bit mask per tile row).
  [[nodiscard]] static bool live_under(const NciContext::Rect& rect, int x0, int y0, int tw, int th,
                                       const Mask* live, int& rx0, int& ry0, int& rx1, int& ry1,
                                       Mask& span) noexcept {
    if (rect.x0 > rect.x1) return false;
    rx0 = 0, ry0 = 0, rx1 = tw - 1, ry1 = th - 1;
    if (rect.x0 != NciContext::Rect::full) {
      const int lx0 = rect.x0 - x0, lx1 = rect.x1 - x0, ly0 = rect.y0 - y0, ly1 = rect.y1 - y0;
      if (lx1 < 0 || ly1 < 0 || lx0 > tw - 1 || ly0 > th - 1) return false;
      rx0 = std::max(0, lx0);
      rx1 = std::min(tw - 1, lx1);
      ry0 = std::max(0, ly0);
      ry1 = std::min(th - 1, ly1);
    }
    span = TileRays::columns(rx0, rx1);
    Mask under = 0;
    for (int y = ry0; y <= ry1; ++y) under |= live[y] & span;
    return under != 0;
  }

  // Whether the box (min xyz, max xyz) lies wholly outside one plane of the tile's beam with the
  // margin of outside_beam (then so does every triangle inside it): the largest n.x + eps |x|_1
  // over the box, x relative to the eye, is below zero. In double with a 1e-12 relative slack, so
  // the sign is exact for the float data.
  [[nodiscard]] static bool chunk_outside_beam(const TileRays& r, const float* box, const Frame& f) noexcept {
    double lo[3], hi[3], l1 = 0.0, gap[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = double(box[a]) - f.eye[a];
      hi[a] = double(box[3 + a]) - f.eye[a];
      l1 += std::max(std::fabs(lo[a]), std::fabs(hi[a]));
      gap[a] = std::max({lo[a], -hi[a], 0.0});
    }
    if (near_eye(gap[0], gap[1], gap[2])) return false;  // may hold a corner (nearly) at the eye
    const double e = double(r.beam_eps) + 1e-12;
    for (int j = 0; j < 4; ++j) {
      const float* n = r.beam_n[j];
      double top = 0.0;
      for (int a = 0; a < 3; ++a) top += std::max(double(n[a]) * lo[a], double(n[a]) * hi[a]);
      if (top + e * l1 < 0.0) return true;
    }
    return false;
  }

  // Whether triangle `tri` lies wholly outside one plane of the tile's beam with margin: every
  // corner x (relative to the eye, in float as the ray test takes it) has n.x + eps |x|_1 < 0.
  // That set is convex, so it holds the whole triangle; a ray direction d (unit) with
  // n.d >= -eps |d|_1 meets no point of it.
  [[nodiscard]] bool outside_beam(const TileRays& r, std::uint32_t tri, const Frame& f) const noexcept {
    float x[3][3];
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = corner(tri, k);
      x[k][0] = p.x - f.eye_f.x;
      x[k][1] = p.y - f.eye_f.y;
      x[k][2] = p.z - f.eye_f.z;
      if (near_eye(x[k][0], x[k][1], x[k][2])) return false;
    }
    const float e = r.beam_eps;
    for (int j = 0; j < 4; ++j) {
      const float* n = r.beam_n[j];
      bool out = true;
      for (int k = 0; k < 3 && out; ++k) {
        const float l1 = std::fabs(x[k][0]) + std::fabs(x[k][1]) + std::fabs(x[k][2]);
        out = n[0] * x[k][0] + n[1] * x[k][1] + n[2] * x[k][2] + e * l1 < 0.0f;
      }
      if (out) return true;
    }
    return false;
  }

  // Whether every ray that would test the triangle (live, under its rectangle) already holds a
  // hit strictly nearer than any t the watertight test can compute for it: a lower bound on that
  // t (see TileRays::sz_lo) times (1 - 1e-6), against the farthest of those rays' hits. The
  // computed t is tt / det with tt and det sums of non-negative products, so it is at least the
  // bound times (1 - 8 2^-24); the margin covers that, and strictness keeps ties (lower index
  // wins) with the ray test. Such a triangle is not tested at all.
  // `qlo` and `qhi` bound the corners' coordinates relative to the eye as the ray test computes
  // them (float differences; rounding is monotone, so the box of the float corners bounds them).
  [[nodiscard]] static bool behind_hits(const TileRays& r, const float qlo[3], const float qhi[3], int ry0, int ry1,
                                        Mask span, const Mask* live) noexcept {
    const int stride = r.stride;  // the tile's row pitch (kept in a register)
    double bound = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      if (r.sz_lo[k] > r.sz_hi[k]) continue;
      const double lo = r.sz_lo[k], hi = r.sz_hi[k];
      bound = std::min({bound, lo * double(qlo[k]), lo * double(qhi[k]), hi * double(qlo[k]), hi * double(qhi[k])});
    }
    bound *= 1.0 - 1e-6;
    if (!(bound > 1e-30) || !std::isfinite(bound)) return false;
    for (int y = ry0; y <= ry1; ++y) {
      Mask bits = live[y] & span;
      while (bits) {
        const int x = TileRays::low_bit(bits);
        bits &= bits - 1;
        if (!(double(r.solid_t[y * stride + x]) < bound)) return false;
      }
    }
    return true;
  }

  // Whether the triangle lies wholly beside the pixel rectangle [rx0, rx1] x [ry0, ry1] of the tile:
  // all four corner rays outside the plane through the eye and one of its edges, by a margin of
  // 1e-5 (relative). With one target plane for the whole screen (affine_rays) the pixel rays'
  // directions are positive multiples of an affine function of the pixel position, so every pixel ray of the
  // rectangle is a positive combination of the corner rays and lies outside that plane as well;
  // the margin covers the float rounding of the directions and of the ray test (about 1e-7).
  [[nodiscard]] static bool beside_rect(const TileRays& r, const float a[3], const float b[3], const float c[3], int rx0,
                                        int ry0, int rx1, int ry1) noexcept {
    const int stride = r.stride;  // the tile's row pitch (kept in a register)
    const glm::dvec3 p[3] = {glm::dvec3(a[0], a[1], a[2]), glm::dvec3(b[0], b[1], b[2]), glm::dvec3(c[0], c[1], c[2])};
    for (const glm::dvec3& q : p)
      if (near_eye(q.x, q.y, q.z)) return false;
    const int corner[4] = {ry0 * stride + rx0, ry0 * stride + rx1, ry1 * stride + rx1, ry1 * stride + rx0};
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 n = glm::cross(p[k], p[(k + 1) % 3]);
      const double side = glm::dot(n, p[(k + 2) % 3]);  // the inside holds the third corner
      const double len = glm::length(n);
      if (!(std::fabs(side) > 0.0) || !(len > 0.0) || !std::isfinite(side) || !std::isfinite(len)) continue;
      const glm::dvec3 m = side > 0.0 ? n : -n;
      bool out = true;
      for (int j = 0; j < 4 && out; ++j) {
        const glm::dvec3 d = r.direction(corner[j]);
        out = glm::dot(m, d) < -1e-5 * len * glm::length(d);
      }
      if (out) return true;
    }
    return false;
  }

  // Tests `tri` against the unfinished rays of the tile inside its screen rectangle; false when no
  // ray was tested (a back face seen from the eye, or no live pixel under its rectangle).
  // Whether `tri` may be hit by an unfinished ray of the tile (beam, screen rectangle, live
  // pixels under it); when it may, `out` gets the pixels under its rectangle and its sort key.
  bool admit_triangle(const Frame& f, std::uint32_t tri, int x0, int y0, int tw, int th, const Mask* live,
                      const TileRays& r, NciContext::Thread& thread, NciContext::Thread::Cand& out) const {
    // The triangle's screen rectangle, computed once per frame and thread (cached: a triangle is
    // met by many tiles).
    auto& slot = thread.tri[tri];
    bool in_beam = !r.beam;
    if (slot.epoch != thread.frame_epoch) {
      // Not yet met this frame: a triangle wholly outside the tile's beam is rejected without
      // computing its rectangle (most triangles of a big scene met by a tile are).
      if (r.beam && outside_beam(r, tri, f)) return false;
      in_beam = true;
      slot.epoch = thread.frame_epoch;
      slot.rect = screen_rect(f, corner(tri, 0), corner(tri, 1), corner(tri, 2));
    }
    // None (back face, edge-on from the eye, off screen) or no live pixel under it: not tested.
    int rx0, ry0, rx1, ry1;
    Mask span;
    if (!live_under(slot.rect, x0, y0, tw, th, live, rx0, ry0, rx1, ry1, span)) {
      // Counted only inside the beam, so the count does not depend on which thread met it first.
      if (slot.rect.x0 > slot.rect.x1 && (in_beam || !outside_beam(r, tri, f))) ++thread.stats.triangles_no_pixel;
      return false;
    }
    // The same beam test when the rectangle came from the cache, so what is tested does not depend
    // on which thread met the triangle first.
    if (!in_beam && outside_beam(r, tri, f)) return false;
    float key = std::numeric_limits<float>::infinity();
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 d = corner(tri, k) - f.eye_f;
      key = std::min(key, d.x * r.mean_dir[0] + d.y * r.mean_dir[1] + d.z * r.mean_dir[2]);
    }
    out = NciContext::Thread::Cand{key, tri, static_cast<std::int8_t>(rx0), static_cast<std::int8_t>(ry0),
                                   static_cast<std::int8_t>(rx1), static_cast<std::int8_t>(ry1)};
    return true;
  }

  // The 2D footprint pre-test (project issue #6): which live pixels of `bits` (rows ry0..ry1 of the
  // tile at (x0, y0)) have their centre inside the projected triangle grown by a margin; only
  // those rays can hit it. False when the test does not apply (a corner not strictly in front of
  // the eye, a projection that is not finite or has no area): then every ray is tested as before.
  // Why a skipped ray cannot hit (the watertight test stays the only hit decision):
  //  * Exact geometry: the ray through a pixel centre q meets the triangle iff q lies in the
  //    projection of the triangle from the eye onto the target plane (PixelRays aims at that plane,
  //    and with every corner in front the projection of the triangle is the triangle of the
  //    projected corners).
  //  * The float ray test differs from the exact one by (a) angular errors of a few ulp: the unit
  //    direction rounded to float, the shear constants d[kx] / d[kz], the corners' float offsets
  //    from the eye and the sheared coordinates (each relative error <= 2^-24 of a length at most
  //    sqrt(3) times the depth along the ray, together well below 1e-6 rad); at most 25,000 pixels
  //    per radian (Frame::footprint) makes that < 0.025 pixel, inside the margin m = 0.05 pixel
  //    per axis (the screen rectangles' margin Frame::margin, which adds the ray test's edge band
  //    so near misses are tested too; an edge grows by m times the 1-norm of its normal); (b) the rounding of the edge products cx * by - cy * bx, at most about 4 * 2^-24 |B| |C|:
  //    in pixel units (the map from the shear plane to the screen is a projective map close to a
  //    similarity near the ray, condition number well below 10) at most 1e-5 R^2, R bounding the
  //    distance from a tested pixel centre to the corners; an edge grows by that much too (more
  //    for short edges: the distance slack is 1e-5 R^2 / length). The double arithmetic here adds
  //    a relative 1e-12 of the coordinates.
  //  A pixel centre outside the grown triangle has one exact edge function below -(margin), so its
  //  float ray sees that edge function negative and the watertight test rejects it.
  [[nodiscard]] static bool footprint_mask(const Frame& f, const glm::vec3& p0, const glm::vec3& p1,
                                           const glm::vec3& p2, int x0, int y0, int ry0, int ry1,
                                           const Mask* bits, Mask* mask, int x_last) noexcept {
    double px[3], py[3];
    if (!project_point(f, p0, px[0], py[0]) || !project_point(f, p1, px[1], py[1]) ||
        !project_point(f, p2, px[2], py[2]))
      return false;
    const double area = (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0]);
    if (!(std::fabs(area) > 0.0) || !std::isfinite(area)) return false;
    const double sgn = area > 0.0 ? 1.0 : -1.0;
    double lox = x0, hix = x0 + x_last, loy = y0 + ry0, hiy = y0 + ry1;
    for (int k = 0; k < 3; ++k) {
      lox = std::min(lox, px[k]);
      hix = std::max(hix, px[k]);
      loy = std::min(loy, py[k]);
      hiy = std::max(hiy, py[k]);
    }
    const double reach = (hix - lox) + (hiy - loy) + 1.0;
    double nx[3], ny[3], off[3];
    for (int k = 0; k < 3; ++k) {
      const int j = k == 2 ? 0 : k + 1;
      // e(q) = nx (qx - px[k]) + ny (qy - py[k]) >= 0 inside (orientation from the area's sign).
      nx[k] = -(py[j] - py[k]) * sgn;
      ny[k] = (px[j] - px[k]) * sgn;
      const double n1 = std::fabs(nx[k]) + std::fabs(ny[k]);
      const double slack = f.margin * n1 + 1e-5 * reach * reach +
                           1e-12 * n1 * (reach + std::fabs(px[k]) + std::fabs(py[k]) + f.width + f.height);
      off[k] = -nx[k] * px[k] - ny[k] * py[k] + slack;
      if (!std::isfinite(off[k])) return false;
    }
#if CULLKIT_HAS_SSE2
    // Two pixel centres at a time, the same double expressions (so the same mask) as below.
    const __m128d nx0 = _mm_set1_pd(nx[0]), nx1 = _mm_set1_pd(nx[1]), nx2 = _mm_set1_pd(nx[2]);
    const __m128d of0 = _mm_set1_pd(off[0]), of1 = _mm_set1_pd(off[1]), of2 = _mm_set1_pd(off[2]);
    const __m128d zero = _mm_setzero_pd();
    for (int y = ry0; y <= ry1; ++y) {
      const Mask b = bits[y];
      if (!b) {
        mask[y] = 0;
        continue;
      }
      const double qy = y0 + y;
      const __m128d ey0 = _mm_set1_pd(ny[0] * qy), ey1 = _mm_set1_pd(ny[1] * qy), ey2 = _mm_set1_pd(ny[2] * qy);
      Mask m = 0;
      for (int x = TileRays::low_bit(b), x_end = TileRays::high_bit(b); x <= x_end; x += 2) {
        const __m128d qx = _mm_set_pd(double(x0 + x + 1), double(x0 + x));
        const __m128d e0 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx0, qx), ey0), of0);
        const __m128d e1 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx1, qx), ey1), of1);
        const __m128d e2 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(nx2, qx), ey2), of2);
        const __m128d in = _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(e0, zero), _mm_cmpge_pd(e1, zero)), _mm_cmpge_pd(e2, zero));
        m |= static_cast<Mask>(_mm_movemask_pd(in)) << x;
      }
      mask[y] = m & b;
    }
#else
    for (int y = ry0; y <= ry1; ++y) {
      Mask b = bits[y];
      Mask m = 0;
      const double qy = y0 + y;
      while (b) {
        const int x = TileRays::low_bit(b);
        b &= b - 1;
        const double qx = x0 + x;
        if (nx[0] * qx + ny[0] * qy + off[0] >= 0.0 && nx[1] * qx + ny[1] * qy + off[1] >= 0.0 &&
            nx[2] * qx + ny[2] * qy + off[2] >= 0.0)
          m |= TileRays::bit(x);
      }
      mask[y] = m;
    }
#endif
    return true;
  }

  // Tests an admitted triangle against the unfinished rays under its rectangle; false when no ray
  // was tested (all of them already hold nearer hits, or the triangle passes beside them).
  bool test_triangle(const Frame& f, int x0, int y0, const NciContext::Thread::Cand& cand, const Mask* live,
                     TileRays& r, NciContext::Thread& thread) const {
    const int stride = r.stride;  // the tile's row pitch (kept in a register)
    const std::uint32_t tri = cand.tri;
    const int rx0 = cand.rx0, ry0 = cand.ry0, rx1 = cand.rx1, ry1 = cand.ry1;
    const Mask span = TileRays::columns(rx0, rx1);
    const glm::vec3& p0 = corner(tri, 0);
    const glm::vec3& p1 = corner(tri, 1);
    const glm::vec3& p2 = corner(tri, 2);
    const float a[3] = {p0.x - f.eye_f.x, p0.y - f.eye_f.y, p0.z - f.eye_f.z};
    const float b[3] = {p1.x - f.eye_f.x, p1.y - f.eye_f.y, p1.z - f.eye_f.z};
    const float c[3] = {p2.x - f.eye_f.x, p2.y - f.eye_f.y, p2.z - f.eye_f.z};
    const float mag[3] = {std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(a[2])}),
                          std::max({std::fabs(b[0]), std::fabs(b[1]), std::fabs(b[2])}),
                          std::max({std::fabs(c[0]), std::fabs(c[1]), std::fabs(c[2])})};
    const float qlo[3] = {std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}), std::min({a[2], b[2], c[2]})};
    const float qhi[3] = {std::max({a[0], b[0], c[0]}), std::max({a[1], b[1], c[1]}), std::max({a[2], b[2], c[2]})};
    if (behind_hits(r, qlo, qhi, ry0, ry1, span, live)) return false;
    if (f.use_rect && f.affine_rays && (rx1 > rx0 || ry1 > ry0) && beside_rect(r, a, b, c, rx0, ry0, rx1, ry1)) return false;
    // Only the live rays whose pixel centres lie in the triangle's grown 2D footprint can hit it.
    Mask rows[max_tile_];
    for (int y = ry0; y <= ry1; ++y) rows[y] = live[y] & span;
    if (f.footprint) {
      Mask inside[max_tile_];
      if (footprint_mask(f, p0, p1, p2, x0, y0, ry0, ry1, rows, inside, f.tile - 1)) {
        Mask left = 0;
        for (int y = ry0; y <= ry1; ++y) left |= (rows[y] &= inside[y]);
        if (!left) return false;  // no live pixel centre can see it: not tested
      }
    }
    bool any = false;
    for (int y = ry0; y <= ry1; ++y) {
      Mask bits = rows[y];
      while (bits) {
        const int x = TileRays::low_bit(bits);
        bits &= bits - 1;
        const int i = y * stride + x;
        // The depth reject of behind_hits for this ray alone (its own scale sz on its own dominant
        // axis, the same bound and margin): a ray that already holds a solid hit strictly nearer
        // than any t the test could return is not tested. Skipping it changes no answer.
        if (r.solid_t[i] < std::numeric_limits<float>::infinity()) {
          const detail::WatertightRay<float>& w = r.wray[i];
          const double sz = w.sz;
          double bound = std::min(sz * double(qlo[w.kz]), sz * double(qhi[w.kz])) * (1.0 - 1e-6);
          if (bound > 1e-30 && std::isfinite(bound) && double(r.solid_t[i]) < bound) continue;
        }
        ++thread.stats.ray_tests;
        any = true;
        float t = 0.0f;
        bool near = false;
        const bool hit = detail::watertight_hit_band(r.wray[i], a, b, c, mag, band_, t, near);
        // Ties go to the lower mesh index (the internal numbering is not the mesh's).
        if (hit && (t < r.best_t[i] ||
                    (t == r.best_t[i] && (r.best[i] == none_ || tri_original_[tri] < tri_original_[r.best[i]])))) {
          r.best_t[i] = t;
          r.best[i] = tri;
        }
        if (near) {
          if (t <= r.solid_t[i]) thread.unsure.push_back(NciContext::Thread::Unsure{tri, t, static_cast<std::uint16_t>(i)});
        } else if (hit && (t < r.solid_t[i] || (t == r.solid_t[i] && (r.solid[i] == none_ ||
                                                                      tri_original_[tri] < tri_original_[r.solid[i]])))) {
          if (t < r.solid_t[i]) {
            r.dirty[i] = true;
            r.any_dirty = true;
          }
          r.solid_t[i] = t;
          r.solid[i] = tri;
        }
      }
    }
    return any;
  }

  // `r` is the caller's scratch (any contents): every field read below is set here first.
  void process_tile(const Frame& f, int x0, int y0, int x1, int y1, TileRays& r, NciContext::Thread& thread,
                    NciContext& context) const {
    const int tw = x1 - x0, th = y1 - y0;
    const int stride = r.stride = (tw + 3) & ~3;
    {
      // A tile beside the scene box's screen rectangle: every pixel keeps its initial depth (no
      // triangle's rectangle reaches it, so no ray of it would be tested).
      const NciContext::Rect& b = f.box_rect;
      if (b.x0 > b.x1 || (b.x0 != NciContext::Rect::full && (b.x1 < x0 || b.x0 > x1 - 1 || b.y1 < y0 || b.y0 > y1 - 1))) {
        // Written straight to the frame's buffers (no pixel state, no winner to mark).
        for (int y = 0; y < th; ++y) {
          const std::size_t row = static_cast<std::size_t>(y0 + y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(x0);
          for (std::size_t p = row; p < row + static_cast<std::size_t>(tw); ++p) {
            const float t = f.initial_depth ? f.initial_depth[p] : std::numeric_limits<float>::infinity();
            context.pixel_tri_[p] = none_;
            context.pixel_t_[p] = t;
            context.pixel_solid_t_[p] = f.initial_solid ? f.initial_solid[p] : t;
          }
        }
        return;
      }
    }
    r.any_dirty = true;
    r.beam = false;
    r.beam_eps = 0.0f;
    for (int k = 0; k < 4; ++k) r.beam_box[k] = -1;
    for (int k = 0; k < 3; ++k) r.mean_dir[k] = 0.0f;
    r.axis = f.axis;
    r.lo_a = lo_[f.axis];
    r.inv_h = 1.0 / h_;
    const int a = f.axis, b = (a + 1) % 3, c = (a + 2) % 3;
    Mask live[max_tile_] = {};  // unfinished rays, both walks
    Mask walk_mask[2][max_tile_] = {};  // [0]: toward +axis (and flat), [1]: toward -axis
    const glm::dvec3 blo = glm::dvec3(box_.min) - delta_, bhi = glm::dvec3(box_.max) + delta_;
    // The same per component in plain arrays (the per-ray loop below indexes them by a variable;
    // glm's component access is a switch), and the box relative to the eye.
    const double eye3[3] = {f.eye.x, f.eye.y, f.eye.z};
    const double blo3[3] = {blo.x, blo.y, blo.z}, bhi3[3] = {bhi.x, bhi.y, bhi.z};
    const double rlo3[3] = {blo3[0] - eye3[0], blo3[1] - eye3[1], blo3[2] - eye3[2]};
    const double rhi3[3] = {bhi3[0] - eye3[0], bhi3[1] - eye3[1], bhi3[2] - eye3[2]};
    glm::dvec3 cone_sum(0.0);
    for (int k = 0; k < 3; ++k) {
      r.sz_lo[k] = std::numeric_limits<float>::infinity();
      r.sz_hi[k] = -std::numeric_limits<float>::infinity();
    }
    for (int y = 0; y < th; ++y) {
      for (int x = tw, x_end = (tw + 3) & ~3; x < x_end; ++x) r.dx[y * stride + x] = r.dy[y * stride + x] = r.dz[y * stride + x] = 0.0f;
      const std::size_t row = static_cast<std::size_t>(y0 + y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(x0);
      const float* initial_depth = f.initial_depth ? f.initial_depth + row : nullptr;
      const float* initial_solid = f.initial_solid ? f.initial_solid + row : nullptr;
      f.rays.directions(x0, y0 + y, tw, &r.dx[y * stride], &r.dy[y * stride], &r.dz[y * stride]);
      for (int x = 0; x < tw; ++x) {
        const int i = y * stride + x;
        const glm::vec3 direction(r.dx[i], r.dy[i], r.dz[i]);
        const double d3[3] = {direction.x, direction.y, direction.z};
        r.dir_a[i] = static_cast<float>(d3[a]);
        r.best_t[i] = initial_depth ? initial_depth[x] : std::numeric_limits<float>::infinity();
        r.best[i] = none_;
        r.solid_t[i] = initial_solid ? initial_solid[x] : r.best_t[i];
        r.solid[i] = none_;
        r.dirty[i] = true;
        // WatertightRay::make's validity (finite, not zero) without its shear: a ray that misses
        // the scene box is never tested, only its validity is read (make_beam's corners).
        // (the 1-norm in double cannot overflow; it is NaN or infinite iff a component is).
        const double norm1 = std::fabs(d3[0]) + std::fabs(d3[1]) + std::fabs(d3[2]);
        r.wray[i].valid = norm1 > 0.0 && norm1 < std::numeric_limits<double>::infinity();
        if (!r.wray[i].valid) continue;
        // Does the ray reach the (inflated) scene box at all? Entry and exit per axis (the face
        // by the direction's sign: rlo <= rhi, so that is the smaller and the larger of the two
        // products), each widened by a relative 1e-9. The widening x -> x -/+ 1e-9 |x| is
        // monotone (also after rounding), so it is applied once to the largest entry and the
        // smallest exit: the same values as widening every axis's, in fewer instructions.
        double enter = 0.0, leave = std::numeric_limits<double>::infinity();
        double inv3[3] = {0.0, 0.0, 0.0};
        bool hit = true;
        if (d3[0] != 0.0 && d3[1] != 0.0 && d3[2] != 0.0) {
          for (int k = 0; k < 3; ++k) {  // branch-free: min / max instructions
            const double inv = inv3[k] = 1.0 / d3[k];
            const double t0 = rlo3[k] * inv, t1 = rhi3[k] * inv;
            enter = std::max(enter, std::min(t0, t1));
            leave = std::min(leave, std::max(t0, t1));
          }
        } else {
          for (int k = 0; k < 3; ++k) {
            if (d3[k] == 0.0) {
              hit = hit && !(eye3[k] < blo3[k] || eye3[k] > bhi3[k]);
              continue;
            }
            const double inv = inv3[k] = 1.0 / d3[k];
            const double t0 = rlo3[k] * inv, t1 = rhi3[k] * inv;
            enter = std::max(enter, std::min(t0, t1));
            leave = std::min(leave, std::max(t0, t1));
          }
        }
        const double tmin = enter - 1e-9 * std::fabs(enter), tmax = leave + 1e-9 * std::fabs(leave);
        if (!hit || tmin > tmax) continue;
        r.wray[i] = detail::WatertightRay<float>::make(direction);
        r.t_exit[i] = static_cast<float>(tmax * (1.0 + 1e-6)) * (1.0f + 1e-6f);
        const double da = d3[a];
        r.flat[i] = std::fabs(da) < 1e-6;
        // Slopes by the reciprocal the box test took (inv3[a] is 1 / da when not flat): within a
        // double rounding of the quotient, far inside the float rounding the beam allows for.
        r.slope_b[i] = r.flat[i] ? 0.0f : static_cast<float>(d3[b] * inv3[a]);
        r.slope_c[i] = r.flat[i] ? 0.0f : static_cast<float>(d3[c] * inv3[a]);
        live[y] |= TileRays::bit(x);
        const detail::WatertightRay<float>& w = r.wray[i];
        r.sz_lo[w.kz] = std::min(r.sz_lo[w.kz], w.sz);
        r.sz_hi[w.kz] = std::max(r.sz_hi[w.kz], w.sz);
        walk_mask[da >= 0.0 ? 0 : 1][y] |= TileRays::bit(x);
        cone_sum += glm::dvec3(d3[0], d3[1], d3[2]);
      }
    }
    bool any = false;
    for (int y = 0; y < th; ++y) any = any || live[y] != 0;
    if (!any) {
      write_tile(f, r, x0, y0, tw, th, context, thread);
      return;
    }

    make_beam(r, tw, th, live);

    // Classes that may face some ray of the tile: skip a class only when every normal of its cone
    // and every live ray direction make an angle below 90 degrees (a back face for all of them).
    auto& active = thread.active_classes;
    active.clear();
    {
      const double len = glm::length(cone_sum);
      double cos_psi = -1.0;
      glm::dvec3 axis(0.0);
      if (len > 1e-12) {
        axis = cone_sum / len;
        for (int j = 0; j < 3; ++j) r.mean_dir[j] = static_cast<float>(axis[j]);
        cos_psi = 1.0;
        for (int y = 0; y < th; ++y)
          for (int x = 0; x < tw; ++x)
            if (live[y] & (TileRays::bit(x))) cos_psi = std::min(cos_psi, glm::dot(axis, r.direction(y * stride + x)));
      }
      const double psi = std::acos(std::clamp(cos_psi, -1.0, 1.0)) + 2e-3;
      const bool can_skip = psi < 1.5707963267948966;
      const double sp = std::sin(psi), cp = std::cos(psi);
      for (std::size_t k = 0; k < class_axis_.size(); ++k) {
        bool skip = false;
        if (can_skip && class_sin_[k] <= 1.0f) {
          // angle(axis_k, tile axis) < 90 - theta - psi  <=>  dot > sin(theta + psi), if theta + psi < 90.
          const double st = class_sin_[k], ct = class_cos_[k];
          const double cos_sum = ct * cp - st * sp;  // cos(theta + psi)
          if (cos_sum > 0.0) {
            const double sin_sum = st * cp + ct * sp;
            skip = glm::dot(glm::dvec3(class_axis_[k]), axis) > sin_sum + 1e-6;
          }
        }
        if (!skip) active.push_back(static_cast<std::uint16_t>(k));
      }
    }

    if (++thread.stamp_value == 0) {
      for (auto& t : thread.tri) t.stamp = 0u;
      thread.stamp_value = 1;
    }
    const std::uint32_t stamp = thread.stamp_value;
    const double ea = f.eye[a], eb = f.eye[b], ec = f.eye[c];
    const int na = dims_[a], nb = dims_[b], nc = dims_[c];

    std::size_t met = 0;  // NciSelectStats::triangles_met of this tile (a local: the visit loop is hot)
    for (int walk = 0; walk < 2; ++walk) {
      Mask* mask = walk_mask[walk];
      const int step = walk == 0 ? 1 : -1;
      const int start = cell_of(ea, a);
      // The beam's slopes change only when rays finish; the finish test runs only when a ray's
      // hit improved or the walk reaches the earliest finishing slice (`next_finish`).
      r.any_dirty = true;
      int next_finish = start;
      bool slopes_stale = true, full = false;
      float smin_b = 0.0f, smax_b = 0.0f, smin_c = 0.0f, smax_c = 0.0f;
      for (int s = start; s >= 0 && s < na; s += step) {
        Mask unfinished = 0;  // any ray of this walk still live
        for (int y = 0; y < th; ++y) unfinished |= mask[y];
        if (!unfinished) break;
        ++thread.stats.slices_walked;
        // The part of the slab this walk's rays cross, inflated like the cells.
        double s0 = lo_[a] + s * h_ - delta_, s1 = lo_[a] + (s + 1) * h_ + delta_;
        if (walk == 0) s0 = std::max(s0, ea);
        else s1 = std::min(s1, ea);
        if (s0 <= s1) {
          // Beam of the walk's unfinished rays across [s0, s1].
          double bmin = std::numeric_limits<double>::infinity(), bmax = -bmin, cmin = bmin, cmax = -bmin;
          if (slopes_stale) {
            slopes_stale = false;
            full = false;
            smin_b = std::numeric_limits<float>::infinity();
            smax_b = -smin_b;
            smin_c = smin_b;
            smax_c = -smin_b;
            for (int y = 0; y < th; ++y) {
              Mask bits = mask[y];
              while (bits) {
                const int x = TileRays::low_bit(bits);
                bits &= bits - 1;
                const int i = y * stride + x;
                if (r.flat[i]) full = true;
                smin_b = std::min(smin_b, r.slope_b[i]);
                smax_b = std::max(smax_b, r.slope_b[i]);
                smin_c = std::min(smin_c, r.slope_c[i]);
                smax_c = std::max(smax_c, r.slope_c[i]);
              }
            }
          }
          int rlo = 0, rhi = nb - 1, clo = 0, chi = nc - 1;
          if (!full) {
            const double ends[2] = {s0 - ea, s1 - ea};
            for (double e : ends) {
              bmin = std::min({bmin, eb + e * double(smin_b), eb + e * double(smax_b)});
              bmax = std::max({bmax, eb + e * double(smin_b), eb + e * double(smax_b)});
              cmin = std::min({cmin, ec + e * double(smin_c), ec + e * double(smax_c)});
              cmax = std::max({cmax, ec + e * double(smin_c), ec + e * double(smax_c)});
            }
            // Slopes were rounded to float: widen by their relative error over the slab's reach.
            const double reach = std::max(std::fabs(ends[0]), std::fabs(ends[1]));
            const double wb = delta_ + 1e-6 * reach * (1.0 + std::max(std::fabs(double(smin_b)), std::fabs(double(smax_b))));
            const double wc = delta_ + 1e-6 * reach * (1.0 + std::max(std::fabs(double(smin_c)), std::fabs(double(smax_c))));
            bmin -= wb;
            bmax += wb;
            cmin -= wc;
            cmax += wc;
            if (bmax < lo_[b] || cmax < lo_[c] || bmin > lo_[b] + nb * h_ || cmin > lo_[c] + nc * h_) {
              rlo = 1;
              rhi = 0;  // beam outside the box in this slice
            } else {
              rlo = cell_of(bmin, b);
              rhi = cell_of(bmax, b);
              clo = cell_of(cmin, c);
              chi = cell_of(cmax, c);
            }
          }
          if (rlo <= rhi && clo <= chi) {
            for (std::uint16_t k : active) {
              const std::size_t base = grid_base_[static_cast<std::size_t>(k) * 3 + static_cast<std::size_t>(a)];
              const std::uint32_t shift = grid_shift_[static_cast<std::size_t>(k) * 3 + static_cast<std::size_t>(a)];
              const std::uint32_t class_base = class_cell_base_[k];
              const std::uint32_t row_first = slice_rows_[base + static_cast<std::size_t>(s)];
              const std::uint32_t row_last = slice_rows_[base + static_cast<std::size_t>(s) + 1];
              // Rows are sorted: a class whose rows in this slice all lie outside [rlo, rhi] is
              // passed over without a search.
              if (row_first == row_last || row_coord_[row_first] > rhi || row_coord_[row_last - 1] < rlo) continue;
              auto row_it = row_coord_[row_first] >= rlo
                                ? row_coord_.begin() + row_first
                                : std::lower_bound(row_coord_.begin() + row_first, row_coord_.begin() + row_last,
                                                   static_cast<std::uint16_t>(rlo));
              for (; row_it != row_coord_.begin() + row_last && *row_it <= rhi; ++row_it) {
                const std::size_t row = static_cast<std::size_t>(row_it - row_coord_.begin());
                const std::uint32_t cf = row_begin_[row], cl = row_begin_[row + 1];
                if (cell_col_[cf] > chi || cell_col_[cl - 1] < clo) continue;  // sorted columns, none in range
                auto cell_it = cell_col_[cf] >= clo ? cell_col_.begin() + cf
                                                    : std::lower_bound(cell_col_.begin() + cf, cell_col_.begin() + cl,
                                                                       static_cast<std::uint16_t>(clo));
                for (; cell_it != cell_col_.begin() + cl && *cell_it <= chi; ++cell_it) {
                  const std::uint32_t pos = static_cast<std::uint32_t>(cell_it - cell_col_.begin());
                  const std::uint32_t cell = a == 0     ? pos - shift
                                             : wide_ids_ ? cell_id_[pos - shift]
                                                         : class_base + cell_id16_[pos - shift];
                  ++thread.stats.cells_visited;
                  std::uint32_t e, e_end;
                  if (cell_begin16_.empty()) {
                    e = cell_tri_begin_[cell];
                    e_end = cell_tri_begin_[cell + 1];
                  } else {
                    e = class_entry_base_[k] + cell_begin16_[cell + k];
                    e_end = class_entry_base_[k] + cell_begin16_[cell + k + 1];
                  }
                  auto visit = [&](std::uint32_t tri) {
                    if (thread.tri[tri].stamp == stamp) return;
                    thread.tri[tri].stamp = stamp;
                    ++met;
                    NciContext::Thread::Cand cand;
                    if (admit_triangle(f, tri, x0, y0, tw, th, live, r, thread, cand)) thread.cand.push_back(cand);
                  };
                  const std::uint32_t tri_base = class_tri_begin_[k];
                  while (e < e_end) {
                    std::uint32_t part_end = e_end;
                    if (!chunk_box_.empty() && r.beam) {
                      const std::uint32_t j = e / static_cast<std::uint32_t>(chunk_);
                      part_end = std::min(e_end, (j + 1) * static_cast<std::uint32_t>(chunk_));
                      if (chunk_outside_beam(r, &chunk_box_[6 * std::size_t{j}], f) ||
                          chunk_hidden(f, j, x0, y0, tw, th, live, r, thread)) {
                        e = part_end;
                        continue;
                      }
                    }
                    if (wide_tris_) {
                      for (; e < part_end; ++e) visit(cell_tris_[e]);
                    } else {
                      for (; e < part_end; ++e) visit(tri_base + cell_tris16_[e]);
                    }
                  }
                }
              }
            }
            // Nearest first, so hits found early let behind_hits drop the triangles behind them.
            if (!thread.cand.empty()) {
              std::sort(thread.cand.begin(), thread.cand.end(), [](const auto& p, const auto& q) {
                return p.key != q.key ? p.key < q.key : p.tri < q.tri;
              });
              for (const auto& cand : thread.cand)
                if (test_triangle(f, x0, y0, cand, live, r, thread)) {
                  ++thread.tested_count;
                  thread.tested_bits[cand.tri / 64] |= std::uint64_t{1} << (cand.tri % 64);
                }
              thread.cand.clear();
            }
          }
        }
        // Finish the rays whose nearest hit lies before the next slice (with margins that only
        // keep rays unfinished longer). Nothing to do while no hit improved and no ray's finishing
        // slice is reached.
        if (!r.any_dirty && (walk == 0 ? s < next_finish : s > next_finish)) continue;
        r.any_dirty = false;
        next_finish = walk == 0 ? na : -1;
        for (int y = 0; y < th; ++y) {
          Mask bits = mask[y];
          while (bits) {
            const int x = TileRays::low_bit(bits);
            bits &= bits - 1;
            const int i = y * stride + x;
            if (r.dirty[i]) {
              r.finish[i] = finish_slice(r, i, walk, s, ea, na);
              r.dirty[i] = false;
            }
            const bool done = walk == 0 ? s >= r.finish[i] : s <= r.finish[i];
            if (done) {
              mask[y] &= ~TileRays::bit(x);
              live[y] &= ~TileRays::bit(x);
              slopes_stale = true;
            } else {
              next_finish = walk == 0 ? std::min(next_finish, r.finish[i]) : std::max(next_finish, r.finish[i]);
            }
          }
        }
        if (slopes_stale) narrow_beam(r, tw, th, live);
      }
      for (int y = 0; y < th; ++y) {  // a walk that ran out of slices finishes its rays
        live[y] &= ~mask[y];
        mask[y] = 0;
      }
    }
    thread.stats.triangles_met += met;
    // Beside each pixel's first hit: the triangles within rounding of an edge in front of its
    // solid hit, and that solid hit itself.
    const auto global = [&](int i) {
      return static_cast<std::uint32_t>(y0 + i / stride) * static_cast<std::uint32_t>(f.width) +
             static_cast<std::uint32_t>(x0 + i % stride);
    };
    const auto show = [&](std::uint32_t tri) { thread.shown_bits[tri / 64] |= std::uint64_t{1} << (tri % 64); };
    for (const auto& u : thread.unsure) {
      if (u.t <= r.solid_t[u.pixel] && u.tri != r.best[u.pixel]) {
        thread.extra.push_back(NciContext::Extra{u.tri, u.t, global(u.pixel)});
        show(u.tri);
      }
    }
    thread.unsure.clear();
    for (int y = 0; y < th; ++y)
      for (int x = 0; x < tw; ++x) {
        const int i = y * stride + x;
        if (r.solid[i] != none_ && r.solid[i] != r.best[i]) {
          thread.extra.push_back(NciContext::Extra{r.solid[i], r.solid_t[i], global(i)});
          show(r.solid[i]);
        }
      }
    write_tile(f, r, x0, y0, tw, th, context, thread);
  }

  // The first slice (in walk order, from `from`) after which ray i may stop: its nearest solid
  // hit (or the box exit: nothing lies beyond) comes before where it enters the next slice, with
  // margins that only keep it longer (the predicate `done` below; the last slice of a walk always
  // qualifies). Rays exactly parallel to the slices never reach another slice. The predicate is
  // monotone along the walk; an estimate from the stop coordinate is corrected by the predicate
  // itself, so the answer is exactly the first slice where it holds. The predicate's per-ray parts
  // (stop coordinate and margin) are computed once, not per evaluation.
  [[nodiscard]] int finish_slice(const TileRays& r, int i, int walk, int from, double ea, int na) const noexcept {
    const int end = walk == 0 ? na - 1 : 0;
    if (r.dir_a[i] == 0.0f) return from;
    const float t_stop = std::min(r.solid_t[i], r.t_exit[i]);
    const double reach = double(t_stop) * (1.0 + 1e-5) * double(r.dir_a[i]);
    const double pos = ea + reach;
    const double margin = 0.25 * delta_ - 1e-6 * std::fabs(reach);
    const auto done = [&](int k) {
      if (walk == 0 ? k + 1 >= na : k <= 0) return true;
      const double next_plane = walk == 0 ? r.lo_a + (k + 1) * h_ : r.lo_a + k * h_;
      return walk == 0 ? pos < next_plane + margin : pos > next_plane - margin;
    };
    int s = from;
    const double x = ea + double(t_stop) * double(r.dir_a[i]);
    if (std::isfinite(x)) {
      // Any start gives the same answer (the loops below correct it); starting at the slice
      // holding the stop point usually needs two evaluations of the predicate.
      const double cell = std::clamp((x - r.lo_a) * r.inv_h, -2.0, double(na) + 2.0);
      // The slice holding the stop point: floor (cell is clamped, so an int holds it; no libm
      // call without SSE4.1).
      int cut = static_cast<int>(cell);
      if (double(cut) > cell) --cut;
      const double est = cut;
      if (walk == 0 && est > from) s = static_cast<int>(std::min(est, double(end)));
      if (walk == 1 && est < from) s = static_cast<int>(std::max(est, double(end)));
    } else {
      s = end;
    }
    const int step = walk == 0 ? 1 : -1;
    // Back up while the previous slice already qualifies, then move on until this one does.
    while (s != from && done(s - step)) s -= step;
    while (s != end && !done(s)) s += step;
    return s;
  }

  static void write_tile(const Frame& f, const TileRays& r, int x0, int y0, int tw, int th, NciContext& context,
                         NciContext::Thread& thread) {
    const int stride = r.stride;  // the tile's row pitch (kept in a register)
    const std::size_t width = static_cast<std::size_t>(f.width);
    for (int y = 0; y < th; ++y) {
      for (int x = 0; x < tw; ++x) {
        const std::size_t p = static_cast<std::size_t>(y0 + y) * width + static_cast<std::size_t>(x0 + x);
        context.pixel_tri_[p] = r.best[y * stride + x];
        context.pixel_t_[p] = r.best_t[y * stride + x];
        context.pixel_solid_t_[p] = r.solid_t[y * stride + x];
        const std::uint32_t tri = r.best[y * stride + x];
        if (tri != none_) thread.shown_bits[tri / 64] |= std::uint64_t{1} << (tri % 64);
      }
    }
  }

  NciParams params_;
  NciStats stats_;
  Aabb box_ = Aabb::empty();
  glm::dvec3 lo_{0.0};
  double h_ = 1.0;
  double delta_ = 0.0;
  int dims_[3] = {1, 1, 1};
  std::vector<glm::vec3> vertices_;
  std::vector<std::uint32_t> tri_vertices_;   // 3 per kept triangle, into vertices_, or empty:
  std::vector<std::uint16_t> tri_vertices16_; // the same in 16 bits (at most 65536 vertices)
  std::vector<std::uint32_t> tri_original_;   // internal triangle -> mesh triangle
  std::vector<std::uint16_t> class_of_;       // mesh triangle -> class, skipped_class_ when skipped
  std::vector<std::uint32_t> class_tri_begin_;  // classes + 1: each class's run of internal ids
  std::vector<glm::vec3> class_axis_;
  std::vector<float> class_sin_, class_cos_;  // cone half-angle (with margin); sin > 1: never skip
  std::vector<std::uint32_t> cell_tri_begin_; // cells + 1, or empty:
  std::vector<std::uint16_t> cell_begin16_;   // cells + classes: ranges relative to the class's entries
  std::vector<std::uint32_t> class_entry_base_;  // per class: its first entry (with cell_begin16_)
  // Internal triangle ids per cell (ascending within a cell): class-local in 16 bits (plus
  // class_tri_begin_) unless some class has more than 65536 triangles (wide_tris_): then global in
  // 32 bits.
  std::vector<std::uint32_t> cell_tris_;
  std::vector<std::uint16_t> cell_tris16_;
  bool wide_tris_ = false;
  // Chunk boxes (min xyz, max xyz) of every chunk_ consecutive cell entries, or empty when the
  // cells hold fewer than chunk_min_mean_ entries on average (a box would not pay for itself).
  static constexpr std::size_t chunk_ = 16;
  static constexpr std::size_t chunk_min_mean_ = 8;
  std::vector<float> chunk_box_;
  std::vector<std::uint32_t> grid_base_;      // (class, axis) -> first entry in slice_rows_
  std::vector<std::uint32_t> slice_rows_;     // per grid dims[axis] + 1 row offsets
  std::vector<std::uint16_t> row_coord_;
  std::vector<std::uint32_t> row_begin_;      // rows + 1 (global sentinel)
  std::vector<std::uint16_t> cell_col_;
  // Cells of the Y and Z grids' entries (X grids list cells in id order and need none): the
  // class's own cell number in 16 bits, added to class_cell_base_, unless some class has more
  // than 65536 cells (wide_ids_): then the global cell in 32 bits.
  std::vector<std::uint32_t> cell_id_;
  std::vector<std::uint16_t> cell_id16_;
  std::vector<std::uint32_t> class_cell_base_;  // per class: its first cell (0 when wide_ids_)
  std::vector<std::uint32_t> grid_shift_;  // (class, axis): X: cell = position - shift; else id at position - shift
  bool wide_ids_ = false;
  // Width of the ray test's edge band (detail::watertight_hit_band) in units of the coordinates.
  float band_ = detail::edge_band_units * 0x1p-24f;
};

}  // namespace cullkit
