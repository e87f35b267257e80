// Surface patches, triangle-level object tests and solid-box occluders of MeshOcclusionCuller, each
// in a scene built to need it, with the feature switched off as the control (so each check can
// fail), and every hidden object searched for by the brute-force ray oracle:
// - big_object: a ground and a wall in ONE object of more triangles than the occluder budget. Cut
//   into patches, the budget takes the wall's patches and hides the cubes behind it; as one patch
//   (patch_triangles at its maximum) the object does not fit and hides nothing.
// - slanted_beam: a finely cut beam standing on a floor behind a wall with a window. The beam's box
//   covers the window, its triangles do not: hidden by triangle tests, not by boxes
//   (object_test_triangles = 0).
// - touching_boxes: two closed boxes of different heights side by side (their front faces meet in
//   a T-junction, which the coverage grid cannot fuse); cubes behind the seam are hidden by the
//   solid-box tree, not without it (max_box_occluders = 0). Eyes nearer a box than the near plane
//   check that a box reaching into the clipped part of the frustum hides nothing it should not.
// - box_behind_wall: the same boxes with two places in the tree (max_box_occluders = 2) and a third
//   solid box, the biggest on screen, hidden on the grid behind a wall of one quad: it must leave
//   its place to the touching boxes, which then hide the cubes (with one place, the control, not).
// - far_backdrop: the same wall and cubes inside a sky dome (an inward-facing sphere of 2,048
//   triangles, one object, whose patches' boxes hold the eye). The dome is farther than every other
//   object, so it can hide none of them: it must take no part in the occluders (the same occluder
//   triangles and the same answers as without it, also from an eye 2 mm beyond the near plane from
//   the wall, where the dome's extent must not move the occluders' clipping level), and the cubes
//   stay hidden.
// - dense_wall: a wall of 10,000 small triangles with cubes behind it. From afar each of its
//   patches covers fewer cells than it has triangles, so by default the wall is no occluder and
//   hides nothing; with min_occluder_cells_per_triangle = 0 (the control) it hides the cubes. From
//   near, its patches are big on screen and hide the cubes by default too.
// - thin_slats: a wall of 20 horizontal slats, each its own object of two triangles, their long
//   edges shared with their neighbours', with cubes behind it. From afar each slat is narrower on
//   screen than min_occluder_width_cells, so by default none occludes and the cubes stay; with the
//   rule off (0, the control, and a NaN value, which is taken as 0) the slats fuse and hide them.
//   From near, the slats are wide enough and hide the cubes by default; and one wall of the same
//   size, two triangles, hides them from afar by default.
// - twin_reach: the index's note of which edges' twins a frame looks up (PatchSet::twin_reach),
//   against every patch's own triangles: an edge whose twin is in one of the patches holding the
//   triangle must be marked as in the patch, one whose twin is outside one of them as elsewhere.
//   The mesh has patches cut from one surface, a T-junction seam (cut triangles) and two objects
//   sharing triangles, so each kind of pair occurs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

using cullkit::support::Rng;
using mesh_oracle::TestScene;

namespace {

using mesh_oracle::grid_quads;

struct Tally {
  int targets = 0, hidden = 0, violations = 0;
};

// Culls from each eye with `params`; counts how many of `targets` are hidden, and checks every
// hidden object (targets or not) against the oracle.
Tally run(const TestScene& s, const std::vector<std::uint32_t>& targets, const std::vector<glm::vec3>& eyes,
          const glm::vec3& look_at, float near_plane, const cullkit::MeshOcclusionParams& params, const char* name,
          float far_plane = 200.0f) {
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size(), params);
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  Rng rng(17);
  Tally tally;
  for (std::size_t e = 0; e < eyes.size(); ++e) {
    const cullkit::Camera cam = cullkit::support::make_camera(eyes[e], look_at, 60.0f, 320, 180, near_plane, far_plane);
    culler.cull(cam, context, out);
    std::vector<char> kept(s.objects.size(), 0);
    for (std::uint32_t o : out) kept[o] = 1;
    const mesh_oracle::NearSide ns{glm::dvec3(eyes[e]), glm::normalize(glm::dvec3(look_at) - glm::dvec3(eyes[e])),
                                   double(near_plane)};
    for (std::uint32_t o = 0; o < s.objects.size(); ++o) {
      const bool target = std::find(targets.begin(), targets.end(), o) != targets.end();
      tally.targets += target;
      if (kept[o]) continue;
      tally.hidden += target;
      if (mesh_oracle::find_sighting(s, ns, cam, o, 8, 24, rng)) {
        ++tally.violations;
        CHECK_MSG(false, "%s: eye %zu, object %u hidden but seen", name, e, o);
      }
    }
  }
  std::printf("%-32s targets %3d, hidden %3d, oracle violations %d\n", name, tally.targets, tally.hidden, tally.violations);
  return tally;
}

