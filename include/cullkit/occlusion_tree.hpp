// cullkit/occlusion_tree.hpp: the occlusion tree, a binary tree of planes for one eye that holds the
// union of the regions hidden behind inserted occluders, and answers "is this box entirely hidden?".
//
// Seed: 基于主要遮挡物的动态可见性算法 (dynamic visibility with major occluders), §3.1-3.4 (see
// docs/papers.md), with the corrections said below. An occluder polygon becomes a chain of planes: one plane through the eye and each
// edge (inside: toward the polygon), then the polygon's own plane (inside: away from the eye), then
// an explicit hidden leaf. A solid box becomes its outline's edge planes, then its 1-3 front-face
// planes (cullkit::BoxProxy), then hidden. Inserting pushes the occluder down the tree, splitting it
// where it straddles a plane: fragments reaching an empty slot grow a new chain there, fragments
// reaching a hidden leaf are dropped. A query pushes the box's front faces down the same way; the box
// is hidden only if every fragment ends in a hidden leaf. Unlike the seed, a query fragment that
// straddles an occluder's own plane is split rather than declared visible.
//
// Box queries in three phases, cheapest first, each exact where it answers: (1) the whole box goes
// down one path, to the outside of any plane its front straddles; a hidden leaf reached that way is
// proof (it is only reachable through one complete occluder chain, whose every inside step held for
// the whole box). (2) Otherwise the box's outline cone is split from the first straddled plane: at
// planes through the eye a cone piece stands for the surface behind it; at an occluder's own plane
// the whole front decides. (3) Only if the front straddles such a plane are the faces split. Chains
// list an occluder's longest edges (seen from the eye) first, so walks passing beside it leave sooner.
//
// Coordinates. The tree stores its planes relative to the eye, so planes through the eye have d = 0
// exactly; plane normals are computed in double precision and rounded once.
//
// Epsilon policy (one rule, OcclusionParams::margin, relative). Correctness rests on one fact: every
// hidden leaf is reached only through the complete chain of the fragment that created it, and that
// chain describes a region truly hidden by that fragment. So only one decision can hide something
// visible: sending a query fragment to the *inside* of a plane. A query fragment goes inside only
// when every corner lies at least `m = margin * (S + |d|)` inside the plane, where S bounds the
// distance of the query box (and the eye) from the origin; that margin absorbs every float rounding
// of corners, plane normals and split points (about 1e-7 relative, margin 1e-5). Fragments that are
// not clearly inside go outside, or are split along the plane shifted inward by m (both pieces
// kept). Occluders may lose area freely (that is always safe): their corners seen from nearly the
// same direction are merged, fragments with no area seen from the eye are dropped, and a slightly
// non-planar occluder's own plane is pushed back behind its farthest corner.
//
// Fusion (seams; detail/occlusion_seams.hpp, docs/occlusion_fusion.md). Two occluders sharing an
// edge each have a plane through the eye and that edge: one true plane, so a query piece within
// the margin of it would be "not clearly inside" for both, and the pair would hide nothing along the
// seam. Every edge plane therefore carries a seam id that names its true plane exactly (the edge's
// corners bit for bit, or an axis plane through the eye), and edge normals are computed from the
// corners in canonical order, so partners are exact negations. At a seam used by two occluders, a
// piece within the band becomes two overlapping copies (distance >= -m inside, <= m outside), each
// assuming its side; at every later node of that seam a copy follows its assumption. Each point has
// a copy on its true side, and every plane of the chain that copy ends in holds for the point (by
// the margin or by the assumption), so a hidden answer stays proof.
//
// Thread safety: queries are const and may run concurrently; insert/reset need exclusive access.
// Allocation: insertion grows flat arrays (none once warm, since `reset` keeps capacity); queries
// never allocate (their work stack is a fixed local array; if it fills, the answer is "visible").
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/ext/vector_double3.hpp>

#include "box_proxy.hpp"
#include "config.hpp"
#include "detail/occlusion_geometry.hpp"
#include "detail/occlusion_query.hpp"
#include "detail/occlusion_seams.hpp"
#include "geometry/aabb.hpp"
#include "geometry/convex_polygon.hpp"
#include "geometry/plane.hpp"

