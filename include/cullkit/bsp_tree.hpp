// cullkit/bsp_tree.hpp: BspTree, an exact back-to-front (or front-to-back) order of a triangle
// mesh's pieces from any eye position, for drawing transparent surfaces.
//
// A binary space partition over the triangles (Fuchs, Kedem, Naylor 1980; the textbook seed's
// polygon BSP): each node's plane is the plane of one of its triangles; triangles lying in it stay at
// the node, the others go to the front or back subtree, and a triangle straddling the plane is cut
// into two convex fragments. Seen from any eye, nothing in the subtree on the eye's side of a node's
// plane can be hidden by the node's fragments or by anything behind the plane, so painting the far
// subtree, the node, then the near subtree gives the depth-tested image. No depth sort can do this
// for interpenetrating or cyclically overlapping triangles; the BSP cuts them apart.
//
// Fragments keep their source triangle and the barycentric (u, v) of each corner, so a renderer
// interpolates its own attributes (normals, UVs, colours) at the new corners:
// attribute = (1 - u - v) * at_corner0 + u * at_corner1 + v * at_corner2.
//
// Back faces: the order covers every fragment, whichever way it faces. A renderer that culls back
// faces simply skips them while painting: the remaining order is still correct, since removing
// surfaces from a correct painter's order keeps it correct.
//
// Rounding: planes are computed in double from the float corners; a corner within a tolerance of a
// plane is on it, the tolerance being BspParams::epsilon times the largest coordinate magnitude of
// the two triangles concerned (the splitter's and the one tested). Errors are therefore limited to
// surfaces closer than that tolerance to each other (coplanar overlaps, and near-coincident
// surfaces), and to eyes within it of a splitting plane, where the surfaces concerned are seen
// edge-on. Cuts are made exactly where a polygon crosses the plane, so a triangle's fragments tile it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "config.hpp"
#include "detail/bsp/build.hpp"
#include "detail/mesh_instances.hpp"
#include "mesh_buffers.hpp"
#include "traits.hpp"

namespace cullkit {

/// An exact painter's order over a triangle mesh (see the file comment).
///
/// Build cost: about O(n log n) plane tests for n triangles when the splitters cut little; the
/// fragment count depends on the scene (docs/bsp.md lists fragments per triangle on real scenes).
/// Memory: per fragment 12 bytes, per corner 20 bytes, per node 56 bytes. The tree copies what it
/// needs: the mesh need not outlive it. Queries are `const` and safe to run from several threads.
template <class Vertex, class Index = std::uint32_t, class Traits = VertexTraits<Vertex>>
class BspTree {
  static_assert(require_vertex_traits<Vertex, Traits>::value, "");

 public:
  /// Builds the tree over every usable triangle of `mesh`. Triangles with an index out of range,
  /// a NaN or infinite corner, or zero area (no plane: see BspStats::dropped_degenerate) are dropped
  /// and counted in `stats()`; they have no fragments. Every other triangle, however small or thin,
  /// is covered exactly once by its fragments. Empty input gives an empty tree. Uses `params.threads` worker threads for large
  /// inputs (the result does not depend on them) and reports through `params.progress`.
  /// pre: mesh.vertices != nullptr when vertex_count > 0, mesh.indices likewise (asserted in debug
  /// builds; a null pointer is read as an empty buffer in release builds).
  explicit BspTree(MeshView<Vertex, Index> mesh, const BspParams& params = {}) {
    mesh = detail::checked_mesh(mesh);
    const auto read = [&mesh](std::size_t t, glm::vec3 out[3]) {
      return triangle_positions<Traits>(mesh, t, out);
    };
    detail::bsp::build(mesh.triangle_count(), read, params, data_);
  }

  /// Builds over raw buffers: positions through a pointer and a byte stride, indices of a width
  /// chosen at run time (see StridedMesh). The same tree (fragments, corners, order) as the
  /// MeshView constructor given the same positions and indices; `Vertex` is not read.
  /// pre: as StridedMesh's (asserted in debug builds; null buffers are read as empty in release).
  explicit BspTree(const StridedMesh& mesh, const BspParams& params = {}) {
    const StridedMesh m = detail::checked_mesh(mesh);
    const auto read = [&m](std::size_t t, glm::vec3 out[3]) { return triangle_positions(m, t, out); };
    detail::bsp::build(m.triangle_count(), read, params, data_);
  }

