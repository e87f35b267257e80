// cullkit/adaptive_binary_tree.hpp: AdaptiveBinaryTree, a bounding-volume tree for view-frustum
// culling of objects (or triangles), after 牛鹏, 廉东本, 苏谟, "基于自适应二叉树的场景视锥体裁剪算法"
// (View frustum culling for scenes based on an adaptive binary tree), 计算机系统应用 27(3), 2018.
//
// What it is. A binary tree over the objects' bounding boxes. Each inner node is cut by one
// axis-aligned plane chosen by the seed's weighted score (longest axis, equal child volumes, equal
// child counts, few straddling objects); an object goes to the child that holds its centroid and
// every child takes the tight box of what it holds. Boxes may therefore overlap, but no object is
// ever duplicated or cut. Objects are permuted so that every node covers one contiguous range of
// `order()`: a renderer that reorders its index buffer the same way (see `reorder_indices`) draws
// a visible leaf, or a whole visible subtree, as one range.
//
// Culling walks top-down: the node's bounding sphere first, then its box (the seed's order),
// carrying a mask of the frustum planes a parent was already fully inside (beyond the seed). A node
// fully inside is reported as one range without descending. Only leaves (or small subtrees) that
// straddle the frustum test their objects one by one, 16 at a time from a structure-of-arrays copy
// of the boxes. Beyond the seed too: candidates by binning, normalized criteria, plane masks,
// the vectorized leaf scan, refit, front-to-back order and the parallel build.
//
// Conventions: boxes are closed (touching counts as meeting); all answers are conservative: an
// object is left out only when its box is certainly outside a frustum plane despite float rounding.
//
// Thread safety: a built tree is immutable except through `refit`; concurrent `const` queries are
// safe. The build may use worker threads (`AbtParams::threads`); its result never depends on them.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "config.hpp"
#include "detail/abt_leaf.hpp"
#include "detail/abt_split.hpp"
#include "geometry/aabb.hpp"
#include "geometry/frustum.hpp"
#include "geometry/sphere.hpp"
#include "traits.hpp"

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
  /// (about 2n / max_leaf_size, 60 bytes each) and a slower build. Measured on 60k boxes at 38%
  /// visible (time over the SoA scan's): leaves of 4: 0.47, 8: 0.34, 16: 0.25 without `scan_below`;
  /// 16 with scans below 64: 0.20. 0 is treated as 1.
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
  /// Worker threads for the build: 0 or 1 build on the calling thread only (default 0). With N > 1,
  /// subtrees are built by up to N threads (the caller included). The tree is identical either way.
  unsigned threads = 0;
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
  std::uint32_t skipped = 0;  ///< objects left out: NaN, infinite or inverted bounds (or beyond 2^32 - 2)
  std::uint32_t max_leaf_objects = 0;     ///< largest leaf (above max_leaf_size only for inseparable objects)
  std::uint32_t refit_invalid = 0;        ///< at the last refit: held objects whose new bounds were bad
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

/// An adaptive binary tree over objects with bounds (see the file comment).
///
/// `Object` is read through `Traits::bounds(const Object&) -> Aabb` (default `BoundsTraits<Object>`),
/// or through a getter with `from_getter`. The tree copies the bounds it needs: the objects need not
/// outlive it. Memory: 60 bytes per node (about 2n / max_leaf_size nodes) + 52 bytes per held
/// object (its index, its box, and the box again as padded SoA for vectorized leaf tests); the
/// build needs 40 more bytes per object while it runs.
template <class Object, class Traits = BoundsTraits<Object>>
class AdaptiveBinaryTree {
 public:
  /// Hard limit on depth; bounds the fixed traversal stacks.
  static constexpr std::uint32_t depth_limit = 64;

  /// An empty tree (culls to nothing).
  AdaptiveBinaryTree() = default;

  /// Builds over `objects[0, count)`. Objects whose bounds are not `is_valid` (NaN, infinite,
  /// inverted) are skipped, counted in `stats().skipped`, and never returned.
  /// pre: `objects` points to `count` objects (may be null when count is 0).
  /// Cost: O(n log n) time, O(n) memory; allocates. Thread safety: reads `objects` only.
  AdaptiveBinaryTree(const Object* objects, std::size_t count, const AbtParams& params = {}) {
    static_assert(require_bounds_traits<Object, Traits>::value, "");
    CULLKIT_ASSERT(objects != nullptr || count == 0, "objects points to count objects");
    if constexpr (has_bounds_traits_v<Object, Traits>) {
      if (objects == nullptr) count = 0;
      build([objects](std::uint32_t i) { return Aabb(Traits::bounds(objects[i])); }, count, params);
    }
  }

