// Occluder fusion: one wall given as 2 triangles (both diagonals, welded or not), as a finely
// triangulated mesh with jittered inner vertices, as several objects sharing edges, as a curved
// triangulated wall, and as two halves meeting in T-junctions (one big triangle's edge against the
// edges of several small triangles, along an axis or a slanted seam, within one object or across
// two). From many eyes, every cube whose screen rectangle (widened by three cells) lies on the wall
// must be hidden, and every cube the culler hides must be unseen by the brute-force oracle (cubes
// peeking past the wall's edges among them). The T-junction walls are also culled without the
// T-junction cuts (the control): then cubes behind the seam must stay visible, or the variant would
// not test the cuts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

using cullkit::support::Rng;
using mesh_oracle::TestScene;

namespace {

constexpr float kWallX = 4.0f, kWallY0 = 0.0f, kWallY1 = 3.0f;

// The flat wall at z = 0 facing +z, an nx x ny grid of quads; `objects_x` vertical strips become
// separate objects; `jitter` moves inner vertices within the plane; `weld` shares vertex indices.
void flat_wall(TestScene& s, int nx, int ny, int objects_x, float jitter, bool other_diagonal, Rng& rng) {
  std::vector<glm::vec3> grid;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      glm::vec3 p(-kWallX + 2 * kWallX * i / nx, kWallY0 + (kWallY1 - kWallY0) * j / ny, 0.0f);
      if (i > 0 && i < nx && j > 0 && j < ny) {
        p.x += jitter * rng.uniform(-1.0f, 1.0f) * (2 * kWallX / nx);
        p.y += jitter * rng.uniform(-1.0f, 1.0f) * ((kWallY1 - kWallY0) / ny);
      }
      grid.push_back(p);
    }
  const auto at = [&](int i, int j) { return grid[static_cast<std::size_t>(j * (nx + 1) + i)]; };
  for (int strip = 0; strip < objects_x; ++strip) {
    s.begin_object();
    for (int i = strip * nx / objects_x; i < (strip + 1) * nx / objects_x; ++i)
      for (int j = 0; j < ny; ++j) {
        const glm::vec3 a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
        if (!other_diagonal) {
          s.triangle(a, b, c);
          s.triangle(a, c, d);
        } else {
          s.triangle(a, b, d);
          s.triangle(b, c, d);
        }
      }
  }
}

// A curved wall: a cylinder arc of radius r around the z axis point (0, 0, 6), seen from inside
// (the eyes stand near its axis), facing inward, as `segments` x `ny` quads over 120 degrees.
void curved_wall(TestScene& s, int segments, int ny, int objects) {
  const float r = 6.0f;
  const auto at = [&](int i, int j) {
    const float a = glm::radians(-60.0f + 120.0f * i / segments);
    return glm::vec3(r * std::sin(a), kWallY0 + (kWallY1 - kWallY0) * j / ny, 6.0f - r * std::cos(a));
  };
  for (int o = 0; o < objects; ++o) {
    s.begin_object();
    for (int i = o * segments / objects; i < (o + 1) * segments / objects; ++i)
      for (int j = 0; j < ny; ++j) {
        // Counter-clockwise seen from the axis side (+z of the arc's middle).
        s.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
        s.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
  }
}

// The flat wall as two halves meeting along a seam from (x0, 0) to (x1, 3): the left half is two
// big triangles, one of whose edges is the whole seam; the right half is `pieces` strips whose
// corners lie on the seam at exactly representable points (the seam's ends are chosen so), so the
// big edge meets the small triangles' edges in T-junctions. `two_objects`: the halves are separate
// objects.
void tjunction_wall(TestScene& s, float x0, float x1, int pieces, bool two_objects) {
  const glm::vec3 a(-kWallX, kWallY0, 0.0f), b(x0, kWallY0, 0.0f), c(x1, kWallY1, 0.0f), d(-kWallX, kWallY1, 0.0f);
  s.begin_object();
  s.triangle(a, b, c);  // b -> c is the seam
  s.triangle(a, c, d);
  if (two_objects) s.begin_object();
  for (int k = 0; k < pieces; ++k) {
    const float t0 = float(k) / float(pieces), t1 = float(k + 1) / float(pieces);
    const glm::vec3 s0(x0 + (x1 - x0) * t0, kWallY0 + (kWallY1 - kWallY0) * t0, 0.0f);
    const glm::vec3 s1(x0 + (x1 - x0) * t1, kWallY0 + (kWallY1 - kWallY0) * t1, 0.0f);
    const glm::vec3 r0(kWallX, s0.y, 0.0f), r1(kWallX, s1.y, 0.0f);
    s.triangle(s0, r0, r1);
    s.triangle(s0, r1, s1);  // s1 -> s0 runs against the seam
  }
}

struct Variant {
  std::string name;
  std::function<void(TestScene&, Rng&)> wall;
  bool curved;
  bool tjunction = false;  // also run the control without T-junction cuts
};

}  // namespace

