// libFuzzer target: bytes -> a small mesh cut into objects (quantized or raw float corners, NaN and
// inf included, indices possibly out of range, object ranges possibly outside the mesh) and a
// perspective camera (either depth range, reversed-Z, infinite far plane, any grid size). Checks:
// no crash, no sanitizer report, each written object once and in range, unusable objects written,
// the same answer on three tasks (run in reverse order) as on one, and the contract on a few rays: no pixel-rule ray through the screen sees a hidden object first
// (front faces, between the near and the far plane; double-precision brute force).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/common.hpp>
#include <glm/ext/vector_double3.hpp>
#include <glm/geometric.hpp>

#include <cullkit/mesh_occlusion_culler.hpp>

namespace {
struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  std::uint8_t byte() {
    if (size == 0) return 0;
    --size;
    return *data++;
  }
  float coord(bool raw) {
    if (raw && size >= 4) {
      float f;
      std::memcpy(&f, data, 4);
      data += 4;
      size -= 4;
      return f;
    }
    return (static_cast<int>(byte()) - 128) / 16.0f;  // [-8, 8) in 1/16 steps: shared edges, ties
  }
};

// A job system that runs the tasks on the calling thread, last first.
void run_reversed(void*, std::size_t count, void (*run)(void*, std::size_t), void* job) {
  for (std::size_t i = count; i > 0; --i) run(job, i - 1);
}

// det[x, y, z] and a bound on its rounding (the permanent of the magnitudes, times 2^-40).
double det3(const glm::dvec3& x, const glm::dvec3& y, const glm::dvec3& z, double& bound) {
  bound = 0x1p-40 * (std::fabs(x.x) * (std::fabs(y.y * z.z) + std::fabs(y.z * z.y)) +
                     std::fabs(x.y) * (std::fabs(y.x * z.z) + std::fabs(y.z * z.x)) +
                     std::fabs(x.z) * (std::fabs(y.x * z.y) + std::fabs(y.y * z.x)));
  return x.x * (y.y * z.z - y.z * z.y) - x.y * (y.x * z.z - y.z * z.x) + x.z * (y.x * z.y - y.y * z.x);
}

