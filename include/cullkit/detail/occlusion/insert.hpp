// cullkit/detail/occlusion/insert.hpp: occluder insertion for OcclusionTree (not public API).
//
// `OcclusionInsert<Tree>` turns one occluder (a convex polygon, or a box through its outline) into
// the description of its chain (`OcclusionChain`: the whole occluder's beam planes, longest edge
// first, each with its seam code, and its closing plane(s)), then pushes the occluder down the tree,
// splitting it where it straddles a plane, growing the chain at every empty slot a fragment reaches
// and dropping fragments that reach a hidden leaf. It is a template over the tree only so that this
// header needs none of the public types (the tree names them through member aliases) and compiles
// on its own; `OcclusionTree` is its one instantiation and befriends it. Insertion mutates the tree:
// the caller needs exclusive access.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include "../../box_proxy.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/convex_polygon.hpp"
#include "../../geometry/plane.hpp"
#include "geometry.hpp"
#include "query.hpp"
#include "seams.hpp"

namespace cullkit::detail {

/// What the occluder being inserted closes its chain with: its beam planes (eye-relative, through
/// the eye) and their seam codes, its closing plane(s), and for a box its eye-relative front corners
/// (a box fragment is its outline, so planes off the eye are decided by the box's front instead).
struct OcclusionChain {
  Plane edges[ConvexPolygon::capacity] = {};               // the whole occluder's beam planes
  std::uint32_t edge_seams[ConvexPolygon::capacity] = {};  // OcclusionNode::seam of each
  std::size_t edge_count = 0;
  bool is_box = false;
  Plane closing[3] = {};
  int closing_count = 0;
  glm::vec3 box_points[8] = {};  // eye-relative front corners of a box occluder
  glm::vec3 corners[ConvexPolygon::capacity] = {};  // a polygon's corners, eye-relative as inserted
  glm::vec3 world[ConvexPolygon::capacity] = {};    // the same corners in world coordinates
  int corner_count = 0;
  int box_point_count = 0;
  float split_epsilon = 0.0f;

  /// Empties the description for the next occluder. The arrays are written before they are read (up
  /// to their counts), so only the counts are reset: no kilobyte of zeros per occluder.
  void clear() noexcept {
    edge_count = 0;
    is_box = false;
    closing_count = 0;
    box_point_count = 0;
    corner_count = 0;
    split_epsilon = 0.0f;
  }
};

/// A pending occluder fragment: `fragment.ref` is the node whose child slot it enters next
/// (OcclusionTree::whole_tree: the root slot), `inside` says which child.
template <std::size_t Capacity>
struct InsertItem {
  QueryFragment<Capacity> fragment;
  bool inside;
};

/// The eye moved into the plane of every box face it sees at a grazing angle (within 1/250 of its
/// distance to the box; see OcclusionTree::insert_box_occluder), or the eye itself.
[[nodiscard]] inline glm::vec3 grazing_view(const Aabb& box, const glm::vec3& eye) {
  const glm::vec3 gap = glm::max(glm::max(box.min - eye, eye - box.max), glm::vec3(0.0f));
  const float reach = (1.0f / 250.0f) * glm::length(gap);
  glm::vec3 view = eye;
  for (int a = 0; a < 3; ++a) {
    if (eye[a] < box.min[a] && box.min[a] - eye[a] <= reach) view[a] = box.min[a];
    if (eye[a] > box.max[a] && eye[a] - box.max[a] <= reach) view[a] = box.max[a];
  }
  return view;
}

/// The insertion side of `Tree` (an OcclusionTree); see the file comment.
template <class Tree>
struct OcclusionInsert {
  using Fragment = typename Tree::Fragment;
  using Node = typename Tree::Node;
  using NodeKind = typename Tree::NodeKind;
  static constexpr std::uint32_t hidden_leaf = Tree::hidden_leaf;
  static constexpr std::uint32_t visible_leaf = Tree::visible_leaf;
  static constexpr std::uint32_t whole_tree = Tree::whole_tree;

