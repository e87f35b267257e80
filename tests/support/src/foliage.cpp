// make_foliage: a forest whose crowns are clouds of small leaf triangles.
//
// Trees stand on a jittered square grid (kSpacing apart, some cells left empty for clearings) over
// a gently waved ground of kCell cells. A tree is a trunk box and a crown: `leaves` leaf triangles
// scattered through an ellipsoid above the trunk, each an equilateral-ish triangle of kLeaf..2 kLeaf
// metres facing a random direction (so about half face any given eye). Everything comes from one
// support::Rng stream in a fixed order, so a seed gives the same bytes everywhere.
#include <algorithm>
#include <cmath>
#include <string>

#include <glm/geometric.hpp>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

namespace {

constexpr float kSpacing = 6.0f;   // grid step of the trees (m)
constexpr float kCell = 4.0f;      // ground cell (m)
constexpr float kLeaf = 0.12f;     // smallest leaf edge (m)
constexpr float kClearing = 0.1f;  // share of grid places left without a tree

float ground_height(float x, float z) {
  return 1.5f * std::sin(0.021f * x + 0.7f) + 1.0f * std::sin(0.033f * z + 1.9f) + 0.5f * std::sin(0.05f * (x + z));
}

glm::vec3 random_unit(Rng& rng) {
  for (;;) {
    const glm::vec3 v(rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f));
    const float l = glm::length(v);
    if (l > 0.05f && l <= 1.0f) return v / l;
  }
}

}  // namespace

Scene make_foliage(std::uint32_t seed, int trees_per_side, int leaves) {
  Scene scene;
  scene.name = "foliage_" + std::to_string(seed) + "_" + std::to_string(trees_per_side) + "_" + std::to_string(leaves);
  if (trees_per_side <= 0) return scene;  // (a negative count of leaves plants bare trunks)
  Rng rng(0xF011A6Eull ^ (static_cast<std::uint64_t>(seed) << 32));
  const float half = 0.5f * kSpacing * static_cast<float>(trees_per_side);
  // Ground: one object, cells counter-clockwise from above.
  {
    const int n = std::max(1, static_cast<int>(std::ceil(2.0f * half / kCell)));
    const float step = 2.0f * half / static_cast<float>(n);
    std::vector<glm::vec3> p;
    std::vector<std::uint32_t> t;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const float x = -half + step * static_cast<float>(i), z = -half + step * static_cast<float>(j);
        p.push_back({x, ground_height(x, z), z});
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + static_cast<std::uint32_t>(n + 1);
        t.insert(t.end(), {a, b, b + 1, a, b + 1, a + 1});
      }
    scene.add_mesh(p, t, "ground");
  }
  std::vector<glm::vec3> corners;
  for (int gj = 0; gj < trees_per_side; ++gj)
    for (int gi = 0; gi < trees_per_side; ++gi) {
      if (rng.uniform() < kClearing) continue;
      const float x = -half + kSpacing * (static_cast<float>(gi) + 0.5f) + rng.uniform(-2.0f, 2.0f);
      const float z = -half + kSpacing * (static_cast<float>(gj) + 0.5f) + rng.uniform(-2.0f, 2.0f);
      const float ground = ground_height(x, z);
      const float trunk_r = rng.uniform(0.12f, 0.3f), trunk_h = rng.uniform(1.5f, 4.0f);
      const std::string tag = std::to_string(gi) + "_" + std::to_string(gj);
      scene.add_box({{x - trunk_r, ground - 0.5f, z - trunk_r}, {x + trunk_r, ground + trunk_h, z + trunk_r}},
                    "trunk_" + tag, false);
      // Crown: an ellipsoid resting on the trunk top, leaves uniform in its volume.
      const float rxz = rng.uniform(1.5f, 3.0f), ry = rng.uniform(2.0f, 4.0f);
      const glm::vec3 centre(x, ground + trunk_h + 0.8f * ry, z);
      corners.clear();
      for (int k = 0; k < leaves; ++k) {
        glm::vec3 q;
        do q = glm::vec3(rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f));
        while (glm::dot(q, q) > 1.0f);
        const glm::vec3 c = centre + glm::vec3(q.x * rxz, q.y * ry, q.z * rxz);
        const glm::vec3 n = random_unit(rng);
        const glm::vec3 u = glm::normalize(glm::cross(n, std::fabs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
        const glm::vec3 v = glm::cross(n, u);
        const float s = kLeaf * rng.uniform(1.0f, 2.0f);
        // Counter-clockwise seen from the side n points to.
        corners.push_back(c + s * u);
        corners.push_back(c + s * (-0.5f * u + 0.866f * v));
        corners.push_back(c + s * (-0.5f * u - 0.866f * v));
      }
      scene.add_triangles(corners, "crown_" + tag);
    }
  return scene;
}

}  // namespace cullkit::support
