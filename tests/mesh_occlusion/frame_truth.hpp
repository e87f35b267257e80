// tests/mesh_occlusion/frame_truth.hpp: what is truly visible in an engine frame, by Embree: static
// objects of which some do not occlude (see-through: glass, beams, fences), moving occluders given
// as a mesh and a world matrix, and boxes that are not objects at all.
//
// A ray from the eye, over its part between the near and the far plane, stops at the first front
// face of an occluder (a static occluding object's or a moving occluder's) and sees that object;
// on the way it passes through every see-through object's front faces and sees those objects too.
// A box is seen when some ray meets it before the ray stops. Rays: the families of RaySet (pixel
// centres at two resolutions and seeded sub-pixel positions, some on the screen's border).
//
// Shared by the see-through, box query and moving occluder tests and the benchmark.
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_double4x4.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/ext/vector_double3.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "embree_truth.hpp"

namespace mesh_occlusion_test {

/// One moving occluder in world space, as the truth sees it: its triangles transformed in double
/// precision, the winding reversed for a mirroring matrix (front faces stay front faces).
inline std::vector<glm::vec3> world_triangles(const std::vector<glm::vec3>& positions,
                                              const std::vector<std::uint32_t>& indices, const glm::mat4& model) {
  const glm::dmat4 m(model);
  const bool mirrored = glm::determinant(glm::dmat3(m)) < 0.0;
  std::vector<glm::vec3> out;
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const std::uint32_t c[3] = {indices[t], indices[t + (mirrored ? 2 : 1)], indices[t + (mirrored ? 1 : 2)]};
    for (std::uint32_t v : c) out.push_back(glm::vec3(m * glm::dvec4(glm::dvec3(positions[v]), 1.0)));
  }
  return out;
}

/// The frame's occluders for Embree: the scene's occluding objects' triangles (the see-through ones
/// kept as never-hit triangles, so triangle ids stay the scene's), then the moving occluders' world
/// triangles (ids past the scene's, seen by no object).
class FrameOccluders {
 public:
  FrameOccluders(const support::Scene& scene, const std::vector<std::uint8_t>& see_through,
                 const std::vector<std::vector<glm::vec3>>& moving_world = {}) {
    std::vector<std::uint32_t> indices = scene.indices;
    const auto out_of_range = static_cast<std::uint32_t>(scene.positions.size());
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
      if (o >= see_through.size() || !see_through[o]) continue;
      const auto& so = scene.objects[o];
      for (std::size_t t = so.first_triangle; t < std::size_t(so.first_triangle) + so.triangle_count; ++t)
        for (int k = 0; k < 3; ++k) indices[3 * t + std::size_t(k)] = out_of_range;
    }
    embree_.add_mesh(scene.positions.data(), scene.positions.size(), indices.data(), indices.size());
    for (const auto& tris : moving_world) {
      std::vector<std::uint32_t> seq(tris.size());
      for (std::size_t i = 0; i < seq.size(); ++i) seq[i] = static_cast<std::uint32_t>(i);
      if (!tris.empty()) embree_.add_mesh(tris.data(), tris.size(), seq.data(), seq.size());
    }
    embree_.commit();
  }
  [[nodiscard]] const oracle::EmbreeScene& embree() const { return embree_; }

 private:
  oracle::EmbreeScene embree_;
};

/// One ray of a frame: eye + t * dir for t in [t0, t_stop], where t_stop is the first occluder's
/// front face or the far plane; `object` is the static object it stops at (no_object: none, or a
/// moving occluder).
struct TruthRay {
  glm::dvec3 dir;
  double t0, t_stop;
  std::uint32_t object;
  std::uint8_t family;
};

/// Every ray of the frame, cast against the occluders.
inline std::vector<TruthRay> cast_frame(const FrameOccluders& occluders, const ObjectMap& map, const Camera& cam,
                                        const RaySet& set) {
  std::vector<TruthRay> rays;
  const auto cast = [&](const glm::vec3& dir, std::uint8_t family) {
    if (dir == glm::vec3(0.0f)) return;
    double t0 = 0, t1 = 0;
    if (!depth_segment(cam, dir, t0, t1)) return;
    const glm::dvec3 origin = glm::dvec3(cam.eye) + glm::dvec3(dir) * t0;
    const float tfar = std::isfinite(t1) ? static_cast<float>(t1 - t0) : std::numeric_limits<float>::infinity();
    float d = 0.0f;
    const std::uint32_t t = occluders.embree().first_hit(Ray{glm::vec3(origin), dir}, &d, tfar);
    TruthRay r{glm::dvec3(dir), t0, t1, no_object, family};
    if (t != oracle::HitBuffer::miss) {
      r.t_stop = t0 + double(d);
      if (t < map.triangle_object.size()) r.object = map.triangle_object[t];
    }
    rays.push_back(r);
  };
  for_each_ray(cam, set, cast);
  return rays;
}

