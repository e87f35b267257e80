// cullkit/normal_class_index.hpp: NormalClassIndex, pixel-driven near-to-far selection of the
// triangles a camera sees (seed: Wei, Wang, Wu, "Fast selecting visible surfaces in high
// precision", Journal of Software 17(10), 2006, with the corrections docs/nci_internals.md lists).
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
// the surface: its plane within 2^-20 of the farthest corner's distance from the eye) gets noise from
// the float ray test, up to hits at depth about 0 on rays the exact geometry sends away from it. The
// index keeps such hits only where its exact rejections (class cones, beams, screen rectangles, edge
// planes) allow them, so there its answer may differ from a plain float ray caster's and may depend
// on the grid and tile size (never on the thread count). Elsewhere it equals the float test's.
#pragma once

#include <algorithm>
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
#include "geometry/aabb.hpp"
#include "geometry/camera.hpp"
#include "task_runner.hpp"
#include "mesh_buffers.hpp"
#include "traits.hpp"
#include "detail/nci/context.hpp"
#include "detail/nci/core.hpp"
#include "detail/nci/degenerate_camera.hpp"
#include "detail/nci/index_data.hpp"
#include "detail/nci/moving.hpp"
#include "nci_params.hpp"

namespace cullkit {

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
  /// nothing. pre: mesh.vertices != nullptr when vertex_count > 0, mesh.indices likewise (asserted
  /// in debug builds; a null pointer is read as an empty buffer in release builds).
  explicit NormalClassIndex(MeshView<Vertex, Index> mesh, const NciParams& params = {}) {
    mesh = detail::checked_mesh(mesh);
    const Vertex* vertices = mesh.vertices;
    const Index* indices = mesh.indices;
    construct([vertices](std::size_t i) { return glm::vec3(Traits::position(vertices[i])); }, mesh.vertex_count,
              [indices](std::size_t i) { return widen_index(indices[i]); }, mesh.index_count, params);
  }

  /// Builds the index from raw buffers: positions through a pointer and a byte stride, indices of
  /// a width chosen at run time (see StridedMesh). Same skipping rules and the same index (hence
  /// the same answers) as the MeshView constructor given the same positions and indices; `Vertex`
  /// and `Index` are not read. pre: as StridedMesh's (asserted in debug builds; null buffers are
  /// read as empty in release builds).
  explicit NormalClassIndex(const StridedMesh& mesh, const NciParams& params = {}) {
    const StridedMesh m = detail::checked_mesh(mesh);
    construct([&m](std::size_t i) { return m.positions(static_cast<std::uint32_t>(i)); }, m.vertex_count,
              [&m](std::size_t i) { return std::uint64_t{m.indices[i]}; }, m.indices.count, params);
  }

  /// Builds the index from positions read through a pointer and a byte stride (an interleaved
  /// vertex buffer: three floats at `positions.base + i * stride_bytes + offset_bytes`, any
  /// alignment) and `index_count` indices (3 per triangle) of this index's `Index` type, which may
  /// be 16 or 32 bits. Same skipping rules and answers as the MeshView constructor; `Vertex` is not
  /// read. pre: positions.base != nullptr when vertex_count > 0, indices != nullptr when
  /// index_count > 0. For an index width chosen at run time, use the StridedMesh constructor.
  NormalClassIndex(const StridedPositions& positions, std::size_t vertex_count, const Index* indices,
                   std::size_t index_count, const NciParams& params = {}) {
    CULLKIT_ASSERT(positions.base != nullptr || vertex_count == 0, "positions present when vertex_count > 0");
    CULLKIT_ASSERT(indices != nullptr || index_count == 0, "indices present when index_count > 0");
    if (positions.base == nullptr) vertex_count = 0;
    if (indices == nullptr) index_count = 0;
    construct([&positions](std::size_t i) { return positions(static_cast<std::uint32_t>(i)); }, vertex_count,
              [indices](std::size_t i) { return widen_index(indices[i]); }, index_count, params);
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
  /// A camera with a non-positive width or height gives an empty set (no pixel sees anything). A
  /// degenerate camera (a NaN or infinite eye; a NaN, infinite or singular matrix), whose pixel
  /// rays are undefined, gives every kept triangle (nothing can be decided, so nothing is hidden)
  /// with no triangle tested and every pixel a miss. Allocates a context.
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
    if (camera.width > 0 && camera.height > 0 && detail::nci::degenerate_camera(camera))
      return detail::nci::select_everything(data_, camera, context, out, pixels);
    detail::nci::select_frame(data_, detail::nci::frame_camera(camera), context, out, pixels, nullptr, nullptr);
  }

