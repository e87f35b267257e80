// MeshOcclusionCuller against brute force: many random small scenes (closed boxes, walls made of
// jittered triangle grids cut into objects, random triangle soups), many random cameras (both depth
// ranges, reversed-Z, infinite far planes, near planes from 0.01 to 2, eyes inside objects, eyes
// nearer a wall than the near plane, eyes beside a wall that reaches behind them, views grazing a
// wall), random grid sizes. For every object the culler hides, dense and jittered rays over its
// screen rectangle must all meet another object's front face first (beyond the near plane). The
// test also counts what it hid and how many visible objects the oracle confirms, so it shows it can
// fail: hiding any of those would be caught.
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

glm::vec3 random_unit(Rng& rng) {
  for (;;) {
    const glm::vec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const float l = glm::length(v);
    if (l > 0.1f && l <= 1.0f) return v / l;
  }
}

// A planar grid wall of nx x ny quads with in-plane jitter, centred at c, cut into `pieces` objects.
void wall(TestScene& s, Rng& rng, const glm::vec3& c, const glm::vec3& normal, float w, float h, int nx, int ny,
          int pieces, float jitter) {
  glm::vec3 u = glm::normalize(glm::cross(normal, std::fabs(normal.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
  glm::vec3 v = glm::cross(normal, u);  // (u, v, normal) right-handed: u x v = normal, CCW seen from +normal
  std::vector<glm::vec3> g;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      float a = -0.5f + float(i) / nx, b = -0.5f + float(j) / ny;
      if (i > 0 && i < nx && j > 0 && j < ny) {
        a += jitter * rng.uniform(-0.5f, 0.5f) / nx;
        b += jitter * rng.uniform(-0.5f, 0.5f) / ny;
      }
      g.push_back(c + u * (a * w) + v * (b * h));
    }
  const auto at = [&](int i, int j) { return g[static_cast<std::size_t>(j * (nx + 1) + i)]; };
  for (int p = 0; p < pieces; ++p) {
    s.begin_object();
    for (int j = p * ny / pieces; j < (p + 1) * ny / pieces; ++j)
      for (int i = 0; i < nx; ++i) {
        if (rng.uniform() < 0.5f) {
          s.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
          s.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
        } else {
          s.triangle(at(i, j), at(i + 1, j), at(i, j + 1));
          s.triangle(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
        }
      }
    if (s.objects.back().triangle_count == 0) s.objects.pop_back();
  }
}

TestScene random_scene(Rng& rng, std::vector<std::pair<glm::vec3, glm::vec3>>& walls) {
  TestScene s;
  const int boxes = rng.range(2, 14);
  for (int i = 0; i < boxes; ++i) {
    const glm::vec3 c(rng.uniform(-8, 8), rng.uniform(-3, 3), rng.uniform(-8, 8));
    const glm::vec3 e(rng.uniform(0.1f, 2.5f), rng.uniform(0.1f, 2.5f), rng.uniform(0.1f, 2.5f));
    s.box(c - e, c + e);
  }
  const int wall_count = rng.range(1, 4);
  for (int i = 0; i < wall_count; ++i) {
    const glm::vec3 c(rng.uniform(-6, 6), rng.uniform(-2, 2), rng.uniform(-6, 6));
    const glm::vec3 n = random_unit(rng);
    walls.emplace_back(c, n);
    const float ww = rng.uniform(3, 14), wh = rng.uniform(2, 8);
    wall(s, rng, c, n, ww, wh, rng.range(1, 6), rng.range(1, 5), rng.range(1, 3), rng.uniform() < 0.5f ? 0.0f : 0.8f);
    // Boxes behind it, some peeking past its edges.
    const int behind = rng.range(1, 5);
    for (int b = 0; b < behind; ++b) {
      const glm::vec3 p = c - n * rng.uniform(0.3f, 4.0f) + random_unit(rng) * (0.5f * std::min(ww, wh) * rng.uniform(0.2f, 1.3f));
      const glm::vec3 e(rng.uniform(0.05f, 1.0f), rng.uniform(0.05f, 1.0f), rng.uniform(0.05f, 1.0f));
      s.box(p - e, p + e);
    }
  }
  const int soups = rng.range(0, 6);
  for (int i = 0; i < soups; ++i) {
    s.begin_object();
    const glm::vec3 c(rng.uniform(-8, 8), rng.uniform(-3, 3), rng.uniform(-8, 8));
    const float size = rng.uniform(0.3f, 6.0f);
    const int n = rng.range(1, 10);
    for (int t = 0; t < n; ++t)
      s.triangle(c + random_unit(rng) * size * rng.uniform(), c + random_unit(rng) * size * rng.uniform(),
                 c + random_unit(rng) * size * rng.uniform());
  }
  return s;
}

}  // namespace

int main() {
  std::size_t cameras = 0, hidden = 0, occluded = 0, confirmed_visible = 0, disabled = 0, violations = 0;
  const int scene_count = 300, cameras_per_scene = 16;
  for (int sc = 0; sc < scene_count; ++sc) {
    Rng rng(0x3e5ull * 7919u + std::uint64_t(sc));
    std::vector<std::pair<glm::vec3, glm::vec3>> walls;
    const TestScene s = random_scene(rng, walls);
    cullkit::MeshOcclusionParams params;
    if (sc % 3 == 1) {
      params.grid_width = rng.range(8, 64);
      params.grid_height = rng.range(8, 64);
    } else if (sc % 3 == 2) {
      params.grid_width = rng.range(200, 400);
      params.grid_height = rng.range(100, 300);
    }
    params.min_occluder_screen_fraction = sc % 2 ? 0.0f : 0.0005f;
    const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), params);
    cullkit::MeshOcclusionContext context;
    std::vector<std::uint32_t> visible;
    for (int ci = 0; ci < cameras_per_scene; ++ci) {
      glm::vec3 eye(rng.uniform(-12, 12), rng.uniform(-5, 5), rng.uniform(-12, 12));
      glm::vec3 target(rng.uniform(-6, 6), rng.uniform(-2, 2), rng.uniform(-6, 6));
      float near_plane = std::vector<float>{0.01f, 0.1f, 0.5f, 2.0f}[std::size_t(rng.range(0, 3))];
      const int kind = rng.range(0, 9);
      if (kind == 0 && !walls.empty()) {
        // Nearer a wall than the near plane, looking at it.
        const auto& w = walls[std::size_t(rng.range(0, int(walls.size()) - 1))];
        eye = w.first + w.second * (near_plane * rng.uniform(0.1f, 0.9f));
        target = w.first - w.second * 5.0f + random_unit(rng) * 0.5f;
      } else if (kind == 1 && !walls.empty()) {
        // Grazing: the eye in (or next to) a wall's plane.
        const auto& w = walls[std::size_t(rng.range(0, int(walls.size()) - 1))];
        const glm::vec3 along = glm::normalize(glm::cross(w.second, random_unit(rng)));
        eye = w.first + along * rng.uniform(4.0f, 12.0f) + w.second * (rng.uniform() < 0.5f ? 0.0f : rng.uniform(-0.01f, 0.01f));
        target = w.first - along * 2.0f;
      } else if (kind >= 3 && kind <= 6 && !walls.empty()) {
        // In front of a wall, looking at it.
        const auto& w = walls[std::size_t(rng.range(0, int(walls.size()) - 1))];
        eye = w.first + w.second * rng.uniform(0.5f, 10.0f) + random_unit(rng) * rng.uniform(0.0f, 2.0f);
        target = w.first + random_unit(rng) * rng.uniform(0.0f, 2.0f);
      } else if (kind == 7 && !walls.empty()) {
        // Beside a wall that reaches behind the eye, looking along it at a slant: its triangles
        // cross the near plane and are clipped there.
        const auto& w = walls[std::size_t(rng.range(0, int(walls.size()) - 1))];
        const glm::vec3 along = glm::normalize(glm::cross(w.second, random_unit(rng)));
        eye = w.first + along * rng.uniform(-1.0f, 1.0f) + w.second * rng.uniform(0.02f, 1.5f);
        target = w.first - along * rng.uniform(3.0f, 8.0f) - w.second * rng.uniform(0.0f, 3.0f);
      } else if (kind == 2) {
        // Inside an object's box (or a box's surface).
        const cullkit::MeshObject& o = s.objects[std::size_t(rng.range(0, int(s.objects.size()) - 1))];
        eye = s.positions[s.indices[3 * o.first_triangle]] * 0.999f;
      }
      if (glm::length(target - eye) < 0.5f) target = eye + glm::vec3(0.3f, 0.1f, 1.0f);
      const float far_plane = std::vector<float>{0.0f, 50.0f, 1000.0f}[std::size_t(rng.range(0, 2))];
      const auto depth = rng.uniform() < 0.5f ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one;
      const bool reversed = rng.uniform() < 0.3f;
      const int w = std::vector<int>{64, 320, 1920, 100}[std::size_t(rng.range(0, 3))];
      const int h = std::vector<int>{64, 180, 1080, 300}[std::size_t(rng.range(0, 3))];
      const cullkit::Camera cam = cullkit::support::make_camera(eye, target, rng.uniform(30, 110), w, h, near_plane,
                                                               far_plane, depth, reversed);
      const mesh_oracle::NearSide ns{glm::dvec3(eye), glm::normalize(glm::dvec3(target) - glm::dvec3(eye)), double(near_plane)};
      culler.cull(cam, context, visible);
      ++cameras;
      disabled += !context.stats().occlusion_enabled;
      occluded += context.stats().objects_hidden;
      std::vector<char> is_visible(s.objects.size(), 0);
      for (std::uint32_t o : visible) {
        CHECK(o < s.objects.size());
        if (o < s.objects.size()) {
          CHECK_MSG(!is_visible[o], "object %u written twice", o);
          is_visible[o] = 1;
        }
      }
      for (std::uint32_t o = 0; o < s.objects.size(); ++o) {
        const bool seen = mesh_oracle::find_sighting(s, ns, cam, o, 12, is_visible[o] ? 40 : 300, rng);
        if (!is_visible[o]) {
          ++hidden;
          if (seen) ++violations;
          CHECK_MSG(!seen, "scene %d camera %d: object %u hidden but seen (grid %dx%d)", sc, ci, o, params.grid_width,
                    params.grid_height);
        } else if (seen) {
          ++confirmed_visible;
        }
      }
    }
  }
  std::printf("cameras %zu (occlusion off for %zu), objects left out %zu (by occlusion %zu), violations %zu, "
              "visible objects the oracle sees %zu\n",
              cameras, disabled, hidden, occluded, violations, confirmed_visible);
  // Non-vacuous: the culler hides things, and the oracle sees many objects, each of which it would
  // have flagged had the culler hidden it.
  CHECK(occluded > 3000);
  CHECK(confirmed_visible > 10000);
  return cullkit_test::report("test_mesh_occlusion_bruteforce");
}
