// Cells and portals picture: the generated office from above, the rooms one view reaches through
// its doors, and the narrowed volume of each path.
//
//   build/release/examples/portals_picture [output-dir]     (writes <dir>/portals_topdown.png)
//
// Rooms are the cells and door openings the portals (the office generator reports both). The view
// (blue lines: the frustum's footprint) is the one of 300 seeded random views that reaches the most
// rooms. Every pixel is a point at eye height: white in rooms the traversal never reaches, pale
// yellow in reached rooms but outside every volume listed for that room, blue in the eye's room
// inside the frustum, green inside a narrowed volume (darker where several paths overlap). Doors:
// green when both their rooms are reached, grey otherwise. Objects: filled dark blue when the
// portal cull keeps them and the occlusion tree (grown from the kept walls, nearest first) does not
// hide them, purple when portals keep them and occlusion removes them, outlined grey when culled.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;
using support::Rgb;

namespace {

struct Office {
  support::Scene scene;
  support::OfficeCells cells;
  PortalGraph graph;
  std::vector<Aabb> bounds;
  CellObjects objects;
};

Camera pick_view(const Office& o, PortalScratch& scratch, std::vector<PortalView>& views) {
  support::Rng rng(0x71C7);
  Camera best{};
  std::size_t best_rooms = 0;
  for (int k = 0; k < 300; ++k) {
    const Aabb room = o.cells.rooms[rng.next() % o.cells.rooms.size()];
    const glm::vec3 eye{rng.uniform(room.min.x + 0.5f, room.max.x - 0.5f), 1.6f, rng.uniform(room.min.z + 0.5f, room.max.z - 0.5f)};
    const float yaw = rng.uniform(0.0f, 6.2831853f);
    const Camera cam = support::make_camera(eye, eye + glm::vec3(std::cos(yaw), -0.05f, std::sin(yaw)), 70.0f, 640, 480, 0.1f, 100.0f);
    o.graph.visible_cells(o.graph.locate_cell(eye), eye, Frustum::from_matrix(cam.view_proj), views, scratch);
    std::vector<std::uint32_t> rooms;
    for (const PortalView& v : views) rooms.push_back(v.cell);
    std::sort(rooms.begin(), rooms.end());
    const std::size_t n = static_cast<std::size_t>(std::unique(rooms.begin(), rooms.end()) - rooms.begin());
    if (n > best_rooms) {
      best_rooms = n;
      best = cam;
    }
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  Office o;
  o.scene = support::make_office(1, 8, 6, &o.cells);
  for (const Aabb& room : o.cells.rooms) o.graph.set_cell_bounds(o.graph.add_cell(), room);
  for (const auto& d : o.cells.doors) o.graph.add_portal(d.room_a, d.room_b, d.corners, 4);
  o.bounds = o.scene.object_bounds();
  o.objects.build(o.graph, o.bounds.data(), o.bounds.size());

  PortalScratch scratch;
  std::vector<PortalView> views;
  const Camera cam = pick_view(o, scratch, views);
  const Frustum frustum = Frustum::from_matrix(cam.view_proj);
  const std::uint32_t eye_cell = o.graph.locate_cell(cam.eye);
  o.graph.visible_cells(eye_cell, cam.eye, frustum, views, scratch);
  std::vector<std::uint32_t> kept;
  o.objects.cull(frustum, views, kept, scratch);

  // Occlusion on top: nearest kept object first; walls found visible become box occluders.
  std::vector<std::pair<float, std::uint32_t>> order;
  for (std::uint32_t k : kept) {
    const glm::vec3 d = glm::max(glm::max(o.bounds[k].min - cam.eye, cam.eye - o.bounds[k].max), glm::vec3(0.0f));
    order.push_back({glm::dot(d, d), k});
  }
  std::sort(order.begin(), order.end());
  OcclusionTree tree(cam.eye);
  std::vector<int> state(o.bounds.size(), 0);  // 0 culled, 1 kept, 2 hidden by occlusion
  for (const auto& [dist, k] : order) {
    (void)dist;
    if (!tree.empty() && tree.is_occluded(o.bounds[k])) {
      state[k] = 2;
      continue;
    }
    state[k] = 1;
    if (o.scene.objects[k].is_box && o.scene.objects[k].major_occluder) tree.insert_box_occluder(o.bounds[k]);
  }

  Aabb world = o.scene.bounds;
  world.min -= glm::vec3(1.0f);
  world.max += glm::vec3(1.0f);
  support::TopDownMap map(world, 1400);
  support::Image& img = map.image();
  // Invert the map's linear pixel mapping from three reference points.
  const glm::vec2 p0 = map.to_pixel(glm::vec3(0.0f)), px = map.to_pixel(glm::vec3(1.0f, 0.0f, 0.0f)),
                  pz = map.to_pixel(glm::vec3(0.0f, 0.0f, 1.0f));
  std::vector<char> reached(o.cells.rooms.size(), 0);
  for (const PortalView& v : views) reached[v.cell] = 1;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x) {
      const float wx = (static_cast<float>(x) + 0.5f - p0.x) / (px.x - p0.x);
      const float wz = (static_cast<float>(y) + 0.5f - p0.y) / (pz.y - p0.y);
      const glm::vec3 p(wx, cam.eye.y, wz);
      const std::uint32_t c = o.graph.locate_cell(p);
      Rgb col{255, 255, 255};
      if (c != PortalGraph::no_cell && reached[c]) {
        int inside = 0;
        bool eye_volume = false;
        for (std::size_t i = 0; i < views.size(); ++i)
          if (views[i].cell == c && views[i].volume.contains(p)) {
            ++inside;
            eye_volume = eye_volume || i == 0;
          }
        if (eye_volume) col = Rgb{190, 215, 250};
        else if (inside > 0) {
          const int g = std::max(120, 215 - 30 * (inside - 1));
          col = Rgb{static_cast<std::uint8_t>(g - 40), static_cast<std::uint8_t>(std::min(255, g + 25)), static_cast<std::uint8_t>(g - 40)};
        } else col = Rgb{252, 240, 200};
      }
      img.set(x, y, col);
    }
  for (std::size_t k = 0; k < o.bounds.size(); ++k) {
    const support::SceneObject& so = o.scene.objects[k];
    if (so.name.rfind("floor_", 0) == 0) continue;
    const bool wall = so.major_occluder;
    if (state[k] == 1) map.box(so.bounds, wall ? Rgb{40, 40, 90} : Rgb{30, 60, 200});
    else if (state[k] == 2) map.box(so.bounds, Rgb{160, 60, 190});
    else if (wall) map.box(so.bounds, Rgb{150, 150, 150});
    else map.outline(so.bounds, Rgb{160, 160, 160});
  }
  for (std::uint32_t p = 0; p < o.graph.portal_count(); ++p) {
    const glm::vec3* q = o.graph.portal_corners(p);
    glm::vec3 lo = q[0], hi = q[0];
    for (std::size_t i = 1; i < o.graph.portal_corner_count(p); ++i) {
      lo = glm::min(lo, q[i]);
      hi = glm::max(hi, q[i]);
    }
    const bool passed = reached[o.graph.portal_cell(p, 0)] && reached[o.graph.portal_cell(p, 1)];
    for (float off = -0.12f; off <= 0.12f; off += 0.04f) {
      const glm::vec3 shift = lo.x == hi.x ? glm::vec3(off, 0, 0) : glm::vec3(0, 0, off);
      map.segment(lo + shift, hi + shift, passed ? Rgb{0, 170, 0} : Rgb{120, 120, 120});
    }
  }
  map.camera(cam, 60.0f, Rgb{20, 60, 220});
  const glm::vec2 e = map.to_pixel(cam.eye);
  img.fill_rect(static_cast<int>(e.x) - 4, static_cast<int>(e.y) - 4, static_cast<int>(e.x) + 4, static_cast<int>(e.y) + 4, Rgb{20, 60, 220});

  std::size_t n_kept = 0, n_hidden = 0, n_rooms = 0;
  for (int s : state) {
    n_kept += s == 1;
    n_hidden += s == 2;
  }
  for (char r : reached) n_rooms += r != 0;
  std::printf("eye (%.2f %.2f %.2f) in room %u: %zu entries, %zu of %zu rooms reached; %zu of %zu objects kept by "
              "portals, %zu of them hidden by occlusion\n",
              cam.eye.x, cam.eye.y, cam.eye.z, eye_cell, views.size(), n_rooms, o.cells.rooms.size(), n_kept + n_hidden,
              o.bounds.size(), n_hidden);
  const std::string path = dir + "/portals_topdown.png";
  if (!img.write_png(path)) {
    std::printf("could not write %s\n", path.c_str());
    return 1;
  }
  std::printf("wrote %s\n", path.c_str());
  return 0;
}
