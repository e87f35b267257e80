// cullkit/geometry/convex_polygon.hpp: small fixed-capacity convex polygons, split by planes.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "plane.hpp"

namespace cullkit {

/// Which side of a plane a polygon lies on (see `BasicConvexPolygon::split`).
enum class PolygonSide : std::uint8_t {
  front,     ///< every vertex at distance >= -epsilon, some > epsilon
  back,      ///< every vertex at distance <= epsilon, some < -epsilon
  straddling,///< vertices clearly on both sides: split into two pieces
  coplanar,  ///< every vertex within epsilon of the plane
  empty,     ///< the polygon had no vertices
};

/// A planar convex polygon of at most `Capacity` vertices, stored inline (no heap).
///
/// Epsilon policy (one rule everywhere): a vertex whose signed distance lies within
/// [-epsilon, +epsilon] is *on* the plane. `split` never cuts a polygon for vertices that are only on
/// the plane; a polygon with no vertex clearly on one side is not split. Pieces are exact otherwise:
/// new vertices are placed where the edge crosses distance 0. Callers that need a conservative
/// answer shift the plane by epsilon toward the side that must not lose area (the occlusion tree does).
///
/// Overflow: a split adds at most one vertex to each piece. If a piece would exceed `Capacity`,
/// `split` reports it through `overflow()` on the piece, whose vertices then describe a *subset*
/// of the true piece. Users who must not lose area check `overflow()`.
template <std::size_t Capacity>
class BasicConvexPolygon {
  static_assert(Capacity >= 3, "cullkit: a polygon needs room for at least 3 vertices");

 public:
  static constexpr std::size_t capacity = Capacity;

  BasicConvexPolygon() noexcept = default;
  /// Copies up to `Capacity` vertices; more set `overflow()`.
  BasicConvexPolygon(const glm::vec3* vertices, std::size_t count) noexcept {
    for (std::size_t i = 0; i < count; ++i) push_back(vertices[i]);
  }

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  [[nodiscard]] bool overflow() const noexcept { return overflow_; }
  [[nodiscard]] const glm::vec3& operator[](std::size_t i) const noexcept { return v_[i]; }
  [[nodiscard]] glm::vec3& operator[](std::size_t i) noexcept { return v_[i]; }
  [[nodiscard]] const glm::vec3* data() const noexcept { return v_; }
  [[nodiscard]] const glm::vec3* begin() const noexcept { return v_; }
  [[nodiscard]] const glm::vec3* end() const noexcept { return v_ + size_; }

  void clear() noexcept { size_ = 0; overflow_ = false; }
  /// Appends a vertex; when full, sets `overflow()` and drops it.
  void push_back(const glm::vec3& p) noexcept {
    if (size_ < Capacity) v_[size_++] = p;
    else overflow_ = true;
  }

  /// Area-weighted normal (Newell's method): length is twice the area, direction follows the
  /// winding by the right-hand rule.
  [[nodiscard]] glm::vec3 normal() const noexcept {
    glm::vec3 n(0.0f);
    for (std::size_t i = 0, j = size_ ? size_ - 1 : 0; i < size_; j = i++) {
      const glm::vec3& a = v_[j];
      const glm::vec3& b = v_[i];
      n.x += (a.y - b.y) * (a.z + b.z);
      n.y += (a.z - b.z) * (a.x + b.x);
      n.z += (a.x - b.x) * (a.y + b.y);
    }
    return n;
  }
  [[nodiscard]] float area() const noexcept { return 0.5f * glm::length(normal()); }
  [[nodiscard]] glm::vec3 centroid() const noexcept {
    glm::vec3 c(0.0f);
    for (std::size_t i = 0; i < size_; ++i) c += v_[i];
    return size_ ? c / static_cast<float>(size_) : c;
  }

  /// Classifies against `plane` without splitting.
  [[nodiscard]] PolygonSide side(const Plane& plane, float epsilon) const noexcept {
    if (size_ == 0) return PolygonSide::empty;
    bool front = false, back = false;
    for (std::size_t i = 0; i < size_; ++i) {
      const float d = signed_distance(plane, v_[i]);
      front |= d > epsilon;
      back |= d < -epsilon;
      if (!(d == d)) front = back = true;  // NaN: treat as straddling, never as decided
    }
    return front ? (back ? PolygonSide::straddling : PolygonSide::front)
                 : (back ? PolygonSide::back : PolygonSide::coplanar);
  }

  /// Splits by `plane`. For `front`/`back`/`coplanar` answers the pieces are left untouched (the
  /// caller still has the whole polygon); for `straddling`, `front_piece` gets the part with
  /// distance >= 0 and `back_piece` the part with distance <= 0 (vertices within epsilon go to both).
  PolygonSide split(const Plane& plane, float epsilon, BasicConvexPolygon& front_piece,
                    BasicConvexPolygon& back_piece) const noexcept {
    float dist[Capacity];
    bool f = false, b = false;
    for (std::size_t i = 0; i < size_; ++i) {
      dist[i] = signed_distance(plane, v_[i]);
      if (!(dist[i] == dist[i])) return PolygonSide::straddling;  // NaN: no pieces made
      f |= dist[i] > epsilon;
      b |= dist[i] < -epsilon;
    }
    if (size_ == 0) return PolygonSide::empty;
    if (!(f && b)) return f ? PolygonSide::front : (b ? PolygonSide::back : PolygonSide::coplanar);
    front_piece.clear();
    back_piece.clear();
    front_piece.overflow_ = back_piece.overflow_ = overflow_;  // a partial polygon stays partial
    for (std::size_t i = 0; i < size_; ++i) {
      const std::size_t j = (i + 1 == size_) ? 0 : i + 1;
      const float di = dist[i], dj = dist[j];
      const int si = di > epsilon ? 1 : (di < -epsilon ? -1 : 0);
      const int sj = dj > epsilon ? 1 : (dj < -epsilon ? -1 : 0);
      if (si >= 0) front_piece.push_back(v_[i]);
      if (si <= 0) back_piece.push_back(v_[i]);
      if (si * sj < 0) {
        // A clear crossing: interpolate from the vertex with the larger |distance| for accuracy.
        const float t = di / (di - dj);
        const glm::vec3 p = v_[i] + (v_[j] - v_[i]) * t;
        front_piece.push_back(p);
        back_piece.push_back(p);
      }
    }
    return PolygonSide::straddling;
  }

 private:
  glm::vec3 v_[Capacity] = {};
  std::uint32_t size_ = 0;
  bool overflow_ = false;
};

/// The polygon type the occlusion tree uses: room for an occluder of up to 16 corners split a
/// further 16 times.
using ConvexPolygon = BasicConvexPolygon<32>;

}  // namespace cullkit
