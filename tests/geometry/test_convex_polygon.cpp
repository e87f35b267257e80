// ConvexPolygon::split: pieces lie on their sides, areas add up, the epsilon policy holds, NaN and
// overflow are reported instead of corrupting anything.
#include <cmath>
#include <limits>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

namespace {
ConvexPolygon regular(int n, float radius, const glm::vec3& center) {
  ConvexPolygon p;
  for (int i = 0; i < n; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / static_cast<float>(n);
    p.push_back(center + glm::vec3(radius * std::cos(a), radius * std::sin(a), 0.0f));
  }
  return p;
}
}  // namespace

int main() {
  support::Rng rng(99);
  const float eps = 1e-4f;
  int straddles = 0;
  for (int it = 0; it < 5000; ++it) {
    const int n = rng.range(3, 12);
    const ConvexPolygon poly = regular(n, rng.uniform(0.1f, 10.0f), glm::vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), 0));
    const glm::vec3 nrm = glm::normalize(glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) + glm::vec3(1e-3f));
    const Plane plane = plane_from_point_normal(glm::vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), 0), nrm);
    ConvexPolygon front, back;
    const PolygonSide side = poly.split(plane, eps, front, back);
    CHECK(side == poly.side(plane, eps));
    if (side == PolygonSide::straddling) {
      ++straddles;
      CHECK(front.size() >= 3 && back.size() >= 3);
      CHECK(front.size() <= poly.size() + 1 && back.size() <= poly.size() + 1);
      for (const glm::vec3& v : front) CHECK(signed_distance(plane, v) >= -eps * 10);
      for (const glm::vec3& v : back) CHECK(signed_distance(plane, v) <= eps * 10);
      const float total = poly.area(), parts = front.area() + back.area();
      CHECK_MSG(std::fabs(total - parts) <= 1e-4f * total + 1e-6f, "area %g vs %g (iteration %d)", total, parts, it);
      CHECK(!front.overflow() && !back.overflow());
    } else if (side == PolygonSide::front) {
      for (const glm::vec3& v : poly) CHECK(signed_distance(plane, v) >= -eps);
    } else if (side == PolygonSide::back) {
      for (const glm::vec3& v : poly) CHECK(signed_distance(plane, v) <= eps);
    }
  }
  CHECK(straddles > 1000);

  // Vertices within epsilon never cause a split.
  const ConvexPolygon square = regular(4, 1.0f, glm::vec3(0));
  ConvexPolygon f, b;
  const Plane through_corner = plane_from_point_normal(glm::vec3(1.0f + 0.5f * eps, 0, 0), glm::vec3(-1, 0, 0));
  CHECK(square.split(through_corner, eps, f, b) == PolygonSide::front);
  const Plane own = plane_from_point_normal(glm::vec3(0), glm::vec3(0, 0, 1));
  CHECK(square.split(own, eps, f, b) == PolygonSide::coplanar);
  CHECK(ConvexPolygon().split(own, eps, f, b) == PolygonSide::empty);

  // NaN: never decided as one side.
  ConvexPolygon poisoned = square;
  poisoned[2].x = std::numeric_limits<float>::quiet_NaN();
  CHECK(poisoned.split(through_corner, eps, f, b) == PolygonSide::straddling);
  CHECK(poisoned.side(through_corner, eps) == PolygonSide::straddling);

  // Overflow is reported, never written past the end.
  BasicConvexPolygon<4> small;
  for (int i = 0; i < 6; ++i) small.push_back(glm::vec3(float(i), 0, 0));
  CHECK(small.size() == 4 && small.overflow());
  const BasicConvexPolygon<4> quad(square.data(), 4);
  BasicConvexPolygon<4> qf, qb;
  const Plane diag = plane_from_point_normal(glm::vec3(0.2f, 0.1f, 0), glm::vec3(1, 0.3f, 0));
  CHECK(quad.split(diag, eps, qf, qb) == PolygonSide::straddling);
  CHECK(qf.overflow() || qb.overflow() || (qf.size() <= 4 && qb.size() <= 4));
  CHECK(qf.size() <= 4 && qb.size() <= 4);

  // Newell normal follows the winding.
  CHECK(square.normal().z > 0.0f);
  CHECK(std::fabs(square.area() - 2.0f) < 1e-5f);
  return cullkit_test::report("test_convex_polygon");
}
