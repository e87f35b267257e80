// cullkit/mesh_occlusion_params.hpp: the plain types of MeshOcclusionCuller: objects, parameters
// and statistics (included by mesh_occlusion_culler.hpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/mat4x4.hpp>

#include "adaptive_binary_tree.hpp"
#include "mesh_buffers.hpp"
#include "task_runner.hpp"

namespace cullkit {

/// An object of a `MeshOcclusionCuller`: the triangles [first_triangle, first_triangle +
/// triangle_count) of the mesh (triangle t is indices[3t, 3t + 3)).
struct MeshObject {
  std::uint32_t first_triangle;
  std::uint32_t triangle_count;
  /// false: the object is culled like any other but hides nothing (glass, force fields, grates and
  /// foliage cards drawn with alpha test, decals, water). `MeshObject{first, count}` occludes.
  bool occludes = true;
};

/// Geometry that moves, given each frame to `MeshOcclusionCuller::cull`: a mesh in its own space
/// (front faces counter-clockwise there, as everywhere) and its world matrix (affine, any scale). A
/// mirroring matrix (negative determinant) reverses the apparent winding; the culler compensates, so
/// the faces that are front faces in the mesh's own space stay front faces in the world. Like a
/// static occluder it must be a real, opaque surface where it is drawn (see docs/mesh_occlusion.md,
/// "What may occlude").
struct MovingOccluder {
  StridedMesh mesh;
  glm::mat4 model;
};

/// Parameters of `MeshOcclusionCuller`. Every field has a documented default; `{}` is a sound choice.
struct MeshOcclusionParams {
  /// Coverage cells across the screen. Default 256. The cells are not the renderer's pixels: the
  /// answer holds for every ray whatever the grid. More cells hide objects seen through narrower
  /// gaps and behind thinner occluders, at a cost roughly proportional to the cell count (covered
  /// area) plus the occluder edges' lengths in cells. Clamped to [8, 4096].
  int grid_width = 256;
  /// Coverage cells down the screen. Default 144 (16:9 with the default width). Clamped to [8, 4096].
  int grid_height = 144;
  /// Most occluder triangles per frame. Default 16384. Occluder objects are taken by size on screen,
  /// biggest first, while their triangles fit; raise it for scenes whose occluders are finely
  /// triangulated, lower it when `cull` is too slow.
  std::uint32_t occluder_triangle_budget = 16384;
  /// Objects whose box covers less than this fraction of the screen are never occluders. Default
  /// 0.0005 (about 1000 pixels at 1920x1080). Small objects hide little and cost as much per triangle.
  float min_occluder_screen_fraction = 0.0005f;
  /// A patch whose box covers fewer coverage cells than this many per triangle is never an
  /// occluder. Default 1: its triangles average under a cell each on screen, and each costs about
  /// as much to insert as a big one (on fzk_haus, 0.9 of the frame's time at the same kept share).
  /// 0 keeps every patch above the size floor.
  float min_occluder_cells_per_triangle = 1.0f;
  /// A patch narrower on screen than this many coverage cells is never an occluder. Its width is
  /// the area of its front-facing triangles on screen over the diagonal of their screen box: a
  /// straight strip's width, less for a curved one. Default 1.5: a window frame, a railing, a rod
  /// or a trim seen from afar, or a wall seen edge-on, covers few cells by itself, or none, and
  /// costs as much per triangle as a wall seen square-on. Decided after the occluders are chosen
  /// (their triangles still count against `occluder_triangle_budget`). 0 keeps every patch.
  float min_occluder_width_cells = 1.5f;
  /// Occluder patches go in one at a time, nearest first, and each patch's triangles nearest first,
  /// in bands: a band holds the triangles whose nearest corner is at most (1 + depth_band_ratio)
  /// times as far as the band's first. A cell is given its depth when a band ends, as the farthest
  /// of the triangles near it so far. Default 0.1. 0 makes every distinct depth its own band
  /// (tightest depths, slowest); larger values are faster and hide less behind folded occluders.
  float depth_band_ratio = 0.1f;
  /// Most occluder patches per frame. Default 4096.
  std::uint32_t max_occluder_objects = 4096;
  /// Objects are cut at build time into surface patches of at most this many triangles (grown over
  /// shared edges, so each is connected and compact). Occluders are chosen patch by patch, so the
  /// budget takes the part of a big object that is big on screen instead of skipping it whole; an
  /// object whose box is not hidden is hidden when all its patches' boxes are. Default 256. Smaller
  /// patches fit the budget and the object tests tighter, at more boxes to project per frame.
  /// Clamped to [1, 65536].
  std::uint32_t patch_triangles = 256;
  /// A patch of at most this many triangles whose box is not hidden is tested triangle by triangle:
  /// each front-facing triangle by its own screen rectangle at its own nearest depth (triangles
  /// that clearly face away from the eye are never seen, so an object facing away is hidden). The
  /// test stops at the first triangle not hidden. Default 256 (every patch of the default size).
  /// 0 turns it off: objects are then tested by their box and their patches' boxes only.
  std::uint32_t object_test_triangles = 256;
  /// Objects whose triangles are exactly a closed box (12 outward triangles on the faces of their
  /// bounds: buildings and crates of generated scenes, walls of some building models) are solids:
  /// up to this many of them in the frustum, the biggest on screen (above the occluder size floor,
  /// wholly beyond the near plane), also go into an object-space OcclusionTree as box occluders, and
  /// an object the grid does not hide is hidden when that tree hides its box. The tree is exact
  /// where the grid's cells blur the occluders' outlines (a roof edge in front of a rooftop prop),
  /// and fuses boxes that touch. Default 128. 0 turns it off.
  std::uint32_t max_box_occluders = 128;
  /// At build time, a triangle whose unpaired edge has corners of other triangles lying exactly on
  /// it (a T-junction: a long edge P-Q against the edges Q-M and M-P of smaller neighbours) is cut
  /// at those corners, so that the seam's edges are shared and fuse on the coverage grid. Only
  /// corners exactly on the edge (exact arithmetic) are taken: the parts cover exactly the
  /// triangle, so no answer can become less conservative. The cut triangles remain one triangle
  /// for everything but occlusion. Default true. false: triangles are used as given.
  bool cut_tjunctions = true;
  /// Each occluder patch goes into a grid of its own before it joins the union of all occluders, and
  /// a cell it covers by itself takes the patch's depth bound where that is nearer than the union's.
  /// The union fuses the occluders' seams but keeps, per cell, the farthest depth of every triangle
  /// that touched the cell before it was covered (a floor's far part where a wall stands in front of
  /// it); a patch alone gives its own. Default true. false: the union's depths only, for comparison:
  /// it hides less and is no faster (fewer cells covered early leaves more work to later patches).
  bool patch_layers = true;
  /// Parameters of the frustum-culling tree over object bounds.
  AbtParams tree = {};
  /// Tasks for one `cull`: 1 (the default) runs it on the calling thread only; 0 uses all hardware
  /// threads; N > 1 up to N tasks. The object boxes' projection, the occluders' corners and the
  /// object tests are split into batches that the tasks take from a shared counter; with N > 1 the
  /// occluder insertion into the grid is split into strips of the grid's rows (a number set by
  /// `grid_height` alone), each inserted on its own by whichever task takes it. Never changes the
  /// answer: the same objects, in the same order, and the same statistics, for every count and every
  /// task order. One thread is the default because a frame's cull is short (a few ms) and an
  /// engine usually has other work for its other threads; the gain is measured in
  /// docs/mesh_occlusion.md. Does not apply to the frustum tree's build (`tree.threads`).
  unsigned threads = 1;
  /// The caller's job system for those tasks (see TaskRunner); by default the library's own
  /// persistent worker pool. Each task has its own working memory in the MeshOcclusionContext, so
  /// a warm context still allocates nothing.
  TaskRunner task_runner{};
};

/// What the constructor found (`MeshOcclusionCuller::build_stats`).
struct MeshOcclusionBuildStats {
  std::size_t triangles = 0;             ///< whole triangles in the mesh (index_count / 3)
  std::size_t triangles_unusable = 0;    ///< an index out of range or a NaN/infinite corner
  std::size_t triangles_degenerate = 0;  ///< finite, but two corners coincide or all three are collinear
  std::size_t welded_vertices = 0;       ///< distinct corner positions (exact float equality)
  std::size_t shared_edges = 0;          ///< edges used by two triangles in opposite directions
                                         ///< (after the cuts below)
  std::size_t tjunction_corners = 0;     ///< corners lying exactly on another triangle's unpaired edge
  std::size_t triangles_cut = 0;         ///< triangles cut at those corners (occluder parts only)
  std::size_t triangle_parts_added = 0;  ///< parts beyond the cut triangles' own slots
  std::size_t objects = 0;               ///< objects given
  std::size_t objects_unusable = 0;      ///< always reported visible: range outside the mesh, no
                                         ///< triangles, or an unusable triangle (bounds unknown)
};

/// What one `cull` did (`MeshOcclusionContext::stats`).
struct MeshOcclusionStats {
  std::size_t objects_in_frustum = 0;          ///< usable objects whose box may meet the frustum
  std::size_t occluders_used = 0;              ///< occluder patches chosen (some may insert no triangle: all facing away, or narrower than min_occluder_width_cells)
  std::size_t occluder_triangles = 0;          ///< occluder triangles rasterized (front-facing, beyond the near plane; with threads > 1, in some strip of rows)
  std::size_t moving_triangles = 0;            ///< of which moving occluders' triangles
  std::size_t objects_hidden = 0;              ///< objects in the frustum left out as hidden
  std::size_t objects_unusable_visible = 0;    ///< objects with unusable bounds, reported visible
  std::size_t cells_covered = 0;               ///< coverage cells covered at the end
  bool occlusion_enabled = false;              ///< false: orthographic, degenerate or NaN matrix, or
                                               ///< an eye away from the matrix's centre: no occlusion
};

}  // namespace cullkit
