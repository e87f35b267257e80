// bench/bench_portals.cpp: cells and portals on the generated office, against frustum culling alone
// and frustum + occlusion culling, with what Embree really sees and a false-cull count.
//
// Scenes: make_office(1, 10, 10) (100 rooms), make_office(1, 10, 8) (the seed paper's office size),
// make_office(1, 32, 25) (800 rooms). Cells are the rooms, portals the door openings, both reported by
// the generator; objects go to every room their box meets (CellObjects).
// Cameras (seeded): `office_cameras` in tests/portals/office_portals.hpp: eyes in random rooms
// 1.0-1.8 m high, clear of furniture, random heading, pitch -20..+10 degrees, 60-90 degree vertical
// field of view, near 0.1, far the scene diagonal.
//
// Columns (triangles of the kept objects, as a share of the scene's triangles, mean over cameras):
//   frustum %       AdaptiveBinaryTree::cull(frustum)
//   frustum+occl %  cull_with_occlusion (ABT front to back, wall boxes grown into an OcclusionTree)
//   portals %       PortalGraph::visible_cells + CellObjects::cull
//   portals+occl %  the portal set, nearest first, each object tested against an OcclusionTree grown
//                   from the wall boxes of the portal set found visible (the occluders of visible
//                   cells hide what the portals let through)
//   visible %       objects some pixel of an Embree render sees (one ray per pixel centre, front
//                   faces, hit beyond the near plane)
//   x visible       portals % / visible %, and portals+occl % / visible %
//   views           PortalView entries per frame; rooms: distinct rooms reached per frame
//   false culls     (object, camera) pairs Embree sees that the portal set, or the portal+occlusion
//                   set, left out. Must be 0 (the program exits with 1 otherwise).
// Times: median over repetitions of the time to cull every camera once, divided by the camera count
// (single thread), for each contestant interleaved (race.hpp): frustum (ABT), portals (locate_cell +
// visible_cells + cull), portals+occl, frustum+occl. The CSV race rows come first, the table last.
//
// Usage: bench_portals [cameras=100] [width=320] [height=240]
// CULLKIT_BENCH_SMOKE=1: the 10x10 office only, 4 cameras, 80x60.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "../tests/oracle/embree_oracle.hpp"
#include "../tests/portals/office_portals.hpp"
#include "race.hpp"

using namespace cullkit;
using namespace portal_test;

namespace {

struct Culler {
  const OfficePortals& o;
  PortalScratch scratch;
  std::vector<PortalView> views;
  std::vector<std::uint32_t> kept, order;
  std::vector<std::pair<float, std::uint32_t>> by_distance;
  OcclusionTree tree{glm::vec3(0.0f)};

  explicit Culler(const OfficePortals& office) : o(office) {}