  /// With moving objects: each object has its own index, built in its local frame, and an affine
  /// `local_to_world` transform (any invertible one: rotation, translation, uniform or non-uniform
  /// scale, shear, mirror). The objects are selected first, each with the camera taken into its
  /// local frame (the pixel rays mapped by the inverse transform, so ray parameters t stay those of
  /// the world; depths are brought back to the unit world pixel ray); then the static scene, whose
  /// pixels stay unfinished but start from the objects' depths, so only static triangles in front
  /// of the objects are searched. `out` holds the static triangles; `object_triangles` (cleared
  /// first) the objects' visible triangles as sorted unique (object id, triangle) pairs. `pixels`,
  /// when given, holds static triangle ids, or for a pixel won by an object NciPixels::miss with
  /// the object's world depth. Edge bands (see above) span objects and scene: an object's triangle
  /// is reported where it lies no farther than its pixel's first hit outside every band, whichever
  /// mesh that hit belongs to.
  /// Faces: an object's triangle counts where it faces the eye in the object's own frame. For a
  /// mirrored transform (negative determinant) that is the world back face of the moved triangle:
  /// the faces an engine draws when it flips its cull mode for such a transform, so a mirrored
  /// closed mesh still shows its outside.
  /// Transforms that cannot be used (a NaN or infinite entry, a bottom row other than (0, 0, 0, 1),
  /// a singular linear part or one with condition number above 1e6, or one that takes the eye
  /// beyond float range in the object's frame) are rejected: the object is reported whole (every
  /// triangle its index kept), hides nothing, and is counted in `context.stats.moving_objects_rejected`. A degenerate camera (see select_visible) reports the
  /// static scene and every object whole.
  /// pre: every `objects[k].index` is not null. Allocates a second context inside `context`.
  template <class ObjectIndex>
  void select_visible(const Camera& camera, const NciMovingObject<ObjectIndex>* objects, std::size_t object_count,
                      NciContext& context, VisibleSet& out, std::vector<NciObjectTriangle>& object_triangles,
                      NciPixels* pixels = nullptr) const {
    // An object's index is selected in its own frame through its data (another NormalClassIndex).
    const auto object_data = [](const ObjectIndex& index) -> const detail::nci::IndexData& { return index.data_; };
    detail::nci::select_with_objects(data_, camera, objects, object_count, object_data, context, out, object_triangles,
                                     pixels);
  }

 public:
  /// Build statistics (skipped triangles, classes, cells, build time).
  [[nodiscard]] const NciStats& stats() const noexcept { return data_.stats; }
  /// Bytes held by the index (capacity of every array).
  [[nodiscard]] std::size_t memory_bytes() const noexcept { return sizeof(*this) - sizeof(data_) + data_.memory_bytes(); }
  /// Triangles kept by the build.
  [[nodiscard]] std::size_t triangle_count() const noexcept { return data_.triangle_count(); }
  /// Normal class of a kept triangle, by the mesh's numbering; -1 for a skipped triangle.
  [[nodiscard]] int triangle_class(std::uint32_t mesh_triangle) const noexcept {
    const auto& class_of = data_.class_of;
    if (mesh_triangle >= class_of.size() || class_of[mesh_triangle] == detail::nci::skipped_class) return -1;
    return static_cast<int>(class_of[mesh_triangle]);
  }
  /// Number of (non-empty) normal classes.
  [[nodiscard]] std::size_t class_count() const noexcept { return data_.class_axis.size(); }
  /// The parameters in use (after clamping).
  [[nodiscard]] const NciParams& params() const noexcept { return data_.params; }
  /// The scene box (of the kept triangles); Aabb::empty() when nothing was kept.
  [[nodiscard]] Aabb bounds() const noexcept { return data_.box; }

 private:
  template <class, class, class>
  friend class NormalClassIndex;  // for the moving objects' indexes