int main() {
  const std::vector<Variant> variants = {
      {"quad", [](TestScene& s, Rng& rng) { flat_wall(s, 1, 1, 1, 0.0f, false, rng); }, false},
      {"quad_other_diagonal", [](TestScene& s, Rng& rng) { flat_wall(s, 1, 1, 1, 0.0f, true, rng); }, false},
      {"fine_jittered", [](TestScene& s, Rng& rng) { flat_wall(s, 16, 9, 1, 0.35f, false, rng); }, false},
      {"two_objects", [](TestScene& s, Rng& rng) { flat_wall(s, 2, 1, 2, 0.0f, false, rng); }, false},
      {"many_objects_jittered", [](TestScene& s, Rng& rng) { flat_wall(s, 8, 6, 8, 0.3f, true, rng); }, false},
      {"curved", [](TestScene& s, Rng&) { curved_wall(s, 24, 4, 1); }, true},
      {"curved_objects", [](TestScene& s, Rng&) { curved_wall(s, 24, 4, 6); }, true},
      {"tjunction_axis", [](TestScene& s, Rng&) { tjunction_wall(s, 0.0f, 0.0f, 3, false); }, false, true},
      {"tjunction_slanted_objects", [](TestScene& s, Rng&) { tjunction_wall(s, -1.0f, 1.0f, 4, true); }, false, true},
  };
  // Depth bands of one distinct depth each: the cubes stand only 10% behind the curved wall, and
  // this test is about fusion, not about how coarse bands may be.
  cullkit::MeshOcclusionParams params;
  params.depth_band_ratio = 0.0f;
  std::size_t total_must = 0, total_hidden = 0, total_peek_visible = 0;
  for (std::size_t vi = 0; vi < variants.size(); ++vi) {
    const Variant& variant = variants[vi];
    Rng rng(1000 + vi);
    TestScene s;
    variant.wall(s, rng);
    const auto wall_objects = static_cast<std::uint32_t>(s.objects.size());
    // Cubes: a grid behind the wall (on every seam of the coarse variants too), and peeking ones
    // across the wall's left, right and top edges.
    std::vector<std::uint32_t> peeking;
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 9; ++i) {
        const float x = -3.0f + 0.75f * i, y = 0.4f + 0.55f * j;
        if (!variant.curved) {
          s.box(glm::vec3(x - 0.1f, y - 0.1f, -1.2f - 0.1f * j), glm::vec3(x + 0.1f, y + 0.1f, -1.0f - 0.1f * j));
        } else {
          const float a = glm::radians(-40.0f + 10.0f * i), r = 6.8f + 0.2f * j;
          const glm::vec3 c(r * std::sin(a), y, 6.0f - r * std::cos(a));
          s.box(c - glm::vec3(0.1f), c + glm::vec3(0.1f));
        }
      }
    if (!variant.curved) {
      for (int j = 0; j < 3; ++j) {
        const float y = 0.6f + j;
        peeking.push_back(s.box(glm::vec3(kWallX - 0.15f, y, -1.0f), glm::vec3(kWallX + 0.15f, y + 0.3f, -0.7f)));
        peeking.push_back(s.box(glm::vec3(-kWallX - 0.15f, y, -1.0f), glm::vec3(-kWallX + 0.15f, y + 0.3f, -0.7f)));
      }
      for (int i = 0; i < 3; ++i)
        peeking.push_back(s.box(glm::vec3(-2.0f + 2.0f * i, kWallY1 - 0.1f, -0.6f), glm::vec3(-1.7f + 2.0f * i, kWallY1 + 0.2f, -0.3f)));
    }
    const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), params);
    cullkit::MeshOcclusionContext context;
    std::vector<std::uint32_t> visible;
    std::size_t must = 0, must_failed = 0, hidden = 0, peek_visible = 0;
    std::vector<std::pair<cullkit::Camera, mesh_oracle::NearSide>> cameras;  // for the control
    for (int e = 0; e < 24; ++e) {
      const glm::vec3 eye = variant.curved ? glm::vec3(rng.uniform(-1.0f, 1.0f), rng.uniform(1.0f, 2.0f), 6.0f + rng.uniform(-1.0f, 1.0f))
                                           : glm::vec3(rng.uniform(-1.5f, 1.5f), rng.uniform(1.0f, 2.0f), rng.uniform(3.0f, 8.0f));
      const glm::vec3 target = variant.curved ? glm::vec3(rng.uniform(-1.0f, 1.0f), 1.5f, 0.0f)
                                              : glm::vec3(rng.uniform(-1.0f, 1.0f), rng.uniform(1.0f, 2.0f), 0.0f);
      const float fov = rng.uniform(60.0f, 90.0f);
      const cullkit::Camera cam = cullkit::support::make_camera(eye, target, fov, 1280, 720, 0.1f, 100.0f);
      const mesh_oracle::NearSide ns{glm::dvec3(eye), glm::normalize(glm::dvec3(target) - glm::dvec3(eye)), 0.1};
      cameras.emplace_back(cam, ns);
      culler.cull(cam, context, visible);
      std::vector<char> is_visible(s.objects.size(), 0);
      for (std::uint32_t o : visible) is_visible[o] = 1;
      for (std::uint32_t o = wall_objects; o < s.objects.size(); ++o) {
        const bool peek = std::find(peeking.begin(), peeking.end(), o) != peeking.end();
        if (!is_visible[o]) {
          ++hidden;
          const bool seen = mesh_oracle::find_sighting(s, ns, cam, o, 16, 200, rng);
          CHECK_MSG(!seen, "%s eye %d: object %u hidden but a ray sees it", variant.name.c_str(), e, o);
        } else if (peek) {
          ++peek_visible;
        }
        if (!peek && mesh_oracle::covered_in_front(s, cam, ns, o, 0, wall_objects, params.grid_width, params.grid_height, HUGE_VAL)) {
          ++must;
          if (is_visible[o]) ++must_failed;
        }
      }
    }
    std::printf("%-22s cubes on the wall %4zu, of them reported visible %zu; hidden %zu; peeking visible %zu\n",
                variant.name.c_str(), must, must_failed, hidden, peek_visible);
    CHECK_MSG(must_failed == 0, "%s: %zu cubes behind the wall not hidden", variant.name.c_str(), must_failed);
    CHECK_MSG(must > 60, "%s: the must-hide rule applied to only %zu cubes", variant.name.c_str(), must);
    if (variant.tjunction) {
      // The control: the same wall and cameras without the cuts. Cubes behind the seam then touch
      // the seam's outline cells and stay visible.
      cullkit::MeshOcclusionParams uncut = params;
      uncut.cut_tjunctions = false;
      const cullkit::MeshOcclusionCuller<glm::vec3> control(s.mesh(), s.objects.data(), s.objects.size(), uncut);
      CHECK(culler.stats().triangles_cut == 1 && control.stats().triangles_cut == 0);
      std::size_t control_failed = 0;
      for (const auto& [cam, ns] : cameras) {
        control.cull(cam, context, visible);
        std::vector<char> is_visible(s.objects.size(), 0);
        for (std::uint32_t o : visible) is_visible[o] = 1;
        for (std::uint32_t o = wall_objects; o < s.objects.size(); ++o)
          if (is_visible[o] && mesh_oracle::covered_in_front(s, cam, ns, o, 0, wall_objects, params.grid_width, params.grid_height, HUGE_VAL))
            ++control_failed;
      }
      std::printf("%-22s without T-junction cuts: %zu of those cubes reported visible\n", "", control_failed);
      CHECK_MSG(control_failed >= 24, "%s: only %zu cubes on the wall visible without the cuts", variant.name.c_str(),
                control_failed);
    }
    total_must += must;
    total_hidden += hidden;
    total_peek_visible += peek_visible;
  }
  CHECK(total_must > 500);
  CHECK(total_hidden > 600);
  CHECK(total_peek_visible > 60);
  return cullkit_test::report("test_mesh_occlusion_fusion");
}
