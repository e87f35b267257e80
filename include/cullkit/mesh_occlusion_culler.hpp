// cullkit/mesh_occlusion_culler.hpp: occlusion culling of the objects of one triangle mesh, with
// the mesh's own surfaces as occluders, conservative for every ray.
//
// The mesh is an indexed triangle list cut into objects (runs of consecutive triangles). Each frame,
// `cull` keeps the objects inside the view frustum, picks the objects that are biggest on screen as
// occluders (up to a triangle budget), and fills a coarse coverage grid with their front-facing
// triangles. A cell counts as covered only when the union of those triangles covers all of it;
// triangles that share an edge fuse with no seam, within one object and across objects, because
// coverage is decided by the winding number of the union's outline: an edge used by two occluder
// triangles in opposite directions cancels and is not part of the outline. Each covered cell gets a
// depth that no ray through it can pass without meeting an occluder. An object whose screen
// rectangle lies entirely on covered cells nearer than its box is hidden. The algorithm, its
// parameters and its limits are described in docs/mesh_occlusion.md.
//
// Depth is clip-space w, which grows along every ray from the eye; cells and object rectangles are
// computed through the eye itself, in double precision, with margins for what rounding is left,
// so the answer holds for every ray, not only for the rays of some resolution.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "adaptive_binary_tree.hpp"
#include "config.hpp"
#include "geometry/aabb.hpp"
#include "geometry/camera.hpp"
#include "mesh_buffers.hpp"
#include "traits.hpp"
#include "mesh_occlusion_params.hpp"
// The index and the query are plain functions on flat arrays, compiled once whatever the vertex type.
#include "detail/mesh_occlusion/box_test.hpp"
#include "detail/mesh_occlusion/index.hpp"
#include "detail/mesh_instances.hpp"
#include "detail/mesh_occlusion/query.hpp"

namespace cullkit {

/// Caller-owned working memory for `MeshOcclusionCuller::cull`. Reusing one context makes the warm
/// path allocation-free (buffers only grow). One context per thread: a context must not be used by
/// two `cull` calls at once. A context may be used with different cullers. A cull on several tasks
/// (MeshOcclusionParams::threads) keeps each task's memory here too.
class MeshOcclusionContext {
 public:
  MeshOcclusionContext() = default;
  /// Statistics of the last `cull` that used this context.
  [[nodiscard]] const MeshOcclusionStats& stats() const noexcept { return scratch_.stats; }

  /// After a `cull` with this context, until the next one: true only if every point of `box` beyond
  /// the near plane and inside the frustum lies behind a front face of an occluder that cull used
  /// (static or moving) along the ray from the eye, so nothing of the box can be seen. It is the
  /// culler's own test of an object's box, for any box (a moving object, a particle system's or a
  /// light's bounds, a decal). A box wholly outside the frustum may answer either way; a box
  /// reaching the near plane, a box with NaN, infinite or inverted bounds, and any box before the
  /// first cull or after a cull that filled no grid (no occlusion that frame, or fewer than two
  /// objects in the frustum and no moving occluder) answer false.
  /// Cost: the box's corners projected, then its screen rectangle's tiles (a few hundred ns).
  /// Thread safety: const, safe from several threads at once (not during a cull with this context).
  [[nodiscard]] bool is_hidden(const Aabb& box) const noexcept {
    return detail::mesh_occlusion::query_box_hidden(scratch_, ready_, box);
  }

  /// As above for the box `local_box` placed in the world by `model` (affine: a rotated, scaled or
  /// mirrored box), tested through the world bounds of its 8 corners (conservative: hidden only if
  /// that larger box is). A non-affine or non-finite matrix answers false.
  [[nodiscard]] bool is_hidden(const Aabb& local_box, const glm::mat4& model) const noexcept {
    Aabb world;
    return detail::mesh_occlusion::oriented_bounds(local_box, model, world) && is_hidden(world);
  }

