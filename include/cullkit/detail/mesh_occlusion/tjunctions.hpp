// cullkit/detail/mesh_occlusion/tjunctions.hpp: triangles cut at the corners of their neighbours
// that lie exactly on their unpaired edges (T-junctions), at build time.
//
// Why: the coverage grid fuses two triangles only along an edge they share (the same two welded
// corners). Where a long edge P-Q of triangle A meets the edges Q-M and M-P of its neighbours (a
// wall running into a slab, a panel against two smaller ones), no edge is shared: all three stay on
// the outline and the cells along the seam are never covered, though the surfaces close the seam.
// Cutting A at M into triangles whose edges are P-M and M-Q makes the seam's edges pairs again.
//
// Conservative by construction: M is taken only when it lies *exactly* on the open segment P-Q
// (exact arithmetic on the float corners; see on_open_segment), so A's parts are coplanar with A,
// have its winding, and their union is A as a point set: every ray meets the parts exactly where it
// meets A, at the same depth. The surface neither grows nor moves; per frame the parts are projected
// and rasterized like any triangle, with the margins every triangle already has. A corner that lies
// near the edge but not exactly on it (a real crack, however thin) is left alone.
//
// The parts are occluder geometry of A's object: A's slot holds its first part and the others are
// appended after the user's triangles (`origin` maps every slot to the user's triangle). Object
// bounds and solid-box marks are taken from the user's triangles before the cut; an object's
// triangle test over the parts is the test over A (same plane, same facing, same union).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// a - b for doubles holding floats; false when the difference is not exact in double (operands of
/// very different magnitude), in which case the caller must not conclude anything.
inline bool exact_difference(double a, double b, double& out) {
  const double s = a - b;
  const double bb = s - a;  // TwoSum of a and -b: the rounding error of s, exactly
  const double err = (a - (s - bb)) + (-b - bb);
  out = s;
  return err == 0.0;
}

/// True when x1 * y1 == x2 * y2 exactly (products split into a rounded value and its exact error by
/// an FMA; the pair is unique for an exact product, so equal products give equal pairs).
inline bool exact_products_equal(double x1, double y1, double x2, double y2) {
  const double p1 = x1 * y1, p2 = x2 * y2;
  if (p1 != p2) return false;
  return std::fma(x1, y1, -p1) == std::fma(x2, y2, -p2);
}

/// True only when m lies exactly on the open segment from p to q: collinear in exact arithmetic (the
/// cross product of q - p and m - p is exactly zero) and strictly between p and q. False whenever
/// exactness cannot be established.
inline bool on_open_segment(const glm::vec3& p, const glm::vec3& q, const glm::vec3& m) {
  double d[3], e[3];
  for (int a = 0; a < 3; ++a)
    if (!exact_difference(q[a], p[a], d[a]) || !exact_difference(m[a], p[a], e[a])) return false;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    if (!exact_products_equal(d[b], e[c], d[c], e[b])) return false;
  }
  // Collinear: strictly between along the axis of q - p's largest component.
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::fabs(d[a]) > std::fabs(d[axis])) axis = a;
  if (d[axis] > 0.0) return p[axis] < m[axis] && m[axis] < q[axis];
  if (d[axis] < 0.0) return q[axis] < m[axis] && m[axis] < p[axis];
  return false;
}

/// A uniform spatial hash of points: cells of side `h`, points sorted by a 64-bit hash of their cell
/// (a collision only adds candidates). `near_segment` visits every point in the cells that a segment,
/// widened by `pad`, may touch: slab by slab along its longest axis, so a long edge costs its length
/// over h, not its box's volume.
class PointGrid {
 public:
  PointGrid(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& points, double h)
      : h_(h > 0.0 && std::isfinite(h) ? h : 1.0) {
    entries_.reserve(points.size());
    for (std::uint32_t v : points) {
      const glm::vec3& p = positions[v];
      entries_.emplace_back(key(cell(p.x), cell(p.y), cell(p.z)), v);
    }
    std::sort(entries_.begin(), entries_.end());
  }

