// tests/nci/nci_test_util.hpp: brute-force oracles and cameras shared by the NormalClassIndex tests.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit/normal_class_index.hpp>
#include <cullkit_support/scene.hpp>

// 1 under AddressSanitizer (the tests shrink their screens there).
#if defined(__SANITIZE_ADDRESS__)
#define NCI_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NCI_SANITIZED 1
#endif
#endif
#ifndef NCI_SANITIZED
#define NCI_SANITIZED 0
#endif

namespace nci_test {

constexpr std::uint32_t miss = 0xFFFFFFFFu;

/// Per-pixel nearest front-face hit over ALL triangles, with the same float watertight test and
/// tie rule as the index (smaller t, then smaller triangle index). Skips invalid triangles the same
/// way (out of range, non-finite, zero area in double).
struct BruteHits {
  std::vector<std::uint32_t> tri;
  std::vector<float> t;
  /// (float only) The set select_visible must return: every pixel's first hit, plus at each pixel
  /// the triangles the ray passes within the edge band of (detail::watertight_hit_band, hit or
  /// near miss) in front of its first hit outside any band, and that hit. Sorted, unique.
  std::vector<std::uint32_t> selected;
};

template <class Real>
/// `window` (x0, y0, x1, y1 exclusive; default the whole screen): only those pixels are traced
/// (the others stay misses and add nothing to `selected`).
inline BruteHits brute_force(const cullkit::support::Scene& scene, const cullkit::Camera& cam,
                             float band = cullkit::detail::edge_band_units * 0x1p-24f,
                             std::array<int, 4> window = {0, 0, 1 << 30, 1 << 30}) {
  const cullkit::PixelRays rays(cam);
  const std::size_t n = scene.triangle_count();
  std::vector<char> ok(n, 0);
  std::vector<Real> rel(9 * n);
  for (std::size_t t = 0; t < n; ++t) {
    glm::vec3 p[3];
    if (!cullkit::triangle_positions(scene.mesh(), t, p)) continue;
    bool finite = true;
    for (auto& v : p) finite = finite && std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    if (!finite) continue;
    const glm::dvec3 nrm = glm::cross(glm::dvec3(p[1]) - glm::dvec3(p[0]), glm::dvec3(p[2]) - glm::dvec3(p[0]));
    const double len = glm::length(nrm);
    if (!(len > 0.0) || !std::isfinite(len)) continue;
    if (!cullkit::detail::faces_eye(p[0], p[1], p[2], glm::dvec3(cam.eye))) continue;  // the index's front rule
    ok[t] = 1;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) {
        // float: exactly what the index computes (float corner minus float eye); double: exact-ish.
        if constexpr (std::is_same_v<Real, float>) rel[9 * t + 3 * k + a] = p[k][a] - cam.eye[a];
        else rel[9 * t + 3 * k + a] = double(p[k][a]) - double(cam.eye[a]);
      }
  }
  BruteHits out;
  std::vector<std::pair<Real, std::uint32_t>> unsure;
  out.tri.assign(static_cast<std::size_t>(cam.width) * cam.height, miss);
  out.t.assign(out.tri.size(), std::numeric_limits<float>::infinity());
  for (int y = window[1]; y < std::min(cam.height, window[3]); ++y) {
    for (int x = window[0]; x < std::min(cam.width, window[2]); ++x) {
      const auto wr = cullkit::detail::WatertightRay<Real>::make(rays.ray(x, y).direction);
      Real best = std::numeric_limits<Real>::infinity(), solid = best;
      std::uint32_t best_tri = miss, solid_tri = miss;
      unsure.clear();
      for (std::size_t t = 0; t < n; ++t) {
        if (!ok[t]) continue;
        Real th;
        if constexpr (std::is_same_v<Real, float>) {
          bool near = false;
          const float* q = &rel[9 * t];
          float mag[3];
          for (int k = 0; k < 3; ++k)
            mag[k] = std::max({std::fabs(q[3 * k]), std::fabs(q[3 * k + 1]), std::fabs(q[3 * k + 2])});
          const bool hit = cullkit::detail::watertight_hit_band(wr, q, q + 3, q + 6, mag, band, th, near);
          if (hit && th < best) {
            best = th;
            best_tri = static_cast<std::uint32_t>(t);
          }
          if (near) unsure.push_back({th, static_cast<std::uint32_t>(t)});
          else if (hit && th < solid) {
            solid = th;
            solid_tri = static_cast<std::uint32_t>(t);
          }
        } else if (cullkit::detail::watertight_hit(wr, &rel[9 * t], &rel[9 * t + 3], &rel[9 * t + 6], th) &&
                   th < best) {
          best = th;
          best_tri = static_cast<std::uint32_t>(t);
        }
      }
      if (best_tri != miss) out.selected.push_back(best_tri);
      if (solid_tri != miss) out.selected.push_back(solid_tri);
      for (const auto& u : unsure)
        if (u.first <= solid) out.selected.push_back(u.second);
      const std::size_t p = static_cast<std::size_t>(y) * cam.width + x;
      out.tri[p] = best_tri;
      out.t[p] = static_cast<float>(best);
    }
  }
  std::sort(out.selected.begin(), out.selected.end());
  out.selected.erase(std::unique(out.selected.begin(), out.selected.end()), out.selected.end());
  return out;
}

