// One answer for a degenerate camera across the containers: a NaN matrix entry, an all-NaN matrix,
// a NaN eye, an infinite eye, a zero matrix and a rank-deficient (singular) matrix. Nothing can be
// decided from such a camera, so every container answers "visible": AdaptiveBinaryTree (frustum cull
// and occlusion cull), OcclusionTree, MeshOcclusionCuller, NormalClassIndex (with and without
// moving objects), PortalGraph and BspTree. Where only the eye is bad and the matrix is good, the
// frustum still culls (it does not read the eye) and the answer is at least the frustum's. The
// good camera's answers are checked to be strictly smaller, so every "everything" here is a
// decision the containers made, not a scene where everything is visible anyway.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <glm/ext/matrix_transform.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

struct Variant {
  std::string name;
  Camera camera;
  bool bad_matrix;  // false: only the eye is bad
};

std::vector<Variant> variants(const Camera& good) {
  std::vector<Variant> v;
  Camera c = good;
  c.view_proj[2][1] = kNaN;
  v.push_back({"one NaN entry", c, true});
  c = good;
  c.view_proj = glm::mat4(kNaN);
  v.push_back({"NaN matrix", c, true});
  c = good;
  c.view_proj = glm::mat4(0.0f);
  v.push_back({"zero matrix", c, true});
  c = good;
  c.view_proj = good.view_proj * glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 0.0f, 1.0f));  // forgets world y
  v.push_back({"singular matrix", c, true});
  c = good;
  c.eye.y = kNaN;
  v.push_back({"NaN eye", c, false});
  c = good;
  c.eye = glm::vec3(kInf, 0.0f, 0.0f);
  v.push_back({"infinite eye", c, false});
  c = good;
  c.eye.z = -kInf;
  v.push_back({"-infinite eye", c, false});
  return v;
}

std::vector<std::uint32_t> sorted(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

bool includes(const std::vector<std::uint32_t>& big, const std::vector<std::uint32_t>& small) {
  return std::includes(big.begin(), big.end(), small.begin(), small.end());
}

}  // namespace

