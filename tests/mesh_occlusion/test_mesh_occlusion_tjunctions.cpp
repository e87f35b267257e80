// The T-junction cuts' parts on their own: the exact on-segment test (corners exactly on the open
// segment are taken, corners one float step off it, at its ends or beyond are not, nor corners whose
// differences are not exact in double), the ear clipping (the parts of a triangle with corners on
// all three sides are non-degenerate, wound as the triangle, cover its area exactly and have every
// piece of its sides as an edge), random triangles with dyadic points on their sides, and the
// culler's build counts (a seam one float step off the edge is a crack and is not cut; corners off
// by less than 2^-10 of the edge from an end are left alone).
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit/detail/mesh_occlusion/tjunctions.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

namespace dmo = cullkit::detail::mesh_occlusion;
using mesh_oracle::TestScene;

namespace {

void on_segment_cases() {
  const glm::vec3 p(0.0f, 0.0f, 0.0f), q(2.0f, 3.0f, 0.0f);
  CHECK(dmo::on_open_segment(p, q, glm::vec3(1.0f, 1.5f, 0.0f)));
  CHECK(dmo::on_open_segment(p, q, glm::vec3(0.5f, 0.75f, 0.0f)));
  CHECK(dmo::on_open_segment(q, p, glm::vec3(1.5f, 2.25f, 0.0f)));
  CHECK(!dmo::on_open_segment(p, q, glm::vec3(1.0f, std::nextafter(1.5f, 2.0f), 0.0f)));
  CHECK(!dmo::on_open_segment(p, q, glm::vec3(1.0f, 1.5f, std::nextafter(0.0f, 1.0f))));
  CHECK(!dmo::on_open_segment(p, q, p));
  CHECK(!dmo::on_open_segment(p, q, q));
  CHECK(!dmo::on_open_segment(p, q, glm::vec3(4.0f, 6.0f, 0.0f)));
  CHECK(!dmo::on_open_segment(p, q, glm::vec3(-2.0f, -3.0f, 0.0f)));
  // An axis-aligned edge far from the origin, and a corner on it.
  const glm::vec3 a(1000.25f, -7.0f, 3.5f), b(1000.25f, 9.0f, 3.5f);
  CHECK(dmo::on_open_segment(a, b, glm::vec3(1000.25f, 0.125f, 3.5f)));
  CHECK(!dmo::on_open_segment(a, b, glm::vec3(std::nextafter(1000.25f, 0.0f), 0.125f, 3.5f)));
  // Differences not exact in double: no conclusion, so no.
  CHECK(!dmo::on_open_segment(glm::vec3(1e30f, 0.0f, 0.0f), glm::vec3(-1e30f, 0.0f, 0.0f), glm::vec3(1e-30f, 0.0f, 0.0f)));
}

double area2(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return glm::cross(b - a, c - a).z;  // all test triangles lie in z = const
}

// Cuts the triangle (c0, c1, c2) with `points[k]` on side k (in order) and checks the parts.
void check_cut(const std::vector<glm::vec3>& positions, const std::uint32_t c[3],
               const std::vector<std::uint32_t> points[3], const char* what) {
  std::vector<std::uint32_t> parts;
  const bool ok = dmo::cut_triangle(positions, c, points, parts);
  CHECK_MSG(ok, "%s: not cut", what);
  if (!ok) return;
  std::size_t n = 3;
  for (int k = 0; k < 3; ++k) n += points[k].size();
  CHECK_MSG(parts.size() == 3 * (n - 2), "%s: %zu parts for a polygon of %zu corners", what, parts.size() / 3, n);
  const auto at = [&](std::uint32_t v) { return glm::dvec3(positions[v]); };
  const double whole = area2(at(c[0]), at(c[1]), at(c[2]));
  double sum = 0.0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t i = 0; i < parts.size(); i += 3) {
    const double a = area2(at(parts[i]), at(parts[i + 1]), at(parts[i + 2]));
    CHECK_MSG(a * whole > 0.0, "%s: part %zu degenerate or flipped (%g)", what, i / 3, a);
    sum += a;
    for (int k = 0; k < 3; ++k) ++edges[{parts[i + std::size_t(k)], parts[i + std::size_t((k + 1) % 3)]}];
  }
  CHECK_MSG(std::fabs(sum - whole) <= 1e-12 * std::fabs(whole), "%s: parts cover %g of %g", what, sum, whole);
  // Every piece of every side is an edge of a part, in the triangle's direction.
  for (int k = 0; k < 3; ++k) {
    std::uint32_t from = c[k];
    std::vector<std::uint32_t> chain = points[k];
    chain.push_back(c[(k + 1) % 3]);
    for (std::uint32_t to : chain) {
      CHECK_MSG(edges.count({from, to}) == 1, "%s: side %d piece %u -> %u missing", what, k, from, to);
      from = to;
    }
  }
}

