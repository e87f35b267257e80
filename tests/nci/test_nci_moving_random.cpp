// NormalClassIndex with moving objects under random affine transforms, against a double-precision
// ray cast. Each trial: a camera (eye near the origin or up to 1e5 from it, far/near from 10 to
// 1e7, either depth range), a static scene (loose triangles and a backdrop), and two objects whose
// transforms are translate * rotate * scale * shear, mirrored in half the trials, with 1-norm
// condition numbers up to about 2e4 (all accepted). An object's triangles are made in the world,
// taken into its frame (rounded to float there), and the oracle moves those float corners back in
// double. Some objects also have a triangle behind the eye, which no pixel ray can meet. For every
// pixel whose true first hit is robust (at least 1e-4 inside its triangle's edges, not grazing,
// and 1e-4 relative depth in front of every other triangle the ray may meet), the test checks that
// it is reported: (a) an object triangle in `object_triangles`, (b) a static triangle in the set.
// Seeded: the same trials on every run.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <cullkit/cullkit.hpp>

#include "check.hpp"
#include "nci_double_cast.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;

namespace {

using Index = NormalClassIndex<glm::vec3>;
using Mover = NciMovingObject<Index>;

struct Rng {
  std::mt19937_64 engine;
  explicit Rng(std::uint64_t seed) : engine(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * double(engine() >> 11) * 0x1p-53; }
  glm::dvec3 unit() {
    for (;;) {
      const glm::dvec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double l = glm::length(v);
      if (l > 0.1 && l <= 1.0) return v / l;
    }
  }
};

double condition_1(const glm::dmat3& l) {
  const glm::dmat3 li = glm::inverse(l);
  double a = 0.0, b = 0.0;
  for (int c = 0; c < 3; ++c) {
    a = std::max(a, std::fabs(l[c][0]) + std::fabs(l[c][1]) + std::fabs(l[c][2]));
    b = std::max(b, std::fabs(li[c][0]) + std::fabs(li[c][1]) + std::fabs(li[c][2]));
  }
  return a * b;
}

// translate(origin) * rotate * scale * shear, condition number at most 2e4, mirrored when asked.
glm::dmat4 random_affine(Rng& rng, const glm::dvec3& origin, bool mirror) {
  for (;;) {
    const double spread = rng.uniform(0.0, 3.5);  // log10 of the largest scale ratio
    glm::dvec3 s(std::pow(10.0, rng.uniform(-spread / 2, spread / 2)), std::pow(10.0, rng.uniform(-spread / 2, spread / 2)),
                 std::pow(10.0, rng.uniform(-spread / 2, spread / 2)));
    if (mirror) s.x = -s.x;
    glm::dmat4 shear(1.0);
    const double k = rng.uniform(0.0, 3.0);
    shear[1][0] = rng.uniform(-k, k);
    shear[2][0] = rng.uniform(-k, k);
    shear[2][1] = rng.uniform(-k, k);
    const glm::dmat4 m = glm::translate(glm::dmat4(1.0), origin) *
                         glm::rotate(glm::dmat4(1.0), rng.uniform(0.0, 6.283), rng.unit()) *
                         glm::scale(glm::dmat4(1.0), s) * shear;
    if (condition_1(glm::dmat3(m)) <= 2e4) return m;
  }
}

struct Counts {
  long object_pixels = 0, static_pixels = 0, lost_object = 0, lost_static = 0, rejected = 0;
};

void trial(std::uint64_t seed, Counts& counts) {
  Rng rng(seed);
  // Camera.
  const bool far_eye = rng.uniform(0, 1) < 0.5;
  const glm::dvec3 eye_d = far_eye ? rng.unit() * std::pow(10.0, rng.uniform(3.0, 5.0))
                                   : glm::dvec3(rng.uniform(-10, 10), rng.uniform(-10, 10), rng.uniform(-10, 10));
  const glm::vec3 eye(eye_d);
  const glm::dvec3 view = rng.unit();
  const glm::dvec3 up = std::fabs(view.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
  const double fov = rng.uniform(30.0, 90.0);
  const double near = std::pow(10.0, rng.uniform(-2.0, 0.0)), ratio = std::pow(10.0, rng.uniform(1.0, 7.0));
  const bool zero_one = rng.uniform(0, 1) < 0.3;
  const int width = 32, height = rng.uniform(0, 1) < 0.5 ? 32 : 24;
  Camera cam;
  cam.eye = eye;
  cam.width = width;
  cam.height = height;
  cam.depth = zero_one ? DepthRange::zero_to_one : DepthRange::negative_one_to_one;
  const float aspect = float(width) / float(height);
  const glm::mat4 proj = zero_one ? glm::perspectiveRH_ZO(glm::radians(float(fov)), aspect, float(near), float(near * ratio))
                                  : glm::perspectiveRH_NO(glm::radians(float(fov)), aspect, float(near), float(near * ratio));
  cam.view_proj = proj * glm::lookAt(eye, glm::vec3(eye_d + view), glm::vec3(up));
  // Points in view: along a direction inside the cone of the view, at depth `dist`.
  const glm::dvec3 side = glm::normalize(glm::cross(view, up)), upv = glm::cross(side, view);
  const double spread = std::tan(glm::radians(fov) * 0.5);
  const auto in_view = [&](double dist) {
    return eye_d + dist * (view + side * rng.uniform(-spread, spread) * 0.9 + upv * rng.uniform(-spread, spread) * 0.9);
  };
  // Static scene: loose triangles and a backdrop of quads at depth 100.
  std::vector<glm::vec3> svert;
  std::vector<nci_test::DoubleTriangle> truth;  // static first (as floats), then the objects'
  const auto face = [](glm::dvec3& a, glm::dvec3& b, glm::dvec3& c, const glm::dvec3& from) {
    if (glm::dot(glm::cross(b - a, c - a), from - a) < 0.0) std::swap(b, c);
  };
  for (int k = 0; k < 30; ++k) {
    const double dist = rng.uniform(2.0, 60.0), size = dist * rng.uniform(0.05, 0.3);
    const glm::dvec3 c0 = in_view(dist);
    glm::dvec3 p[3] = {c0 + rng.unit() * size, c0 + rng.unit() * size, c0 + rng.unit() * size};
    if (rng.uniform(0, 1) < 0.7) face(p[0], p[1], p[2], eye_d);
    for (const auto& q : p) svert.push_back(glm::vec3(q));
  }
  {
    const double d = 100.0, h = d * spread * 2.0;
    const glm::dvec3 o = eye_d + view * d;
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) {
        const auto at = [&](int a, int b) { return o + side * (h * (a / 3.0 - 1.0)) + upv * (h * (b / 3.0 - 1.0)); };
        glm::dvec3 q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
        glm::dvec3 t0[3] = {q[0], q[1], q[2]}, t1[3] = {q[0], q[2], q[3]};
        face(t0[0], t0[1], t0[2], eye_d);
        face(t1[0], t1[1], t1[2], eye_d);
        for (const auto& v : t0) svert.push_back(glm::vec3(v));
        for (const auto& v : t1) svert.push_back(glm::vec3(v));
      }
  }
  const std::size_t static_count = svert.size() / 3;
  for (std::size_t t = 0; t < static_count; ++t)
    truth.push_back({glm::dvec3(svert[3 * t]), glm::dvec3(svert[3 * t + 1]), glm::dvec3(svert[3 * t + 2]), false});
  std::vector<std::uint32_t> sidx(svert.size());
  for (std::size_t i = 0; i < sidx.size(); ++i) sidx[i] = static_cast<std::uint32_t>(i);
  NciParams params;
  params.threads = 1;
  params.classes = 4;  // a few dozen triangles per index: the build's normal lookup would dominate the test's time
  const nci_test::TestIndex<glm::vec3> static_index({svert.data(), svert.size(), sidx.data(), sidx.size()}, params);
  // Two objects.
  const bool mirror = rng.uniform(0, 1) < 0.5;
  std::vector<std::vector<glm::vec3>> local(2);
  std::vector<std::vector<std::uint32_t>> lidx(2);
  std::vector<std::size_t> first(2);
  std::vector<Mover> movers(2);
  std::vector<Index> indexes;
  indexes.reserve(2);
  for (int k = 0; k < 2; ++k) {
    const double dist = rng.uniform(3.0, 40.0), radius = dist * rng.uniform(0.05, 0.2);
    const glm::dvec3 centre = in_view(dist);
    const glm::dvec3 origin = centre + rng.unit() * radius * rng.uniform(0.0, 3.0);
    const glm::dmat4 m = random_affine(rng, origin, mirror && k == 0);
    const glm::dmat4 mi = glm::inverse(m);
    const glm::dvec3 local_eye(mi * glm::dvec4(eye_d, 1.0));
    std::vector<glm::dvec3> world;
    for (int t = 0; t < 20; ++t) {
      const glm::dvec3 c0 = centre + rng.unit() * radius;
      for (int c = 0; c < 3; ++c) world.push_back(c0 + rng.unit() * radius * 0.6);
    }
    if (k == 0 || rng.uniform(0, 1) < 0.5) {  // a big triangle behind the eye
      const glm::dvec3 b = eye_d - view * rng.uniform(1.0, 20.0);
      const double s = rng.uniform(5.0, 50.0);
      for (int c = 0; c < 3; ++c) world.push_back(b + rng.unit() * s);
    }
    for (std::size_t t = 0; t < world.size() / 3; ++t) {
      glm::dvec3 p[3];
      for (int c = 0; c < 3; ++c) p[c] = glm::dvec3(mi * glm::dvec4(world[3 * t + static_cast<std::size_t>(c)], 1.0));
      if (rng.uniform(0, 1) < 0.7 || t + 1 == world.size() / 3) face(p[0], p[1], p[2], local_eye);
      for (const auto& q : p) local[static_cast<std::size_t>(k)].push_back(glm::vec3(q));
    }
    auto& lv = local[static_cast<std::size_t>(k)];
    auto& li = lidx[static_cast<std::size_t>(k)];
    for (std::size_t i = 0; i < lv.size(); ++i) li.push_back(static_cast<std::uint32_t>(i));
    indexes.emplace_back(MeshView<glm::vec3>{lv.data(), lv.size(), li.data(), li.size()}, params);
    first[static_cast<std::size_t>(k)] = truth.size();
    const bool flip = glm::determinant(glm::dmat3(m)) < 0.0;
    for (std::size_t t = 0; t < lv.size() / 3; ++t) {
      glm::dvec3 w[3];
      for (int c = 0; c < 3; ++c) w[c] = glm::dvec3(m * glm::dvec4(glm::dvec3(lv[3 * t + static_cast<std::size_t>(c)]), 1.0));
      truth.push_back({w[0], w[1], w[2], flip});
    }
    movers[static_cast<std::size_t>(k)] = Mover{&indexes.back(), glm::mat4(m), 10u + static_cast<std::uint32_t>(k)};
  }
  // The oracle moves the float matrix the index gets, not the double one.
  for (int k = 0; k < 2; ++k) {
    const glm::dmat4 m(movers[static_cast<std::size_t>(k)].local_to_world);
    const auto& lv = local[static_cast<std::size_t>(k)];
    for (std::size_t t = 0; t < lv.size() / 3; ++t) {
      auto& tri = truth[first[static_cast<std::size_t>(k)] + t];
      tri.a = glm::dvec3(m * glm::dvec4(glm::dvec3(lv[3 * t]), 1.0));
      tri.b = glm::dvec3(m * glm::dvec4(glm::dvec3(lv[3 * t + 1]), 1.0));
      tri.c = glm::dvec3(m * glm::dvec4(glm::dvec3(lv[3 * t + 2]), 1.0));
    }
  }
  NciContext ctx;
  VisibleSet set;
  std::vector<NciObjectTriangle> objs;
  static_index.select_visible(cam, movers.data(), movers.size(), ctx, set, objs, nullptr);
  counts.rejected += static_cast<long>(ctx.stats.moving_objects_rejected);
  long lost_object = 0, lost_static = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const int hit = nci_test::robust_first_hit(glm::dvec3(eye), nci_test::double_pixel_ray(cam, x, y), truth);
      if (hit < 0) continue;
      const auto h = static_cast<std::size_t>(hit);
      if (h < static_count) {
        ++counts.static_pixels;
        lost_static += !std::binary_search(set.triangles.begin(), set.triangles.end(), static_cast<std::uint32_t>(h));
      } else {
        const std::size_t k = h >= first[1] ? 1 : 0;
        ++counts.object_pixels;
        const NciObjectTriangle ot{10u + static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(h - first[k])};
        lost_object += !std::binary_search(objs.begin(), objs.end(), ot);
      }
    }
  if (lost_object || lost_static)
    std::printf("seed %llu: %ld object pixels and %ld static pixels lost (far/near %.3g, eye %.3g from the origin)\n",
                static_cast<unsigned long long>(seed), lost_object, lost_static, ratio, glm::length(eye_d));
  counts.lost_object += lost_object;
  counts.lost_static += lost_static;
}

}  // namespace

int main() {
  Counts counts;
  const int trials = NCI_SANITIZED ? 100 : 400;
  for (int s = 0; s < trials; ++s) trial(0x6d6f7665ull * 1000003ull + static_cast<std::uint64_t>(s), counts);
  std::printf("%d trials: %ld object pixels, %ld static pixels checked; lost %ld and %ld; %ld objects rejected\n", trials,
              counts.object_pixels, counts.static_pixels, counts.lost_object, counts.lost_static, counts.rejected);
  CHECK(counts.object_pixels > 10000);
  CHECK(counts.static_pixels > 10000);
  CHECK(counts.rejected == 0);
  CHECK(counts.lost_object == 0);  // (a) every visible moving triangle is reported
  CHECK(counts.lost_static == 0);  // (b) and every visible static triangle
  return cullkit_test::report("test_nci_moving_random");
}