void big_object() {
  TestScene s;
  s.begin_object();
  // Ground 60 x 60 quads (7,200 triangles) facing up, and a wall 100 x 50 quads (10,000) facing +z:
  // 17,200 triangles in one object, over the default budget of 16,384.
  grid_quads(s, glm::vec3(-15, 0, 15), glm::vec3(30, 0, 0), glm::vec3(0, 0, -30), 60, 60);
  grid_quads(s, glm::vec3(-6, 0, 0), glm::vec3(12, 0, 0), glm::vec3(0, 4, 0), 100, 50);
  std::vector<std::uint32_t> cubes;
  for (int i = -1; i <= 1; ++i)
    for (int k = 1; k <= 3; ++k)
      cubes.push_back(s.box(glm::vec3(1.5f * i - 0.3f, 0.2f, -2.0f * k - 0.3f), glm::vec3(1.5f * i + 0.3f, 1.2f, -2.0f * k + 0.3f)));
  const std::vector<glm::vec3> eyes = {{0, 1.7f, 6}, {-1, 1.7f, 8}, {1, 1.7f, 5}, {0.5f, 2.5f, 7}};
  cullkit::MeshOcclusionParams patched;
  const Tally with = run(s, cubes, eyes, glm::vec3(0, 1.5f, 0), 0.1f, patched, "big_object patches");
  cullkit::MeshOcclusionParams whole;
  whole.patch_triangles = 65536;
  const Tally without = run(s, cubes, eyes, glm::vec3(0, 1.5f, 0), 0.1f, whole, "big_object one patch");
  CHECK(with.hidden * 10 >= with.targets * 9);
  CHECK(without.hidden == 0);  // the control: the object does not fit the budget
}

void slanted_beam() {
  TestScene s;
  s.begin_object();  // floor
  grid_quads(s, glm::vec3(-10, 0, 10), glm::vec3(20, 0, 0), glm::vec3(0, 0, -20), 1, 1);
  s.begin_object();  // wall at z = 0 with a window x in [-3, -1], y in [1.5, 2.5]
  const float xs[4] = {-4, -3, -1, 4}, ys[4] = {0, 1.5f, 2.5f, 3};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != 1 || j != 1)
        grid_quads(s, glm::vec3(xs[i], ys[j], 0), glm::vec3(xs[i + 1] - xs[i], 0, 0), glm::vec3(0, ys[j + 1] - ys[j], 0), 1, 1);
  // The beam at z = -1: a strip from the floor at the left rising to the right, cut in 40 pieces,
  // facing +z. Its box covers the window; the strip stays below it.
  const std::uint32_t beam = s.begin_object();
  for (int k = 0; k < 40; ++k) {
    const float x0 = -3.8f + 7.3f * k / 40.0f, x1 = -3.8f + 7.3f * (k + 1) / 40.0f;
    const float y0 = 0.0f + 2.4f * k / 40.0f, y1 = 0.0f + 2.4f * (k + 1) / 40.0f;
    s.triangle(glm::vec3(x0, y0, -1), glm::vec3(x1, y1, -1), glm::vec3(x1, y1 + 0.3f, -1));
    s.triangle(glm::vec3(x0, y0, -1), glm::vec3(x1, y1 + 0.3f, -1), glm::vec3(x0, y0 + 0.3f, -1));
  }
  const std::vector<glm::vec3> eyes = {{0, 1.7f, 6}, {-0.5f, 1.7f, 7}, {0.8f, 1.7f, 6.5f}, {0, 1.9f, 8}};
  cullkit::MeshOcclusionParams tested;
  const Tally with = run(s, {beam}, eyes, glm::vec3(0, 1.5f, 0), 0.1f, tested, "slanted_beam triangle tests");
  cullkit::MeshOcclusionParams boxes_only;
  boxes_only.object_test_triangles = 0;
  const Tally without = run(s, {beam}, eyes, glm::vec3(0, 1.5f, 0), 0.1f, boxes_only, "slanted_beam boxes only");
  CHECK(with.hidden == with.targets);
  CHECK(without.hidden == 0);  // the control: the box shows through the window
}

