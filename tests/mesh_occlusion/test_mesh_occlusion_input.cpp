// MeshOcclusionCuller on bad and unusual input, each with its documented answer: empty mesh, no
// objects, objects with no triangles or a range leaving the mesh, NaN/inf corners, indices out of
// range, degenerate triangles, 16-bit indices (same answer as 32-bit), orthographic / NaN /
// singular matrices (no occlusion: every object in the frustum), the eye off the matrix's centre,
// concurrent calls (same answers as serial), a reused context (same answers as fresh ones, and no
// growth of `out` once warm).
#include <cmath>
#include <cstdio>
#include <limits>
#include <thread>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "mesh_occlusion_oracle.hpp"

using mesh_oracle::TestScene;

namespace {

// A wall at z = 0 facing +z (two triangles), and three cubes behind it.
TestScene wall_and_cubes() {
  TestScene s;
  s.begin_object();
  s.triangle({-5, -5, 0}, {5, -5, 0}, {5, 5, 0});
  s.triangle({-5, -5, 0}, {5, 5, 0}, {-5, 5, 0});
  for (int i = 0; i < 3; ++i) s.box(glm::vec3(-1.5f + i, -0.2f, -2.0f), glm::vec3(-1.2f + i, 0.2f, -1.5f));
  return s;
}

cullkit::Camera front_camera(cullkit::DepthRange depth = cullkit::DepthRange::negative_one_to_one) {
  return cullkit::support::make_camera(glm::vec3(0, 0, 6), glm::vec3(0, 0, 0), 60.0f, 640, 360, 0.1f, 100.0f, depth);
}

std::vector<std::uint32_t> sorted(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

template <class Index>
std::vector<std::uint32_t> cull_with(const TestScene& s, const std::vector<Index>& indices, const cullkit::Camera& cam,
                                     cullkit::MeshOcclusionStats* stats = nullptr) {
  const cullkit::MeshView<glm::vec3, Index> mesh{s.positions.data(), s.positions.size(), indices.data(), indices.size()};
  const cullkit::MeshOcclusionCuller<glm::vec3, Index> culler(mesh, s.objects.data(), s.objects.size());
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  culler.cull(cam, context, out);
  if (stats) *stats = context.stats();
  return sorted(out);
}

}  // namespace

int main() {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const TestScene base = wall_and_cubes();
  const std::vector<std::uint32_t> all = {0, 1, 2, 3};

  // The normal case hides the three cubes (so the cases below show a change of answer).
  {
    cullkit::MeshOcclusionStats st;
    CHECK(cull_with(base, base.indices, front_camera(), &st) == std::vector<std::uint32_t>{0});
    CHECK(st.occlusion_enabled && st.objects_hidden == 3 && st.objects_in_frustum == 4 && st.occluder_triangles == 2);
    CHECK(cull_with(base, base.indices, front_camera(cullkit::DepthRange::zero_to_one)) == std::vector<std::uint32_t>{0});
  }
  // Empty mesh and no objects.
  {
    const cullkit::MeshOcclusionCuller<glm::vec3> empty(cullkit::MeshView<glm::vec3>{nullptr, 0, nullptr, 0}, nullptr, 0);
    std::vector<std::uint32_t> out = {7};
    empty.cull(front_camera(), out);
    CHECK(out.empty());
    CHECK(empty.stats().triangles == 0 && empty.object_count() == 0);
    // Objects but no mesh: every object is unusable, so reported.
    const cullkit::MeshObject objects[2] = {{0, 0}, {0, 3}};
    const cullkit::MeshOcclusionCuller<glm::vec3> no_mesh(cullkit::MeshView<glm::vec3>{nullptr, 0, nullptr, 0}, objects, 2);
    no_mesh.cull(front_camera(), out);
    CHECK(sorted(out) == (std::vector<std::uint32_t>{0, 1}));
    CHECK(no_mesh.stats().objects_unusable == 2);
  }
  // An object with no triangles, and one whose range leaves the mesh: always reported.
  {
    TestScene s = base;
    s.objects.push_back({0, 0});
    s.objects.push_back({static_cast<std::uint32_t>(s.indices.size() / 3 - 1), 5});
    s.objects.push_back({0xffffffffu, 0xffffffffu});
    cullkit::MeshOcclusionStats st;
    CHECK(cull_with(s, s.indices, front_camera(), &st) == (std::vector<std::uint32_t>{0, 4, 5, 6}));
    CHECK(st.objects_unusable_visible == 3);
  }
  // A NaN or infinite corner: its object is always reported; a NaN in the wall stops it occluding
  // (the triangle is skipped), and the other triangle alone still covers a cube behind it.
  {
    TestScene s = base;
    s.positions[s.indices[3 * 2]] = glm::vec3(nan, 0, 0);  // first cube, first triangle
    CHECK(cull_with(s, s.indices, front_camera()) == (std::vector<std::uint32_t>{0, 1}));
    TestScene t = base;
    t.positions[t.indices[0]] = glm::vec3(inf, 0, 0);  // the wall
    const auto out = cull_with(t, t.indices, front_camera());
    CHECK(std::find(out.begin(), out.end(), 0u) != out.end());
    CHECK(out.size() == 4);  // the wall is unusable (always visible) and so never occludes
  }
  // Indices out of range: the triangle is unusable, its object reported.
  {
    TestScene s = base;
    s.indices[3 * 14 + 1] = 100000;  // a triangle of the second cube (triangles 2..13 are cube 1)
    const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size());
    CHECK(culler.stats().triangles_unusable == 1 && culler.stats().objects_unusable == 1);
    std::vector<std::uint32_t> out;
    culler.cull(front_camera(), out);
    CHECK(sorted(out) == (std::vector<std::uint32_t>{0, 2}));
    // A trailing partial triangle is ignored.
    s.indices.push_back(0);
    const cullkit::MeshOcclusionCuller<glm::vec3> partial(s.mesh(), s.objects.data(), s.objects.size());
    CHECK(partial.stats().triangles == s.indices.size() / 3);
  }
  // Overlapping objects (the wall twice, and one of its triangles a third time): the same
  // answer as without the copies.
  {
    TestScene s = base;
    s.objects.push_back({0, 2});
    s.objects.push_back({1, 1});
    cullkit::MeshOcclusionStats st;
    CHECK(cull_with(s, s.indices, front_camera(), &st) == (std::vector<std::uint32_t>{0, 4, 5}));
    CHECK(st.occluder_triangles == 2);
  }
  // Degenerate triangles are counted and never occlude; their object keeps its bounds.
  {
    TestScene s = base;
    s.positions[s.indices[1]] = s.positions[s.indices[0]];  // wall triangle 0 loses its area
    const cullkit::MeshOcclusionCuller<glm::vec3> culler(s.mesh(), s.objects.data(), s.objects.size());
    CHECK(culler.stats().triangles_degenerate == 1);
    std::vector<std::uint32_t> out;
    culler.cull(front_camera(), out);
    CHECK(std::find(out.begin(), out.end(), 0u) != out.end());
  }
  // 16-bit indices give the 32-bit answer, from many eyes.
  {
    const std::vector<std::uint16_t> idx16(base.indices.begin(), base.indices.end());
    cullkit::support::Rng rng(5);
    for (int e = 0; e < 50; ++e) {
      const glm::vec3 eye(rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(-8, 8));
      const cullkit::Camera cam = cullkit::support::make_camera(eye, glm::vec3(0), 70.0f, 320, 200, 0.05f, 0.0f);
      CHECK(cull_with(base, idx16, cam) == cull_with(base, base.indices, cam));
    }
  }
  // Orthographic, NaN and singular matrices, and an eye away from the matrix's centre: no
  // occlusion, every object in the frustum is reported.
  {
    cullkit::Camera ortho = front_camera();
    ortho.view_proj = glm::orthoRH_NO(-6.0f, 6.0f, -4.0f, 4.0f, 0.1f, 100.0f) *
                      glm::lookAtRH(glm::vec3(0, 0, 6), glm::vec3(0), glm::vec3(0, 1, 0));
    cullkit::MeshOcclusionStats st;
    CHECK(cull_with(base, base.indices, ortho, &st) == all);
    CHECK(!st.occlusion_enabled);
    cullkit::Camera bad = front_camera();
    bad.view_proj[2][1] = nan;
    CHECK(cull_with(base, base.indices, bad) == all);
    bad = front_camera();
    bad.view_proj = glm::mat4(0.0f);
    CHECK(cull_with(base, base.indices, bad) == all);
    bad = front_camera();
    bad.eye = glm::vec3(0.5f, 0, 6);  // not the centre of projection
    CHECK(cull_with(base, base.indices, bad, &st) == all);
    CHECK(!st.occlusion_enabled);
    bad = front_camera();
    bad.eye = glm::vec3(nan);
    CHECK(cull_with(base, base.indices, bad) == all);
  }
  // The eye nearer the wall than the near plane: the wall is clipped (outside the frustum) and
  // hides nothing.
  {
    const cullkit::Camera cam =
        cullkit::support::make_camera(glm::vec3(0, 0, 0.05f), glm::vec3(0, 0, -1), 60.0f, 640, 360, 0.1f, 100.0f);
    CHECK(cull_with(base, base.indices, cam) == (std::vector<std::uint32_t>{1, 2, 3}));
  }
  // Behind the wall (it faces away): nothing occludes, and the cubes are in view.
  {
    const cullkit::Camera cam = cullkit::support::make_camera(glm::vec3(0, 0, -6), glm::vec3(0), 60.0f, 640, 360, 0.1f, 100.0f);
    const auto out = cull_with(base, base.indices, cam);
    CHECK(out.size() >= 3);
    CHECK(std::find(out.begin(), out.end(), 1u) != out.end());
  }
  // Concurrent calls give the serial answers; a reused context gives fresh-context answers, and
  // once warm, `out` does not grow.
  {
    cullkit::support::Rng rng(9);
    std::vector<cullkit::Camera> cams;
    for (int e = 0; e < 64; ++e)
      cams.push_back(cullkit::support::make_camera(glm::vec3(rng.uniform(-6, 6), rng.uniform(-6, 6), rng.uniform(1, 9)),
                                                   glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), -2), 70.0f, 320, 200,
                                                   0.1f, 100.0f));
    const cullkit::MeshOcclusionCuller<glm::vec3> culler(base.mesh(), base.objects.data(), base.objects.size());
    std::vector<std::vector<std::uint32_t>> serial(cams.size()), parallel(cams.size());
    std::size_t hidden = 0;
    for (std::size_t c = 0; c < cams.size(); ++c) {
      culler.cull(cams[c], serial[c]);
      serial[c] = sorted(serial[c]);
      hidden += 4 - serial[c].size();
    }
    CHECK(hidden > 30);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        cullkit::MeshOcclusionContext context;
        std::vector<std::uint32_t> out;
        for (std::size_t c = static_cast<std::size_t>(t); c < cams.size(); c += 4) {
          culler.cull(cams[c], context, out);
          parallel[c] = sorted(out);
        }
      });
    for (auto& th : threads) th.join();
    CHECK(serial == parallel);
    cullkit::MeshOcclusionContext context;
    std::vector<std::uint32_t> out;
    culler.cull(cams[0], context, out);
    out.reserve(8);
    const std::size_t capacity = out.capacity();
    for (std::size_t c = 0; c < cams.size(); ++c) {
      culler.cull(cams[c], context, out);
      CHECK(sorted(out) == serial[c]);
    }
    CHECK(out.capacity() == capacity);
  }
  return cullkit_test::report("test_mesh_occlusion_input");
}
