// cullkit/abt_params.hpp: the value types of AdaptiveBinaryTree: build parameters, statistics,
// the read-only node, and the box that stands for "bounds unknown".
#pragma once

#include <cstdint>
#include <functional>
#include <limits>

#include <glm/vec3.hpp>

#include "geometry/aabb.hpp"
#include "geometry/sphere.hpp"
#include "task_runner.hpp"

namespace cullkit {

/// How split-plane candidates are generated.
enum class AbtCandidates : std::uint8_t {
  /// `candidates` evenly spaced planes per axis across the node's centroid range (binning). One
  /// cheap pass per axis. The default: in bench_abt it builds faster and culls as well or better.
  binning,
  /// `candidates` planes per axis through the centroids of objects drawn at random (the seed's
  /// "random sampling"), with a seeded splitmix64 stream per node: same input and seed, same tree.
  sampling,
};

/// Build parameters. Every field has a documented default; `AbtParams{}` is a sound choice.
struct AbtParams {
  /// A node with at most this many objects becomes a leaf. Default 16. Culling answers per object
  /// whatever the leaf size; smaller leaves give finer draw ranges and traversals but more nodes
  /// (about 2n / max_leaf_size, 60 bytes each) and a slower build; docs/abt.md has the measured
  /// trade-off. 0 is treated as 1.
  std::uint32_t max_leaf_size = 16;
  /// Deepest level (the root is level 0); a node there becomes a leaf whatever its size.
  /// Default 48; values above `AdaptiveBinaryTree::depth_limit` (64) are clamped to it.
  std::uint32_t max_depth = 48;
  /// Candidate generator. Default `binning` (see AbtCandidates).
  AbtCandidates candidates = AbtCandidates::binning;
  /// Candidate planes per axis and node. Default 16. More is slower to build, rarely better.
  std::uint32_t candidate_count = 16;
  /// Weight of f1, which prefers the longest axis of the node's box (0 on it, up to 1). Default 1.
  float weight_axis = 1.0f;
  /// Weight of f2 = |V_left - V_right| / (V_left + V_right) of the children's tight boxes. Default 1.
  float weight_volume = 1.0f;
  /// Weight of f3 = |n_left - n_right| / n, balance of object counts. Default 1.
  float weight_count = 1.0f;
  /// Weight of f4 = (objects whose box straddles the plane) / n. Default 1. 0 also skips counting.
  float weight_straddle = 1.0f;
  /// Nodes with more objects than this score their candidates on an evenly strided subset of about
  /// this many objects (the split itself is always exact). Default 8192; raise it for slightly
  /// better top levels at a higher build cost. Values below 64 are treated as 64.
  std::uint32_t score_sample_limit = 8192;
  /// Seed of the sampling generator (unused by binning). Default 0x5eed.
  std::uint64_t seed = 0x5eedu;
  /// Worker threads for the build, as everywhere in cullkit: 0 (the default) uses all hardware
  /// threads, 1 builds on the calling thread only, N > 1 up to N tasks. Builds of fewer than
  /// 2 * `parallel_grain` objects always run on the calling thread. The tasks run on
  /// `task_runner` when it is set, else on the library's persistent worker pool. The tree is
  /// identical either way.
  unsigned threads = 0;
  /// The caller's job system for the build's tasks (see TaskRunner); default: the library's pool.
  TaskRunner task_runner{};
  /// Subtrees smaller than this are never handed to another thread. Default 4096 objects.
  std::uint32_t parallel_grain = 4096;
  /// `cull` tests the objects of a straddling subtree of at most this many objects directly
  /// (16 at a time, vectorized, one contiguous range) instead of descending into it. Default 64
  /// (see `max_leaf_size` for measurements). 0 descends to the leaves. Results are the same
  /// either way; only speed changes.
  std::uint32_t scan_below = 64;
  /// Optional progress report, called with a fraction in [0, 1] (non-decreasing, 1 at the end) a
  /// few dozen times over a build of at least `progress_min_objects` objects. It may be called from
  /// any build thread, but never concurrently. Default: none.
  std::function<void(float)> progress;
  /// Smallest build that reports progress. Default 65536 objects.
  std::uint32_t progress_min_objects = 65536;
};

/// Build statistics (`AdaptiveBinaryTree::stats`).
struct AbtStats {
  std::uint32_t nodes = 0;    ///< nodes in `nodes()`
  std::uint32_t leaves = 0;   ///< leaf nodes
  std::uint32_t depth = 0;    ///< deepest level (root = 0; 0 also for an empty tree)
  std::uint32_t objects = 0;  ///< objects held (= size())
  std::uint32_t skipped = 0;  ///< objects left out: only those beyond the first 2^32 - 2
  std::uint32_t max_leaf_objects = 0;     ///< largest leaf (above max_leaf_size only for inseparable objects)
  std::uint32_t refit_invalid = 0;        ///< at the last refit: held objects whose new bounds were bad
  /// Objects whose bounds are NaN, infinite or inverted now (at the build or the last refit). They
  /// are held with `unbounded_box()` and reported by every cull.
  std::uint32_t unbounded = 0;
  std::uint32_t subtrees_rebuilt = 0;     ///< at the last repairing refit: subtrees rebuilt
  std::uint32_t objects_rebuilt = 0;      ///< at the last repairing refit: objects in those subtrees
};

/// Parameters of the repairing refit (`AdaptiveBinaryTree::refit(objects, AbtRefitParams)`).
struct AbtRefitParams {
  /// An inner node's split ratio is (area of its two children) / (its own area): about 1.3 for a
  /// good split of evenly spread objects, 2 when the children have spread to cover the whole node.
  /// A node's subtree is rebuilt once its ratio has gone this fraction of the way from its value
  /// when it was built towards 2. Default 0.2: the trade-off between tree quality and the objects
  /// rebuilt per frame is measured in docs/engine_fit.md. Values outside (0, 1), or NaN, turn the
  /// repair off (plain refit).
  double rebuild_threshold = 0.2;
};

/// A read-only node. Node 0 is the root; inner nodes have two children, `left` and `left + 1`.
struct AbtNode {
  Aabb bounds;            ///< tight box of every object in the subtree
  Sphere sphere;          ///< `bounding_sphere(bounds)`
  std::uint32_t begin;    ///< the subtree's objects are `order()[begin, end)`
  std::uint32_t end;
  std::uint32_t left;     ///< left child index (right child = left + 1); 0 for a leaf
  std::uint8_t axis;      ///< inner nodes: split axis (0 x, 1 y, 2 z)
  float split;            ///< inner nodes: objects with centroid[axis] < split went left (at build)

  [[nodiscard]] bool is_leaf() const noexcept { return left == 0; }
  [[nodiscard]] std::uint32_t right() const noexcept { return left + 1; }
  [[nodiscard]] std::uint32_t count() const noexcept { return end - begin; }
};

/// The box an AdaptiveBinaryTree stores for an object whose bounds are NaN, infinite or inverted:
/// every coordinate at the largest float. Every plane test of the library answers `intersecting`
/// for it (its half extents overflow to infinity), so such an object is never culled; its
/// ancestors' boxes grow to it, which costs one extra node test per level on its path only.
[[nodiscard]] constexpr Aabb unbounded_box() noexcept {
  constexpr float big = std::numeric_limits<float>::max();
  return Aabb{glm::vec3(-big), glm::vec3(big)};
}

/// True for a box whose extent overflows float on some axis (`unbounded_box()`, and finite boxes
/// wider than 3.4e38). The tree keeps such boxes out of occlusion queries and quality measures.
[[nodiscard]] inline bool is_unbounded(const Aabb& b) noexcept {
  constexpr float big = std::numeric_limits<float>::max();
  for (int a = 0; a < 3; ++a)
    if (!(b.max[a] - b.min[a] <= big)) return true;
  return false;
}

}  // namespace cullkit
