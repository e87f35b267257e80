// Occluder triangles clipped at the near plane. A floor and a side wall run from behind the eye far
// into the scene, so every one of their triangles crosses the near plane (a culler that drops such
// triangles hides nothing behind them). Cubes under the floor and behind the wall whose screen
// rectangle (widened by three cells) lies on the floor or the wall, well nearer than the cube, must
// be hidden; every hidden cube must be unseen by the brute-force ray oracle. The occluders come as
// 2 triangles each and as jittered, welded grids cut into objects (clipped edges shared by two
// triangles, in one object and across objects), under OpenGL and Direct3D depth, reversed-Z and
// infinite far planes, with eyes from 0.05 to 1.5 units beside the wall.
//
// Two white-box checks on the clipping itself: two triangles sharing a clipped edge get
// bit-identical clip points on it (else the shared edge would not cancel), and every clip point is
// beyond the near plane by at least the per-point margin that `View::project` demands.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit/detail/mesh_occlusion/query.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

using cullkit::support::Rng;
using mesh_oracle::TestScene;
namespace dmo = cullkit::detail::mesh_occlusion;

namespace {

// A planar nu x nv grid of quads from `origin` along u and v (counter-clockwise seen from u x v),
// inner vertices jittered within the plane, cut into `objects` strips along u.
void grid(TestScene& s, Rng& rng, const glm::vec3& origin, const glm::vec3& u, const glm::vec3& v, int nu, int nv,
          int objects, float jitter) {
  std::vector<glm::vec3> g;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      float a = float(i) / nu, b = float(j) / nv;
      if (i > 0 && i < nu && j > 0 && j < nv) {
        a += jitter * rng.uniform(-0.5f, 0.5f) / nu;
        b += jitter * rng.uniform(-0.5f, 0.5f) / nv;
      }
      g.push_back(origin + u * a + v * b);
    }
  const auto at = [&](int i, int j) { return g[static_cast<std::size_t>(j * (nu + 1) + i)]; };
  for (int o = 0; o < objects; ++o) {
    s.begin_object();
    for (int i = o * nu / objects; i < (o + 1) * nu / objects; ++i)
      for (int j = 0; j < nv; ++j) {
        s.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
        s.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      }
  }
}

constexpr float kWallX = -3.0f;

// The floor y = 0 facing up, or the wall x = kWallX facing +x, from z = 10 (behind every eye) to
// z = -30. Returns the number of occluder objects (they come first). One occluder per scene: a
// floor behind a wall would freeze the cells they share at the depth of whichever goes in first
// (the depth bands' rule), which is not what this test is about.
std::uint32_t occluders(TestScene& s, Rng& rng, bool wall, int n, int objects, float jitter) {
  if (!wall) grid(s, rng, glm::vec3(-20, 0, 10), glm::vec3(40, 0, 0), glm::vec3(0, 0, -40), n, n, objects, jitter);
  else grid(s, rng, glm::vec3(kWallX, -4, 10), glm::vec3(0, 0, -40), glm::vec3(0, 12, 0), n, std::max(1, n / 4), objects, jitter);
  return static_cast<std::uint32_t>(s.objects.size());
}

struct CameraKind {
  const char* name;
  cullkit::DepthRange depth;
  bool reversed;
  float far_plane;
};

struct Tally {
  std::size_t must = 0, must_failed = 0, hidden = 0, violations = 0, seen_front = 0;
};