  /// Builds over several meshes placed by world matrices (a level of prefabs), as if they were one
  /// mesh whose triangles are the instances' one after another in the order given (fragments name
  /// triangles in that numbering). Corners are placed in double precision and rounded to float; a
  /// mirroring matrix (negative determinant) has its triangles' winding reversed, so front faces
  /// stay front faces. The triangles of an instance whose matrix is not affine or not finite are
  /// dropped and counted (`dropped_bad_index`), as are triangles with an index out of range.
  /// pre: `instances` points to `instance_count` instances (may be null when the count is 0); as
  /// the StridedMesh constructor's otherwise.
  BspTree(const MeshInstance* instances, std::size_t instance_count, const BspParams& params = {}) {
    CULLKIT_ASSERT(instances != nullptr || instance_count == 0, "instances points to instance_count instances");
    if (instances == nullptr) instance_count = 0;
    detail::InstanceReader reader(instances, instance_count);
    detail::bsp::build(reader.triangle_count(), [&reader](std::size_t t, glm::vec3 out[3]) { return reader.read(t, out); },
                       params, data_);
  }

  /// Every fragment, grouped by node (fragments of one node are consecutive).
  [[nodiscard]] const std::vector<BspFragment>& fragments() const noexcept { return data_.fragments; }
  /// Corner positions of the fragments (float: cut corners are rounded from double).
  [[nodiscard]] const std::vector<glm::vec3>& corners() const noexcept { return data_.corners; }
  /// Per corner (u, v) in its source triangle: p = (1 - u - v) a + u b + v c.
  [[nodiscard]] const std::vector<glm::vec2>& barycentrics() const noexcept { return data_.barycentrics; }
  /// The nodes, root first (preorder, front child before back), for custom traversals.
  [[nodiscard]] const std::vector<BspNode>& nodes() const noexcept { return data_.nodes; }
  [[nodiscard]] const BspStats& stats() const noexcept { return data_.stats; }

  /// Calls `visit(std::uint32_t fragment)` for every fragment once, back to front as seen from
  /// `eye`: painting them in this order without a depth test gives the depth-tested image, from any
  /// eye position (see the file comment for rounding). A NaN eye still visits every fragment once, in
  /// an unspecified order. Cost: O(nodes + fragments), no allocation, no recursion (parent links).
  template <class Visit>
  void visit_back_to_front(const glm::vec3& eye, Visit&& visit) const {
    walk(eye, true, visit);
  }
  /// As `visit_back_to_front`, nearest first (front to back: for occlusion-aware drawing).
  template <class Visit>
  void visit_front_to_back(const glm::vec3& eye, Visit&& visit) const {
    walk(eye, false, visit);
  }

  /// Clears `out`, then writes every fragment once, back to front as seen from `eye`: painting
  /// them in this order without a depth test gives the depth-tested image, from any eye position.
  /// Allocates only if `out` must grow.
  void back_to_front(const glm::vec3& eye, std::vector<std::uint32_t>& out) const {
    out.clear();
    out.reserve(data_.fragments.size());
    walk(eye, true, [&out](std::uint32_t f) { out.push_back(f); });
  }
  /// Clears `out`, then writes every fragment once, front to back as seen from `eye` (the reverse
  /// of `back_to_front`).
  void front_to_back(const glm::vec3& eye, std::vector<std::uint32_t>& out) const {
    out.clear();
    out.reserve(data_.fragments.size());
    walk(eye, false, [&out](std::uint32_t f) { out.push_back(f); });
  }