  /// OcclusionTree::insert_occluder without the statistics: false when the polygon was not used.
  static bool polygon(Tree& t, const glm::vec3* polygon, std::size_t count) {
    if (!t.eye_ok_ || count < 3 || polygon == nullptr) return false;
    const std::size_t n = std::min<std::size_t>(count, ConvexPolygon::capacity);
    glm::dvec3 a[ConvexPolygon::capacity];
    const glm::dvec3 e(t.eye_);
    for (std::size_t i = 0; i < n; ++i) {
      if (!finite3(polygon[i])) return false;
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
    if (!(deviation <= double(t.params_.planarity) * diameter)) return false;
    // The eye is the origin: its signed distance is d. Inside must be away from the eye.
    if (d > 0.0) {
      unit = -unit;
      d = -d;
    }
    // No area seen from the eye: the eye (nearly) in the polygon's plane.
    if (!(-d > deviation + double(t.params_.min_angle) * (glm::length(center) + diameter))) return false;
    // Behind every corner: push the plane back by the deviation (and its own rounding).
    const Plane own{glm::vec3(unit), static_cast<float>(d - deviation)};
    if (!is_valid(own)) return false;

    ConvexPolygon frag;
    float scale = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
      frag.push_back(glm::vec3(a[i]));
      scale = std::max(scale, norm1(frag[i]));
    }
    OcclusionChain& chain = t.current_;
    chain.clear();
    remember_corners(chain, frag, polygon);
    chain.edge_count = beam_edges(t, frag, polygon);
    if (chain.edge_count == 0) return false;
    chain.is_box = false;
    chain.closing[0] = own;
    chain.closing_count = 1;
    chain.split_epsilon = t.params_.margin * scale;
    insert_fragment(t, frag);
    return true;
  }

  /// OcclusionTree::insert_box_occluder(box) without the skip count: false when the box was not used
  /// (the caller counts it as skipped); a used box is counted as inserted here.
  static bool box(Tree& t, const Aabb& box) {
    if (!t.eye_ok_) return false;
    const glm::vec3& eye = t.eye_;
    glm::vec3 view = grazing_view(box, eye);
    BoxProxy proxy = make_box_proxy(box, view);
    if (!proxy.valid()) {  // the moved eye landed on the box (an eye near one of its edges)
      view = eye;
      proxy = make_box_proxy(box, eye);
    }
    if (!proxy.valid()) return false;
    ConvexPolygon frag;
    float scale = 0.0f;
    for (int i = 0; i < proxy.corner_count; ++i) {
      frag.push_back(proxy.corners[i] - eye);
      scale = std::max(scale, norm1(frag[static_cast<std::size_t>(i)]));
    }
    OcclusionChain& chain = t.current_;
    chain.clear();
    chain.edge_count = beam_edges(t, frag, proxy.corners);
    if (chain.edge_count == 0) return false;
    chain.is_box = true;
    for (int f = 0; f < proxy.face_count; ++f) {
      const Plane& p = proxy.faces[f];  // world plane, normal into the box
      const double d = double(p.d) + glm::dot(glm::dvec3(p.normal), glm::dvec3(eye));
      chain.closing[f] = Plane{p.normal, static_cast<float>(d)};
    }
    chain.closing_count = proxy.face_count;
    int cycles[3][4];
    const int face_count = box_front_face_cycles(box, view, cycles);
    unsigned corner_mask = 0;
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 4; ++k) corner_mask |= 1u << cycles[f][k];
    chain.box_point_count = 0;
    for (int c = 0; c < 8; ++c)
      if (corner_mask & (1u << c)) chain.box_points[chain.box_point_count++] = corner(box, c) - eye;
    chain.split_epsilon = t.params_.margin * scale;
    ++t.stats_.occluders_inserted;
    insert_fragment(t, frag);
    return true;
  }

