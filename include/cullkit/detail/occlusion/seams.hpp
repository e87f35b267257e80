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
//  - the unordered pair of an edge's two corners, bit for bit (eye-relative floats; equal world
//    corners give equal eye-relative ones): the plane through the eye and those two points;
//  - an edge whose corners both have coordinate `axis` exactly equal to the eye's: the axis plane
//    through the eye (two boxes sharing a face the eye lies in the plane of).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cmath>
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

/// Edges by key, and the planes they lie in. Every distinct edge key gets an id of its own; edges that
/// span one plane through the eye (collinear edges of a regular grid, found through a shared corner
/// and an exact orientation test) are linked to one plane, its `root`, so that a query assumption
/// about one holds at all of them. Flat open-addressing tables (no allocation once warm; `clear`
/// keeps the memory). Each plane remembers the first occluder that used it and whether another did.
class SeamTable {
 public:
  static constexpr std::uint32_t none = 0xFFFFFFFFu;

  /// Empties the table for a new eye (world coordinates).
  void clear(const glm::vec3& eye) {
    eye_ = eye;
    std::fill(slots_.begin(), slots_.end(), none);
    std::fill(plane_slots_.begin(), plane_slots_.end(), none);
    keys_.clear();
    root_.clear();
    flip_.clear();
    owner_.clear();
    shared_.clear();
    plane_ids_.clear();
    first_corner_.clear();
    corner_point_.clear();
    corner_next_.clear();
  }

  /// The id of the edge (a, b) (world corners), added if new; marks its plane shared when
  /// `occluder` differs from the plane's first user.
  std::uint32_t use(const glm::vec3& a, const glm::vec3& b, std::uint32_t occluder) {
    const SeamKey key = seam_key(a, b, eye_);
    if (2 * (keys_.size() + 1) > slots_.size()) grow();
    const std::uint32_t mask = static_cast<std::uint32_t>(slots_.size() - 1);
    std::uint32_t s = hash(key.bits, 6) & mask;
    for (; slots_[s] != none; s = (s + 1) & mask) {
      const std::uint32_t id = slots_[s];
      if (keys_[id] == key) {
        mark_user(root_[id], occluder);
        if (is_axis_key(key)) {  // one key for every edge in the axis plane: keep each one's corners
          add_corner(id, a);
          add_corner(id, b);
        }
        return id;
      }
    }
    const auto id = static_cast<std::uint32_t>(keys_.size());
    slots_[s] = id;
    keys_.push_back(key);
    root_.push_back(id);
    flip_.push_back(0);
    owner_.push_back(occluder);
    shared_.push_back(0);
    first_corner_.push_back(none);
    add_corner(id, a);
    add_corner(id, b);
    if (!is_axis_key(key)) {
      link_coplanar(id, a, b);
      add_plane(id);
    }
    mark_user(root_[id], occluder);
    return id;
  }

  /// The corners of the edges in the plane of edge `id`: `first_corner(root(id))`, then
  /// `next_corner(k)` until `none`; `corner(k)` is a world point.
  [[nodiscard]] std::uint32_t first_corner(std::uint32_t root) const noexcept { return first_corner_[root]; }
  [[nodiscard]] std::uint32_t next_corner(std::uint32_t k) const noexcept { return corner_next_[k]; }
  [[nodiscard]] const glm::vec3& corner(std::uint32_t k) const noexcept { return corner_point_[k]; }