  /// Builds over `count` objects whose bounds are `get_bounds(i)` for i in [0, count): a stateful
  /// getter may index into the caller's own buffers. Same rules and cost as the constructor; the
  /// getter is called once per object, from the calling thread.
  template <class Getter>
  [[nodiscard]] static AdaptiveBinaryTree from_getter(std::size_t count, Getter&& get_bounds,
                                                      const AbtParams& params = {}) {
    static_assert(is_bounds_getter_v<std::decay_t<Getter>>,
                  "cullkit: from_getter needs a callable get_bounds(std::uint32_t) returning cullkit::Aabb");
    AdaptiveBinaryTree tree;
    tree.build(get_bounds, count, params);
    return tree;
  }

  // ---------------------------------------------------------------------------------------------
  // Queries
  // ---------------------------------------------------------------------------------------------

  /// Clears `out`, then appends the input index of every held object whose box may meet the
  /// frustum, each once, grouped by subtree (not sorted). Never leaves out an object whose box
  /// meets the frustum. Cost: O(visible + boundary nodes). Allocation: only growth of `out`.
  /// Thread safety: concurrent calls on one tree are safe (with distinct `out`).
  void cull(const Frustum& frustum, std::vector<std::uint32_t>& out) const {
    out.clear();
    cull(frustum, [&](std::uint32_t b, std::uint32_t e, Containment) {
      if (e - b == 1) out.push_back(order_[b]);
      else out.insert(out.end(), order_.begin() + b, order_.begin() + e);
    });
  }

  /// Visitor form of `cull`: `visitor(begin, end, containment)` receives ranges of `order()`
  /// positions, disjoint, together covering every object that may meet the frustum. `inside`
  /// ranges (whole subtrees, or single objects) are certainly inside; `intersecting` ones are
  /// single objects that may straddle the boundary. The visitor may return `bool`: false stops the
  /// walk at once (early exit); a `void` visitor sees everything. No allocation.
  template <class Visitor, class = std::enable_if_t<!std::is_same_v<std::decay_t<Visitor>, std::vector<std::uint32_t>>>>
  void cull(const Frustum& frustum, Visitor&& visitor) const {
    if (nodes_.empty()) return;
    struct Entry {
      std::uint32_t node;
      PlaneMask mask;
    };
    Entry stack[depth_limit + 2];
    std::uint32_t top = 0;
    stack[top++] = Entry{0, frustum.active_mask()};
    const AbtNode* nodes = nodes_.data();
    while (top > 0) {
      const Entry entry = stack[--top];
      const AbtNode& node = nodes[entry.node];
      PlaneMask mask = entry.mask;
      if (node_outside(frustum, node, mask)) continue;
      if (mask == 0) {
        if (!call(visitor, node.begin, node.end, Containment::inside)) return;
        continue;
      }
      if (node.is_leaf() || node.count() <= scan_below_) {
        // A leaf, or a small subtree (its objects are contiguous too): objects one by one, only
        // the planes the node straddles, several objects per step.
        const bool go_on = leaf_boxes_.test(frustum, mask, node.begin, node.end, [&](std::uint32_t i, Containment c) {
          return call(visitor, i, i + 1, c);
        });
        if (!go_on) return;
        continue;
      }
      stack[top++] = Entry{node.left + 1, mask};
      stack[top++] = Entry{node.left, mask};
    }
  }

