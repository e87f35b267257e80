// tests/portals/box_world.hpp: the brute-force oracle for portal traversal. A world of box rooms on
// a grid whose shared faces are solid except for portal polygons; a ray is traced room by room
// (leave the room through a face; go on only if the exit point lies in a portal of that face), and
// points sampled along it are the points the portal answer must hold.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

namespace portal_test {

using namespace cullkit;

struct WorldPortal {
  std::uint32_t a = 0, b = 0;   // a is the lower room along `axis`
  int axis = 0;                 // the shared face is perpendicular to this axis
  std::vector<glm::vec3> corners;
};

/// Rooms (i, j, k) on a grid with irregular column widths; room boxes share faces exactly.
struct BoxWorld {
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> xs, ys, zs;  // grid lines
  std::vector<WorldPortal> portals;
  PortalGraph graph;

  [[nodiscard]] std::uint32_t room(int i, int j, int k) const {
    return static_cast<std::uint32_t>((k * ny + j) * nx + i);
  }
  [[nodiscard]] Aabb box(std::uint32_t r) const {
    const int i = static_cast<int>(r) % nx, j = (static_cast<int>(r) / nx) % ny, k = static_cast<int>(r) / (nx * ny);
    return Aabb{{xs[i], ys[j], zs[k]}, {xs[i + 1], ys[j + 1], zs[k + 1]}};
  }
  [[nodiscard]] std::uint32_t rooms() const { return static_cast<std::uint32_t>(nx * ny * nz); }
};

/// A random convex polygon of `n` corners inside the rectangle [u0,u1] x [v0,v1] of the plane
/// `axis` = `at`: corners on an ellipse at sorted random angles, random winding.
inline std::vector<glm::vec3> random_portal(support::Rng& rng, int axis, float at, float u0, float u1, float v0,
                                            float v1, int n) {
  const float cu = rng.uniform(u0 + 0.3f * (u1 - u0), u1 - 0.3f * (u1 - u0));
  const float cv = rng.uniform(v0 + 0.3f * (v1 - v0), v1 - 0.3f * (v1 - v0));
  const float ru = rng.uniform(0.1f, 0.29f) * (u1 - u0), rv = rng.uniform(0.1f, 0.29f) * (v1 - v0);
  std::vector<float> ang;
  for (int i = 0; i < n; ++i) ang.push_back(6.2831853f * (static_cast<float>(i) + rng.uniform(0.0f, 0.8f)) / static_cast<float>(n));
  std::vector<glm::vec3> out;
  for (float t : ang) {
    const float u = cu + ru * std::cos(t), v = cv + rv * std::sin(t);
    glm::vec3 p;
    p[axis] = at;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    out.push_back(p);
  }
  if (rng.uniform() < 0.5f) std::vector<glm::vec3>(out.rbegin(), out.rend()).swap(out);
  return out;
}

/// A rectangle portal (4 corners) covering [u0,u1] x [v0,v1] of the face.
inline std::vector<glm::vec3> rect_portal(int axis, float at, float u0, float u1, float v0, float v1) {
  std::vector<glm::vec3> out;
  const float uv[4][2] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  for (const auto& q : uv) {
    glm::vec3 p;
    p[axis] = at;
    p[(axis + 1) % 3] = q[0];
    p[(axis + 2) % 3] = q[1];
    out.push_back(p);
  }
  return out;
}

inline void add_portal(BoxWorld& w, std::uint32_t a, std::uint32_t b, int axis, std::vector<glm::vec3> corners) {
  w.graph.add_portal(a, b, corners.data(), corners.size());
  w.portals.push_back(WorldPortal{a, b, axis, std::move(corners)});
}

/// A grid world; each shared face gets a portal with probability `p_portal` (random polygon of 3
/// to 16 corners, or a door-like rectangle reaching the floor).
/// `big`: every portal is a rectangle covering 90% of its face (wide views: many paths, loops).
inline BoxWorld make_world(support::Rng& rng, int nx, int ny, int nz, float p_portal, const PortalParams& params = {},
                           bool big = false) {
  BoxWorld w;
  w.graph = PortalGraph(params);
  w.nx = nx;
  w.ny = ny;
  w.nz = nz;
  float x = 0.0f;
  for (int i = 0; i <= nx; ++i) { w.xs.push_back(x); x += rng.uniform(3.0f, 8.0f); }
  for (int j = 0; j <= ny; ++j) w.ys.push_back(3.0f * static_cast<float>(j));
  float z = 0.0f;
  for (int k = 0; k <= nz; ++k) { w.zs.push_back(z); z += rng.uniform(3.0f, 8.0f); }
  for (std::uint32_t r = 0; r < w.rooms(); ++r) {
    w.graph.add_cell();
    w.graph.set_cell_bounds(r, w.box(r));
  }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (int axis = 0; axis < 3; ++axis) {
          const int ii = i + (axis == 0), jj = j + (axis == 1), kk = k + (axis == 2);
          if (ii >= nx || jj >= ny || kk >= nz) continue;
          if (rng.uniform() >= p_portal) continue;
          const std::uint32_t a = w.room(i, j, k), b = w.room(ii, jj, kk);
          const Aabb box = w.box(a);
          const int u = (axis + 1) % 3, v = (axis + 2) % 3;
          std::vector<glm::vec3> poly;
          if (big) {
            const float du = 0.05f * (box.max[u] - box.min[u]), dv = 0.05f * (box.max[v] - box.min[v]);
            poly = rect_portal(axis, box.max[axis], box.min[u] + du, box.max[u] - du, box.min[v] + dv, box.max[v] - dv);
          } else if (axis != 1 && rng.uniform() < 0.5f) {  // a door: a rectangle standing on the floor
            const float lo = box.min[u == 1 ? v : u], hi = box.max[u == 1 ? v : u];
            const float wdt = std::min(1.0f, 0.4f * (hi - lo)), at = rng.uniform(lo + 0.1f, hi - 0.1f - wdt);
            if (u == 1) poly = rect_portal(axis, box.max[axis], box.min.y, box.min.y + 2.1f, at, at + wdt);
            else poly = rect_portal(axis, box.max[axis], at, at + wdt, box.min.y, box.min.y + 2.1f);
          } else {
            const int corners = rng.range(3, 16);  // one draw per statement: the same world on every compiler
            poly = random_portal(rng, axis, box.max[axis], box.min[u], box.max[u], box.min[v], box.max[v], corners);
          }
          add_portal(w, a, b, axis, std::move(poly));
        }
  return w;
}

/// True if `p` (on the portal's plane) lies in the convex polygon, within `tol` (inclusive).
inline bool in_portal(const WorldPortal& wp, const glm::dvec3& p, double tol) {
  const int u = (wp.axis + 1) % 3, v = (wp.axis + 2) % 3;
  const std::size_t n = wp.corners.size();
  double sign = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::dvec3 a(wp.corners[i]), b(wp.corners[(i + 1) % n]);
    const double cr = (b[u] - a[u]) * (p[v] - a[v]) - (b[v] - a[v]) * (p[u] - a[u]);
    const double len = std::hypot(b[u] - a[u], b[v] - a[v]);
    if (sign == 0.0) {
      // Orientation from the polygon's signed area.
      double area = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const glm::dvec3 c(wp.corners[k]), d(wp.corners[(k + 1) % n]);
        area += c[u] * d[v] - d[u] * c[v];
      }
      sign = area > 0.0 ? 1.0 : -1.0;
    }
    if (sign * cr < -tol * len) return false;
  }
  return true;
}

