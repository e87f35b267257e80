// test_portals_bruteforce: PortalGraph::visible_cells against ray tracing through box rooms.
//
// Oracle: rays from the eye through the frustum are traced room by room (box_world.hpp); every
// point sampled along a traced ray that lies clearly inside the frustum must be inside the volume of
// some entry for the room it is in. The worlds and cameras cover the cases users report as bugs in
// other engines: the eye nearer to a portal than the near plane, the eye standing in a doorway,
// portals behind the eye, grazing rays through portal edges and corners, long chains of aligned
// doors, loops of rooms with tiny budgets, objects straddling a doorway, the eye in no cell, and
// portals the graph cannot use. Mutants (volumes shrunk by 5 cm past the portal, entries dropped)
// must be caught, and the traversal must have culled something, so the checks are not vacuous.
#include <algorithm>
#include <cstdio>

#include "box_world.hpp"
#include "check.hpp"

using namespace cullkit;
using namespace portal_test;

namespace {

struct Totals {
  long points = 0;           // sampled points checked
  long beyond_eye_cell = 0;  // of which in a room other than the eye's
  long uncovered = 0;        // of which no entry held (must stay 0)
  long culled_space = 0;     // random points of reached rooms outside every entry (narrowing works)
  long unreached = 0;        // rooms not listed at all
};

glm::dvec3 unproject(const Camera& cam, double x, double y) {
  const glm::dmat4 inv = glm::inverse(glm::dmat4(cam.view_proj));
  glm::dvec4 p = inv * glm::dvec4(x, y, 0.0, 1.0);
  return glm::dvec3(p) / p.w;
}

// Samples along the traced ray and counts points no entry holds. `eye_cell` is where tracing
// starts; `mutant` views are checked instead of `views` when given.
void check_ray(const BoxWorld& w, std::uint32_t eye_cell, const Camera& cam, const Frustum& f, const glm::dvec3& dir,
               const std::vector<PortalView>& views, support::Rng& rng, Totals& t, bool report) {
  const glm::dvec3 eye(cam.eye);
  const double len = glm::length(dir);
  if (!(len > 0.0)) return;
  const glm::dvec3 d = dir / len;
  for (const Segment& s : trace(w, eye_cell, eye, d)) {
    const double span = s.t1 - s.t0;
    const double ts[4] = {s.t0, s.t0 + span * rng.uniform(), s.t0 + span * rng.uniform(), s.t1};
    for (double tt : ts) {
      const glm::dvec3 p = eye + d * tt;
      if (!clearly_in(f, p, 1e-4)) continue;
      ++t.points;
      if (s.cell != eye_cell) ++t.beyond_eye_cell;
      if (!covered(views, s.cell, glm::vec3(p))) {
        ++t.uncovered;
        if (report)
          CHECK_MSG(false, "point (%g %g %g) of room %u not covered; eye (%g %g %g) in room %u", p.x, p.y, p.z, s.cell,
                    eye.x, eye.y, eye.z, eye_cell);
      }
    }
  }
}

// Rays: uniform over the screen, and aimed at portal corners and edges (grazing).
void check_camera(const BoxWorld& w, std::uint32_t eye_cell, const Camera& cam, const std::vector<PortalView>& views,
                  support::Rng& rng, Totals& t, bool report, int screen_rays = 200, int edge_rays = 150) {
  const Frustum f = Frustum::from_matrix(cam.view_proj);
  const glm::dvec3 eye(cam.eye);
  for (int r = 0; r < screen_rays; ++r)
  {
    const float sx = rng.uniform(-1.0f, 1.0f), sy = rng.uniform(-1.0f, 1.0f);
    check_ray(w, eye_cell, cam, f, unproject(cam, sx, sy) - eye, views, rng, t, report);
  }
  for (int r = 0; r < edge_rays && !w.portals.empty(); ++r) {
    const WorldPortal& p = w.portals[rng.next() % w.portals.size()];
    const std::size_t i = rng.next() % p.corners.size();
    const glm::vec3 a = p.corners[i], b = p.corners[(i + 1) % p.corners.size()];
    const float u = rng.uniform() < 0.3f ? 0.0f : rng.uniform();
    check_ray(w, eye_cell, cam, f, glm::dvec3(a + (b - a) * u) - eye, views, rng, t, report);
  }
}

void count_culling(const BoxWorld& w, const std::vector<PortalView>& views, support::Rng& rng, Totals& t) {
  std::vector<char> listed(w.rooms(), 0);
  for (const PortalView& v : views) listed[v.cell] = 1;
  for (std::uint32_t r = 0; r < w.rooms(); ++r) {
    if (!listed[r]) {
      ++t.unreached;
      continue;
    }
    const Aabb b = w.box(r);
    for (int k = 0; k < 4; ++k) {
      const glm::vec3 p{rng.uniform(b.min.x, b.max.x), rng.uniform(b.min.y, b.max.y), rng.uniform(b.min.z, b.max.z)};
      if (!covered(views, r, p)) ++t.culled_space;
    }
  }
}

glm::vec3 random_in(support::Rng& rng, const Aabb& b, float inset) {
  // Braces: the three draws happen left to right on every compiler.
  return glm::vec3{rng.uniform(b.min.x + inset, b.max.x - inset), rng.uniform(b.min.y + inset, b.max.y - inset),
                   rng.uniform(b.min.z + inset, b.max.z - inset)};
}

Camera random_camera(support::Rng& rng, const glm::vec3& eye, const glm::vec3& target) {
  const float nears[4] = {0.01f, 0.1f, 1.0f, 3.0f};
  const float near_plane = nears[rng.range(0, 3)];
  const float far_plane = rng.uniform() < 0.3f ? 0.0f : rng.uniform(10.0f, 80.0f);
  return support::make_camera(eye, target, rng.uniform(40.0f, 100.0f), 64, 48, near_plane, far_plane);
}

// Random grid worlds, random eyes and views.
void test_random_worlds(Totals& t) {
  support::Rng rng(0x9047A1);
  PortalScratch scratch;
  std::vector<PortalView> views;
  for (int world = 0; world < 30; ++world) {
    const int nx = rng.range(2, 5), ny = rng.range(1, 2), nz = rng.range(2, 5);
    const BoxWorld w = make_world(rng, nx, ny, nz, 0.6f);
    for (int c = 0; c < 20; ++c) {
      const std::uint32_t room = static_cast<std::uint32_t>(rng.next() % w.rooms());
      const glm::vec3 eye = random_in(rng, w.box(room), 0.05f);
      const Aabb all{glm::vec3(w.xs.front(), w.ys.front(), w.zs.front()), glm::vec3(w.xs.back(), w.ys.back(), w.zs.back())};
      const glm::vec3 target = random_in(rng, all, 0.0f);
      const Camera cam = random_camera(rng, eye, target);
      CHECK(w.graph.locate_cell(eye) == room);
      w.graph.visible_cells(room, eye, Frustum::from_matrix(cam.view_proj), views, scratch);
      CHECK(!views.empty() && views[0].cell == room);
      check_camera(w, room, cam, views, rng, t, true);
      count_culling(w, views, rng, t);
    }
  }
}

// The eye in front of a portal, nearer to it than the near plane, looking through it.
void test_eye_nearer_than_near_plane(Totals& t) {
  support::Rng rng(0x4EA7);
  PortalScratch scratch;
  std::vector<PortalView> views;
  int reached = 0, cases = 0, before_near = 0;
  for (int world = 0; world < 20; ++world) {
    const BoxWorld w = make_world(rng, 3, 1, 3, 0.8f);
    for (const WorldPortal& p : w.portals) {
      glm::vec3 centre(0.0f);
      for (const glm::vec3& q : p.corners) centre += q;
      centre /= static_cast<float>(p.corners.size());
      const bool from_a = rng.uniform() < 0.5f;
      glm::vec3 normal(0.0f);
      normal[p.axis] = from_a ? 1.0f : -1.0f;  // from the eye's room into the other
      const float gap = rng.uniform(0.002f, 0.3f);
      const glm::vec3 eye = centre - normal * gap;
      const float sway = rng.uniform(-0.3f, 0.3f), near_plane = gap + rng.uniform(0.05f, 2.0f);
      const Camera cam = support::make_camera(eye, eye + normal + glm::vec3(sway, 0.0f, 0.1f), 70.0f, 64, 48, near_plane,
                                              60.0f);
      const std::uint32_t room = from_a ? p.a : p.b, other = from_a ? p.b : p.a;
      const Frustum f = Frustum::from_matrix(cam.view_proj);
      // A traversal that clipped portals by the near plane would lose the room behind this one.
      bool all_before_near = true;
      for (const glm::vec3& q : p.corners) all_before_near = all_before_near && !f.contains(q);
      before_near += all_before_near;
      w.graph.visible_cells(room, eye, f, views, scratch);
      ++cases;
      for (const PortalView& v : views) reached += v.cell == other ? 1 : 0;
      CHECK(std::any_of(views.begin(), views.end(), [&](const PortalView& v) { return v.cell == other; }));
      check_camera(w, room, cam, views, rng, t, true, 100, 50);
    }
  }
  CHECK(cases > 50);
  CHECK(before_near > 50);
  std::printf("eye nearer than the near plane: %d cases (%d with the whole portal before the near plane), room "
              "behind listed %d times\n", cases, before_near, reached);
}

// The eye on a portal's plane, inside its polygon, in either room, looking anywhere.
void test_eye_in_doorway(Totals& t) {
  support::Rng rng(0xD00A);
  PortalScratch scratch;
  std::vector<PortalView> views;
  int cases = 0;
  for (int world = 0; world < 20; ++world) {
    const BoxWorld w = make_world(rng, 3, 1, 3, 0.8f);
    for (const WorldPortal& p : w.portals) {
      glm::vec3 eye(0.0f);
      for (const glm::vec3& q : p.corners) eye += q;
      eye /= static_cast<float>(p.corners.size());
      const std::uint32_t loc = w.graph.locate_cell(eye);
      CHECK(loc == p.a || loc == p.b);
      const std::uint32_t room = rng.uniform() < 0.5f ? p.a : p.b;
      const Aabb all{glm::vec3(w.xs.front(), w.ys.front(), w.zs.front()), glm::vec3(w.xs.back(), w.ys.back(), w.zs.back())};
      const glm::vec3 target = random_in(rng, all, 0.0f);
      const Camera cam = random_camera(rng, eye, target);
      w.graph.visible_cells(room, eye, Frustum::from_matrix(cam.view_proj), views, scratch);
      ++cases;
      check_camera(w, room, cam, views, rng, t, true, 100, 50);
    }
  }
  CHECK(cases > 50);
}

// A corridor of rooms along Z whose doors are the same rectangle: the eye at one end sees them all.
void test_aligned_chain(Totals& t) {
  BoxWorld w;
  w.nx = 1;
  w.ny = 1;
  w.nz = 40;
  w.xs = {0.0f, 4.0f};
  w.ys = {0.0f, 3.0f};
  for (int k = 0; k <= w.nz; ++k) w.zs.push_back(5.0f * static_cast<float>(k));
  for (std::uint32_t r = 0; r < w.rooms(); ++r) {
    w.graph.add_cell();
    CHECK(!w.graph.cell_has_shape(r));
    w.graph.set_cell_bounds(r, w.box(r));
    CHECK(w.graph.cell_has_shape(r));
  }
  CHECK(!w.graph.cell_has_shape(w.rooms()));  // not a cell
  for (int k = 0; k + 1 < w.nz; ++k) add_portal(w, w.room(0, 0, k), w.room(0, 0, k + 1), 2, rect_portal(2, w.zs[k + 1], 1.5f, 2.5f, 0.0f, 2.1f));
  support::Rng rng(0xA119);
  std::vector<PortalView> views;
  for (int c = 0; c < 40; ++c) {
    const glm::vec3 eye{rng.uniform(1.6f, 2.4f), rng.uniform(0.5f, 2.0f), rng.uniform(0.1f, 4.9f)};
    const glm::vec3 target(2.0f + rng.uniform(-0.4f, 0.4f), 1.0f, 200.0f);
    const Camera cam = support::make_camera(eye, target, 60.0f, 64, 48, 0.1f, 0.0f);
    w.graph.visible_cells(0, eye, Frustum::from_matrix(cam.view_proj), views);
    std::uint32_t deepest = 0;
    for (const PortalView& v : views) deepest = std::max(deepest, v.cell);
    if (c == 0) std::printf("aligned doors: eye at z=%.2f reaches room %u of %u\n", eye.z, deepest, w.rooms() - 1);
    check_camera(w, 0, cam, views, rng, t, true, 100, 200);
  }
  // Straight down the middle, every door is seen.
  const glm::vec3 eye(2.0f, 1.0f, 2.5f);
  w.graph.visible_cells(0, eye, Frustum::from_matrix(support::make_camera(eye, glm::vec3(2.0f, 1.0f, 300.0f), 60.0f, 64, 48, 0.1f, 0.0f).view_proj), views);
  std::uint32_t deepest = 0;
  for (const PortalView& v : views) deepest = std::max(deepest, v.cell);
  CHECK(deepest == w.rooms() - 1);
}

// Loops: fully connected grids with big portals; default budgets and tiny ones (fallbacks taken).
void test_loops(Totals& t) {
  support::Rng rng(0x100B);
  std::vector<PortalView> views;
  PortalScratch scratch;
  int widened = 0, exhausted = 0;
  for (int world = 0; world < 12; ++world) {
    PortalParams params;
    if (world % 3 == 1) params.max_views_per_cell = 1;
    if (world % 3 == 2) {
      params.max_views_per_cell = 2;
      params.max_views = 12;
    }
    const BoxWorld w = make_world(rng, 4, 2, 4, 1.0f, params, true);
    for (int c = 0; c < 10; ++c) {
      const std::uint32_t room = static_cast<std::uint32_t>(rng.next() % w.rooms());
      const glm::vec3 eye = random_in(rng, w.box(room), 0.05f);
      const Aabb all{glm::vec3(w.xs.front(), w.ys.front(), w.zs.front()), glm::vec3(w.xs.back(), w.ys.back(), w.zs.back())};
      const glm::vec3 target = random_in(rng, all, 0.0f);
      const Camera cam = random_camera(rng, eye, target);
      w.graph.visible_cells(room, eye, Frustum::from_matrix(cam.view_proj), views, scratch);
      widened += scratch.stats().widened_arrivals > 0;
      exhausted += scratch.stats().budget_exhausted;
      CHECK(views.size() <= params.max_views + w.rooms());
      check_camera(w, room, cam, views, rng, t, true);
    }
  }
  std::printf("loops: %d traversals widened a portal side, %d hit the total budget\n", widened, exhausted);
  CHECK(widened > 0);
  CHECK(exhausted > 0);
}

// Objects straddling doorways are in both rooms and kept when seen through either.
void test_straddling_objects() {
  support::Rng rng(0x57AD);
  PortalScratch scratch;
  std::vector<PortalView> views;
  std::vector<std::uint32_t> kept;
  long seen = 0, missed = 0, straddlers_seen_beyond = 0;
  for (int world = 0; world < 15; ++world) {
    const BoxWorld w = make_world(rng, 3, 1, 3, 0.8f);
    std::vector<Aabb> objects;
    for (const WorldPortal& p : w.portals) {  // a box across each portal
      glm::vec3 c(0.0f);
      for (const glm::vec3& q : p.corners) c += q;
      c /= static_cast<float>(p.corners.size());
      objects.push_back(Aabb{c - glm::vec3(0.3f), c + glm::vec3(0.3f)});
    }
    const std::size_t straddlers = objects.size();
    for (std::uint32_t r = 0; r < w.rooms(); ++r)
      for (int k = 0; k < 5; ++k) {
        const glm::vec3 c = random_in(rng, w.box(r), 0.3f);
        objects.push_back(Aabb{c - glm::vec3(0.25f), c + glm::vec3(0.25f)});
      }
    objects.push_back(Aabb{glm::vec3(-100.0f), glm::vec3(-99.0f)});  // in no room
    const CellObjects cells(w.graph, objects.data(), objects.size());
    CHECK(cells.loose_objects().size() == 1);
    for (int c = 0; c < 15; ++c) {
      const std::uint32_t room = static_cast<std::uint32_t>(rng.next() % w.rooms());
      const glm::vec3 eye = random_in(rng, w.box(room), 0.05f);
      const Aabb all{glm::vec3(w.xs.front(), w.ys.front(), w.zs.front()), glm::vec3(w.xs.back(), w.ys.back(), w.zs.back())};
      const glm::vec3 target = random_in(rng, all, 0.0f);
      const Camera cam = random_camera(rng, eye, target);
      const Frustum f = Frustum::from_matrix(cam.view_proj);
      w.graph.visible_cells(room, eye, f, views, scratch);
      cells.cull(f, views, kept, scratch);
      std::vector<char> in(objects.size(), 0);
      for (std::uint32_t o : kept) {
        CHECK(!in[o]);  // once each
        in[o] = 1;
      }
      for (int r = 0; r < 1000; ++r) {
        const float sx = rng.uniform(-1.0f, 1.0f), sy = rng.uniform(-1.0f, 1.0f);
        const glm::dvec3 d = unproject(cam, sx, sy) - glm::dvec3(eye);
        const glm::dvec3 dn = d / glm::length(d);
        for (const Segment& s : trace(w, room, glm::dvec3(eye), dn)) {
          const glm::dvec3 p = glm::dvec3(eye) + dn * (s.t0 + (s.t1 - s.t0) * rng.uniform());
          if (!clearly_in(f, p, 1e-4)) continue;
          for (std::size_t o = 0; o < objects.size(); ++o) {
            if (!contains(objects[o], glm::vec3(p))) continue;
            ++seen;
            if (o < straddlers && s.cell != room) ++straddlers_seen_beyond;
            if (!in[o]) ++missed;
          }
        }
      }
    }
  }
  std::printf("straddling objects: %ld object points seen (%ld on doorway boxes beyond the eye's room), %ld missed\n",
              seen, straddlers_seen_beyond, missed);
  CHECK(seen > 1000);
  CHECK(straddlers_seen_beyond > 50);
  CHECK(missed == 0);
}

// The eye in no cell, a NaN eye, bad cell indices: every cell, with the frustum's volume.
void test_eye_outside() {
  support::Rng rng(0x0E7E);
  const BoxWorld w = make_world(rng, 3, 1, 3, 0.5f);
  const glm::vec3 outside(-50.0f, 1.0f, -50.0f);
  CHECK(w.graph.locate_cell(outside) == PortalGraph::no_cell);
  CHECK(w.graph.locate_cell(glm::vec3(std::nanf(""), 0.0f, 0.0f)) == PortalGraph::no_cell);
  const Camera cam = support::make_camera(outside, glm::vec3(5.0f, 1.0f, 5.0f), 60.0f, 64, 48, 0.1f, 100.0f);
  const Frustum f = Frustum::from_matrix(cam.view_proj);
  std::vector<PortalView> views;
  PortalScratch scratch;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t cell = k == 0 ? PortalGraph::no_cell : (k == 1 ? w.rooms() + 5 : 0u);
    const glm::vec3 eye = k == 2 ? glm::vec3(std::nanf(""), 1.0f, 1.0f) : outside;
    w.graph.visible_cells(cell, eye, f, views, scratch);
    CHECK(scratch.stats().eye_outside);
    CHECK(views.size() == w.rooms());
    for (std::uint32_t i = 0; i < views.size(); ++i) {
      CHECK(views[i].cell == i);
      CHECK(views[i].volume.plane_count() == ConvexVolume(f).plane_count());
    }
  }
  PortalGraph empty;
  empty.visible_cells(PortalGraph::no_cell, outside, f, views);
  CHECK(views.empty());
  CHECK(empty.locate_cell(outside) == PortalGraph::no_cell);
}