  /// Frustum and occlusion culling: clears `out`, then appends, in front-to-back order from
  /// `occlusion.eye()`, the input index of every held object that may meet the frustum and that
  /// `occlusion` does not hide. Nodes are tested against the frustum (sphere, box, plane masks),
  /// then with `occlusion.is_occluded(node.bounds)`: a hidden node drops its subtree. At a leaf,
  /// each object is tested on its own (frustum, then occlusion).
  /// `Occlusion` needs `const glm::vec3& eye() const` and `bool is_occluded(const Aabb&) const`
  /// (cullkit::OcclusionTree has both); `is_occluded` must only say true for boxes that are
  /// entirely hidden. Cost: one occlusion query per visited node and per tested object.
  /// Allocation: only growth of `out`.
  template <class Occlusion>
  void cull(const Frustum& frustum, const Occlusion& occlusion, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (nodes_.empty()) return;
    const glm::vec3 eye = occlusion.eye();
    struct Entry {
      std::uint32_t node;
      PlaneMask mask;
    };
    Entry stack[depth_limit + 2];
    std::uint32_t top = 0;
    stack[top++] = Entry{0, frustum.active_mask()};
    while (top > 0) {
      const Entry entry = stack[--top];
      const AbtNode& node = nodes_[entry.node];
      PlaneMask mask = entry.mask;
      if (node_outside(frustum, node, mask)) continue;
      if (occlusion.is_occluded(node.bounds)) continue;
      if (node.is_leaf()) {
        for (std::uint32_t i = node.begin; i < node.end; ++i) {
          PlaneMask m = mask;
          if (m != 0 && frustum.classify(bounds_[i], m) == Containment::outside) continue;
          if (node.count() > 1 && occlusion.is_occluded(bounds_[i])) continue;
          out.push_back(order_[i]);
        }
        continue;
      }
      const bool left_first = near_is_left(node, eye);
      // Pushed far child first, so the near child is popped (visited) first.
      stack[top++] = Entry{left_first ? node.left + 1 : node.left, mask};
      stack[top++] = Entry{left_first ? node.left : node.left + 1, mask};
    }
  }

  /// Pre-order walk in front-to-back order from `eye`: at every inner node, the child on the eye's
  /// side of the split plane comes first (the BSP order; an eye exactly on the plane takes the
  /// right child first). `visitor(node_index, const AbtNode&)` returns whether to descend into that
  /// node's children (a `void` visitor descends everywhere). Because child boxes may overlap
  /// (objects straddling a split stay whole), the order is exact for split planes and centroids,
  /// approximate for overlapping boxes; after `refit` it follows the build-time planes.
  /// No allocation; safe to run concurrently.
  template <class Visitor>
  void traverse_front_to_back(const glm::vec3& eye, Visitor&& visitor) const {
    traverse(eye, true, visitor);
  }
  /// The reverse order (far child first), e.g. for sorted transparent draws. Same rules.
  template <class Visitor>
  void traverse_back_to_front(const glm::vec3& eye, Visitor&& visitor) const {
    traverse(eye, false, visitor);
  }

  // ---------------------------------------------------------------------------------------------
  // Moving objects
  // ---------------------------------------------------------------------------------------------

  /// After objects moved: re-reads every held object's bounds from `objects` (the same array layout
  /// as at build, at least as long) and recomputes every node's box and sphere bottom-up. The
  /// topology and `order()` are kept; split planes keep their build-time values. An object whose
  /// new bounds are not valid keeps its previous bounds and is counted in `stats().refit_invalid`.
  /// Objects skipped at build stay out. Cost: O(n), no allocation. Not thread-safe with queries.
  void refit(const Object* objects) {
    static_assert(require_bounds_traits<Object, Traits>::value, "");
    if constexpr (has_bounds_traits_v<Object, Traits>) {
      CULLKIT_ASSERT(objects != nullptr || order_.empty(), "objects points to the objects of the build");
      if (objects == nullptr) return;
      refit_from_getter([objects](std::uint32_t i) { return Aabb(Traits::bounds(objects[i])); });
    }
  }

  /// `refit` through a getter: `get_bounds(i)` for the input indices of the build (same as
  /// `refit_from_getter`; chosen when the argument is callable with a std::uint32_t).
  template <class Getter, class = std::enable_if_t<is_bounds_getter_v<std::decay_t<Getter>>>>
  void refit(Getter&& get_bounds) {
    refit_from_getter(get_bounds);
  }

