// make_office: one floor of rooms on a grid, with walls (door gaps), floors and furniture.
//
// Room (i, j) covers [i * room_w, (i + 1) * room_w] x [j * room_d, (j + 1) * room_d] (metres, Y up).
// Each room owns the wall on its -X side and the one on its -Z side; the last column and row add
// the outer +X and +Z walls. A wall is a thin box centred on the room boundary, split into boxes
// around a door gap (left part, right part, lintel above the door); walls between rooms always get a
// door, outer walls never do. Every wall piece is a major-occluder box. Furniture stands on the
// floor tiles (y = 0) and stays clear of the walls: desks (top + 4 legs, one object), chairs
// (seat, back, post: one object) and monitors (screen + foot: one object) per workstation.
#include <algorithm>
#include <string>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

namespace {

constexpr float kRoomW = 6.0f, kRoomD = 5.0f;  // room size along X and Z
constexpr float kWallH = 3.0f, kWallT = 0.2f;  // wall height and thickness
constexpr float kDoorW = 1.0f, kDoorH = 2.1f;

// Appends the 12 triangles of `b` to a mesh under construction.
void append_box(std::vector<glm::vec3>& pos, std::vector<std::uint32_t>& idx, const Aabb& b) {
  const auto base = static_cast<std::uint32_t>(pos.size());
  for (int i = 0; i < 8; ++i) pos.push_back(corner(b, i));
  for (std::uint32_t k : kBoxTriangleCorners) idx.push_back(base + k);
}

// A wall along `axis` (0: runs along X at z = `at`; 2: runs along Z at x = `at`) from `from` to
// `to`, with an optional door gap starting at `door` (NaN-free: pass door < from for none).
void wall(Scene& scene, int axis, float at, float from, float to, float door, bool has_door, const std::string& name) {
  auto piece = [&](float a, float b, float y0, float y1, const char* part) {
    if (!(b > a)) return;
    Aabb box;
    if (axis == 0) box = Aabb{{a, y0, at - 0.5f * kWallT}, {b, y1, at + 0.5f * kWallT}};
    else box = Aabb{{at - 0.5f * kWallT, y0, a}, {at + 0.5f * kWallT, y1, b}};
    scene.add_box(box, name + part, true);
  };
  if (!has_door) {
    piece(from, to, 0.0f, kWallH, "");
    return;
  }
  piece(from, door, 0.0f, kWallH, "_left");
  piece(door + kDoorW, to, 0.0f, kWallH, "_right");
  piece(door, door + kDoorW, kDoorH, kWallH, "_lintel");
}

}  // namespace

Scene make_office(std::uint32_t seed, int rooms_x, int rooms_z) { return make_office(seed, rooms_x, rooms_z, nullptr); }

