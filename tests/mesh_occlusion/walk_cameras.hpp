// tests/mesh_occlusion/walk_cameras.hpp: cameras where a player would stand. A walk keeps the eye at
// eye height above the floor under it (a ray cast down, front faces only, so floors that face up),
// steps forward while rays at eye and knee height are clear, and turns toward open space when they
// are not; its view looks around the walking direction. Models without a floor to stand on (the
// car, the bunny) get an orbit instead. Plus the hard cases every culler must survive: an eye
// nearer a wall than the near plane, an eye inside an object, grazing views along a wall, and the
// other depth conventions.
//
// Shared by the Embree test, the benchmark and the picture example. Seeded: the same cameras on
// every run of one build (other compilers may round the trigonometry and Embree's hits differently
// and walk elsewhere).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

namespace mesh_occlusion_test {

using namespace cullkit;

/// How to place cameras in one scene. Lengths are in the scene's units.
struct WalkSpec {
  float metre = 1.0f;        ///< scene units per metre
  float eye_height = 1.7f;   ///< above the floor
  float step = 1.0f;         ///< distance between consecutive eyes
  float near_plane = 0.1f;
  float far_plane = 1000.0f;
  float fov_y = 60.0f;       ///< degrees
  bool orbit = false;        ///< circle around the model instead of walking
  std::vector<std::pair<glm::vec3, glm::vec3>> starts;  ///< eye, horizontal heading
};

namespace walk_detail {

constexpr float kPi = 3.14159265358979f;

inline float diagonal(const Aabb& b) { return glm::length(b.max - b.min); }

inline glm::vec3 yaw_dir(float yaw) { return glm::vec3(std::cos(yaw), 0.0f, std::sin(yaw)); }

inline bool near_any_box(const support::Scene& scene, const glm::vec3& p, float margin) {
  for (const auto& o : scene.objects) {
    const Aabb& b = o.bounds;
    if (p.x >= b.min.x - margin && p.x <= b.max.x + margin && p.y >= b.min.y - margin && p.y <= b.max.y + margin &&
        p.z >= b.min.z - margin && p.z <= b.max.z + margin)
      return true;
  }
  return false;
}

/// Distance to the first front face along `dir` from `p` (inf when nothing).
inline float clear_distance(const oracle::EmbreeScene& embree, const glm::vec3& p, const glm::vec3& dir) {
  float t = 0;
  if (embree.first_hit(Ray{p, dir}, &t) == oracle::HitBuffer::miss) return 3.0e38f;
  return t;
}

/// The eye above the floor under `p` (searched from `p` down to `p.y - reach`), if there is one.
inline bool stand(const oracle::EmbreeScene& embree, const WalkSpec& spec, const glm::vec3& p, float reach,
                  glm::vec3& eye) {
  float t = 0;
  if (embree.first_hit(Ray{p, glm::vec3(0, -1, 0)}, &t, reach) == oracle::HitBuffer::miss) return false;
  eye = p + glm::vec3(0.0f, spec.eye_height - t, 0.0f);
  return true;
}

/// A player keeps a body's width from walls: 0.3 m clear all round at eye and knee height.
inline bool roomy(const oracle::EmbreeScene& embree, const WalkSpec& spec, const glm::vec3& eye) {
  const glm::vec3 knee = eye - glm::vec3(0.0f, spec.eye_height - 0.4f * spec.metre, 0.0f);
  for (int a = 0; a < 8; ++a) {
    const glm::vec3 d = yaw_dir(static_cast<float>(a) * 0.25f * kPi);
    if (clear_distance(embree, eye, d) < 0.3f * spec.metre || clear_distance(embree, knee, d) < 0.3f * spec.metre)
      return false;
  }
  return true;
}

/// The `info_player_deathmatch` origins and headings of a Quake-style map's entity text (the scene's
/// .json sidecar holds it as an escaped string; quotes may be escaped, numbers are not). Map (x, y, z)
/// becomes (x, z, -y) in the scene; a yaw `angle` a (degrees, about the map's z) looks along
/// (cos a, 0, -sin a).
inline std::vector<std::pair<glm::vec3, glm::vec3>> deathmatch_spawns(const std::string& json_path) {
  std::vector<std::pair<glm::vec3, glm::vec3>> out;
  std::ifstream in(json_path);
  if (!in) return out;
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const auto number_after = [&](std::size_t from, std::size_t end, const char* key, float* v, int n) {
    const std::size_t k = text.find(key, from);
    if (k == std::string::npos || k >= end) return false;
    std::size_t i = k + std::char_traits<char>::length(key);
    for (int j = 0; j < n; ++j) {
      while (i < end && !(std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '-' || text[i] == '.')) ++i;
      if (i >= end) return false;
      char* stop = nullptr;
      v[j] = std::strtof(text.c_str() + i, &stop);
      i = static_cast<std::size_t>(stop - text.c_str());
    }
    return true;
  };
  for (std::size_t at = text.find("info_player_deathmatch"); at != std::string::npos;
       at = text.find("info_player_deathmatch", at + 1)) {
    const std::size_t begin = text.rfind('{', at), end = text.find('}', at);
    if (begin == std::string::npos || end == std::string::npos) continue;
    float o[3], a = 0.0f;
    if (!number_after(begin, end, "origin", o, 3)) continue;
    number_after(begin, end, "angle", &a, 1);
    const float yaw = a * kPi / 180.0f;
    out.emplace_back(glm::vec3(o[0], o[2], -o[1]), glm::vec3(std::cos(yaw), 0.0f, -std::sin(yaw)));
  }
  return out;
}

}  // namespace walk_detail

/// The camera rules for a scene, by its name (file name for real scenes, "city"/"office" for the
/// generated ones). Start points come from the scene itself: spawn points, streets, rooms, or the
/// floor under the objects.
inline WalkSpec walk_spec(const std::string& name, const support::Scene& scene, const oracle::EmbreeScene& embree,
                          std::uint64_t seed) {
  using namespace walk_detail;
  WalkSpec spec;
  const Aabb sb = scene.bounds;
  const float diag = diagonal(sb);
  spec.far_plane = 1.5f * diag;
  support::Rng rng(seed);
  float max_start_y = 1.0e30f;
  const auto floor_starts = [&](int count, const auto& sample) {
    for (int tries = 0; static_cast<int>(spec.starts.size()) < count && tries < 200 * count; ++tries) {
      glm::vec3 p = sample();
      glm::vec3 eye;
      if (!stand(embree, spec, p, 1.0e30f, eye) || eye.y > max_start_y || !roomy(embree, spec, eye)) continue;
      if (near_any_box(scene, eye, 0.0f) && name == "city") continue;
      spec.starts.emplace_back(eye, yaw_dir(rng.uniform(0.0f, 2.0f * kPi)));
    }
  };
  if (name.find("oacmpdm9") != std::string::npos) {
    spec.metre = 40.0f;  // Quake units are about 2.5 cm
    spec.eye_height = 50.0f;
    spec.step = 56.0f;
    spec.near_plane = 4.0f;
    const std::string json = support::scenes_dir() + "/oacmpdm9.json";
    for (const auto& s : deathmatch_spawns(json)) {
      glm::vec3 eye;
      if (stand(embree, spec, s.first + glm::vec3(0, 16, 0), 400.0f, eye) && roomy(embree, spec, eye))
        spec.starts.emplace_back(eye, s.second);
    }
  } else if (name.find("sportsCar") != std::string::npos || name.find("bunny") != std::string::npos) {
    spec.orbit = true;
    spec.metre = 1.0f;
    spec.near_plane = 1e-3f * diag;
  } else if (name == "office") {
    spec.eye_height = 1.6f;
    spec.step = 0.8f;
    std::vector<Aabb> rooms;
    for (const auto& o : scene.objects)
      if (o.name.rfind("floor_", 0) == 0) rooms.push_back(o.bounds);
    for (std::size_t i = 0; i < rooms.size() && spec.starts.size() < 8; i += 1 + rooms.size() / 8) {
      glm::vec3 eye;
      const glm::vec3 c = rooms[i].center();
      if (stand(embree, spec, glm::vec3(c.x, rooms[i].max.y + 2.0f, c.z), 10.0f, eye) && roomy(embree, spec, eye))
        spec.starts.emplace_back(eye, yaw_dir(rng.uniform(0.0f, 2.0f * kPi)));
    }
  } else if (name == "city") {
    spec.step = 3.0f;
    floor_starts(8, [&] { return glm::vec3(rng.uniform(sb.min.x, sb.max.x), sb.min.y + 1.0f, rng.uniform(sb.min.z, sb.max.z)); });
  } else {
    // Outdoor scenes in metres: stand on what is under the centre of a random object. A lone house
    // (fzk_haus) would put most starts on its roof: there, only floors up to 2 m above the lowest
    // point (the site and the ground floor) are starting points.
    const bool lone_house = name.find("fzk_haus") != std::string::npos;
    spec.step = name.find("lasdunas") != std::string::npos ? 4.0f : 1.0f;
    max_start_y = lone_house ? sb.min.y + 2.0f + spec.eye_height : 1.0e30f;
    floor_starts(8, [&] {
      const Aabb& b = scene.objects[rng.next() % scene.objects.size()].bounds;
      const glm::vec3 c = b.center();
      return glm::vec3(c.x, std::min(b.max.y, sb.max.y) + 0.5f, c.z);
    });
  }
  if (spec.starts.empty() && !spec.orbit) spec.orbit = true;  // nothing to stand on: orbit
  if (spec.orbit) spec.near_plane = std::min(spec.near_plane, 1e-3f * diag);
  return spec;
}

/// `count` cameras: `legs` walks from the spec's start points in turn (or an orbit). Rays are cast
/// against `embree` (front faces only).
inline std::vector<Camera> walk(const WalkSpec& spec, const support::Scene& scene, const oracle::EmbreeScene& embree,
                                int count, int legs, int width, int height, std::uint64_t seed) {
  using namespace walk_detail;
  std::vector<Camera> cams;
  support::Rng rng(seed);
  const Aabb sb = scene.bounds;
  const auto camera = [&](const glm::vec3& eye, const glm::vec3& dir) {
    return support::make_camera(eye, eye + dir, spec.fov_y, width, height, spec.near_plane, spec.far_plane);
  };
  if (spec.orbit) {
    const glm::vec3 c = sb.center();
    const float r = 0.5f * diagonal(sb);
    for (int k = 0; k < count; ++k) {
      const float a = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(std::max(count, 1));
      const float radius = r * (k % 5 == 4 ? 0.35f : rng.uniform(1.1f, 2.0f));  // one in five close in
      const glm::vec3 eye = c + glm::vec3(std::cos(a) * radius, rng.uniform(-0.2f, 0.6f) * r, std::sin(a) * radius);
      const glm::vec3 target = c + glm::vec3(rng.uniform(-0.3f, 0.3f), rng.uniform(-0.3f, 0.3f), rng.uniform(-0.3f, 0.3f)) * r;
      cams.push_back(camera(eye, glm::normalize(target - eye)));
    }
    return cams;
  }
  const int per_leg = (count + legs - 1) / std::max(legs, 1);
  const float knee = spec.eye_height - 0.4f * spec.metre;
  for (int leg = 0; static_cast<int>(cams.size()) < count; ++leg) {
    const auto& start = spec.starts[static_cast<std::size_t>(leg) % spec.starts.size()];
    glm::vec3 eye = start.first;
    float yaw = std::atan2(start.second.z, start.second.x);
    for (int k = 0; k < per_leg && static_cast<int>(cams.size()) < count; ++k) {
      // Look around the walking direction, a little up and down.
      const float look = yaw + 0.5f * std::sin(0.9f * static_cast<float>(k) + static_cast<float>(leg));
      const float pitch = rng.uniform(-10.0f, 5.0f) * kPi / 180.0f;
      const glm::vec3 dir(std::cos(look) * std::cos(pitch), std::sin(pitch), std::sin(look) * std::cos(pitch));
      cams.push_back(camera(eye, dir));
      // Step: keep the heading (a little wander) while eye and knee rays are clear, else turn to
      // the most open of a few random headings.
      const auto clear = [&](float y) {
        const glm::vec3 d = yaw_dir(y);
        return std::min(clear_distance(embree, eye, d), clear_distance(embree, eye - glm::vec3(0, knee, 0), d));
      };
      float next = yaw + rng.uniform(-0.35f, 0.35f);
      const float need = spec.step + 0.5f * spec.metre;
      if (clear(next) < need) {
        float best = -1.0f;
        for (int t = 0; t < 12; ++t) {
          const float y = rng.uniform(0.0f, 2.0f * kPi);
          const float d = clear(y);
          if (d > best) best = d, next = y;
        }
      }
      yaw = next;
      // The new eye must be roomy, or the walker stays and turns.
      glm::vec3 moved;
      const glm::vec3 p = eye + yaw_dir(yaw) * spec.step;
      bool ok = clear(yaw) >= need && stand(embree, spec, p, spec.eye_height + 3.0f * spec.metre, moved) &&
                moved.y > eye.y - 3.0f * spec.metre && moved.y < eye.y + 0.7f * spec.eye_height;
      ok = ok && roomy(embree, spec, moved);
      if (ok) eye = moved;
      else yaw += rng.uniform(0.5f * kPi, 1.5f * kPi);
    }
  }
  return cams;
}

/// A named camera.
struct NamedCamera {
  std::string name;
  Camera camera;
};

/// The hard cases, built from the walk's eyes: an eye nearer a wall than the near plane (looking at
/// it), an eye at the centre of an object (inside a closed one, every face is a back face), grazing
/// views along a wall (1 cm off it, and on its plane), a near plane far out, and the other depth
/// conventions (zero-to-one, reversed-Z finite and infinite).
inline std::vector<NamedCamera> hard_cameras(const WalkSpec& spec, const support::Scene& scene,
                                             const oracle::EmbreeScene& embree, const std::vector<Camera>& walk_cams,
                                             int width, int height) {
  using namespace walk_detail;
  std::vector<NamedCamera> out;
  if (walk_cams.empty()) return out;
  const auto pick = [&](std::size_t i) { return walk_cams[i % walk_cams.size()]; };
  const auto forward = [](const Camera& c) {
    // The view direction: the ray through the screen centre.
    return PixelRays(c).ray_at(0.5 * c.width, 0.5 * c.height).direction;
  };
  const auto make = [&](const glm::vec3& eye, const glm::vec3& dir, float near_plane, float far_plane,
                        DepthRange depth = DepthRange::negative_one_to_one, bool reversed = false) {
    return support::make_camera(eye, eye + dir, spec.fov_y, width, height, near_plane, far_plane, depth, reversed);
  };
  // Walls: the first front face ahead of some walk eye.
  int walls = 0;
  for (std::size_t i = 0; i < walk_cams.size() && walls < 2; ++i) {
    const Camera c = pick(i * 3 + 1);
    const glm::vec3 f = forward(c);
    float t = 0;
    const std::uint32_t tri = embree.first_hit(Ray{c.eye, f}, &t, 40.0f * spec.metre);
    if (tri == oracle::HitBuffer::miss || tri >= scene.triangle_count()) continue;
    const glm::vec3 a = scene.positions[scene.indices[3 * tri]], b = scene.positions[scene.indices[3 * tri + 1]],
                    d = scene.positions[scene.indices[3 * tri + 2]];
    glm::vec3 n = glm::cross(b - a, d - a);
    if (!(glm::length(n) > 0.0f)) continue;
    n = glm::normalize(n);
    const glm::vec3 hit = c.eye + f * t;
    ++walls;
    const std::string w = std::to_string(walls);
    out.push_back({"wall nearer than the near plane " + w, make(c.eye + f * (t - 0.5f * spec.near_plane), f,
                                                                 spec.near_plane, spec.far_plane)});
    glm::vec3 along = f - n * glm::dot(f, n);
    if (!(glm::length(along) > 1e-3f)) along = glm::cross(n, glm::vec3(0, 1, 0));
    if (!(glm::length(along) > 1e-3f)) continue;
    along = glm::normalize(along);
    out.push_back({"grazing, 1 cm off a wall " + w, make(hit + n * (0.01f * spec.metre), along, spec.near_plane, spec.far_plane)});
    out.push_back({"grazing, on a wall's plane " + w, make(hit, along, spec.near_plane, spec.far_plane)});
  }
  // Inside an object: the biggest one that is not a large part of the whole scene.
  const float diag = diagonal(scene.bounds);
  std::size_t best = scene.objects.size();
  float best_volume = -1.0f;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const Aabb& b = scene.objects[o].bounds;
    if (scene.objects[o].triangle_count < 6 || !(diagonal(b) < 0.3f * diag)) continue;
    const glm::vec3 e = b.max - b.min;
    if (e.x * e.y * e.z > best_volume) best_volume = e.x * e.y * e.z, best = o;
  }
  if (best < scene.objects.size()) {
    const glm::vec3 eye = scene.objects[best].bounds.center();
    glm::vec3 to_centre = scene.bounds.center() - eye;
    to_centre.y = 0.0f;
    const glm::vec3 dir = glm::length(to_centre) > 1e-3f ? glm::normalize(to_centre) : glm::vec3(1, 0, 0);
    out.push_back({"inside an object (" + scene.objects[best].name + ")", make(eye, dir, spec.near_plane, spec.far_plane)});
  }
  const Camera a = pick(1), b = pick(2), c = pick(3), d = pick(4);
  out.push_back({"reversed-Z, infinite far", make(a.eye, forward(a), spec.near_plane, 0.0f, DepthRange::zero_to_one, true)});
  out.push_back({"zero-to-one depth", make(b.eye, forward(b), spec.near_plane, spec.far_plane, DepthRange::zero_to_one)});
  out.push_back({"reversed-Z, finite", make(c.eye, forward(c), spec.near_plane, spec.far_plane, DepthRange::zero_to_one, true)});
  out.push_back({"near plane 2 m out", make(d.eye, forward(d), 2.0f * spec.metre, spec.far_plane)});
  return out;
}

/// A scene's walk (`count` cameras in 2 legs, named "walk <i>") followed by its hard cameras.
inline std::vector<NamedCamera> walk_then_hard_cameras(const WalkSpec& spec, const support::Scene& scene,
                                                       const oracle::EmbreeScene& embree, int count, int width,
                                                       int height, std::uint64_t seed) {
  std::vector<NamedCamera> cams;
  const auto walk_cams = walk(spec, scene, embree, count, 2, width, height, seed);
  for (std::size_t i = 0; i < walk_cams.size(); ++i) cams.push_back({"walk " + std::to_string(i), walk_cams[i]});
  for (auto& h : hard_cameras(spec, scene, embree, walk_cams, width, height)) cams.push_back(h);
  return cams;
}

}  // namespace mesh_occlusion_test
