// cullkit/detail/occlusion/walk.hpp: the query walks of OcclusionTree (not public API).
//
// `OcclusionWalk<Tree>` holds the three query phases described in occlusion_tree.hpp as static
// functions over a const tree: the undivided descent of the whole box or polygon, the exact walk of
// fragments (outline cone or front faces) with the seam rule, and the test of a box's front against
// one plane. It is a template over the tree only so that this header needs none of the public types
// (the tree names them through member aliases) and compiles on its own; `OcclusionTree` is its one
// instantiation and befriends it. Everything here is const: queries may run concurrently.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "../../box_proxy.hpp"
#include "../../config.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/convex_polygon.hpp"
#include "../../geometry/plane.hpp"
#include "geometry.hpp"
#include "query.hpp"
#include "seams.hpp"

namespace cullkit::detail {

/// The front of a query box: the box, its center and half extent (eye-relative) and its front
/// corners (eye-relative, computed on first need).
struct BoxFront {
  BoxFront(const Aabb& b, const glm::vec3& c, const glm::vec3& h) : box(&b), center(c), half(h) {}
  const Aabb* box;
  glm::vec3 center, half;
  glm::vec3 points[8];  // not initialized: written on first need
  int point_count = 0;
};

/// The outline of a query seen from the eye (its world corners) and whether the directions it covers
/// have an interior (see OcclusionWalk::has_interior), decided on first need: only a seam copy that
/// may be dropped asks, so most queries never pay for it.
struct QueryOutline {
  QueryOutline(const glm::vec3* w, std::uint32_t n) : world(w), count(n) {}
  const glm::vec3* world;
  std::uint32_t count;
  int interior = -1;  // -1: not decided yet; else 0 or 1
};

/// Where the whole front of a query box lies against one plane; `unknown` for NaN or overflow.
enum class FrontSide : std::uint8_t { inside, outside, straddles, unknown };

/// Which side of `plane` the whole front of the box lies on, `m` being the margin. Tested first
/// with the box's nearest and farthest corners (center +- half-extent projected on the normal),
/// which decides almost every node ("inside" this way needs twice the margin, so the rounding of
/// the center/extent form can never matter), then with the front corners only (the faces the query
/// really tests), as a box may straddle a plane its front does not. `dmin` gets the front's least
/// distance when the corners were needed. `unknown`: NaN.
[[nodiscard]] CULLKIT_FORCEINLINE FrontSide front_side(const Plane& plane, float m, const glm::vec3& eye,
                                                       BoxFront& front, float& dmin) {
  const float c = signed_distance(plane, front.center);
  const float r = glm::dot(glm::abs(plane.normal), front.half);
  // Distances that overflow (coordinates near the float range) or NaN decide nothing.
  if (!(std::fabs(c) + r <= std::numeric_limits<float>::max())) return FrontSide::unknown;
  if (c - r >= 2.0f * m) return FrontSide::inside;
  if (c + r <= m) return FrontSide::outside;
  if (front.point_count == 0) front.point_count = box_front_points(*front.box, eye, front.points);
  if (front.point_count == 0) return FrontSide::unknown;  // cannot happen: the eye is outside the box
  dmin = signed_distance(plane, front.points[0]);
  float dmax = dmin;
  for (int i = 1; i < front.point_count; ++i) {
    const float dist = signed_distance(plane, front.points[i]);
    dmin = std::min(dmin, dist);
    dmax = std::max(dmax, dist);
  }
  if (!finite_distance(dmin) || !finite_distance(dmax)) return FrontSide::unknown;
  if (dmin >= m) return FrontSide::inside;
  if (dmax <= m) return FrontSide::outside;
  return FrontSide::straddles;
}

/// The query side of `Tree` (an OcclusionTree); see the file comment.
template <class Tree>
struct OcclusionWalk {
  using Fragment = typename Tree::Fragment;
  using Node = typename Tree::Node;
  using NodeKind = typename Tree::NodeKind;
  using Answer = typename Tree::Answer;
  using Result = typename Tree::QueryResult;
  static constexpr Answer undecided_answer = static_cast<Answer>(0xFF);
  static constexpr std::uint32_t hidden_leaf = Tree::hidden_leaf;
  static constexpr std::uint32_t visible_leaf = Tree::visible_leaf;
  static constexpr std::uint32_t whole_tree = Tree::whole_tree;
  static constexpr int stack_size = Tree::query_stack_size;

