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
    if (corners >= 3) {
      for (std::uint32_t i = 0; i < corners; ++i) stack[0].v[i] = outline[i] - eye;
      stack[0].size = corners;
      stack[0].ref = first_split;
      stack[0].assumed_count = 0;
      result.answer = walk_fragments(t, stack, 1, scale, want_clear, &front);
      if (result.answer != undecided_answer) return result;
    }
    // Phase 3: the front faces, split at every plane they straddle.
    result.answer = Answer::visible;
    const int nfaces = box_front_fragments(box, eye, stack);
    if (nfaces == 0) return result;
    for (int f = 0; f < nfaces; ++f) stack[f].ref = first_split;
    result.answer = walk_fragments(t, stack, nfaces, scale, want_clear, nullptr);
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
    result.answer = walk_fragments(t, stack, 1, scale, want_clear, nullptr);
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
    ordinary,   // no room for another assumption: treat the node as an ordinary plane
    visible,    // cannot be decided (NaN, too many corners): the query answers visible
  };

  // One step at a node on a seam shared by several occluders (see seams.hpp). A fragment
  // that already assumed a side of this seam follows that side: every point it stands for is there.
  // Otherwise a fragment clearly on one side (by the margin) goes there; one within the margin band
  // becomes two overlapping copies, the part at distance >= -m going inside and the part at distance
  // <= m going outside, each assuming its side. Each point then has a copy on its true side, and a
  // copy meeting the other occluder's plane of the same seam keeps the band instead of losing it
  // to "visible".
  [[nodiscard]] static SeamStep seam_step(const Node& node, float m, Fragment& cur, Fragment* stack, int& top,
                                          Fragment& alt) {
    const std::uint32_t id = node.seam >> 1;
    const std::uint32_t node_side = node.seam & 1u;  // the canonical side this node's inside is
    for (std::uint32_t k = 0; k < cur.assumed_count; ++k) {
      if ((cur.assumed[k] >> 1) != id) continue;
      cur.ref = (cur.assumed[k] & 1u) == node_side ? node.inside : node.outside;
      return SeamStep::moved;
    }
    const Plane inner{node.plane.normal, node.plane.d - m};  // inside it: distance >= m
    const Plane outer{node.plane.normal, node.plane.d + m};  // outside it: distance <= -m
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
    if (cur.assumed_count >= max_seam_assumptions || top >= stack_size) return SeamStep::ordinary;
    Fragment scratch;
    Fragment& in_copy = stack[top];
    // The inside copy: the part at distance >= -m (all of it unless the fragment crosses `outer`).
    if (out_side == FragmentSide::split) {
      if (split_fragment(cur, outer, 0.0f, in_copy, scratch) != FragmentSide::split) return SeamStep::visible;
    } else {
      copy_fragment(cur, in_copy);
    }
    // The outside copy: the part at distance <= m.
    if (in_side == FragmentSide::split) {
      if (split_fragment(cur, inner, 0.0f, scratch, alt) != FragmentSide::split) return SeamStep::visible;
    } else {
      copy_fragment(cur, alt);
    }
    copy_assumptions(cur, in_copy);
    copy_assumptions(cur, alt);
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
  [[nodiscard]] static Answer walk_fragments(const Tree& t, Fragment* stack, int count, float scale, bool want_clear,
                                             BoxFront* front) {
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
