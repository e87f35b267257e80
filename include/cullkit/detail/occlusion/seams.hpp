// cullkit/detail/occlusion/seams.hpp: shared edges of occluders ("seams") for OcclusionTree (not
// public API).
//
// Two occluders that meet along an edge (two triangles of one mesh, two faces of one box, two boxes
// whose shared face the eye sees edge-on) each bound their hidden region by a plane through the eye
// and that edge. Both planes are the same true plane; only their rounding differs. A query piece
// within the rounding margin of that plane cannot be proven to lie on either side, so taken one plane
// at a time it is "visible" to both occluders and the pair hides nothing along the seam. The tree
// therefore gives every edge plane a seam id that names its true plane exactly; the query may then
// split a piece into two overlapping copies, each carrying the assumption "I only stand for the
// points on this side of seam k", and wherever it meets seam k again it follows that assumption
// instead of measuring. Every point has a copy on its true side, so the answer stays conservative.
//
// A seam id is valid only if it names one true plane exactly, so ids come from exact data:
//  - the unordered pair of an edge's two world corners, bit for bit: the plane through the eye and
//    those two points (world corners, not eye-relative ones: their rounding would break the
//    collinearity of a regular grid's diagonals);
//  - an edge whose corners both have coordinate `axis` exactly equal to the eye's: the axis plane
//    through the eye (two boxes sharing a face the eye lies in the plane of).
// Distinct keys can still name one plane (collinear edges); `SeamTable::coplanar` decides that
// exactly when a query needs it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include "exact_orientation.hpp"