void run_variant(const char* name, bool at_wall, int n, int objects, float jitter, std::uint64_t seed, Tally& total) {
  Rng rng(seed);
  TestScene s;
  const std::uint32_t occluder_objects = occluders(s, rng, at_wall, n, objects, jitter);
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) {
      const float x = -1.6f + 0.8f * i, y = 0.6f + 0.7f * i, z = -3.0f - 2.0f * k;
      if (!at_wall) s.box(glm::vec3(x - 0.1f, -2.6f, z - 0.1f), glm::vec3(x + 0.1f, -2.4f, z + 0.1f));
      else s.box(glm::vec3(kWallX - 2.1f, y - 0.1f, z - 0.1f), glm::vec3(kWallX - 1.9f, y + 0.1f, z + 0.1f));
    }
  // Cubes on the eye's side of the occluder, some seen: the oracle checks these too.
  const std::uint32_t first_front = static_cast<std::uint32_t>(s.objects.size());
  for (int k = 0; k < 6; ++k) {
    const float z = -2.0f - 2.5f * k;
    if (!at_wall) s.box(glm::vec3(-1.0f + 0.4f * k, 0.05f, z - 0.1f), glm::vec3(-0.8f + 0.4f * k, 0.25f, z + 0.1f));
    else s.box(glm::vec3(kWallX + 0.05f, 0.5f + 0.4f * k, z - 0.1f), glm::vec3(kWallX + 0.25f, 0.7f + 0.4f * k, z + 0.1f));
  }
  // Only the floor and the wall occlude: the cubes, sorted before the floor (it goes in by its
  // farthest depth), would freeze their own cells at their own depth.
  cullkit::MeshOcclusionParams params;
  params.min_occluder_screen_fraction = 0.02f;
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), params);
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> visible;
  const CameraKind kinds[] = {{"gl", cullkit::DepthRange::negative_one_to_one, false, 100.0f},
                              {"d3d", cullkit::DepthRange::zero_to_one, false, 100.0f},
                              {"reversed", cullkit::DepthRange::zero_to_one, true, 100.0f},
                              {"reversed_infinite", cullkit::DepthRange::zero_to_one, true, 0.0f},
                              {"gl_infinite", cullkit::DepthRange::negative_one_to_one, false, 0.0f}};
  Tally tally;
  for (int e = 0; e < 20; ++e) {
    const glm::vec3 eye = at_wall ? glm::vec3(kWallX + rng.uniform(0.05f, 1.5f), rng.uniform(1.0f, 3.0f), rng.uniform(-1.0f, 1.0f))
                                  : glm::vec3(rng.uniform(-1.0f, 1.0f), rng.uniform(1.2f, 2.5f), rng.uniform(-1.0f, 1.0f));
    const glm::vec3 target = at_wall ? glm::vec3(kWallX - rng.uniform(0.5f, 2.0f), rng.uniform(0.5f, 3.0f), rng.uniform(-10.0f, -6.0f))
                                     : glm::vec3(rng.uniform(-1.5f, 1.5f), rng.uniform(-1.0f, 0.0f), rng.uniform(-9.0f, -5.0f));
    const float near_plane = e % 2 ? 0.1f : 0.02f;
    const CameraKind& kind = kinds[static_cast<std::size_t>(e) % (sizeof kinds / sizeof kinds[0])];
    const cullkit::Camera cam = cullkit::support::make_camera(eye, target, rng.uniform(50.0f, 80.0f), 1280, 720, near_plane,
                                                             kind.far_plane, kind.depth, kind.reversed);
    const mesh_oracle::NearSide ns{glm::dvec3(eye), glm::normalize(glm::dvec3(target) - glm::dvec3(eye)), double(near_plane)};
    culler.cull(cam, context, visible);
    CHECK(context.stats().occlusion_enabled);
    std::vector<char> is_visible(s.objects.size(), 0);
    for (std::uint32_t o : visible) is_visible[o] = 1;
    for (std::uint32_t o = occluder_objects; o < s.objects.size(); ++o) {
      if (!is_visible[o]) {
        ++tally.hidden;
        const bool seen = mesh_oracle::find_sighting(s, ns, cam, o, 12, 100, rng);
        tally.violations += seen;
        CHECK_MSG(!seen, "%s eye %d (%s): object %u hidden but a ray sees it", name, e, kind.name, o);
      } else if (o >= first_front) {
        tally.seen_front += mesh_oracle::find_sighting(s, ns, cam, o, 12, 40, rng);
      }
      if (o < first_front && mesh_oracle::covered_in_front(s, cam, ns, o, 0, occluder_objects, params.grid_width, params.grid_height, 0.9)) {
        ++tally.must;
        if (is_visible[o]) ++tally.must_failed;
      }
    }
  }
  std::printf("%-20s cubes that must be hidden %3zu, of them reported visible %zu; hidden %3zu; oracle violations %zu; "
              "front cubes the oracle sees %zu\n",
              name, tally.must, tally.must_failed, tally.hidden, tally.violations, tally.seen_front);
  CHECK_MSG(tally.must_failed == 0, "%s: %zu cubes behind the floor or wall not hidden", name, tally.must_failed);
  CHECK_MSG(tally.must >= 30, "%s: the must-hide rule applied to only %zu cubes", name, tally.must);
  total.must += tally.must;
  total.hidden += tally.hidden;
  total.seen_front += tally.seen_front;
}