/// Calls fn(file, scene) for every real scene present (smallest first); says which were absent, could
/// not be loaded, or are skipped under sanitizers (more than 100,000 triangles).
template <class Fn>
inline void for_each_real_scene(Fn&& fn) {
  const auto files = cullkit::support::real_scene_files();
  if (files.empty()) std::printf("real scenes absent: skipped\n");
  for (const auto& file : files) {
    const auto scene = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + file);
    if (!scene) {
      std::printf("%s: could not load, skipped\n", file.c_str());
      continue;
    }
    if (NCI_SANITIZED && scene->triangle_count() > 100000) {
      std::printf("%s: large, skipped under sanitizers\n", file.c_str());
      continue;
    }
    fn(file, *scene);
  }
}

/// Our own float test of one mesh triangle against one pixel ray (for the tie rule).
inline bool own_hit(const cullkit::support::Scene& scene, const cullkit::Camera& cam, std::uint32_t tri, int x, int y,
                    float& t) {
  glm::vec3 p[3];
  if (!cullkit::triangle_positions(scene.mesh(), tri, p)) return false;
  if (!cullkit::detail::faces_eye(p[0], p[1], p[2], glm::dvec3(cam.eye))) return false;
  const cullkit::PixelRays rays(cam);
  const auto wr = cullkit::detail::WatertightRay<float>::make(rays.ray(x, y).direction);
  float r[3][3];
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) r[k][a] = p[k][a] - cam.eye[a];
  return cullkit::detail::watertight_hit(wr, r[0], r[1], r[2], t);
}

/// Cameras around and inside a box: outside looking in, inside looking every way, axis-aligned
/// views (rays nearly parallel to slices), and a few at grazing heights.
inline std::vector<cullkit::Camera> cameras_for(const cullkit::Aabb& box, int count, int width, int height,
                                                std::uint64_t seed) {
  using cullkit::support::make_camera;
  cullkit::support::Rng rng(seed);
  std::vector<cullkit::Camera> cams;
  const glm::vec3 c = box.center(), e = box.extent();
  const float r = glm::length(e) * 0.5f + 1e-3f;
  for (int i = 0; i < count; ++i) {
    glm::vec3 eye, target;
    const int kind = i % 5;
    if (kind == 0) {  // outside, looking at the centre
      glm::vec3 d(rng.uniform(-1, 1), rng.uniform(-0.2f, 1), rng.uniform(-1, 1));
      if (glm::length(d) < 1e-3f) d = glm::vec3(1, 0.5f, 0.3f);
      eye = c + glm::normalize(d) * r * rng.uniform(1.1f, 2.5f);
      target = c + glm::vec3(rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f)) * e;
    } else if (kind == 1 || kind == 2) {  // inside the box, random direction
      eye = box.min + glm::vec3(rng.uniform(), rng.uniform(0.02f, 0.5f), rng.uniform()) * e;
      target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.5f, 0.5f), rng.uniform(-1, 1));
    } else if (kind == 3) {  // inside, looking exactly along an axis (rays nearly parallel to slices)
      eye = box.min + glm::vec3(rng.uniform(0.1f, 0.9f), rng.uniform(0.05f, 0.4f), rng.uniform(0.1f, 0.9f)) * e;
      glm::vec3 d(0.0f);
      d[rng.range(0, 2) == 1 ? 0 : 2] = rng.uniform() < 0.5f ? -1.0f : 1.0f;
      target = eye + d;
    } else {  // low grazing view from outside along a diagonal
      eye = glm::vec3(box.min.x - 0.3f * e.x, box.min.y + 0.02f * e.y + 0.5f, box.min.z - 0.3f * e.z);
      target = glm::vec3(box.max.x, box.min.y + 0.02f * e.y, box.max.z);
      eye += glm::vec3(rng.uniform(-0.1f, 0.1f), 0.0f, rng.uniform(-0.1f, 0.1f)) * e;
    }
    if (glm::length(target - eye) < 1e-4f) target = eye + glm::vec3(0, 0, -1);
    const float fov = rng.uniform(40.0f, 90.0f);
    const bool zo = (i % 7) == 3;
    cams.push_back(make_camera(eye, target, fov, width, height, 0.05f, (i % 3 == 0) ? 0.0f : 5000.0f,
                               zo ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one,
                               (i % 11) == 5));
  }
  return cams;
}

}  // namespace nci_test
