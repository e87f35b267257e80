// test_portals_office: zero false culls against Embree on the generated office, rooms as cells and
// door gaps as portals (known by construction).
//
// Oracle: one ray per pixel (cullkit::Camera rule, front faces only). For every pixel whose first
// hit lies inside the frustum (a hit nearer than the near plane is clipped by the renderer and
// excused), the object hit must be among the objects CellObjects::cull keeps, and the hit point must
// lie inside the volume of some entry of a room whose box holds it. Cameras: random eyes in rooms,
// and the hard cases (the eye nearer to a door than the near plane, the eye in a doorway, grazing
// views along a wall past a door, the eye above the building in no room). Also: the scene's bytes
// do not change when the generator reports its cells, and a mutant (the last entry of each room
// dropped) is caught.
#include <algorithm>
#include <cstdio>
#include <map>

#include "check.hpp"
#include "embree_oracle.hpp"
#include "office_portals.hpp"

using namespace cullkit;
using namespace portal_test;

namespace {

struct Tally {
  long pixels = 0, excused_near = 0, beyond_eye_room = 0, false_objects = 0, false_points = 0;
  long frustum_objects = 0, portal_objects = 0, seen_objects = 0;
};

// Checks one camera; returns the false culls (objects seen but not kept).
long check_camera(const OfficePortals& o, const oracle::EmbreeScene& embree, const Camera& cam,
                  const std::vector<PortalView>& views, const std::vector<std::uint32_t>& kept, std::uint32_t eye_cell,
                  Tally& t, bool report) {
  const Frustum f = Frustum::from_matrix(cam.view_proj);
  const oracle::HitBuffer hits = embree.render(cam, 1);
  const PixelRays rays(cam);
  std::vector<char> in(o.bounds.size(), 0), seen(o.bounds.size(), 0);
  for (std::uint32_t k : kept) in[k] = 1;
  long false_culls = 0;
  for (int y = 0; y < hits.height; ++y)
    for (int x = 0; x < hits.width; ++x) {
      const std::uint32_t tri = hits.at(x, y);
      if (tri == oracle::HitBuffer::miss) continue;
      const Ray r = rays.ray(x, y);
      const float dist = hits.distance[static_cast<std::size_t>(y) * hits.width + x];
      const glm::vec3 p = r.origin + r.direction * dist;
      ++t.pixels;
      // Before the near plane (by more than rounding): clipped by the renderer, hides nothing.
      const Plane& np = f.plane(Frustum::near_plane);
      if (f.has_plane(Frustum::near_plane) && signed_distance(np, p) < -1e-4f) {
        ++t.excused_near;
        continue;
      }
      const std::uint32_t obj = o.object_of_triangle[tri];
      seen[obj] = 1;
      if (!in[obj]) ++false_culls;
      // The promise is about points inside the frustum; a hit within rounding of its boundary
      // that the frustum itself calls outside is not one.
      if (eye_cell == PortalGraph::no_cell || !ConvexVolume(f).contains(p)) continue;
      bool covered = false, beyond = false;
      for (std::uint32_t c = 0; c < o.graph.cell_count() && !covered; ++c) {
        if (!o.graph.cell_meets(c, Aabb{p, p})) continue;
        beyond = beyond || c != eye_cell;
        for (const PortalView& v : views) covered = covered || (v.cell == c && v.volume.contains(p));
      }
      t.beyond_eye_room += beyond && !o.graph.cell_meets(eye_cell, Aabb{p, p});
      if (!covered) {
        ++t.false_points;
        if (report) {
          for (const PortalView& v : views) {
            if (!o.graph.cell_meets(v.cell, Aabb{p, p})) continue;
            for (std::size_t k = 0; k < v.volume.plane_count(); ++k)
              if (signed_distance(v.volume.plane(k), p) < 0.0f)
                std::fprintf(stderr, "    room %u plane %zu of %zu: distance %g\n", v.cell, k, v.volume.plane_count(),
                             signed_distance(v.volume.plane(k), p));
          }
        }
        if (report)
          CHECK_MSG(false, "pixel (%d %d) hit (%g %g %g) of %s outside every entry; eye (%g %g %g) in room %u", x, y, p.x,
                    p.y, p.z, o.scene.objects[obj].name.c_str(), cam.eye.x, cam.eye.y, cam.eye.z, eye_cell);
      }
    }
  for (std::size_t k = 0; k < seen.size(); ++k)
    if (seen[k] && !in[k] && report)
      CHECK_MSG(false, "%s seen but culled; eye (%g %g %g) in room %u", o.scene.objects[k].name.c_str(), cam.eye.x,
                cam.eye.y, cam.eye.z, eye_cell);
  t.seen_objects += std::count(seen.begin(), seen.end(), 1);
  t.false_objects += false_culls;
  t.portal_objects += static_cast<long>(kept.size());
  return false_culls;
}

void test_cells_match_scene() {
  support::OfficeCells cells;
  const support::Scene a = support::make_office(1, 10, 8), b = support::make_office(1, 10, 8, &cells);
  CHECK(a.positions == b.positions && a.indices == b.indices && a.objects.size() == b.objects.size());
  CHECK(cells.rooms.size() == 80);
  CHECK(cells.doors.size() == 9 * 8 + 10 * 7);
  // Every door opening is an actual gap: no wall piece's interior meets it, and a lintel sits on it.
  int blocked = 0, lintels = 0;
  for (const support::OfficeCells::Door& d : cells.doors) {
    Aabb gap = Aabb::empty();
    for (const glm::vec3& q : d.corners) gap = merge(gap, q);
    const int n = gap.min.x == gap.max.x ? 0 : 2, u = 2 - n;  // the door's normal axis, its width axis
    for (const support::SceneObject& so : a.objects) {
      if (so.name.rfind("wall_", 0) != 0) continue;
      const Aabb& w = so.bounds;
      const bool across = w.min[n] < gap.min[n] && gap.min[n] < w.max[n];
      const float wide = std::min(w.max[u], gap.max[u]) - std::max(w.min[u], gap.min[u]);
      const float high = std::min(w.max.y, gap.max.y) - std::max(w.min.y, gap.min.y);
      blocked += across && wide > 1e-4f && high > 1e-4f;
      lintels += across && so.name.find("_lintel") != std::string::npos && w.min.y == gap.max.y && wide > 0.99f;
    }
  }
  CHECK(blocked == 0);
  CHECK(lintels == static_cast<int>(cells.doors.size()));
}

}  // namespace

