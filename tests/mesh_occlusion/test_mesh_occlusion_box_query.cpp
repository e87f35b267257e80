// MeshOcclusionContext::is_hidden, axis-aligned and oriented, against Embree truth: from walk and
// hard cameras on the generated and real scenes, thousands of random boxes per scene (inside the
// view, straddling the near plane from behind the eye, across the frustum's sides, rotated, scaled
// and mirrored ones) are asked after a cull; a box reported hidden must have no point that a ray
// through the frustum meets before its first occluder. Also: invalid boxes and a context that has
// not culled are never hidden; the box query is the culler's own box test (an object whose bounds
// is_hidden hides is left out by the culler); two threads querying one context agree with one.
// Prints per scene the share of truly hidden boxes is_hidden hides, beside the share of truly
// hidden objects whose box alone is_hidden hides, on the same frames.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <glm/ext/matrix_transform.hpp>

#include "check.hpp"
#include "frame_truth.hpp"
#include "walk_cameras.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

constexpr int kWalk = MESH_OCC_SLOW ? 3 : 8;
constexpr int kBoxesPerCamera = MESH_OCC_SLOW ? 120 : 300;

/// A query box: axis-aligned (`model` unset) or `local` placed by `model`.
struct QueryBox {
  Aabb local;
  glm::mat4 model{1.0f};
  bool oriented = false;
  int kind = 0;  // 0 inside the view, 1 through the near plane, 2 across a side, 3 oriented
};

/// Whether the ray sees a point of the box, oriented boxes tested in their own space.
bool ray_sees(const glm::dvec3& eye, const TruthRay& r, const QueryBox& q) {
  if (!q.oriented) return ray_sees_box(eye, r, q.local);
  const glm::dmat4 inv = glm::inverse(glm::dmat4(q.model));
  TruthRay local = r;
  const glm::dvec3 o = glm::dvec3(inv * glm::dvec4(eye, 1.0));
  local.dir = glm::dvec3(inv * glm::dvec4(r.dir, 0.0));  // t keeps its meaning along the mapped ray
  return ray_sees_box(o, local, q.local);
}

Aabb box_around(const glm::vec3& c, const glm::vec3& half) { return Aabb{c - half, c + half}; }

std::vector<QueryBox> random_boxes(const Camera& cam, const WalkSpec& spec, float reach, support::Rng& rng, int count) {
  const PixelRays rays(cam);
  const float m = spec.metre;
  std::vector<QueryBox> out;
  for (int i = 0; i < count; ++i) {
    QueryBox q;
    const int kind = i % 10 < 5 ? 0 : i % 10 < 7 ? 1 : i % 10 < 8 ? 2 : 3;
    q.kind = kind;
    double px = double(rng.uniform()) * cam.width, py = double(rng.uniform()) * cam.height;
    if (kind == 2) {
      if (rng.range(0, 1)) px = rng.range(0, 1) ? 0.0 : cam.width;
      else py = rng.range(0, 1) ? 0.0 : cam.height;
    }
    const glm::vec3 dir = rays.ray_at(px, py).direction;
    const float t = spec.near_plane + rng.uniform() * rng.uniform() * reach;
    const glm::vec3 half(m * rng.uniform(0.05f, 3.0f), m * rng.uniform(0.05f, 3.0f), m * rng.uniform(0.05f, 3.0f));
    if (kind == 1) {
      // From behind the eye to somewhere ahead: reaches the near plane, its far corners maybe hidden.
      const glm::vec3 a = cam.eye - dir * (m * rng.uniform(0.1f, 2.0f));
      const glm::vec3 b = cam.eye + dir * (m * rng.uniform(1.0f, 40.0f));
      const glm::vec3 pad(m * rng.uniform(0.0f, 1.0f));
      q.local = Aabb{glm::min(a, b) - pad, glm::max(a, b) + pad};
    } else if (kind == 3) {
      q.oriented = true;
      q.local = box_around(glm::vec3(0.0f), half);
      glm::mat4 model = glm::translate(glm::mat4(1.0f), cam.eye + dir * t);
      model = glm::rotate(model, rng.uniform(0.0f, 6.2831853f), glm::normalize(glm::vec3(rng.uniform(-1, 1), 1.0f, rng.uniform(-1, 1))));
      glm::vec3 scale(rng.uniform(0.3f, 3.0f), rng.uniform(0.3f, 3.0f), rng.uniform(0.3f, 3.0f));
      if (rng.range(0, 2) == 0) scale.x = -scale.x;  // mirrored
      q.model = glm::scale(model, scale);
    } else {
      q.local = box_around(cam.eye + dir * t, half);
    }
    out.push_back(q);
  }
  return out;
}

bool query(const MeshOcclusionContext& context, const QueryBox& q) {
  return q.oriented ? context.is_hidden(q.local, q.model) : context.is_hidden(q.local);
}

struct Tally {
  std::size_t boxes = 0, truly_hidden = 0, hidden = 0, by_kind[4] = {0, 0, 0, 0};
  std::size_t objects_truly_hidden = 0, objects_box_hidden = 0;
  long wrong = 0;
};

