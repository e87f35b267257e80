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
// An object whose bounds are NaN, infinite or inverted (at the build or at a refit) is held with
// `unbounded_box()` and reported by every cull, whatever the view: a skybox with infinite bounds is
// drawn, and a transform that was NaN for one frame is forgotten at the next valid refit.
//
// Views beyond one frustum: `cull(ConvexVolume)` (portals, shadow casters, user planes) and
// `cull_views` (up to 32 frusta in one walk, a bit per view: stereo eyes, shadow cascades).
//
// Thread safety: a built tree changes only through `refit`, `insert`, `remove` and `update`
// (stable ids, O(log n) amortized); concurrent `const` queries are safe. The build may use worker threads (`AbtParams::threads`); its result never depends on them.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "abt_params.hpp"
#include "config.hpp"
#include "detail/abt/build.hpp"
#include "detail/abt/dynamic.hpp"
#include "detail/abt/leaf.hpp"
#include "detail/abt/occlusion_walk.hpp"
#include "detail/abt/repair.hpp"
#include "detail/abt/split.hpp"
#include "detail/abt/validate.hpp"
#include "detail/abt/views.hpp"
#include "geometry/aabb.hpp"
#include "geometry/convex_volume.hpp"
#include "geometry/frustum.hpp"
#include "geometry/sphere.hpp"
#include "traits.hpp"

namespace cullkit {

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
  /// inverted) are held with `unbounded_box()`, counted in `stats().unbounded`, and reported by
  /// every cull. Only objects beyond the first 2^32 - 2 are skipped (`stats().skipped`).
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

  /// `from_getter` with the data first and the count second, as in the constructor's
  /// `(objects, count)`. Both spellings build the same tree.
  template <class Getter, class = std::enable_if_t<is_bounds_getter_v<std::decay_t<Getter>>>>
  [[nodiscard]] static AdaptiveBinaryTree from_getter(Getter&& get_bounds, std::size_t count,
                                                      const AbtParams& params = {}) {
    AdaptiveBinaryTree tree;
    tree.build(get_bounds, count, params);
    return tree;
  }

  // ---- Queries

  /// Clears `out`, then appends the input index of every held object whose box may meet the
  /// frustum, each once, grouped by subtree (not sorted). Never leaves out an object whose box
  /// meets the frustum; objects without valid bounds are always in. A frustum whose planes were
  /// all dropped (a NaN or singular matrix) keeps everything. Cost: O(visible + boundary nodes).
  /// Allocation: only growth of `out`. Thread safety: concurrent calls on one tree are safe (with
  /// distinct `out`).
  void cull(const Frustum& frustum, std::vector<std::uint32_t>& out) const {
    out.clear();
    walk(&frustum.plane(0), frustum.active_mask(), [&](std::uint32_t b, std::uint32_t e, Containment) {
      append_range(out, b, e);
    });
  }

  /// Visitor form of `cull`: `visitor(begin, end, containment)` receives ranges of `order()`
  /// positions, disjoint, together covering every object that may meet the frustum. `inside`
  /// ranges (whole subtrees, or single objects) are certainly inside; `intersecting` ones are
  /// single objects that may straddle the boundary (or have no valid bounds). The visitor may
  /// return `bool`: false stops the walk at once (early exit); a `void` visitor sees everything.
  /// No allocation.
  template <class Visitor, class = std::enable_if_t<!std::is_same_v<std::decay_t<Visitor>, std::vector<std::uint32_t>>>>
  void cull(const Frustum& frustum, Visitor&& visitor) const {
    walk(&frustum.plane(0), frustum.active_mask(), visitor);
  }

  /// The same as `cull(Frustum, out)` for a convex volume of up to 32 planes (a frustum narrowed by
  /// a portal, a shadow-caster volume, a view with user clip planes). A volume without planes keeps
  /// everything. Same cost, allocation and thread safety.
  void cull(const ConvexVolume& volume, std::vector<std::uint32_t>& out) const {
    out.clear();
    walk(volume.plane_count() > 0 ? &volume.plane(0) : nullptr, volume.full_mask(),
         [&](std::uint32_t b, std::uint32_t e, Containment) { append_range(out, b, e); });
  }