  // The occluder's beam planes into the chain's edges, longest edge (in angle) first: a query passing
  // beside the occluder is most likely outside a long edge, so it leaves the chain after fewer steps.
  // (The chain's region does not depend on the order.)
  // `world` holds the outline's corners in world coordinates (the seams name edges by them).
  static std::size_t beam_edges(Tree& t, const ConvexPolygon& outline, const glm::vec3* world) {
    OcclusionChain& chain = t.current_;
    float angles[ConvexPolygon::capacity];  // 1 - cos of each edge's angle: same order as the angle
    std::uint32_t sources[ConvexPolygon::capacity];
    const std::size_t n = beam_planes(outline, t.params_.min_angle, chain.edges, angles, sources);
    ++t.occluder_serial_;
    for (std::size_t i = 0; i < n; ++i)
      chain.edge_seams[i] = edge_seam(t, chain.edges[i], world[sources[i]], world[sources[(i + 1) % n]]);
    for (std::size_t i = 1; i < n; ++i) {
      const Plane plane = chain.edges[i];
      const std::uint32_t seam = chain.edge_seams[i];
      const float angle = angles[i];
      std::size_t j = i;
      for (; j > 0 && angles[j - 1] < angle; --j) {
        chain.edges[j] = chain.edges[j - 1];
        chain.edge_seams[j] = chain.edge_seams[j - 1];
        angles[j] = angles[j - 1];
      }
      chain.edges[j] = plane;
      chain.edge_seams[j] = seam;
      angles[j] = angle;
    }
    return n;
  }

  // The seam code (OcclusionNode::seam) of the edge plane through the eye and the edge with world
  // corners a-b: its edge id, and whether the plane's normal agrees with the edge's canonical normal
  // (parallel vectors: the sign of their dot product is certain).
  static std::uint32_t edge_seam(Tree& t, const Plane& plane, const glm::vec3& a, const glm::vec3& b) {
    const std::uint32_t id = t.seams_.use(a, b, t.occluder_serial_);
    if (id >= Tree::no_seam / 2) return Tree::no_seam;
    const bool agrees = glm::dot(glm::dvec3(plane.normal), t.seams_.canonical_normal(id)) > 0.0;
    return 2 * id + (agrees ? 1u : 0u);
  }

  [[nodiscard]] static std::uint32_t slot_value(const Tree& t, std::uint32_t parent, bool inside) {
    if (parent == whole_tree) return t.root_;
    return inside ? t.nodes_[parent].inside : t.nodes_[parent].outside;
  }
  static void set_slot(Tree& t, std::uint32_t parent, bool inside, std::uint32_t value) {
    if (parent == whole_tree) t.root_ = value;
    else if (inside) t.nodes_[parent].inside = value;
    else t.nodes_[parent].outside = value;
  }
  [[nodiscard]] static std::uint32_t slot_depth(const Tree& t, std::uint32_t parent) {
    return parent == whole_tree ? 0u : t.nodes_[parent].depth + 1u;
  }

