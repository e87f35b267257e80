// make_city: a grid of blocks with box buildings, street and rooftop props, and ground tiles.
//
// Layout (metres, Y up): block b = (i, j) covers [origin + i * pitch, + block] on X and Z, where
// pitch = block + street. Every block gets one ground tile reaching half a street beyond it on each
// side, so the tiles pave the whole city without gaps or overlaps. Buildings stand at least
// `kSetback` inside their block; lamp posts and benches stand on the sidewalk band between the
// block edge and the setback; cars stand in the street beside the block, inside its ground tile.
// Rooftop props rest exactly on their roof: their min.y is the very float of the roof's max.y.
#include <algorithm>
#include <string>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

namespace {

constexpr float kBlock = 60.0f;   // block side
constexpr float kStreet = 14.0f;  // street width
constexpr float kSetback = 3.0f;  // buildings keep this far from the block edge

void ground_tile(Scene& scene, float x0, float z0, float x1, float z1, const std::string& name) {
  // Counter-clockwise seen from above (+Y).
  const std::vector<glm::vec3> p = {{x0, 0, z0}, {x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}};
  scene.add_mesh(p, {0, 1, 2, 0, 2, 3}, name);
}

struct Lot {
  float x0, z0, x1, z1;
};

}  // namespace

Scene make_city(std::uint32_t seed, int blocks) {
  Scene scene;
  scene.name = "city_" + std::to_string(seed) + "_" + std::to_string(std::max(blocks, 0));
  if (blocks <= 0) return scene;
  Rng rng(0xC17Cull ^ (static_cast<std::uint64_t>(seed) << 20));
  const float pitch = kBlock + kStreet;
  const float origin = -0.5f * (static_cast<float>(blocks) * pitch - kStreet);

  for (int j = 0; j < blocks; ++j) {
    for (int i = 0; i < blocks; ++i) {
      const std::string tag = std::to_string(i) + "_" + std::to_string(j);
      const float bx = origin + static_cast<float>(i) * pitch;
      const float bz = origin + static_cast<float>(j) * pitch;
      ground_tile(scene, bx - 0.5f * kStreet, bz - 0.5f * kStreet, bx + kBlock + 0.5f * kStreet,
                  bz + kBlock + 0.5f * kStreet, "ground_" + tag);

      // Lots: split the buildable area once along X, then each half along Z or not.
      const float ax0 = bx + kSetback, ax1 = bx + kBlock - kSetback;
      const float az0 = bz + kSetback, az1 = bz + kBlock - kSetback;
      std::vector<Lot> lots;
      const float sx = ax0 + (ax1 - ax0) * rng.uniform(0.35f, 0.65f);
      for (int half = 0; half < 2; ++half) {
        const float lx0 = half == 0 ? ax0 : sx, lx1 = half == 0 ? sx : ax1;
        if (rng.uniform() < 0.7f) {
          const float sz = az0 + (az1 - az0) * rng.uniform(0.35f, 0.65f);
          lots.push_back({lx0, az0, lx1, sz});
          lots.push_back({lx0, sz, lx1, az1});
        } else {
          lots.push_back({lx0, az0, lx1, az1});
        }
      }
      int building = 0;
      for (const Lot& lot : lots) {
        // Footprint: the lot less a random margin on each side (alleys between buildings).
        const float x0 = lot.x0 + rng.uniform(1.0f, 4.0f), x1 = lot.x1 - rng.uniform(1.0f, 4.0f);
        const float z0 = lot.z0 + rng.uniform(1.0f, 4.0f), z1 = lot.z1 - rng.uniform(1.0f, 4.0f);
        const float u = rng.uniform();
        const float height = 8.0f + 72.0f * u * u;  // mostly low, a few towers up to 80 m
        const Aabb b{{x0, 0.0f, z0}, {x1, height, z1}};
        const std::string bname = "building_" + tag + "_" + std::to_string(building++);
        scene.add_box(b, bname, true);
        // Rooftop props, resting exactly on the roof (min.y == height).
        if (rng.uniform() < 0.5f) {
          const float s = 0.3f, h = rng.uniform(3.0f, 9.0f);
          const float px = rng.uniform(x0 + 0.5f, x1 - 0.5f - s), pz = rng.uniform(z0 + 0.5f, z1 - 0.5f - s);
          scene.add_box({{px, height, pz}, {px + s, height + h, pz + s}}, "roof_antenna_" + bname, false);
        }
        if (rng.uniform() < 0.35f) {
          const float s = rng.uniform(2.0f, 3.5f), h = rng.uniform(2.0f, 4.0f);
          const float px = rng.uniform(x0 + 0.5f, x1 - 0.5f - s), pz = rng.uniform(z0 + 0.5f, z1 - 0.5f - s);
          scene.add_box({{px, height, pz}, {px + s, height + h, pz + s}}, "roof_tank_" + bname, false);
        }
      }
      // Street props. Lamp posts on the sidewalk band along the block's -Z and +Z edges.
      for (int k = 0; k < 2; ++k) {
        const float px = rng.uniform(bx + 1.0f, bx + kBlock - 1.5f);
        const float pz = k == 0 ? bz + 0.8f : bz + kBlock - 1.05f;
        scene.add_box({{px, 0.0f, pz}, {px + 0.25f, rng.uniform(5.0f, 7.0f), pz + 0.25f}},
                      "lamp_" + tag + "_" + std::to_string(k), false);
      }
      // A bench on the sidewalk along the -X edge.
      {
        const float pz = rng.uniform(bz + 2.0f, bz + kBlock - 4.0f);
        scene.add_box({{bx + 0.8f, 0.0f, pz}, {bx + 1.4f, 0.5f, pz + 1.8f}}, "bench_" + tag, false);
      }
      // Cars parked in the street on the block's +X side, inside this block's ground tile.
      const int cars = rng.range(0, 2);
      for (int k = 0; k < cars; ++k) {
        const float px = bx + kBlock + rng.uniform(0.5f, 0.5f * kStreet - 2.5f);
        const float pz = rng.uniform(bz, bz + kBlock - 4.6f);
        scene.add_box({{px, 0.0f, pz}, {px + 1.8f, rng.uniform(1.4f, 1.7f), pz + 4.5f}},
                      "car_" + tag + "_" + std::to_string(k), false);
      }
    }
  }
  return scene;
}

}  // namespace cullkit::support