/// One traced segment: the ray is in `cell` for t in [t0, t1].
struct Segment {
  std::uint32_t cell;
  double t0, t1;
};

/// Traces the ray from `eye` (in room `start`) along `dir` through the world's portals.
inline std::vector<Segment> trace(const BoxWorld& w, std::uint32_t start, const glm::dvec3& eye, const glm::dvec3& dir) {
  std::vector<Segment> out;
  std::uint32_t cell = start;
  double t0 = 0.0;
  for (int step = 0; step < 1000; ++step) {
    const Aabb b = w.box(cell);
    double t1 = 1e30;
    int exit_axis = -1, exit_side = 0;
    for (int a = 0; a < 3; ++a) {
      if (dir[a] == 0.0) continue;
      const double bound = dir[a] > 0 ? b.max[a] : b.min[a];
      const double t = (bound - eye[a]) / dir[a];
      if (t < t1) { t1 = t; exit_axis = a; exit_side = dir[a] > 0 ? 1 : -1; }
    }
    t1 = std::max(t1, t0);
    out.push_back(Segment{cell, t0, t1});
    if (exit_axis < 0) break;
    // The neighbour across the exit face.
    const int i = static_cast<int>(cell) % w.nx, j = (static_cast<int>(cell) / w.nx) % w.ny, k = static_cast<int>(cell) / (w.nx * w.ny);
    int g[3] = {i, j, k};
    g[exit_axis] += exit_side;
    if (g[0] < 0 || g[1] < 0 || g[2] < 0 || g[0] >= w.nx || g[1] >= w.ny || g[2] >= w.nz) break;
    const std::uint32_t next = w.room(g[0], g[1], g[2]);
    const glm::dvec3 x = eye + dir * t1;
    bool through = false;
    for (const WorldPortal& p : w.portals) {
      if (!((p.a == cell && p.b == next) || (p.b == cell && p.a == next))) continue;
      if (in_portal(p, x, 0.0)) through = true;
    }
    if (!through) break;
    cell = next;
    t0 = t1;
  }
  return out;
}

/// True if some entry of `cell` holds `p`.
inline bool covered(const std::vector<PortalView>& views, std::uint32_t cell, const glm::vec3& p) {
  for (const PortalView& v : views)
    if (v.cell == cell && v.volume.contains(p)) return true;
  return false;
}

/// Strictly inside the frustum (by `margin`), so that the check does not depend on which side of a
/// frustum plane rounding puts a point.
inline bool clearly_in(const Frustum& f, const glm::dvec3& p, double margin) {
  for (int i = 0; i < Frustum::max_planes; ++i) {
    if (!f.has_plane(i)) continue;
    const Plane& q = f.plane(i);
    if (glm::dot(glm::dvec3(q.normal), p) + static_cast<double>(q.d) < margin) return false;
  }
  return true;
}

}  // namespace portal_test