  /// Visitor form of `cull(ConvexVolume, out)`, with the rules of the frustum visitor form.
  template <class Visitor, class = std::enable_if_t<!std::is_same_v<std::decay_t<Visitor>, std::vector<std::uint32_t>>>>
  void cull(const ConvexVolume& volume, Visitor&& visitor) const {
    walk(volume.plane_count() > 0 ? &volume.plane(0) : nullptr, volume.full_mask(), visitor);
  }

  /// Up to 32 views in one walk. Clears `out` and `view_bits`, then appends every held object that
  /// may meet some frustum of `frusta[0, view_count)`, once, with `view_bits[i]` (parallel to
  /// `out`) holding bit v set when `out[i]` may meet `frusta[v]`; a bit is never clear for a view
  /// the object's box meets. Objects without valid bounds carry every view's bit. View v's bits
  /// hold every object `cull(frusta[v], ...)` reports; planes that two views share up to rounding
  /// (same normal, offsets within 2^-18 relative: the eyes of a headset, cascades of one camera)
  /// are tested once at the looser offset, so a view may also get an object that far outside it.
  /// pre: `view_count <= 32` (views beyond the 32nd are ignored) and `frusta` points to them.
  /// Cost: one walk over the views' distinct planes (up to 32 of them; beyond that, a walk that
  /// tests each view's planes). It pays where views overlap and share planes: a stereo or headset
  /// pair costs about 0.55-0.8 of two separate culls, depth slices of one camera 0.5-0.95 of theirs
  /// (bench_views). Views that share no plane and overlap little, such as light-space shadow
  /// cascades, gain nothing: the per-object view bits double the output, and such a set can cost up
  /// to 1.3 times its separate culls; cull those one by one when per-view lists are what is drawn.
  /// Allocation: growth of `out` and `view_bits` only. Thread safety: as `cull`.
  void cull_views(const Frustum* frusta, std::size_t view_count, std::vector<std::uint32_t>& out,
                  std::vector<std::uint32_t>& view_bits) const {
    out.clear();
    view_bits.clear();
    CULLKIT_ASSERT(view_count <= 32, "view_count <= 32");
    CULLKIT_ASSERT(frusta != nullptr || view_count == 0, "frusta points to view_count frusta");
    if (frusta == nullptr || view_count == 0 || order_.empty()) return;
    const auto views = static_cast<std::uint32_t>(std::min<std::size_t>(view_count, 32));
    detail::abt_cull_views<depth_limit + 2>(nodes_, order_, leaf_boxes_, dyn_, scan_below_, frusta, views, out,
                                            view_bits);
  }