  /// OcclusionTree::query for a box.
  [[nodiscard]] static Result box(const Tree& t, const Aabb& box, std::uint32_t start, bool want_clear) {
    Result result;
    if (start != whole_tree && start >= t.nodes_.size()) start = whole_tree;  // stale or invalid: the root
    result.together = start;
    const glm::vec3& eye = t.eye_;
    if (!t.eye_ok_ || !is_valid(box) || contains(box, eye)) return result;
    // Eye-relative box; the largest norm1 over the corners separates per axis.
    const glm::vec3 lo = box.min - eye, hi = box.max - eye;
    const glm::vec3 far = glm::max(glm::abs(lo), glm::abs(hi));
    const float scale = far.x + far.y + far.z + t.eye_scale_;
    // Halves first: lo + hi may overflow for boxes near the float range.
    BoxFront front(box, 0.5f * lo + 0.5f * hi, 0.5f * hi - 0.5f * lo);
    // Phase 1: the whole box goes down one path, each plane decided by `front_side`.
    // Where the front straddles a plane, the whole box goes on to the OUTSIDE. That needs no proof:
    // a hidden leaf is only reached through a complete occluder chain, every step of which was an
    // inside decision proven for the whole box, so reaching one means one occluder hides all of the
    // box. Reaching a visible leaf after such a step proves nothing, except in one case: a path with a
    // single straddle whose outside part clearly exists takes exactly that part to the visible leaf.
    // Otherwise the exact walk (phase 2) starts at the first straddled node.
    std::uint32_t ref = start == whole_tree ? t.root_ : start;
    std::uint32_t first_split = visible_leaf;
    int splits = 0;
    bool clear_split = false;  // the first straddle had front corners clearly outside
    while (ref < hidden_leaf) {
      const Node& node = t.nodes_[ref];
      const float m = t.params_.margin * (scale + std::fabs(node.plane.d));
      float dmin = 0.0f;
      FrontSide side = front_side(node.plane, m, eye, front, dmin);
      if (side == FrontSide::unknown) return result;  // NaN: visible
      // On a shared seam, a front within the margin band of the plane must meet the seam rule
      // (walk_fragments), not slip to the outside where the other occluder's chain may not be.
      if (side == FrontSide::outside && is_shared_seam(t, node)) {
        float flipped_min = 0.0f;
        const Plane flipped{-node.plane.normal, -node.plane.d};
        if (front_side(flipped, m, eye, front, flipped_min) != FrontSide::inside) side = FrontSide::straddles;
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
    Fragment stack[static_cast<std::size_t>(stack_size)];
    glm::vec3 outline[6];
    const auto corners = static_cast<std::uint32_t>(box_silhouette(box, eye, outline));
    // The box's front is the graph of its depth over the outline's directions, so the outline says
    // whether the query has an interior for the seam copies' vacuity rule (see `has_interior`).
    QueryOutline shape(outline, corners);
    if (corners >= 3) {
      for (std::uint32_t i = 0; i < corners; ++i) stack[0].v[i] = outline[i] - eye;
      stack[0].size = corners;
      stack[0].ref = first_split;
      stack[0].assumed_count = 0;
      result.answer = walk_fragments(t, stack, 1, scale, want_clear, &front, shape);
      if (result.answer != undecided_answer) return result;
    }
    // Phase 3: the front faces, split at every plane they straddle.
    result.answer = Answer::visible;
    const int nfaces = box_front_fragments(box, eye, stack);
    if (nfaces == 0) return result;
    for (int f = 0; f < nfaces; ++f) stack[f].ref = first_split;
    result.answer = walk_fragments(t, stack, nfaces, scale, want_clear, nullptr, shape);
    return result;
  }

  /// OcclusionTree::query for a convex planar polygon.
  [[nodiscard]] static Result polygon(const Tree& t, const ConvexPolygon& polygon, std::uint32_t start,
                                      bool want_clear) {
    Result result;
    if (start != whole_tree && start >= t.nodes_.size()) start = whole_tree;  // stale or invalid: the root
    result.together = start;
    if (!t.eye_ok_ || polygon.empty() || polygon.overflow()) return result;
    Fragment stack[static_cast<std::size_t>(stack_size)];
    Fragment& local = stack[0];
    float scale = 0.0f;
    local.size = static_cast<std::uint32_t>(polygon.size());
    local.assumed_count = 0;
    for (std::size_t i = 0; i < polygon.size(); ++i) {
      if (!finite3(polygon[i])) return result;
      local.v[i] = polygon[i] - t.eye_;
      scale = std::max(scale, norm1(local.v[i]));
    }
    scale += t.eye_scale_;
    // Phase 1: the whole polygon goes down while its corners stay on one side.
    std::uint32_t ref = start == whole_tree ? t.root_ : start;
    while (ref < hidden_leaf) {
      const Node& node = t.nodes_[ref];
      const float m = t.params_.margin * (scale + std::fabs(node.plane.d));
      float dmin = signed_distance(node.plane, local.v[0]), dmax = dmin;
      for (std::uint32_t i = 1; i < local.size; ++i) {
        const float dist = signed_distance(node.plane, local.v[i]);
        dmin = std::min(dmin, dist);
        dmax = std::max(dmax, dist);
      }
      if (!finite_distance(dmin) || !finite_distance(dmax)) return result;  // overflow, NaN: visible
      if (!(dmin >= m) && !(dmax <= m)) break;  // straddles: split from here
      if (!(dmin >= m) && !(dmax <= -m) && is_shared_seam(t, node)) break;  // in a seam's band: the seam rule
      result.together = ref;
      ref = dmin >= m ? node.inside : node.outside;
    }
    if (ref >= hidden_leaf) return leaf_answer(result, ref, want_clear);
    result.together = ref;
    local.ref = ref;
    QueryOutline shape(&polygon[0], static_cast<std::uint32_t>(polygon.size()));
    result.answer = walk_fragments(t, stack, 1, scale, want_clear, nullptr, shape);
    return result;
  }

  [[nodiscard]] static Result leaf_answer(Result result, std::uint32_t leaf, bool want_clear) {
    if (leaf == hidden_leaf) result.answer = Answer::hidden;
    else result.answer = want_clear ? Answer::clear : Answer::visible;
    return result;
  }

  [[nodiscard]] static bool is_shared_seam(const Tree& t, const Node& node) noexcept {
    return node.seam != Tree::no_seam && t.seams_.shared(node.seam >> 1);
  }

  enum class SeamStep : std::uint8_t {
    moved,      // `cur` went on to one child (its ref is updated)
    copies,     // `cur` became two copies: one pushed on the stack, the other written to `alt`
    ordinary,   // no room for another assumption, or no true plane: treat the node as an ordinary plane
    visible,    // cannot be decided (NaN, too many corners): the query answers visible
  };

  // One step at a node on a seam shared by several occluders (see seams.hpp). A fragment
  // that already assumed a side of this seam follows that side: every point it stands for is there.
  // Otherwise a fragment clearly on one side (by the margin) goes there; one within the margin band
  // becomes two overlapping copies, the part at distance >= -m going inside and the part at distance
  // <= m going outside, each assuming its side. Each point then has a copy on its true side, and a
  // copy meeting the other occluder's plane of the same seam keeps the band instead of losing it
  // to "visible".
  [[nodiscard]] static SeamStep seam_step(const SeamTable& seams, const Node& node, float m, Fragment& cur, Fragment* stack, int& top,
                                          Fragment& alt) {
    const std::uint32_t edge = node.seam >> 1;
    const std::uint32_t id = edge;
    const std::uint32_t node_side = node.seam & 1u;  // the canonical side this node's inside is
    for (std::uint32_t k = 0; k < cur.assumed_count; ++k) {
      if ((cur.assumed[k] >> 1) != id) continue;
      cur.ref = (cur.assumed[k] & 1u) == node_side ? node.inside : node.outside;
      return SeamStep::moved;
    }
    // Measured against the seam's true plane, not the node's: the copies must reach m across the plane
    // their assumptions name at every point, and the node's plane, built from rounded eye-relative
    // corners, can part from it by more than m far along a short edge's line (SeamTable::unit_normal).
    const glm::vec3& canonical = seams.unit_normal(edge);
    if (canonical == glm::vec3(0.0f)) return SeamStep::ordinary;
    const glm::vec3 normal = node_side != 0 ? canonical : -canonical;
    const Plane inner{normal, -m};  // inside it: distance >= m
    const Plane outer{normal, m};   // outside it: distance <= -m
    const FragmentSide in_side = classify_fragment(cur, inner, 0.0f);
    const FragmentSide out_side = classify_fragment(cur, outer, 0.0f);
    if (in_side == FragmentSide::undecided || out_side == FragmentSide::undecided) return SeamStep::visible;
    if (in_side == FragmentSide::inside) {
      cur.ref = node.inside;
      return SeamStep::moved;
    }
    if (out_side == FragmentSide::outside || out_side == FragmentSide::on) {
      cur.ref = node.outside;
      return SeamStep::moved;
    }
    // In the band: an assumption about another edge in the same plane (collinear edges) holds here.
    for (std::uint32_t k = 0; k < cur.assumed_count; ++k) {
      bool opposite = false;
      if (!seams.coplanar(cur.assumed_edge[k], edge, opposite)) continue;
      cur.ref = ((cur.assumed[k] & 1u) ^ (opposite ? 1u : 0u)) == node_side ? node.inside : node.outside;
      return SeamStep::moved;
    }
    if (top >= stack_size) return SeamStep::ordinary;
    // The walk goes on with the inside copy (into this occluder's chain, which it mostly ends in) and
    // keeps the outside one for later: around a mesh corner shared by many triangles, a copy then
    // sweeps round the corner with one pending copy at a time instead of one per triangle.
    Fragment scratch;
    Fragment& in_copy = alt;
    Fragment& out_copy = stack[top];
    // The inside copy: the part at distance >= -m (all of it unless the fragment crosses `outer`).
    if (out_side == FragmentSide::split) {
      if (split_fragment(cur, outer, 0.0f, in_copy, scratch) != FragmentSide::split) return SeamStep::visible;
    } else {
      copy_fragment(cur, in_copy);
    }
    // The outside copy: the part at distance <= m.
    if (in_side == FragmentSide::split) {
      if (split_fragment(cur, inner, 0.0f, scratch, out_copy) != FragmentSide::split) return SeamStep::visible;
    } else {
      copy_fragment(cur, out_copy);
    }
    copy_assumptions(cur, in_copy);
    copy_assumptions(cur, out_copy);
    add_assumption(seams, in_copy, 2 * id + node_side, edge);
    add_assumption(seams, out_copy, 2 * id + (1u - node_side), edge);
    in_copy.ref = node.inside;
    out_copy.ref = node.outside;
    ++top;
    return SeamStep::copies;
  }

  // Adds an assumption. A full list first forgets one that the others imply (see
  // `implied_assumption`), else its oldest one. Any subset of a copy's assumptions is true of every
  // point the copy stands for, so forgetting one is safe: at a later node of that seam the copy
  // measures again (and may split), and a vacuity test on fewer assumptions finds less.
  static void add_assumption(const SeamTable& seams, Fragment& f, std::uint32_t code, std::uint32_t edge) noexcept {
    if (f.assumed_count == max_seam_assumptions) {
      const std::uint32_t implied = implied_assumption(seams, f);
      for (std::uint32_t k = implied == max_seam_assumptions ? 1 : implied + 1; k < max_seam_assumptions; ++k) {
        f.assumed[k - 1] = f.assumed[k];
        f.assumed_edge[k - 1] = f.assumed_edge[k];
      }
      --f.assumed_count;
    }
    f.assumed[f.assumed_count] = code;
    f.assumed_edge[f.assumed_count] = edge;
    ++f.assumed_count;
  }

  // The assumptions of `f` whose planes pass through the world point `v` (a corner of their edge, or
  // exactly on their plane: collinear edges share one plane), as a second point W of each plane and
  // the sign that makes cross(V, W) (V = v - eye, W = w - eye) the normal of the assumed half-space.
  // Returns how many. A plane whose second point lies on the ray through V is left out (a subset of
  // the assumptions: safe).
  static std::uint32_t assumptions_at(const SeamTable& seams, const Fragment& f, const glm::vec3& v,
                                      glm::vec3* other, int* turn, std::uint32_t* index) noexcept {
    const glm::vec3& eye = seams.eye();
    std::uint32_t count = 0;
    for (std::uint32_t j = 0; j < f.assumed_count; ++j) {
      const std::uint32_t edge = f.assumed_edge[j];
      const SeamKey& key = seams.key(edge);
      const glm::dvec3 normal = seams.canonical_normal(edge);
      // x: a point far off the plane, eye + the axis along which the plane's normal is largest.
      int axis = 0;
      for (int a = 1; a < 3; ++a)
        if (std::fabs(normal[a]) > std::fabs(normal[axis])) axis = a;
      glm::vec3 x = eye;
      x[axis] += std::fabs(eye[axis]) + 1.0f;
      glm::vec3 w;
      int x_side;  // the side of x along the edge's canonical normal
      if (is_axis_key(key)) {
        // The axis plane through the eye: v lies in it when its coordinate is the eye's. The second
        // point moves v along the other axis where v - eye is smaller, so that it is off v's ray.
        if (v[axis] != eye[axis]) continue;
        const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        const int along = std::fabs(v[a1] - eye[a1]) < std::fabs(v[a2] - eye[a2]) ? a1 : a2;
        w = v;
        w[along] += std::fabs(v[along]) + 1.0f;
        x_side = 1;
      } else {
        glm::vec3 lo, hi;
        key_corners(key, lo, hi);
        const bool v_is_lo = same_point(lo, v), v_is_hi = same_point(hi, v);
        if (!v_is_lo && !v_is_hi && orientation_sign(eye, lo, hi, v) != 0) continue;
        w = v_is_lo ? hi : lo;
        x_side = orientation_sign(eye, lo, hi, x);
      }
      // cross(V, W) = lambda * (the canonical normal), one plane: lambda has the sign of the product
      // of the sides x lies on for both (x is far off the plane, so both signs are certain).
      const int lambda = orientation_sign(eye, v, w, x) * x_side;
      if (lambda == 0) continue;
      const bool positive = (f.assumed[j] & 1u) != 0;
      other[count] = w;
      turn[count] = positive ? lambda : -lambda;
      index[count] = j;
      ++count;
    }
    return count;
  }

  // Which way the normal of assumed half-space j lies from that of i around the corner v: 1
  // counter-clockwise within a half turn, -1 clockwise, 0 parallel. With V = v - eye and
  // W = w - eye the normals are turn * cross(V, W), and
  // V . (cross(V, W_i) x cross(V, W_j)) = |V|^2 det[V; W_i; W_j].
  [[nodiscard]] static int normal_turn(const SeamTable& seams, const glm::vec3& v, const glm::vec3* other,
                                       const int* turn, std::uint32_t i, std::uint32_t j) noexcept {
    return turn[i] * turn[j] * orientation_sign(seams.eye(), v, other[i], other[j]);
  }

  // An assumption implied by two others at a corner they share (its normal strictly between theirs,
  // which are less than a half turn apart: their half-spaces' intersection lies in its own), or
  // max_seam_assumptions. Around a mesh corner a copy keeps the two that bound its sector.
  [[nodiscard]] static std::uint32_t implied_assumption(const SeamTable& seams, const Fragment& f) noexcept {
    glm::vec3 other[max_seam_assumptions];
    int turn[max_seam_assumptions];
    std::uint32_t index[max_seam_assumptions];
    for (std::uint32_t k = 0; k < f.assumed_count; ++k) {
      const SeamKey& key = seams.key(f.assumed_edge[k]);
      if (is_axis_key(key)) continue;
      glm::vec3 lo, hi;
      key_corners(key, lo, hi);
      for (const glm::vec3& v : {lo, hi}) {
        const std::uint32_t count = assumptions_at(seams, f, v, other, turn, index);
        if (count < 3) continue;
        for (std::uint32_t j = 0; j < count; ++j)
          for (std::uint32_t a = 0; a < count; ++a) {
            if (a == j || normal_turn(seams, v, other, turn, a, j) <= 0) continue;
            for (std::uint32_t b = 0; b < count; ++b) {
              if (b == j || b == a) continue;
              if (normal_turn(seams, v, other, turn, j, b) > 0 && normal_turn(seams, v, other, turn, a, b) > 0) return index[j];
            }
          }
      }
    }
    return max_seam_assumptions;
  }

  // True if no point of the fragment satisfies its seam assumptions: the fragment clipped by every
  // assumed half-space, each widened by a slack far above the error of its double-precision plane
  // (normal from the edge's world corners), keeps no area. Then the points the copy stands for form
  // a set with no interior (or none at all), and the copy may be dropped (see below). This finds the
  // copies whose planes meet away from any shared corner, in a band where other planes cross too.
  [[nodiscard]] static bool assumptions_miss(const SeamTable& seams, const Fragment& f) noexcept {
    if (f.assumed_count == 0) return false;
    constexpr std::size_t capacity = 2 * ConvexPolygon::capacity;
    glm::dvec3 poly[capacity], next[capacity];
    std::size_t n = f.size;
    if (n > ConvexPolygon::capacity) return false;
    for (std::size_t i = 0; i < n; ++i) poly[i] = glm::dvec3(f.v[i]);
    for (std::uint32_t k = 0; k < f.assumed_count && n >= 3; ++k) {
      const std::uint32_t root = f.assumed[k] >> 1;
      glm::dvec3 normal = seams.canonical_normal(root);
      const double length = glm::length(normal);
      if (!(length > 0.0) || !std::isfinite(length)) return false;
      normal /= (f.assumed[k] & 1u) ? length : -length;
      std::size_t m = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (m + 2 > capacity) return false;  // cannot happen (each clip adds one corner at most)
        const glm::dvec3& a = poly[i];
        const glm::dvec3& b = poly[(i + 1) % n];
        const double da = glm::dot(normal, a) + 1e-8 * glm::length(a);
        const double db = glm::dot(normal, b) + 1e-8 * glm::length(b);
        if (da >= 0.0) next[m++] = a;
        if ((da >= 0.0) != (db >= 0.0)) next[m++] = a + (b - a) * (da / (da - db));
      }
      n = m;
      for (std::size_t i = 0; i < n; ++i) poly[i] = next[i];
    }
    if (n < 3) return true;
    glm::dvec3 area(0.0);
    for (std::size_t i = 0; i < n; ++i) area += glm::cross(poly[i], poly[(i + 1) % n]);
    return !(glm::length(area) > 0.0);
  }

  // True if the fragment's seam assumptions leave no open set of directions: some mesh corner V is a
  // corner of three or more of its assumed edges, and the half-spaces they assume (all bounded by
  // planes through the eye and V) meet only in a plane or a line. Each plane is given exactly by V
  // and the edge's other corner W (`normal_turn` is exact). The half-spaces meet in an open set
  // exactly when their normals lie in an open half-plane around V: then one normal has all the
  // others strictly counter-clockwise from it, within a half turn.
  //
  // Why such a copy may be dropped: every point of the query has a chain of copies whose
  // assumptions hold for it (seam_step), so dropping copies that stand only for a closed set with no
  // interior leaves every point outside a closed nowhere-dense set proven hidden; the hidden region
  // of closed occluders is closed, so that proves every point of the query.
  [[nodiscard]] static bool assumptions_vacuous(const SeamTable& seams, const Fragment& f) noexcept {
    if (f.assumed_count < 3) return false;
    // Candidate corners: those of the assumed planes' edges whose direction lies within the
    // fragment's cone (its centre direction and widest corner, with room to spare).
    glm::dvec3 centre(0.0);
    for (std::uint32_t i = 0; i < f.size; ++i) centre += glm::normalize(glm::dvec3(f.v[i]));
    const double centre_length = glm::length(centre);
    if (!(centre_length > 0.0)) return false;
    centre /= centre_length;
    double widest = 1.0;  // the least cosine between the centre and a corner
    for (std::uint32_t i = 0; i < f.size; ++i) widest = std::min(widest, glm::dot(centre, glm::normalize(glm::dvec3(f.v[i]))));
    const double reach = widest - 1e-6 - 0.01 * (1.0 - widest);
    const glm::dvec3 eye(seams.eye());
    glm::vec3 other[max_seam_assumptions];
    int turn[max_seam_assumptions];
    std::uint32_t index[max_seam_assumptions];
    int budget = 64;  // corners examined at most; beyond, the copy is kept (safe)
    for (std::uint32_t k = 0; k < f.assumed_count; ++k) {
      // The corners of the assumed edge, or of every edge in an assumed axis plane.
      const SeamKey& key = seams.key(f.assumed_edge[k]);
      glm::vec3 ends[2];
      const bool axis = is_axis_key(key);
      if (!axis) key_corners(key, ends[0], ends[1]);
      std::uint32_t c = axis ? seams.first_axis_corner(key.bits[1]) : 0;
      for (; axis ? c != SeamTable::none : c < 2; c = axis ? seams.next_corner(c) : c + 1) {
        const glm::vec3& v = axis ? seams.corner(c) : ends[c];
        const glm::dvec3 dir = glm::dvec3(v) - eye;
        const double length = glm::length(dir);
        if (!(length > 0.0) || glm::dot(centre, dir) < reach * length) continue;
        if (--budget < 0) return false;
        const std::uint32_t count = assumptions_at(seams, f, v, other, turn, index);
        if (count < 3) continue;
        bool open = false;
        for (std::uint32_t i = 0; i < count && !open; ++i) {
          bool all_ahead = true;
          for (std::uint32_t j = 0; j < count && all_ahead; ++j)
            all_ahead = j == i || normal_turn(seams, v, other, turn, i, j) > 0;
          open = all_ahead;
        }
        if (!open) return true;
      }
    }
    return false;
  }

  // True if the convex outline `shape` (world corners, taken relative to the eye as a query starts)
  // covers an open set of directions at least `min_width` wide (radians, about): its width seen from
  // the eye, the least
  // over its edges of the farthest corner from the edge's plane through the eye (unit directions),
  // exceeds it. Dropping seam copies whose assumptions leave no open set (`assumptions_vacuous`,
  // `assumptions_miss`) is sound only for a query that is the closure of its interior: then the
  // points those copies stand for are nowhere dense in it, and the closed hidden region that holds
  // the rest holds them too. A zero-size box, a segment or a polygon seen edge-on has no interior;
  // one narrower than the margin is treated alike (its corners' rounding could decide it).
  // NaN or no edge: false (copies kept, the answer errs toward visible).
  // The answer is kept in `shape` (decided once per query).
  [[nodiscard]] static bool has_interior(const glm::vec3& eye, QueryOutline& shape, float min_width) noexcept {
    if (shape.interior < 0) shape.interior = outline_has_interior(eye, shape, min_width) ? 1 : 0;
    return shape.interior != 0;
  }

  [[nodiscard]] static bool outline_has_interior(const glm::vec3& eye, const QueryOutline& shape,
                                                 float min_width) noexcept {
    const std::uint32_t size = shape.count;
    if (size < 3 || size > ConvexPolygon::capacity) return false;
    glm::dvec3 u[ConvexPolygon::capacity];
    for (std::uint32_t i = 0; i < size; ++i) {
      const glm::dvec3 v(shape.world[i] - eye);  // as the query's first fragment has it
      const double length = glm::length(v);
      if (!(length > 0.0) || !std::isfinite(length)) return false;
      u[i] = v / length;
    }
    double width = std::numeric_limits<double>::infinity();
    bool any_edge = false;
    for (std::uint32_t i = 0; i < size; ++i) {
      const glm::dvec3 n = glm::cross(u[i], u[(i + 1) % size]);
      const double length = glm::length(n);
      if (!(length > 0.0)) continue;  // repeated corner: no edge
      double reach = 0.0;
      for (std::uint32_t j = 0; j < size; ++j) reach = std::max(reach, std::fabs(glm::dot(n, u[j])) / length);
      width = std::min(width, reach);
      any_edge = true;
    }
    return any_edge && width > double(min_width);
  }

  [[nodiscard]] static bool same_point(const glm::vec3& a, const glm::vec3& b) noexcept {
    return float_bits(a.x) == float_bits(b.x) && float_bits(a.y) == float_bits(b.y) && float_bits(a.z) == float_bits(b.z);
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
  [[nodiscard]] static Answer walk_fragments(const Tree& t, Fragment* stack, int count, float scale, bool want_clear,
                                             BoxFront* front, QueryOutline& shape) {
    const float eps = t.params_.margin;
    bool any_hidden = false, any_visible = false;
    int top = count;
    Fragment buffers[2];
    while (top > 0) {
      Fragment* cur = &buffers[0];
      Fragment* alt = &buffers[1];
      copy_fragment(stack[--top], *cur);
      for (;;) {
        const std::uint32_t ref = cur->ref;
        if (ref == hidden_leaf) {
          any_hidden = true;
          break;
        }
        if (ref == visible_leaf) {
          // A copy whose assumptions no open set of directions satisfies stands for no point that
          // another copy does not also stand for (see `assumptions_vacuous`): it proves nothing
          // either way. That needs a query with an interior: a point, a segment or a polygon seen
          // edge-on may lie wholly in such a set, and its copies are never dropped.
          if (cur->assumed_count == 0 || (!assumptions_vacuous(t.seams_, *cur) && !assumptions_miss(t.seams_, *cur)) ||
              !has_interior(t.eye_, shape, eps))
            any_visible = true;
          break;
        }
        const Node& node = t.nodes_[ref];
        const float m = eps * (scale + std::fabs(node.plane.d));
        if (front != nullptr && node.kind != NodeKind::top && node.kind != NodeKind::edge) {
          float dmin = 0.0f;
          const FrontSide side = front_side(node.plane, m, t.eye_, *front, dmin);
          if (side == FrontSide::inside) cur->ref = node.inside;
          else if (side == FrontSide::outside) cur->ref = node.outside;
          else return undecided_answer;  // the front straddles (or NaN): walk the faces instead
          continue;
        }
        if (is_shared_seam(t, node)) {
          const SeamStep step = seam_step(t.seams_, node, m, *cur, stack, top, *alt);
          if (step == SeamStep::visible) {
            any_visible = true;
            break;
          }
          if (step == SeamStep::copies) std::swap(cur, alt);
          if (step != SeamStep::ordinary) continue;
        }
        const Plane shifted{node.plane.normal, node.plane.d - m};
        // With the stack full, the inside piece has nowhere to go: a split then answers visible.
        Fragment& in_piece = top < stack_size ? stack[top] : *alt;
        FragmentSide side = classify_fragment(*cur, shifted, 0.0f);
        if (side == FragmentSide::split) side = split_fragment(*cur, shifted, 0.0f, in_piece, *alt);
        if (side == FragmentSide::inside) {
          cur->ref = node.inside;
        } else if (side == FragmentSide::outside || side == FragmentSide::on) {
          cur->ref = node.outside;
        } else if (side == FragmentSide::split && top < stack_size) {
          in_piece.ref = node.inside;
          copy_assumptions(*cur, in_piece);
          ++top;
          alt->ref = node.outside;
          copy_assumptions(*cur, *alt);
          std::swap(cur, alt);
        } else {
          any_visible = true;  // NaN, too many corners or a full stack: cannot be decided, visible
          break;
        }
      }
      if (any_visible && !want_clear) return Answer::visible;
    }
    if (any_visible) return (want_clear && !any_hidden) ? Answer::clear : Answer::visible;
    return any_hidden ? Answer::hidden : Answer::visible;
  }
};

}  // namespace cullkit::detail
