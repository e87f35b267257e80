// tests/abt/abt_oracle.hpp: brute-force frustum oracle for the AdaptiveBinaryTree tests, written
// independently of cullkit::Frustum: planes straight from the matrix rows in double, not
// normalized, corners tested one by one (all eight) in double.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

namespace abt_test {

/// A view in world space: a matrix and its depth range.
struct View {
  glm::mat4 view_proj;
  cullkit::DepthRange depth;
  glm::vec3 eye;
  const char* kind;
};

/// Frustum planes of a matrix, in double, unnormalized. Degenerate planes (the far plane of an
/// infinite projection: a normal that is zero up to rounding) are dropped: they lie at infinity.
class OracleFrustum {
 public:
  OracleFrustum(const glm::mat4& m4, cullkit::DepthRange depth) {
    double m[4][4];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[r][c] = double(m4[c][r]);
    // clip = M p; the volume is -w <= x, y <= w and (-w or 0) <= z <= w.
    auto add = [&](double sx, int rx, double sw) {  // plane: sw * row3 + sx * row(rx)
      double p[4];
      for (int k = 0; k < 4; ++k) p[k] = (sw != 0.0 ? sw * m[3][k] : 0.0) + sx * m[rx][k];
      const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      const double scale = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]) + std::fabs(p[3]);
      if (!(len > 1e-6 * scale)) return;
      planes_.push_back({p[0], p[1], p[2], p[3]});
    };
    add(1, 0, 1);
    add(-1, 0, 1);
    add(1, 1, 1);
    add(-1, 1, 1);
    if (depth == cullkit::DepthRange::zero_to_one) add(1, 2, 0);
    else add(1, 2, 1);
    add(-1, 2, 1);
  }

  /// True if all eight corners are inside (or on) every plane.
  [[nodiscard]] bool contains(const cullkit::Aabb& b) const {
    for (const auto& p : planes_) {
      for (int c = 0; c < 8; ++c) {
        const double x = (c & 1) ? b.max.x : b.min.x, y = (c & 2) ? b.max.y : b.min.y,
                     z = (c & 4) ? b.max.z : b.min.z;
        if (p[0] * x + p[1] * y + p[2] * z + p[3] < 0.0) return false;
      }
    }
    return true;
  }

  /// True unless all eight corners are strictly outside one plane.
  [[nodiscard]] bool meets(const cullkit::Aabb& b) const {
    for (const auto& p : planes_) {
      bool all_out = true;
      for (int c = 0; c < 8 && all_out; ++c) {
        const double x = (c & 1) ? b.max.x : b.min.x, y = (c & 2) ? b.max.y : b.min.y,
                     z = (c & 4) ? b.max.z : b.min.z;
        if (p[0] * x + p[1] * y + p[2] * z + p[3] >= 0.0) all_out = false;
      }
      if (all_out) return false;
    }
    return true;
  }

 private:
  std::vector<std::array<double, 4>> planes_;
};

/// A random view of a region: perspective (finite / infinite far, both depth ranges, reversed-Z)
/// or orthographic (NO / ZO), kind chosen by `k % 7`.
inline View random_view(cullkit::support::Rng& rng, const cullkit::Aabb& region, int k) {
  using cullkit::DepthRange;
  const glm::vec3 lo = region.min, hi = region.max;
  const glm::vec3 size = glm::max(hi - lo, glm::vec3(1.0f));
  auto point = [&](float margin) {
    return glm::vec3(rng.uniform(lo.x - margin * size.x, hi.x + margin * size.x),
                     rng.uniform(lo.y - margin * size.y, hi.y + margin * size.y),
                     rng.uniform(lo.z - margin * size.z, hi.z + margin * size.z));
  };
  const glm::vec3 eye = point(0.3f);
  glm::vec3 target = point(0.0f);
  if (glm::length(target - eye) < 1e-3f * glm::length(size)) target = eye + glm::vec3(1, 0, 0);
  const float diag = glm::length(size);
  const float fov = rng.uniform(10.0f, 110.0f);
  const float near_plane = rng.uniform(0.01f, 0.05f) * diag;
  const float far_plane = rng.uniform(0.2f, 1.5f) * diag;
  const int kind = k % 7;
  View v{};
  v.eye = eye;
  if (kind < 5) {
    static const DepthRange depths[5] = {DepthRange::negative_one_to_one, DepthRange::zero_to_one,
                                         DepthRange::zero_to_one, DepthRange::negative_one_to_one,
                                         DepthRange::zero_to_one};
    static const char* names[5] = {"persp_no", "persp_zo", "persp_zo_reversed", "persp_no_infinite",
                                   "persp_zo_reversed_infinite"};
    const bool reversed = kind == 2 || kind == 4;
    const bool infinite = kind == 3 || kind == 4;
    const cullkit::Camera cam = cullkit::support::make_camera(eye, target, fov, 640, 480, near_plane,
                                                              infinite ? 0.0f : far_plane, depths[kind], reversed);
    v.view_proj = cam.view_proj;
    v.depth = cam.depth;
    v.kind = names[kind];
  } else {
    const glm::vec3 fwd = glm::normalize(target - eye);
    const glm::vec3 up = std::fabs(fwd.y) > 0.999f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
    const glm::mat4 view = glm::lookAtRH(eye, target, up);
    const float half = rng.uniform(0.05f, 0.5f) * diag;
    const float aspect = rng.uniform(0.5f, 2.0f);
    if (kind == 5) {
      v.view_proj = glm::orthoRH_NO(-half * aspect, half * aspect, -half, half, near_plane, far_plane) * view;
      v.depth = DepthRange::negative_one_to_one;
      v.kind = "ortho_no";
    } else {
      v.view_proj = glm::orthoRH_ZO(-half * aspect, half * aspect, -half, half, near_plane, far_plane) * view;
      v.depth = DepthRange::zero_to_one;
      v.kind = "ortho_zo";
    }
  }
  return v;
}

/// Random boxes in a cube of side `world`, sizes up to `max_size`.
inline std::vector<cullkit::Aabb> random_boxes(cullkit::support::Rng& rng, std::size_t n, float world, float max_size) {
  std::vector<cullkit::Aabb> boxes(n);
  for (auto& b : boxes) {
    const glm::vec3 c(rng.uniform(-world, world), rng.uniform(-world, world), rng.uniform(-world, world));
    const glm::vec3 h(rng.uniform(0.0f, max_size), rng.uniform(0.0f, max_size), rng.uniform(0.0f, max_size));
    b = cullkit::Aabb{c - h, c + h};
  }
  return boxes;
}

}  // namespace abt_test
