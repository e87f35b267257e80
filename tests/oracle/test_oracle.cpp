// The Embree oracle against things whose answer is known exactly: a quad filling the view, the same
// quad wound the other way, an edge-on triangle, an empty scene, a box from outside and inside, bad
// triangles, and a small random scene against a brute-force double-precision ray-triangle loop.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

using namespace cullkit;
using oracle::EmbreeScene;
using oracle::HitBuffer;

namespace {

int count_hits(const HitBuffer& h) {
  int n = 0;
  for (auto t : h.triangle) n += t != HitBuffer::miss;
  return n;
}

// A 200 x 200 quad in the plane z = 0, counter-clockwise seen from +z (or from -z if `flip`).
void add_quad(EmbreeScene& s, bool flip, bool two_sided) {
  const glm::vec3 p[4] = {{-100, -100, 0}, {100, -100, 0}, {100, 100, 0}, {-100, 100, 0}};
  const std::uint32_t ccw[6] = {0, 1, 2, 0, 2, 3};
  const std::uint32_t cw[6] = {0, 2, 1, 0, 3, 2};
  s.add_mesh(p, 4, flip ? cw : ccw, 6, two_sided);
}

void test_quad() {
  const Camera cam = support::make_camera({0.3f, -0.2f, 5}, {0.1f, 0.2f, 0}, 60, 64, 48, 0.1f, 100);
  const PixelRays rays(cam);
  {
    EmbreeScene s;
    add_quad(s, false, false);
    s.commit();
    CHECK(s.triangle_count() == 2);
    const HitBuffer h = s.render(cam, 2);
    CHECK(h.width == 64 && h.height == 48);
    int bad_dist = 0;
    for (int y = 0; y < h.height; ++y)
      for (int x = 0; x < h.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * h.width + x;
        CHECK_MSG(h.triangle[i] < 2, "quad missed at pixel (%d, %d)", x, y);
        const Ray r = rays.ray(x, y);
        const double t = -double(r.origin.z) / double(r.direction.z);
        if (!(std::fabs(h.distance[i] - t) <= 1e-5 * t)) ++bad_dist;
      }
    CHECK_MSG(bad_dist == 0, "%d pixels with a wrong distance", bad_dist);
  }
  {  // Wound the other way: seen from the back, never hit...
    EmbreeScene s;
    add_quad(s, true, false);
    s.commit();
    const HitBuffer h = s.render(cam, 3);
    CHECK_MSG(count_hits(h) == 0, "back-facing quad hit at %d pixels (Embree Ng sign wrong?)", count_hits(h));
    for (float d : h.distance) CHECK(std::isinf(d));
  }
  {  // ...unless two-sided.
    EmbreeScene s;
    add_quad(s, true, true);
    s.commit();
    CHECK(count_hits(s.render(cam, 1)) == 64 * 48);
  }
  {  // Seen from behind (eye at -z), the front-wound quad is a back face and the flipped one a front face.
    const Camera back = support::make_camera({0, 0, -5}, {0, 0, 0}, 60, 32, 32, 0.1f, 100);
    EmbreeScene a, b;
    add_quad(a, false, false);
    add_quad(b, true, false);
    a.commit();
    b.commit();
    CHECK(count_hits(a.render(back)) == 0);
    CHECK(count_hits(b.render(back)) == 32 * 32);
  }
}

void test_edge_on() {
  // Triangles whose plane passes through the eye: every ray from the eye either lies in the plane or
  // leaves it at the eye, which is outside the triangle, so no ray can hit them.
  const Camera cam = support::make_camera({0, 0, 5}, {0, 0, 0}, 60, 63, 47, 0.1f, 100);
  const glm::vec3 flat[3] = {{-2, 0, 0}, {2, 0, 0}, {0, 0, -3}};        // plane y = 0
  const glm::vec3 tilted[3] = {{1, -1, 0}, {-1, 1, 0}, {0, 0, -2}};     // plane x + y = 0
  const std::uint32_t fwd[3] = {0, 1, 2}, rev[3] = {0, 2, 1};
  for (const glm::vec3* tri : {flat, tilted})
    for (const std::uint32_t* idx : {fwd, rev}) {
      EmbreeScene s;
      s.add_mesh(tri, 3, idx, 3, false);
      s.commit();
      CHECK_MSG(count_hits(s.render(cam)) == 0, "edge-on triangle hit at %d pixels", count_hits(s.render(cam)));
    }
}

void test_empty_and_bad() {
  const Camera cam = support::make_camera({0, 0, 5}, {0, 0, 0}, 60, 20, 10, 0.1f, 100);
  {
    EmbreeScene s;
    s.commit();
    const HitBuffer h = s.render(cam);
    CHECK(s.triangle_count() == 0);
    CHECK(count_hits(h) == 0);
    CHECK(oracle::visible_triangles(h).empty());
    CHECK(s.first_hit(Ray{{0, 0, 5}, {0, 0, -1}}) == HitBuffer::miss);
  }
  {  // Empty meshes add nothing; zero-size cameras give empty buffers.
    EmbreeScene s;
    CHECK(s.add_mesh(nullptr, 0, nullptr, 0) == 0);
    s.commit();
    Camera z = cam;
    z.width = 0;
    const HitBuffer h = s.render(z);
    CHECK(h.triangle.empty() && h.distance.empty());
  }
  {  // Bad triangles in front of a good quad: out-of-range index, NaN and inf corners. Never hit.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const glm::vec3 p[5] = {{-50, -50, 1}, {50, -50, 1}, {50, 50, 1}, {nan, 0, 1}, {0, inf, 1}};
    const std::uint32_t idx[12] = {0, 1, 99, 0, 1, 3, 4, 0, 1, 2, 4, 0};
    EmbreeScene s;
    CHECK(s.add_mesh(p, 5, idx, 12) == 0);
    CHECK(s.add_mesh(nullptr, 0, idx, 3) == 4);  // no vertices at all: one degenerate triangle
    add_quad(s, false, false);
    s.commit();
    CHECK(s.triangle_count() == 7);
    const HitBuffer h = s.render(cam);
    CHECK(count_hits(h) == 200);
    for (auto t : h.triangle) CHECK(t == 5 || t == 6);
    // A ray with a zero or NaN direction hits nothing.
    CHECK(s.first_hit(Ray{{0, 0, 5}, {0, 0, 0}}) == HitBuffer::miss);
    CHECK(s.first_hit(Ray{{0, 0, 5}, {nan, 0, -1}}) == HitBuffer::miss);
    float d = 0;
    CHECK(s.first_hit(Ray{{0, 0, 5}, {0, 0, -1}}, &d) >= 5);
    CHECK_NEAR(d, 5.0, 1e-5);
    CHECK(s.first_hit(Ray{{0, 0, 5}, {0, 0, -1}}, &d, 4.0f) == HitBuffer::miss);
  }
}

// Double-precision slab test: entry and exit t of a ray against a box.
bool slab(const Ray& r, const Aabb& b, double& t0, double& t1) {
  t0 = 0.0;
  t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double o = r.origin[a], d = r.direction[a];
    if (d == 0.0) {
      if (o < b.min[a] || o > b.max[a]) return false;
      continue;
    }
    double ta = (b.min[a] - o) / d, tb = (b.max[a] - o) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

void test_box() {
  const Aabb box{{-1, -2, -1.5f}, {2, 1, 0.5f}};
  const glm::vec3 eyes[] = {{6, 4, 7}, {-7, 0.5f, 0.2f}, {0.3f, 9, -0.4f}, {-5, -6, -8}, {1, -0.5f, 6}, {9, 9, 9}};
  int margin_skipped = 0;
  for (const glm::vec3& eye : eyes) {
    EmbreeScene s;
    s.add_mesh(nullptr, 0, nullptr, 0);
    const std::uint32_t first = s.add_box(box);
    s.commit();
    CHECK(first == 0 && s.triangle_count() == 12);
    const Camera cam = support::make_camera(eye, box.center(), 50, 80, 60, 0.1f, 100);
    const PixelRays rays(cam);
    const HitBuffer h = s.render(cam);
    int hits = 0, wrong = 0;
    for (int y = 0; y < h.height; ++y)
      for (int x = 0; x < h.width; ++x) {
        const Ray r = rays.ray(x, y);
        double t0, t1;
        const bool in = slab(r, box, t0, t1);
        const std::uint32_t id = h.at(x, y);
        if (in && t1 - t0 < 1e-4) {  // grazing a corner or edge: either answer is fine
          ++margin_skipped;
          continue;
        }
        hits += id != HitBuffer::miss;
        if (in != (id != HitBuffer::miss)) ++wrong;
        if (in && id != HitBuffer::miss && !(std::fabs(h.distance[static_cast<std::size_t>(y) * h.width + x] - t0) < 1e-4 * t0))
          ++wrong;
      }
    CHECK_MSG(wrong == 0, "box from (%g %g %g): %d pixels disagree with the slab test", eye.x, eye.y, eye.z, wrong);
    CHECK_MSG(hits > 150, "box from (%g %g %g): only %d hits", eye.x, eye.y, eye.z, hits);
    for (auto t : h.triangle) CHECK(t == HitBuffer::miss || t < 12);
  }
  CHECK(margin_skipped < 200);
  {  // From inside the box every face is a back face.
    EmbreeScene s;
    s.add_box(box);
    s.commit();
    CHECK(count_hits(s.render(support::make_camera({0.5f, -0.5f, 0}, {3, 1, 2}, 90, 40, 40, 0.01f, 100))) == 0);
  }
}

// Brute force: double precision Möller–Trumbore, front faces only (det > 0 with the CCW normal
// facing the ray). Returns the nearest hit and how close that hit came to an edge of its triangle
// (smallest barycentric coordinate, 0 when exactly on an edge).
struct Brute {
  std::uint32_t id = HitBuffer::miss;
  double t = std::numeric_limits<double>::infinity();
  double edge = 1.0;        // barycentric margin of the winning hit
  double near_miss = 1.0;   // smallest |barycentric| among front-facing triangles just missed
  double second_t = std::numeric_limits<double>::infinity();
};

Brute brute_force(const std::vector<glm::vec3>& p, const std::vector<std::uint32_t>& idx, const Ray& r) {
  Brute b;
  const glm::dvec3 o(r.origin), d(r.direction);
  for (std::size_t k = 0; k < idx.size() / 3; ++k) {
    const glm::dvec3 a(p[idx[3 * k]]), bb(p[idx[3 * k + 1]]), c(p[idx[3 * k + 2]]);
    const glm::dvec3 e1 = bb - a, e2 = c - a;
    const glm::dvec3 pv = glm::cross(d, e2);
    const double det = glm::dot(e1, pv);
    // Front face: the CCW normal e1 x e2 points against the ray, which is det > 0 here.
    if (!(det > 0.0)) continue;
    const glm::dvec3 tv = o - a;
    const double u = glm::dot(tv, pv) / det;
    const glm::dvec3 qv = glm::cross(tv, e1);
    const double v = glm::dot(d, qv) / det;
    const double t = glm::dot(e2, qv) / det;
    const double m = std::min({u, v, 1.0 - u - v});
    if (t < 0.0) continue;
    if (m < 0.0) {
      b.near_miss = std::min(b.near_miss, -m);
      continue;
    }
    if (t < b.t) {
      b.second_t = b.t;
      b.t = t;
      b.id = static_cast<std::uint32_t>(k);
      b.edge = m;
    } else {
      b.second_t = std::min(b.second_t, t);
    }
  }
  return b;
}

void test_random_vs_brute() {
  for (std::uint32_t seed : {11u, 12u, 13u}) {
    support::Rng rng(seed);
    std::vector<glm::vec3> p;
    std::vector<std::uint32_t> idx;
    // A 6 x 6 height-field grid (shared edges, mixed facing toward the camera)...
    const int n = 6;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) p.push_back({float(i) * 2 - 6, rng.uniform(-1, 1) - 4, float(j) * 2 - 6});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        for (std::uint32_t q : {a, c, b, b, c, d}) idx.push_back(q);  // faces +y
      }
    // ...and 80 random triangles in random windings.
    for (int t = 0; t < 80; ++t) {
      const glm::vec3 c{rng.uniform(-5, 5), rng.uniform(-3, 4), rng.uniform(-5, 5)};  // braces: left to right
      for (int k = 0; k < 3; ++k) {
        idx.push_back(static_cast<std::uint32_t>(p.size()));
        p.push_back(c + glm::vec3{rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f)});
      }
    }
    EmbreeScene s;
    s.add_mesh(p.data(), p.size(), idx.data(), idx.size());
    s.commit();
    const glm::vec3 eye{rng.uniform(-12, 12), rng.uniform(4, 10), rng.uniform(-12, 12)};
    const Camera cam = support::make_camera(eye, {0, -1, 0}, 70, 96, 72, 0.1f, 100);
    const PixelRays rays(cam);
    const HitBuffer h = s.render(cam);
    int agree = 0, ties = 0, wrong = 0, hits = 0;
    for (int y = 0; y < h.height; ++y)
      for (int x = 0; x < h.width; ++x) {
        const Ray r = rays.ray(x, y);
        const Brute b = brute_force(p, idx, r);
        const std::uint32_t e = h.at(x, y);
        hits += b.id != HitBuffer::miss;
        if (e == b.id) {
          ++agree;
          if (e != HitBuffer::miss) {
            const double de = h.distance[static_cast<std::size_t>(y) * h.width + x];
            if (!(std::fabs(de - b.t) <= 1e-4 * b.t)) ++wrong;
          }
          continue;
        }
        // Allowed only where the answer is a numerical tie: the ray passes within rounding of an edge
        // (shared edges of the grid, a silhouette) or two surfaces are at the same depth.
        const bool edge_tie = b.edge < 1e-6 || b.near_miss < 1e-6;
        const bool depth_tie = e != HitBuffer::miss && b.id != HitBuffer::miss && std::fabs(b.second_t - b.t) < 1e-5 * b.t;
        if (edge_tie || depth_tie) ++ties;
        else {
          ++wrong;
          if (wrong < 5)
            std::fprintf(stderr, "seed %u pixel (%d, %d): embree %u, brute %u (t %g, edge %g, near miss %g)\n", seed, x,
                         y, e, b.id, b.t, b.edge, b.near_miss);
        }
      }
    CHECK_MSG(wrong == 0, "seed %u: %d pixels disagree with brute force (%d ties, %d agree)", seed, wrong, ties, agree);
    CHECK_MSG(ties <= 10, "seed %u: %d ties is too many", seed, ties);
    CHECK_MSG(hits > 96 * 72 / 8, "seed %u: only %d hit pixels, the scene is not in view", seed, hits);
    std::printf("random scene seed %u: %d pixels agree, %d edge/depth ties, %d hits\n", seed, agree, ties, hits);
  }
}