  template <class Visit>
  void near_segment(const glm::vec3& p, const glm::vec3& q, double pad, Visit&& visit) const {
    const double d[3] = {double(q.x) - p.x, double(q.y) - p.y, double(q.z) - p.z};
    int a = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(d[k]) > std::fabs(d[a])) a = k;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    // Rounding in the slab bounds below (double, about 1e-16 relative) only matters for which cells
    // are visited: widen a little.
    const double slack = pad + 1e-9 * h_ + 1e-12 * (std::fabs(double(p[a])) + std::fabs(double(p[b])) +
                                                    std::fabs(double(p[c])) + std::fabs(d[a]));
    const double lo = std::min(double(p[a]), double(q[a])) - slack, hi = std::max(double(p[a]), double(q[a])) + slack;
    const std::int64_t s0 = cell(lo), s1 = cell(hi);
    for (std::int64_t s = s0; s <= s1; ++s) {
      // The part of the segment whose coordinate a lies in slab s (the whole segment if it is a point).
      double t0 = 0.0, t1 = 1.0;
      if (d[a] != 0.0) {
        const double ta = (double(s) * h_ - slack - p[a]) / d[a], tb = (double(s + 1) * h_ + slack - p[a]) / d[a];
        t0 = std::max(0.0, std::min(ta, tb));
        t1 = std::min(1.0, std::max(ta, tb));
        if (t0 > t1) continue;
      }
      std::int64_t lo_cell[2], hi_cell[2];
      const int axes[2] = {b, c};
      for (int k = 0; k < 2; ++k) {
        const double u0 = p[axes[k]] + t0 * d[axes[k]], u1 = p[axes[k]] + t1 * d[axes[k]];
        lo_cell[k] = cell(std::min(u0, u1) - slack);
        hi_cell[k] = cell(std::max(u0, u1) + slack);
      }
      std::int64_t ijk[3];
      ijk[a] = s;
      for (std::int64_t i = lo_cell[0]; i <= hi_cell[0]; ++i)
        for (std::int64_t j = lo_cell[1]; j <= hi_cell[1]; ++j) {
          ijk[b] = i;
          ijk[c] = j;
          const std::uint64_t k = key(ijk[0], ijk[1], ijk[2]);
          auto it = std::lower_bound(entries_.begin(), entries_.end(), std::make_pair(k, std::uint32_t(0)));
          for (; it != entries_.end() && it->first == k; ++it) visit(it->second);
        }
    }
  }

 private:
  std::int64_t cell(double x) const {
    const double c = std::floor(x / h_);
    return static_cast<std::int64_t>(std::clamp(c, -1e15, 1e15));
  }
  static std::uint64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
    std::uint64_t x = std::uint64_t(i) * 0x9e3779b97f4a7c15ull ^ std::uint64_t(j) * 0xc2b2ae3d27d4eb4full ^
                      std::uint64_t(k) * 0x165667b19e3779f9ull;
    x ^= x >> 29;
    x *= 0xbf58476d1ce4e5b9ull;
    return x ^ (x >> 32);
  }
  double h_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries_;
};

/// The cell side for the unpaired edges' grid: their median length, but at least a quarter of
/// their mean, so that the slabs walked over all edges stay about four per edge.
inline double tjunction_cell_size(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& corners,
                                  const std::vector<std::uint32_t>& edges) {
  if (edges.empty()) return 1.0;
  std::vector<double> lengths;
  lengths.reserve(edges.size());
  double sum = 0.0;
  for (std::uint32_t e : edges) {
    const std::uint32_t t = e / 3, k = e % 3;
    const glm::vec3& p = positions[corners[3 * std::size_t(t) + k]];
    const glm::vec3& q = positions[corners[3 * std::size_t(t) + (k + 1) % 3]];
    const double dx = double(q.x) - p.x, dy = double(q.y) - p.y, dz = double(q.z) - p.z;
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!std::isfinite(l)) continue;
    lengths.push_back(l);
    sum += l;
  }
  if (lengths.empty()) return 1.0;
  std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(lengths.size() / 2), lengths.end());
  const double h = std::max(lengths[lengths.size() / 2], 0.25 * sum / double(lengths.size()));
  return h > 0.0 && std::isfinite(h) ? h : 1.0;
}

/// A corner found on an edge: the directed edge (3t + k), and the corner.
struct EdgePoint {
  std::uint32_t edge;
  std::uint32_t vertex;
};

