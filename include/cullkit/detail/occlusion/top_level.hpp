// cullkit/detail/occlusion/top_level.hpp: the top-level planes of OcclusionTree (not public API).
//
// Before any occluder, the tree is split around the eye by fixed planes through it (seed §3.4.3):
// azimuth wedges around `up`, then elevation bands in each wedge. Occluder chains then hang in
// small wedges, so a walk passes few chains of occluders in other directions. Plane k (k = 0..K-1)
// contains `up` and the horizontal direction at azimuth psi_k = pi k / K; its inside holds the
// azimuths in (psi_k, psi_k + pi). Plane 0 is the root; in each half the other planes' cut rays are
// sorted by k, so a balanced tree over k is built recursively without scratch memory.
// `OcclusionTopLevel<Tree>` is a template over the tree only so that this header compiles on its
// own; `OcclusionTree` is its one instantiation and befriends it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/ext/vector_double3.hpp>

#include "../../geometry/plane.hpp"
#include "geometry.hpp"

namespace cullkit::detail {

/// Builds the top-level planes of `Tree` (an OcclusionTree); see the file comment.
template <class Tree>
struct OcclusionTopLevel {
  using NodeKind = typename Tree::NodeKind;

  /// Adds the top-level nodes to the empty tree `t` and sets its root (nothing when the parameters
  /// ask for no azimuth planes).
  static void build(Tree& t) {
    const int ka = std::min(t.params_.azimuth_planes, 64);
    if (ka <= 0) return;
    glm::dvec3 up(t.params_.up);
    if (!(glm::length(up) > 0.0) || !std::isfinite(glm::length(up))) up = glm::dvec3(0, 1, 0);
    up = glm::normalize(up);
    glm::dvec3 fwd = glm::dvec3(t.params_.forward);
    fwd -= up * glm::dot(up, fwd);
    if (!(glm::length(fwd) > 1e-6) || !std::isfinite(glm::length(fwd))) {
      fwd = std::fabs(up.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
      fwd -= up * glm::dot(up, fwd);
    }
    fwd = glm::normalize(fwd);
    t.up_ = up;
    t.fwd_ = fwd;
    t.right_ = glm::cross(fwd, up);
    const double pi = 3.14159265358979323846;
    const std::uint32_t root = t.add_node(azimuth_plane(t, 0, ka), NodeKind::top, 0);
    t.root_ = root;
    const std::uint32_t first_half = build_azimuth(t, 1, ka, ka, false, 0.0, pi, 1);
    const std::uint32_t second_half = build_azimuth(t, 1, ka, ka, true, pi, 2 * pi, 1);
    t.nodes_[root].inside = first_half;
    t.nodes_[root].outside = second_half;
  }

  [[nodiscard]] static Plane azimuth_plane(const Tree& t, int k, int ka) {
    const double psi = 3.14159265358979323846 * k / ka;
    return eye_plane_from_normal(-std::sin(psi) * t.fwd_ + std::cos(psi) * t.right_);
  }

  static std::uint32_t build_azimuth(Tree& t, int lo, int hi, int ka, bool second_half, double a, double b,
                                     std::uint32_t depth) {
    if (lo >= hi) return build_elevation(t, 0.5 * (a + b), 0, t.params_.elevation_planes, depth);
    const int mid = (lo + hi) / 2;
    const double pi = 3.14159265358979323846;
    const double angle = pi * mid / ka + (second_half ? pi : 0.0);
    const std::uint32_t node = t.add_node(azimuth_plane(t, mid, ka), NodeKind::top, depth);
    const std::uint32_t below = build_azimuth(t, lo, mid, ka, second_half, a, angle, depth + 1);
    const std::uint32_t above = build_azimuth(t, mid + 1, hi, ka, second_half, angle, b, depth + 1);
    // First half: larger azimuths are inside plane k; second half: they are outside.
    t.nodes_[node].inside = second_half ? below : above;
    t.nodes_[node].outside = second_half ? above : below;
    return node;
  }

  static std::uint32_t build_elevation(Tree& t, double azimuth, int lo, int hi, std::uint32_t depth) {
    if (lo >= hi || t.params_.elevation_planes <= 0) return Tree::visible_leaf;
    const int count = t.params_.elevation_planes;
    const int mid = (lo + hi) / 2;
    const double pi = 3.14159265358979323846;
    const double theta = -0.5 * pi + pi * (mid + 1) / (count + 1);
    const glm::dvec3 h = std::cos(azimuth) * t.fwd_ + std::sin(azimuth) * t.right_;
    // Contains the horizontal direction across the wedge; inside = above elevation theta.
    const Plane p = eye_plane_from_normal(-std::sin(theta) * h + std::cos(theta) * t.up_);
    const std::uint32_t node = t.add_node(p, NodeKind::top, depth);
    const std::uint32_t below = build_elevation(t, azimuth, lo, mid, depth + 1);
    const std::uint32_t above = build_elevation(t, azimuth, mid + 1, hi, depth + 1);
    t.nodes_[node].inside = above;
    t.nodes_[node].outside = below;
    return node;
  }
};

}  // namespace cullkit::detail