// Two closed boxes of different heights side by side, and 3 cubes behind their seam (returned).
std::vector<std::uint32_t> boxes_and_cubes(TestScene& s) {
  s.box(glm::vec3(-4, 0, -1), glm::vec3(0, 3, 0));
  s.box(glm::vec3(0, 0, -1), glm::vec3(4, 5, 0));
  std::vector<std::uint32_t> cubes;
  for (int k = 0; k < 3; ++k) cubes.push_back(s.box(glm::vec3(-0.3f, 0.4f + 0.6f * k, -3.3f), glm::vec3(0.3f, 0.8f + 0.6f * k, -2.7f)));
  return cubes;
}

void touching_boxes() {
  TestScene s;
  const std::vector<std::uint32_t> cubes = boxes_and_cubes(s);
  const std::vector<glm::vec3> eyes = {{0, 1.7f, 6}, {-0.4f, 1.5f, 7}, {0.3f, 2.0f, 5}, {0.1f, 1.0f, 9}};
  cullkit::MeshOcclusionParams with_boxes;
  const Tally with = run(s, cubes, eyes, glm::vec3(0, 1.2f, -2), 0.1f, with_boxes, "touching_boxes box tree");
  cullkit::MeshOcclusionParams grid_only;
  grid_only.max_box_occluders = 0;
  const Tally without = run(s, cubes, eyes, glm::vec3(0, 1.2f, -2), 0.1f, grid_only, "touching_boxes grid only");
  CHECK(with.hidden == with.targets);
  // The control: where the T-junction seam crosses a cube's rectangle, the grid leaves it open.
  CHECK(without.hidden + 3 <= with.hidden);
  // Eyes nearer the boxes' front than the near plane, looking through them: what the near plane
  // clips hides nothing, so the cubes behind are seen (the oracle checks every hidden object).
  const std::vector<glm::vec3> close = {{-0.5f, 1.5f, 0.05f}, {0.5f, 1.5f, 0.08f}, {-3.0f, 1.0f, 0.02f}};
  const Tally clipped = run(s, cubes, close, glm::vec3(0, 1.2f, -3), 0.1f, with_boxes, "touching_boxes clipped front");
  CHECK(clipped.hidden < clipped.targets);
}

// A solid box hidden on the grid takes no place in the tree (see the file's comment).
void box_behind_wall() {
  TestScene s;
  const std::vector<std::uint32_t> cubes = boxes_and_cubes(s);
  s.begin_object();
  grid_quads(s, glm::vec3(-6, -2, 3), glm::vec3(5, 0, 0), glm::vec3(0, 8, 0), 1, 1);
  s.box(glm::vec3(-3.6f, -1, 1), glm::vec3(-2, 4, 2));
  const std::vector<glm::vec3> eyes = {{0, 1.7f, 6}, {-0.4f, 1.5f, 7}, {0.3f, 2.0f, 5}};
  cullkit::MeshOcclusionParams two_boxes;
  two_boxes.max_box_occluders = 2;
  const Tally two = run(s, cubes, eyes, glm::vec3(0, 1.2f, -2), 0.1f, two_boxes, "box_behind_wall two boxes");
  CHECK_MSG(two.hidden == two.targets, "box_behind_wall: %d of %d cubes hidden", two.hidden, two.targets);
  // The control: with one place the seam stays open on the grid and in the tree.
  cullkit::MeshOcclusionParams one_box;
  one_box.max_box_occluders = 1;
  const Tally one = run(s, cubes, eyes, glm::vec3(0, 1.2f, -2), 0.1f, one_box, "box_behind_wall one box");
  CHECK_MSG(one.hidden + 3 <= two.hidden, "box_behind_wall: %d cubes hidden with one box, %d with two", one.hidden, two.hidden);
}

