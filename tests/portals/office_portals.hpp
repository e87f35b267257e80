// tests/portals/office_portals.hpp: the generated office as cells and portals (rooms and door gaps
// known by construction), its object lists, and the camera sets of the portal tests and benchmark.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

namespace portal_test {

using namespace cullkit;

struct OfficePortals {
  support::Scene scene;
  support::OfficeCells cells;
  PortalGraph graph;
  CellObjects objects;
  std::vector<Aabb> bounds;
  std::vector<std::uint32_t> object_of_triangle;
};

inline void build_office(OfficePortals& o, std::uint32_t seed, int rooms_x, int rooms_z) {
  o.scene = support::make_office(seed, rooms_x, rooms_z, &o.cells);
  o.graph = PortalGraph();
  for (const Aabb& room : o.cells.rooms) o.graph.set_cell_bounds(o.graph.add_cell(), room);
  for (const support::OfficeCells::Door& d : o.cells.doors) o.graph.add_portal(d.room_a, d.room_b, d.corners, 4);
  o.bounds = o.scene.object_bounds();
  o.objects.build(o.graph, o.bounds.data(), o.bounds.size());
  o.object_of_triangle.assign(o.scene.triangle_count(), 0u);
  for (std::uint32_t i = 0; i < o.scene.objects.size(); ++i) {
    const support::SceneObject& so = o.scene.objects[i];
    for (std::uint32_t t = 0; t < so.triangle_count; ++t) o.object_of_triangle[so.first_triangle + t] = i;
  }
}

/// A named camera and the cell its eye is in (`PortalGraph::no_cell` outside every room).
struct OfficeCamera {
  std::string kind;
  Camera camera;
};

inline bool near_any(const std::vector<Aabb>& boxes, const glm::vec3& p, float margin) {
  for (const Aabb& b : boxes)
    if (p.x >= b.min.x - margin && p.x <= b.max.x + margin && p.y >= b.min.y - margin && p.y <= b.max.y + margin &&
        p.z >= b.min.z - margin && p.z <= b.max.z + margin)
      return true;
  return false;
}

inline glm::vec3 heading(support::Rng& rng, float pitch_lo, float pitch_hi) {
  const float yaw = rng.uniform(0.0f, 6.2831853f), pitch = rng.uniform(pitch_lo, pitch_hi) * 0.017453293f;
  return glm::vec3(std::cos(yaw) * std::cos(pitch), std::sin(pitch), std::sin(yaw) * std::cos(pitch));
}

/// Camera sets. `random`: eyes anywhere in a room, clear of furniture and walls. `near`: the eye
/// 0.11 to 0.3 m in front of a door's plane, looking through it, with a near plane farther than the
/// door. `doorway`: the eye on the door's plane inside the opening. `grazing`: the eye 0.2 to 0.5 m
/// from a wall, looking along it past the door at 3 to 15 degrees. `outside`: above the building
/// (in no room), looking down.
inline std::vector<OfficeCamera> office_cameras(const OfficePortals& o, std::uint32_t seed, int per_kind, int width,
                                                int height, bool hard) {
  support::Rng rng(seed);
  std::vector<OfficeCamera> cams;
  const float diag = glm::length(o.scene.bounds.max - o.scene.bounds.min);
  for (int made = 0, tries = 0; made < per_kind * (hard ? 2 : 1) && tries < 10000; ++tries) {
    const Aabb room = o.cells.rooms[rng.next() % o.cells.rooms.size()];
    // Braces and one draw per statement elsewhere: the same cameras on every compiler.
    const glm::vec3 eye{rng.uniform(room.min.x + 0.3f, room.max.x - 0.3f), rng.uniform(1.0f, 1.8f),
                        rng.uniform(room.min.z + 0.3f, room.max.z - 0.3f)};
    if (near_any(o.bounds, eye, 0.2f)) continue;
    const glm::vec3 look = heading(rng, -20.0f, 10.0f);
    const float fov = rng.uniform(60.0f, 90.0f);
    cams.push_back({"random", support::make_camera(eye, eye + look, fov, width, height, 0.1f, diag)});
    ++made;
  }
  if (!hard) return cams;
  for (int k = 0; k < per_kind; ++k) {
    const support::OfficeCells::Door& d = o.cells.doors[rng.next() % o.cells.doors.size()];
    Aabb gap = Aabb::empty();
    for (const glm::vec3& q : d.corners) gap = merge(gap, q);
    const glm::vec3 c = (gap.min + gap.max) * 0.5f;
    const glm::vec3 n = glm::normalize(glm::cross(d.corners[1] - d.corners[0], d.corners[2] - d.corners[0]));
    const float side = rng.uniform() < 0.5f ? 1.0f : -1.0f;  // from room_a (-1) or room_b (+1)
    const glm::vec3 along = glm::normalize(glm::vec3(gap.max.x - gap.min.x, 0.0f, gap.max.z - gap.min.z));
    {  // near: in front of the door, nearer than the near plane
      const float gap = rng.uniform(0.11f, 0.3f);
      const float sideways = rng.uniform(-0.3f, 0.3f), up = rng.uniform(-0.3f, 0.5f);
      const float turn = rng.uniform(-0.8f, 0.8f), tilt = rng.uniform(-0.3f, 0.2f);
      const float fov = rng.uniform(60.0f, 90.0f), near_plane = gap + rng.uniform(0.05f, 1.0f);
      const glm::vec3 eye = c + n * (side * gap) + along * sideways + glm::vec3(0, up, 0);
      const glm::vec3 dir = -side * n + along * turn + glm::vec3(0, tilt, 0);
      cams.push_back({"near", support::make_camera(eye, eye + dir, fov, width, height, near_plane, diag)});
    }
    {  // doorway: on the door's plane, inside the opening
      const float across = rng.uniform(0.05f, 0.95f), up = rng.uniform(0.8f, 1.9f);
      const glm::vec3 eye = glm::vec3(gap.min.x, 0.0f, gap.min.z) + along * across + glm::vec3(0, up, 0);
      const glm::vec3 look = heading(rng, -20.0f, 10.0f);
      const float fov = rng.uniform(60.0f, 90.0f), near_plane = rng.uniform() < 0.5f ? 0.05f : 0.5f;
      cams.push_back({"doorway", support::make_camera(eye, eye + look, fov, width, height, near_plane, diag)});
    }
    {  // grazing: along the wall, past the door
      const float off = rng.uniform(0.2f, 0.5f), back = rng.uniform(1.0f, 2.5f);
      const float dir_sign = rng.uniform() < 0.5f ? 1.0f : -1.0f;
      const float up = rng.uniform(-0.3f, 0.6f);
      const glm::vec3 eye = c + n * (side * off) - along * (dir_sign * back) + glm::vec3(0, up, 0);
      const float ang = rng.uniform(3.0f, 15.0f) * 0.017453293f;
      const glm::vec3 dir = along * (dir_sign * std::cos(ang)) - n * (side * std::sin(ang));
      const float fov = rng.uniform(50.0f, 80.0f);
      if (!near_any(o.bounds, eye, 0.05f) && o.graph.locate_cell(eye) != PortalGraph::no_cell)
        cams.push_back({"grazing", support::make_camera(eye, eye + dir, fov, width, height, 0.1f, diag)});
    }
  }
  for (int k = 0; k < 3; ++k) {
    const glm::vec3 eye{rng.uniform(o.scene.bounds.min.x, o.scene.bounds.max.x), 12.0f,
                        rng.uniform(o.scene.bounds.min.z, o.scene.bounds.max.z)};
    const glm::vec3 look{rng.uniform(-1.0f, 1.0f), -2.0f, rng.uniform(-1.0f, 1.0f)};
    cams.push_back({"outside", support::make_camera(eye, eye + look, 70.0f, width, height, 0.1f, diag)});
  }
  return cams;
}

}  // namespace portal_test