  /// `refit` through a getter: `get_bounds(i)` for the input indices of the build.
  template <class Getter>
  void refit_from_getter(Getter&& get_bounds) {
    static_assert(is_bounds_getter_v<std::decay_t<Getter>>,
                  "cullkit: refit_from_getter needs a callable get_bounds(std::uint32_t) returning cullkit::Aabb");
    stats_.refit_invalid = 0;
    for (std::size_t i = 0; i < order_.size(); ++i) {
      const Aabb b = get_bounds(order_[i]);
      if (is_valid(b)) {
        bounds_[i] = b;
        leaf_boxes_.set(static_cast<std::uint32_t>(i), b);
      } else {
        ++stats_.refit_invalid;
      }
    }
    // Children always follow their parent in the array, so a reverse sweep is bottom-up.
    for (std::size_t k = nodes_.size(); k-- > 0;) {
      AbtNode& node = nodes_[k];
      Aabb box = Aabb::empty();
      if (node.is_leaf()) {
        for (std::uint32_t i = node.begin; i < node.end; ++i) box = merge(box, bounds_[i]);
      } else {
        box = merge(nodes_[node.left].bounds, nodes_[node.left + 1].bounds);
      }
      node.bounds = box;
      node.sphere = bounding_sphere(box);
    }
    refitted_ = true;
  }

  /// Sum of node surface areas now over the sum at build: 1 right after a build, growing as
  /// objects move apart from their build-time neighbours. A rebuild is worth it when this passes
  /// about 1.5 to 2 (culling cost grows roughly with it). 1 for an empty tree.
  [[nodiscard]] double refit_quality() const noexcept {
    if (!(build_area_ > 0.0)) return 1.0;
    return total_area() / build_area_;
  }

  // ---------------------------------------------------------------------------------------------
  // Read-only views
  // ---------------------------------------------------------------------------------------------

  /// Every node; node 0 is the root; children follow their parent. Empty for an empty tree.
  [[nodiscard]] const std::vector<AbtNode>& nodes() const noexcept { return nodes_; }
  /// Position -> input index of the object: node ranges `[begin, end)` index into this.
  [[nodiscard]] const std::vector<std::uint32_t>& order() const noexcept { return order_; }
  /// Bounds of the object at each position of `order()` (as of the build or the last refit).
  [[nodiscard]] const std::vector<Aabb>& object_bounds() const noexcept { return bounds_; }
  /// Objects held (skipped ones excluded).
  [[nodiscard]] std::size_t size() const noexcept { return order_.size(); }
  [[nodiscard]] bool empty() const noexcept { return order_.empty(); }
  /// Number of objects given to the build (held + skipped).
  [[nodiscard]] std::size_t input_count() const noexcept { return input_count_; }
  [[nodiscard]] const AbtStats& stats() const noexcept { return stats_; }

  /// Writes into `out` the index buffer of `mesh` permuted to the tree's order, for a tree built
  /// over the mesh's triangles (see `make_triangle_tree`): the triangles of the node range
  /// [begin, end) are `out[3 * begin, 3 * end)`. Skipped triangles are left out. Allocates `out`.
  /// pre: the tree was built over exactly this mesh's triangles.
  template <class Vertex, class Index>
  void reorder_indices(const MeshView<Vertex, Index>& mesh, std::vector<Index>& out) const {
    out.clear();
    out.reserve(order_.size() * 3);
    for (const std::uint32_t t : order_) {
      CULLKIT_ASSERT(t < mesh.triangle_count(), "tree built over this mesh");
      if (t >= mesh.triangle_count()) continue;
      const std::size_t base = std::size_t{t} * 3;
      out.push_back(mesh.indices[base]);
      out.push_back(mesh.indices[base + 1]);
      out.push_back(mesh.indices[base + 2]);
    }
  }