namespace cullkit {

/// Construction parameters of an OcclusionTree. Every field has a documented default; the defaults
/// are a sound choice for scenes from centimetres to tens of kilometres.
struct OcclusionParams {
  /// Relative safety margin of every "inside" decision a query makes (see the file comment). A query
  /// corner must lie `margin * (S + |d|)` inside a plane to count as inside, S being the query's
  /// distance scale. Default 1e-5: 100x float rounding. Larger: more boxes near occluder silhouettes
  /// are called visible. Values below 1e-6 (or not finite) are raised to 1e-6, so rounding can
  /// never hide a visible sliver.
  float margin = 1e-5f;
  /// A polygon occluder whose corners deviate from their best plane by more than `planarity` times
  /// the polygon's diameter is skipped (counted in `stats().occluders_skipped`). Default 1e-4.
  /// Accepted polygons have their own plane pushed back by the measured deviation (safe).
  float planarity = 1e-4f;
  /// Occluder corners whose directions from the eye differ by less than this angle (radians) are
  /// merged, and occluder fragments that subtend less are dropped as having no area. Default 1e-6.
  float min_angle = 1e-6f;
  /// Two-level tree: number of fixed planes through the eye and the `up` axis, evenly spaced in
  /// azimuth (they cut the surroundings into 2 * azimuth_planes wedges), built before any occluder
  /// so the tree stays shallow whatever order occluders arrive in (seed §3.4.3). Default 0: none.
  int azimuth_planes = 0;
  /// Two-level tree: planes per azimuth wedge that cut it by elevation (evenly spaced between
  /// straight down and straight up). Needs azimuth_planes >= 1. Default 0.
  int elevation_planes = 0;
  /// The up axis of the top-level planes (need not be unit). Default +Y. Unused without top planes.
  glm::vec3 up = glm::vec3(0.0f, 1.0f, 0.0f);
  /// Azimuth origin of the top-level planes (its part perpendicular to `up` is used). Default -Z.
  glm::vec3 forward = glm::vec3(0.0f, 0.0f, -1.0f);
};

/// What kind of plane a node holds.
enum class OcclusionNodeKind : std::uint8_t {
  top,          ///< a fixed top-level plane through the eye (two-level tree), not from an occluder
  edge,         ///< a plane through the eye and an occluder edge; inside is toward the occluder
  polygon,      ///< a polygon occluder's own plane; inside is away from the eye
  box_face,     ///< a front-face plane of a box occluder; inside is into the box
};

/// A node of the tree (read-only view through `OcclusionTree::nodes()`). Planes are eye-relative:
/// the signed distance of world point w is `dot(plane.normal, w - eye) + plane.d`.
struct OcclusionNode {
  Plane plane;             ///< inside = positive side
  std::uint32_t inside;    ///< child on the positive side: node index, or a leaf code
  std::uint32_t outside;   ///< child on the negative side: node index, or a leaf code
  std::uint32_t depth;     ///< root = 0
  OcclusionNodeKind kind;
  /// For an edge plane, its seam: `2 * id + 1` if this plane's normal is the seam's canonical
  /// normal, `2 * id` if it is the opposite. Edge planes with one id lie on one true plane (through
  /// the eye and one edge, given bit for bit, or an axis plane through the eye), which a query may
  /// classify once for all of them; see the file comment. `OcclusionTree::no_seam` for other nodes.
  std::uint32_t seam = 0xFFFFFFFFu;
};

/// Statistics since construction or the last `reset`.
struct OcclusionStats {
  std::uint32_t nodes = 0;              ///< nodes in the tree (top-level ones included)
  std::uint32_t top_nodes = 0;          ///< fixed top-level nodes
  std::uint32_t depth = 0;              ///< deepest node (root = 0; 0 for an empty tree)
  std::uint32_t occluders_inserted = 0; ///< occluders accepted (polygons and boxes)
  std::uint32_t occluders_skipped = 0;  ///< rejected: non-finite, < 3 corners, non-planar, no area
                                        ///< from the eye, eye inside or on a box
  std::uint32_t occluders_hidden = 0;   ///< boxes `insert_box_occluders` found already hidden
                                        ///< (nothing to add: not inserted)
  std::uint32_t fragments = 0;          ///< occluder fragments that grew a chain
  std::uint32_t fragments_hidden = 0;   ///< fragments dropped because already hidden
  std::uint32_t fragments_degenerate = 0;  ///< fragments dropped as too thin seen from the eye
};

/// A query's answer.
enum class OcclusionAnswer : std::uint8_t {
  visible,  ///< some part may be visible
  hidden,   ///< every point is hidden by the occluders inserted so far
  clear,    ///< no part reached any hidden region (only reported when asked for; else `visible`)
};

/// A query's answer and where the whole query shape last went down the tree undivided.
struct OcclusionQueryResult {
  OcclusionAnswer answer = OcclusionAnswer::visible;
  /// The deepest node at which the query's corners were still all on one side of every plane above
  /// it, or `OcclusionTree::whole_tree` when that is the root slot. A query for a shape contained in
  /// this one (an ABT child box inside its parent box) may start there (seed §3.4.2, refinement 2).
  std::uint32_t together = 0xFFFFFFFDu;  // OcclusionTree::whole_tree
};

/// The occlusion tree for one eye position (see the file comment).
class OcclusionTree {
 public:
  /// Leaf codes in `OcclusionNode::inside/outside`.
  static constexpr std::uint32_t visible_leaf = 0xFFFFFFFFu;  ///< empty: nothing hides this region
  static constexpr std::uint32_t hidden_leaf = 0xFFFFFFFEu;   ///< everything here is hidden
  /// "Start at the root" for `query`.
  /// A value of its own, never a node index nor a leaf code: a node's child is never "the root".
  static constexpr std::uint32_t whole_tree = 0xFFFFFFFDu;
  /// Pending fragments a query can hold; beyond that the query answers "visible".
  static constexpr int query_stack_size = 48;
  /// `OcclusionNode::seam` of a node that lies on no shared edge.
  static constexpr std::uint32_t no_seam = 0xFFFFFFFFu;

  /// An empty tree for `eye` (hides nothing) with default parameters.
  explicit OcclusionTree(const glm::vec3& eye) : OcclusionTree(eye, OcclusionParams{}) {}
  /// An empty tree for `eye` with the given parameters (top-level planes are built now).
  /// A non-finite eye gives a tree that accepts no occluder and hides nothing.
  OcclusionTree(const glm::vec3& eye, const OcclusionParams& params) : params_(params) {
    params_.azimuth_planes = std::clamp(params_.azimuth_planes, 0, 64);
    params_.elevation_planes = params_.azimuth_planes > 0 ? std::clamp(params_.elevation_planes, 0, 64) : 0;
    if (!(params_.margin >= 1e-6f) || !std::isfinite(params_.margin)) params_.margin = 1e-6f;
    reset(eye);
  }

  /// Clears the tree for a new eye, keeping the memory (no allocation once warm), and rebuilds the
  /// top-level planes. Invalidates node indices from earlier queries.
  void reset(const glm::vec3& eye) {
    eye_ = eye;
    eye_ok_ = detail::finite3(eye);
    eye_scale_ = eye_ok_ ? detail::norm1(eye) : 0.0f;
    nodes_.clear();
    seams_.clear();
    occluder_serial_ = 0;
    stats_ = OcclusionStats{};
    root_ = visible_leaf;
    if (eye_ok_) build_top_level();
    stats_.top_nodes = stats_.nodes = static_cast<std::uint32_t>(nodes_.size());
  }

  [[nodiscard]] const glm::vec3& eye() const noexcept { return eye_; }
  [[nodiscard]] const OcclusionParams& params() const noexcept { return params_; }
  [[nodiscard]] const OcclusionStats& stats() const noexcept { return stats_; }
  /// Every node; children are referenced by index or leaf code. Root: `root()`.
  [[nodiscard]] const std::vector<OcclusionNode>& nodes() const noexcept { return nodes_; }
  /// The root: a node index, or a leaf code for a tree without nodes.
  [[nodiscard]] std::uint32_t root() const noexcept { return root_; }
  /// True if no occluder has been inserted (the tree hides nothing).
  [[nodiscard]] bool empty() const noexcept { return stats_.fragments == 0; }

  /// Inserts a convex polygon occluder (world coordinates, either winding, planar within
  /// `params().planarity`). Skipped and counted (stats().occluders_skipped) when a corner is not
  /// finite, `count < 3`, it is not planar, or it has no area as seen from the eye (the eye on or
  /// very near its plane). More than 32 corners: the first 32 are used (a subset: safe).
  /// pre: `polygon` points to `count` corners (may be null when count is 0).
  /// Cost: O(fragments x depth) plane tests; allocates only while the node array grows.
  void insert_occluder(const glm::vec3* polygon, std::size_t count) {
    if (insert_polygon(polygon, count)) ++stats_.occluders_inserted;
    else skip();
  }