  /// The plane of edge `id` (the id of its first edge).
  [[nodiscard]] std::uint32_t root(std::uint32_t id) const noexcept { return root_[id]; }
  /// 1 if the canonical normal of edge `id` is opposite to that of its plane's root.
  [[nodiscard]] std::uint32_t flip(std::uint32_t id) const noexcept { return flip_[id]; }
  /// True if two different occluders use the plane of edge `id`.
  [[nodiscard]] bool shared(std::uint32_t id) const noexcept { return id < root_.size() && shared_[root_[id]] != 0; }
  [[nodiscard]] std::size_t size() const noexcept { return keys_.size(); }
  [[nodiscard]] const SeamKey& key(std::uint32_t id) const noexcept { return keys_[id]; }
  [[nodiscard]] const glm::vec3& eye() const noexcept { return eye_; }

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
  [[nodiscard]] static std::uint32_t hash(const std::uint32_t* words, int count) noexcept {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < count; ++i) h = (h ^ words[i]) * 0xFF51AFD7ED558CCDull;
    return static_cast<std::uint32_t>(h ^ (h >> 29));
  }
  void mark_user(std::uint32_t root, std::uint32_t occluder) {
    if (owner_[root] != occluder) shared_[root] = 1;
  }

  // Links the new edge `id` (a, b) to the plane of every earlier edge that spans the same plane
  // through the eye, exactly (the orientation test on world corners); planes found that way are
  // merged into one. Candidates come from a table of planes by their unit normal, rounded to cells
  // of 2^-23: one plane computed from two of its edges differs by far less, and where a normal lies
  // near a cell's side the neighbouring cell is searched too.
  void link_coplanar(std::uint32_t id, const glm::vec3& a, const glm::vec3& b) {
    if (plane_slots_.empty()) return;
    const glm::dvec3 normal = canonical_normal(id);
    PlaneCell cells[16];
    const int count = nearby_cells(normal, cells);
    const std::uint32_t mask = static_cast<std::uint32_t>(plane_slots_.size() - 1);
    for (int c = 0; c < count; ++c) {
      for (std::uint32_t s = hash(cells[c].bits, 3) & mask; plane_slots_[s] != none; s = (s + 1) & mask) {
        const PlaneEntry& e = plane_ids_[plane_slots_[s]];
        if (e.cell.bits[0] != cells[c].bits[0] || e.cell.bits[1] != cells[c].bits[1] ||
            e.cell.bits[2] != cells[c].bits[2])
          continue;
        const std::uint32_t other = root_[e.id];
        if (other == root_[id]) continue;
        glm::vec3 lo, hi;
        key_corners(keys_[e.id], lo, hi);
        if (orientation_sign(eye_, lo, hi, a) != 0 || orientation_sign(eye_, lo, hi, b) != 0) continue;
        // Parallel normals: the sign of their dot product is certain.
        const std::uint32_t relative = glm::dot(normal, canonical_normal(other)) < 0.0 ? 1u : 0u;
        merge(other, root_[id], relative ^ flip_[id]);
      }
    }
  }

  struct PlaneCell {
    std::uint32_t bits[3];
  };
  struct PlaneEntry {
    PlaneCell cell;
    std::uint32_t id;
  };
  static constexpr double cell_size = 1.0 / 8388608.0;  // 2^-23

  // The unit normal with its largest component made positive (`flip`: the other sign instead).
  [[nodiscard]] static glm::dvec3 signed_unit(const glm::dvec3& normal, bool flip) noexcept {
    glm::dvec3 n = normal / glm::length(normal);
    int big = 0;
    for (int i = 1; i < 3; ++i)
      if (std::fabs(n[i]) > std::fabs(n[big])) big = i;
    if ((n[big] < 0.0) != flip) n = -n;
    return n;
  }
  [[nodiscard]] static std::uint32_t cell_of(double x) noexcept {
    return static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(x / cell_size)));
  }
  [[nodiscard]] static PlaneCell cell_of(const glm::dvec3& n) noexcept {
    return PlaneCell{{cell_of(n.x), cell_of(n.y), cell_of(n.z)}};
  }

  // The cells where a plane with this normal may have been filed (up to 16).
  [[nodiscard]] static int nearby_cells(const glm::dvec3& normal, PlaneCell* out) noexcept {
    const glm::dvec3 n = signed_unit(normal, false);
    double top = 0.0, second = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double m = std::fabs(n[i]);
      if (m > top) {
        second = top;
        top = m;
      } else if (m > second) {
        second = m;
      }
    }
    const int signs = top - second < 1e-6 ? 2 : 1;  // two components nearly tie: either may be "largest"
    int count = 0;
    for (int sign = 0; sign < signs; ++sign) {
      const glm::dvec3 u = sign == 0 ? n : -n;
      std::int32_t lo[3], span[3];
      for (int i = 0; i < 3; ++i) {
        const double scaled = u[i] / cell_size;
        const double base = std::floor(scaled);
        lo[i] = static_cast<std::int32_t>(base);
        span[i] = 1;
        if (scaled - base < 0.01) {
          --lo[i];
          span[i] = 2;
        } else if (scaled - base > 0.99) {
          span[i] = 2;
        }
      }
      for (std::int32_t x = 0; x < span[0]; ++x)
        for (std::int32_t y = 0; y < span[1]; ++y)
          for (std::int32_t z = 0; z < span[2]; ++z)
            out[count++] = PlaneCell{{static_cast<std::uint32_t>(lo[0] + x), static_cast<std::uint32_t>(lo[1] + y),
                                      static_cast<std::uint32_t>(lo[2] + z)}};
    }
    return count;
  }

  // Every edge of plane `gone` joins plane `kept`; `relative` is 1 if their canonical normals are opposite.
  void merge(std::uint32_t kept, std::uint32_t gone, std::uint32_t relative) {
    const std::uint8_t was_shared = shared_[gone] != 0 || owner_[gone] != owner_[kept] ? 1 : 0;
    for (std::size_t i = 0; i < root_.size(); ++i) {
      if (root_[i] != gone) continue;
      root_[i] = kept;
      flip_[i] = static_cast<std::uint8_t>(flip_[i] ^ relative);
    }
    shared_[kept] = static_cast<std::uint8_t>(shared_[kept] | was_shared);
    // The plane's corners: kept's list, then gone's (repeats across the two do no harm).
    if (first_corner_[kept] == none) {
      first_corner_[kept] = first_corner_[gone];
    } else {
      std::uint32_t k = first_corner_[kept];
      while (corner_next_[k] != none) k = corner_next_[k];
      corner_next_[k] = first_corner_[gone];
    }
    first_corner_[gone] = none;
  }

  // Adds corner p to the list of the plane of edge `id`, unless it is there already.
  void add_corner(std::uint32_t id, const glm::vec3& p) {
    const std::uint32_t root = root_[id];
    for (std::uint32_t k = first_corner_[root]; k != none; k = corner_next_[k])
      if (float_bits(corner_point_[k].x) == float_bits(p.x) && float_bits(corner_point_[k].y) == float_bits(p.y) &&
          float_bits(corner_point_[k].z) == float_bits(p.z))
        return;
    corner_point_.push_back(p);
    corner_next_.push_back(first_corner_[root]);
    first_corner_[root] = static_cast<std::uint32_t>(corner_point_.size() - 1);
  }

  void add_plane(std::uint32_t id) {
    if (2 * (plane_ids_.size() + 1) > plane_slots_.size()) grow_planes();
    const PlaneCell cell = cell_of(signed_unit(canonical_normal(id), false));
    const std::uint32_t mask = static_cast<std::uint32_t>(plane_slots_.size() - 1);
    std::uint32_t s = hash(cell.bits, 3) & mask;
    while (plane_slots_[s] != none) s = (s + 1) & mask;
    plane_slots_[s] = static_cast<std::uint32_t>(plane_ids_.size());
    plane_ids_.push_back(PlaneEntry{cell, id});
  }

  void grow() {
    const std::size_t size = slots_.empty() ? 64 : 2 * slots_.size();
    slots_.assign(size, none);
    const std::uint32_t mask = static_cast<std::uint32_t>(size - 1);
    for (std::uint32_t id = 0; id < keys_.size(); ++id) {
      std::uint32_t s = hash(keys_[id].bits, 6) & mask;
      while (slots_[s] != none) s = (s + 1) & mask;
      slots_[s] = id;
    }
  }
  void grow_planes() {
    const std::size_t size = plane_slots_.empty() ? 128 : 2 * plane_slots_.size();
    plane_slots_.assign(size, none);
    const std::uint32_t mask = static_cast<std::uint32_t>(size - 1);
    for (std::uint32_t i = 0; i < plane_ids_.size(); ++i) {
      std::uint32_t s = hash(plane_ids_[i].cell.bits, 3) & mask;
      while (plane_slots_[s] != none) s = (s + 1) & mask;
      plane_slots_[s] = i;
    }
  }

  glm::vec3 eye_ = glm::vec3(0.0f);
  std::vector<std::uint32_t> slots_;         // edge id per slot, or none
  std::vector<SeamKey> keys_;                // per edge id
  std::vector<std::uint32_t> root_;          // per edge id: its plane (an edge id)
  std::vector<std::uint8_t> flip_;           // per edge id: canonical normal opposite to its root's
  std::vector<std::uint32_t> owner_;         // per plane: first occluder (insertion serial)
  std::vector<std::uint8_t> shared_;         // per plane: used by a second occluder
  std::vector<std::uint32_t> plane_slots_;  // index into plane_ids_ per slot, or none
  std::vector<PlaneEntry> plane_ids_;       // each edge's plane cell
  std::vector<std::uint32_t> first_corner_;  // per plane (root edge id): its corner list, or none
  std::vector<glm::vec3> corner_point_;      // corner lists: world points ...
  std::vector<std::uint32_t> corner_next_;   // ... and the next entry, or none
};

}  // namespace cullkit::detail
