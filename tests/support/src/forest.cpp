// make_forest: a height-field terrain in chunks and trees standing on it.
//
// The terrain covers [-half, half] on X and Z with `terrain_cells` square cells of kCell metres;
// heights come from a few seeded sine waves evaluated in double at the grid points (so a point on a
// chunk border gets the same float in both chunks). Each cell is two triangles split along the
// diagonal from (x0, z0) to (x1, z1), facing up. One object per chunk of up to kChunk x kChunk cells.
// A tree's ground height is the exact height of that triangulated surface under the trunk's centre;
// the trunk (a box, its own object) starts kSink below it so slopes leave no gap; the crown (its own
// object) is a closed cone: an 8-sided fan to the apex and a base facing down.
#include <algorithm>
#include <cmath>
#include <string>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

namespace {

constexpr float kCell = 4.0f;
constexpr int kChunk = 8;
constexpr float kSink = 0.5f;
constexpr int kCrownSides = 8;

struct Waves {
  double ax[4], az[4], phase[4], amp[4];
};

float height_at_grid(const Waves& w, double x, double z) {
  double h = 0.0;
  for (int k = 0; k < 4; ++k) h += w.amp[k] * std::sin(w.ax[k] * x + w.az[k] * z + w.phase[k]);
  return static_cast<float>(h);
}

}  // namespace

Scene make_forest(std::uint32_t seed, int terrain_cells, int trees) {
  Scene scene;
  terrain_cells = std::max(terrain_cells, 0);
  trees = std::max(trees, 0);
  scene.name = "forest_" + std::to_string(seed) + "_" + std::to_string(terrain_cells) + "_" + std::to_string(trees);
  if (terrain_cells == 0) return scene;
  Rng rng(0xF02E57ull ^ (static_cast<std::uint64_t>(seed) << 28));
  Waves w{};
  for (int k = 0; k < 4; ++k) {
    const double wavelength = 40.0 + 160.0 * rng.uniform();  // 40..200 m
    const double angle = 6.283185307179586 * rng.uniform();
    w.ax[k] = 6.283185307179586 / wavelength * std::cos(angle);
    w.az[k] = 6.283185307179586 / wavelength * std::sin(angle);
    w.phase[k] = 6.283185307179586 * rng.uniform();
    w.amp[k] = wavelength * rng.uniform(0.02f, 0.05f);
  }
  const int n = terrain_cells;
  const float half = 0.5f * kCell * static_cast<float>(n);
  auto gx = [&](int i) { return -half + kCell * static_cast<float>(i); };
  std::vector<float> grid(static_cast<std::size_t>(n + 1) * (n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) grid[static_cast<std::size_t>(j) * (n + 1) + i] = height_at_grid(w, gx(i), gx(j));
  auto h = [&](int i, int j) { return grid[static_cast<std::size_t>(j) * (n + 1) + i]; };

  for (int cj = 0; cj < n; cj += kChunk) {
    for (int ci = 0; ci < n; ci += kChunk) {
      const int ni = std::min(kChunk, n - ci), nj = std::min(kChunk, n - cj);
      std::vector<glm::vec3> p;
      std::vector<std::uint32_t> t;
      for (int j = 0; j <= nj; ++j)
        for (int i = 0; i <= ni; ++i) p.push_back({gx(ci + i), h(ci + i, cj + j), gx(cj + j)});
      for (int j = 0; j < nj; ++j)
        for (int i = 0; i < ni; ++i) {
          const auto a = static_cast<std::uint32_t>(j * (ni + 1) + i);  // (x0, z0)
          const std::uint32_t d = a + 1;                                // (x1, z0)
          const auto b = static_cast<std::uint32_t>(a + ni + 1);       // (x0, z1)
          const std::uint32_t c = b + 1;                                // (x1, z1)
          t.insert(t.end(), {a, b, c, a, c, d});                        // counter-clockwise from above
        }
      scene.add_mesh(p, t, "terrain_" + std::to_string(ci / kChunk) + "_" + std::to_string(cj / kChunk));
    }
  }

  for (int k = 0; k < trees; ++k) {
    const float x = rng.uniform(-half + 2.0f, half - 2.0f), z = rng.uniform(-half + 2.0f, half - 2.0f);
    // The surface height at (x, z): which cell, which of its two triangles, then the plane of it.
    const int i = std::clamp(static_cast<int>(std::floor((x + half) / kCell)), 0, n - 1);
    const int j = std::clamp(static_cast<int>(std::floor((z + half) / kCell)), 0, n - 1);
    const float fx = (x - gx(i)) / kCell, fz = (z - gx(j)) / kCell;
    const float ha = h(i, j), hb = h(i, j + 1), hc = h(i + 1, j + 1), hd = h(i + 1, j);
    const float ground = fz >= fx ? ha + fz * (hb - ha) + fx * (hc - hb) : ha + fx * (hd - ha) + fz * (hc - hd);
    const float trunk_r = rng.uniform(0.15f, 0.35f), trunk_h = rng.uniform(2.0f, 5.0f);
    const std::string tag = std::to_string(k);
    scene.add_box({{x - trunk_r, ground - kSink, z - trunk_r}, {x + trunk_r, ground + trunk_h, z + trunk_r}},
                  "trunk_" + tag, false);
    // Crown: base ring at the trunk top, apex above; closed.
    const float radius = rng.uniform(1.5f, 3.5f), height = rng.uniform(4.0f, 10.0f);
    const float base_y = ground + trunk_h, turn = rng.uniform(0.0f, 6.2831853f);
    std::vector<glm::vec3> p;
    std::vector<std::uint32_t> t;
    p.push_back({x, base_y + height, z});  // 0: apex
    p.push_back({x, base_y, z});           // 1: base centre
    for (int s = 0; s < kCrownSides; ++s) {
      const float a = turn + 6.2831853f * static_cast<float>(s) / kCrownSides;
      p.push_back({x + radius * std::cos(a), base_y, z + radius * std::sin(a)});
    }
    for (int s = 0; s < kCrownSides; ++s) {
      const std::uint32_t r0 = 2 + s, r1 = 2 + (s + 1) % kCrownSides;
      // The ring runs counter-clockwise seen from below (angle grows from +X toward +Z), so
      // (r0, apex, r1) is counter-clockwise seen from outside and (r0, r1, centre) seen from below.
      t.insert(t.end(), {r0, 0u, r1, r0, r1, 1u});
    }
    scene.add_mesh(p, t, "crown_" + tag);
  }
  return scene;
}

}  // namespace cullkit::support