/// The part [enter, leave] of the ray eye + t * dir inside `box` (false: it misses the box).
inline bool ray_box(const glm::dvec3& eye, const glm::dvec3& dir, const Aabb& box, double& enter, double& leave) {
  enter = -HUGE_VAL;
  leave = HUGE_VAL;
  for (int a = 0; a < 3; ++a) {
    const double lo = double(box.min[a]) - eye[a], hi = double(box.max[a]) - eye[a];
    if (dir[a] == 0.0) {
      if (lo > 0.0 || hi < 0.0) return false;
      continue;
    }
    double t_lo = lo / dir[a], t_hi = hi / dir[a];
    if (t_lo > t_hi) std::swap(t_lo, t_hi);
    enter = std::max(enter, t_lo);
    leave = std::min(leave, t_hi);
  }
  return enter <= leave;
}

/// Whether the ray meets a point of `box` before it stops (a margin of 1e-9 of the distances in the
/// box's favour: the truth may only call more things visible).
inline bool ray_sees_box(const glm::dvec3& eye, const TruthRay& r, const Aabb& box) {
  double enter = 0, leave = 0;
  if (!ray_box(eye, r.dir, box, enter, leave)) return false;
  const double slack = 1e-9 * std::max(1.0, std::fabs(r.t_stop));
  return leave >= r.t0 - slack && enter <= r.t_stop + slack;
}

/// Whether the ray meets the front face of triangle (a, b, c) (counter-clockwise seen from the eye)
/// at a distance in [t0, t_stop], edges included with a small margin.
inline bool ray_meets_front(const glm::dvec3& eye, const TruthRay& r, const glm::dvec3& a, const glm::dvec3& b,
                            const glm::dvec3& c) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 n = glm::cross(e1, e2);
  if (!(glm::dot(n, r.dir) < 0.0)) return false;  // back face or edge-on
  const glm::dvec3 p = glm::cross(r.dir, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 s = eye - a;
  const double u = glm::dot(s, p) * inv;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(r.dir, q) * inv;
  const double eps = 1e-7;
  if (u < -eps || v < -eps || u + v > 1.0 + eps) return false;
  const double t = glm::dot(e2, q) * inv;
  const double slack = 1e-7 * std::max(1.0, std::fabs(t));
  return t >= r.t0 - slack && t <= r.t_stop + slack;
}

/// Per object, whether some ray sees it: the object each ray stops at, and every see-through
/// object with a front face the ray meets before it stops.
inline std::vector<std::uint8_t> seen_objects(const support::Scene& scene, const std::vector<std::uint8_t>& see_through,
                                              const std::vector<TruthRay>& rays, const Camera& cam) {
  std::vector<std::uint8_t> seen(scene.objects.size(), 0);
  std::vector<std::uint32_t> glass;
  for (std::uint32_t o = 0; o < scene.objects.size() && o < see_through.size(); ++o)
    if (see_through[o]) glass.push_back(o);
  const glm::dvec3 eye(cam.eye);
  for (const TruthRay& r : rays) {
    if (r.object != no_object) seen[r.object] = 1;
    for (std::uint32_t o : glass) {
      if (seen[o]) continue;
      const auto& so = scene.objects[o];
      if (!ray_sees_box(eye, r, so.bounds)) continue;
      for (std::size_t t = so.first_triangle; t < std::size_t(so.first_triangle) + so.triangle_count && !seen[o]; ++t) {
        const glm::dvec3 a(scene.positions[scene.indices[3 * t]]), b(scene.positions[scene.indices[3 * t + 1]]),
            c(scene.positions[scene.indices[3 * t + 2]]);
        if (ray_meets_front(eye, r, a, b, c)) seen[o] = 1;
      }
    }
  }
  return seen;
}

/// A vertical pane (two triangles facing each way: glass is seen from both sides) from `a` to `b`
/// on the ground, `height` tall, as one object; returns its number.
inline std::uint32_t add_pane(support::Scene& scene, const glm::vec3& a, const glm::vec3& b, float height,
                              const std::string& name) {
  const glm::vec3 up(0.0f, height, 0.0f);
  const glm::vec3 p[4] = {a, b, b + up, a + up};
  return scene.add_triangles({p[0], p[1], p[2], p[0], p[2], p[3], p[0], p[2], p[1], p[0], p[3], p[2]}, name);
}

