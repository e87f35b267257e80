// NormalClassIndex with a moving object whose camera, taken into the object's frame as a float
// matrix, had its far plane moved through infinity by rounding, so that its pixel rays pointed
// backwards. Eye at the origin looking down -z, 60-degree perspective with near 0.1 and far 1e4,
// 32x32 pixels; the object under translate * rotate * scale * shear (1-norm condition number
// 9.9e3, accepted). Two cases, each against a double-precision ray cast:
// 1. a triangle in front of the eye, the object's only one, fills 72 pixel centres: it must be
//    reported (it was lost);
// 2. the object's triangle lies behind the eye, which no pixel ray meets: every static wall triangle
//    that is some pixel's robust first hit must stay in the set (66 of 70 were hidden).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include <cullkit/cullkit.hpp>

#include "check.hpp"
#include "nci_double_cast.hpp"
#include "nci_index.hpp"

using namespace cullkit;

namespace {

using Index = NormalClassIndex<glm::vec3>;

Camera camera() {
  Camera cam;
  cam.eye = glm::vec3(0.0f);
  cam.width = 32;
  cam.height = 32;
  cam.view_proj = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 10000.0f) *
                  glm::lookAt(glm::vec3(0.0f), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  return cam;
}

glm::mat4 sheared_transform() {
  const float cols[4][4] = {{0x1.11bd56p+0f, -0x1.dd637ep-1f, 0x1.a2874cp-2f, 0.f},
                            {0x1.456cfp+4f, 0x1.01fc68p+4f, -0x1.0f0e52p+4f, 0.f},
                            {-0x1.69a87ap+5f, -0x1.1b9236p+5f, 0x1.2b456ep+5f, 0.f},
                            {-0x1.ac7804p+2f, -0x1.e1dc84p+2f, 0x1.776e46p+2f, 1.f}};
  glm::mat4 m;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = cols[c][r];
  return m;
}

// The world triangle taken into the object's frame (rounded to float there), and moved back in
// double for the oracle.
struct ObjectTriangle {
  std::vector<glm::vec3> local;
  nci_test::DoubleTriangle world;
};
ObjectTriangle object_triangle(const glm::mat4& m, const glm::vec3 (&world)[3]) {
  const glm::dmat4 md(m), mi = glm::inverse(md);
  ObjectTriangle o;
  for (const auto& p : world) o.local.push_back(glm::vec3(mi * glm::dvec4(glm::dvec3(p), 1.0)));
  glm::dvec3 w[3];
  for (int k = 0; k < 3; ++k) w[k] = glm::dvec3(md * glm::dvec4(glm::dvec3(o.local[static_cast<std::size_t>(k)]), 1.0));
  o.world = {w[0], w[1], w[2], glm::determinant(glm::dmat3(md)) < 0.0};
  return o;
}

// select_visible on `scene` with `object` moved by `m` as object 7, on one thread.
struct Selection {
  NciContext ctx;
  VisibleSet set;
  std::vector<NciObjectTriangle> objs;
  NciPixels px;
};
Selection select_with_object(const Camera& cam, const std::vector<glm::vec3>& scene_vertices,
                             const std::vector<std::uint32_t>& scene_indices, const std::vector<glm::vec3>& object_vertices,
                             const glm::mat4& m) {
  NciParams params;
  params.threads = 1;
  const std::vector<std::uint32_t> idx = {0, 1, 2};
  const nci_test::TestIndex<glm::vec3> scene({scene_vertices.data(), scene_vertices.size(), scene_indices.data(), scene_indices.size()}, params);
  const Index object({object_vertices.data(), 3, idx.data(), 3}, params);
  const NciMovingObject<Index> mover{&object, m, 7u};
  Selection s;
  scene.select_visible(cam, &mover, 1, s.ctx, s.set, s.objs, &s.px);
  return s;
}

void visible_object_is_reported() {
  const Camera cam = camera();
  const glm::mat4 m = sheared_transform();
  const ObjectTriangle tri = object_triangle(m, {{-1, -1, -5}, {1, -1, -5}, {0, 1, -5}});
  const Selection s = select_with_object(cam, tri.local, {}, tri.local, m);  // no static triangle
  const auto& objs = s.objs;
  const auto& px = s.px;
  int robust = 0, claimed = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      robust += nci_test::robust_first_hit(glm::dvec3(cam.eye), nci_test::double_pixel_ray(cam, x, y), {tri.world}) == 0;
      claimed += std::isfinite(px.depth[static_cast<std::size_t>(y * cam.width + x)]);
    }
  std::printf("visible object: %d robust pixel centres, %d pixels with an object depth, %zu triangles reported\n", robust,
              claimed, objs.size());
  CHECK(s.ctx.stats.moving_objects_rejected == 0);
  CHECK(robust >= 60);
  CHECK(claimed >= robust);
  CHECK(objs.size() == 1 && objs[0] == NciObjectTriangle{7u, 0u});
}

void object_behind_the_eye_hides_nothing() {
  const Camera cam = camera();
  const glm::mat4 m = sheared_transform();
  // A static wall at z = -8 facing the eye: 8 x 8 quads.
  std::vector<glm::vec3> wall;
  std::vector<std::uint32_t> wall_idx;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) wall.push_back(glm::vec3(-8.0f + 2.0f * float(i), -8.0f + 2.0f * float(j), -8.0f));
  for (std::uint32_t j = 0; j < 8; ++j)
    for (std::uint32_t i = 0; i < 8; ++i) {
      const std::uint32_t a = j * 9 + i;
      wall_idx.insert(wall_idx.end(), {a, a + 1, a + 10, a, a + 10, a + 9});
    }
  std::vector<nci_test::DoubleTriangle> truth;
  for (std::size_t k = 0; k < wall_idx.size(); k += 3)
    truth.push_back({glm::dvec3(wall[wall_idx[k]]), glm::dvec3(wall[wall_idx[k + 1]]), glm::dvec3(wall[wall_idx[k + 2]]), false});
  // The object: one big triangle behind the eye at z = +5, counter-clockwise seen from the eye.
  const ObjectTriangle tri = object_triangle(m, {{-20, -20, 5}, {0, 20, 5}, {20, -20, 5}});
  truth.push_back(tri.world);
  const Selection s = select_with_object(cam, wall, wall_idx, tri.local, m);
  const auto& set = s.set;
  const auto& objs = s.objs;
  const auto& px = s.px;
  int robust = 0, lost = 0, claimed = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y * cam.width + x);
      claimed += px.triangle[p] == NciPixels::miss && std::isfinite(px.depth[p]);
      const int hit = nci_test::robust_first_hit(glm::dvec3(cam.eye), nci_test::double_pixel_ray(cam, x, y), truth);
      if (hit < 0) continue;
      CHECK(static_cast<std::size_t>(hit) + 1 < truth.size());  // never the triangle behind the eye
      ++robust;
      lost += !std::binary_search(set.triangles.begin(), set.triangles.end(), static_cast<std::uint32_t>(hit));
    }
  std::printf("object behind the eye: %d robust wall pixels, %d lost, %d pixels claimed by the object, %zu object triangles\n",
              robust, lost, claimed, objs.size());
  CHECK(s.ctx.stats.moving_objects_rejected == 0);
  CHECK(robust >= 900);
  CHECK(lost == 0);
  CHECK(claimed == 0);
  CHECK(objs.empty());
}

}  // namespace

int main() {
  visible_object_is_reported();
  object_behind_the_eye_hides_nothing();
  return cullkit_test::report("test_nci_moving_far_plane");
}
