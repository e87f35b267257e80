// cullkit/detail/mesh_occlusion/moving.hpp: moving occluders, given per frame as a mesh and a world
// matrix, into the frame's coverage grid beside the static occluders.
//
// Each moving occluder is one patch of its own: its corners are welded by position in the mesh's
// own space, its opposite edges paired (so its triangles fuse along shared edges), its corners
// placed in the world in double precision and projected by the frame's view, its triangles clipped
// at the near plane, sorted nearest first and inserted in depth bands into a grid of its own that is
// then added into the frame's grid, exactly as a static patch is (insert_run). A mirroring matrix
// swaps two corners of every triangle, so the faces that are front faces in the mesh's own space
// stay front faces in the world.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>

// Scratch (and through it the view and the grid), MeshIndex with its welding and edge pairing.
#include "frame.hpp"
#include "index.hpp"
#if CULLKIT_CORE_BODIES
// insert_run, the path of static patches (compiled only where the frame's definition is).
#include "occluders.hpp"
#endif

namespace cullkit::detail::mesh_occlusion {

/// Working memory for the moving occluders of a frame; only grows.
struct MovingScratch {
  MeshIndex index;                 // one occluder at a time: its welded corners and their twins
  Scratch s;                       // its per-triangle state for insert_run (view: the frame's)
  std::vector<glm::vec3> local;    // welded corners in the mesh's own space
  std::vector<glm::dvec3> world;   // the same in the world
};

#if CULLKIT_CORE_BODIES

/// Reads a moving occluder's triangles into `m.index.corners` (welded ids in `m.local`; none for a
/// triangle that cannot occlude: an index out of range, a non-finite corner, zero area), winding
/// reversed when `mirrored`.
inline void read_moving(const StridedMesh& mesh, bool mirrored, MovingScratch& m) {
  const std::size_t count = std::min<std::size_t>(mesh.triangle_count(), none / 3 - 1);
  m.local.clear();
  m.index.corners.assign(3 * count, none);
  PositionWelder welder(count);
  for (std::size_t t = 0; t < count; ++t) {
    glm::vec3 p[3];
    if (!triangle_positions(mesh, t, p) || !finite(p[0]) || !finite(p[1]) || !finite(p[2])) continue;
    std::uint32_t id[3];
    for (int k = 0; k < 3; ++k) id[k] = welder.id(p[k], m.local);
    if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2]) continue;
    if (mirrored) std::swap(id[1], id[2]);
    for (int k = 0; k < 3; ++k) m.index.corners[3 * t + std::size_t(k)] = id[k];
  }
}

/// The corners of `m.local` placed by `model` (double precision) and projected by `m.s.view`, whose
/// clipping level is set for this occluder's world box. False when nothing of it can occlude.
inline bool place_moving(const glm::mat4& model, MovingScratch& m) {
  const glm::dmat4 to_world(model);
  const std::size_t n = m.local.size();
  m.world.resize(n);
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t v = 0; v < n; ++v) {
    const glm::dvec4 p = to_world * glm::dvec4(glm::dvec3(m.local[v]), 1.0);
    m.world[v] = glm::dvec3(p);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  }
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a])) return false;
  m.s.view.clip_level = m.s.view.level_for(lo, hi);
  m.s.projected.resize(n);
  m.s.vertex_slot.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    m.s.projected[v] = m.s.view.project(m.world[v].x, m.world[v].y, m.world[v].z);
    m.s.vertex_slot[v] = static_cast<std::uint32_t>(v);
  }
  return true;
}

/// Clips triangle t of the moving occluder (corners c, `inside` as for clip_occluder) at the
/// clipping level, each clip point from its edge's endpoints ordered by welded id, so the two
/// triangles of a shared edge get the same point.
inline bool clip_moving(const MovingScratch& m, const std::uint32_t* c, unsigned inside, ClippedPolygon& poly) {
  poly.n = 0;
  const auto put = [&poly](const Projected& p, int edge) {
    poly.x[poly.n] = p.x;
    poly.y[poly.n] = p.y;
    poly.w[poly.n] = p.w;
    poly.edge[poly.n++] = edge;
  };
  for (int k = 0; k < 3; ++k) {
    const int l = (k + 1) % 3;
    const bool in_k = (inside >> k) & 1u, in_l = (inside >> l) & 1u;
    if (in_k) put(m.s.projected[c[k]], k);  // on along edge k, to corner l or its clip point
    if (in_k == in_l) continue;
    const glm::dvec3 &from = m.world[std::min(c[k], c[l])], &to = m.world[std::max(c[k], c[l])];
    const double a[3] = {from.x, from.y, from.z}, b[3] = {to.x, to.y, to.z};
    Projected q;
    if (!m.s.view.clip_point(a, b, q)) return false;
    put(q, in_k ? -1 : k);  // leaving: on along the clipping line; entering: on along edge k
  }
  return true;
}

/// The screen box and depth range of a projected polygon of n corners.
struct PolygonExtent {
  double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, w0 = HUGE_VAL, w1 = -HUGE_VAL;
  PolygonExtent(const double* x, const double* y, const double* w, int n) {
    for (int k = 0; k < n; ++k) add(x[k], y[k], w[k]);
  }
  void add(double x, double y, double w) {
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
    w0 = std::min(w0, w), w1 = std::max(w1, w);
  }
};

/// gather_patch's front-facing rule: the polygon's signed grid area, by `orient`, clearly positive
/// against its extent (edge-on and back-facing polygons never occlude).
inline bool clearly_front_facing(const double* x, const double* y, int n, const PolygonExtent& e, int orient) {
  double twice_area = 0.0;
  for (int k = 2; k < n; ++k)
    twice_area += (x[k - 1] - x[0]) * (y[k] - y[0]) - (x[k] - x[0]) * (y[k - 1] - y[0]);
  const double size = std::max(e.x1 - e.x0, e.y1 - e.y0);
  return twice_area * orient > 1e-9 * size * size;
}