/// Every (unpaired edge, corner of an unpaired edge) with the corner exactly on the edge's open
/// segment, grouped by edge and sorted along it from the edge's start; consecutive corners (and the
/// edge's ends) are at least `min_piece` of the edge's length apart along its longest axis.
/// `corners` as in the index (none for triangles that cannot occlude), `twins` from pair_edges.
inline std::vector<EdgePoint> find_tjunctions(const std::vector<glm::vec3>& positions,
                                              const std::vector<std::uint32_t>& corners,
                                              const std::vector<std::uint32_t>& twins, double min_piece) {
  constexpr std::uint32_t none = 0xffffffffu;
  std::vector<std::uint32_t> edges, points;
  for (std::size_t e = 0; e < corners.size(); ++e) {
    if (corners[e - e % 3] == none || twins[e] != none) continue;
    edges.push_back(static_cast<std::uint32_t>(e));
    points.push_back(corners[e]);
    points.push_back(corners[e - e % 3 + (e % 3 + 1) % 3]);
  }
  std::vector<EdgePoint> found;
  if (edges.empty()) return found;
  // Only ends of unpaired edges: a corner whose edges are all paired closes no seam.
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  const PointGrid grid(positions, points, tjunction_cell_size(positions, corners, edges));
  std::vector<std::uint32_t> on_edge;
  for (std::uint32_t e : edges) {
    const std::uint32_t t = e / 3, k = e % 3;
    const std::uint32_t a = corners[3 * std::size_t(t) + k], b = corners[3 * std::size_t(t) + (k + 1) % 3];
    const glm::vec3 &p = positions[a], &q = positions[b];
    on_edge.clear();
    grid.near_segment(p, q, 0.0, [&](std::uint32_t v) {
      if (v != a && v != b && on_open_segment(p, q, positions[v])) on_edge.push_back(v);
    });
    if (on_edge.empty()) continue;
    std::sort(on_edge.begin(), on_edge.end());
    on_edge.erase(std::unique(on_edge.begin(), on_edge.end()), on_edge.end());
    // Along the edge: by the coordinate of its longest axis, from p.
    int axis = 0;
    for (int c = 1; c < 3; ++c)
      if (std::fabs(double(q[c]) - p[c]) > std::fabs(double(q[axis]) - p[axis])) axis = c;
    const bool up = q[axis] > p[axis];
    std::sort(on_edge.begin(), on_edge.end(), [&](std::uint32_t u, std::uint32_t v) {
      return up ? positions[u][axis] < positions[v][axis] : positions[u][axis] > positions[v][axis];
    });
    // Pieces shorter than min_piece of the edge would make parts so thin that a frame may find them
    // edge-on and leave them out, opening the long inner edges of their neighbours: such corners
    // are left alone (their short piece of seam stays an outline).
    const double length = std::fabs(double(q[axis]) - p[axis]);
    double last = 0.0;
    for (std::size_t i = 0; i < on_edge.size(); ++i) {
      const double at = std::fabs(double(positions[on_edge[i]][axis]) - p[axis]);
      if (at - last < min_piece * length || length - at < min_piece * length) continue;
      found.push_back(EdgePoint{e, on_edge[i]});
      last = at;
    }
  }
  return found;
}

/// Cuts triangle (its corners c[0..2], and for each edge k the corners on it in order) into parts
/// whose edges along the triangle's sides are exactly the pieces between consecutive corners. Ear
/// clipping of the convex polygon: a vertex is cut off when it and its neighbours lie on no common
/// side of the triangle (then they are not collinear: a line meets a triangle's boundary in at most
/// two points or along a side) and its neighbours share no side (else the rest would be flat).
/// Appends the parts, winding as the triangle, to `out` (3 corners each); false (nothing appended)
/// when no such cut exists, which leaves the triangle whole.
inline bool cut_triangle(const std::vector<glm::vec3>& positions, const std::uint32_t c[3],
                         const std::vector<std::uint32_t> on_side[3], std::vector<std::uint32_t>& out) {
  struct Vertex {
    std::uint32_t id;
    unsigned sides;  // bit k: lies on side k (corner k -> corner k + 1)
  };
  std::vector<Vertex> poly;
  for (int k = 0; k < 3; ++k) {
    poly.push_back(Vertex{c[k], (1u << k) | (1u << ((k + 2) % 3))});
    for (std::uint32_t v : on_side[k]) poly.push_back(Vertex{v, 1u << k});
  }
  // Of the ears, the fattest (area over longest side squared) goes first: thin parts may be left
  // out by a frame that sees them nearly edge-on, and their neighbours' edges then stay outline.
  const auto fatness = [&positions](std::uint32_t a, std::uint32_t v, std::uint32_t b) {
    const glm::dvec3 pa(positions[a]), pv(positions[v]), pb(positions[b]);
    const glm::dvec3 n = glm::cross(pv - pa, pb - pa);
    const double longest = std::max({glm::dot(pv - pa, pv - pa), glm::dot(pb - pv, pb - pv), glm::dot(pa - pb, pa - pb)});
    return longest > 0.0 ? std::sqrt(glm::dot(n, n)) / longest : 0.0;
  };
  const std::size_t start = out.size();
  while (poly.size() >= 3) {
    const std::size_t n = poly.size();
    std::size_t best = n;
    double best_fatness = -1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vertex &a = poly[(i + n - 1) % n], &v = poly[i], &b = poly[(i + 1) % n];
      if ((a.sides & v.sides & b.sides) != 0) continue;
      if (n > 3 && (a.sides & b.sides) != 0) continue;
      const double f = fatness(a.id, v.id, b.id);
      if (f > best_fatness) {
        best_fatness = f;
        best = i;
      }
    }
    if (best == n) {
      out.resize(start);
      return false;
    }
    out.insert(out.end(), {poly[(best + n - 1) % n].id, poly[best].id, poly[(best + 1) % n].id});
    poly.erase(poly.begin() + std::ptrdiff_t(best));
    if (n == 3) break;
  }
  return true;
}