// A wall of 8 x 4 quads at z = 0 facing +z, with 6 cubes behind it.
std::vector<std::uint32_t> wall_and_cubes(TestScene& s) {
  s.begin_object();
  grid_quads(s, glm::vec3(-6, 0, 0), glm::vec3(12, 0, 0), glm::vec3(0, 4, 0), 8, 4);
  std::vector<std::uint32_t> cubes;
  for (int i = -1; i <= 1; ++i)
    for (int k = 1; k <= 2; ++k)
      cubes.push_back(s.box(glm::vec3(1.5f * i - 0.3f, 0.2f, -2.0f * k - 0.3f), glm::vec3(1.5f * i + 0.3f, 1.2f, -2.0f * k + 0.3f)));
  return cubes;
}

void far_backdrop() {
  TestScene plain;
  const std::vector<std::uint32_t> cubes = wall_and_cubes(plain);
  TestScene domed = plain;
  const std::uint32_t dome = domed.begin_object();
  const float radius = 500.0f;
  const int around = 64, up = 16;  // 2 * 64 * 16 = 2,048 triangles
  const auto at = [&](int u, int v) {
    const float phi = 6.2831853f * static_cast<float>(u) / around, theta = 3.1415927f * static_cast<float>(v) / up;
    return radius * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  for (int v = 0; v < up; ++v)
    for (int u = 0; u < around; ++u) {  // counter-clockwise seen from the centre
      domed.triangle(at(u, v), at(u, v + 1), at(u + 1, v));
      domed.triangle(at(u + 1, v), at(u, v + 1), at(u + 1, v + 1));
    }
  const std::vector<glm::vec3> eyes = {{0, 1.7f, 6}, {-1, 1.7f, 8}, {1, 1.7f, 5}, {0.5f, 2.5f, 7}, {0, 3.0f, 12}};
  const glm::vec3 look_at(0, 1.5f, 0);
  const float far_plane = 2000.0f;
  const cullkit::MeshOcclusionParams params;
  const Tally with = run(domed, cubes, eyes, look_at, 0.1f, params, "far_backdrop dome", far_plane);
  CHECK(with.hidden == with.targets);
  const cullkit::MeshOcclusionCuller<glm::vec3> a(plain.mesh(), plain.objects.data(), plain.objects.size(), params);
  const cullkit::MeshOcclusionCuller<glm::vec3> b(domed.mesh(), domed.objects.data(), domed.objects.size(), params);
  cullkit::MeshOcclusionContext ca, cb;
  std::vector<std::uint32_t> out_a, out_b;
  // The last eye stands 2 mm beyond the near plane from the wall, looking straight at it: the wall is
  // an occluder only if it is clipped at a level set by the occluders' own extent, not by the dome's.
  std::vector<std::pair<glm::vec3, glm::vec3>> views;
  for (const glm::vec3& eye : eyes) views.emplace_back(eye, look_at);
  views.emplace_back(glm::vec3(0.2f, 1.0f, 0.102f), glm::vec3(0.2f, 1.0f, -10.0f));
  for (std::size_t e = 0; e < views.size(); ++e) {
    const cullkit::Camera cam = cullkit::support::make_camera(views[e].first, views[e].second, 60.0f, 320, 180, 0.1f, far_plane);
    a.cull(cam, ca, out_a);
    b.cull(cam, cb, out_b);
    out_b.erase(std::remove(out_b.begin(), out_b.end(), dome), out_b.end());
    std::sort(out_a.begin(), out_a.end());
    std::sort(out_b.begin(), out_b.end());
    CHECK_MSG(out_a == out_b, "far_backdrop eye %zu: the dome changed the answer", e);
    CHECK_MSG(ca.stats().occluder_triangles == cb.stats().occluder_triangles,
              "far_backdrop eye %zu: %zu occluder triangles without the dome, %zu with it", e,
              ca.stats().occluder_triangles, cb.stats().occluder_triangles);
  }
}

void dense_wall() {
  TestScene s;
  s.begin_object();
  grid_quads(s, glm::vec3(-6, 0, 0), glm::vec3(12, 0, 0), glm::vec3(0, 4, 0), 100, 50);
  std::vector<std::uint32_t> cubes;
  for (int i = -1; i <= 1; ++i)
    for (int k = 1; k <= 3; ++k)
      cubes.push_back(s.box(glm::vec3(1.5f * i - 0.3f, 0.8f, -2.0f * k - 0.3f), glm::vec3(1.5f * i + 0.3f, 1.6f, -2.0f * k + 0.3f)));
  const std::vector<glm::vec3> far_eyes = {{0, 2, 20}, {-1, 2, 22}, {1, 1.5f, 21}};
  const std::vector<glm::vec3> near_eyes = {{0, 2, 6}, {-0.5f, 1.7f, 5}};
  const glm::vec3 look_at(0, 1.5f, 0);
  cullkit::MeshOcclusionParams defaults;
  cullkit::MeshOcclusionParams every;
  every.min_occluder_cells_per_triangle = 0.0f;
  const Tally far_default = run(s, cubes, far_eyes, look_at, 0.1f, defaults, "dense_wall far, default");
  const Tally far_every = run(s, cubes, far_eyes, look_at, 0.1f, every, "dense_wall far, every patch");
  const Tally near_default = run(s, cubes, near_eyes, look_at, 0.1f, defaults, "dense_wall near, default");
  CHECK(far_default.hidden == 0);
  CHECK(far_every.hidden * 10 >= far_every.targets * 9);  // the control: the wall can hide them
  CHECK(near_default.hidden * 10 >= near_default.targets * 9);
}

void thin_slats() {
  // A wall x in [-6, 6], y in [0, 3] at z = 0, facing +z: one object, or 20 slats 0.15 high.
  const auto wall = [](TestScene& s, int slats) {
    std::vector<float> ys(static_cast<std::size_t>(slats) + 1);
    for (int k = 0; k <= slats; ++k) ys[static_cast<std::size_t>(k)] = 3.0f * float(k) / float(slats);
    for (std::size_t k = 0; k + 1 < ys.size(); ++k) {
      s.begin_object();
      const glm::vec3 a(-6, ys[k], 0), b(6, ys[k], 0), c(6, ys[k + 1], 0), d(-6, ys[k + 1], 0);
      s.triangle(a, b, c);
      s.triangle(a, c, d);
    }
  };
  const auto cubes_behind = [](TestScene& s) {
    std::vector<std::uint32_t> cubes;
    for (int i = -1; i <= 1; ++i)
      for (int k = 1; k <= 3; ++k)
        cubes.push_back(s.box(glm::vec3(1.5f * i - 0.3f, 0.8f, -2.0f * k - 0.3f), glm::vec3(1.5f * i + 0.3f, 1.6f, -2.0f * k + 0.3f)));
    return cubes;
  };
  TestScene slatted, solid;
  wall(slatted, 20);
  wall(solid, 1);
  const std::vector<std::uint32_t> cubes = cubes_behind(slatted);
  const std::vector<std::uint32_t> solid_cubes = cubes_behind(solid);
  // From 20 m a slat is about 0.9 cells high on the default grid; from 5 to 6 m, 2.5 to 3.
  const std::vector<glm::vec3> far_eyes = {{0, 2, 20}, {-1, 2, 22}, {1, 1.5f, 21}};
  const std::vector<glm::vec3> near_eyes = {{0, 2, 6}, {-0.5f, 1.7f, 5}};
  const glm::vec3 look_at(0, 1.5f, 0);
  const cullkit::MeshOcclusionParams defaults;
  cullkit::MeshOcclusionParams off, nan;
  off.min_occluder_width_cells = 0.0f;
  nan.min_occluder_width_cells = std::nanf("");
  const Tally far_default = run(slatted, cubes, far_eyes, look_at, 0.1f, defaults, "thin_slats far, default");
  const Tally far_off = run(slatted, cubes, far_eyes, look_at, 0.1f, off, "thin_slats far, rule off");
  const Tally far_nan = run(slatted, cubes, far_eyes, look_at, 0.1f, nan, "thin_slats far, NaN width");
  const Tally near_default = run(slatted, cubes, near_eyes, look_at, 0.1f, defaults, "thin_slats near, default");
  const Tally far_solid = run(solid, solid_cubes, far_eyes, look_at, 0.1f, defaults, "thin_slats one wall far");
  CHECK(far_default.hidden == 0);
  CHECK(far_off.hidden == far_off.targets);  // the control: the slats fuse and hide the cubes
  CHECK(far_nan.hidden == far_nan.targets);
  CHECK(near_default.hidden == near_default.targets);
  CHECK(far_solid.hidden == far_solid.targets);
}

void twin_reach() {
  namespace dmo = cullkit::detail::mesh_occlusion;
  TestScene s;
  s.begin_object();
  grid_quads(s, glm::vec3(0, 0, 0), glm::vec3(4, 0, 0), glm::vec3(0, 4, 0), 20, 20);
  // Beside it, half as fine: its corners fall on the finer grid's edges (T-junctions).
  grid_quads(s, glm::vec3(4, 0, 0), glm::vec3(4, 0, 0), glm::vec3(0, 4, 0), 10, 10);
  s.box(glm::vec3(1, 1, -3), glm::vec3(2, 2, -2));
  // An object overlapping the first: its triangles are in a patch of each.
  s.objects.push_back(cullkit::MeshObject{300, 200});
  dmo::MeshIndex index;
  mesh_oracle::build_test_index(s, index, 64);
  const dmo::PatchSet& ps = index.patches;
  const std::size_t triangles = index.corners.size() / 3;
  CHECK(ps.twin_reach.size() == triangles);
  if (ps.twin_reach.size() != triangles) return;
  std::vector<std::uint32_t> in_patch(triangles, dmo::none);
  std::size_t inside = 0, across = 0, shared = 0, bad = 0;
  for (std::uint32_t p = 0; p < ps.patches.size(); ++p) {
    const dmo::Patch& patch = ps.patches[p];
    for (std::uint32_t i = patch.first; i < patch.first + patch.count; ++i) {
      shared += in_patch[ps.triangles[i]] != dmo::none;
      in_patch[ps.triangles[i]] = p;
    }
    for (std::uint32_t i = patch.first; i < patch.first + patch.count; ++i) {
      const std::uint32_t t = ps.triangles[i];
      for (unsigned k = 0; k < 3; ++k) {
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + k];
        if (twin == dmo::none) continue;
        const bool here = in_patch[twin / 3] == p;
        inside += here;
        across += !here;
        const unsigned bit = here ? 1u << k : 8u << k;
        bad += (ps.twin_reach[t] & bit) == 0;
      }
    }
  }
  std::printf("%-32s pairs in a patch %zu, across %zu, triangles in two patches %zu, missed %zu\n", "twin_reach", inside,
              across, shared, bad);
  CHECK(index.build_stats.triangles_cut > 0);
  CHECK(inside > 0 && across > 0 && shared > 0);
  CHECK(bad == 0);
}

}  // namespace

int main() {
  big_object();
  slanted_beam();
  touching_boxes();
  box_behind_wall();
  far_backdrop();
  dense_wall();
  thin_slats();
  twin_reach();
  return cullkit_test::report("test_mesh_occlusion_patches");
}