// Portals the graph cannot narrow with are open: conservative, and counted.
void test_bad_portals(Totals& t) {
  BoxWorld w;
  w.nx = 3;
  w.ny = 1;
  w.nz = 1;
  w.xs = {0.0f, 5.0f, 10.0f, 15.0f};
  w.ys = {0.0f, 3.0f};
  w.zs = {0.0f, 5.0f};
  for (std::uint32_t r = 0; r < 3; ++r) {
    w.graph.add_cell();
    w.graph.set_cell_bounds(r, w.box(r));
  }
  const float nan = std::nanf("");
  support::Rng poly_rng(7);
  std::vector<glm::vec3> many = random_portal(poly_rng, 0, 5.0f, 0.0f, 3.0f, 0.0f, 5.0f, 16);
  many.push_back(many.front() * 0.5f + many[1] * 0.5f);  // 17 corners
  std::vector<glm::vec3> bent = rect_portal(0, 10.0f, 0.5f, 2.5f, 1.0f, 4.0f);
  bent[2].x += 0.3f;  // not planar
  const glm::vec3 line[3] = {{5, 0, 0}, {5, 1, 1}, {5, 2, 2}};
  const glm::vec3 with_nan[3] = {{5, 0, 0}, {5, nan, 1}, {5, 2, 0}};
  CHECK(w.graph.add_portal(0, 7, line, 3) == PortalGraph::no_portal);
  CHECK(w.graph.add_portal(PortalGraph::no_cell, 0, line, 3) == PortalGraph::no_portal);
  CHECK(w.graph.stats().rejected_portals == 2);
  add_portal(w, 0, 1, 0, many);
  add_portal(w, 1, 2, 0, bent);
  w.graph.add_portal(0, 1, line, 3);
  w.graph.add_portal(0, 1, with_nan, 3);
  w.graph.add_portal(0, 1, nullptr, 0);
  w.graph.add_portal(1, 1, line, 3);  // to itself
  CHECK(w.graph.stats().open_portals == 6);
  CHECK(!w.graph.portal_usable(0));
  support::Rng rng(0xBAD);
  std::vector<PortalView> views;
  for (int c = 0; c < 20; ++c) {
    const glm::vec3 eye = random_in(rng, w.box(0), 0.1f);
    const glm::vec3 target{15.0f, rng.uniform(0.0f, 3.0f), rng.uniform(0.0f, 5.0f)};
    const Camera cam = random_camera(rng, eye, target);
    w.graph.visible_cells(0, eye, Frustum::from_matrix(cam.view_proj), views);
    CHECK(std::any_of(views.begin(), views.end(), [](const PortalView& v) { return v.cell == 2; }));
    check_camera(w, 0, cam, views, rng, t, true, 100, 50);
  }
}