 private:
  template <class, class, class>
  friend class MeshOcclusionCuller;
  detail::mesh_occlusion::Scratch scratch_;
  detail::mesh_occlusion::MovingScratch moving_;
  bool ready_ = false;  // the last cull filled and finished scratch_'s grid
};

/// Occlusion culling of the objects of a triangle mesh by the mesh's own front faces.
///
/// Build: O(n) expected in triangles (a hash weld of corner positions and a hash of directed edges),
/// plus the frustum tree over object bounds, O(m log m) in objects; the culler copies what it needs
/// (the mesh and objects need not outlive it): about 60 bytes per triangle and 12 per vertex.
///
/// Query: see `cull`. Queries are `const` and safe to run concurrently, each with its own context.
template <class Vertex, class Index = std::uint32_t, class Traits = VertexTraits<Vertex>>
class MeshOcclusionCuller {
 public:
  /// Builds over `mesh` cut into `objects[0, object_count)`. Triangles with an index out of range
  /// or a NaN/infinite corner are skipped and counted; the objects that hold one, objects whose range
  /// leaves the mesh and objects with no triangles are always reported visible. Degenerate
  /// triangles count towards their object's bounds but never occlude. Objects may overlap, leave
  /// triangles out, or come in any order.
  /// pre: `objects` points to `object_count` objects (may be null when the count is 0); `mesh`'s
  /// pointers hold their counts. Allocates; reads the mesh once.
  MeshOcclusionCuller(MeshView<Vertex, Index> mesh, const MeshObject* objects, std::size_t object_count,
                      const MeshOcclusionParams& params = {}) {
    static_assert(require_vertex_traits<Vertex, Traits>::value, "");
    if constexpr (has_vertex_traits_v<Vertex, Traits>) {
      mesh = detail::checked_mesh(mesh);
      build(mesh.index_count / 3,
            [&mesh](std::size_t t, glm::vec3 p[3]) { return triangle_positions<Traits>(mesh, t, p); }, objects,
            object_count, params);
    }
  }

  /// Builds over raw buffers: positions through a pointer and a byte stride, indices of a width
  /// chosen at run time (see StridedMesh). The same culler (hence the same answers) as the
  /// MeshView constructor given the same positions and indices; `Vertex` is not read.
  /// pre: as the MeshView constructor's, and StridedMesh's (asserted in debug builds; null
  /// buffers are read as empty in release builds).
  MeshOcclusionCuller(const StridedMesh& mesh, const MeshObject* objects, std::size_t object_count,
                      const MeshOcclusionParams& params = {}) {
    const StridedMesh m = detail::checked_mesh(mesh);
    build(m.triangle_count(), [&m](std::size_t t, glm::vec3 p[3]) { return triangle_positions(m, t, p); }, objects,
          object_count, params);
  }

  /// Builds over several meshes placed by world matrices (instances of prefabs), as if their
  /// triangles were one mesh, pre-transformed, in the order given: the objects index that numbering.
  /// Corners are placed in double precision and rounded to float (the same corner of two instances
  /// that meet lands on the same float, so their seam fuses); a mirroring matrix (negative
  /// determinant) has its triangles' winding reversed, so front faces stay front faces. The
  /// triangles of an instance whose matrix is not affine or not finite are unusable (skipped,
  /// counted, and their objects always reported visible), as are triangles with an index out of
  /// range or a corner placed at a non-finite point.
  /// pre: `instances` points to `instance_count` instances (may be null when the count is 0); as the
  /// StridedMesh constructor's otherwise.
  MeshOcclusionCuller(const MeshInstance* instances, std::size_t instance_count, const MeshObject* objects,
                      std::size_t object_count, const MeshOcclusionParams& params = {}) {
    CULLKIT_ASSERT(instances != nullptr || instance_count == 0, "instances points to instance_count instances");
    if (instances == nullptr) instance_count = 0;
    detail::InstanceReader reader(instances, instance_count);
    build(reader.triangle_count(), [&reader](std::size_t t, glm::vec3 p[3]) { return reader.read(t, p); }, objects,
          object_count, params);
  }

  /// Clears `out`, then writes, once each, in any order, every object that may be visible from
  /// `camera`: an object is left out only if no ray from camera.eye through the view frustum meets a
  /// front-facing triangle of it beyond the near plane before it meets a front-facing triangle of
  /// another object beyond the near plane. Objects outside the frustum are left out; objects with
  /// unusable bounds are always written. For an orthographic or degenerate (NaN, singular) matrix,
  /// or an eye that is not the matrix's centre of projection, nothing occludes: every object that
  /// may meet the frustum is written.
  /// Cost: frustum tree walk, then O(occluder triangles + covered cells + in-frustum objects).
  /// Allocates a fresh context per call; use the context overload on hot paths.
  /// Thread safety: concurrent calls are safe (distinct `out`).
  void cull(const Camera& camera, std::vector<std::uint32_t>& out) const {
    MeshOcclusionContext context;
    cull(camera, context, out);
  }

  /// As above, with caller-owned working memory: no allocation once `context` and `out` have grown
  /// to this scene's needs. `context.stats()` then describes this call. With `params().threads`
  /// other than 1, parts of the call run as tasks on `params().task_runner` (or the library's
  /// pool), each with its own memory in `context`; the call returns when all have, and the answer
  /// is the one-thread answer (see MeshOcclusionParams::threads).
  void cull(const Camera& camera, MeshOcclusionContext& context, std::vector<std::uint32_t>& out) const {
    cull(camera, context, out, nullptr, 0);
  }