  /// Frustum and occlusion culling: clears `out`, then appends, in front-to-back order from
  /// `occlusion.eye()`, the input index of every held object that may meet the frustum and that
  /// `occlusion` does not hide. Nodes are tested against the frustum (sphere, box, plane masks),
  /// then with `occlusion.is_occluded(node.bounds)`: a hidden node drops its subtree. At a leaf,
  /// each object is tested on its own (frustum, then occlusion).
  /// `Occlusion` needs `const glm::vec3& eye() const` and `bool is_occluded(const Aabb&) const`
  /// (cullkit::OcclusionTree has both); `is_occluded` must only say true for boxes that are
  /// entirely hidden. Boxes that are `is_unbounded` (objects without valid bounds and their
  /// ancestors) are never queried: such objects are always reported.
  /// Cost: one occlusion query per visited node and per tested object.
  /// Allocation: only growth of `out`.
  template <class Occlusion>
  void cull(const Frustum& frustum, const Occlusion& occlusion, std::vector<std::uint32_t>& out) const {
    out.clear();
    struct NoState {};
    detail::AbtOcclusionWalkCounts counts;
    detail::abt_occlusion_walk(
        *this, frustum, occlusion.eye(), NoState{}, true,
        [&occlusion](const Aabb& box, NoState&) { return !occlusion.is_occluded(box); },
        [&](std::uint32_t pos, const NoState&) { out.push_back(order_[pos]); }, counts);
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

  // ---- Moving objects

  /// After objects moved: re-reads every held object's bounds from `objects` (the same array layout
  /// as at build, at least as long) and recomputes every node's box and sphere bottom-up. The
  /// topology and `order()` are kept; split planes keep their build-time values. An object whose
  /// new bounds are not valid gets `unbounded_box()` (reported by every cull until a later refit
  /// gives it valid bounds) and is counted in `stats().refit_invalid` and `stats().unbounded`; an
  /// object that had no valid bounds and now has them is culled by them from now on.
  /// Cost: O(n), no allocation. Not thread-safe with queries. The tree's quality falls as objects
  /// move away from their build-time neighbours (`refit_quality`); the repairing overload below
  /// bounds that loss.
  void refit(const Object* objects) {
    static_assert(require_bounds_traits<Object, Traits>::value, "");
    if constexpr (has_bounds_traits_v<Object, Traits>) {
      CULLKIT_ASSERT(objects != nullptr || order_.empty(), "objects points to the objects of the build");
      if (objects == nullptr) return;
      refit_from_getter([objects](std::uint32_t i) { return Aabb(Traits::bounds(objects[i])); });
    }
  }

  /// Repairing refit: `refit(objects)`, then `repair(params.rebuild_threshold)`: the topmost
  /// subtrees whose root's children have come to overlap (see AbtRefitParams) are rebuilt in place
  /// from the current bounds (their objects are re-split among their children). Returns the number of subtrees rebuilt (also in `stats().subtrees_rebuilt`, with
  /// their object count in `stats().objects_rebuilt`).
  /// Unlike the plain refit, `order()` may be permuted inside each rebuilt subtree's range (a
  /// triangle tree's reordered index buffer must then be rebuilt with `reorder_indices`; the
  /// return value says whether). Cost: O(n) plus O(m log m) for the m objects rebuilt; allocates
  /// O(m) while it runs. Measured (AbtRefitParams): the tree's node area stays within a small
  /// factor of a fresh build's instead of growing without bound.
  std::uint32_t refit(const Object* objects, const AbtRefitParams& params) {
    refit(objects);
    return repair(params.rebuild_threshold);
  }

  /// `refit` through a getter: `get_bounds(i)` for the input indices of the build (same as
  /// `refit_from_getter`; chosen when the argument is callable with a std::uint32_t).
  template <class Getter, class = std::enable_if_t<is_bounds_getter_v<std::decay_t<Getter>>>>
  void refit(Getter&& get_bounds) {
    refit_from_getter(get_bounds);
  }

  /// Repairing refit through a getter (see `refit(objects, params)`).
  template <class Getter, class = std::enable_if_t<is_bounds_getter_v<std::decay_t<Getter>>>>
  std::uint32_t refit(Getter&& get_bounds, const AbtRefitParams& params) {
    refit_from_getter(get_bounds);
    return repair(params.rebuild_threshold);
  }

  /// `refit` through a getter: `get_bounds(i)` for the input indices of the build.
  template <class Getter>
  void refit_from_getter(Getter&& get_bounds) {
    static_assert(is_bounds_getter_v<std::decay_t<Getter>>,
                  "cullkit: refit_from_getter needs a callable get_bounds(std::uint32_t) returning cullkit::Aabb");
    stats_.refit_invalid = 0;
    dyn_.pending_box = Aabb::empty();
    for (std::size_t i = 0; i < order_.size(); ++i) {
      if (dyn_.is_hole(static_cast<std::uint32_t>(i))) continue;
      Aabb b = get_bounds(order_[i]);
      if (!is_valid(b)) {
        ++stats_.refit_invalid;
        b = unbounded_box();
      }
      bounds_[i] = b;
      leaf_boxes_.set(static_cast<std::uint32_t>(i), b);
      if (i >= dyn_.tree_end) dyn_.pending_box = merge(dyn_.pending_box, b);
    }
    stats_.unbounded = stats_.refit_invalid;
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

  /// The repair step of the repairing refit, on the current bounds. For an inner node, the split
  /// ratio is (area of the left child + area of the right child) / own area: about 1.3 for a
  /// good split of evenly spread objects, towards 2 as moving objects make the children overlap.
  /// The topmost nodes whose split ratio has gone the fraction `rebuild_threshold` of the way from
  /// its value when they were built towards 2 are rebuilt with their subtrees. The test is local to each node, so the loss allowed at
  /// one level does not compound with the levels above. Returns the number of subtrees rebuilt.
  /// `rebuild_threshold` outside (0, 1) or NaN: nothing.
  std::uint32_t repair(double rebuild_threshold) {
    stats_.subtrees_rebuilt = 0;
    stats_.objects_rebuilt = 0;
    if (!(rebuild_threshold > 0.0 && rebuild_threshold < 1.0) || order_.empty()) return 0;
    if (dyn_.dead != 0 || dyn_.tree_end < order_.size()) {  // holes or pending: one full rebuild
      stats_.objects_rebuilt = static_cast<std::uint32_t>(size());
      rebuild_live();
      return stats_.subtrees_rebuilt = 1;
    }
    detail::abt_repair(rebuild_threshold, build_context_, nodes_, ref_split_, order_, bounds_, leaf_boxes_, stats_);
    if (stats_.subtrees_rebuilt != 0)
      for (std::size_t p = 0; p < order_.size(); ++p) dyn_.pos_of[order_[p]] = static_cast<std::uint32_t>(p);
    return stats_.subtrees_rebuilt;
  }

  /// Sum of node surface areas now over the sum at the last full build: 1 right after a build,
  /// growing as objects move apart from their build-time neighbours (repairs bring it back down).
  /// A rebuild (or the repairing refit) is worth it when this passes about 1.5 to 2 (culling cost
  /// grows roughly with it). Boxes that are `is_unbounded` are left out of both sums. 1 for an
  /// empty tree.
  [[nodiscard]] double refit_quality() const noexcept {
    if (!(build_area_ > 0.0)) return 1.0;
    return total_area() / build_area_;
  }

  // ---- Incremental changes. Ids are stable: the build's objects have ids 0..count-1 (their input
  // ---- index), `insert` hands out more; every cull reports ids. Internals: detail/abt/dynamic.hpp.

  /// Returned by `insert` when no id is left (2^32 - 2 ids in use).
  static constexpr std::uint32_t invalid_id = detail::abt_no_position;

  /// Adds an object with `bounds` and returns its id: the most recently removed id if there is
  /// one, else the next unused (`input_count()` before the call). Bounds that are not `is_valid`
  /// make it unbounded (reported by every cull, counted in `stats().unbounded`). Every cull
  /// reports it from now on. Cost: amortized O(log n) (see `maintain`); allocates amortized O(1).
  /// Not thread-safe with queries.
  std::uint32_t insert(const Aabb& bounds) {
    std::uint32_t id;
    if (!dyn_.free_ids.empty()) {
      id = dyn_.free_ids.back();
      dyn_.free_ids.pop_back();
    } else {
      if (input_count_ >= std::numeric_limits<std::uint32_t>::max() - 1u) return invalid_id;
      id = static_cast<std::uint32_t>(input_count_++);
      dyn_.pos_of.resize(input_count_, detail::abt_no_position);
    }
    append_pending(id, held_box(bounds));
    ++stats_.objects;
    after_change();
    return id;
  }

  /// Removes the object `id`: no cull reports it from now on, and `insert` may hand the id out
  /// again. Returns false (and changes nothing) for an id that is not held: never given out,
  /// or already removed. Cost: amortized O(log n). Not thread-safe with queries.
  bool remove(std::uint32_t id) {
    if (!holds(id)) return false;
    const std::uint32_t p = dyn_.pos_of[id];
    dyn_.pos_of[id] = detail::abt_no_position;
    dyn_.free_ids.push_back(id);
    if (is_unbounded_marker(bounds_[p])) --stats_.unbounded;
    if (p >= dyn_.tree_end) {  // pending: the last pending object takes its place
      const std::size_t last = order_.size() - 1;
      order_[p] = order_[last];
      bounds_[p] = bounds_[last];
      leaf_boxes_.set(p, bounds_[p]);
      dyn_.pos_of[order_[p]] = p;
      order_.pop_back();
      bounds_.pop_back();
      leaf_boxes_.pop_back();
    } else {  // a hole in the tree's range, counted on its path
      std::uint32_t path[depth_limit + 2];
      detail::abt_make_hole(dyn_, order_, nodes_.size(), p, path, detail::abt_path_to(nodes_, p, path));
    }
    --stats_.objects;
    after_change();
    return true;
  }

  /// New bounds for the object `id` (a moving object). A box that stays near its leaf (the leaf's
  /// box grown to it has at most 1.5 times its area) is refitted in place: its box and the boxes
  /// of the nodes on its path follow at once. A box that jumped away (or became unbounded) leaves
  /// a hole and joins the pending objects, so one teleport cannot stretch a path of boxes across
  /// the scene. Returns false for an id that is not held. Invalid bounds make it unbounded until a
  /// later update. Cost: amortized O(log n + leaf size). Not thread-safe with queries.
  bool update(std::uint32_t id, const Aabb& bounds) {
    if (!holds(id)) return false;
    const std::uint32_t p = dyn_.pos_of[id];
    if (is_unbounded_marker(bounds_[p])) --stats_.unbounded;
    const Aabb b = held_box(bounds);
    std::uint32_t path[depth_limit + 2], len = 0;
    if (p < dyn_.tree_end) {
      len = detail::abt_path_to(nodes_, p, path);
      const double leaf = detail::abt_measured_area(nodes_[path[len - 1]].bounds);
      if (is_unbounded(b) || !(detail::abt_measured_area(merge(nodes_[path[len - 1]].bounds, b)) <= 1.5 * leaf)) {
        detail::abt_make_hole(dyn_, order_, nodes_.size(), p, path, len);
        append_pending(id, b);
        after_change();
        return true;
      }
    }
    bounds_[p] = b;
    leaf_boxes_.set(p, b);
    if (p >= dyn_.tree_end) {
      dyn_.pending_box = merge(dyn_.pending_box, b);
    } else {
      for (std::uint32_t i = len; i-- > 0;) {
        AbtNode& node = nodes_[path[i]];
        Aabb box = Aabb::empty();
        if (node.is_leaf()) {
          for (std::uint32_t j = node.begin; j < node.end; ++j) box = merge(box, bounds_[j]);
        } else {
          box = merge(nodes_[node.left].bounds, nodes_[node.left + 1].bounds);
        }
        node.bounds = box;
        node.sphere = bounding_sphere(box);
      }
      refitted_ = true;
    }
    after_change();
    return true;
  }

  /// True when `id` is held (given out by the build or `insert`, and not removed since).
  [[nodiscard]] bool holds(std::uint32_t id) const noexcept {
    return id < dyn_.pos_of.size() && dyn_.pos_of[id] != detail::abt_no_position;
  }

  /// Restores the tree's shape; run by insert, remove and update once the changes since the last
  /// run reach max(64, size() / 8). Afterwards there are no holes and nothing pending, so every
  /// object is back in front-to-back order. With holes or pending objects, the tree is rebuilt from
  /// the live objects (ids kept, the build's split settings, calling thread); after updates alone,
  /// `repair(0.2)`. Cost O(n log n) at most: O(log n) amortized per change.
  void maintain() {
    dyn_.ops = 0;
    if (dyn_.dead != 0 || dyn_.tree_end < order_.size()) {
      rebuild_live();
    } else {
      repair(0.2);
    }
  }

  // ---- Read-only views

  /// Every node; node 0 is the root; children follow their parent. Empty for an empty tree.
  [[nodiscard]] const std::vector<AbtNode>& nodes() const noexcept { return nodes_; }
  /// Position -> id of the object: node ranges `[begin, end)` index into this. After `remove`, a
  /// position may hold `removed_slot` (a hole: skip it); positions from `pending_begin()` on (no
  /// node covers them) hold objects inserted since the last rebuild.
  [[nodiscard]] const std::vector<std::uint32_t>& order() const noexcept { return order_; }
  static constexpr std::uint32_t removed_slot = detail::abt_removed_slot;
  [[nodiscard]] std::size_t pending_begin() const noexcept { return dyn_.tree_end; }
  /// Bounds of the object at each position of `order()` (as of the build or the last refit).
  [[nodiscard]] const std::vector<Aabb>& object_bounds() const noexcept { return bounds_; }
  /// Objects held (including those without valid bounds; skipped ones excluded).
  [[nodiscard]] std::size_t size() const noexcept { return order_.size() - dyn_.dead; }
  [[nodiscard]] bool empty() const noexcept { return size() == 0; }
  /// Number of objects given to the build (held + skipped).
  [[nodiscard]] std::size_t input_count() const noexcept { return input_count_; }
  [[nodiscard]] const AbtStats& stats() const noexcept { return stats_; }

  /// Writes into `out` the index buffer of `mesh` permuted to the tree's order, for a tree built
  /// over the mesh's triangles (see `make_triangle_tree`): the triangles of the node range
  /// [begin, end) are `out[3 * begin, 3 * end)`. Every held triangle is written (a bad one too, as
  /// the caller gave it). Allocates `out`.
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
    return detail::abt_validate(nodes_, order_, bounds_, dyn_, input_count_, stats_, refitted_, depth_limit);
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

  void append_range(std::vector<std::uint32_t>& out, std::uint32_t b, std::uint32_t e) const {
    if (e - b == 1) out.push_back(order_[b]);
    else out.insert(out.end(), order_.begin() + b, order_.begin() + e);
  }

  // The top-down walk of every single-view cull: nodes by sphere then box with a mask of the
  // planes still straddled; a node inside every plane is one `inside` range; a leaf or a small
  // subtree that straddles tests its objects 16 at a time from the SoA copy.
  template <class Visitor>
  void walk(const Plane* planes, std::uint32_t plane_mask, Visitor&& visitor) const {
    const auto emit_range = [&](std::uint32_t k, std::uint32_t b, std::uint32_t e) {
      if (!dyn_.node_has_holes(k)) return call(visitor, b, e, Containment::inside);
      return dyn_.live_runs(b, e, [&](std::uint32_t rb, std::uint32_t re) { return call(visitor, rb, re, Containment::inside); });
    };
    const auto emit_one = [&](std::uint32_t i, Containment c) { return dyn_.is_hole(i) || call(visitor, i, i + 1, c); };
    const auto n = static_cast<std::uint32_t>(order_.size());
    if (dyn_.tree_end < n) {  // objects inserted since the last rebuild
      const bool go_on = plane_mask == 0 ? emit_range(~0u, dyn_.tree_end, n)
                                         : leaf_boxes_.test(planes, plane_mask, dyn_.tree_end, n, emit_one);
      if (!go_on) return;
    }
    if (nodes_.empty()) return;
    struct Entry {
      std::uint32_t node;
      std::uint32_t mask;
    };
    Entry stack[depth_limit + 2];
    std::uint32_t top = 0;
    stack[top++] = Entry{0, plane_mask};
    const AbtNode* nodes = nodes_.data();
    while (top > 0) {
      const Entry entry = stack[--top];
      const AbtNode& node = nodes[entry.node];
      std::uint32_t mask = entry.mask;
      if (detail::abt_node_outside(planes, mask, node.bounds, node.sphere)) continue;
      if (mask == 0) {
        if (!emit_range(entry.node, node.begin, node.end)) return;
        continue;
      }
      if (node.is_leaf() || node.count() <= scan_below_) {
        const bool go_on = leaf_boxes_.test(planes, mask, node.begin, node.end, emit_one);
        if (!go_on) return;
        continue;
      }
      stack[top++] = Entry{node.left + 1, mask};
      stack[top++] = Entry{node.left, mask};
    }
  }

  static bool near_is_left(const AbtNode& node, const glm::vec3& eye) noexcept {
    return eye[node.axis] < node.split;
  }

  template <class Visitor>
  void traverse(const glm::vec3& eye, bool front_first, Visitor& visitor) const {
    if (front_first) visit_pending(visitor);
    traverse_tree(eye, front_first, visitor);
    if (!front_first) visit_pending(visitor);
  }

  // Objects inserted since the last rebuild, shown to node visitors as one extra leaf with index
  // nodes().size() (a valid node index never reaches it).
  template <class Visitor>
  void visit_pending(Visitor& visitor) const {
    const auto n = static_cast<std::uint32_t>(order_.size());
    if (dyn_.tree_end >= n) return;
    const AbtNode pending{dyn_.pending_box, bounding_sphere(dyn_.pending_box), dyn_.tree_end, n, 0, 0, 0.0f};
    call(visitor, static_cast<std::uint32_t>(nodes_.size()), pending);
  }

  template <class Visitor>
  void traverse_tree(const glm::vec3& eye, bool front_first, Visitor& visitor) const {
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

  // (area of the children) / (own area) of an inner node; 0 for leaves and for nodes without a
  // measurable area (flat, or unbounded).
  [[nodiscard]] double split_ratio(std::uint32_t k) const noexcept { return detail::abt_split_ratio(nodes_, k); }


  [[nodiscard]] double total_area() const noexcept {
    double sum = 0.0;
    for (const AbtNode& node : nodes_) sum += detail::abt_measured_area(node.bounds);
    return sum;
  }

  // Builds from scratch: every object becomes a build item (objects without valid bounds with
  // `unbounded_box()`), the builder fills a raw node array, the canonical layout is taken.
  template <class Getter>
  void build(Getter&& get_bounds, std::size_t count, const AbtParams& params) {
    nodes_.clear();
    order_.clear();
    bounds_.clear();
    ref_split_.clear();
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
      Aabb b = get_bounds(static_cast<std::uint32_t>(i));
      if (!is_valid(b)) {
        b = unbounded_box();
        ++stats_.unbounded;
      }
      items.push_back(detail::AbtBuildItem{b, detail::abt_centroid(b), static_cast<std::uint32_t>(i)});
    }
    stats_.skipped = static_cast<std::uint32_t>(count - usable);
    const auto n = static_cast<std::uint32_t>(items.size());
    scan_below_ = params.scan_below;
    build_context_ = detail::AbtBuildContext{};
    build_context_.cfg = detail::abt_split_config(params);
    build_context_.leaf_size = std::max<std::uint32_t>(1u, params.max_leaf_size);
    build_context_.max_depth = std::min(params.max_depth, depth_limit);
    if (n == 0) {
      dyn_.reset(order_, input_count_);
      if (params.progress) params.progress(1.0f);
      build_area_ = 0.0;
      return;
    }

    detail::AbtBuildContext ctx = build_context_;
    ctx.items = items.data();
    ctx.runner = params.task_runner;
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
    const std::uint32_t grain = std::max<std::uint32_t>(params.parallel_grain, 2u * ctx.leaf_size + 2u);
    const std::vector<AbtNode> raw = detail::abt_build_raw(ctx, 0, n, 0, params.threads, grain);
    std::vector<std::uint32_t> from;
    detail::abt_relayout(raw, nodes_, from, stats_);
    adopt_build(items);
    if (params.progress) params.progress(1.0f);
  }

  // After a build of `items` into nodes_: the order, bounds, leaf boxes, split references and
  // dynamic state follow the items' final order.
  void adopt_build(const std::vector<detail::AbtBuildItem>& items) {
    const auto n = static_cast<std::uint32_t>(items.size());
    stats_.objects = n;
    order_.resize(n);
    bounds_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      order_[i] = items[i].index;
      bounds_[i] = items[i].box;
    }
    leaf_boxes_.assign(bounds_);
    ref_split_.resize(nodes_.size());
    for (std::size_t k = 0; k < nodes_.size(); ++k) ref_split_[k] = split_ratio(static_cast<std::uint32_t>(k));
    build_area_ = total_area();
    dyn_.reset(order_, input_count_);
  }

  static bool is_unbounded_marker(const Aabb& b) noexcept { return b.min == unbounded_box().min && b.max == unbounded_box().max; }

  // The box held for `bounds` (unbounded_box() for bad bounds, counted).
  Aabb held_box(const Aabb& bounds) {
    if (is_valid(bounds)) return bounds;
    ++stats_.unbounded;
    return unbounded_box();
  }

  void append_pending(std::uint32_t id, const Aabb& b) {
    dyn_.pos_of[id] = static_cast<std::uint32_t>(order_.size());
    order_.push_back(id);
    bounds_.push_back(b);
    leaf_boxes_.append(b);
    dyn_.pending_box = merge(dyn_.pending_box, b);
  }

  void after_change() {
    if (++dyn_.ops >= std::max<std::size_t>(64, size() / 8)) maintain();
  }

  // Rebuild from the live objects, their ids and the build's split settings kept.
  void rebuild_live() {
    std::vector<detail::AbtBuildItem> items;
    items.reserve(size());
    for (std::size_t p = 0; p < order_.size(); ++p)
      if (!dyn_.is_hole(static_cast<std::uint32_t>(p)))
        items.push_back(detail::AbtBuildItem{bounds_[p], detail::abt_centroid(bounds_[p]), order_[p]});
    const auto n = static_cast<std::uint32_t>(items.size());
    std::vector<std::uint32_t> free_ids = std::move(dyn_.free_ids);
    const AbtStats keep = stats_;
    nodes_.clear();
    stats_ = AbtStats{};
    stats_.unbounded = keep.unbounded;
    stats_.skipped = keep.skipped;
    std::vector<AbtNode> raw;
    if (n > 0) {
      detail::AbtBuildContext ctx = build_context_;
      ctx.items = items.data();
      raw = detail::abt_build_raw(ctx, 0, n, 0, 1, 0);
      std::vector<std::uint32_t> from;
      detail::abt_relayout(raw, nodes_, from, stats_);
    }
    adopt_build(items);
    refitted_ = false;
    dyn_.free_ids = std::move(free_ids);
  }

  std::vector<AbtNode> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<Aabb> bounds_;
  detail::AbtLeafBoxes leaf_boxes_;
  detail::AbtDynamic dyn_;           // holes, pending objects, ids (insert, remove, update)  // bounds_ again, as padded SoA for the leaf tests
  std::vector<double> ref_split_;    // per node: split_ratio when it was last (re)built
  detail::AbtBuildContext build_context_;  // the build's split settings, for repairs
  std::size_t input_count_ = 0;
  AbtStats stats_;
  double build_area_ = 0.0;
  bool refitted_ = false;
  std::uint32_t scan_below_ = 64;
};

/// Builds a tree whose objects are the triangles of `mesh` (object i = triangle i, bounds = the
/// box of its corners). Triangles with an index out of range or a non-finite corner get no valid
/// bounds: they are held with `unbounded_box()`, counted in `stats().unbounded` and reported by
/// every cull; degenerate (zero-area) triangles are kept as they are. Pair with `reorder_indices` to draw
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
