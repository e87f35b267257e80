// NormalClassIndex with moving objects: each object has its own index in its local frame and a
// rigid transform. Checked against a float brute force over the static scene plus the objects'
// triangles transformed to the world: every pixel's first hit must be reported (as a static
// triangle or as an (object, triangle) pair), up to ties within 1e-5 relative depth (the object
// is hit with rays taken into its frame, which round differently).
#include <cstdio>

#include <glm/ext/matrix_transform.hpp>

#include "check.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;
using cullkit::support::Scene;

int main() {
  const Scene city = support::make_city(41, 2);
  const Scene object = support::make_office(42, 1, 1);  // a furnished room as the moving object
  const nci_test::TestIndex<glm::vec3> static_index(city.mesh());
  const nci_test::TestIndex<glm::vec3> object_index(object.mesh());
  const glm::vec3 oc = object.bounds.center();
  int checked = 0, ties = 0, object_pixels = 0;
  for (int frame = 0; frame < 6; ++frame) {
    // Two copies of the object moving through the city, rotated about y and x.
    std::vector<NciMovingObject<NormalClassIndex<glm::vec3>>> movers;
    for (int k = 0; k < 2; ++k) {
      glm::mat4 m(1.0f);
      m = glm::translate(m, city.bounds.center() + glm::vec3(-20.0f + 12.0f * frame, 4.0f + 6.0f * k, 10.0f * k));
      m = glm::rotate(m, 0.4f * frame + 1.3f * k, glm::vec3(0, 1, 0));
      m = glm::rotate(m, 0.2f * k, glm::vec3(1, 0, 0));
      m = glm::scale(m, glm::vec3(1.0f));
      m = glm::translate(m, -oc);
      movers.push_back({&object_index, m, 100u + static_cast<std::uint32_t>(k)});
    }
    // The world scene for the oracle: static triangles first, then each object's, transformed.
    Scene world = city;
    std::vector<std::uint32_t> first;
    for (const auto& mv : movers) {
      first.push_back(static_cast<std::uint32_t>(world.triangle_count()));
      std::vector<glm::vec3> corners;
      for (std::size_t t = 0; t < object.triangle_count(); ++t)
        for (int c = 0; c < 3; ++c)
          corners.push_back(glm::vec3(mv.local_to_world * glm::vec4(object.positions[object.indices[3 * t + c]], 1.0f)));
      world.add_triangles(corners, "mover");
    }
    auto cams = nci_test::cameras_for(world.bounds, 3, 64, 48, 400 + frame);
    for (int k = 0; k < 3; ++k) {  // looking at the first object from around it (and from inside the second)
      const glm::vec3 target = glm::vec3(movers[0].local_to_world * glm::vec4(oc, 1.0f));
      const float ang = 0.9f * k + 0.3f * frame;
      const glm::vec3 eye = k == 2 ? glm::vec3(movers[1].local_to_world * glm::vec4(oc, 1.0f))
                                   : target + glm::vec3(std::cos(ang), 0.5f, std::sin(ang)) * 18.0f;
      cams.push_back(support::make_camera(eye, target, 60, 64, 48, 0.1f, 1000.0f));
    }
    for (std::size_t ci = 0; ci < cams.size(); ++ci) {
      const Camera& cam = cams[ci];
      NciContext ctx;
      VisibleSet set;
      std::vector<NciObjectTriangle> objs;
      NciPixels px;
      static_index.select_visible(cam, movers.data(), movers.size(), ctx, set, objs, &px);
      CHECK(std::is_sorted(objs.begin(), objs.end()));
      const auto brute = nci_test::brute_force<float>(world, cam);
      int missing = 0;
      for (std::size_t p = 0; p < brute.tri.size(); ++p) {
        const std::uint32_t want = brute.tri[p];
        if (want == nci_test::miss) continue;
        ++checked;
        bool found = false;
        if (want < first[0]) {
          found = std::binary_search(set.triangles.begin(), set.triangles.end(), want);
        } else {
          const int k = want >= first[1] ? 1 : 0;
          ++object_pixels;
          const NciObjectTriangle ot{100u + static_cast<std::uint32_t>(k), want - first[static_cast<std::size_t>(k)]};
          found = std::binary_search(objs.begin(), objs.end(), ot);
        }
        if (!found) {
          // A tie: our pixel depth equals the oracle's within 1e-5 relative.
          if (std::fabs(px.depth[p] - brute.t[p]) <= 1e-5f * std::max(1.0f, brute.t[p])) {
            ++ties;
            continue;
          }
          if (++missing <= 3)
            std::fprintf(stderr, "  frame %d cam %zu pixel %zu: world triangle %u t=%g missing (ours t=%g)\n", frame,
                         ci, p, want, double(brute.t[p]), double(px.depth[p]));
        }
      }
      CHECK_MSG(missing == 0, "frame %d cam %zu: %d pixels miss", frame, ci, missing);
      // Nothing hidden is reported for the objects: each reported pair is some pixel's winner.
      for (const auto& ot : objs) {
        const std::uint32_t world_id = first[ot.object - 100u] + ot.triangle;
        bool seen = false;
        for (std::size_t p = 0; p < brute.tri.size() && !seen; ++p) {
          if (brute.tri[p] == world_id) seen = true;
          else if (std::fabs(px.depth[p] - brute.t[p]) <= 1e-5f * std::max(1.0f, brute.t[p])) seen = true;
        }
        CHECK(seen);
      }
    }
  }
  CHECK(object_pixels > 100);  // the objects were really in view
  std::printf("moving objects: %d pixels checked, %d on objects, %d ties\n", checked, object_pixels, ties);
  return cullkit_test::report("test_nci_moving");
}