  /// Checks the invariants: every node box encloses its children and objects, spheres enclose
  /// their boxes, child ranges partition their parent's range, every held object is at exactly one
  /// position, depth within the limit, split planes separate centroids (until the first refit).
  /// Cost O(n + nodes), allocates a little. For tests and debugging.
  [[nodiscard]] bool validate() const {
    if (bounds_.size() != order_.size()) return false;
    if (nodes_.empty()) return order_.empty();
    const auto n = static_cast<std::uint32_t>(order_.size());
    std::vector<std::uint8_t> seen(input_count_, 0);
    for (const std::uint32_t idx : order_) {
      if (idx >= input_count_ || seen[idx]) return false;
      seen[idx] = 1;
    }
    if (nodes_[0].begin != 0 || nodes_[0].end != n) return false;
    std::vector<std::uint32_t> depth(nodes_.size(), 0);
    std::uint32_t leaves = 0, max_depth = 0;
    std::vector<std::uint8_t> reached(nodes_.size(), 0);
    reached[0] = 1;
    for (std::size_t k = 0; k < nodes_.size(); ++k) {
      const AbtNode& node = nodes_[k];
      if (!reached[k]) return false;
      if (node.begin >= node.end || node.end > n) return false;
      if (!sphere_encloses(node.sphere, node.bounds)) return false;
      max_depth = std::max(max_depth, depth[k]);
      if (node.is_leaf()) {
        ++leaves;
        for (std::uint32_t i = node.begin; i < node.end; ++i) {
          if (!contains(node.bounds, bounds_[i])) return false;
        }
        continue;
      }
      const std::size_t l = node.left;
      if (l <= k || l + 1 >= nodes_.size() || reached[l] || reached[l + 1]) return false;
      reached[l] = reached[l + 1] = 1;
      depth[l] = depth[l + 1] = depth[k] + 1;
      const AbtNode& a = nodes_[l];
      const AbtNode& b = nodes_[l + 1];
      if (a.begin != node.begin || a.end != b.begin || b.end != node.end) return false;
      if (!contains(node.bounds, a.bounds) || !contains(node.bounds, b.bounds)) return false;
      if (node.axis > 2) return false;
      if (!refitted_) {
        for (std::uint32_t i = a.begin; i < a.end; ++i) {
          if (!(detail::abt_centroid(bounds_[i])[node.axis] < node.split)) return false;
        }
        for (std::uint32_t i = b.begin; i < b.end; ++i) {
          if (detail::abt_centroid(bounds_[i])[node.axis] < node.split) return false;
        }
      }
    }
    if (max_depth > depth_limit) return false;
    return leaves == stats_.leaves && max_depth == stats_.depth && nodes_.size() == stats_.nodes;
  }

 private:
  template <class Visitor, class... Args>
  static bool call(Visitor& visitor, const Args&... args) {
    if constexpr (std::is_same_v<decltype(visitor(args...)), void>) {
      visitor(args...);
      return true;
    } else {
      return static_cast<bool>(visitor(args...));
    }
  }

  // The node test of every top-down walk, in the seed's order: the sphere first (cheap; it may
  // settle the whole subtree), then the box. Clears from `mask` the planes the node is inside of.
  static bool node_outside(const Frustum& frustum, const AbtNode& node, PlaneMask& mask) noexcept {
    if (mask == 0) return false;
    const Containment c = frustum.classify(node.sphere, mask);
    if (c == Containment::outside) return true;
    return c != Containment::inside && frustum.classify(node.bounds, mask) == Containment::outside;
  }

  static bool near_is_left(const AbtNode& node, const glm::vec3& eye) noexcept {
    return eye[node.axis] < node.split;
  }