  /// Checks the tree's invariants: every fragment is listed by exactly one node, has 3 or more
  /// corners within the tolerance of its node's plane, every corner of the subtree in front of
  /// (behind) a node is at distance >= -tolerance (<= tolerance) from its plane, and links are
  /// consistent. The tolerance of a fragment against a node is BspParams::epsilon times the largest
  /// coordinate magnitude of its triangle's fragments and of the node's fragments' triangles (an
  /// upper bound of what the build used, since fragments tile their triangles).
  /// Cost: O(corners x depth). For tests.
  [[nodiscard]] bool validate() const {
    const auto& nodes = data_.nodes;
    const auto& frags = data_.fragments;
    std::vector<double> triangle_scale(data_.stats.triangles, 0.0), node_scale(nodes.size(), 0.0);
    for (const BspFragment& frag : frags) {
      if (frag.triangle >= triangle_scale.size() || frag.first_corner + std::size_t(frag.corner_count) > data_.corners.size())
        return false;
      for (std::uint32_t c = frag.first_corner; c < frag.first_corner + frag.corner_count; ++c)
        for (int a = 0; a < 3; ++a)
          triangle_scale[frag.triangle] = std::max(triangle_scale[frag.triangle], double(std::fabs(data_.corners[c][a])));
    }
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i].first_fragment + std::size_t(nodes[i].fragment_count) > frags.size()) return false;
      for (std::uint32_t f = nodes[i].first_fragment; f < nodes[i].first_fragment + nodes[i].fragment_count; ++f)
        node_scale[i] = std::max(node_scale[i], triangle_scale[frags[f].triangle]);
    }
    std::vector<std::uint8_t> seen(data_.fragments.size(), 0);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const BspNode& n = nodes[i];
      if (n.first_fragment + std::size_t(n.fragment_count) > data_.fragments.size()) return false;
      for (std::uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f) {
        if (seen[f]++) return false;
        const BspFragment& frag = data_.fragments[f];
        if (frag.corner_count < 3 || frag.first_corner + std::size_t(frag.corner_count) > data_.corners.size())
          return false;
        // Every ancestor's plane: on it (its own node), or on the side of the branch taken.
        std::uint32_t child = static_cast<std::uint32_t>(i);
        for (std::uint32_t a = static_cast<std::uint32_t>(i); a != kBspNone; child = a, a = nodes[a].parent) {
          const BspNode& an = nodes[a];
          const int want = a == i ? 0 : (an.front == child ? 1 : -1);
          const double eps =
              data_.relative_epsilon * std::max(node_scale[a], triangle_scale[frag.triangle]) * 1.0001 + 1e-30;
          for (std::uint32_t c = frag.first_corner; c < frag.first_corner + frag.corner_count; ++c) {
            const double s = glm::dot(an.normal, glm::dvec3(data_.corners[c])) + an.d;
            // Corners are stored in float: allow their rounding on top of the tolerance.
            const double slack = eps + 4.0 * 1.2e-7 * (std::fabs(data_.corners[c].x) + std::fabs(data_.corners[c].y) +
                                                       std::fabs(data_.corners[c].z));
            if ((want >= 0 && s < -slack) || (want <= 0 && s > slack)) return false;
          }
        }
      }
      for (std::uint32_t c : {n.front, n.back})
        if (c != kBspNone && (c >= nodes.size() || nodes[c].parent != i)) return false;
    }
    for (std::uint8_t s : seen)
      if (s != 1) return false;
    return nodes.empty() || nodes[0].parent == kBspNone;
  }

 private:
  // In-order walk without a stack: each node is entered from its parent, then from its first
  // child, then from its second; the eye's side of the node's plane decides which child is first,
  // and is recomputed on each entry (the same answer every time).
  template <class Visit>
  void walk(const glm::vec3& eye_f, bool back_to_front, Visit&& visit) const {
    const auto& nodes = data_.nodes;
    if (nodes.empty()) return;
    const glm::dvec3 eye(eye_f);
    std::uint32_t node = 0, from = kBspNone;
    while (node != kBspNone) {
      const BspNode& n = nodes[node];
      const bool eye_in_front = !(glm::dot(n.normal, eye) + n.d < 0.0);
      // Back to front: the subtree away from the eye first.
      const std::uint32_t first = (eye_in_front == back_to_front) ? n.back : n.front;
      const std::uint32_t second = (eye_in_front == back_to_front) ? n.front : n.back;
      std::uint32_t next;
      if (from == n.parent && (first != kBspNone) && from != first) {
        next = first;
      } else if (from == second && second != kBspNone) {
        next = n.parent;
      } else {
        // Coming from the first child, or from the parent with no first child: the node itself,
        // then the second child (or back up).
        // A node's fragments share a plane: any order among them is right. Front to back lists
        // them in reverse so that it is exactly the reverse of back to front.
        if (back_to_front) {
          for (std::uint32_t f = n.first_fragment; f < n.first_fragment + n.fragment_count; ++f) visit(f);
        } else {
          for (std::uint32_t f = n.first_fragment + n.fragment_count; f-- > n.first_fragment;) visit(f);
        }
        next = second != kBspNone ? second : n.parent;
      }
      from = node;
      node = next;
    }
  }

  detail::bsp::Data data_;
};

/// `BspTree tree(strided_mesh)` builds a BspTree<glm::vec3>.
BspTree(const StridedMesh&)->BspTree<glm::vec3>;
BspTree(const StridedMesh&, const BspParams&)->BspTree<glm::vec3>;

}  // namespace cullkit
