// AdaptiveBinaryTree::cull(ConvexVolume) and the volume's own tests with planes whose normals are
// not unit length. A plane and the same plane with its normal and offset scaled by a positive factor
// bound the same half-space, so every answer must hold for both. Polytopes of 10 planes through
// points about 300 units from a centre, normals scaled by 0.01 to 100, over random and integer boxes.
// Oracles: (1) the volume's own box test, which the tree's leaf test repeats term for term, so a box
// it does not call `outside` must be reported (a node test that prunes more is a false cull); (2)
// in double precision, a box whose centre lies inside every plane must be reported; (3) a sphere
// holding a point inside every plane is never `outside`. Frustum::from_planes is checked the same way.
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/adaptive_binary_tree.hpp>
#include <cullkit/geometry/convex_volume.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"

using namespace cullkit;

namespace {

using Tree = AdaptiveBinaryTree<Aabb>;

struct ScaledPlanes {
  std::vector<Plane> given;  // as handed to the volume: non-unit normals
};

glm::dvec3 random_direction(support::Rng& rng) {
  for (;;) {
    const glm::dvec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double l = glm::length(v);
    if (l > 0.1 && l <= 1.0) return v / l;
  }
}

// Ten planes facing a centre, each through a point about 300 units from it, the normal scaled by
// 10^u with u uniform in [-2, 2].
ScaledPlanes make_polytope(support::Rng& rng, const glm::dvec3& centre) {
  ScaledPlanes p;
  for (int i = 0; i < 10; ++i) {
    const glm::dvec3 n = random_direction(rng);
    const glm::dvec3 on = centre - n * static_cast<double>(rng.uniform(250.0f, 350.0f));
    const double scale = std::pow(10.0, static_cast<double>(rng.uniform(-2.0f, 2.0f)));
    const glm::dvec3 sn = n * scale;
    p.given.push_back(Plane{glm::vec3(sn), static_cast<float>(-glm::dot(sn, on))});
  }
  return p;
}

bool centre_inside_all(const std::vector<Plane>& planes, const Aabb& b) {
  const glm::dvec3 c = (glm::dvec3(b.min) + glm::dvec3(b.max)) * 0.5;
  for (const Plane& p : planes)
    if (glm::dot(glm::dvec3(p.normal), c) + static_cast<double>(p.d) < 0.0) return false;
  return true;
}

}  // namespace

int main() {
  support::Rng rng(20261128);
  const glm::dvec3 centre(120.0, -300.0, 270.0);

  // Random boxes of all sizes around the polytopes, and boxes with integer corners.
  std::vector<Aabb> boxes;
  for (int i = 0; i < 60000; ++i) {
    const glm::vec3 c = glm::vec3(centre) + glm::vec3(rng.uniform(-450, 450), rng.uniform(-450, 450), rng.uniform(-450, 450));
    const float s = std::pow(10.0f, rng.uniform(-1.0f, 2.3f));
    const glm::vec3 e(rng.uniform(0, s), rng.uniform(0, s), rng.uniform(0, s));
    boxes.push_back(Aabb{c - e, c + e});
  }
  for (int i = 0; i < 60000; ++i) {
    const glm::vec3 lo(static_cast<float>(rng.range(-350, 550)), static_cast<float>(rng.range(-700, 100)),
                       static_cast<float>(rng.range(-100, 650)));
    const glm::vec3 e(static_cast<float>(rng.range(0, 40)), static_cast<float>(rng.range(0, 40)),
                      static_cast<float>(rng.range(0, 40)));
    boxes.push_back(Aabb{lo, lo + e});
  }
  const Tree tree(boxes.data(), boxes.size());

  std::vector<std::uint32_t> out;
  std::vector<std::uint8_t> reported;
  std::size_t meets = 0, missed_rule = 0, centre_inside = 0, missed_centre = 0, frustum_missed = 0;
  std::size_t sphere_checks = 0, sphere_missed = 0;
  for (int v = 0; v < 120; ++v) {
    const ScaledPlanes polytope = make_polytope(rng, centre);
    ConvexVolume volume;
    for (const Plane& p : polytope.given) CHECK(volume.add_plane(p));
    CHECK(volume.plane_count() == polytope.given.size());
    tree.cull(volume, out);
    reported.assign(boxes.size(), 0);
    for (std::uint32_t i : out) reported[i] = 1;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (volume.classify(boxes[i]) != Containment::outside) {
        ++meets;
        if (!reported[i] && ++missed_rule <= 3)
          std::fprintf(stderr, "  volume %d: box %zu (%g %g %g)..(%g %g %g) meets the volume, not reported\n", v, i,
                       double(boxes[i].min.x), double(boxes[i].min.y), double(boxes[i].min.z), double(boxes[i].max.x),
                       double(boxes[i].max.y), double(boxes[i].max.z));
      }
      if (centre_inside_all(polytope.given, boxes[i])) {
        ++centre_inside;
        if (!reported[i]) ++missed_centre;
      }
    }
    // A frustum from six of the planes: the tree's frustum walk has the same node tests.
    const Frustum frustum = Frustum::from_planes(polytope.given.data(), Frustum::max_planes);
    tree.cull(frustum, out);
    reported.assign(boxes.size(), 0);
    for (std::uint32_t i : out) reported[i] = 1;
    const std::vector<Plane> six(polytope.given.begin(), polytope.given.begin() + Frustum::max_planes);
    for (std::size_t i = 0; i < boxes.size(); ++i)
      if (centre_inside_all(six, boxes[i]) && !reported[i]) ++frustum_missed;
    // Spheres around points inside every plane.
    for (int k = 0; k < 200; ++k) {
      const glm::vec3 p = glm::vec3(centre) + glm::vec3(rng.uniform(-200, 200), rng.uniform(-200, 200), rng.uniform(-200, 200));
      const Aabb point{p, p};
      if (!centre_inside_all(polytope.given, point)) continue;
      ++sphere_checks;
      const glm::vec3 off = glm::vec3(random_direction(rng)) * rng.uniform(0.0f, 50.0f);
      const Sphere s{p + off, glm::length(off) * 1.001f};
      if (volume.classify(s) == Containment::outside) ++sphere_missed;
    }
  }
  CHECK_MSG(missed_rule == 0, "%zu of %zu boxes the volume's own test keeps were left out by the tree", missed_rule, meets);
  CHECK_MSG(missed_centre == 0, "%zu of %zu boxes with their centre inside every plane were left out", missed_centre,
            centre_inside);
  CHECK_MSG(frustum_missed == 0, "%zu boxes with their centre inside a from_planes frustum were left out", frustum_missed);
  CHECK_MSG(sphere_missed == 0, "%zu of %zu spheres holding an inside point were called outside", sphere_missed,
            sphere_checks);
  // The oracle must have seen enough of each kind to mean something.
  CHECK(meets > 100000);
  CHECK(centre_inside > 50000);
  CHECK(sphere_checks > 1000);
  return cullkit_test::report("test_abt_volume_scale");
}
