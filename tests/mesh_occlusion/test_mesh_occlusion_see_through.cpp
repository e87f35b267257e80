// MeshObject::occludes and set_occludes: a see-through object is culled like any other and hides
// nothing. The shortest case (a glass quad in front of a crate face), switching an object off and on
// between culls, and Embree truth where rays pass through see-through objects (seeing them) and stop
// at the first front face of an occluding one: the generated city and office with glass panes,
// alpha-tested fences and foliage cards added, and oacmpdm9 with its own surface flags. The control
// (every object occluding) must make false culls on the same frames, or the frames prove nothing.
#include <cstdio>
#include <string>
#include <vector>

#include "check.hpp"
#include "frame_truth.hpp"
#include "walk_cameras.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

constexpr int kWalk = MESH_OCC_SLOW ? 3 : 10;

/// A 4x4 glass quad at z = 0 in front of a 1x1 crate face at z = -3, eye at z = 5.
void glass_in_front_of_crate() {
  const std::vector<glm::vec3> positions = {{-2, -2, 0}, {2, -2, 0},   {2, 2, 0},   {-2, 2, 0},
                                            {-0.5f, -0.5f, -3}, {0.5f, -0.5f, -3}, {0.5f, 0.5f, -3}, {-0.5f, 0.5f, -3}};
  const std::vector<std::uint32_t> indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  const MeshView<glm::vec3> mesh{positions.data(), positions.size(), indices.data(), indices.size()};
  const Camera cam = look_at({0, 0, 5}, {0, 0, 0});
  std::vector<std::uint32_t> out;
  {
    const MeshObject objects[2] = {{0, 2, false}, {2, 2}};
    const MeshOcclusionCuller<glm::vec3> culler(mesh, objects, 2);
    culler.cull(cam, out);
    CHECK_MSG(lists(out, 0) && lists(out, 1), "glass: the crate behind non-occluding glass must be kept");
    CHECK(!culler.occludes(0) && culler.occludes(1) && !culler.occludes(2));
  }
  {
    // Control: opaque, the same quad hides the crate.
    const MeshObject objects[2] = {{0, 2}, {2, 2}};
    MeshOcclusionCuller<glm::vec3> culler(mesh, objects, 2);
    MeshOcclusionContext context;
    culler.cull(cam, context, out);
    CHECK_MSG(lists(out, 0) && !lists(out, 1), "glass control: an opaque quad hides the crate");
    // A door of the level that opens, then closes again: no rebuild.
    culler.set_occludes(0, false);
    culler.cull(cam, context, out);
    CHECK_MSG(lists(out, 0) && lists(out, 1), "set_occludes(false): the crate is kept");
    culler.set_occludes(0, true);
    culler.cull(cam, context, out);
    CHECK_MSG(lists(out, 0) && !lists(out, 1), "set_occludes(true): the crate is hidden again");
    culler.set_occludes(7, false);  // out of range: ignored
    culler.cull(cam, context, out);
    CHECK(!lists(out, 1));
  }
}

struct Counts {
  std::size_t cameras = 0, see_through = 0;
  long false_culls = 0, control_false_culls = 0;
  double kept = 0, visible = 0;
};

void run_scene(const std::string& name, const support::Scene& scene, const std::vector<std::uint8_t>& see_through,
               std::uint64_t seed, bool expect_control_failures) {
  oracle::EmbreeScene walker;  // the walk treats every surface as a wall
  walker.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  walker.commit();
  const FrameOccluders occluders(scene, see_through);
  ObjectMap map(scene);
  Counts n;
  for (std::size_t o = 0; o < map.objects.size(); ++o) {
    map.objects[o].occludes = !see_through[o];
    n.see_through += see_through[o];
  }
  const MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), map.objects.data(), map.objects.size());
  std::vector<MeshObject> all_occlude = map.objects;
  for (MeshObject& o : all_occlude) o.occludes = true;
  const MeshOcclusionCuller<glm::vec3> control(scene.mesh(), all_occlude.data(), all_occlude.size());

  const WalkSpec spec = walk_spec(name, scene, walker, seed);
  const auto cams = walk_then_hard_cameras(spec, scene, walker, kWalk, kFrameWidth, kFrameHeight, seed + 1);
  std::vector<std::uint32_t> out;
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci].camera;
    const RaySet set = frame_rays(seed * 1000 + ci);
    const auto rays = cast_frame(occluders, map, cam, set);
    const auto seen = seen_objects(scene, see_through, rays, cam);
    const auto missing = [&](const std::vector<std::uint32_t>& answer) {
      std::vector<std::uint8_t> kept(seen.size(), 0);
      for (std::uint32_t o : answer) kept[o] = 1;
      long m = 0;
      for (std::size_t o = 0; o < seen.size(); ++o) m += seen[o] && !kept[o];
      return m;
    };
    culler.cull(cam, out);
    const long fc = missing(out);
    CHECK_MSG(fc == 0, "%s camera %zu (%s): %ld false culls with see-through objects", name.c_str(), ci,
              cams[ci].name.c_str(), fc);
    n.false_culls += fc;
    n.kept += triangles_of(map, out);
    double vis = 0;
    for (std::size_t o = 0; o < seen.size(); ++o) vis += seen[o] ? map.triangle_count[o] : 0;
    n.visible += vis;
    control.cull(cam, out);
    n.control_false_culls += missing(out);
    ++n.cameras;
  }
  const double total = double(scene.triangle_count()) * double(std::max<std::size_t>(n.cameras, 1));
  std::printf("| %s | %zu | %zu | %zu | %.2f | %.2f | %ld | %ld |\n", name.c_str(), scene.objects.size(), n.see_through,
              n.cameras, 100.0 * n.kept / total, 100.0 * n.visible / total, n.false_culls, n.control_false_culls);
  std::fflush(stdout);
  if (expect_control_failures)
    CHECK_MSG(n.control_false_culls > 0, "%s: every object occluding makes no false cull: the frames prove nothing",
              name.c_str());
}

}  // namespace

int main() {
  glass_in_front_of_crate();
  std::printf("| scene | objects | see-through | cameras | kept %% | visible %% | false culls | all occluding: false culls |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  {
    auto city = support::make_city(3, MESH_OCC_SLOW ? 4 : 8);
    const auto flags = add_see_through(city, MESH_OCC_SLOW ? 60 : 200, 6.0f, 5);
    run_scene("city", city, flags, 31, true);
  }
  {
    auto office = support::make_office(3, MESH_OCC_SLOW ? 5 : 10, MESH_OCC_SLOW ? 4 : 8);
    const auto flags = add_see_through(office, MESH_OCC_SLOW ? 60 : 200, 1.5f, 7);
    run_scene("office", office, flags, 37, true);
  }
  const std::string obj = support::scenes_dir() + "/oacmpdm9.obj";
  if (const auto map = support::load_obj(obj)) {
    const auto flags = quake_see_through(*map, support::scenes_dir() + "/oacmpdm9.json");
    std::size_t count = 0, triangles = 0;
    for (std::size_t o = 0; o < flags.size(); ++o)
      if (flags[o]) ++count, triangles += map->objects[o].triangle_count;
    CHECK_MSG(count == 18 && triangles == 2304, "oacmpdm9: %zu see-through objects, %zu triangles (18, 2304 expected)",
              count, triangles);
    run_scene("oacmpdm9.obj", *map, flags, 41, false);
  } else {
    std::printf("oacmpdm9 absent: skipped\n");
  }
  return cullkit_test::report("test_mesh_occlusion_see_through");
}
