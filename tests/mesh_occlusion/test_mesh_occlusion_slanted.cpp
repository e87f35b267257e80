// Objects held to their own depth cell by cell. A ceiling runs from above the eyes far ahead; slabs
// lie just above it, facing down (front faces for the eyes below). Every ray to a slab crosses the
// ceiling first, so every slab is hidden. But each slab is long in depth: its nearest corner is
// nearer than the ceiling is over the far part of the slab's screen rectangle, so its rectangle at
// its nearest depth (the test of a whole triangle) is never hidden; per cell, each point of the slab
// lies behind the ceiling's point on the same ray. Slabs just below the ceiling are seen: every
// object the culler leaves out must be unseen by the brute-force ray oracle.
//
// The ceiling runs from behind the eyes, so its triangles are clipped at the near plane. In the
// second variant its left half is one quad whose edge meets the right half's finer grid at
// T-junctions: that quad's triangles are cut into parts at build time, and the parts, clipped each
// on its own, must still fuse into a ceiling.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

using cullkit::support::Rng;
using mesh_oracle::TestScene;

namespace {

constexpr float ceiling_y = 1.0f, above_y = 1.4f, below_y = 0.8f;

// Depth along the view axis of the point where the ray from `eye` through `p` meets the plane
// y = ceiling_y.
double ceiling_depth_towards(const glm::dvec3& eye, const glm::dvec3& forward, const glm::dvec3& p) {
  const glm::dvec3 d = p - eye;
  const double t = (ceiling_y - eye.y) / d.y;
  return glm::dot(t * d, forward);
}

struct Variant {
  const char* name;
  bool tjunctions;
};

void run_variant(const Variant& v, std::uint64_t seed) {
  Rng rng(seed);
  TestScene s;
  // The ceiling (y = 1, facing down), from z = 6 to z = -54.
  s.begin_object();
  if (v.tjunctions) {
    mesh_oracle::grid_quads(s, glm::vec3(-20, ceiling_y, 6), glm::vec3(0, 0, -60), glm::vec3(20, 0, 0), 1, 1);
    mesh_oracle::grid_quads(s, glm::vec3(0, ceiling_y, 6), glm::vec3(0, 0, -60), glm::vec3(20, 0, 0), 12, 4);
  } else {
    mesh_oracle::grid_quads(s, glm::vec3(-20, ceiling_y, 6), glm::vec3(0, 0, -60), glm::vec3(40, 0, 0), 6, 4);
  }
  const std::uint32_t first_slab = 1;
  // Slabs 2.5 m wide and 10 m deep, each one quad facing down, above and below the ceiling.
  const int columns = 5;
  for (int level = 0; level < 2; ++level)
    for (int i = 0; i < columns; ++i) {
      const float x = -7.0f + 3.0f * i, y = level == 0 ? above_y : below_y;
      s.begin_object();
      mesh_oracle::grid_quads(s, glm::vec3(x, y, -2.0f), glm::vec3(0, 0, -10), glm::vec3(2.5f, 0, 0), 1, 1);
    }
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), {});
  if (v.tjunctions) CHECK_MSG(culler.stats().triangles_cut > 0, "%s: no triangle cut at a T-junction", v.name);
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> visible;
  std::size_t must = 0, must_failed = 0, seen_below = 0, hidden = 0;
  for (int e = 0; e < 40; ++e) {
    const glm::vec3 eye(rng.uniform(-2.0f, 2.0f), rng.uniform(0.0f, 0.4f), rng.uniform(2.0f, 4.0f));
    const glm::vec3 target(rng.uniform(-2.0f, 2.0f), rng.uniform(0.6f, 1.0f), -10.0f);
    const cullkit::Camera cam = cullkit::support::make_camera(eye, target, rng.uniform(50.0f, 70.0f), 1280, 720, 0.1f, 200.0f);
    const glm::dvec3 forward = glm::normalize(glm::dvec3(target) - glm::dvec3(eye));
    const mesh_oracle::NearSide ns{glm::dvec3(eye), forward, 0.1};
    culler.cull(cam, context, visible);
    std::vector<char> is_visible(s.objects.size(), 0);
    for (std::uint32_t o : visible) is_visible[o] = 1;
    for (std::uint32_t o = first_slab; o < s.objects.size(); ++o) {
      const bool above = o < first_slab + columns;
      if (!is_visible[o]) {
        ++hidden;
        CHECK_MSG(!mesh_oracle::find_sighting(s, ns, cam, o, 16, 200, rng), "%s eye %d: slab %u hidden but a ray sees it",
                  v.name, e, o);
      } else if (!above) {
        ++seen_below;
      }
      if (!above || !context.stats().occlusion_enabled) continue;
      // The slab's corners: its nearest depth, and the ceiling's depth on the ray to its far corners.
      const cullkit::MeshObject& r = s.objects[o];
      double nearest = HUGE_VAL, ceiling_far = 0.0;
      for (std::uint32_t k = 3 * r.first_triangle; k < 3 * (r.first_triangle + r.triangle_count); ++k) {
        const glm::dvec3 p(s.positions[s.indices[k]]);
        nearest = std::min(nearest, glm::dot(p - glm::dvec3(eye), forward));
        ceiling_far = std::max(ceiling_far, ceiling_depth_towards(glm::dvec3(eye), forward, p));
      }
      // Only slabs whose rectangle test cannot hide them count: the ceiling is well beyond the
      // slab's nearest corner somewhere on the slab's rectangle.
      if (!(ceiling_far > 1.2 * nearest)) continue;
      ++must;
      must_failed += is_visible[o] ? 1u : 0u;
    }
  }
  std::printf("%-16s slabs behind the ceiling beyond their rectangle's reach: %zu, visible %zu; hidden in all %zu; "
              "slabs below seen %zu\n",
              v.name, must, must_failed, hidden, seen_below);
  CHECK_MSG(must >= 100, "%s: the must-hide rule applied to only %zu slabs", v.name, must);
  CHECK_MSG(must_failed == 0, "%s: %zu slabs behind the ceiling kept", v.name, must_failed);
  CHECK_MSG(seen_below >= 40, "%s: only %zu slabs below the ceiling kept: the oracle has too few seen cases", v.name,
            seen_below);
}

}  // namespace

int main() {
  run_variant({"ceiling_grid", false}, 77);
  run_variant({"ceiling_tjunctions", true}, 78);
  return cullkit_test::report("test_mesh_occlusion_slanted");
}