/// Adds `count` see-through objects across the scene's ground: glass panes, alpha-tested fences
/// (long, low) and foliage cards (two crossed panes). Returns the per-object see-through flags.
inline std::vector<std::uint8_t> add_see_through(support::Scene& scene, int count, float size, std::uint64_t seed) {
  support::Rng rng(seed);
  const Aabb sb = scene.bounds;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 at(rng.uniform(sb.min.x, sb.max.x), sb.min.y, rng.uniform(sb.min.z, sb.max.z));
    const float yaw = rng.uniform(0.0f, 6.2831853f);
    const glm::vec3 along(std::cos(yaw), 0.0f, std::sin(yaw));
    const int kind = i % 3;
    if (kind == 0) {
      const float w = size * rng.uniform(0.5f, 2.0f);
      add_pane(scene, at - along * w, at + along * w, size * rng.uniform(0.5f, 1.5f), "glass_" + std::to_string(i));
    } else if (kind == 1) {
      const float w = size * rng.uniform(1.0f, 3.0f);
      add_pane(scene, at - along * w, at + along * w, size * 0.4f, "fence_" + std::to_string(i));
    } else {
      const float w = size * 0.5f, h = size * rng.uniform(0.5f, 1.0f);
      const glm::vec3 across(-along.z, 0.0f, along.x);
      const glm::vec3 up(0.0f, h, 0.0f);
      const glm::vec3 p[8] = {at - along * w, at + along * w, at + along * w + up, at - along * w + up,
                              at - across * w, at + across * w, at + across * w + up, at - across * w + up};
      std::vector<glm::vec3> tris;
      for (int q = 0; q < 2; ++q) {
        const glm::vec3* c = p + 4 * q;
        for (const glm::vec3& v : {c[0], c[1], c[2], c[0], c[2], c[3], c[0], c[2], c[1], c[0], c[3], c[2]}) tris.push_back(v);
      }
      scene.add_triangles(tris, "foliage_" + std::to_string(i));
    }
  }
  std::vector<std::uint8_t> flags(scene.objects.size(), 0);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const std::string& n = scene.objects[o].name;
    flags[o] = n.rfind("glass_", 0) == 0 || n.rfind("fence_", 0) == 0 || n.rfind("foliage_", 0) == 0;
  }
  return flags;
}

/// See-through objects of a Quake 3 map by its .json sidecar (per object `contents` and
/// `surface_flags`, objects named as in the .obj): translucent, water, lava, slime or fog contents,
/// or a nodraw, sky, alpha-shadow or non-solid surface. Empty when the sidecar is absent.
inline std::vector<std::uint8_t> quake_see_through(const support::Scene& scene, const std::string& json_path) {
  std::ifstream in(json_path);
  if (!in) return {};
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::vector<std::pair<std::string, bool>> named;
  const std::string key = "{\"name\": \"";
  for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
    const std::size_t b = at + key.size(), e = text.find('"', b), close = text.find('}', b);
    if (e == std::string::npos || close == std::string::npos) break;
    const auto field = [&](const char* k) -> long long {
      const std::size_t f = text.find(k, b);
      if (f == std::string::npos || f > close) return 0;
      return std::strtoll(text.c_str() + f + std::char_traits<char>::length(k), nullptr, 10);
    };
    const long long contents = field("\"contents\": "), surface = field("\"surface_flags\": ");
    const long long see_contents = 0x20000000LL | 8 | 16 | 32 | 64;  // translucent, lava, slime, water, fog
    const long long see_surface = 0x80 | 0x4 | 0x10000 | 0x4000;     // nodraw, sky, alpha shadow, non-solid
    named.emplace_back(text.substr(b, e - b), (contents & see_contents) != 0 || (surface & see_surface) != 0);
  }
  std::vector<std::uint8_t> flags(scene.objects.size(), 0);
  std::size_t j = 0;  // the sidecar lists the objects in the .obj's order
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    while (j < named.size() && named[j].first != scene.objects[o].name) ++j;
    if (j == named.size()) break;
    flags[o] = named[j].second;
  }
  return flags;
}

/// The ray families of the engine-frame tests: fewer in slow builds (MESH_OCC_SLOW).
inline RaySet frame_rays(std::uint64_t seed) {
  RaySet set;
  set.second_width = MESH_OCC_SLOW ? 127 : 257;
  set.second_height = MESH_OCC_SLOW ? 71 : 143;
  set.jitter = MESH_OCC_SLOW ? 1024 : 4096;
  set.seed = seed;
  return set;
}
constexpr int kFrameWidth = MESH_OCC_SLOW ? 160 : 320, kFrameHeight = MESH_OCC_SLOW ? 90 : 180;

/// A 256x256 camera at `eye` looking at `target` (60 degrees, near 0.1, far 100).
inline Camera look_at(const glm::vec3& eye, const glm::vec3& target) {
  Camera cam;
  cam.eye = eye;
  cam.width = 256;
  cam.height = 256;
  cam.view_proj = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 100.0f) * glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  return cam;
}

/// Whether `out` lists object `o`.
inline bool lists(const std::vector<std::uint32_t>& out, std::uint32_t o) {
  return std::find(out.begin(), out.end(), o) != out.end();
}

/// A panel x in [-0.5, 0.5], y in [0, 1], z = 0, facing +z, cut into n x n quads (shared corners).
inline void cut_panel(int n, std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices) {
  positions.clear();
  indices.clear();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) positions.emplace_back(float(i) / float(n) - 0.5f, float(j) / float(n), 0.0f);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const auto a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + std::uint32_t(n + 2), d = a + std::uint32_t(n + 1);
      for (std::uint32_t v : {a, b, c, a, c, d}) indices.push_back(v);
    }
}

}  // namespace mesh_occlusion_test