/// The parts of the cut triangles beyond the user's: slot user_count + i holds a part of user
/// triangle origin[i], and user triangle t's parts beyond its own slot are the slots user_count +
/// [first[t], first[t + 1]). Both empty when nothing was cut.
struct TrianglePartsMap {
  std::vector<std::uint32_t> origin;
  std::vector<std::uint32_t> first;
  /// Per slot: for a part, i such that whole_corners[3i, 3i + 3) are the cut triangle's corners;
  /// none for a triangle that was not cut. Parts are ordered by the whole triangle's nearest corner,
  /// so that they go into one depth band together, as the triangle would.
  std::vector<std::uint32_t> whole;
  std::vector<std::uint32_t> whole_corners;
  /// The user's triangle that slot u belongs to.
  std::uint32_t user_triangle(std::uint32_t u, std::size_t user_count) const {
    return u < user_count ? u : origin[u - user_count];
  }
};

/// Counts of what cut_tjunctions did.
struct TjunctionCuts {
  std::size_t corners_on_edges = 0;  ///< (unpaired edge, corner exactly on it) found
  std::size_t triangles_cut = 0;     ///< user triangles replaced by parts
  std::size_t parts_added = 0;       ///< slots appended after the user's triangles
};

/// Finds the T-junctions and cuts their triangles: each cut triangle's slot gets its first part, the
/// other parts are appended to `corners` (which then holds more slots than the user has triangles),
/// and `parts` records where they came from. The caller pairs the edges again.
inline TjunctionCuts cut_tjunctions(const std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& corners,
                                    const std::vector<std::uint32_t>& twins, TrianglePartsMap& parts,
                                    double min_piece = 0x1p-10) {
  TjunctionCuts cuts;
  parts = TrianglePartsMap{};
  const std::vector<EdgePoint> found = find_tjunctions(positions, corners, twins, min_piece);
  cuts.corners_on_edges = found.size();
  if (found.empty()) return cuts;
  const std::size_t user_count = corners.size() / 3;
  parts.first.assign(user_count + 1, 0);
  std::vector<std::uint32_t> on_side[3], pieces;
  // `found` is grouped by edge in increasing order, hence by triangle.
  for (std::size_t i = 0; i < found.size();) {
    const std::uint32_t t = found[i].edge / 3;
    for (auto& side : on_side) side.clear();
    for (; i < found.size() && found[i].edge / 3 == t; ++i) on_side[found[i].edge % 3].push_back(found[i].vertex);
    const std::uint32_t c[3] = {corners[3 * std::size_t(t)], corners[3 * std::size_t(t) + 1],
                                corners[3 * std::size_t(t) + 2]};
    pieces.clear();
    if (!cut_triangle(positions, c, on_side, pieces)) continue;
    // Edge numbers (3 slot + side) stay 32-bit, as for the user's triangles.
    if (corners.size() + pieces.size() - 3 >= std::size_t(0xffffffffu) - 3) continue;
    ++cuts.triangles_cut;
    parts.whole_corners.insert(parts.whole_corners.end(), c, c + 3);
    std::copy(pieces.begin(), pieces.begin() + 3, corners.begin() + std::ptrdiff_t(3 * std::size_t(t)));
    corners.insert(corners.end(), pieces.begin() + 3, pieces.end());
    const std::size_t added = pieces.size() / 3 - 1;
    parts.origin.insert(parts.origin.end(), added, t);
    parts.first[t + 1] = static_cast<std::uint32_t>(added);
  }
  for (std::size_t t = 0; t < user_count; ++t) parts.first[t + 1] += parts.first[t];
  cuts.parts_added = parts.origin.size();
  parts.whole.assign(corners.size() / 3, 0xffffffffu);
  std::uint32_t whole = 0;
  for (std::size_t t = 0; t < user_count; ++t) {
    // A cut triangle's slot holds a part: its corners are no longer the triangle's.
    const bool cut = parts.first[t + 1] > parts.first[t];
    if (!cut) continue;
    parts.whole[t] = whole;
    for (std::uint32_t u = parts.first[t]; u < parts.first[t + 1]; ++u) parts.whole[user_count + u] = whole;
    ++whole;
  }
  return cuts;
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
