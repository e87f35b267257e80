// cullkit/detail/nci/index_data.hpp: IndexData, everything a NormalClassIndex holds, as flat arrays.
// The build (build.hpp) fills it; the selection (select.hpp) only reads it. Nothing here depends
// on the user's vertex or index types.
//
// Layout: triangles are renumbered class by class in the order of their first cell in the X
// grid, so the triangles of a cell (and their vertices and per-worker records) are mostly one run
// of consecutive memory; tri_original maps back to the mesh's numbering. Each class has three
// sparse grids over the scene box, one per axis: slices -> rows -> cells, as sorted coordinates in
// flat arrays; only non-empty cells exist. Narrow forms (16-bit ids and ranges) are used whenever
// the counts allow, which is what keeps memory_bytes() small.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "../../geometry/aabb.hpp"
#include "triangle_bvh.hpp"
#include "watertight.hpp"
#include "../../nci_params.hpp"

namespace cullkit::detail::nci {

// An internal triangle id meaning "none" (no hit, no vertex yet).
inline constexpr std::uint32_t no_triangle = 0xFFFFFFFFu;
// IndexData::class_of of a mesh triangle the build skipped.
inline constexpr std::uint16_t skipped_class = 0xFFFFu;

struct IndexData {
  NciParams params;  // after clamping
  NciStats stats;
  Aabb box = Aabb::empty();  // of the kept triangles
  glm::dvec3 lo{0.0};        // the grid's origin (box.min)
  double h = 1.0;            // cell edge (cubic cells)
  // Inflation of cells and slices: absorbs the rounding of the overlap tests and of the ray
  // parameters (see build.hpp, grid_size).
  double delta = 0.0;
  int dims[3] = {1, 1, 1};
  // Corners: with slot_vertices, each triangle holds its own three corners (no ids: chosen when it
  // takes no more bytes, as on meshes of unshared triangles), in the order of the hierarchy's
  // leaves: corner k of the triangle at leaf position p (bvh.tris[p]) is vertices[3 p + k], so a
  // leaf's corners are one contiguous run the cast loads without an id first, and tri_slot maps an
  // internal triangle to its position (while the build runs, before the hierarchy exists,
  // tri_slot is empty and the position is the internal id). Else vertices are shared and named by
  // 3 ids per triangle in tri_vertices or, at most 65536 vertices, tri_vertices16.
  std::vector<glm::vec3> vertices;
  bool slot_vertices = false;
  std::vector<std::uint32_t> tri_slot;  // with slot_vertices: internal triangle -> leaf position
  std::vector<std::uint32_t> tri_vertices;    // 3 per kept triangle, into vertices, or empty:
  std::vector<std::uint16_t> tri_vertices16;  // the same in 16 bits (at most 65536 vertices)
  std::vector<std::uint32_t> tri_original;    // internal triangle -> mesh triangle
  std::vector<std::uint16_t> class_of;        // mesh triangle -> class, skipped_class when skipped
  std::vector<std::uint32_t> class_tri_begin;  // classes + 1: each class's run of internal ids
  std::vector<glm::vec3> class_axis;
  std::vector<float> class_sin, class_cos;  // cone half-angle (with margin); sin > 1: never skip
  std::vector<std::uint32_t> cell_tri_begin;  // cells + 1, or empty:
  std::vector<std::uint16_t> cell_begin16;    // cells + classes: ranges relative to the class's entries
  std::vector<std::uint32_t> class_entry_base;  // per class: its first entry (with cell_begin16)
  // Internal triangle ids per cell (ascending within a cell): class-local in 16 bits (plus
  // class_tri_begin) unless some class has more than 65536 triangles (wide_tris): then global in
  // 32 bits.
  std::vector<std::uint32_t> cell_tris;
  std::vector<std::uint16_t> cell_tris16;
  bool wide_tris = false;
  // Chunk boxes (min xyz, max xyz) of every `chunk` consecutive cell entries, or empty when the
  // cells hold fewer than chunk_min_mean entries on average (a box would not pay for itself).
  static constexpr std::size_t chunk = 16;
  static constexpr std::size_t chunk_min_mean = 8;
  std::vector<float> chunk_box;
  std::vector<std::uint32_t> grid_base;   // (class, axis) -> first entry in slice_rows
  std::vector<std::uint32_t> slice_rows;  // per grid dims[axis] + 1 row offsets
  std::vector<std::uint16_t> row_coord;
  std::vector<std::uint32_t> row_begin;   // rows + 1 (global sentinel)
  std::vector<std::uint16_t> cell_col;
  // Cells of the Y and Z grids' entries (X grids list cells in id order and need none): the
  // class's own cell number in 16 bits, added to class_cell_base, unless some class has more
  // than 65536 cells (wide_ids): then the global cell in 32 bits.
  std::vector<std::uint32_t> cell_id;
  std::vector<std::uint16_t> cell_id16;
  std::vector<std::uint32_t> class_cell_base;  // per class: its first cell (0 when wide_ids)
  std::vector<std::uint32_t> grid_shift;  // (class, axis): X: cell = position - shift; else id at position - shift
  bool wide_ids = false;
  // NciCrowdedPath::automatic casts a frame through `frame` when the eye is outside the scene box
  // and the index holds at least this many triangles per pixel of the box's screen rectangle.
  // Measured (docs/nci.md, "Crowded views"), with the cast's footprint pre-test: the cast took
  // 0.67-0.68 of the walk's time at 2.1 triangles per pixel, 0.88-0.89 at 1.7 and at 0.83, 1.22-1.27
  // at 0.66 and 1.0-1.76 from 0.07 to 0.33 (0.15-0.24 at 24-63 before the pre-test).
  static constexpr double cast_crowding = 0.75;
  // One hierarchy over every kept triangle (triangle_bvh.hpp): the tiles of a crowded frame cast their
  // rays through it (frame_tile.hpp) instead of walking the grid. Leaves name internal ids.
  TriangleBvh bvh;
  // Width of the ray test's edge band (detail::watertight_hit_band) in units of the coordinates.
  float band = edge_band_units * 0x1p-24f;

