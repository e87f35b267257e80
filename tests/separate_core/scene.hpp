// A small deterministic scene for the separate-core check: a field of boxes (12 triangles each) on
// a floor, seen from a few cameras. Shared by both translation units of the check.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/vec3.hpp>

#include <cullkit/geometry/camera.hpp>

namespace separate_core {

struct Scene {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
};

inline void add_box(Scene& s, const glm::vec3& lo, const glm::vec3& hi) {
  const auto base = static_cast<std::uint32_t>(s.positions.size());
  for (int c = 0; c < 8; ++c)
    s.positions.emplace_back((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
  // Outward, counter-clockwise faces: -x, +x, -y, +y, -z, +z.
  const std::uint32_t faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    for (std::uint32_t k : {f[0], f[1], f[2], f[0], f[2], f[3]}) s.indices.push_back(base + k);
  }
}

inline Scene make_scene() {
  Scene s;
  add_box(s, glm::vec3(-60, -1, -60), glm::vec3(60, 0, 60));
  std::uint64_t x = 0x9E3779B97F4A7C15ull;
  for (int i = 0; i < 400; ++i) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    const float px = float((x >> 20) % 1000) * 0.1f - 50.0f;
    const float pz = float((x >> 40) % 1000) * 0.1f - 50.0f;
    const float h = 1.0f + float((x >> 10) % 100) * 0.08f;
    add_box(s, glm::vec3(px, 0, pz), glm::vec3(px + 1.5f, h, pz + 1.5f));
  }
  return s;
}

inline std::vector<cullkit::Camera> make_cameras() {
  std::vector<cullkit::Camera> cams;
  const glm::vec3 eyes[3] = {{-55, 3, -55}, {0, 40, 0.5f}, {30, 1.7f, -10}};
  const glm::vec3 targets[3] = {{0, 0, 0}, {0, 0, 0}, {-20, 2, 10}};
  for (int k = 0; k < 3; ++k) {
    const glm::mat4 vp = glm::perspective(glm::radians(70.0f), 4.0f / 3.0f, 0.1f, 300.0f) *
                         glm::lookAt(eyes[k], targets[k], glm::vec3(0, 1, 0));
    cams.push_back(cullkit::Camera{eyes[k], vp, 160, 120});
  }
  return cams;
}

// FNV-1a over a list of 32-bit values.
inline std::uint64_t fnv(std::uint64_t h, const std::vector<std::uint32_t>& v) {
  for (std::uint32_t x : v) {
    for (int b = 0; b < 4; ++b) h = (h ^ ((x >> (8 * b)) & 0xFFu)) * 0x100000001B3ull;
  }
  return h;
}

// The second translation unit's answer (NormalClassIndex over a user vertex type).
std::uint64_t second_unit_hash(const Scene& scene);

}  // namespace separate_core
