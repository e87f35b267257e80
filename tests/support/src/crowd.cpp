// make_crowd: a field of many small objects, most of them smaller than a pixel when seen whole.
//
// Layout (metres, Y up): `side` x `side` lots of kPitch, centred on the origin, each paved by two
// up-facing ground triangles at y = 0. A lot holds one of:
//  * a box standing on the ground (4 walls and a roof, no floor), axis-aligned or turned about Y,
//    footprint small enough that a turned box stays inside its lot;
//  * a floating slab (a closed box, its underside facing down): overhangs for eyes below them;
//  * a tuft of thin, long triangles leaning out in seeded directions, each with both windings, so
//    rays graze many slivers in layers (the "hairball" case);
//  * nothing (bare ground).
// Lots of a row form one object. With `mixed`, a plaza of large boxes on one large ground quad is
// added beside the field on +X, so one view can hold both crowded and large-triangle parts.
// Only support::Rng and IEEE-exact operations (+, *, /, sqrt) are used, so the bytes do not depend
// on the compiler or its math library.
#include <algorithm>
#include <cmath>
#include <string>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

namespace {

constexpr float kPitch = 1.0f;

struct Builder {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  void tri(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const auto base = static_cast<std::uint32_t>(positions.size());
    positions.push_back(a);
    positions.push_back(b);
    positions.push_back(c);
    indices.insert(indices.end(), {base, base + 1, base + 2});
  }
  // Counter-clockwise seen from the side the quad faces: a, b, c, d in that order around it.
  void quad(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& d) {
    const auto base = static_cast<std::uint32_t>(positions.size());
    positions.insert(positions.end(), {a, b, c, d});
    indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  // A prism over the footprint p[0..3] (counter-clockwise seen from above) from y0 to y1: walls and
  // roof, and the floor when `floor`.
  void prism(const glm::vec3 (&p)[4], float y0, float y1, bool floor) {
    glm::vec3 lo[4], hi[4];
    for (int k = 0; k < 4; ++k) {
      lo[k] = glm::vec3(p[k].x, y0, p[k].z);
      hi[k] = glm::vec3(p[k].x, y1, p[k].z);
    }
    for (int k = 0; k < 4; ++k) {
      const int n = (k + 1) % 4;
      quad(lo[k], lo[n], hi[n], hi[k]);  // faces away from the footprint's inside
    }
    quad(hi[0], hi[1], hi[2], hi[3]);
    if (floor) quad(lo[0], lo[3], lo[2], lo[1]);
  }
};

// A footprint of half-extents (hx, hz) centred at (cx, cz), turned by the unit vector (c, s).
void footprint(float cx, float cz, float hx, float hz, float c, float s, glm::vec3 (&p)[4]) {
  // Counter-clockwise seen from above: the corners (-x, -z), (-x, +z), (+x, +z), (+x, -z).
  const float u[4] = {-hx, -hx, hx, hx}, v[4] = {-hz, hz, hz, -hz};
  for (int k = 0; k < 4; ++k) p[k] = glm::vec3(cx + c * u[k] - s * v[k], 0.0f, cz + s * u[k] + c * v[k]);
}

// A seeded unit vector in the XZ plane (rejection sampling; sqrt is exact-rounded everywhere).
void turn(Rng& rng, float& c, float& s) {
  for (;;) {
    const float x = rng.uniform(-1.0f, 1.0f), z = rng.uniform(-1.0f, 1.0f);
    const float len2 = x * x + z * z;
    if (len2 > 0.04f && len2 <= 1.0f) {
      const float len = std::sqrt(len2);
      c = x / len;
      s = z / len;
      return;
    }
  }
}

void lot(Builder& b, Rng& rng, float x0, float z0) {
  const float cx = x0 + 0.5f * kPitch, cz = z0 + 0.5f * kPitch;
  b.quad({x0, 0, z0}, {x0, 0, z0 + kPitch}, {x0 + kPitch, 0, z0 + kPitch}, {x0 + kPitch, 0, z0});
  const float pick = rng.uniform();
  if (pick < 0.62f) {  // a standing box, half of them turned
    const bool turned = rng.uniform() < 0.5f;
    const float limit = turned ? 0.34f : 0.42f;  // a turned box's corners stay inside the lot
    const float hx = rng.uniform(0.12f, limit) * kPitch, hz = rng.uniform(0.12f, limit) * kPitch;
    float c = 1.0f, s = 0.0f;
    if (turned) turn(rng, c, s);
    const float u = rng.uniform();
    glm::vec3 p[4];
    footprint(cx, cz, hx, hz, c, s, p);
    b.prism(p, 0.0f, (0.2f + 2.8f * u * u) * kPitch, false);
  } else if (pick < 0.76f) {  // a floating slab (an overhang)
    const float hx = rng.uniform(0.2f, 0.45f) * kPitch, hz = rng.uniform(0.2f, 0.45f) * kPitch;
    const float y0 = rng.uniform(0.6f, 2.2f) * kPitch;
    glm::vec3 p[4];
    footprint(cx, cz, hx, hz, 1.0f, 0.0f, p);
    b.prism(p, y0, y0 + 0.08f * kPitch, true);
  } else if (pick < 0.92f) {  // a tuft of thin, long triangles, both windings
    const int strands = rng.range(3, 6);
    for (int k = 0; k < strands; ++k) {
      float c = 1.0f, s = 0.0f;
      turn(rng, c, s);
      const float lean = rng.uniform(0.1f, 0.9f), len = rng.uniform(0.5f, 2.0f) * kPitch;
      const float w = rng.uniform(0.01f, 0.04f) * kPitch;
      const glm::vec3 root(cx + rng.uniform(-0.3f, 0.3f) * kPitch, 0.0f, cz + rng.uniform(-0.3f, 0.3f) * kPitch);
      const glm::vec3 tip = root + glm::vec3(c * lean, 1.0f, s * lean) * len;
      const glm::vec3 a = root + glm::vec3(-s * w, 0.0f, c * w), d = root - glm::vec3(-s * w, 0.0f, c * w);
      b.tri(a, d, tip);
      b.tri(d, a, tip);
    }
  }
}

}  // namespace

Scene make_crowd(std::uint32_t seed, int side, bool mixed) {
  Scene scene;
  side = std::max(side, 0);
  scene.name = std::string(mixed ? "crowd_mixed_" : "crowd_") + std::to_string(seed) + "_" + std::to_string(side);
  if (side == 0) return scene;
  Rng rng(0xC20D0ull ^ (static_cast<std::uint64_t>(seed) << 24));
  const float half = 0.5f * kPitch * static_cast<float>(side);
  for (int j = 0; j < side; ++j) {
    Builder row;
    for (int i = 0; i < side; ++i)
      lot(row, rng, -half + kPitch * static_cast<float>(i), -half + kPitch * static_cast<float>(j));
    scene.add_mesh(row.positions, row.indices, "crowd_row_" + std::to_string(j));
  }
  if (mixed) {
    // The plaza: [half, half + 0.75 side] on X, the field's span on Z; 3 x 4 large blocks.
    const float x0 = half, x1 = half + 0.75f * kPitch * static_cast<float>(side);
    Builder ground;
    ground.quad({x0, 0, -half}, {x0, 0, half}, {x1, 0, half}, {x1, 0, -half});
    scene.add_mesh(ground.positions, ground.indices, "plaza_ground");
    const float cell_x = (x1 - x0) / 3.0f, cell_z = 2.0f * half / 4.0f;
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 3; ++i) {
        const float bx = x0 + cell_x * (static_cast<float>(i) + rng.uniform(0.15f, 0.3f));
        const float bz = -half + cell_z * (static_cast<float>(j) + rng.uniform(0.15f, 0.3f));
        const float h = rng.uniform(0.15f, 0.5f) * static_cast<float>(side) * kPitch;
        const Aabb box{{bx, 0.0f, bz}, {bx + 0.55f * cell_x, h, bz + 0.55f * cell_z}};
        scene.add_box(box, "plaza_block_" + std::to_string(i) + "_" + std::to_string(j), true);
      }
    }
  }
  return scene;
}

}  // namespace cullkit::support