// The detail-level culler on the fine jittered scene, its scratch read back after each frame.
void clip_points(std::uint64_t seed) {
  Rng rng(seed);
  TestScene s;
  occluders(s, rng, false, 12, 3, 0.8f);
  occluders(s, rng, true, 12, 3, 0.8f);
  dmo::MeshIndex index;
  mesh_oracle::build_test_index(s, index, 256);
  cullkit::MeshOcclusionParams params;
  params.min_occluder_screen_fraction = 0.0f;
  dmo::Scratch scratch;
  std::size_t shared = 0, identical = 0, points = 0, short_of_margin = 0;
  for (int e = 0; e < 24; ++e) {
    const glm::vec3 eye(kWallX + rng.uniform(0.05f, 2.0f), rng.uniform(0.5f, 2.5f), rng.uniform(-2.0f, 2.0f));
    const glm::vec3 target(rng.uniform(-4.0f, 2.0f), rng.uniform(-1.0f, 2.0f), rng.uniform(-10.0f, -4.0f));
    const bool reversed = e % 3 == 1;
    const cullkit::Camera cam = cullkit::support::make_camera(
        eye, target, 70.0f, 640, 360, e % 2 ? 0.1f : 0.5f, e % 4 == 3 ? 0.0f : 100.0f,
        e % 3 == 0 ? cullkit::DepthRange::negative_one_to_one : cullkit::DepthRange::zero_to_one, reversed);
    std::vector<std::uint32_t> out;
    dmo::cull(index, params, cam, scratch, out);
    const auto polygon_of = [&](std::uint32_t t) -> const dmo::ClippedPolygon* {
      if (scratch.clip_stamp[t] != scratch.frame) return nullptr;
      return &scratch.clipped[scratch.clip_slot[t]];
    };
    const auto same = [](const dmo::ClippedPolygon& p, int i, const dmo::ClippedPolygon& q, int j) {
      return p.x[i] == q.x[j] && p.y[i] == q.y[j] && p.w[i] == q.w[j];
    };
    for (std::uint32_t t = 0; t < index.corners.size() / 3; ++t) {
      const dmo::ClippedPolygon* p = polygon_of(t);
      if (!p) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
        if (twin == dmo::none || twin / 3 < t) continue;
        const dmo::ClippedPolygon* q = polygon_of(twin / 3);
        if (!q) continue;
        // The edge is clipped on both sides when both polygons run along it to a clip point: count
        // the points the two polygons have bit for bit in common (the edge's inside corner and its
        // clip point, when it is clipped).
        const std::uint32_t a = index.corners[3 * std::size_t(t) + std::size_t(k)];
        const std::uint32_t b = index.corners[3 * std::size_t(t) + std::size_t((k + 1) % 3)];
        const bool in_a = scratch.projected[scratch.vertex_slot[a]].inside, in_b = scratch.projected[scratch.vertex_slot[b]].inside;
        if (in_a == in_b) continue;
        ++shared;
        int common = 0;
        for (int i = 0; i < p->n; ++i)
          for (int j = 0; j < q->n; ++j) common += same(*p, i, *q, j);
        identical += common >= 2;
      }
    }
    // Clip points of random segments across the clipping level meet the per-point near-plane margin.
    const dmo::View& view = scratch.view;
    CHECK(view.enabled);
    for (int k = 0; k < 200 && view.enabled; ++k) {
      const std::uint32_t t = static_cast<std::uint32_t>(rng.range(0, int(index.corners.size() / 3) - 1));
      const glm::vec3& pa = index.positions[index.corners[3 * std::size_t(t)]];
      const glm::vec3& pb = index.positions[index.corners[3 * std::size_t(t) + 1]];
      const double a[3] = {pa.x, pa.y, pa.z}, b[3] = {pb.x, pb.y, pb.z};
      dmo::Projected q;
      double at[3];
      if (!view.clip_point(a, b, q, at)) continue;
      ++points;
      const double* n = view.near_plane;
      const double margin = 0x1p-18 * (std::fabs(n[0] * at[0]) + std::fabs(n[1] * at[1]) + std::fabs(n[2] * at[2]) + std::fabs(n[3]));
      const double value = view.near_value(at[0], at[1], at[2]);
      short_of_margin += !(value > 1.5 * margin && q.usable);
      // On the segment: along the edge from a, within the rounding of its coordinates.
      const glm::dvec3 da = glm::dvec3(at[0], at[1], at[2]) - glm::dvec3(a[0], a[1], a[2]);
      const glm::dvec3 ab = glm::dvec3(b[0], b[1], b[2]) - glm::dvec3(a[0], a[1], a[2]);
      CHECK(glm::length(glm::cross(da, ab)) <= 1e-12 * (glm::dot(ab, ab) + 1.0));
    }
  }
  std::printf("clip points: %zu clipped edges shared by two clipped triangles, %zu with identical points; "
              "%zu random clip points, %zu short of the near-plane margin\n",
              shared, identical, points, short_of_margin);
  CHECK(shared >= 50);
  CHECK(identical == shared);
  CHECK(points >= 50);
  CHECK(short_of_margin == 0);
}

}  // namespace

int main() {
  Tally total;
  run_variant("floor two_triangles", false, 1, 1, 0.0f, 11, total);
  run_variant("floor grid_jittered", false, 8, 1, 0.8f, 12, total);
  run_variant("floor grid_objects", false, 12, 3, 0.8f, 13, total);
  run_variant("wall two_triangles", true, 1, 1, 0.0f, 21, total);
  run_variant("wall grid_jittered", true, 8, 1, 0.8f, 22, total);
  run_variant("wall grid_objects", true, 12, 3, 0.8f, 23, total);
  clip_points(14);
  CHECK(total.must >= 200);
  // Non-vacuous: the oracle sees many objects near the clipped occluders, each of which it would
  // have flagged had the culler hidden it.
  CHECK(total.seen_front >= 200);
  return cullkit_test::report("test_mesh_occlusion_nearclip");
}
