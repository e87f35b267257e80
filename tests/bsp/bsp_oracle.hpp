// bsp_oracle.hpp: brute-force checks of a painter's order, shared by the BSP tests.
//
// Ray oracle: cast rays from the eye through random interior points of random fragments, collect
// every fragment the ray crosses (double precision, point-in-convex-polygon with a margin), and
// require that along each ray a nearer hit is painted later than a farther one. Hits closer than
// `tie` to each other along the ray, or within `margin` of a fragment's edge, decide nothing.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cullkit/bsp_tree.hpp>
#include <cullkit_support/scene.hpp>

namespace bsp_test {

struct OrderCheck {
  std::size_t rays = 0;
  std::size_t pairs_checked = 0;  // hit pairs with a clear depth order
  std::size_t violations = 0;     // a nearer hit painted before a farther one
};

// A fragment's plane and size, computed once per check.
struct FragmentGeometry {
  glm::dvec3 normal;  // unit, Newell's
  double size;        // largest distance from its first corner
  bool usable;
};

template <class Tree>
std::vector<FragmentGeometry> fragment_geometry(const Tree& tree) {
  std::vector<FragmentGeometry> out;
  for (const auto& frag : tree.fragments()) {
    const glm::vec3* c = tree.corners().data() + frag.first_corner;
    glm::dvec3 n(0.0);
    double size = 0;
    for (std::uint32_t i = 0; i < frag.corner_count; ++i) {
      n += glm::cross(glm::dvec3(c[i]), glm::dvec3(c[(i + 1) % frag.corner_count]));
      size = std::max(size, glm::length(glm::dvec3(c[i]) - glm::dvec3(c[0])));
    }
    const double len = glm::length(n);
    out.push_back({len > 0 ? n / len : n, size, len > 0});
  }
  return out;
}

// Distance along `dir` from `eye` to fragment f, or -1 when the ray misses it (or only grazes an
// edge: within `margin` relative to the fragment's size).
template <class Tree>
double ray_hit(const Tree& tree, const FragmentGeometry& g, std::uint32_t f, const glm::dvec3& eye,
               const glm::dvec3& dir, double margin) {
  if (!g.usable) return -1;
  const auto& frag = tree.fragments()[f];
  const glm::vec3* c = tree.corners().data() + frag.first_corner;
  const double denom = glm::dot(g.normal, dir);
  if (std::fabs(denom) < 1e-12) return -1;
  const double t = glm::dot(g.normal, glm::dvec3(c[0]) - eye) / denom;
  if (!(t > 0)) return -1;
  const glm::dvec3 p = eye + dir * t;
  for (std::uint32_t i = 0; i < frag.corner_count; ++i) {
    const glm::dvec3 a(c[i]), b(c[(i + 1) % frag.corner_count]);
    const glm::dvec3 e = b - a;
    const double el = glm::length(e);
    if (!(el > 0)) continue;
    const double inside = glm::dot(glm::cross(e, p - a), g.normal) / el;  // distance inside this edge
    if (inside < margin * g.size) return -1;
  }
  return t;
}

// Checks `order` (positions of fragments in painting order) from `eye` with `rays` rays.
template <class Tree>
OrderCheck check_order(const Tree& tree, const glm::vec3& eye_f, const std::vector<std::uint32_t>& order,
                       std::size_t rays, std::uint64_t seed, double tie = 1e-4, double margin = 1e-4) {
  OrderCheck res;
  const std::size_t nf = tree.fragments().size();
  if (nf == 0) return res;
  std::vector<std::uint32_t> pos(nf);
  for (std::size_t i = 0; i < order.size(); ++i) pos[order[i]] = static_cast<std::uint32_t>(i);
  cullkit::support::Rng rng(seed);
  const glm::dvec3 eye(eye_f);
  std::vector<std::pair<double, std::uint32_t>> hits;
  const auto geometry = fragment_geometry(tree);
  for (std::size_t r = 0; r < rays; ++r) {
    const auto f = static_cast<std::uint32_t>(rng.next() % nf);
    const auto& frag = tree.fragments()[f];
    glm::dvec3 target(0.0);
    double wsum = 0;
    for (std::uint32_t i = 0; i < frag.corner_count; ++i) {
      const double w = 0.05 + rng.uniform();
      target += w * glm::dvec3(tree.corners()[frag.first_corner + i]);
      wsum += w;
    }
    target /= wsum;
    const glm::dvec3 dir = target - eye;
    if (!(glm::length(dir) > 1e-9)) continue;
    const glm::dvec3 d = glm::normalize(dir);
    hits.clear();
    for (std::uint32_t g = 0; g < nf; ++g) {
      const double t = ray_hit(tree, geometry[g], g, eye, d, margin);
      if (t > 0) hits.push_back({t, g});
    }
    std::sort(hits.begin(), hits.end());
    ++res.rays;
    for (std::size_t i = 0; i < hits.size(); ++i) {
      for (std::size_t j = i + 1; j < hits.size(); ++j) {
        if (hits[j].first - hits[i].first <= tie * hits[j].first) continue;  // a tie decides nothing
        ++res.pairs_checked;
        if (pos[hits[i].second] < pos[hits[j].second]) ++res.violations;  // nearer painted first
      }
    }
  }
  return res;
}

// Random triangles in a cube: most of them interpenetrate others.
inline cullkit::support::Scene random_soup(std::uint64_t seed, int count, float cube, float size) {
  cullkit::support::Rng rng(seed);
  std::vector<glm::vec3> corners;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 c(rng.uniform(-cube, cube), rng.uniform(-cube, cube), rng.uniform(-cube, cube));
    for (int k = 0; k < 3; ++k)
      corners.push_back(c + glm::vec3(rng.uniform(-size, size), rng.uniform(-size, size), rng.uniform(-size, size)));
  }
  cullkit::support::Scene s;
  s.add_triangles(corners, "soup");
  return s;
}