// Front-face hit parameter, or -1. grow > 0 widens the triangle (occluders), < 0 shrinks it.
// Everything is decided from the corners relative to the eye: A, B, C = a, b, c - o. The eye is on
// the front side when det[A, B, C] < 0, and the ray meets the triangle beyond the eye when d is a
// non-negative mix of A, B, C, i.e. when det[d, B, C], det[A, d, C] and det[A, B, d] all have the
// sign of det[A, B, C] (then t = det[A, B, C] / their sum). Corners near 1e30 make world-space
// edges and barycentrics meaningless; these determinants carry their own rounding bounds, and
// where a sign is within its bound the answer is taken the way that claims less: an occluder
// (grow > 0) faces the eye and is met, a hidden object is not.
double hit(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
           double grow) {
  const glm::dvec3 A = a - o, B = b - o, C = c - o;
  double bs, b0, b1, b2;
  const double s = det3(A, B, C, bs);
  if (std::fabs(s) <= bs ? grow < 0.0 : !(s < 0.0)) return -1.0;
  const double k[3] = {det3(d, B, C, b0), det3(A, d, C, b1), det3(A, B, d, b2)}, bound[3] = {b0, b1, b2};
  const double sum = k[0] + k[1] + k[2];
  for (int i = 0; i < 3; ++i) {
    // Inside means k[i] <= 0 (the sign of s); grow scales a margin on the mix's weights.
    const double margin = bound[i] + std::fabs(grow) * std::fabs(sum);
    if (grow < 0.0 ? !(k[i] < -margin) : !(k[i] <= margin)) return -1.0;
  }
  const double t = s / sum;
  if (!(t > 0.0) || !std::isfinite(t)) return -1.0;
  return t;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader r{data, size};
  const std::uint8_t config = r.byte();
  const bool raw = (config & 1) != 0;
  const auto depth = (config & 2) ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one;
  const bool reversed = (config & 4) != 0, infinite = (config & 8) != 0;
  const std::size_t vertex_count = r.byte() % 24;
  const std::size_t triangle_count = r.byte() % 20;
  const std::size_t object_count = r.byte() % 8;
  std::vector<glm::vec3> vertices(vertex_count);
  for (auto& v : vertices) v = glm::vec3(r.coord(raw), r.coord(raw), r.coord(raw));
  std::vector<std::uint32_t> indices(3 * triangle_count);
  for (auto& i : indices) i = r.byte() % (vertex_count + 2);  // a few out of range
  std::vector<cullkit::MeshObject> objects(object_count);
  for (auto& o : objects) {
    o.first_triangle = r.byte() % (triangle_count + 2);
    o.triangle_count = r.byte() % 6;
  }
  const glm::vec3 eye(r.coord(false), r.coord(false), r.coord(false));
  glm::vec3 target(r.coord(false), r.coord(false), r.coord(false));
  if (glm::length(target - eye) < 0.1f) target = eye + glm::vec3(0.0f, 0.0f, -1.0f);
  const float near_plane = 0.01f + r.byte() / 64.0f;
  const float fov = glm::radians(20.0f + r.byte() % 120);
  const glm::vec3 forward = glm::normalize(target - eye);
  const glm::vec3 up = std::fabs(forward.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const glm::mat4 view = glm::lookAtRH(eye, target, up);
  glm::mat4 proj;
  const float far_plane = 100.0f;
  if (infinite) {
    proj = glm::infinitePerspectiveRH(fov, 1.5f, near_plane);
  } else if (depth == cullkit::DepthRange::zero_to_one) {
    proj = reversed ? glm::perspectiveRH_ZO(fov, 1.5f, far_plane, near_plane) : glm::perspectiveRH_ZO(fov, 1.5f, near_plane, far_plane);
  } else {
    proj = glm::perspectiveRH_NO(fov, 1.5f, near_plane, far_plane);
  }
  const cullkit::Camera cam{eye, proj * view, 96, 64, infinite ? cullkit::DepthRange::negative_one_to_one : depth};

  cullkit::MeshOcclusionParams params;
  params.grid_width = 8 + r.byte() % 64;
  params.grid_height = 8 + r.byte() % 64;
  params.min_occluder_screen_fraction = 0.0f;
  params.depth_band_ratio = (r.byte() % 4) * 0.1f;
  // Taller grids too (the occluder insertion cuts them into several strips of rows).
  if (r.byte() & 1) params.grid_height *= 3;
  const cullkit::MeshView<glm::vec3> mesh{vertices.data(), vertices.size(), indices.data(), indices.size()};
  const cullkit::MeshOcclusionCuller<glm::vec3> culler(mesh, objects.data(), objects.size(), params);
  std::vector<std::uint32_t> out;
  culler.cull(cam, out);
  // The same cull on three tasks, run in reverse order on this thread: the same answer.
  cullkit::MeshOcclusionParams on_tasks = params;
  on_tasks.threads = 3;
  on_tasks.task_runner = cullkit::TaskRunner{run_reversed, nullptr};
  const cullkit::MeshOcclusionCuller<glm::vec3> culler_on_tasks(mesh, objects.data(), objects.size(), on_tasks);
  std::vector<std::uint32_t> out_on_tasks;
  culler_on_tasks.cull(cam, out_on_tasks);
  if (out_on_tasks != out) std::abort();
  std::vector<char> written(object_count, 0);
  for (std::uint32_t o : out) {
    if (o >= object_count || written[o]) std::abort();
    written[o] = 1;
  }
  // Object of each triangle (the last object listing it; overlaps are allowed) for the rays.
  std::vector<int> owner(triangle_count, -1);
  for (std::size_t o = 0; o < object_count; ++o)
    for (std::uint64_t t = objects[o].first_triangle; t < std::uint64_t(objects[o].first_triangle) + objects[o].triangle_count; ++t)
      if (t < triangle_count) owner[t] = static_cast<int>(o);
  const cullkit::PixelRays rays(cam);
  const glm::dvec3 o(eye), fwd(forward);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 12; ++x) {
      const cullkit::Ray ray = rays.ray_at(x * 8.0 + 4.0, y * 8.0 + 4.0);
      const glm::dvec3 d(ray.direction);
      if (d == glm::dvec3(0.0)) continue;
      // Nearest hit of each object beyond the near plane, for the objects the culler hid.
      for (std::size_t ob = 0; ob < object_count; ++ob) {
        if (written[ob]) continue;
        double t_ob = -1.0, t_other = -1.0;
        for (std::size_t t = 0; t < triangle_count; ++t) {
          bool ok = true;
          glm::dvec3 p[3];
          for (int k = 0; k < 3; ++k) {
            const std::uint32_t i = indices[3 * t + std::size_t(k)];
            ok = ok && i < vertex_count;
            if (ok) p[k] = glm::dvec3(vertices[i]);
          }
          if (!ok) continue;
          const bool mine = objects[ob].first_triangle <= t && t < std::uint64_t(objects[ob].first_triangle) + objects[ob].triangle_count;
          const double th = hit(o, d, p[0], p[1], p[2], mine ? -1e-9 : 1e-9);
          // Between the planes: beyond the far plane (finite) the frustum test rightly drops an
          // object; hits within 2^-12 of it count as beyond (the culler's plane is float).
          const double along = th * glm::dot(d, fwd);
          if (th < 0.0 || !(along > near_plane) || (!infinite && !(along < far_plane * (1.0 - 0x1p-12)))) continue;
          if (mine && owner[t] >= 0) {
            if (t_ob < 0.0 || th < t_ob) t_ob = th;
          } else if (!mine && owner[t] >= 0) {
            if (t_other < 0.0 || th < t_other) t_other = th;
          }
        }
        if (t_ob >= 0.0 && !(t_other >= 0.0 && t_other < t_ob)) std::abort();  // a hidden object is seen
      }
    }
  return 0;
}