int main() {
  const Scene city = support::make_city(3, 4);
  const glm::vec3 c = city.bounds.center();
  const Camera good = support::make_camera(glm::vec3(c.x - 40.0f, city.bounds.min.y + 2.0f, c.z - 35.0f), c, 50.0f,
                                           96, 72, 0.1f, 1000.0f);
  const std::size_t n_objects = city.objects.size();
  std::vector<Aabb> boxes;
  std::vector<MeshObject> mesh_objects;
  for (const auto& o : city.objects) {
    boxes.push_back(o.bounds);
    mesh_objects.push_back(MeshObject{o.first_triangle, o.triangle_count});
  }
  const AdaptiveBinaryTree<Aabb> abt(boxes.data(), boxes.size());
  const MeshOcclusionCuller<glm::vec3> moc(city.mesh(), mesh_objects.data(), mesh_objects.size());
  const NormalClassIndex<glm::vec3> nci(city.mesh());
  const Scene room = support::make_office(4, 1, 1);
  const NormalClassIndex<glm::vec3> room_index(room.mesh());
  const NciMovingObject<NormalClassIndex<glm::vec3>> mover{&room_index, glm::translate(glm::mat4(1.0f), c), 9u};
  const BspTree<glm::vec3> bsp(room.mesh());

  // The good camera: each container hides or culls something.
  std::vector<std::uint32_t> good_abt, good_moc, out;
  abt.cull(Frustum::from_matrix(good.view_proj), good_abt);
  good_abt = sorted(good_abt);
  moc.cull(good, good_moc);
  good_moc = sorted(good_moc);
  const VisibleSet good_nci = nci.select_visible(good);
  CHECK(good_abt.size() < n_objects);
  CHECK(good_moc.size() < good_abt.size());
  CHECK(good_nci.triangles.size() < nci.triangle_count() && !good_nci.triangles.empty());
  // Occluders for the occlusion tree: the big closed solids of the city.
  std::vector<Aabb> occluders;
  for (const auto& o : city.objects)
    if (o.major_occluder && o.is_box && !contains(o.bounds, good.eye)) occluders.push_back(o.bounds);
  OcclusionTree good_tree(good.eye);
  for (const Aabb& b : occluders) good_tree.insert_box_occluder(b);
  std::size_t hidden_by_good_tree = 0;
  for (const Aabb& b : boxes) hidden_by_good_tree += good_tree.is_occluded(b);

  std::vector<std::uint32_t> all_objects(n_objects);
  for (std::size_t i = 0; i < n_objects; ++i) all_objects[i] = static_cast<std::uint32_t>(i);
  std::vector<std::uint32_t> all_triangles;
  for (std::uint32_t t = 0; t < city.triangle_count(); ++t)
    if (nci.triangle_class(t) >= 0) all_triangles.push_back(t);

  for (const Variant& v : variants(good)) {
    const Camera& cam = v.camera;
    const Frustum frustum = Frustum::from_matrix(cam.view_proj, cam.depth);
    std::printf("%-16s frustum planes %d\n", v.name.c_str(), __builtin_popcount(frustum.active_mask()));
    // AdaptiveBinaryTree: everything for a bad matrix; the good camera's frustum answer for a bad eye.
    abt.cull(frustum, out);
    out = sorted(out);
    if (v.bad_matrix) CHECK_MSG(out == all_objects, "%s: ABT kept %zu of %zu", v.name.c_str(), out.size(), n_objects);
    else CHECK(out == good_abt);
    // OcclusionTree at the camera's eye: a bad eye accepts no occluder and hides nothing.
    OcclusionTree tree(cam.eye);
    for (const Aabb& b : occluders) tree.insert_box_occluder(b);
    std::size_t hidden = 0;
    for (const Aabb& b : boxes) hidden += tree.is_occluded(b);
    if (!v.bad_matrix) CHECK_MSG(hidden == 0, "%s: occlusion tree hid %zu", v.name.c_str(), hidden);
    abt.cull(frustum, tree, out);
    out = sorted(out);
    if (!v.bad_matrix) CHECK(out == good_abt);
    // MeshOcclusionCuller: nothing occludes; everything the frustum keeps.
    moc.cull(cam, out);
    out = sorted(out);
    if (v.bad_matrix) CHECK_MSG(out == all_objects, "%s: MOC kept %zu of %zu", v.name.c_str(), out.size(), n_objects);
    else CHECK_MSG(includes(out, good_abt), "%s: MOC kept %zu, frustum %zu", v.name.c_str(), out.size(), good_abt.size());
    // NormalClassIndex: every kept triangle, none tested, every pixel a miss.
    NciContext ctx;
    VisibleSet set;
    NciPixels px;
    nci.select_visible(cam, ctx, set, &px);
    CHECK_MSG(set.triangles == all_triangles, "%s: NCI selected %zu of %zu", v.name.c_str(), set.triangles.size(),
              all_triangles.size());
    CHECK(px.triangle.size() == 96u * 72u);
    CHECK(std::all_of(px.triangle.begin(), px.triangle.end(), [](std::uint32_t t) { return t == NciPixels::miss; }));
    std::vector<NciObjectTriangle> objs;
    nci.select_visible(cam, &mover, 1, ctx, set, objs, &px);
    CHECK(set.triangles == all_triangles);
    CHECK(objs.size() == room_index.triangle_count());
    // BspTree: every fragment once, from a NaN or infinite eye.
    bsp.back_to_front(cam.eye, out);
    out = sorted(out);
    bool each_once = out.size() == bsp.fragments().size();
    for (std::size_t i = 0; each_once && i < out.size(); ++i) each_once = out[i] == i;
    CHECK_MSG(each_once, "%s: BSP order is not every fragment once", v.name.c_str());
  }
  CHECK(hidden_by_good_tree > 0);  // the occluder hides something from a good eye

  // PortalGraph: three rooms in a row joined by doorways. A bad eye lists every cell with the
  // frustum's volume; a bad matrix's frustum has no planes, so every volume keeps everything.
  PortalGraph graph;
  for (int k = 0; k < 3; ++k) graph.add_cell();
  for (int k = 0; k < 2; ++k) {
    const float x = 10.0f * (k + 1);
    const glm::vec3 door[4] = {{x, 0, -1}, {x, 0, 1}, {x, 2, 1}, {x, 2, -1}};
    graph.add_portal(static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(k + 1), door, 4);
  }
  const Camera room_cam = support::make_camera(glm::vec3(5, 1, 0), glm::vec3(30, 1, 0), 60.0f, 64, 48, 0.1f, 100.0f);
  std::vector<PortalView> views;
  graph.visible_cells(0, room_cam.eye, Frustum::from_matrix(room_cam.view_proj), views);
  CHECK(views.size() == 3);
  const Camera side_cam = support::make_camera(glm::vec3(5, 1, 0), glm::vec3(5, 1, 30), 60.0f, 64, 48, 0.1f, 100.0f);
  graph.visible_cells(0, side_cam.eye, Frustum::from_matrix(side_cam.view_proj), views);
  CHECK(views.size() == 1);  // looking at a wall: only the eye's room
  for (const Variant& v : variants(side_cam)) {
    graph.visible_cells(0, v.camera.eye, Frustum::from_matrix(v.camera.view_proj), views);
    std::vector<std::uint32_t> cells;
    for (const PortalView& pv : views) cells.push_back(pv.cell);
    cells = sorted(cells);
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    if (!v.bad_matrix) {
      CHECK_MSG(cells.size() == 3, "%s: portals listed %zu cells", v.name.c_str(), cells.size());
    } else {
      // The frustum has no planes; each listed volume holds at most the portals' planes.
      bool open = true;
      for (const PortalView& pv : views) open = open && (pv.cell != 0 || pv.volume.plane_count() == 0);
      CHECK_MSG(open, "%s: the eye's cell is narrowed", v.name.c_str());
      CHECK_MSG(cells.size() == 3, "%s: portals listed %zu cells", v.name.c_str(), cells.size());
    }
  }
  return cullkit_test::report("test_engine_degenerate_camera");
}