Scene make_office(std::uint32_t seed, int rooms_x, int rooms_z, OfficeCells* cells) {
  Scene scene;
  if (cells) *cells = OfficeCells{};
  rooms_x = std::max(rooms_x, 0);
  rooms_z = std::max(rooms_z, 0);
  scene.name = "office_" + std::to_string(seed) + "_" + std::to_string(rooms_x) + "x" + std::to_string(rooms_z);
  if (rooms_x == 0 || rooms_z == 0) return scene;
  Rng rng(0x0FF1CEull ^ (static_cast<std::uint64_t>(seed) << 24));
  const float total_x = kRoomW * static_cast<float>(rooms_x), total_z = kRoomD * static_cast<float>(rooms_z);

  for (int j = 0; j < rooms_z; ++j) {
    for (int i = 0; i < rooms_x; ++i) {
      const std::string tag = std::to_string(i) + "_" + std::to_string(j);
      const float x0 = kRoomW * static_cast<float>(i), z0 = kRoomD * static_cast<float>(j);
      const float x1 = x0 + kRoomW, z1 = z0 + kRoomD;
      // Floor, facing up.
      scene.add_mesh({{x0, 0, z0}, {x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}}, {0, 1, 2, 0, 2, 3}, "floor_" + tag);
      // Walls: -Z side (door unless outer), -X side (door unless outer); then outer +X / +Z.
      // One draw per wall, in this order, door or not (the scene's bytes depend on it).
      const float door_z = x0 + rng.uniform(0.6f, kRoomW - kDoorW - 0.6f);
      wall(scene, 0, z0, x0, x1, door_z, j > 0, "wall_z_" + tag);
      const float door_x = z0 + rng.uniform(0.6f, kRoomD - kDoorW - 0.6f);
      wall(scene, 2, x0, z0, z1, door_x, i > 0, "wall_x_" + tag);
      if (cells) {
        const auto room = static_cast<std::uint32_t>(j * rooms_x + i);
        cells->rooms.push_back(Aabb{{x0, 0.0f, z0}, {x1, kWallH, z1}});
        if (j > 0)  // wall at z = z0 between room (i, j - 1) and this one; normal +Z
          cells->doors.push_back({room - static_cast<std::uint32_t>(rooms_x), room,
                                  {{door_z, 0, z0}, {door_z + kDoorW, 0, z0}, {door_z + kDoorW, kDoorH, z0}, {door_z, kDoorH, z0}}});
        if (i > 0)  // wall at x = x0 between room (i - 1, j) and this one; normal +X
          cells->doors.push_back({room - 1u, room,
                                  {{x0, 0, door_x}, {x0, kDoorH, door_x}, {x0, kDoorH, door_x + kDoorW}, {x0, 0, door_x + kDoorW}}});
      }
      if (i == rooms_x - 1) wall(scene, 2, total_x, z0, z1, 0.0f, false, "wall_x_" + std::to_string(i + 1) + "_" + std::to_string(j));
      if (j == rooms_z - 1) wall(scene, 0, total_z, x0, x1, 0.0f, false, "wall_z_" + std::to_string(i) + "_" + std::to_string(j + 1));

      // Workstations in a row along X, in the room's back half (+Z), clear of the walls and doors.
      const int stations = rng.range(2, 3);
      const float slot = (kRoomW - 1.0f) / static_cast<float>(stations);
      for (int k = 0; k < stations; ++k) {
        const std::string st = tag + "_" + std::to_string(k);
        const float dw = std::min(slot - 0.2f, rng.uniform(1.0f, 1.4f)), dd = rng.uniform(0.6f, 0.8f);
        const float dx = x0 + 0.5f + slot * static_cast<float>(k) + 0.5f * (slot - dw);
        const float dz = z1 - 0.6f - dd;
        const float top = 0.72f, th = 0.03f, leg = 0.05f;
        {
          std::vector<glm::vec3> p;
          std::vector<std::uint32_t> t;
          append_box(p, t, {{dx, top - th, dz}, {dx + dw, top, dz + dd}});
          for (int c = 0; c < 4; ++c) {
            const float lx = (c & 1) ? dx + dw - leg : dx, lz = (c & 2) ? dz + dd - leg : dz;
            append_box(p, t, {{lx, 0.0f, lz}, {lx + leg, top - th, lz + leg}});
          }
          scene.add_mesh(p, t, "desk_" + st);
        }
        {  // Monitor on the desk: a thin screen on a small foot, resting on the desktop.
          std::vector<glm::vec3> p;
          std::vector<std::uint32_t> t;
          const float mw = std::min(dw - 0.2f, rng.uniform(0.5f, 0.7f)), mx = dx + 0.5f * (dw - mw);
          const float mz = dz + dd - 0.25f;
          append_box(p, t, {{mx + 0.5f * mw - 0.1f, top, mz}, {mx + 0.5f * mw + 0.1f, top + 0.12f, mz + 0.15f}});
          append_box(p, t, {{mx, top + 0.12f, mz + 0.05f}, {mx + mw, top + 0.12f + rng.uniform(0.3f, 0.4f), mz + 0.09f}});
          scene.add_mesh(p, t, "monitor_" + st);
        }
        {  // Chair in front of the desk (toward -Z).
          std::vector<glm::vec3> p;
          std::vector<std::uint32_t> t;
          const float cw = 0.45f, cx = dx + 0.5f * dw - 0.5f * cw + rng.uniform(-0.15f, 0.15f);
          const float cz = dz - rng.uniform(0.35f, 0.6f) - cw, seat = 0.45f;
          append_box(p, t, {{cx + 0.5f * cw - 0.03f, 0.0f, cz + 0.5f * cw - 0.03f}, {cx + 0.5f * cw + 0.03f, seat - 0.05f, cz + 0.5f * cw + 0.03f}});
          append_box(p, t, {{cx, seat - 0.05f, cz}, {cx + cw, seat, cz + cw}});
          append_box(p, t, {{cx, seat, cz - 0.05f}, {cx + cw, seat + 0.45f, cz}});
          scene.add_mesh(p, t, "chair_" + st);
        }
      }
      // A cabinet against the -X wall in the front half, and a plant pot, to vary the rooms.
      if (rng.uniform() < 0.6f) {
        const float cz = z0 + rng.uniform(0.4f, 1.2f);
        scene.add_box({{x0 + 0.2f, 0.0f, cz}, {x0 + 0.7f, rng.uniform(1.0f, 2.0f), cz + 0.9f}}, "cabinet_" + tag, false);
      }
      if (rng.uniform() < 0.5f) {
        const float px = x1 - 0.7f, pz = z0 + rng.uniform(0.4f, 1.5f);
        std::vector<glm::vec3> p;
        std::vector<std::uint32_t> t;
        append_box(p, t, {{px, 0.0f, pz}, {px + 0.4f, 0.4f, pz + 0.4f}});
        append_box(p, t, {{px + 0.05f, 0.4f, pz + 0.05f}, {px + 0.35f, rng.uniform(1.0f, 1.6f), pz + 0.35f}});
        scene.add_mesh(p, t, "plant_" + tag);
      }
    }
  }
  return scene;
}

}  // namespace cullkit::support
