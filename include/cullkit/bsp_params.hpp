// cullkit/bsp_params.hpp: the value types of BspTree's interface: its parameters, build progress and
// statistics, fragments and nodes. cullkit/bsp_tree.hpp includes this.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>

#include <glm/vec3.hpp>

#include "task_runner.hpp"

namespace cullkit {

/// What a BSP build has done so far, for `BspParams::progress`.
struct BspProgress {
  std::size_t fragments_placed = 0;   ///< polygons already stored at a node (final fragments)
  std::size_t fragments_pending = 0;  ///< polygons still waiting in unbuilt subtrees
};

/// Options of `BspTree`. Every field has a default that suits scenes from a few triangles to
/// millions; the trade-offs are measured in docs/bsp.md.
struct BspParams {
  /// On-plane tolerance, relative to the coordinates of the two triangles concerned (the
  /// splitter's and the tested polygon's source triangle): epsilon times the largest coordinate
  /// magnitude m among their corners, since float input is only that exact there; but no more
  /// than 1e-3 of the shorter of their longest edges (a tolerance must stay small next to the
  /// triangles it decides about) and no less than min(epsilon, 2^-22) m (a few float ulps). A
  /// corner within it of a splitting plane is on the plane: polygons are never cut for corners
  /// that are only on the plane, and a polygon with every corner on it is stored at that node.
  /// Larger merges more near-coplanar surfaces (fewer cuts) at the price of ordering errors of that
  /// size; default 1e-6, about 8 to 16 float ulps.
  float epsilon = 1e-6f;
  /// Splitter candidates scored per node (spread evenly over the node's polygons). 1 takes the
  /// first polygon's plane (fastest build, most fragments). Default 16.
  unsigned candidates = 16;
  /// Polygons each candidate is scored against (spread evenly); bounds the cost of scoring at
  /// large nodes. Default 256.
  unsigned sample = 256;
  /// Candidate score, lowest wins: split_weight x polygons cut + balance_weight x |front - back|
  /// - coplanar_weight x polygons in the plane (counted over the sample). Defaults 8, 1, 1.
  float split_weight = 8.0f;
  float balance_weight = 1.0f;
  float coplanar_weight = 1.0f;
  /// Worker threads for the build: 0 uses all hardware threads, 1 builds on the calling thread
  /// only; N > 1 uses up to N tasks, run on `task_runner` when it is set, else on the library's
  /// persistent worker pool. The tree does not depend on it.
  unsigned threads = 0;
  /// The caller's job system for the build's tasks (see TaskRunner); default: the library's pool.
  TaskRunner task_runner{};
  /// Inputs with fewer triangles are built on the calling thread only. Default 8192.
  std::size_t parallel_min_triangles = 8192;
  /// Called now and then during the build (at least once at the end, with nothing pending) when
  /// set, from one thread at a time: the calling thread, unless `task_runner` runs the build's
  /// first task on another. Must not throw.
  std::function<void(const BspProgress&)> progress;
};

/// What a build kept and dropped.
struct BspStats {
  std::size_t triangles = 0;            ///< triangles in the mesh (index_count / 3)
  std::size_t dropped_bad_index = 0;    ///< a corner index out of range (or negative)
  std::size_t dropped_non_finite = 0;   ///< a NaN or infinite corner coordinate
  std::size_t dropped_degenerate = 0;   ///< zero area: its edges' cross product is 0 in double (no plane)
  std::size_t cuts = 0;                 ///< polygons cut in two by a splitting plane
  std::size_t fragments = 0;            ///< fragments stored (kept triangles + cuts)
  std::size_t nodes = 0;
  std::size_t depth = 0;                ///< nodes on the longest root-to-leaf path
  double epsilon = 0;                   ///< the largest absolute on-plane tolerance used (see BspParams)
  double seconds = 0;                   ///< wall time of the build
};

/// A convex, planar piece of one input triangle (see BspTree::fragments()).
struct BspFragment {
  std::uint32_t triangle;      ///< the input triangle it is part of
  std::uint32_t first_corner;  ///< its corners: corners()[first_corner, first_corner + corner_count)
  std::uint32_t corner_count;  ///< 3 or more, counter-clockwise like its triangle
};

/// A node of the tree, for custom traversals. Its plane is dot(normal, p) + d = 0 (unit normal, in
/// double); the fragments lying in that plane (either facing) are
/// fragments()[first_fragment, first_fragment + fragment_count); `front` is the subtree on the side
/// the normal points to, `back` the other; kBspNone marks a missing child or the root's parent.
struct BspNode {
  glm::dvec3 normal;
  double d;
  std::uint32_t front, back, parent;
  std::uint32_t first_fragment, fragment_count;
};
inline constexpr std::uint32_t kBspNone = 0xFFFFFFFFu;

}  // namespace cullkit
