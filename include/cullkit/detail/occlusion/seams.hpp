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
#include <cstring>
#include <vector>

#include <glm/vec3.hpp>

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

/// The key of the plane through the eye (origin) and the edge a-b (eye-relative corners), and
/// whether the plane's canonical normal is cross(a, b) (`forward`) or cross(b, a). For an axis
/// plane, the canonical normal is +axis and `forward` says whether cross(a, b) points that way.
[[nodiscard]] inline SeamKey seam_key(const glm::vec3& a, const glm::vec3& b, bool& forward) noexcept {
  SeamKey key{};
  for (int axis = 0; axis < 3; ++axis) {
    if (a[axis] == 0.0f && b[axis] == 0.0f) {
      // Marker words that no finite corner has (NaN patterns), then the axis.
      key.bits[0] = 0x7FC0FFEEu;
      key.bits[1] = static_cast<std::uint32_t>(axis);
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      const double along = double(a[a1]) * double(b[a2]) - double(a[a2]) * double(b[a1]);
      forward = along > 0.0;
      return key;
    }
  }
  forward = corner_before(a, b);
  const glm::vec3& lo = forward ? a : b;
  const glm::vec3& hi = forward ? b : a;
  for (int i = 0; i < 3; ++i) {
    key.bits[i] = float_bits(lo[i]);
    key.bits[3 + i] = float_bits(hi[i]);
  }
  return key;
}

/// Seam ids by key: a flat open-addressing hash table (no allocation once warm; `clear` keeps the
/// memory). Each id remembers the first occluder that used it and whether a second one did.
class SeamTable {
 public:
  static constexpr std::uint32_t none = 0xFFFFFFFFu;

  void clear() {
    std::fill(slots_.begin(), slots_.end(), none);
    owner_.clear();
    shared_.clear();
    keys_.clear();
  }

  /// The id of `key`, added if new; marks it shared when `occluder` differs from its first user.
  std::uint32_t use(const SeamKey& key, std::uint32_t occluder) {
    if (2 * (keys_.size() + 1) > slots_.size()) grow();
    const std::uint32_t mask = static_cast<std::uint32_t>(slots_.size() - 1);
    for (std::uint32_t s = hash(key) & mask;; s = (s + 1) & mask) {
      const std::uint32_t id = slots_[s];
      if (id == none) {
        slots_[s] = static_cast<std::uint32_t>(keys_.size());
        keys_.push_back(key);
        owner_.push_back(occluder);
        shared_.push_back(0);
        return slots_[s];
      }
      if (keys_[id] == key) {
        if (owner_[id] != occluder) shared_[id] = 1;
        return id;
      }
    }
  }

  /// True if two different occluders use seam `id`.
  [[nodiscard]] bool shared(std::uint32_t id) const noexcept { return id < shared_.size() && shared_[id] != 0; }

 private:
  [[nodiscard]] static std::uint32_t hash(const SeamKey& key) noexcept {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (std::uint32_t w : key.bits) h = (h ^ w) * 0xFF51AFD7ED558CCDull;
    return static_cast<std::uint32_t>(h ^ (h >> 29));
  }
  void grow() {
    const std::size_t size = slots_.empty() ? 64 : 2 * slots_.size();
    slots_.assign(size, none);
    const std::uint32_t mask = static_cast<std::uint32_t>(size - 1);
    for (std::uint32_t id = 0; id < keys_.size(); ++id) {
      std::uint32_t s = hash(keys_[id]) & mask;
      while (slots_[s] != none) s = (s + 1) & mask;
      slots_[s] = id;
    }
  }

  std::vector<std::uint32_t> slots_;  // id per slot, or none
  std::vector<SeamKey> keys_;
  std::vector<std::uint32_t> owner_;  // first occluder (insertion serial) per id
  std::vector<std::uint8_t> shared_;  // used by a second occluder
};

}  // namespace cullkit::detail