  [[nodiscard]] std::size_t triangle_count() const noexcept { return stats.triangles_indexed; }
  [[nodiscard]] std::uint32_t original(std::uint32_t tri) const noexcept { return tri_original[tri]; }
  // Corner k of internal triangle tri.
  [[nodiscard]] const glm::vec3& corner(std::uint32_t tri, int k) const noexcept {
    const std::size_t i = 3 * std::size_t{tri} + static_cast<std::size_t>(k);
    if (slot_vertices) return vertices[tri_slot.empty() ? i : 3 * std::size_t{tri_slot[tri]} + static_cast<std::size_t>(k)];
    return vertices[tri_vertices.empty() ? tri_vertices16[i] : tri_vertices[i]];
  }
  // Corner k of the triangle at leaf position pos of the hierarchy (bvh.tris[pos] = tri).
  [[nodiscard]] const glm::vec3& leaf_corner(std::uint32_t pos, std::uint32_t tri, int k) const noexcept {
    if (slot_vertices) return vertices[3 * std::size_t{pos} + static_cast<std::size_t>(k)];
    return corner(tri, k);
  }
  // The internal triangle of entry e, which belongs to a cell of class c.
  [[nodiscard]] std::uint32_t entry_triangle(std::uint32_t e, std::uint32_t c) const noexcept {
    return wide_tris ? cell_tris[e] : class_tri_begin[c] + cell_tris16[e];
  }
  // The cell holding coordinate x on axis a, clamped to the grid (NaN: 0).
  [[nodiscard]] int cell_of(double x, int a) const noexcept {
    const double f = std::floor((x - lo[a]) / h);
    if (!(f >= 0.0)) return 0;
    if (f >= dims[a] - 1) return dims[a] - 1;
    return static_cast<int>(f);
  }
  // Bytes held (capacity of every array), the struct itself included.
  [[nodiscard]] std::size_t memory_bytes() const noexcept {
    return sizeof(*this) + bytes(vertices) + bytes(tri_slot) + bytes(tri_vertices) + bytes(tri_vertices16) + bytes(cell_begin16) +
           bytes(class_entry_base) + bytes(tri_original) + bytes(class_axis) + bytes(class_sin) + bytes(class_cos) +
           bytes(cell_tri_begin) + bytes(cell_tris) + bytes(cell_tris16) + bytes(chunk_box) + bytes(class_tri_begin) +
           bytes(grid_base) + bytes(slice_rows) + bytes(row_coord) + bytes(row_begin) + bytes(cell_col) +
           bytes(cell_id) + bytes(cell_id16) + bytes(grid_shift) + bytes(class_cell_base) + bytes(class_of) +
           bvh.memory_bytes();
  }

 private:
  template <class T>
  static std::size_t bytes(const std::vector<T>& v) noexcept {
    return v.capacity() * sizeof(T);
  }
};

}  // namespace cullkit::detail::nci