// The checks must be able to fail: shrink every narrowed volume by moving its portal plane 5 cm
// further from the eye, or drop the last entry of each non-eye room; both must be caught.
void test_mutants() {
  support::Rng rng(0x3117);
  PortalScratch scratch;
  std::vector<PortalView> views, shrunk, dropped;
  Totals good, bad_shrunk, bad_dropped;
  for (int world = 0; world < 10; ++world) {
    const BoxWorld w = make_world(rng, 4, 1, 4, 0.7f);
    for (int c = 0; c < 10; ++c) {
      const std::uint32_t room = static_cast<std::uint32_t>(rng.next() % w.rooms());
      const glm::vec3 eye = random_in(rng, w.box(room), 0.05f);
      const Aabb all{glm::vec3(w.xs.front(), w.ys.front(), w.zs.front()), glm::vec3(w.xs.back(), w.ys.back(), w.zs.back())};
      const glm::vec3 target = random_in(rng, all, 0.0f);
      const Camera cam = random_camera(rng, eye, target);
      const Frustum f = Frustum::from_matrix(cam.view_proj);
      w.graph.visible_cells(room, eye, f, views, scratch);
      const std::size_t frustum_planes = ConvexVolume(f).plane_count();
      shrunk = views;
      for (std::size_t i = 1; i < shrunk.size(); ++i) {
        if (shrunk[i].volume.plane_count() <= frustum_planes) continue;
        ConvexVolume v;
        for (std::size_t k = 0; k < shrunk[i].volume.plane_count(); ++k) {
          Plane p = shrunk[i].volume.plane(k);
          if (k == frustum_planes) p.d -= 0.05f;
          v.add_plane(p);
        }
        shrunk[i].volume = v;
      }
      dropped.clear();
      for (std::size_t i = 0; i < views.size(); ++i) {
        bool last = i > 0;
        for (std::size_t j = i + 1; j < views.size(); ++j) last = last && views[j].cell != views[i].cell;
        if (!last) dropped.push_back(views[i]);
      }
      support::Rng r1(static_cast<std::uint64_t>(world * 100 + c)), r2 = r1, r3 = r1;
      check_camera(w, room, cam, views, r1, good, false);
      check_camera(w, room, cam, shrunk, r2, bad_shrunk, false);
      check_camera(w, room, cam, dropped, r3, bad_dropped, false);
    }
  }
  std::printf("mutants: %ld/%ld points uncovered (answer), %ld (portal plane moved 5 cm), %ld (an entry dropped)\n",
              good.uncovered, good.points, bad_shrunk.uncovered, bad_dropped.uncovered);
  CHECK(good.uncovered == 0);
  CHECK(bad_shrunk.uncovered > 0);
  CHECK(bad_dropped.uncovered > 0);
}

}  // namespace

int main() {
  Totals t;
  test_random_worlds(t);
  std::printf("random worlds: %ld points checked (%ld beyond the eye's room), %ld uncovered; %ld room samples "
              "outside every entry, %ld rooms not reached\n",
              t.points, t.beyond_eye_cell, t.uncovered, t.culled_space, t.unreached);
  CHECK(t.beyond_eye_cell > 10000);
  CHECK(t.culled_space > 1000);
  CHECK(t.unreached > 100);
  Totals hard;
  test_eye_nearer_than_near_plane(hard);
  test_eye_in_doorway(hard);
  test_aligned_chain(hard);
  test_loops(hard);
  test_bad_portals(hard);
  std::printf("hard cases: %ld points checked (%ld beyond the eye's room), %ld uncovered\n", hard.points,
              hard.beyond_eye_cell, hard.uncovered);
  CHECK(hard.beyond_eye_cell > 10000);
  test_straddling_objects();
  test_eye_outside();
  test_mutants();
  return cullkit_test::report("test_portals_bruteforce");
}
