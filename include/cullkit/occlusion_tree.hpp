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
// Fusion (seams; detail/occlusion/seams.hpp, docs/occlusion_fusion.md). Two occluders sharing an
// edge each have a plane through the eye and that edge: one true plane, so a query piece within
// the margin of it would be "not clearly inside" for both, and the pair would hide nothing along the
// seam. Every edge plane therefore carries a seam id that names its true plane exactly (the edge's
// corners bit for bit, or an axis plane through the eye), and edge normals are computed from the
// corners in canonical order, so partners are exact negations. At a seam used by two occluders, a
// piece within the band becomes two overlapping copies (distance >= -m inside, <= m outside, from the
// seam's true plane, whose normal comes from the world corners), each assuming its side; at every
// later node of that seam a copy follows its assumption. Each point has a copy on its true side, and
// every plane of the chain that copy ends in holds for the point (by the margin or by the
// assumption), so a hidden answer stays proof. For a triangulated surface
// (docs/occlusion_fusion.md, "Triangulated meshes"): an assumption also holds at an edge exactly
// collinear with the assumed one; a copy reaching an empty leaf is dropped when its assumptions leave
// it no open set of points (exact tests around a mesh corner, or a clip with no area left), which is
// safe because the hidden region is closed; and a polygon occluder with a corner in the band of an
// edge plane but truly across it is inserted on both sides.
//
// Layout: this header holds the public types; the machinery lives in detail headers, as helpers
// over the tree's arrays: detail/occlusion/insert.hpp (chains, insertion), detail/occlusion/walk.hpp
// (the query phases and the seam rule), detail/occlusion/top_level.hpp (the planes around the eye).
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
#include "detail/occlusion/geometry.hpp"
#include "detail/occlusion/insert.hpp"
#include "detail/occlusion/query.hpp"
#include "detail/occlusion/seams.hpp"
#include "detail/occlusion/top_level.hpp"
#include "detail/occlusion/walk.hpp"
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
    seams_.clear(eye);
    occluder_serial_ = 0;
    stats_ = OcclusionStats{};
    root_ = visible_leaf;
    if (eye_ok_) detail::OcclusionTopLevel<OcclusionTree>::build(*this);
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
    if (detail::OcclusionInsert<OcclusionTree>::polygon(*this, polygon, count)) ++stats_.occluders_inserted;
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
    if (!detail::OcclusionInsert<OcclusionTree>::box(*this, box)) skip();
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
    for (int f = 0; f < count; ++f) any = detail::OcclusionInsert<OcclusionTree>::polygon(*this, faces[f], 4) || any;
    if (any) ++stats_.occluders_inserted;
    else skip();
  }

  /// Inserts many solid box occluders, nearest to the eye first (each as `insert_box_occluder`),
  /// leaving out those already hidden by the nearer ones (counted in `stats().occluders_hidden`:
  /// everything behind a hidden box is hidden too, so they would add nothing). The hidden region does
  /// not depend on the order, but the tree does: near occluders inserted first hide most of the far
  /// ones, which makes the tree much smaller and its queries faster than a random order (measured
  /// in docs/occlusion.md). Invalid boxes are skipped and counted
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
    return detail::OcclusionWalk<OcclusionTree>::box(*this, box, start, want_clear);
  }

  /// The same for a convex planar polygon in world coordinates.
  [[nodiscard]] OcclusionQueryResult query(const ConvexPolygon& polygon, std::uint32_t start = whole_tree,
                                           bool want_clear = false) const {
    return detail::OcclusionWalk<OcclusionTree>::polygon(*this, polygon, start, want_clear);
  }

 private:
  // The machinery lives in detail headers, as helpers over this class's arrays.
  template <class>
  friend struct detail::OcclusionInsert;
  template <class>
  friend struct detail::OcclusionWalk;
  template <class>
  friend struct detail::OcclusionTopLevel;
  // The names the helpers use, so that their headers need none of the public types.
  using Node = OcclusionNode;
  using NodeKind = OcclusionNodeKind;
  using Answer = OcclusionAnswer;
  using QueryResult = OcclusionQueryResult;
  using Fragment = detail::QueryFragment<ConvexPolygon::capacity>;
  struct SortKey {
    float key;
    std::uint32_t index;
  };

  void skip() { ++stats_.occluders_skipped; }

  std::uint32_t add_node(const Plane& plane, OcclusionNodeKind kind, std::uint32_t depth,
                         std::uint32_t seam = no_seam) {
    const auto index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(OcclusionNode{plane, visible_leaf, visible_leaf, depth, kind, seam});
    stats_.depth = std::max(stats_.depth, depth);
    return index;
  }

  OcclusionParams params_;
  glm::vec3 eye_ = glm::vec3(0.0f);
  bool eye_ok_ = false;
  float eye_scale_ = 0.0f;
  std::uint32_t root_ = visible_leaf;
  std::vector<OcclusionNode> nodes_;
  std::vector<detail::InsertItem<ConvexPolygon::capacity>> work_;  // insertion's fragment stack
  std::vector<SortKey> order_;  // insert_box_occluders' scratch
  OcclusionStats stats_;
  detail::OcclusionChain current_;  // the occluder being inserted
  detail::SeamTable seams_;
  std::uint32_t occluder_serial_ = 0;  // numbers the occluders since `reset` (seam owners)
  glm::dvec3 up_ = glm::dvec3(0, 1, 0), fwd_ = glm::dvec3(0, 0, -1), right_ = glm::dvec3(1, 0, 0);
};

}  // namespace cullkit