  // Clamps the parameters, gathers the triangles and builds; times the whole.
  // An index as an unsigned 64-bit value; a negative one (signed Index) becomes out of range.
  template <class I>
  [[nodiscard]] static std::uint64_t widen_index(I i) noexcept {
    if constexpr (std::is_signed_v<I>) {
      if (i < 0) return ~std::uint64_t{0};
    }
    return static_cast<std::uint64_t>(i);
  }

  template <class Position, class IndexAt>
  void construct(const Position& position, std::size_t vertex_count, const IndexAt& index_at, std::size_t index_count,
                 const NciParams& params) {
    NciParams& p = data_.params = params;
    p.classes = std::clamp(p.classes, 1, 4096);
    p.grid = std::clamp(p.grid, 1, 4096);
    if (p.tile_size != 0) p.tile_size = std::clamp(p.tile_size, 2, detail::nci::TileState::max_tile);
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<glm::vec3> normals;
    gather(position, vertex_count, index_at, index_count, normals);
    detail::nci::build(data_, normals);
    data_.stats.build_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  // The valid triangles into data_ (vertices deduplicated through a remap) and their unit
  // normals; the skipped ones counted. `position(i)`: vertex i's position, for i < vertex_count;
  // `index_at(i)`: index i widened to 64 bits (out of range when negative). The only step that
  // reads the user's types.
  template <class Position, class IndexAt>
  void gather(const Position& position, std::size_t vertex_count, const IndexAt& index_at, std::size_t index_count,
              std::vector<glm::vec3>& normals) {
    detail::nci::IndexData& data = data_;
    data.stats.triangles_input = index_count / 3;
    detail::nci::report(data, 0.0f);
    std::vector<std::uint32_t> remap;
    // Room for every triangle up front (most meshes keep nearly all): no regrowth copies on large
    // meshes. The build trims what it keeps.
    data.tri_vertices.reserve(3 * data.stats.triangles_input);
    data.tri_original.reserve(data.stats.triangles_input);
    data.vertices.reserve(std::min(vertex_count, 3 * data.stats.triangles_input));
    normals.reserve(data.stats.triangles_input);
    for (std::size_t t = 0; t < data.stats.triangles_input; ++t) {
      std::size_t idx[3];
      bool in_range = true;
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t i = index_at(3 * t + static_cast<std::size_t>(k));
        if (i >= vertex_count) in_range = false;
        idx[k] = in_range ? static_cast<std::size_t>(i) : 0;
      }
      if (!in_range) {
        ++data.stats.skipped_out_of_range;
        continue;
      }
      glm::vec3 p[3];
      bool finite = true;
      for (int k = 0; k < 3; ++k) {
        p[k] = position(idx[k]);
        finite = finite && std::isfinite(p[k].x) && std::isfinite(p[k].y) && std::isfinite(p[k].z);
      }
      if (!finite) {
        ++data.stats.skipped_non_finite;
        continue;
      }
      const glm::dvec3 e1 = glm::dvec3(p[1]) - glm::dvec3(p[0]);
      const glm::dvec3 e2 = glm::dvec3(p[2]) - glm::dvec3(p[0]);
      const glm::dvec3 n = glm::cross(e1, e2);
      const double len = glm::length(n);
      if (!(len > 0.0) || !std::isfinite(len)) {
        ++data.stats.skipped_degenerate;
        continue;
      }
      if (remap.empty()) remap.assign(vertex_count, detail::nci::no_triangle);
      for (int k = 0; k < 3; ++k) {
        std::uint32_t& r = remap[idx[k]];
        if (r == detail::nci::no_triangle) {
          r = static_cast<std::uint32_t>(data.vertices.size());
          data.vertices.push_back(p[k]);
        }
        data.tri_vertices.push_back(r);
      }
      data.tri_original.push_back(static_cast<std::uint32_t>(t));
      normals.push_back(glm::vec3(n / len));
      data.box = merge(data.box, p[0]);
      data.box = merge(data.box, p[1]);
      data.box = merge(data.box, p[2]);
    }
    remap.clear();
    remap.shrink_to_fit();
  }

  detail::nci::IndexData data_;
};

/// `NormalClassIndex index(strided_mesh)` builds a NormalClassIndex<glm::vec3> (the vertex type
/// is not read from raw buffers).
NormalClassIndex(const StridedMesh&)->NormalClassIndex<glm::vec3>;
NormalClassIndex(const StridedMesh&, const NciParams&)->NormalClassIndex<glm::vec3>;

}  // namespace cullkit