  /// Inserts a solid box occluder through its outline (cullkit::make_box_proxy, front-face closure).
  /// Skipped and counted when the box is invalid, flat on two axes, or the eye is inside or on it.
  /// A face the eye sees at a grazing angle (the eye within 1/250 of its distance to the box from
  /// the face's plane) is left out, as if the eye were in that plane: the outline then runs along
  /// the face's near edge, which a touching box shares bit for bit, so the two fuse (a box with one
  /// face less hides a subset: safe; where the outline is then slightly concave, the beam through
  /// its edges is smaller still). Cost and allocation as `insert_occluder`.
  void insert_box_occluder(const Aabb& box) {
    if (!eye_ok_) return skip();
    glm::vec3 view = grazing_view(box);
    BoxProxy proxy = make_box_proxy(box, view);
    if (!proxy.valid()) {  // the moved eye landed on the box (an eye near one of its edges)
      view = eye_;
      proxy = make_box_proxy(box, eye_);
    }
    if (!proxy.valid()) return skip();
    ConvexPolygon frag;
    float scale = 0.0f;
    for (int i = 0; i < proxy.corner_count; ++i) {
      frag.push_back(proxy.corners[i] - eye_);
      scale = std::max(scale, detail::norm1(frag[static_cast<std::size_t>(i)]));
    }
    current_ = Current{};
    current_.edge_count = beam_edges(frag);
    if (current_.edge_count == 0) return skip();
    current_.is_box = true;
    for (int f = 0; f < proxy.face_count; ++f) {
      const Plane& p = proxy.faces[f];  // world plane, normal into the box
      const double d = double(p.d) + glm::dot(glm::dvec3(p.normal), glm::dvec3(eye_));
      current_.closing[f] = Plane{p.normal, static_cast<float>(d)};
    }
    current_.closing_count = proxy.face_count;
    int cycles[3][4];
    const int face_count = detail::box_front_face_cycles(box, view, cycles);
    unsigned corner_mask = 0;
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 4; ++k) corner_mask |= 1u << cycles[f][k];
    current_.box_point_count = 0;
    for (int c = 0; c < 8; ++c)
      if (corner_mask & (1u << c)) current_.box_points[current_.box_point_count++] = corner(box, c) - eye_;
    current_.split_epsilon = params_.margin * scale;
    ++stats_.occluders_inserted;
    insert_fragment(frag);
  }

  /// Inserts a solid box in any orientation: `local_box` placed in the world by the affine matrix
  /// `model` (rotation, translation, scale, shear; world = model * local). The box must be a SOLID:
  /// opaque all through, like a building's walls and roof, never a bounding box of something with
  /// gaps (a tree, a car, a fence): everything behind it is treated as hidden. Its front faces (the
  /// ones the eye sees, 1 to 3) are inserted as polygon occluders; they share their edges bit for
  /// bit, so the tree fuses them along every edge. Counted once in `stats().occluders_inserted`.
  /// Skipped and counted when the box or matrix is invalid (NaN, infinite, min > max, last row not
  /// (0, 0, 0, 1)) or the eye is inside or on the box (no face sees it), or no face has area seen
  /// from the eye. An axis-aligned box with the identity matrix hides the same region as
  /// `insert_box_occluder(box)` (which builds one chain from the outline; faster to insert).
  /// Cost and allocation as `insert_occluder`, times the number of front faces.
  void insert_box_occluder(const Aabb& local_box, const glm::mat4& model) {
    glm::vec3 faces[3][4];
    const int count = eye_ok_ ? detail::oriented_box_front_faces(local_box, model, eye_, faces) : 0;
    bool any = false;
    for (int f = 0; f < count; ++f) any = insert_polygon(faces[f], 4) || any;
    if (any) ++stats_.occluders_inserted;
    else skip();
  }

  /// Inserts many solid box occluders, nearest to the eye first (each as `insert_box_occluder`),
  /// leaving out those already hidden by the nearer ones (counted in `stats().occluders_hidden`:
  /// everything behind a hidden box is hidden too, so they would add nothing). The hidden region does
  /// not depend on the order, but the tree does: near occluders inserted first hide most of the far
  /// ones. In bench_occlusion (100 boxes in view) that gives a tree 35x smaller, 25x faster insertion
  /// and 3.5x faster queries than inserting in a random order. Invalid boxes are skipped and counted
  /// as in `insert_box_occluder`.
  /// pre: `boxes` points to `count` boxes (may be null when count is 0). Allocation: a scratch array
  /// kept by the tree (none once warm). Cost: a sort of `count` keys, then the insertions.
  void insert_box_occluders(const Aabb* boxes, std::size_t count) {
    if (count == 0 || boxes == nullptr) return;
    CULLKIT_ASSERT(count <= 0xFFFFFFFFu, "insert_box_occluders: at most 2^32 - 1 boxes per call");
    order_.clear();
    for (std::size_t i = 0; i < count; ++i) {
      // Distance from the eye to the box (0 inside); NaN boxes sort last (then get skipped).
      const glm::vec3 gap = glm::max(glm::max(boxes[i].min - eye_, eye_ - boxes[i].max), glm::vec3(0.0f));
      float key = glm::dot(gap, gap);
      if (!(key == key)) key = std::numeric_limits<float>::infinity();
      order_.push_back(SortKey{key, static_cast<std::uint32_t>(i)});
    }
    std::sort(order_.begin(), order_.end(), [](const SortKey& a, const SortKey& b) {
      return a.key < b.key || (a.key == b.key && a.index < b.index);
    });
    for (const SortKey& k : order_) {
      // Far boxes behind near ones are often hidden whole by now: then so is everything behind
      // them (past a hidden point along each ray), and all their fragments would be dropped.
      if (stats_.fragments > 0 && is_occluded(boxes[k.index])) {
        ++stats_.occluders_hidden;
        continue;
      }
      insert_box_occluder(boxes[k.index]);
    }
  }

  /// True only if every point of `box` is hidden from the eye by the occluders inserted so far.
  /// False for an invalid box (NaN, infinite, min > max) and when the eye is inside or on the box.
  /// Cost: O(depth) plane tests while the box stays whole, more where occluder boundaries cut it.
  /// No allocation; safe to call concurrently.
  [[nodiscard]] bool is_occluded(const Aabb& box) const {
    return query(box).answer == OcclusionAnswer::hidden;
  }

  /// True only if every point of `polygon` (world coordinates, convex, planar) is hidden. False for
  /// an empty, overflowed or non-finite polygon. No allocation; safe to call concurrently.
  [[nodiscard]] bool is_occluded(const ConvexPolygon& polygon) const {
    return query(polygon).answer == OcclusionAnswer::hidden;
  }