namespace cullkit::detail {

/// Exact identity of an edge plane through the eye (see the file comment).
struct SeamKey {
  std::uint32_t bits[6];
  [[nodiscard]] bool operator==(const SeamKey& o) const noexcept {
    for (int i = 0; i < 6; ++i)
      if (bits[i] != o.bits[i]) return false;
    return true;
  }
};

[[nodiscard]] inline std::uint32_t float_bits(float f) noexcept {
  if (f == 0.0f) f = 0.0f;  // -0 and +0 are one point
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

/// True if `a` comes before `b` in the canonical (lexicographic, bitwise) order of edge corners.
[[nodiscard]] inline bool corner_before(const glm::vec3& a, const glm::vec3& b) noexcept {
  for (int i = 0; i < 3; ++i) {
    const std::uint32_t x = float_bits(a[i]), y = float_bits(b[i]);
    if (x != y) return x < y;
  }
  return false;
}

/// The key of the edge a-b (world corners) whose plane passes through `eye`: its two corners in
/// canonical order, or, for an edge whose corners both have coordinate `axis` exactly equal to the
/// eye's, the axis plane through the eye.
[[nodiscard]] inline SeamKey seam_key(const glm::vec3& a, const glm::vec3& b, const glm::vec3& eye) noexcept {
  SeamKey key{};
  for (int axis = 0; axis < 3; ++axis) {
    if (a[axis] == eye[axis] && b[axis] == eye[axis]) {
      // Marker words that no finite corner has (NaN patterns), then the axis.
      key.bits[0] = 0x7FC0FFEEu;
      key.bits[1] = static_cast<std::uint32_t>(axis);
      return key;
    }
  }
  const bool forward = corner_before(a, b);
  const glm::vec3& lo = forward ? a : b;
  const glm::vec3& hi = forward ? b : a;
  for (int i = 0; i < 3; ++i) {
    key.bits[i] = float_bits(lo[i]);
    key.bits[3 + i] = float_bits(hi[i]);
  }
  return key;
}

/// The corners of an edge key (world; meaningless for an axis-plane key).
inline void key_corners(const SeamKey& key, glm::vec3& lo, glm::vec3& hi) noexcept {
  float f[6];
  std::memcpy(f, key.bits, sizeof f);
  lo = glm::vec3(f[0], f[1], f[2]);
  hi = glm::vec3(f[3], f[4], f[5]);
}

[[nodiscard]] inline bool is_axis_key(const SeamKey& key) noexcept { return key.bits[0] == 0x7FC0FFEEu; }

/// Edges by key (no allocation once warm; `clear` keeps the memory). Each edge id remembers the first
/// occluder that used it and whether another did. Edges of one axis plane through the eye share one
/// key; the table keeps the corners of all of them (the corners a query may meet in that plane).
/// Distinct keys may still span one plane (collinear edges): queries find that out when it matters,
/// with `coplanar`.
class SeamTable {
 public:
  static constexpr std::uint32_t none = 0xFFFFFFFFu;

  /// Empties the table for a new eye (world coordinates).
  void clear(const glm::vec3& eye) {
    eye_ = eye;
    std::fill(slots_.begin(), slots_.end(), none);
    keys_.clear();
    unit_normal_.clear();
    owner_.clear();
    shared_.clear();
    for (std::uint32_t& first : axis_corners_) first = none;
    corner_point_.clear();
    corner_next_.clear();
  }

  /// The id of the edge (a, b) (world corners), added if new; marks it shared when `occluder` differs
  /// from its first user.
  std::uint32_t use(const glm::vec3& a, const glm::vec3& b, std::uint32_t occluder) {
    const SeamKey key = seam_key(a, b, eye_);
    if (is_axis_key(key)) {
      add_axis_corner(key.bits[1], a);
      add_axis_corner(key.bits[1], b);
    }
    if (2 * (keys_.size() + 1) > slots_.size()) grow();
    const std::uint32_t mask = static_cast<std::uint32_t>(slots_.size() - 1);
    std::uint32_t s = hash(key.bits) & mask;
    for (; slots_[s] != none; s = (s + 1) & mask) {
      const std::uint32_t id = slots_[s];
      if (keys_[id] == key) {
        if (owner_[id] != occluder && shared_[id] == 0) {
          shared_[id] = 1;
          unit_normal_[id] = true_unit_normal(id);  // only shared edges make copies
        }
        return id;
      }
    }
    const auto id = static_cast<std::uint32_t>(keys_.size());
    slots_[s] = id;
    keys_.push_back(key);
    owner_.push_back(occluder);
    shared_.push_back(0);
    unit_normal_.push_back(glm::vec3(0.0f));
    return id;
  }

  /// True if two different occluders use edge `id`.
  [[nodiscard]] bool shared(std::uint32_t id) const noexcept { return id < shared_.size() && shared_[id] != 0; }
  [[nodiscard]] const SeamKey& key(std::uint32_t id) const noexcept { return keys_[id]; }
  [[nodiscard]] const glm::vec3& eye() const noexcept { return eye_; }

  /// The corners of the edges in the axis plane `axis` through the eye: `first_axis_corner(axis)`,
  /// then `next_corner(k)` until `none`; `corner(k)` is a world point.
  [[nodiscard]] std::uint32_t first_axis_corner(std::uint32_t axis) const noexcept { return axis_corners_[axis]; }
  [[nodiscard]] std::uint32_t next_corner(std::uint32_t k) const noexcept { return corner_next_[k]; }
  [[nodiscard]] const glm::vec3& corner(std::uint32_t k) const noexcept { return corner_point_[k]; }

  /// True if edges `i` and `j` lie in one plane through the eye, exactly; `opposite` then says
  /// whether their canonical normals point opposite ways.
  [[nodiscard]] bool coplanar(std::uint32_t i, std::uint32_t j, bool& opposite) const noexcept {
    const SeamKey& ki = keys_[i];
    const SeamKey& kj = keys_[j];
    if (is_axis_key(ki) || is_axis_key(kj)) return false;  // one axis plane has one key
    // Shared edges have their planes' unit normals, within float rounding (about 1e-7) of the true
    // ones: normals more than 1e-4 radians apart (sines) need no exact test.
    const glm::vec3& ni = unit_normal_[i];
    const glm::vec3& nj = unit_normal_[j];
    if (ni != glm::vec3(0.0f) && nj != glm::vec3(0.0f)) {
      const glm::vec3 turn = glm::cross(ni, nj);
      if (glm::dot(turn, turn) > 1e-8f) return false;
    }
    glm::vec3 lo, hi, a, b;
    key_corners(ki, lo, hi);
    key_corners(kj, a, b);
    if (orientation_sign(eye_, lo, hi, a) != 0 || orientation_sign(eye_, lo, hi, b) != 0) return false;
    opposite = glm::dot(canonical_normal(i), canonical_normal(j)) < 0.0;  // parallel: the sign is certain
    return true;
  }

  /// True if world point `p` is, bit for bit, a corner of edge `id` (then it lies on its plane).
  [[nodiscard]] bool is_corner(std::uint32_t id, const glm::vec3& p) const noexcept {
    const SeamKey& key = keys_[id];
    if (is_axis_key(key)) return false;
    const std::uint32_t x = float_bits(p.x), y = float_bits(p.y), z = float_bits(p.z);
    return (key.bits[0] == x && key.bits[1] == y && key.bits[2] == z) ||
           (key.bits[3] == x && key.bits[4] == y && key.bits[5] == z);
  }

  /// The exact side of world point `p` of the true plane of the edge plane with seam code `code`
  /// (OcclusionNode::seam): 1 on its inside, -1 on its outside, 0 on the plane.
  [[nodiscard]] int true_side(std::uint32_t code, const glm::vec3& p) const noexcept {
    const SeamKey& key = keys_[code >> 1];
    int along;  // the side of the edge's canonical normal
    if (is_axis_key(key)) {
      const int axis = static_cast<int>(key.bits[1]);
      along = p[axis] > eye_[axis] ? 1 : (p[axis] < eye_[axis] ? -1 : 0);
    } else {
      glm::vec3 lo, hi;
      key_corners(key, lo, hi);
      along = orientation_sign(eye_, lo, hi, p);  // the sign of dot(cross(lo - eye, hi - eye), p - eye)
    }
    return (code & 1u) ? along : -along;
  }

  /// The true plane of shared edge `id` through the eye as a unit normal rounded once to float (the
  /// canonical side positive); zero when the eye and the edge's corners are collinear, or the edge is
  /// not shared. Its distances are within float rounding of the true ones everywhere, unlike those of
  /// an edge node's plane, which is built from eye-relative corners rounded to float: for a short edge
  /// far away, rounding that differs between its two corners turns that plane about the edge's
  /// midpoint, by the rounding over the edge's length, so far along the edge's line the two planes
  /// part by more than a query's margin.
  [[nodiscard]] const glm::vec3& unit_normal(std::uint32_t id) const noexcept { return unit_normal_[id]; }

  /// The canonical normal of edge `id`: cross(lo - eye, hi - eye) of its corners in canonical order,
  /// or +axis for an axis-plane key. An edge plane's `inside` is the canonical side when its normal
  /// agrees.
  [[nodiscard]] glm::dvec3 canonical_normal(std::uint32_t id) const noexcept {
    const SeamKey& key = keys_[id];
    if (is_axis_key(key)) {
      glm::dvec3 n(0.0);
      n[static_cast<int>(key.bits[1])] = 1.0;
      return n;
    }
    glm::vec3 lo, hi;
    key_corners(key, lo, hi);
    const glm::dvec3 e(eye_);
    return glm::cross(glm::dvec3(lo) - e, glm::dvec3(hi) - e);
  }

 private:
  [[nodiscard]] static std::uint32_t hash(const std::uint32_t* words) noexcept {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < 6; ++i) h = (h ^ words[i]) * 0xFF51AFD7ED558CCDull;
    return static_cast<std::uint32_t>(h ^ (h >> 29));
  }

  [[nodiscard]] glm::vec3 true_unit_normal(std::uint32_t id) const noexcept {
    const glm::dvec3 normal = canonical_normal(id);
    const double length = glm::length(normal);
    return length > 0.0 && std::isfinite(length) ? glm::vec3(normal / length) : glm::vec3(0.0f);
  }

  // Adds corner p to the list of axis plane `axis`, unless it is there already.
  void add_axis_corner(std::uint32_t axis, const glm::vec3& p) {
    for (std::uint32_t k = axis_corners_[axis]; k != none; k = corner_next_[k])
      if (float_bits(corner_point_[k].x) == float_bits(p.x) && float_bits(corner_point_[k].y) == float_bits(p.y) &&
          float_bits(corner_point_[k].z) == float_bits(p.z))
        return;
    corner_point_.push_back(p);
    corner_next_.push_back(axis_corners_[axis]);
    axis_corners_[axis] = static_cast<std::uint32_t>(corner_point_.size() - 1);
  }

  void grow() {
    const std::size_t size = slots_.empty() ? 64 : 2 * slots_.size();
    slots_.assign(size, none);
    const std::uint32_t mask = static_cast<std::uint32_t>(size - 1);
    for (std::uint32_t id = 0; id < keys_.size(); ++id) {
      std::uint32_t s = hash(keys_[id].bits) & mask;
      while (slots_[s] != none) s = (s + 1) & mask;
      slots_[s] = id;
    }
  }

  glm::vec3 eye_ = glm::vec3(0.0f);
  std::vector<std::uint32_t> slots_;      // edge id per slot, or none
  std::vector<SeamKey> keys_;             // per edge id
  std::vector<glm::vec3> unit_normal_;    // per edge id: its true plane once shared (unit_normal)
  std::vector<std::uint32_t> owner_;      // per edge id: first occluder (insertion serial)
  std::vector<std::uint8_t> shared_;      // per edge id: used by a second occluder
  std::uint32_t axis_corners_[3] = {none, none, none};  // per axis plane: its corner list, or none
  std::vector<glm::vec3> corner_point_;   // corner lists: world points ...
  std::vector<std::uint32_t> corner_next_;  // ... and the next entry, or none
};

}  // namespace cullkit::detail
