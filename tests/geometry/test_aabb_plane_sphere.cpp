// Aabb, Plane and Sphere helpers: validity rules for bad input, merge identity, bounding spheres
// that really enclose their boxes.
#include <cmath>
#include <limits>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

int main() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();

  const Aabb unit{glm::vec3(0), glm::vec3(1)};
  CHECK(is_valid(unit));
  CHECK(is_valid(Aabb{glm::vec3(2), glm::vec3(2)}));  // a point box is valid
  CHECK(!is_valid(Aabb{glm::vec3(1), glm::vec3(0)}));
  CHECK(!is_valid(Aabb{glm::vec3(0, nan, 0), glm::vec3(1)}));
  CHECK(!is_valid(Aabb{glm::vec3(0), glm::vec3(inf)}));
  CHECK(!is_valid(Aabb::empty()));
  CHECK(is_empty(Aabb::empty()));
  CHECK(!is_empty(unit));
  const Aabb m = merge(Aabb::empty(), unit);
  CHECK(m.min == unit.min && m.max == unit.max);
  CHECK(overlaps(unit, Aabb{glm::vec3(1), glm::vec3(2)}));  // touching boxes overlap
  CHECK(!overlaps(unit, Aabb{glm::vec3(1.0001f), glm::vec3(2)}));
  CHECK(!overlaps(unit, Aabb::empty()));
  CHECK(contains(unit, glm::vec3(1, 0, 0.5f)));
  CHECK(!contains(unit, glm::vec3(nan)));
  CHECK(volume(Aabb{glm::vec3(0), glm::vec3(1, 2, 3)}) == 6.0f);
  CHECK(volume(Aabb::empty()) == 0.0f);
  CHECK(surface_area(Aabb{glm::vec3(0), glm::vec3(1, 2, 3)}) == 22.0f);
  CHECK(longest_axis(Aabb{glm::vec3(0), glm::vec3(1, 3, 2)}) == 1);
  CHECK(corner(unit, 5) == glm::vec3(1, 0, 1));
  CHECK(is_empty(intersection(unit, Aabb{glm::vec3(2), glm::vec3(3)})));

  // Bounding spheres enclose every corner, even for boxes far from the origin and thin boxes.
  support::Rng rng(7);
  int enclosed = 0, total = 0;
  for (int i = 0; i < 20000; ++i) {
    const float scale = std::pow(10.0f, rng.uniform(-3, 6));
    const glm::vec3 c(rng.uniform(-1, 1) * scale, rng.uniform(-1, 1) * scale, rng.uniform(-1, 1) * scale);
    const glm::vec3 h(rng.uniform(0, 1) * scale * 0.01f, rng.uniform(0, 1) * scale, rng.uniform(0, 1e-3f) * scale);
    const Aabb b{c - h, c + h};
    const Sphere s = bounding_sphere(b);
    for (int k = 0; k < 8; ++k) {
      ++total;
      // In double: the float sphere must contain the float corner.
      const glm::dvec3 d = glm::dvec3(corner(b, k)) - glm::dvec3(s.center);
      enclosed += std::sqrt(glm::dot(d, d)) <= double(s.radius);
    }
  }
  CHECK_MSG(enclosed == total, "%d of %d corners enclosed", enclosed, total);
  CHECK(bounding_sphere(Aabb::empty()).radius < 0.0f);

  // Planes: orientation of plane_from_points, invalid input gives the zero plane.
  const Plane p = plane_from_points(glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  CHECK(is_valid(p));
  CHECK(signed_distance(p, glm::vec3(0, 0, 2)) == 2.0f);  // counter-clockwise seen from +z: +z is inside
  CHECK(signed_distance(flipped(p), glm::vec3(0, 0, 2)) == -2.0f);
  CHECK(!is_valid(plane_from_points(glm::vec3(0), glm::vec3(1), glm::vec3(2))));  // collinear
  CHECK(!is_valid(plane_from_point_normal(glm::vec3(0), glm::vec3(nan, 0, 0))));
  CHECK(!is_valid(plane_from_point_normal(glm::vec3(0), glm::vec3(0))));
  CHECK(!is_valid(Plane{glm::vec3(0, 1, 0), inf}));
  return cullkit_test::report("test_aabb_plane_sphere");
}