  /// The full query: is the box hidden, and (with `want_clear`) is it clear of every hidden region.
  /// `start`: `whole_tree`, or the `together` node of an earlier query, in this tree since the last
  /// `reset`, for a box that contained this one (then the walk starts there; seed §3.4.2); any other
  /// value that is not a node of this tree starts at the root. With
  /// `want_clear` the walk does not stop at the first visible fragment, so it can report `clear`.
  /// Returns where the box last went down the tree whole. No allocation; safe concurrently.
  [[nodiscard]] OcclusionQueryResult query(const Aabb& box, std::uint32_t start = whole_tree,
                                           bool want_clear = false) const {
    OcclusionQueryResult result;
    if (start != whole_tree && start >= nodes_.size()) start = whole_tree;  // stale or invalid: the root
    result.together = start;
    if (!eye_ok_ || !is_valid(box) || contains(box, eye_)) return result;
    // Eye-relative box; the largest norm1 over the corners separates per axis.
    const glm::vec3 lo = box.min - eye_, hi = box.max - eye_;
    const glm::vec3 far = glm::max(glm::abs(lo), glm::abs(hi));
    const float scale = far.x + far.y + far.z + eye_scale_;
    // Halves first: lo + hi may overflow for boxes near the float range (a fuzzer find).
    BoxFront front(box, 0.5f * lo + 0.5f * hi, 0.5f * hi - 0.5f * lo);
    // Phase 1: the whole box goes down one path, each plane decided by `front_side`.
    // Where the front straddles a plane, the whole box goes on to the OUTSIDE. That needs no proof:
    // a hidden leaf is only reached through a complete occluder chain, every step of which was an
    // inside decision proven for the whole box, so reaching one means one occluder hides all of the
    // box. Reaching a visible leaf after such a step proves nothing, except in one case: a path with a
    // single straddle whose outside part clearly exists takes exactly that part to the visible leaf.
    // Otherwise the exact walk (phase 2) starts at the first straddled node.
    std::uint32_t ref = start == whole_tree ? root_ : start;
    std::uint32_t first_split = visible_leaf;
    int splits = 0;
    bool clear_split = false;  // the first straddle had front corners clearly outside
    while (ref < hidden_leaf) {
      const OcclusionNode& node = nodes_[ref];
      const float m = params_.margin * (scale + std::fabs(node.plane.d));
      float dmin = 0.0f;
      FrontSide side = front_side(node.plane, m, front, dmin);
      if (side == FrontSide::unknown) return result;  // NaN: visible
      // On a shared seam, a front within the margin band of the plane must meet the seam rule
      // (walk_fragments), not slip to the outside where the other occluder's chain may not be.
      if (side == FrontSide::outside && is_shared_seam(node)) {
        float flipped_min = 0.0f;
        const Plane flipped{-node.plane.normal, -node.plane.d};
        if (front_side(flipped, m, front, flipped_min) != FrontSide::inside) side = FrontSide::straddles;
      }
      if (side == FrontSide::straddles && splits++ == 0) {
        first_split = ref;
        clear_split = dmin <= -m;
      }
      if (splits == 0) result.together = ref;
      ref = side == FrontSide::inside ? node.inside : node.outside;
    }
    if (ref == hidden_leaf || splits == 0) return leaf_answer(result, ref, want_clear);
    result.together = first_split;
    if (splits == 1 && clear_split && !want_clear) return result;  // really visible
    // Phase 2: one fragment, the box's outline (the cone of every ray into the box), split at planes
    // through the eye; at an occluder's own plane the whole front of the box decides. Only when the
    // front straddles such a plane does the query fall back to the faces themselves (phase 3).
    Fragment stack[query_stack_size];
    glm::vec3 outline[6];
    const auto corners = static_cast<std::uint32_t>(box_silhouette(box, eye_, outline));
    if (corners >= 3) {
      for (std::uint32_t i = 0; i < corners; ++i) stack[0].v[i] = outline[i] - eye_;
      stack[0].size = corners;
      stack[0].ref = first_split;
      stack[0].assumed_count = 0;
      result.answer = walk_fragments(stack, 1, scale, want_clear, &front);
      if (result.answer != undecided_answer) return result;
    }
    // Phase 3: the front faces, split at every plane they straddle.
    result.answer = OcclusionAnswer::visible;
    const int nfaces = detail::box_front_fragments(box, eye_, stack);
    if (nfaces == 0) return result;
    for (int f = 0; f < nfaces; ++f) stack[f].ref = first_split;
    result.answer = walk_fragments(stack, nfaces, scale, want_clear, nullptr);
    return result;
  }

