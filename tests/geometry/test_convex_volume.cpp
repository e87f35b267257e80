// ConvexVolume against a brute-force oracle: random volumes of 1 to 32 planes, random boxes; a box
// with a sample point inside the volume must never be `outside`, and a box called `inside` must
// have every sampled point inside. Also the frustum equivalence, the 32-plane limit and bad planes.
#include <cmath>
#include <limits>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <glm/gtc/matrix_transform.hpp>

using namespace cullkit;

namespace {
bool inside_all(const ConvexVolume& v, const glm::vec3& p) {
  for (std::size_t i = 0; i < v.plane_count(); ++i)
    if (signed_distance(v.plane(i), p) < 0.0f) return false;
  return true;
}
glm::vec3 random_unit(support::Rng& rng) {
  for (;;) {
    const glm::vec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const float l = glm::length(v);
    if (l > 0.1f && l <= 1.0f) return v / l;
  }
}
}  // namespace

int main() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  support::Rng rng(20261125);

  // Empty volume: everything inside.
  const ConvexVolume all;
  CHECK(all.plane_count() == 0);
  CHECK(all.classify(Aabb{glm::vec3(-1e30f), glm::vec3(1e30f)}) == Containment::inside);

  // The 32-plane limit and invalid planes.
  ConvexVolume v;
  for (int i = 0; i < 32; ++i) CHECK(v.add_plane(Plane{random_unit(rng), 5.0f}));
  CHECK(v.plane_count() == 32);
  CHECK(!v.add_plane(Plane{glm::vec3(1, 0, 0), 0.0f}));
  CHECK(v.plane_count() == 32);
  ConvexVolume bad;
  CHECK(bad.add_plane(Plane{glm::vec3(0), 1.0f}));
  CHECK(bad.add_plane(Plane{glm::vec3(nan, 0, 0), 1.0f}));
  CHECK(bad.plane_count() == 0);
  CHECK(bad.classify(Aabb{glm::vec3(0), glm::vec3(1)}) == Containment::inside);
  // A NaN box is never `outside`.
  CHECK(v.classify(Aabb{glm::vec3(nan), glm::vec3(nan)}) != Containment::outside);

  // From a frustum: the same answers as the frustum itself.
  const glm::mat4 vp = glm::perspective(1.0f, 1.5f, 0.5f, 100.0f) *
                       glm::lookAt(glm::vec3(1, 2, 3), glm::vec3(10, 0, -20), glm::vec3(0, 1, 0));
  const Frustum f = Frustum::from_matrix(vp);
  const ConvexVolume fv(f);
  CHECK(fv.plane_count() == 6);
  int frustum_disagreements = 0;
  for (int i = 0; i < 5000; ++i) {
    const glm::vec3 c(rng.uniform(-120, 120), rng.uniform(-120, 120), rng.uniform(-120, 120));
    const glm::vec3 e(rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(0, 10));
    const Aabb b{c - e, c + e};
    frustum_disagreements += f.classify(b) != fv.classify(b);
  }
  CHECK(frustum_disagreements == 0);

  // Random volumes against sampled points.
  int outside_seen = 0, inside_seen = 0;
  for (int trial = 0; trial < 300; ++trial) {
    ConvexVolume vol;
    const int n = rng.range(1, 32);
    for (int i = 0; i < n; ++i) vol.add_plane(Plane{random_unit(rng), rng.uniform(1.0f, 8.0f)});
    for (int k = 0; k < 60; ++k) {
      const glm::vec3 c(rng.uniform(-12, 12), rng.uniform(-12, 12), rng.uniform(-12, 12));
      const glm::vec3 e(rng.uniform(0, 4), rng.uniform(0, 4), rng.uniform(0, 4));
      const Aabb b{c - e, c + e};
      VolumeMask mask = vol.full_mask();
      const Containment got = vol.classify(b, mask);
      CHECK(got == vol.classify(b));
      outside_seen += got == Containment::outside;
      inside_seen += got == Containment::inside;
      for (int s = 0; s < 64; ++s) {
        const glm::vec3 p = b.min + (b.max - b.min) * glm::vec3(s & 1 ? 1.0f : rng.uniform(),
                                                                 s & 2 ? 1.0f : rng.uniform(),
                                                                 s & 4 ? 0.0f : rng.uniform());
        const bool in = inside_all(vol, p);
        if (got == Containment::outside) CHECK_MSG(!in, "trial %d box %d: outside box holds an inside point", trial, k);
        if (got == Containment::inside) CHECK_MSG(in, "trial %d box %d: inside box holds an outside point", trial, k);
      }
      // Planes cleared from the mask are ones the box is wholly inside of.
      if (got != Containment::outside)
        for (std::size_t i = 0; i < vol.plane_count(); ++i)
          if (!((mask >> i) & 1u)) {
            for (int corner_id = 0; corner_id < 8; ++corner_id) CHECK(signed_distance(vol.plane(i), corner(b, corner_id)) >= 0.0f);
          }
    }
  }
  // The oracle has to see both kinds of answer, or it proved nothing.
  CHECK(outside_seen > 100);
  CHECK(inside_seen > 100);
  return cullkit_test::report("test_convex_volume");
}