// Three long triangles overlapping cyclically (each above the next, the last above the first as
// seen from +y): no order of whole triangles paints them right. Plus two interpenetrating pairs.
inline cullkit::support::Scene cyclic_scene() {
  std::vector<glm::vec3> c;
  for (int k = 0; k < 3; ++k) {
    const float a = 2.0943951f * float(k);
    const glm::vec3 along(std::cos(a), 0, std::sin(a));
    const glm::vec3 side(-along.z, 0, along.x);
    const glm::vec3 base = -along * 2.0f + side * 0.6f;  // offset: the three cross pairwise, not at one point
    // Rises from y=0 at one end to y=1 at the other: each passes over the next one's low end.
    c.push_back(base + side * 0.4f + glm::vec3(0, 0.2f, 0));
    c.push_back(base - side * 0.4f + glm::vec3(0, 0.2f, 0));
    c.push_back(base + along * 4.5f + glm::vec3(0, 0.8f, 0));
  }
  // Interpenetrating pair: a horizontal and a tilted triangle crossing it.
  c.push_back({3, 0.5f, 3}); c.push_back({5, 0.5f, 3}); c.push_back({4, 0.5f, 5});
  c.push_back({3.5f, 0.0f, 3.5f}); c.push_back({4.5f, 1.0f, 4.5f}); c.push_back({3.5f, 1.0f, 4.7f});
  cullkit::support::Scene s;
  s.add_triangles(c, "cyclic");
  return s;
}

// Small triangles (0.05 to 0.3 across) interpenetrating in a 4 m box far from the origin (its
// centre at (3000, 1000, -2000)): the triangles are small next to their coordinates' magnitude.
inline cullkit::support::Scene small_far_cloud(std::uint64_t seed, int count) {
  cullkit::support::Rng rng(seed);
  const glm::vec3 centre(3000.0f, 1000.0f, -2000.0f);
  std::vector<glm::vec3> corners;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 c = centre + glm::vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2));
    const float size = rng.uniform(0.05f, 0.3f);
    for (int k = 0; k < 3; ++k)
      corners.push_back(c + size * glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
  }
  cullkit::support::Scene s;
  s.add_triangles(corners, "small_far");
  return s;
}

