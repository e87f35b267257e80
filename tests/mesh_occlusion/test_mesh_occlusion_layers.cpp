// Per-patch layers (MeshOcclusionParams::patch_layers). A floor runs from in front of the eye far
// behind a wall that stands on it. The floor's triangles reach nearer than the wall, so they go in
// first, and on the union's grid the cells where the wall stands in front of the far floor freeze at
// the floor's far depth there. Cubes behind the wall, standing on the floor or floating, whose
// screen rectangle (widened by three cells) lies on the wall well in front of them, must be hidden:
// the wall's patch alone covers those cells at the wall's own depth. Every hidden cube must be unseen
// by the brute-force ray oracle. The same scenes and cameras without the layers are the control:
// there some of those cubes must stay visible, or the scenes would not test the layers.
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

// A planar grid of quads as one object (mesh_oracle::grid_quads).
void quad_grid(TestScene& s, const glm::vec3& origin, const glm::vec3& u, const glm::vec3& v, int nu, int nv) {
  s.begin_object();
  mesh_oracle::grid_quads(s, origin, u, v, nu, nv);
}

struct Variant {
  const char* name;
  int floor_cells, wall_x, wall_y;
};

struct Tally {
  std::size_t must = 0, must_failed = 0, control_failed = 0, hidden = 0, peeking_visible = 0;
};

void run_variant(const Variant& v, std::uint64_t seed, Tally& total) {
  Rng rng(seed);
  TestScene s;
  // The floor (y = 0, facing up) from z = 3, in front of every eye below, to z = -40; the wall
  // (z = 0, facing +z) stands on it.
  quad_grid(s, glm::vec3(-20, 0, 3), glm::vec3(40, 0, 0), glm::vec3(0, 0, -43), v.floor_cells, v.floor_cells);
  quad_grid(s, glm::vec3(-4, 0, 0), glm::vec3(8, 0, 0), glm::vec3(0, 3, 0), v.wall_x, v.wall_y);
  const std::uint32_t wall = 1, first_cube = 2;
  for (int i = 0; i < 7; ++i)
    for (int k = 0; k < 4; ++k) {
      const float x = -3.0f + 1.0f * i, z = -0.8f - 1.1f * k;
      s.box(glm::vec3(x - 0.15f, 0.0f, z - 0.15f), glm::vec3(x + 0.15f, 0.3f, z + 0.15f));  // on the floor
      s.box(glm::vec3(x - 0.1f, 1.2f, z - 0.1f), glm::vec3(x + 0.1f, 1.4f, z + 0.1f));      // floating
    }
  // Cubes across the wall's side and top edges, partly seen from most eyes, and cubes on the floor
  // in front of the wall, seen: the oracle's cases.
  const auto first_peeking = static_cast<std::uint32_t>(s.objects.size());
  for (int i = 0; i < 5; ++i) s.box(glm::vec3(-2.2f + i, 0.0f, 1.2f), glm::vec3(-1.9f + i, 0.3f, 1.5f));
  for (int k = 0; k < 3; ++k) {
    const float z = -0.8f - 1.5f * k;
    s.box(glm::vec3(3.85f, 0.0f, z - 0.15f), glm::vec3(4.15f, 0.3f, z + 0.15f));
    s.box(glm::vec3(-4.15f, 0.0f, z - 0.15f), glm::vec3(-3.85f, 0.3f, z + 0.15f));
    s.box(glm::vec3(-1.0f + k, 2.9f, z - 0.1f), glm::vec3(-0.8f + k, 3.4f, z + 0.1f));
  }
  cullkit::MeshOcclusionParams params;
  cullkit::MeshOcclusionParams control_params = params;
  control_params.patch_layers = false;
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), params);
  const cullkit::MeshOcclusionCuller<glm::vec3> control(s.mesh(), s.objects.data(), s.objects.size(), control_params);
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> visible, control_visible;
  Tally t;
  for (int e = 0; e < 24; ++e) {
    const glm::vec3 eye(rng.uniform(-1.5f, 1.5f), rng.uniform(1.2f, 2.2f), rng.uniform(4.0f, 9.0f));
    const glm::vec3 target(rng.uniform(-1.0f, 1.0f), rng.uniform(0.3f, 1.5f), 0.0f);
    const cullkit::Camera cam = cullkit::support::make_camera(eye, target, rng.uniform(50.0f, 80.0f), 1280, 720, 0.1f, 100.0f);
    const mesh_oracle::NearSide ns{glm::dvec3(eye), glm::normalize(glm::dvec3(target) - glm::dvec3(eye)), 0.1};
    culler.cull(cam, context, visible);
    control.cull(cam, context, control_visible);
    std::vector<char> is_visible(s.objects.size(), 0), control_is_visible(s.objects.size(), 0);
    for (std::uint32_t o : visible) is_visible[o] = 1;
    for (std::uint32_t o : control_visible) control_is_visible[o] = 1;
    for (std::uint32_t o = first_cube; o < s.objects.size(); ++o) {
      if (o >= first_peeking) {
        t.peeking_visible += is_visible[o] ? 1u : 0u;
      }
      if (!is_visible[o]) {
        ++t.hidden;
        CHECK_MSG(!mesh_oracle::find_sighting(s, ns, cam, o, 16, 200, rng), "%s eye %d: cube %u hidden but a ray sees it",
                  v.name, e, o);
      }
      if (!control_is_visible[o])
        CHECK_MSG(!mesh_oracle::find_sighting(s, ns, cam, o, 16, 200, rng),
                  "%s eye %d: cube %u hidden without layers but a ray sees it", v.name, e, o);
      if (o >= first_peeking) continue;
      if (!mesh_oracle::covered_in_front(s, cam, ns, o, wall, 1, params.grid_width, params.grid_height, 0.9)) continue;
      ++t.must;
      t.must_failed += is_visible[o] ? 1u : 0u;
      t.control_failed += control_is_visible[o] ? 1u : 0u;
    }
  }
  std::printf("%-22s cubes on the wall %4zu: visible with layers %zu, without %zu; hidden %zu, peeking visible %zu\n",
              v.name, t.must, t.must_failed, t.control_failed, t.hidden, t.peeking_visible);
  CHECK_MSG(t.must_failed == 0, "%s: %zu cubes behind the wall not hidden", v.name, t.must_failed);
  CHECK_MSG(t.must >= 100, "%s: the must-hide rule applied to only %zu cubes", v.name, t.must);
  CHECK_MSG(t.peeking_visible >= 24, "%s: only %zu peeking cubes visible", v.name, t.peeking_visible);
  total.must += t.must;
  total.control_failed += t.control_failed;
  total.hidden += t.hidden;
}

}  // namespace

int main() {
  const Variant variants[] = {
      {"floor_quad_wall_quad", 1, 1, 1},
      {"floor_grid_wall_grid", 6, 8, 3},
      {"floor_fine_wall_fine", 12, 16, 6},
  };
  Tally total;
  std::uint64_t seed = 500;
  for (const Variant& v : variants) run_variant(v, seed++, total);
  // The control: without the layers the union's far floor depth keeps cubes visible.
  std::printf("all variants: %zu cubes on the wall, %zu of them visible without layers\n", total.must,
              total.control_failed);
  CHECK_MSG(total.control_failed >= 30, "only %zu cubes on the wall visible without layers: the scenes do not test them",
            total.control_failed);
  return cullkit_test::report("test_mesh_occlusion_layers");
}