void run_scene(const std::string& name, const support::Scene& scene, std::uint64_t seed, Tally& all) {
  oracle::EmbreeScene walker;
  walker.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  walker.commit();
  const FrameOccluders occluders(scene, {});
  const ObjectMap map(scene);
  const MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), map.objects.data(), map.objects.size());
  const WalkSpec spec = walk_spec(name, scene, walker, seed);
  const auto cams = walk_then_hard_cameras(spec, scene, walker, kWalk, kFrameWidth, kFrameHeight, seed + 1);
  const float reach = std::min(glm::length(scene.bounds.max - scene.bounds.min) * 0.5f, 150.0f * spec.metre);
  support::Rng rng(seed * 7 + 3);
  MeshOcclusionContext context;
  CHECK_MSG(!context.is_hidden(scene.objects.front().bounds), "%s: a context that never culled hides a box", name.c_str());
  Tally tally;
  std::vector<std::uint32_t> out;
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci].camera;
    culler.cull(cam, context, out);
    const RaySet set = frame_rays(seed * 1000 + ci);
    const auto rays = cast_frame(occluders, map, cam, set);
    const glm::dvec3 eye(cam.eye);
    const auto boxes = random_boxes(cam, spec, reach, rng, kBoxesPerCamera);
    std::vector<std::uint8_t> answers(boxes.size());
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      const QueryBox& q = boxes[b];
      const bool hidden = query(context, q);
      answers[b] = hidden;
      bool seen = false;
      for (const TruthRay& r : rays)
        if (ray_sees(eye, r, q)) {
          seen = true;
          break;
        }
      ++tally.boxes;
      tally.truly_hidden += !seen;
      tally.hidden += hidden;
      tally.by_kind[q.kind] += hidden;
      if (hidden && seen) {
        ++tally.wrong;
        if (tally.wrong <= 5)
          std::fprintf(stderr, "FALSE HIDE %s camera %zu (%s): box kind %d [%g %g %g]-[%g %g %g] is seen\n", name.c_str(),
                       ci, cams[ci].name.c_str(), q.kind, q.local.min.x, q.local.min.y, q.local.min.z, q.local.max.x,
                       q.local.max.y, q.local.max.z);
      }
    }
    // The box query is the culler's box test: a box it hides is an object the culler leaves out.
    std::vector<std::uint8_t> kept(scene.objects.size(), 0), seen(scene.objects.size(), 0);
    for (std::uint32_t o : out) kept[o] = 1;
    for (const TruthRay& r : rays)
      if (r.object != no_object) seen[r.object] = 1;
    const Frustum frustum = frustum_of(cam);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      const bool box_hidden = context.is_hidden(scene.objects[o].bounds);
      CHECK_MSG(!(box_hidden && kept[o]), "%s camera %zu: object %u's box is hidden but the culler keeps it",
                name.c_str(), ci, o);
      if (frustum.classify(scene.objects[o].bounds) == Containment::outside || seen[o]) continue;
      ++tally.objects_truly_hidden;
      tally.objects_box_hidden += box_hidden;
    }
    // Invalid boxes are never hidden.
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const glm::vec3 ahead = cam.eye;
    for (const Aabb& bad : {Aabb{glm::vec3(nan), glm::vec3(nan)}, Aabb{ahead + glm::vec3(1), ahead - glm::vec3(1)},
                            Aabb{glm::vec3(-inf), glm::vec3(inf)}, Aabb{glm::vec3(0, nan, 0), glm::vec3(1)}})
      CHECK(!context.is_hidden(bad) && !context.is_hidden(bad, glm::mat4(1.0f)));
    if (!boxes.empty())
      CHECK(!context.is_hidden(boxes.front().local, glm::mat4(nan)));
    // Several threads at once.
    if (ci == 0) {
      std::vector<std::uint8_t> other(boxes.size());
      std::thread worker([&] {
        for (std::size_t b = 0; b < boxes.size(); ++b) other[b] = query(context, boxes[b]);
      });
      std::vector<std::uint8_t> mine(boxes.size());
      for (std::size_t b = 0; b < boxes.size(); ++b) mine[b] = query(context, boxes[b]);
      worker.join();
      CHECK_MSG(mine == answers && other == answers, "%s: two threads querying one context disagree", name.c_str());
    }
  }
  CHECK_MSG(tally.wrong == 0, "%s: %ld boxes reported hidden are seen", name.c_str(), tally.wrong);
  CHECK_MSG(tally.hidden > 0, "%s: no box hidden: the test proves nothing", name.c_str());
  std::printf("| %s | %zu | %zu | %zu | %.1f | %.1f | %zu / %zu / %zu / %zu | %ld |\n", name.c_str(), cams.size(),
              tally.boxes, tally.truly_hidden, 100.0 * double(tally.hidden) / double(std::max<std::size_t>(tally.truly_hidden, 1)),
              100.0 * double(tally.objects_box_hidden) / double(std::max<std::size_t>(tally.objects_truly_hidden, 1)),
              tally.by_kind[0], tally.by_kind[1], tally.by_kind[2], tally.by_kind[3], tally.wrong);
  std::fflush(stdout);
  all.hidden += tally.hidden;
  all.by_kind[1] += tally.by_kind[1];
}

}  // namespace

int main() {
  std::printf("| scene | cameras | boxes | truly hidden | is_hidden hides %% of truly hidden boxes | culler's box test "
              "hides %% of truly hidden objects | hidden inside / through near / across sides / oriented | false hides |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---|---:|\n");
  Tally all;
  run_scene("city", support::make_city(3, MESH_OCC_SLOW ? 4 : 8), 31, all);
  run_scene("office", support::make_office(3, MESH_OCC_SLOW ? 5 : 10, MESH_OCC_SLOW ? 4 : 8), 37, all);
  std::uint64_t seed = 41;
  for (const auto& file : support::real_scene_files()) {
    if (file.find("oacmpdm9") == std::string::npos && file.find("fzk_haus") == std::string::npos &&
        (MESH_OCC_SLOW || file.find("lasdunas") == std::string::npos))
      continue;
    if (const auto scene = support::load_obj(support::scenes_dir() + "/" + file)) run_scene(file, *scene, seed++, all);
  }
  return cullkit_test::report("test_mesh_occlusion_box_query");
}