void test_depth_ranges_and_threads() {
  // The same view built for every depth convention gives the same pixel rays and the same hits.
  EmbreeScene s;
  s.add_box({{-1, -1, -1}, {1, 1, 1}});
  s.add_box({{-4, -1, -6}, {-2, 3, -3}});
  add_quad(s, false, true);
  s.commit();
  const glm::vec3 eye(3, 2.5f, 7), target(-0.5f, 0, -1);
  const Camera cams[] = {
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 200, DepthRange::negative_one_to_one),
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 200, DepthRange::zero_to_one),
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 200, DepthRange::zero_to_one, true),
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 0, DepthRange::negative_one_to_one),
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 0, DepthRange::zero_to_one),
      support::make_camera(eye, target, 55, 70, 50, 0.1f, 0, DepthRange::zero_to_one, true),
  };
  const PixelRays ref_rays(cams[0]);
  const HitBuffer ref = s.render(cams[0], 1);
  CHECK(count_hits(ref) > 1000);
  for (int v = 0; v < 6; ++v) {
    const PixelRays rays(cams[v]);
    double max_dev = 0;
    for (int y = 0; y < 50; ++y)
      for (int x = 0; x < 70; ++x)
        max_dev = std::max(max_dev, double(glm::length(rays.ray(x, y).direction - ref_rays.ray(x, y).direction)));
    CHECK_MSG(max_dev <= 1e-5, "camera variant %d: ray directions differ by %g", v, max_dev);
    const HitBuffer h = s.render(cams[v], 1 + v % 3);
    int differ = 0;
    for (std::size_t i = 0; i < h.triangle.size(); ++i) {
      if (h.triangle[i] != ref.triangle[i]) ++differ;
      else if (h.triangle[i] != HitBuffer::miss && !(std::fabs(h.distance[i] - ref.distance[i]) <= 1e-4 * ref.distance[i]))
        ++differ;
    }
    // Ray directions differ in the last float bits; a pixel centre that lands on an edge may flip.
    CHECK_MSG(differ <= 3, "camera variant %d: %d pixels differ from the [-1, 1] camera", v, differ);
  }
  // Threads do not change the answer.
  const HitBuffer a = s.render(cams[0], 0), b = s.render(cams[0], 7);
  CHECK(a.triangle == ref.triangle && b.triangle == ref.triangle && a.distance == ref.distance);
  CHECK(oracle::visible_triangles(a).size() >= 6);
  const auto vis = oracle::visible_triangles(a);
  CHECK(std::is_sorted(vis.begin(), vis.end()) && std::adjacent_find(vis.begin(), vis.end()) == vis.end());
}

}  // namespace

int main() {
  test_quad();
  test_edge_on();
  test_empty_and_bad();
  test_box();
  test_random_vs_brute();
  test_depth_ranges_and_threads();
  return cullkit_test::report("test_oracle");
}
