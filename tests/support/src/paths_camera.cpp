// Where real scenes live, and the standard test camera.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include <cullkit_support/scene.hpp>

namespace cullkit::support {

std::string scenes_dir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (const char* env = std::getenv("CULLKIT_SCENES"); env && *env) {
    return fs::is_directory(env, ec) ? std::string(env) : std::string();
  }
#ifdef CULLKIT_DEFAULT_SCENES
  if (fs::is_directory(CULLKIT_DEFAULT_SCENES, ec)) return CULLKIT_DEFAULT_SCENES;
#endif
  return {};
}

std::vector<std::string> real_scene_files() {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::uintmax_t, std::string>> found;
  const std::string dir = scenes_dir();
  if (dir.empty()) return {};
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ".obj") found.emplace_back(entry.file_size(ec), entry.path().filename().string());
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> names;
  for (auto& f : found) names.push_back(f.second);
  return names;
}

Camera make_camera(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees, int width, int height,
                   float near_plane, float far_plane, DepthRange depth, bool reversed_z) {
  const glm::vec3 fwd = glm::normalize(target - eye);
  const glm::vec3 up = std::fabs(fwd.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
  const glm::mat4 view = glm::lookAtRH(eye, target, up);
  const float fovy = glm::radians(fov_y_degrees);
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  glm::mat4 proj;
  const bool zo = depth == DepthRange::zero_to_one;
  if (far_plane <= 0.0f) {
    // Infinite far plane. glm's infinitePerspective is [-1, 1]; build the [0, 1] one by hand.
    const float f = 1.0f / std::tan(fovy * 0.5f);
    proj = glm::mat4(0.0f);
    proj[0][0] = f / aspect;
    proj[1][1] = f;
    proj[2][3] = -1.0f;
    if (!zo) {
      proj[2][2] = -1.0f;
      proj[3][2] = -2.0f * near_plane;
    } else if (!reversed_z) {
      proj[2][2] = -1.0f;
      proj[3][2] = -near_plane;
    } else {
      proj[2][2] = 0.0f;
      proj[3][2] = near_plane;
    }
  } else {
    const float n = reversed_z ? far_plane : near_plane;
    const float f = reversed_z ? near_plane : far_plane;
    proj = zo ? glm::perspectiveRH_ZO(fovy, aspect, n, f) : glm::perspectiveRH_NO(fovy, aspect, n, f);
  }
  return Camera{eye, proj * view, width, height, depth};
}

}  // namespace cullkit::support