/// Keeps the moving occluder's triangles that can occlude, by gather_patch's rules (clearly
/// front-facing, touching the grid, some corner beyond the clipping level, clipped there), into
/// `m.s.triangles`, nearest first; marks them as the run's members. Returns the screen box and the
/// nearest depth of what was kept in xmin..wmin.
inline void gather_moving(MovingScratch& m, int grid_width, int grid_height, double box[5]) {
  Scratch& s = m.s;
  const std::size_t count = m.index.corners.size() / 3;
  s.triangles.clear();
  s.clipped.clear();
  s.frame = 1;
  s.clip_stamp.assign(count, 0);
  s.clip_slot.resize(count);
  s.triangle_band.resize(count);
  s.member_stamp.assign(count, 0);
  s.member_value = 1;
  s.occluder_boxes.clear();
  s.box_slot.resize(count);
  PolygonExtent all(nullptr, nullptr, nullptr, 0);
  for (std::size_t t = 0; t < count; ++t) {
    const std::uint32_t* c = &m.index.corners[3 * t];
    if (c[0] == none) continue;
    unsigned inside = 0;
    for (int k = 0; k < 3; ++k) inside |= s.projected[c[k]].inside ? 1u << k : 0u;
    if (inside == 0u) continue;  // wholly short of the clipping level
    ClippedPolygon poly;
    if (inside == 7u) {
      for (int k = 0; k < 3; ++k) {
        const Projected& p = s.projected[c[k]];
        poly.x[k] = p.x, poly.y[k] = p.y, poly.w[k] = p.w, poly.edge[k] = k;
      }
      poly.n = 3;
    } else if (!clip_moving(m, c, inside, poly)) {
      continue;
    }
    const PolygonExtent e(poly.x, poly.y, poly.w, poly.n);
    if (e.x1 < 0.0 || e.x0 > grid_width || e.y1 < 0.0 || e.y0 > grid_height) continue;
    if (!clearly_front_facing(poly.x, poly.y, poly.n, e, s.view.orient)) continue;
    if (inside != 7u) {
      s.clip_stamp[t] = s.frame;
      s.clip_slot[t] = static_cast<std::uint32_t>(s.clipped.size());
      s.clipped.push_back(poly);
    }
    // A clipped polygon goes in by its farthest depth, as a static one does (gather_patch).
    const float key = static_cast<float>(inside != 7u ? e.w1 : e.w0);
    std::uint32_t bits;
    std::memcpy(&bits, &key, sizeof bits);
    s.triangles.emplace_back(bits, static_cast<std::uint32_t>(t));
    s.box_slot[t] = static_cast<std::uint32_t>(s.occluder_boxes.size());
    s.occluder_boxes.push_back(OccluderBox{e.x0, e.y0, e.x1, e.y1, e.w0});
    s.member_stamp[t] = s.member_value;
    all.add(e.x0, e.y0, e.w0);
    all.add(e.x1, e.y1, e.w0);
  }
  box[0] = all.x0, box[1] = all.y0, box[2] = all.x1, box[3] = all.y1, box[4] = all.w0;
  radix_sort(s.triangles, s.sort_buffer);
}

/// Inserts the moving occluders into the frame's grid `s.grid` (after the static occluders, before
/// it is finished), each as a patch: its own grid seeded from the union, its triangles in depth
/// bands, then added into the union. Counts the triangles inserted.
inline void insert_moving(const MeshOcclusionParams& params, const MovingOccluder* moving, std::size_t moving_count,
                          Scratch& s, MovingScratch& m) {
  for (std::size_t i = 0; i < moving_count; ++i) {
    const MovingOccluder& occluder = moving[i];
    const StridedMesh mesh = checked_mesh(occluder.mesh);
    if (mesh.triangle_count() == 0) continue;
    const glm::dmat4 model(occluder.model);
    // Only affine matrices place a mesh; anything else hides nothing.
    if (model[0][3] != 0.0 || model[1][3] != 0.0 || model[2][3] != 0.0 || model[3][3] != 1.0) continue;
    const double det = glm::determinant(glm::dmat3(model));
    if (!std::isfinite(det) || det == 0.0) continue;
    read_moving(mesh, det < 0.0, m);
    m.s.view = s.view;
    if (!place_moving(occluder.model, m)) continue;
    pair_edges(m.index.corners, m.index.twins);
    double box[5];
    gather_moving(m, s.grid.width(), s.grid.height(), box);
    if (m.s.triangles.empty()) continue;
    s.patch_grid.reset(s.grid.width(), s.grid.height());
    const CellRect cells = s.grid.cells_of(box[0], box[1], box[2], box[3]);
    if (!s.patch_grid.seed_frozen(s.grid, cells, static_cast<float>(1.0 / box[4]))) continue;
    const RunMembers members{m.s.member_stamp, m.s.member_value};
    std::size_t inserted = 0;
    const auto* first = m.s.triangles.data();
    const auto* last = first + m.s.triangles.size();
    assign_depth_bands(params, first, last, m.s.triangle_band);
    insert_run(m.index, m.s, s.patch_grid, first, last, members, inserted);
    s.grid.absorb(s.patch_grid, params.patch_layers);
    s.grid.end_band();
    s.stats.occluder_triangles += inserted;
    s.stats.moving_triangles += inserted;
  }
}

#endif  // CULLKIT_CORE_BODIES

}  // namespace cullkit::detail::mesh_occlusion
