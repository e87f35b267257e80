// cullkit/detail/occlusion/query.hpp: the query side of OcclusionTree (not public API).
//
// Query fragments are small polygons pushed down the tree. They live in a fixed local array on the
// stack of a const query, so they must cost nothing until written: the type has no member
// initializers (a stack array of 48 of them is not zeroed, unlike ConvexPolygon), and splits copy
// only the vertices in use.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "../../geometry/aabb.hpp"
#include "../../geometry/plane.hpp"

namespace cullkit::detail {

/// Seam assumptions a query fragment can carry (see seams.hpp); a fragment that has no
/// room for another one treats further seams as ordinary planes (safe, less precise).
inline constexpr std::uint32_t max_seam_assumptions = 8;

/// A convex query fragment (eye-relative vertices) and the tree slot it is about to enter.
/// Deliberately trivial: uninitialized until `size`, `assumed_count` and the vertices are written.
template <std::size_t Capacity>
struct QueryFragment {
  glm::vec3 v[Capacity];
  std::uint32_t size;
  std::uint32_t ref;  ///< node index or leaf code the fragment enters next
  /// The seams this fragment only stands for one side of: `2 * id + 1` for the positive side of
  /// seam `id`'s canonical plane, `2 * id` for the negative side.
  std::uint32_t assumed[max_seam_assumptions];
  /// The edge (seam table id) at whose node each assumption was made.
  std::uint32_t assumed_edge[max_seam_assumptions];
  std::uint32_t assumed_count;
};

/// False for NaN and for infinities (a distance that overflowed: coordinates near the float range).
[[nodiscard]] inline bool finite_distance(float d) noexcept {
  return std::fabs(d) <= std::numeric_limits<float>::max();
}

/// Where a fragment went at one plane.
enum class FragmentSide : std::uint8_t {
  inside,     ///< every vertex at distance >= -epsilon, some > epsilon
  outside,    ///< every vertex at distance <= epsilon, some < -epsilon
  on,         ///< every vertex within epsilon of the plane
  split,      ///< vertices clearly on both sides: `in` and `out` were written
  undecided,  ///< a NaN or infinite distance, or a piece would exceed the capacity (nothing written)
};

/// Classifies `src` against `plane` like `split_fragment`, without writing any piece: `split` here
/// means "straddles; call split_fragment". NaN or an infinite distance gives `undecided`. Kept small so it inlines into the
/// tree walks (most nodes only classify).
template <std::size_t Capacity>
[[nodiscard]] inline FragmentSide classify_fragment(const QueryFragment<Capacity>& src, const Plane& plane,
                                                    float epsilon) noexcept {
  bool f = false, b = false, nan = false;
  const std::uint32_t n = src.size;
  for (std::uint32_t i = 0; i < n; ++i) {
    const float d = signed_distance(plane, src.v[i]);
    f |= d > epsilon;
    b |= d < -epsilon;
    nan |= !finite_distance(d);
  }
  if (nan) return FragmentSide::undecided;
  if (f && b) return FragmentSide::split;
  return f ? FragmentSide::inside : (b ? FragmentSide::outside : FragmentSide::on);
}

/// Classifies `src` against `plane` and splits it when it straddles, with the same rule as
/// ConvexPolygon::split (so fragments and polygons are cut alike): a vertex within
/// `epsilon` of the plane is on it and goes to both pieces; `in` gets the part at distance >= 0, `out`
/// the part at distance <= 0, crossing points placed where a clearly crossing edge meets distance 0.
/// `in`/`out` may not alias `src`; their `ref` is left alone. Cost: one dot product per vertex, and a
/// copy of the vertices only when splitting.
template <std::size_t Capacity>
[[nodiscard]] inline FragmentSide split_fragment(const QueryFragment<Capacity>& src, const Plane& plane,
                                                 float epsilon, QueryFragment<Capacity>& in,
                                                 QueryFragment<Capacity>& out) noexcept {
  float dist[Capacity];
  bool f = false, b = false;
  const std::uint32_t n = src.size;
  for (std::uint32_t i = 0; i < n; ++i) {
    const float d = signed_distance(plane, src.v[i]);
    if (!finite_distance(d)) return FragmentSide::undecided;
    dist[i] = d;
    f |= d > epsilon;
    b |= d < -epsilon;
  }
  if (!(f && b)) return f ? FragmentSide::inside : (b ? FragmentSide::outside : FragmentSide::on);
  std::uint32_t ni = 0, no = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1 == n) ? 0 : i + 1;
    const float di = dist[i], dj = dist[j];
    const int si = di > epsilon ? 1 : (di < -epsilon ? -1 : 0);
    const int sj = dj > epsilon ? 1 : (dj < -epsilon ? -1 : 0);
    // Room for this vertex and a crossing point in both pieces.
    if (ni + 2 > Capacity || no + 2 > Capacity) return FragmentSide::undecided;
    if (si >= 0) in.v[ni++] = src.v[i];
    if (si <= 0) out.v[no++] = src.v[i];
    if (si * sj < 0) {
      const float t = di / (di - dj);
      const glm::vec3 p = src.v[i] + (src.v[j] - src.v[i]) * t;
      in.v[ni++] = p;
      out.v[no++] = p;
    }
  }
  in.size = ni;
  out.size = no;
  return FragmentSide::split;
}