  /// As above, with `moving[0, moving_count)` also hiding what lies behind them in this frame
  /// (doors, vehicles, characters, lifts, destructible walls): each is placed by its matrix (in
  /// double precision), clipped and projected like the static occluders and rasterized into the
  /// same coverage grid after them, so it fuses with them where the grid allows. Moving occluders
  /// are not objects: they are never written to `out`. A triangle with an index out of range, a
  /// non-finite corner or zero area hides nothing; an occluder whose matrix is not affine, is
  /// singular or places a corner at a non-finite point hides nothing. `moving` may be null when the
  /// count is 0. `context.is_hidden` then also sees the moving occluders.
  /// Cost: as above plus O(moving triangles) (their corners welded, edges paired, triangles
  /// rasterized). Allocates when moving occluders are given.
  void cull(const Camera& camera, MeshOcclusionContext& context, std::vector<std::uint32_t>& out,
            const MovingOccluder* moving, std::size_t moving_count) const {
    CULLKIT_ASSERT(moving != nullptr || moving_count == 0, "moving points to moving_count occluders");
    context.ready_ = false;
    context.ready_ = detail::mesh_occlusion::cull(index_, params_, camera, context.scratch_, out, moving, moving_count,
                                                  &context.moving_);
  }

  /// Switches object `object`'s part as an occluder for the culls that follow (a door of the level
  /// that opens, a wall that breaks), with no rebuild: a non-occluding object is culled like any
  /// other and hides nothing. An object number out of range is ignored. O(1).
  /// Thread safety: not concurrent with `cull` (or any other call) on this culler.
  void set_occludes(std::uint32_t object, bool occludes) noexcept {
    if (object < index_.objects.size()) index_.objects[object].occludes = occludes;
  }
  /// Whether object `object` hides anything (MeshObject::occludes, or the last `set_occludes`);
  /// false for an object number out of range.
  [[nodiscard]] bool occludes(std::uint32_t object) const noexcept {
    return object < index_.objects.size() && index_.objects[object].occludes;
  }

  /// The frustum-only answer: clears `out`, then writes every object whose box may meet `camera`'s
  /// frustum and every object always reported visible (unusable data), as `cull` does before
  /// occlusion. Thread safety: concurrent calls are safe (distinct `out`). Allocation: growth of `out`.
  void cull_frustum(const Camera& camera, std::vector<std::uint32_t>& out) const {
    index_.tree.cull(frustum_of(camera), out);
    for (std::uint32_t& i : out) i = index_.tree_objects[i];
    out.insert(out.end(), index_.unusable.begin(), index_.unusable.end());
  }

  /// Object `object`'s bounds (tight over its triangles, degenerate ones included); an inverted box
  /// (Aabb::empty()) for an object out of range or one always reported visible (unusable data).
  [[nodiscard]] Aabb object_bounds(std::uint32_t object) const noexcept {
    if (object >= index_.objects.size() || index_.objects[object].triangle_count == 0) return Aabb::empty();
    return index_.bounds[object];
  }

  /// What the constructor found (as every container's `stats()`; a cull's own counts are in
  /// `MeshOcclusionContext::stats()`).
  [[nodiscard]] const MeshOcclusionBuildStats& stats() const noexcept { return index_.build_stats; }
  /// The former name of `stats()`.
  [[deprecated("use stats(), the name every container gives what its build found")]] [[nodiscard]]
  const MeshOcclusionBuildStats& build_stats() const noexcept { return index_.build_stats; }
  /// Objects given to the constructor.
  [[nodiscard]] std::size_t object_count() const noexcept { return index_.object_count; }
  /// The parameters in use (after clamping).
  [[nodiscard]] const MeshOcclusionParams& params() const noexcept { return params_; }

 private:
  // The constructors' common part: `read(t, corners)` reads triangle t (false: an index out of range).
  template <class ReadTriangle>
  void build(std::size_t triangle_count, const ReadTriangle& read, const MeshObject* objects, std::size_t object_count,
             const MeshOcclusionParams& params) {
    CULLKIT_ASSERT(objects != nullptr || object_count == 0, "objects points to object_count objects");
    if (objects == nullptr) object_count = 0;
    params_ = detail::mesh_occlusion::sanitize(params);
    detail::mesh_occlusion::build_index(index_, triangle_count, read, objects, object_count, params_.tree,
                                        params_.patch_triangles, params_.cut_tjunctions);
  }

  MeshOcclusionParams params_;
  detail::mesh_occlusion::MeshIndex index_;
};

/// `MeshOcclusionCuller culler(strided_mesh, objects, count)` builds a MeshOcclusionCuller<glm::vec3>.
MeshOcclusionCuller(const StridedMesh&, const MeshObject*, std::size_t)->MeshOcclusionCuller<glm::vec3>;
MeshOcclusionCuller(const StridedMesh&, const MeshObject*, std::size_t, const MeshOcclusionParams&)
    ->MeshOcclusionCuller<glm::vec3>;

}  // namespace cullkit