  static bool sphere_encloses(const Sphere& s, const Aabb& b) {
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 p = corner(b, c);
      double d2 = 0.0;
      for (int a = 0; a < 3; ++a) {
        const double d = double(p[a]) - double(s.center[a]);
        d2 += d * d;
      }
      if (!(d2 <= double(s.radius) * double(s.radius))) return false;
    }
    return true;
  }

  template <class Visitor>
  void traverse(const glm::vec3& eye, bool front_first, Visitor& visitor) const {
    if (nodes_.empty()) return;
    std::uint32_t stack[depth_limit + 2];
    std::uint32_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const std::uint32_t k = stack[--top];
      const AbtNode& node = nodes_[k];
      if (!call(visitor, k, node)) continue;
      if (node.is_leaf()) continue;
      const bool left_first = near_is_left(node, eye) == front_first;
      stack[top++] = left_first ? node.left + 1 : node.left;
      stack[top++] = left_first ? node.left : node.left + 1;
    }
  }

  [[nodiscard]] double total_area() const noexcept {
    double sum = 0.0;
    for (const AbtNode& node : nodes_) sum += detail::abt_area(node.bounds);
    return sum;
  }

  // ---- build ----------------------------------------------------------------------------------

  struct Task {
    std::uint32_t node;  // index in the top-level node array (a placeholder until stitched)
    std::uint32_t begin, end, depth;
    Aabb box, centroids;
  };

  // Bounds of items [begin, end) and of their centroids.
  static void range_bounds(const detail::AbtBuildItem* items, std::uint32_t begin, std::uint32_t end, Aabb& box,
                           Aabb& centroids) {
    box = Aabb::empty();
    centroids = Aabb::empty();
    for (std::uint32_t i = begin; i < end; ++i) {
      box = merge(box, items[i].box);
      centroids = merge(centroids, items[i].centroid);
    }
  }

  struct BuildContext {
    detail::AbtBuildItem* items = nullptr;
    detail::AbtSplitConfig cfg{};
    std::uint32_t leaf_size = 4;
    std::uint32_t max_depth = 48;
    std::uint32_t grain = 0;  // > 0: defer subtrees below this size as tasks (top-level pass)
    std::vector<Task>* tasks = nullptr;
    // progress
    const std::function<void(float)>* progress = nullptr;
    std::atomic<std::uint32_t>* done = nullptr;
    std::mutex* progress_mutex = nullptr;
    float* progress_last = nullptr;
    std::uint32_t total = 0;
  };

  static void report_leaf(const BuildContext& ctx, std::uint32_t count) {
    if (ctx.progress == nullptr) return;
    const std::uint32_t before = ctx.done->fetch_add(count);
    const std::uint32_t step = std::max<std::uint32_t>(1u, ctx.total / 50u);
    if ((before + count) / step == before / step) return;
    std::lock_guard<std::mutex> lock(*ctx.progress_mutex);
    const float f = std::min(0.999f, float(double(ctx.done->load()) / double(ctx.total)));
    if (f > *ctx.progress_last) {
      *ctx.progress_last = f;
      (*ctx.progress)(f);
    }
  }

  // Builds the subtree of `nodes[node]` over items [begin, end). Children are appended as pairs.
  // `box` and `centroids` are the bounds of the items and of their centroids (from the parent's
  // partition pass, so each level reads the items twice: once to score, once to partition).
  static void build_node(std::vector<AbtNode>& nodes, std::uint32_t node, std::uint32_t begin, std::uint32_t end,
                         std::uint32_t depth, const Aabb& box, const Aabb& centroids, const BuildContext& ctx,
                         detail::AbtSplitScratch& scratch) {
    detail::AbtBuildItem* items = ctx.items;
    {
      AbtNode& n = nodes[node];
      n.bounds = box;
      n.sphere = bounding_sphere(box);
      n.begin = begin;
      n.end = end;
      n.left = 0;
      n.axis = 0;
      n.split = 0.0f;
    }
    const std::uint32_t count = end - begin;
    if (ctx.grain > 0 && count < ctx.grain) {
      ctx.tasks->push_back(Task{node, begin, end, depth, box, centroids});
      return;
    }
    if (count <= ctx.leaf_size || depth >= ctx.max_depth) {
      report_leaf(ctx, count);
      return;
    }
    const std::uint64_t key = (std::uint64_t{begin} << 32) ^ std::uint64_t{end} ^ (std::uint64_t{depth} << 58);
    const detail::AbtSplit split = detail::abt_find_split(items, begin, end, box, centroids, ctx.cfg, key, scratch);
    if (!split.found) {
      report_leaf(ctx, count);
      return;
    }
    const int axis = split.axis;
    const float pos = split.position;
    // Partition (centroid < pos goes left), gathering both children's bounds on the way.
    Aabb lbox = Aabb::empty(), lcen = Aabb::empty(), rbox = Aabb::empty(), rcen = Aabb::empty();
    std::uint32_t i = begin, j = end;
    for (;;) {
      while (i < j && items[i].centroid[axis] < pos) {
        lbox = merge(lbox, items[i].box);
        lcen = merge(lcen, items[i].centroid);
        ++i;
      }
      while (i < j && !(items[j - 1].centroid[axis] < pos)) {
        rbox = merge(rbox, items[j - 1].box);
        rcen = merge(rcen, items[j - 1].centroid);
        --j;
      }
      if (i >= j) break;
      std::swap(items[i], items[j - 1]);  // now items[i] goes left, items[j - 1] right
    }
    const std::uint32_t m = i;
    if (m == begin || m == end) {  // rounding left one side empty: nothing separates
      report_leaf(ctx, count);
      return;
    }
    const auto left = static_cast<std::uint32_t>(nodes.size());
    nodes[node].left = left;
    nodes[node].axis = static_cast<std::uint8_t>(axis);
    nodes[node].split = pos;
    nodes.emplace_back();
    nodes.emplace_back();
    build_node(nodes, left, begin, m, depth + 1, lbox, lcen, ctx, scratch);
    build_node(nodes, left + 1, m, end, depth + 1, rbox, rcen, ctx, scratch);
  }

  template <class Getter>
  void build(Getter&& get_bounds, std::size_t count, const AbtParams& params) {
    nodes_.clear();
    order_.clear();
    bounds_.clear();
    leaf_boxes_.assign(bounds_);
    stats_ = AbtStats{};
    refitted_ = false;
    constexpr std::size_t max_count = std::numeric_limits<std::uint32_t>::max() - 1u;
    CULLKIT_ASSERT(count <= max_count, "fewer than 2^32 - 1 objects");
    const std::size_t usable = std::min(count, max_count);
    input_count_ = usable;
    std::vector<detail::AbtBuildItem> items;
    items.reserve(usable);
    for (std::size_t i = 0; i < usable; ++i) {
      const Aabb b = get_bounds(static_cast<std::uint32_t>(i));
      if (!is_valid(b)) continue;
      items.push_back(detail::AbtBuildItem{b, detail::abt_centroid(b), static_cast<std::uint32_t>(i)});
    }
    stats_.skipped = static_cast<std::uint32_t>(count - items.size());
    const auto n = static_cast<std::uint32_t>(items.size());
    if (n == 0) {
      if (params.progress) params.progress(1.0f);
      build_area_ = 0.0;
      return;
    }

    BuildContext ctx;
    ctx.items = items.data();
    ctx.cfg.weights[0] = params.weight_axis;
    ctx.cfg.weights[1] = params.weight_volume;
    ctx.cfg.weights[2] = params.weight_count;
    ctx.cfg.weights[3] = params.weight_straddle;
    for (float& w : ctx.cfg.weights) w = std::isfinite(w) && w > 0.0f ? w : 0.0f;  // bad weight: off
    ctx.cfg.candidates = std::clamp<std::uint32_t>(params.candidate_count, 1u, 1024u);
    ctx.cfg.sampling = params.candidates == AbtCandidates::sampling;
    ctx.cfg.seed = params.seed;
    scan_below_ = params.scan_below;
    ctx.cfg.sample_limit = params.score_sample_limit;
    ctx.leaf_size = std::max<std::uint32_t>(1u, params.max_leaf_size);
    ctx.max_depth = std::min(params.max_depth, depth_limit);
    std::atomic<std::uint32_t> done{0};
    std::mutex progress_mutex;
    float progress_last = 0.0f;
    if (params.progress && n >= params.progress_min_objects) {
      ctx.progress = &params.progress;
      ctx.done = &done;
      ctx.progress_mutex = &progress_mutex;
      ctx.progress_last = &progress_last;
      ctx.total = n;
    }

    std::vector<AbtNode> raw(1);
    raw.reserve(2 * (n / ctx.leaf_size + 1));
    detail::AbtSplitScratch scratch;
    scratch.reserve(ctx.cfg.candidates);
    Aabb root_box, root_centroids;
    range_bounds(items.data(), 0, n, root_box, root_centroids);
    const unsigned threads = params.threads;
    const std::uint32_t grain = std::max<std::uint32_t>(params.parallel_grain, 2u * ctx.leaf_size + 2u);
    if (threads <= 1 || n < 2 * grain) {
      build_node(raw, 0, 0, n, 0, root_box, root_centroids, ctx, scratch);
    } else {
      // Top levels on this thread, deferring subtrees smaller than the grain; then the deferred
      // subtrees on a pool, each into its own array; then stitched. Split choices depend only on a
      // node's own objects and key, so the tree is the same as a serial build (made identical in
      // layout by the canonical renumbering below).
      std::vector<Task> tasks;
      ctx.grain = grain;
      ctx.tasks = &tasks;
      build_node(raw, 0, 0, n, 0, root_box, root_centroids, ctx, scratch);
      ctx.grain = 0;
      ctx.tasks = nullptr;
      std::vector<std::vector<AbtNode>> local(tasks.size());
      std::atomic<std::size_t> next{0};
      auto worker = [&]() {
        detail::AbtSplitScratch s;
        s.reserve(ctx.cfg.candidates);
        for (;;) {
          const std::size_t t = next.fetch_add(1);
          if (t >= tasks.size()) return;
          std::vector<AbtNode>& sub = local[t];
          sub.resize(1);
          build_node(sub, 0, tasks[t].begin, tasks[t].end, tasks[t].depth, tasks[t].box, tasks[t].centroids, ctx, s);
        }
      };
      std::vector<std::thread> pool;
      const unsigned extra = std::min<unsigned>(threads - 1, static_cast<unsigned>(tasks.size()));
      pool.reserve(extra);
      for (unsigned t = 0; t < extra; ++t) pool.emplace_back(worker);
      worker();
      for (std::thread& th : pool) th.join();
      for (std::size_t t = 0; t < tasks.size(); ++t) {
        const std::vector<AbtNode>& sub = local[t];
        const auto offset = static_cast<std::uint32_t>(raw.size()) - 1u;  // sub[1] lands at raw.size()
        AbtNode root = sub[0];
        if (!root.is_leaf()) root.left += offset;
        raw[tasks[t].node] = root;
        for (std::size_t k = 1; k < sub.size(); ++k) {
          AbtNode nd = sub[k];
          if (!nd.is_leaf()) nd.left += offset;
          raw.push_back(nd);
        }
      }
    }

    // Canonical layout: pre-order, each inner node's children allocated as a pair when the node
    // is visited, left subtree before right. Identical for every thread count.
    nodes_.resize(raw.size());
    {
      struct Move {
        std::uint32_t from, to, depth;
      };
      std::vector<Move> stack;
      stack.push_back(Move{0, 0, 0});
      std::uint32_t next = 1;
      while (!stack.empty()) {
        const Move mv = stack.back();
        stack.pop_back();
        AbtNode nd = raw[mv.from];
        stats_.depth = std::max(stats_.depth, mv.depth);
        if (nd.is_leaf()) {
          ++stats_.leaves;
          stats_.max_leaf_objects = std::max(stats_.max_leaf_objects, nd.count());
        } else {
          const std::uint32_t l = next;
          next += 2;
          stack.push_back(Move{nd.left + 1, l + 1, mv.depth + 1});
          stack.push_back(Move{nd.left, l, mv.depth + 1});
          nd.left = l;
        }
        nodes_[mv.to] = nd;
      }
    }
    stats_.nodes = static_cast<std::uint32_t>(nodes_.size());
    stats_.objects = n;
    order_.resize(n);
    bounds_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      order_[i] = items[i].index;
      bounds_[i] = items[i].box;
    }
    leaf_boxes_.assign(bounds_);
    build_area_ = total_area();
    if (params.progress) params.progress(1.0f);
  }

  std::vector<AbtNode> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<Aabb> bounds_;
  detail::AbtLeafBoxes leaf_boxes_;  // bounds_ again, as padded SoA for the leaf tests
  std::size_t input_count_ = 0;
  AbtStats stats_;
  double build_area_ = 0.0;
  bool refitted_ = false;
  std::uint32_t scan_below_ = 64;
};