  // Pushes one occluder (its first fragment) down the tree. The work stack keeps its size (entries
  // past `top` are stale, never value-initialized again), and a split writes its inside piece straight
  // into the next stack entry, so vertices are copied only when an entry is popped.
  static void insert_fragment(Tree& t, const ConvexPolygon& first) {
    const OcclusionChain& chain = t.current_;
    auto& work = t.work_;
    std::size_t top = 0;
    if (work.empty()) work.resize(16);
    {
      Fragment& f = work[top].fragment;
      f.size = static_cast<std::uint32_t>(first.size());
      f.assumed_count = 0;
      for (std::size_t i = 0; i < first.size(); ++i) f.v[i] = first[i];
      f.ref = whole_tree;
      work[top].inside = false;
      ++top;
    }
    Fragment buffers[2];
    while (top > 0) {
      --top;
      Fragment* cur = &buffers[0];
      Fragment* alt = &buffers[1];
      copy_fragment(work[top].fragment, *cur);
      bool inside = work[top].inside;
      for (;;) {
        const std::uint32_t parent = cur->ref;
        const std::uint32_t ref = slot_value(t, parent, inside);
        if (ref == hidden_leaf) {
          ++t.stats_.fragments_hidden;
          break;
        }
        if (ref == visible_leaf) {
          grow_chain(t, parent, inside);
          break;
        }
        const Node& node = t.nodes_[ref];
        const bool through_eye = node.kind == NodeKind::top || node.kind == NodeKind::edge;
        if (!through_eye && chain.is_box) {
          // A box fragment is its outline, not a surface: against a plane off the eye it goes whole
          // to the side its surface is on (inside only if all of the box's front is behind).
          bool behind = true;
          for (int i = 0; i < chain.box_point_count; ++i)
            behind = behind && signed_distance(node.plane, chain.box_points[i]) >= 0.0f;
          cur->ref = ref;
          inside = behind;
          continue;
        }
        if (top + 1 >= work.size()) work.resize(2 * work.size());  // `node` stays valid: the node array does not move
        Fragment& in_piece = work[top].fragment;
        bool in_band = false;  // some corner within split_epsilon of the plane (polygon occluders only)
        FragmentSide side = chain.is_box ? classify_fragment(*cur, node.plane, chain.split_epsilon)
                                         : classify_with_band(*cur, node.plane, chain.split_epsilon, in_band);
        if (in_band && node.kind == NodeKind::edge &&
            (side == FragmentSide::inside || side == FragmentSide::outside) &&
            reaches_across(t, node, *cur, chain.split_epsilon, side == FragmentSide::inside)) {
          // A sliver truly across the edge's plane: each side gets the part within the band there.
          side = overlapping_pieces(*cur, node.plane, chain.split_epsilon, in_piece, *alt) ? FragmentSide::split
                                                                                            : FragmentSide::undecided;
        } else if (side == FragmentSide::split) {
          side = split_fragment(*cur, node.plane, chain.split_epsilon, in_piece, *alt);
        }
        if (side == FragmentSide::inside) {
          cur->ref = ref;
          inside = true;
        } else if (side == FragmentSide::outside) {
          cur->ref = ref;
          inside = false;
        } else if (side == FragmentSide::split) {
          if (in_piece.size < 3 || alt->size < 3) {
            ++t.stats_.fragments_degenerate;
            break;
          }
          in_piece.ref = ref;
          in_piece.assumed_count = 0;
          alt->assumed_count = 0;
          work[top].inside = true;
          ++top;
          alt->ref = ref;
          inside = false;
          std::swap(cur, alt);
        } else {
          // Coplanar with a plane through the eye (no area) or with another occluder's own plane
          // (it hides nothing more there): drop. NaN or too many corners: drop too (losing occluder
          // area is safe).
          ++t.stats_.fragments_degenerate;
          break;
        }
      }
    }
  }

  // classify_fragment, also telling whether some corner lies within `epsilon` of the plane.
  [[nodiscard]] static FragmentSide classify_with_band(const Fragment& f, const Plane& plane, float epsilon,
                                                       bool& in_band) noexcept {
    bool front = false, back = false, band = false, nan = false;
    for (std::uint32_t i = 0; i < f.size; ++i) {
      const float d = signed_distance(plane, f.v[i]);
      front |= d > epsilon;
      back |= d < -epsilon;
      band |= std::fabs(d) <= epsilon;
      nan |= !finite_distance(d);
    }
    in_band = band;
    if (nan) return FragmentSide::undecided;
    if (front && back) return FragmentSide::split;
    return front ? FragmentSide::inside : (back ? FragmentSide::outside : FragmentSide::on);
  }

  // True if a fragment that lies on one side of an edge plane (`inward`: the inside), within the band
  // of it, may reach across its true plane: a corner in the band is truly on the other side. Queries split at the true plane of a shared edge (seams.hpp) and trust
  // each side's subtree for the points truly there, so a sliver of an occluder across it (nearly
  // collinear edges of a mesh) must be found on both sides. A corner of the occluder itself is placed
  // exactly (its world corner against the plane through the eye and the edge's world corners); a
  // mesh's shared corners, and the corners of collinear edges, lie on it and reach no further.
  [[nodiscard]] static bool reaches_across(const Tree& t, const Node& node, const Fragment& f, float epsilon,
                                           bool inward) {
    const OcclusionChain& chain = t.current_;
    for (std::uint32_t i = 0; i < f.size; ++i) {
      const float d = signed_distance(node.plane, f.v[i]);
      if (inward ? !(d <= epsilon) : !(d >= -epsilon)) continue;  // clearly on the fragment's side
      if (node.seam == Tree::no_seam) return true;
      int k = 0;
      while (k < chain.corner_count && !same_corner(f.v[i], chain.corners[k])) ++k;
      int truly;
      if (k < chain.corner_count) {
        if (t.seams_.is_corner(node.seam >> 1, chain.world[k])) continue;  // a shared corner: on the plane
        truly = t.seams_.true_side(node.seam, chain.world[k]);
      } else {
        // Made by a split: placed in double precision against the true plane; a corner within
        // rounding of it (cut on a plane of the same edge) counts as on it.
        const glm::dvec3 normal = t.seams_.canonical_normal(node.seam >> 1);
        const glm::dvec3 p(f.v[i]);
        const double along = glm::dot(normal, p) / glm::length(normal);
        if (!(std::fabs(along) > 1e-6 * glm::length(p))) continue;
        truly = ((along > 0.0) == ((node.seam & 1u) != 0)) ? 1 : -1;
      }
      if (inward ? truly < 0 : truly > 0) return true;
    }
    return false;
  }