int main() {
  test_cells_match_scene();
  OfficePortals o;
  build_office(o, 7, 6, 5);
  oracle::EmbreeScene embree;
  embree.add_mesh(o.scene.positions.data(), o.scene.positions.size(), o.scene.indices.data(), o.scene.indices.size());
  embree.commit();
  const auto cams = office_cameras(o, 0x0FF1CE, 16, 160, 120, true);
  std::map<std::string, Tally> by_kind;
  PortalScratch scratch;
  std::vector<PortalView> views, dropped;
  std::vector<std::uint32_t> kept;
  long mutant_false = 0, total_false = 0;
  for (const OfficeCamera& oc : cams) {
    const Camera& cam = oc.camera;
    const Frustum f = Frustum::from_matrix(cam.view_proj);
    const std::uint32_t cell = o.graph.locate_cell(cam.eye);
    if (oc.kind == "outside") CHECK(cell == PortalGraph::no_cell);
    else CHECK_MSG(cell != PortalGraph::no_cell, "%s eye (%g %g %g) in no room", oc.kind.c_str(), cam.eye.x, cam.eye.y, cam.eye.z);
    o.graph.visible_cells(cell, cam.eye, f, views, scratch);
    o.objects.cull(f, views, kept, scratch);
    Tally& t = by_kind[oc.kind];
    total_false += check_camera(o, embree, cam, views, kept, cell, t, true);
    for (const support::SceneObject& so : o.scene.objects) t.frustum_objects += f.classify(so.bounds) != Containment::outside;
    // Mutant: the last entry of each room other than the eye's dropped.
    dropped.clear();
    for (std::size_t i = 0; i < views.size(); ++i) {
      bool last = i > 0;
      for (std::size_t j = i + 1; j < views.size(); ++j) last = last && views[j].cell != views[i].cell;
      if (!last) dropped.push_back(views[i]);
    }
    o.objects.cull(f, dropped, kept, scratch);
    Tally scrap;
    mutant_false += check_camera(o, embree, cam, dropped, kept, cell, scrap, false);
  }
  for (const auto& [kind, t] : by_kind)
    std::printf("%-8s pixels %7ld (%6ld before the near plane, %6ld in rooms beyond the eye's)  objects: frustum %5ld "
                "portals %5ld seen %5ld  false culls %ld, points outside %ld\n",
                kind.c_str(), t.pixels, t.excused_near, t.beyond_eye_room, t.frustum_objects, t.portal_objects,
                t.seen_objects, t.false_objects, t.false_points);
  std::printf("mutant (last entry of each room dropped): %ld false culls\n", mutant_false);
  CHECK(total_false == 0);
  CHECK(mutant_false > 0);
  CHECK(by_kind["near"].beyond_eye_room > 1000);
  CHECK(by_kind["doorway"].beyond_eye_room > 1000);
  CHECK(by_kind["grazing"].beyond_eye_room > 100);
  CHECK(by_kind["random"].portal_objects < by_kind["random"].frustum_objects / 2);
  return cullkit_test::report("test_portals_office");
}