void cut_cases() {
  // Corners 0..2, then points on the sides (dyadic, so exactly on them).
  std::vector<glm::vec3> pos = {{0, 0, 0}, {8, 0, 0}, {0, 8, 0}, {2, 0, 0}, {4, 0, 0}, {6, 0, 0},
                                {6, 2, 0}, {2, 6, 0}, {0, 4, 0}, {0, 1, 0}};
  const std::uint32_t c[3] = {0, 1, 2};
  {
    const std::vector<std::uint32_t> points[3] = {{3, 4, 5}, {}, {}};
    check_cut(pos, c, points, "one side");
  }
  {
    const std::vector<std::uint32_t> points[3] = {{4}, {6, 7}, {8, 9}};
    check_cut(pos, c, points, "all sides");
  }
  {
    const std::vector<std::uint32_t> points[3] = {{3, 4, 5}, {6, 7}, {8, 9}};
    check_cut(pos, c, points, "all sides, many");
  }
  // Random triangles with integer corners and points at dyadic fractions of their sides.
  cullkit::support::Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<glm::vec3> p;
    for (int k = 0; k < 3; ++k)
      p.emplace_back(float(int(rng.uniform(-64.0f, 64.0f))), float(int(rng.uniform(-64.0f, 64.0f))), 5.0f);
    if (area2(glm::dvec3(p[0]), glm::dvec3(p[1]), glm::dvec3(p[2])) == 0.0) continue;
    std::vector<std::uint32_t> points[3];
    for (int k = 0; k < 3; ++k) {
      const int count = int(rng.uniform(0.0f, 4.0f));
      for (int i = 1; i <= count; ++i) {
        const float t = float(i) / 8.0f;  // dyadic: the point is exactly on the side
        const glm::vec3 m = p[std::size_t(k)] + t * (p[std::size_t((k + 1) % 3)] - p[std::size_t(k)]);
        CHECK(dmo::on_open_segment(p[std::size_t(k)], p[std::size_t((k + 1) % 3)], m));
        points[k].push_back(static_cast<std::uint32_t>(p.size()));
        p.push_back(m);
      }
    }
    const std::uint32_t cc[3] = {0, 1, 2};
    check_cut(p, cc, points, "random");
  }
}

// A wall of two halves meeting in T-junctions along x = 0; `off` moves the small triangles' seam
// corners by one float step off the big edge (a crack), `near_end` puts one of them within 2^-10
// of the edge's length from its end.
std::size_t cuts_of_wall(bool off, bool near_end) {
  TestScene s;
  s.begin_object();
  s.triangle({-4, 0, 0}, {0, 0, 0}, {0, 3, 0});
  s.triangle({-4, 0, 0}, {0, 3, 0}, {-4, 3, 0});
  s.begin_object();
  const float ys[4] = {0.0f, near_end ? 0.001f : 1.0f, 2.0f, 3.0f};
  for (int k = 0; k < 3; ++k) {
    const float x0 = (off && k > 0) ? std::nextafter(0.0f, 1.0f) : 0.0f;
    const float x1 = (off && k < 2) ? std::nextafter(0.0f, 1.0f) : 0.0f;
    s.triangle({x0, ys[k], 0}, {4, ys[k], 0}, {4, ys[k + 1], 0});
    s.triangle({x0, ys[k], 0}, {4, ys[k + 1], 0}, {x1, ys[k + 1], 0});
  }
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size());
  return culler.stats().tjunction_corners;
}

}  // namespace

int main() {
  on_segment_cases();
  cut_cases();
  const std::size_t exact = cuts_of_wall(false, false), crack = cuts_of_wall(true, false),
                    near_end = cuts_of_wall(false, true);
  std::printf("seam corners cut: exact %zu, one float step off %zu, one within 2^-10 of an end %zu\n", exact, crack,
              near_end);
  CHECK(exact == 2);
  CHECK(crack == 0);
  CHECK(near_end == 1);
  return cullkit_test::report("test_mesh_occlusion_tjunctions");
}