  [[nodiscard]] static bool same_corner(const glm::vec3& a, const glm::vec3& b) noexcept {
    return float_bits(a.x) == float_bits(b.x) && float_bits(a.y) == float_bits(b.y) && float_bits(a.z) == float_bits(b.z);
  }

  // The two pieces of `f` that reach the band of `plane` from either side: `in` gets the part at
  // distance >= -epsilon, `out` the part at distance <= epsilon. False when a piece has no area or
  // too many corners (the fragment is then dropped: losing occluder area is safe).
  [[nodiscard]] static bool overlapping_pieces(const Fragment& f, const Plane& plane, float epsilon, Fragment& in,
                                               Fragment& out) {
    Fragment scratch;
    const Plane inner{plane.normal, plane.d + epsilon};    // distance >= -epsilon: positive here
    const Plane outer{-plane.normal, -plane.d + epsilon};  // distance <= epsilon: positive here
    if (!keep_positive(f, inner, in, scratch) || !keep_positive(f, outer, out, scratch)) return false;
    return in.size >= 3 && out.size >= 3;
  }

  // The part of `f` at distance >= 0 from `plane`, into `out`.
  [[nodiscard]] static bool keep_positive(const Fragment& f, const Plane& plane, Fragment& out, Fragment& scratch) {
    const FragmentSide side = split_fragment(f, plane, 0.0f, out, scratch);
    if (side == FragmentSide::split) return true;
    if (side != FragmentSide::inside && side != FragmentSide::on) return false;
    out.size = f.size;
    for (std::uint32_t i = 0; i < f.size; ++i) out.v[i] = f.v[i];
    return true;
  }

  static void remember_corners(OcclusionChain& chain, const ConvexPolygon& outline, const glm::vec3* world) {
    chain.corner_count = static_cast<int>(outline.size());
    for (std::size_t i = 0; i < outline.size(); ++i) {
      chain.corners[i] = outline[i];
      chain.world[i] = world[i];
    }
  }

  // The chain of a fragment is the beam of the WHOLE occluder (its original edges, not the cut
  // edges of the fragment), closed by its own plane(s). Its region is then truly hidden on its own,
  // wherever it hangs in the tree, and two fragments of one occluder leave no seam between them:
  // a query piece sent across a cut plane within the margin still meets the same beam.
  static void grow_chain(Tree& t, std::uint32_t parent, bool inside) {
    const OcclusionChain& chain = t.current_;
    const std::size_t n = chain.edge_count;
    const Plane* edges = chain.edges;
    ++t.stats_.fragments;
    std::uint32_t depth = slot_depth(t, parent);
    const auto first = static_cast<std::uint32_t>(t.nodes_.size());
    std::uint32_t previous = whole_tree;
    const auto link = [&](std::uint32_t node) {
      if (previous != whole_tree) t.nodes_[previous].inside = node;
      previous = node;
    };
    for (std::size_t i = 0; i < n; ++i) link(t.add_node(edges[i], NodeKind::edge, depth++, chain.edge_seams[i]));
    const NodeKind closing_kind = chain.is_box ? NodeKind::box_face : NodeKind::polygon;
    for (int f = 0; f < chain.closing_count; ++f) link(t.add_node(chain.closing[f], closing_kind, depth++));
    t.nodes_[previous].inside = hidden_leaf;
    set_slot(t, parent, inside, first);
    t.stats_.nodes = static_cast<std::uint32_t>(t.nodes_.size());
  }
};

}  // namespace cullkit::detail