  /// The same for a convex planar polygon in world coordinates.
  [[nodiscard]] OcclusionQueryResult query(const ConvexPolygon& polygon, std::uint32_t start = whole_tree,
                                           bool want_clear = false) const {
    OcclusionQueryResult result;
    if (start != whole_tree && start >= nodes_.size()) start = whole_tree;  // stale or invalid: the root
    result.together = start;
    if (!eye_ok_ || polygon.empty() || polygon.overflow()) return result;
    Fragment stack[query_stack_size];
    Fragment& local = stack[0];
    float scale = 0.0f;
    local.size = static_cast<std::uint32_t>(polygon.size());
    local.assumed_count = 0;
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      if (!detail::finite3(polygon[i])) return result;
      local.v[i] = polygon[i] - eye_;
      scale = std::max(scale, detail::norm1(local.v[i]));
    }
    scale += eye_scale_;
    // Phase 1: the whole polygon goes down while its corners stay on one side.
    std::uint32_t ref = start == whole_tree ? root_ : start;
    while (ref < hidden_leaf) {
      const OcclusionNode& node = nodes_[ref];
      const float m = params_.margin * (scale + std::fabs(node.plane.d));
      float dmin = signed_distance(node.plane, local.v[0]), dmax = dmin;
      for (std::uint32_t i = 1; i < local.size; ++i) {
        const float dist = signed_distance(node.plane, local.v[i]);
        dmin = std::min(dmin, dist);
        dmax = std::max(dmax, dist);
      }
      if (!detail::finite_distance(dmin) || !detail::finite_distance(dmax)) return result;  // overflow, NaN: visible
      if (!(dmin >= m) && !(dmax <= m)) break;  // straddles: split from here
      if (!(dmin >= m) && !(dmax <= -m) && is_shared_seam(node)) break;  // in a seam's band: the seam rule
      result.together = ref;
      ref = dmin >= m ? node.inside : node.outside;
    }
    if (ref >= hidden_leaf) return leaf_answer(result, ref, want_clear);
    result.together = ref;
    local.ref = ref;
    result.answer = walk_fragments(stack, 1, scale, want_clear, nullptr);
    return result;
  }

 private:
  // What the occluder being inserted closes its chain with.
  struct Current {
    Plane edges[ConvexPolygon::capacity] = {};  // the whole occluder's beam planes
    std::uint32_t edge_seams[ConvexPolygon::capacity] = {};  // OcclusionNode::seam of each
    std::size_t edge_count = 0;
    bool is_box = false;
    Plane closing[3] = {};
    int closing_count = 0;
    glm::vec3 box_points[8] = {};  // eye-relative front corners of a box occluder
    int box_point_count = 0;
    float split_epsilon = 0.0f;
  };
  using Fragment = detail::QueryFragment<ConvexPolygon::capacity>;
  // A pending occluder fragment: `fragment.ref` is the node whose child slot it enters next
  // (whole_tree: the root slot), `inside` says which child.
  struct InsertItem {
    Fragment fragment;
    bool inside;
  };

  void skip() { ++stats_.occluders_skipped; }

  // The eye moved into the plane of every box face it sees at a grazing angle (see
  // insert_box_occluder), or the eye itself.
  [[nodiscard]] glm::vec3 grazing_view(const Aabb& box) const {
    const glm::vec3 gap = glm::max(glm::max(box.min - eye_, eye_ - box.max), glm::vec3(0.0f));
    const float reach = (1.0f / 250.0f) * glm::length(gap);
    glm::vec3 view = eye_;
    for (int a = 0; a < 3; ++a) {
      if (eye_[a] < box.min[a] && box.min[a] - eye_[a] <= reach) view[a] = box.min[a];
      if (eye_[a] > box.max[a] && eye_[a] - box.max[a] <= reach) view[a] = box.max[a];
    }
    return view;
  }

  // insert_occluder without the statistics: false when the polygon was not used.
  bool insert_polygon(const glm::vec3* polygon, std::size_t count) {
    if (!eye_ok_ || count < 3 || polygon == nullptr) return false;
    const std::size_t n = std::min<std::size_t>(count, ConvexPolygon::capacity);
    glm::dvec3 a[ConvexPolygon::capacity];
    const glm::dvec3 e(eye_);
    for (std::size_t i = 0; i < n; ++i) {
      if (!detail::finite3(polygon[i])) return false;
      a[i] = glm::dvec3(polygon[i]) - e;
    }
    glm::dvec3 normal(0.0), center(0.0);
    for (std::size_t i = 0; i < n; ++i) {
      normal += glm::cross(a[i], a[(i + 1) % n]);
      center += a[i];
    }
    center /= static_cast<double>(n);
    const double len = glm::length(normal);
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    glm::dvec3 unit = normal / len;
    double d = -glm::dot(unit, center);
    double deviation = 0.0, diameter = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      deviation = std::max(deviation, std::fabs(glm::dot(unit, a[i]) + d));
      diameter = std::max(diameter, glm::length(a[i] - a[0]));
    }
    if (!(deviation <= double(params_.planarity) * diameter)) return false;
    // The eye is the origin: its signed distance is d. Inside must be away from the eye.
    if (d > 0.0) {
      unit = -unit;
      d = -d;
    }
    // No area seen from the eye: the eye (nearly) in the polygon's plane.
    if (!(-d > deviation + double(params_.min_angle) * (glm::length(center) + diameter))) return false;
    // Behind every corner: push the plane back by the deviation (and its own rounding).
    const Plane own{glm::vec3(unit), static_cast<float>(d - deviation)};
    if (!is_valid(own)) return false;

    ConvexPolygon frag;
    float scale = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
      frag.push_back(glm::vec3(a[i]));
      scale = std::max(scale, detail::norm1(frag[i]));
    }
    current_ = Current{};
    current_.edge_count = beam_edges(frag);
    if (current_.edge_count == 0) return false;
    current_.is_box = false;
    current_.closing[0] = own;
    current_.closing_count = 1;
    current_.split_epsilon = params_.margin * scale;
    insert_fragment(frag);
    return true;
  }

  // The occluder's beam planes into current_.edges, longest edge (in angle) first: a query passing
  // beside the occluder is most likely outside a long edge, so it leaves the chain after fewer steps.
  // (The chain's region does not depend on the order.)
  std::size_t beam_edges(const ConvexPolygon& outline) {
    float angles[ConvexPolygon::capacity];  // 1 - cos of each edge's angle: same order as the angle
    glm::vec3 corners[ConvexPolygon::capacity];
    const std::size_t n = detail::beam_planes(outline, params_.min_angle, current_.edges, angles, corners);
    ++occluder_serial_;
    for (std::size_t i = 0; i < n; ++i)
      current_.edge_seams[i] = edge_seam(current_.edges[i], corners[i], corners[(i + 1) % n]);
    for (std::size_t i = 1; i < n; ++i) {
      const Plane plane = current_.edges[i];
      const std::uint32_t seam = current_.edge_seams[i];
      const float angle = angles[i];
      std::size_t j = i;
      for (; j > 0 && angles[j - 1] < angle; --j) {
        current_.edges[j] = current_.edges[j - 1];
        current_.edge_seams[j] = current_.edge_seams[j - 1];
        angles[j] = angles[j - 1];
      }
      current_.edges[j] = plane;
      current_.edge_seams[j] = seam;
      angles[j] = angle;
    }
    return n;
  }

  // The seam code (OcclusionNode::seam) of the edge plane through the eye and a-b.
  std::uint32_t edge_seam(const Plane& plane, const glm::vec3& a, const glm::vec3& b) {
    bool forward = false;  // cross(a, b) is the seam's canonical normal
    const detail::SeamKey key = detail::seam_key(a, b, forward);
    const std::uint32_t id = seams_.use(key, occluder_serial_);
    if (id >= no_seam / 2) return no_seam;
    const glm::dvec3 ab = glm::cross(glm::dvec3(a), glm::dvec3(b));
    const bool along_ab = glm::dot(glm::dvec3(plane.normal), ab) > 0.0;
    return 2 * id + (along_ab == forward ? 1u : 0u);
  }

  [[nodiscard]] std::uint32_t slot_value(std::uint32_t parent, bool inside) const {
    if (parent == whole_tree) return root_;
    return inside ? nodes_[parent].inside : nodes_[parent].outside;
  }
  void set_slot(std::uint32_t parent, bool inside, std::uint32_t value) {
    if (parent == whole_tree) root_ = value;
    else if (inside) nodes_[parent].inside = value;
    else nodes_[parent].outside = value;
  }
  [[nodiscard]] std::uint32_t slot_depth(std::uint32_t parent) const {
    return parent == whole_tree ? 0u : nodes_[parent].depth + 1u;
  }

  std::uint32_t add_node(const Plane& plane, OcclusionNodeKind kind, std::uint32_t depth,
                         std::uint32_t seam = no_seam) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(OcclusionNode{plane, visible_leaf, visible_leaf, depth, kind, seam});
    stats_.depth = std::max(stats_.depth, depth);
    return index;
  }

  // Pushes one occluder (its first fragment) down the tree. The work stack keeps its size (entries
  // past `top` are stale, never value-initialized again), and a split writes its inside piece straight
  // into the next stack entry, so vertices are copied only when an entry is popped.
  void insert_fragment(const ConvexPolygon& first) {
    std::size_t top = 0;
    if (work_.empty()) work_.resize(16);
    {
      Fragment& f = work_[top].fragment;
      f.size = static_cast<std::uint32_t>(first.size());
      f.assumed_count = 0;
      for (std::size_t i = 0; i < first.size(); ++i) f.v[i] = first[i];
      f.ref = whole_tree;
      work_[top].inside = false;
      ++top;
    }
    Fragment buffers[2];
    while (top > 0) {
      --top;
      Fragment* cur = &buffers[0];
      Fragment* alt = &buffers[1];
      detail::copy_fragment(work_[top].fragment, *cur);
      bool inside = work_[top].inside;
      for (;;) {
        const std::uint32_t parent = cur->ref;
        const std::uint32_t ref = slot_value(parent, inside);
        if (ref == hidden_leaf) {
          ++stats_.fragments_hidden;
          break;
        }
        if (ref == visible_leaf) {
          grow_chain(parent, inside);
          break;
        }
        const OcclusionNode& node = nodes_[ref];
        const bool through_eye = node.kind == OcclusionNodeKind::top || node.kind == OcclusionNodeKind::edge;
        if (!through_eye && current_.is_box) {
          // A box fragment is its outline, not a surface: against a plane off the eye it goes whole
          // to the side its surface is on (inside only if all of the box's front is behind).
          bool behind = true;
          for (int i = 0; i < current_.box_point_count; ++i)
            behind = behind && signed_distance(node.plane, current_.box_points[i]) >= 0.0f;
          cur->ref = ref;
          inside = behind;
          continue;
        }
        if (top == work_.size()) work_.resize(2 * top);  // `node` stays valid: nodes_ does not move
        Fragment& in_piece = work_[top].fragment;
        detail::FragmentSide side = detail::classify_fragment(*cur, node.plane, current_.split_epsilon);
        if (side == detail::FragmentSide::split)
          side = detail::split_fragment(*cur, node.plane, current_.split_epsilon, in_piece, *alt);
        if (side == detail::FragmentSide::inside) {
          cur->ref = ref;
          inside = true;
        } else if (side == detail::FragmentSide::outside) {
          cur->ref = ref;
          inside = false;
        } else if (side == detail::FragmentSide::split) {
          if (in_piece.size < 3 || alt->size < 3) {
            ++stats_.fragments_degenerate;
            break;
          }
          in_piece.ref = ref;
          in_piece.assumed_count = 0;
          alt->assumed_count = 0;
          work_[top].inside = true;
          ++top;
          alt->ref = ref;
          inside = false;
          std::swap(cur, alt);
        } else {
          // Coplanar with a plane through the eye (no area) or with another occluder's own plane
          // (it hides nothing more there): drop. NaN or too many corners: drop too (losing occluder
          // area is safe).
          ++stats_.fragments_degenerate;
          break;
        }
      }
    }
  }

  // The chain of a fragment is the beam of the WHOLE occluder (its original edges, not the cut
  // edges of the fragment), closed by its own plane(s). Its region is then truly hidden on its own,
  // wherever it hangs in the tree, and two fragments of one occluder leave no seam between them:
  // a query piece sent across a cut plane within the margin still meets the same beam.
  void grow_chain(std::uint32_t parent, bool inside) {
    const std::size_t n = current_.edge_count;
    const Plane* edges = current_.edges;
    ++stats_.fragments;
    std::uint32_t depth = slot_depth(parent);
    const auto first = static_cast<std::uint32_t>(nodes_.size());
    std::uint32_t previous = whole_tree;
    const auto link = [&](std::uint32_t node) {
      if (previous != whole_tree) nodes_[previous].inside = node;
      previous = node;
    };
    for (std::size_t i = 0; i < n; ++i)
      link(add_node(edges[i], OcclusionNodeKind::edge, depth++, current_.edge_seams[i]));
    const OcclusionNodeKind closing_kind = current_.is_box ? OcclusionNodeKind::box_face : OcclusionNodeKind::polygon;
    for (int f = 0; f < current_.closing_count; ++f) link(add_node(current_.closing[f], closing_kind, depth++));
    nodes_[previous].inside = hidden_leaf;
    set_slot(parent, inside, first);
    stats_.nodes = static_cast<std::uint32_t>(nodes_.size());
  }

  // The front of a query box: the box, its center and half extent (eye-relative) and its front
  // corners (eye-relative, computed on first need).
  struct BoxFront {
    BoxFront(const Aabb& b, const glm::vec3& c, const glm::vec3& h) : box(&b), center(c), half(h) {}
    const Aabb* box;
    glm::vec3 center, half;
    glm::vec3 points[8];  // not initialized: written on first need
    int point_count = 0;
  };
  enum class FrontSide : std::uint8_t { inside, outside, straddles, unknown };
  static constexpr auto undecided_answer = static_cast<OcclusionAnswer>(0xFF);

  // Which side of `plane` the whole front of the box lies on, `m` being the margin. Tested first
  // with the box's nearest and farthest corners (center +- half-extent projected on the normal),
  // which decides almost every node ("inside" this way needs twice the margin, so the rounding of
  // the center/extent form can never matter), then with the front corners only (the faces the query
  // really tests), as a box may straddle a plane its front does not. `dmin` gets the front's least
  // distance when the corners were needed. `unknown`: NaN.
  [[nodiscard]] CULLKIT_FORCEINLINE FrontSide front_side(const Plane& plane, float m, BoxFront& front,
                                                         float& dmin) const {
    const float c = signed_distance(plane, front.center);
    const float r = glm::dot(glm::abs(plane.normal), front.half);
    // Distances that overflow (coordinates near the float range) or NaN decide nothing.
    if (!(std::fabs(c) + r <= std::numeric_limits<float>::max())) return FrontSide::unknown;
    if (c - r >= 2.0f * m) return FrontSide::inside;
    if (c + r <= m) return FrontSide::outside;
    if (front.point_count == 0) front.point_count = detail::box_front_points(*front.box, eye_, front.points);
    if (front.point_count == 0) return FrontSide::unknown;  // cannot happen: the eye is outside the box
    dmin = signed_distance(plane, front.points[0]);
    float dmax = dmin;
    for (int i = 1; i < front.point_count; ++i) {
      const float dist = signed_distance(plane, front.points[i]);
      dmin = std::min(dmin, dist);
      dmax = std::max(dmax, dist);
    }
    if (!detail::finite_distance(dmin) || !detail::finite_distance(dmax)) return FrontSide::unknown;
    if (dmin >= m) return FrontSide::inside;
    if (dmax <= m) return FrontSide::outside;
    return FrontSide::straddles;
  }

  [[nodiscard]] static OcclusionQueryResult leaf_answer(OcclusionQueryResult result, std::uint32_t leaf,
                                                        bool want_clear) {
    if (leaf == hidden_leaf) result.answer = OcclusionAnswer::hidden;
    else result.answer = want_clear ? OcclusionAnswer::clear : OcclusionAnswer::visible;
    return result;
  }

  [[nodiscard]] bool is_shared_seam(const OcclusionNode& node) const noexcept {
    return node.seam != no_seam && seams_.shared(node.seam >> 1);
  }

  enum class SeamStep : std::uint8_t {
    moved,      // `cur` went on to one child (its ref is updated)
    copies,     // `cur` became two copies: one pushed on the stack, the other written to `alt`
    ordinary,   // no room for another assumption: treat the node as an ordinary plane
    visible,    // cannot be decided (NaN, too many corners): the query answers visible
  };

  // One step at a node on a seam shared by several occluders (see occlusion_seams.hpp). A fragment
  // that already assumed a side of this seam follows that side: every point it stands for is there.
  // Otherwise a fragment clearly on one side (by the margin) goes there; one within the margin band
  // becomes two overlapping copies, the part at distance >= -m going inside and the part at distance
  // <= m going outside, each assuming its side. Each point then has a copy on its true side, and a
  // copy meeting the other occluder's plane of the same seam no longer loses the band to "visible".
  [[nodiscard]] SeamStep seam_step(const OcclusionNode& node, float m, Fragment& cur, Fragment* stack, int& top,
                                   Fragment& alt) const {
    const std::uint32_t id = node.seam >> 1;
    const std::uint32_t node_side = node.seam & 1u;  // the canonical side this node's inside is
    for (std::uint32_t k = 0; k < cur.assumed_count; ++k) {
      if ((cur.assumed[k] >> 1) != id) continue;
      cur.ref = (cur.assumed[k] & 1u) == node_side ? node.inside : node.outside;
      return SeamStep::moved;
    }
    const Plane inner{node.plane.normal, node.plane.d - m};  // inside it: distance >= m
    const Plane outer{node.plane.normal, node.plane.d + m};  // outside it: distance <= -m
    const detail::FragmentSide in_side = detail::classify_fragment(cur, inner, 0.0f);
    const detail::FragmentSide out_side = detail::classify_fragment(cur, outer, 0.0f);
    if (in_side == detail::FragmentSide::undecided || out_side == detail::FragmentSide::undecided)
      return SeamStep::visible;
    if (in_side == detail::FragmentSide::inside) {
      cur.ref = node.inside;
      return SeamStep::moved;
    }
    if (out_side == detail::FragmentSide::outside || out_side == detail::FragmentSide::on) {
      cur.ref = node.outside;
      return SeamStep::moved;
    }
    if (cur.assumed_count >= detail::max_seam_assumptions || top >= query_stack_size) return SeamStep::ordinary;
    Fragment scratch;
    Fragment& in_copy = stack[top];
    // The inside copy: the part at distance >= -m (all of it unless the fragment crosses `outer`).
    if (out_side == detail::FragmentSide::split) {
      if (detail::split_fragment(cur, outer, 0.0f, in_copy, scratch) != detail::FragmentSide::split)
        return SeamStep::visible;
    } else {
      detail::copy_fragment(cur, in_copy);
    }
    // The outside copy: the part at distance <= m.
    if (in_side == detail::FragmentSide::split) {
      if (detail::split_fragment(cur, inner, 0.0f, scratch, alt) != detail::FragmentSide::split)
        return SeamStep::visible;
    } else {
      detail::copy_fragment(cur, alt);
    }
    detail::copy_assumptions(cur, in_copy);
    detail::copy_assumptions(cur, alt);
    in_copy.assumed[in_copy.assumed_count++] = 2 * id + node_side;
    alt.assumed[alt.assumed_count++] = 2 * id + (1u - node_side);
    in_copy.ref = node.inside;
    alt.ref = node.outside;
    ++top;
    return SeamStep::copies;
  }

  // The exact walk: the fragments stack[0..count) are pushed down the tree from their `ref`, split
  // where they straddle a plane shifted inward by the margin. Depth first, outside pieces first, so
  // a query that reaches a visible leaf stops early (unless `want_clear`); hidden only if every
  // piece reached a hidden leaf. The current fragment lives in one of two local buffers (a split
  // writes its outside piece into the other one and its inside piece straight onto the stack), so
  // only pops copy vertices.
  // With `front`, the fragments are the box's outline cone, which stands for its surface only at
  // planes through the eye (there the side of a point depends only on its direction); at any other
  // plane the whole front of the box decides, and if it straddles the walk returns
  // `undecided_answer` so the caller can walk the faces themselves.
  [[nodiscard]] OcclusionAnswer walk_fragments(Fragment* stack, int count, float scale, bool want_clear,
                                               BoxFront* front) const {
    const float eps = params_.margin;
    bool any_hidden = false, any_visible = false;
    int top = count;
    Fragment buffers[2];
    while (top > 0) {
      Fragment* cur = &buffers[0];
      Fragment* alt = &buffers[1];
      detail::copy_fragment(stack[--top], *cur);
      for (;;) {
        const std::uint32_t ref = cur->ref;
        if (ref == hidden_leaf) {
          any_hidden = true;
          break;
        }
        if (ref == visible_leaf) {
          any_visible = true;
          break;
        }
        const OcclusionNode& node = nodes_[ref];
        const float m = eps * (scale + std::fabs(node.plane.d));
        if (front != nullptr && node.kind != OcclusionNodeKind::top && node.kind != OcclusionNodeKind::edge) {
          float dmin = 0.0f;
          const FrontSide side = front_side(node.plane, m, *front, dmin);
          if (side == FrontSide::inside) cur->ref = node.inside;
          else if (side == FrontSide::outside) cur->ref = node.outside;
          else return undecided_answer;  // the front straddles (or NaN): walk the faces instead
          continue;
        }
        if (is_shared_seam(node)) {
          const SeamStep step = seam_step(node, m, *cur, stack, top, *alt);
          if (step == SeamStep::visible) {
            any_visible = true;
            break;
          }
          if (step == SeamStep::copies) std::swap(cur, alt);
          if (step != SeamStep::ordinary) continue;
        }
        const Plane shifted{node.plane.normal, node.plane.d - m};
        // With the stack full, the inside piece has nowhere to go: a split then answers visible.
        Fragment& in_piece = top < query_stack_size ? stack[top] : *alt;
        detail::FragmentSide side = detail::classify_fragment(*cur, shifted, 0.0f);
        if (side == detail::FragmentSide::split) side = detail::split_fragment(*cur, shifted, 0.0f, in_piece, *alt);
        if (side == detail::FragmentSide::inside) {
          cur->ref = node.inside;
        } else if (side == detail::FragmentSide::outside || side == detail::FragmentSide::on) {
          cur->ref = node.outside;
        } else if (side == detail::FragmentSide::split && top < query_stack_size) {
          in_piece.ref = node.inside;
          detail::copy_assumptions(*cur, in_piece);
          ++top;
          alt->ref = node.outside;
          detail::copy_assumptions(*cur, *alt);
          std::swap(cur, alt);
        } else {
          any_visible = true;  // NaN, too many corners or a full stack: cannot be decided, visible
          break;
        }
      }
      if (any_visible && !want_clear) return OcclusionAnswer::visible;
    }
    if (any_visible) return (want_clear && !any_hidden) ? OcclusionAnswer::clear : OcclusionAnswer::visible;
    return any_hidden ? OcclusionAnswer::hidden : OcclusionAnswer::visible;
  }

  // Top-level planes (seed §3.4.3): azimuth wedges around `up`, then elevation bands in each wedge.
  // Plane k (k = 0..K-1) contains `up` and the horizontal direction at azimuth psi_k = pi k / K; its
  // inside holds the azimuths in (psi_k, psi_k + pi). Plane 0 is the root; in each half the other
  // planes' cut rays are sorted by k, so a balanced tree over k needs no scratch memory.
  void build_top_level() {
    const int ka = std::min(params_.azimuth_planes, 64);
    if (ka <= 0) return;
    glm::dvec3 up(params_.up);
    if (!(glm::length(up) > 0.0) || !std::isfinite(glm::length(up))) up = glm::dvec3(0, 1, 0);
    up = glm::normalize(up);
    glm::dvec3 fwd = glm::dvec3(params_.forward);
    fwd -= up * glm::dot(up, fwd);
    if (!(glm::length(fwd) > 1e-6) || !std::isfinite(glm::length(fwd))) {
      fwd = std::fabs(up.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
      fwd -= up * glm::dot(up, fwd);
    }
    fwd = glm::normalize(fwd);
    up_ = up;
    fwd_ = fwd;
    right_ = glm::cross(fwd, up);
    const double pi = 3.14159265358979323846;
    const std::uint32_t root = add_node(azimuth_plane(0, ka), OcclusionNodeKind::top, 0);
    root_ = root;
    const std::uint32_t first_half = build_azimuth(1, ka, ka, false, 0.0, pi, 1);
    const std::uint32_t second_half = build_azimuth(1, ka, ka, true, pi, 2 * pi, 1);
    nodes_[root].inside = first_half;
    nodes_[root].outside = second_half;
  }
  [[nodiscard]] Plane azimuth_plane(int k, int ka) const {
    const double psi = 3.14159265358979323846 * k / ka;
    return detail::eye_plane_from_normal(-std::sin(psi) * fwd_ + std::cos(psi) * right_);
  }
  std::uint32_t build_azimuth(int lo, int hi, int ka, bool second_half, double a, double b, std::uint32_t depth) {
    if (lo >= hi) return build_elevation(0.5 * (a + b), 0, params_.elevation_planes, depth);
    const int mid = (lo + hi) / 2;
    const double pi = 3.14159265358979323846;
    const double angle = pi * mid / ka + (second_half ? pi : 0.0);
    const std::uint32_t node = add_node(azimuth_plane(mid, ka), OcclusionNodeKind::top, depth);
    const std::uint32_t below = build_azimuth(lo, mid, ka, second_half, a, angle, depth + 1);
    const std::uint32_t above = build_azimuth(mid + 1, hi, ka, second_half, angle, b, depth + 1);
    // First half: larger azimuths are inside plane k; second half: they are outside.
    nodes_[node].inside = second_half ? below : above;
    nodes_[node].outside = second_half ? above : below;
    return node;
  }
  std::uint32_t build_elevation(double azimuth, int lo, int hi, std::uint32_t depth) {
    if (lo >= hi || params_.elevation_planes <= 0) return visible_leaf;
    const int count = params_.elevation_planes;
    const int mid = (lo + hi) / 2;
    const double pi = 3.14159265358979323846;
    const double theta = -0.5 * pi + pi * (mid + 1) / (count + 1);
    const glm::dvec3 h = std::cos(azimuth) * fwd_ + std::sin(azimuth) * right_;
    // Contains the horizontal direction across the wedge; inside = above elevation theta.
    const Plane p = detail::eye_plane_from_normal(-std::sin(theta) * h + std::cos(theta) * up_);
    const std::uint32_t node = add_node(p, OcclusionNodeKind::top, depth);
    const std::uint32_t below = build_elevation(azimuth, lo, mid, depth + 1);
    const std::uint32_t above = build_elevation(azimuth, mid + 1, hi, depth + 1);
    nodes_[node].inside = above;
    nodes_[node].outside = below;
    return node;
  }

  OcclusionParams params_;
  glm::vec3 eye_ = glm::vec3(0.0f);
  bool eye_ok_ = false;
  float eye_scale_ = 0.0f;
  std::uint32_t root_ = visible_leaf;
  std::vector<OcclusionNode> nodes_;
  std::vector<InsertItem> work_;
  struct SortKey {
    float key;
    std::uint32_t index;
  };
  std::vector<SortKey> order_;  // insert_box_occluders' scratch
  OcclusionStats stats_;
  Current current_;
  detail::SeamTable seams_;
  std::uint32_t occluder_serial_ = 0;  // numbers the occluders since `reset` (seam owners)
  glm::dvec3 up_ = glm::dvec3(0, 1, 0), fwd_ = glm::dvec3(0, 0, -1), right_ = glm::dvec3(1, 0, 0);
};

}  // namespace cullkit