// Slivers: long triangles (2 to 8 long) whose apex stands 1e-5 to 1e-2 of their length off the
// long edge, crossing each other and a few ordinary triangles in a 6 m box, plus one far triangle
// that makes the largest coordinate 1000 (so that a tolerance tied to it is large next to them).
inline cullkit::support::Scene sliver_soup(std::uint64_t seed, int count) {
  cullkit::support::Rng rng(seed);
  std::vector<glm::vec3> corners;
  const auto random_unit = [&rng] {
    for (;;) {
      const glm::vec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
      const float l = glm::length(v);
      if (l > 0.1f && l < 1.0f) return v / l;
    }
  };
  for (int i = 0; i < count; ++i) {
    const glm::vec3 a(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3));
    const glm::vec3 dir = random_unit();
    const float length = rng.uniform(2, 8);
    glm::vec3 up = glm::cross(dir, random_unit());
    up /= glm::length(up);
    const float thin = i % 8 == 0 ? 0.3f : std::pow(10.0f, rng.uniform(-5, -2));  // a few ordinary ones
    const glm::vec3 b = a + dir * length;
    corners.push_back(a);
    corners.push_back(b);
    corners.push_back(a + dir * (length * rng.uniform(0.2f, 0.8f)) + up * (thin * length));
  }
  corners.push_back({1000, 0, 0});
  corners.push_back({1000, 1, 0});
  corners.push_back({1000, 0, 1});
  cullkit::support::Scene s;
  s.add_triangles(corners, "slivers");
  return s;
}

// Fans of nearly coplanar triangles: each fan is a disc of `spokes` triangles around a centre whose
// rim corners leave the disc's plane by up to `bend` of its radius (a gently curved cap), and the
// fans lie in planes tilted 1e-4 to 1e-2 radians from each other through nearby centres, so they
// cross at grazing angles.
inline cullkit::support::Scene near_coplanar_fans(std::uint64_t seed, int fans, int spokes, float bend) {
  cullkit::support::Rng rng(seed);
  std::vector<glm::vec3> corners;
  for (int f = 0; f < fans; ++f) {
    const glm::vec3 centre(rng.uniform(-0.5f, 0.5f), rng.uniform(-0.02f, 0.02f), rng.uniform(-0.5f, 0.5f));
    const float tilt_x = std::pow(10.0f, rng.uniform(-4, -2)) * (rng.uniform() < 0.5f ? -1.0f : 1.0f);
    const float tilt_z = std::pow(10.0f, rng.uniform(-4, -2)) * (rng.uniform() < 0.5f ? -1.0f : 1.0f);
    const float radius = rng.uniform(0.5f, 1.5f);
    std::vector<glm::vec3> rim;
    for (int k = 0; k < spokes; ++k) {
      const float a = 6.2831853f * (float(k) + rng.uniform(-0.2f, 0.2f)) / float(spokes);
      const float x = radius * std::cos(a), z = radius * std::sin(a);
      const float y = tilt_x * x + tilt_z * z + bend * radius * rng.uniform(-1, 1);
      rim.push_back(centre + glm::vec3(x, y, z));
    }
    for (int k = 0; k < spokes; ++k) {
      corners.push_back(centre);
      corners.push_back(rim[std::size_t((k + 1) % spokes)]);
      corners.push_back(rim[std::size_t(k)]);
    }
  }
  cullkit::support::Scene s;
  s.add_triangles(corners, "fans");
  return s;
}

// `scene` with every position multiplied by `factor`.
inline cullkit::support::Scene scaled(const cullkit::support::Scene& scene, float factor, const char* name) {
  cullkit::support::Scene s;
  std::vector<glm::vec3> positions = scene.positions;
  for (glm::vec3& p : positions) p *= factor;
  s.add_mesh(positions, scene.indices, name);
  s.name = name;
  return s;
}

// Eyes that lie on the mesh: exactly on a corner of triangle `t`, at the midpoint of its first
// edge, and in its plane beyond its first edge (the node planes the walk tests them against pass
// through them, within rounding).
inline std::vector<glm::vec3> eyes_on_mesh(const cullkit::support::Scene& s, std::size_t t) {
  const glm::vec3 a = s.positions[s.indices[3 * t]], b = s.positions[s.indices[3 * t + 1]],
                  c = s.positions[s.indices[3 * t + 2]];
  const glm::vec3 mid = (a + b) * 0.5f;
  return {a, mid, mid + (mid - c) * 2.0f};
}

}  // namespace bsp_test