/// Builds a tree whose objects are the triangles of `mesh` (object i = triangle i, bounds = the
/// box of its corners). Triangles with an index out of range or a non-finite corner are skipped
/// and counted; degenerate (zero-area) triangles are kept. Pair with `reorder_indices` to draw
/// visible ranges directly. `VTraits` reads vertex positions (default `VertexTraits<Vertex>`).
template <class Vertex, class Index = std::uint32_t, class VTraits = VertexTraits<Vertex>>
[[nodiscard]] AdaptiveBinaryTree<Aabb> make_triangle_tree(const MeshView<Vertex, Index>& mesh,
                                                          const AbtParams& params = {}) {
  static_assert(require_vertex_traits<Vertex, VTraits>::value, "");
  return AdaptiveBinaryTree<Aabb>::from_getter(
      mesh.triangle_count(),
      [&mesh](std::uint32_t t) {
        glm::vec3 p[3] = {};
        const float nan = std::numeric_limits<float>::quiet_NaN();
        if (!triangle_positions<VTraits>(mesh, t, p)) return Aabb{glm::vec3(nan), glm::vec3(nan)};
        for (const glm::vec3& q : p) {
          // merge() would silently drop a NaN coordinate (min/max comparisons), so test first.
          if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) return Aabb{glm::vec3(nan), glm::vec3(nan)};
        }
        return merge(merge(Aabb{p[0], p[0]}, p[1]), p[2]);
      },
      params);
}

}  // namespace cullkit
