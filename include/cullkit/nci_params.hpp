// cullkit/nci_params.hpp: the value types of NormalClassIndex's interface: its parameters, results,
// statistics and moving objects. cullkit/normal_class_index.hpp includes this.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>

#include "task_runner.hpp"

namespace cullkit {

/// Which path serves the screen tiles of a select_visible call (`NciParams::crowded_path`): the
/// near-to-far walk of the grid, or casting the tiles' rays through the index's one hierarchy over
/// all its triangles. Both give the same per-pixel answer and set; they differ in cost (and in
/// `VisibleSet::triangles_tested`).
enum class NciCrowdedPath : std::uint8_t {
  automatic,  ///< per frame: the hierarchy for crowded views seen from outside the scene box, else the walk,
              ///< a tile's walk handing its unfinished rays to the hierarchy where it meets many triangles
  walk_only,  ///< always the walk; the index then builds no hierarchy (less build time and memory)
  rays_only,  ///< always the hierarchy
};

/// Configuration of a NormalClassIndex. Every field has a usable default.
struct NciParams {
  /// Normal classes (k of the spherical k-means). More classes: tighter cones, so more classes are
  /// skipped per tile, but more grids to search. The seed measures 32, 128 and 512. Clamped to
  /// [1, 4096]; classes that end up empty are dropped.
  int classes = 32;
  /// Cells along the scene box's longest axis (cubic cells). Finer: fewer triangles met per tile
  /// (not fewer tested: the screen rectangles already keep the tests down), more memory, and more
  /// cells and slices to walk. Clamped to [1, 4096]. The trade-off is measured in docs/nci.md.
  int grid = 32;
  /// Worker threads for select_visible; 0: all hardware threads. Never changes the result. The
  /// threads come from the library's persistent pool (started on first use, never per call) or,
  /// with `task_runner`, from the caller's job system; 1 runs on the calling thread only.
  unsigned threads = 0;
  /// Worker threads for the build (per class, and the hierarchy's subtrees); 0: all hardware
  /// threads, 1: the calling thread only. Never changes the index.
  unsigned build_threads = 0;
  /// Where the parallel work runs, the build's and select_visible's: the tasks (select_visible:
  /// `threads` of them, 0 as many as hardware threads, at most one per screen tile) are handed to
  /// `task_runner.dispatch` when it is set, else to the library's pool. Each select task owns one
  /// worker's scratch in the NciContext and pulls screen tiles from a shared counter, so the
  /// answer (and the index) is the same however the tasks are run.
  TaskRunner task_runner{};
  /// Screen tile edge in pixels, clamped to [2, 64]; 0 (the default): 64 for screens of at least
  /// 640x480 pixels, 32 below. Each tile walks the slices on its own and pays the per-triangle work
  /// (cell entry visits, screen-rectangle tests) once, so bigger tiles amortize it over more pixels;
  /// the answer (per-pixel triangle and depth, selected set) does not depend on it, the count of
  /// ray-tested triangles does. The trade-off is measured in docs/nci.md.
  int tile_size = 0;
  /// Seed of the k-means (sampling and re-seeding of empty classes). Same seed, same index.
  std::uint64_t seed = 0x6e63692d6b6dULL;
  /// Optional build progress report, called with a fraction in [0, 1] (monotone, 1 at the end),
  /// from one thread at a time: the building thread, unless `task_runner` runs the build's first
  /// task on another. `progress_user` is passed through. nullptr: no reports.
  void (*progress)(float fraction, void* user) = nullptr;
  /// Passed to `progress` unchanged.
  void* progress_user = nullptr;
  /// Which path serves a frame's tiles (see NciCrowdedPath). Never changes the answer. The build
  /// keeps the hierarchy whatever this says (about 16 bytes per triangle). `automatic` casts a frame
  /// when the eye is outside the scene box and the index holds at least 0.75 triangles per pixel of
  /// the box's screen rectangle, where it measured faster than the walk (see docs/nci.md); in a
  /// walked frame, a tile whose walk has met more than 4 triangles per live ray casts its unfinished
  /// rays through the hierarchy from the hits the walk found.
  NciCrowdedPath crowded_path = NciCrowdedPath::automatic;
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
  /// through a BVH does less work.
  std::size_t triangles_no_pixel = 0;
  std::size_t cells_walked = 0;    ///< (tile, cell) pairs served by the near-to-far walk
  std::size_t tiles_ray_cast = 0;  ///< tiles whose rays were cast through the triangle hierarchy (from the start, or
                                   ///< after their walk met too many triangles)
  int axis = 0;                    ///< grid axis walked
  /// Moving objects whose transform could not be used (singular, NaN or infinite, or projective;
  /// see NciMovingObject): each was reported whole and hid nothing.
  std::size_t moving_objects_rejected = 0;
};

/// A moving object for NormalClassIndex::select_visible: an index of its triangles in its local
/// frame, an affine transform to the world, and the id it is reported with.
template <class ObjectIndex>
struct NciMovingObject {
  const ObjectIndex* index = nullptr;  ///< not owned; must outlive the call
  /// Any invertible affine map (column vectors, bottom row exactly 0, 0, 0, 1): rotation,
  /// translation, scale (non-uniform too), shear, mirror. On a mirrored object the faces that
  /// count are those facing the eye in the local frame. A NaN, infinite, projective, singular or
  /// badly conditioned (above 1e6) matrix makes the object reported whole (see select_visible).
  glm::mat4 local_to_world{1.0f};
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

}  // namespace cullkit