  void portals(const Camera& cam, const Frustum& f) {
    o.graph.visible_cells(o.graph.locate_cell(cam.eye), cam.eye, f, views, scratch);
    o.objects.cull(f, views, kept, scratch);
  }
  // Nearest first; an object is dropped only if the walls already inserted hide its box.
  void occlude(const Camera& cam, std::vector<std::uint32_t>& out) {
    by_distance.clear();
    for (std::uint32_t k : kept) {
      const Aabb& b = o.bounds[k];
      const glm::vec3 d = glm::max(glm::max(b.min - cam.eye, cam.eye - b.max), glm::vec3(0.0f));
      by_distance.push_back({glm::dot(d, d), k});
    }
    std::sort(by_distance.begin(), by_distance.end());
    tree.reset(cam.eye);
    out.clear();
    for (const auto& [dist, k] : by_distance) {
      (void)dist;
      if (!tree.empty() && tree.is_occluded(o.bounds[k])) continue;
      out.push_back(k);
      const support::SceneObject& so = o.scene.objects[k];
      if (so.is_box && so.major_occluder) tree.insert_box_occluder(so.bounds);
    }
  }
};

struct Row {
  std::string scene;
  std::size_t triangles = 0, objects = 0, rooms = 0, cameras = 0;
  double frustum = 0, frustum_occ = 0, portals = 0, portals_occ = 0, visible = 0, views = 0, reached = 0;
  long false_portals = 0, false_portals_occ = 0;
  double ns_frustum = 0, ns_portals = 0, ns_portals_occ = 0, ns_frustum_occ = 0;
};

std::size_t triangles_of(const support::Scene& s, const std::vector<std::uint32_t>& objs) {
  std::size_t n = 0;
  for (std::uint32_t k : objs) n += s.objects[k].triangle_count;
  return n;
}

Row run(const std::string& name, std::uint32_t seed, int rx, int rz, int ncam, int width, int height) {
  OfficePortals o;
  build_office(o, seed, rx, rz);
  Row row;
  row.scene = name;
  row.triangles = o.scene.triangle_count();
  row.objects = o.scene.objects.size();
  row.rooms = o.cells.rooms.size();
  const AdaptiveBinaryTree<Aabb> abt(o.bounds.data(), o.bounds.size());
  std::vector<std::uint8_t> box_flag(o.bounds.size());
  for (std::size_t k = 0; k < box_flag.size(); ++k) box_flag[k] = o.scene.objects[k].is_box && o.scene.objects[k].major_occluder;
  const BoxOccluderSource source{o.bounds.data(), box_flag.data()};
  oracle::EmbreeScene embree;
  embree.add_mesh(o.scene.positions.data(), o.scene.positions.size(), o.scene.indices.data(), o.scene.indices.size());
  embree.commit();
  const auto ocams = office_cameras(o, 0xBE7C0 + seed, ncam, width, height, false);
  std::vector<Camera> cams;
  std::vector<Frustum> frusta;
  for (const auto& oc : ocams) {
    cams.push_back(oc.camera);
    frusta.push_back(Frustum::from_matrix(oc.camera.view_proj));
  }
  row.cameras = cams.size();
  Culler c(o);
  std::vector<std::uint32_t> frustum_set, occ_set, portal_occ_set;
  OcclusionTree ftree(glm::vec3(0.0f));
  const double total = static_cast<double>(row.triangles);
  for (std::size_t i = 0; i < cams.size(); ++i) {
    const Camera& cam = cams[i];
    const Frustum& f = frusta[i];
    abt.cull(f, frustum_set);
    ftree.reset(cam.eye);
    cull_with_occlusion(abt, f, ftree, source, occ_set);
    c.portals(cam, f);
    c.occlude(cam, portal_occ_set);
    std::vector<char> reached(row.rooms, 0);
    for (const PortalView& v : c.views) reached[v.cell] = 1;
    row.views += static_cast<double>(c.views.size());
    row.reached += static_cast<double>(std::count(reached.begin(), reached.end(), 1));
    // Ground truth: objects hit by some pixel beyond the near plane.
    const oracle::HitBuffer hits = embree.render(cam, 1);
    const PixelRays rays(cam);
    std::vector<char> seen(row.objects, 0), in_p(row.objects, 0), in_po(row.objects, 0);
    for (std::uint32_t k : c.kept) in_p[k] = 1;
    for (std::uint32_t k : portal_occ_set) in_po[k] = 1;
    for (int y = 0; y < hits.height; ++y)
      for (int x = 0; x < hits.width; ++x) {
        const std::uint32_t tri = hits.at(x, y);
        if (tri == oracle::HitBuffer::miss) continue;
        const Ray r = rays.ray(x, y);
        const glm::vec3 p = r.origin + r.direction * hits.distance[static_cast<std::size_t>(y) * hits.width + x];
        if (signed_distance(f.plane(Frustum::near_plane), p) < -1e-4f) continue;
        seen[o.object_of_triangle[tri]] = 1;
      }
    std::vector<std::uint32_t> seen_list;
    for (std::uint32_t k = 0; k < row.objects; ++k) {
      if (!seen[k]) continue;
      seen_list.push_back(k);
      row.false_portals += !in_p[k];
      row.false_portals_occ += !in_po[k];
    }
    row.frustum += triangles_of(o.scene, frustum_set) / total;
    row.frustum_occ += triangles_of(o.scene, occ_set) / total;
    row.portals += triangles_of(o.scene, c.kept) / total;
    row.portals_occ += triangles_of(o.scene, portal_occ_set) / total;
    row.visible += triangles_of(o.scene, seen_list) / total;
  }
  const double n = static_cast<double>(cams.size());
  for (double* v : {&row.frustum, &row.frustum_occ, &row.portals, &row.portals_occ, &row.visible, &row.views, &row.reached})
    *v /= n;
  const auto res = cullkit_bench::race(
      name, {{"frustum_abt", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { abt.cull(frusta[i], frustum_set); cullkit_bench::keep(frustum_set); } }},
             {"portals", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { c.portals(cams[i], frusta[i]); cullkit_bench::keep(c.kept); } }},
             {"portals_occlusion", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { c.portals(cams[i], frusta[i]); c.occlude(cams[i], portal_occ_set); cullkit_bench::keep(portal_occ_set); } }},
             {"frustum_occlusion_abt", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { ftree.reset(cams[i].eye); cull_with_occlusion(abt, frusta[i], ftree, source, occ_set); cullkit_bench::keep(occ_set); } }}},
      15);
  row.ns_frustum = res[0].median_ns / n;
  row.ns_portals = res[1].median_ns / n;
  row.ns_portals_occ = res[2].median_ns / n;
  row.ns_frustum_occ = res[3].median_ns / n;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const bool smoke = cullkit_bench::smoke();
  int ncam = argc > 1 ? std::atoi(argv[1]) : 100, width = argc > 2 ? std::atoi(argv[2]) : 320,
      height = argc > 3 ? std::atoi(argv[3]) : 240;
  if (smoke) {
    ncam = 4;
    width = 80;
    height = 60;
  }
  std::vector<Row> rows;
  rows.push_back(run("office 10x10 (100 rooms)", 1, 10, 10, ncam, width, height));
  if (!smoke) {
    rows.push_back(run("office 10x8 (80 rooms)", 1, 10, 8, ncam, width, height));
    rows.push_back(run("office 32x25 (800 rooms)", 1, 32, 25, ncam, width, height));
  }
  std::printf("\n| scene | triangles | cameras | frustum %% | frustum+occl %% | portals %% | portals+occl %% | visible %% | "
              "portals / visible | portals+occl / visible | views | rooms reached | false culls | frustum us | "
              "portals us | portals+occl us | frustum+occl us | portals / frustum time |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  long false_total = 0;
  for (const Row& r : rows) {
    std::printf("| %s | %zu | %zu | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f | %ld | %.1f | %.1f | %.1f | "
                "%.1f | %.2f |\n",
                r.scene.c_str(), r.triangles, r.cameras, 100 * r.frustum, 100 * r.frustum_occ, 100 * r.portals,
                100 * r.portals_occ, 100 * r.visible, r.portals / r.visible, r.portals_occ / r.visible, r.views, r.reached,
                r.false_portals + r.false_portals_occ, r.ns_frustum / 1e3, r.ns_portals / 1e3, r.ns_portals_occ / 1e3,
                r.ns_frustum_occ / 1e3, r.ns_portals / r.ns_frustum);
    false_total += r.false_portals + r.false_portals_occ;
  }
  return false_total == 0 ? 0 : 1;
}