/// Copies the seam assumptions of a fragment.
template <std::size_t Capacity>
inline void copy_assumptions(const QueryFragment<Capacity>& from, QueryFragment<Capacity>& to) noexcept {
  to.assumed_count = from.assumed_count;
  for (std::uint32_t i = 0; i < from.assumed_count; ++i) {
    to.assumed[i] = from.assumed[i];
    to.assumed_edge[i] = from.assumed_edge[i];
  }
}

/// Copies the used vertices, the size, the slot and the seam assumptions of a fragment.
template <std::size_t Capacity>
inline void copy_fragment(const QueryFragment<Capacity>& from, QueryFragment<Capacity>& to) noexcept {
  to.size = from.size;
  to.ref = from.ref;
  for (std::uint32_t i = 0; i < from.size; ++i) to.v[i] = from.v[i];
  copy_assumptions(from, to);
}

/// The box faces the eye sees (at most 3; 0 when the eye is inside or on the box), each as its four
/// corner ids (`cullkit::corner` numbering) in a cycle; winding does not matter to the tree. Shared
/// by occluder insertion and queries, so both see the same faces.
[[nodiscard]] inline int box_front_face_cycles(const Aabb& box, const glm::vec3& eye, int cycles[3][4]) noexcept {
  int nfaces = 0;
  for (int axis = 0; axis < 3; ++axis) {
    int side;  // 0: the min face is seen, 1: the max face
    if (eye[axis] < box.min[axis]) side = 0;
    else if (eye[axis] > box.max[axis]) side = 1;
    else continue;
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const int base = side << axis;
    int* c = cycles[nfaces++];
    c[0] = base;
    c[1] = base | (1 << a1);
    c[2] = base | (1 << a1) | (1 << a2);
    c[3] = base | (1 << a2);
  }
  return nfaces;
}

/// Writes the box faces the eye sees (eye-relative quads, at most 3) into `faces` and returns how many
/// (0 when the eye is inside or on the box). `faces` has room for 3.
template <std::size_t Capacity>
[[nodiscard]] inline int box_front_fragments(const Aabb& box, const glm::vec3& eye,
                                             QueryFragment<Capacity>* faces) noexcept {
  static_assert(Capacity >= 4, "cullkit: a box face needs 4 vertices");
  int cycles[3][4];
  const int nfaces = box_front_face_cycles(box, eye, cycles);
  for (int i = 0; i < nfaces; ++i) {
    QueryFragment<Capacity>& f = faces[i];
    for (int k = 0; k < 4; ++k) f.v[k] = corner(box, cycles[i][k]) - eye;
    f.size = 4;
    f.assumed_count = 0;
  }
  return nfaces;
}

/// The distinct corners of the box faces the eye sees (eye-relative) into `points` (room for 8);
/// returns how many (0 when the eye is inside or on the box).
[[nodiscard]] inline int box_front_points(const Aabb& box, const glm::vec3& eye, glm::vec3* points) noexcept {
  unsigned mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    unsigned face = 0;  // corners of the seen face on this axis
    if (eye[axis] < box.min[axis]) face = 0;
    else if (eye[axis] > box.max[axis]) face = 1;
    else continue;
    for (int c = 0; c < 8; ++c)
      if (((static_cast<unsigned>(c) >> axis) & 1u) == face) mask |= 1u << c;
  }
  int count = 0;
  for (int c = 0; c < 8; ++c)
    if (mask & (1u << c)) points[count++] = corner(box, c) - eye;
  return count;
}

}  // namespace cullkit::detail
