// Occlusion culling in an engine frame with MeshOcclusionCuller: a level built from instanced
// prefabs (a block with interleaved vertices and 16-bit indices, a panel with 32-bit indices, some
// instances mirrored), a glass pane that is drawn but hides nothing, a door of the level that opens
// (set_occludes off, and its swinging leaf given as a moving occluder), a truck passing in front as a
// moving occluder, and a car driving behind the wall that is not one of the culler's objects: the
// renderer asks is_hidden(car box, car matrix) whether to draw it.
//
// Four frames. Each is checked against exact ray casting (double precision, every pixel centre of a
// 320x180 view): every object a ray sees must be kept, and the car must be drawn whenever a ray
// meets its box before an occluder. Writes engine_frame_occlusion.png (the four views side by side:
// kept objects in their colours, glass tinted blue, moving occluders in orange, the car green)
// into the folder given as the first argument (default: the current one). Returns non-zero if an
// answer is wrong.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit/mesh_occlusion_culler.hpp>
#include <cullkit_support/image.hpp>

namespace {

using cullkit::Aabb;

struct Prefab {  // the engine's buffers
  std::vector<float> vertices;  // position + normal
  std::vector<std::uint16_t> indices16;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices32;
  cullkit::StridedMesh mesh;
};

Prefab block() {  // a closed unit box standing on y = 0, interleaved, 16-bit
  Prefab p;
  const std::uint16_t faces[36] = {0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5, 0, 1, 5, 0, 5, 4,
                                   2, 6, 7, 2, 7, 3, 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6};
  for (int i = 0; i < 8; ++i)
    for (float f : {(i & 1) ? 0.5f : -0.5f, (i & 2) ? 1.0f : 0.0f, (i & 4) ? 0.5f : -0.5f, 0.0f, 1.0f, 0.0f})
      p.vertices.push_back(f);
  p.indices16.assign(faces, faces + 36);
  p.mesh = {{reinterpret_cast<const unsigned char*>(p.vertices.data()), 24, 0}, 8, {p.indices16.data(), 36, cullkit::IndexFormat::uint16}};
  return p;
}

Prefab panel() {  // x in [0, 1], y in [0, 1], z = 0, facing +z, 32-bit
  Prefab p;
  p.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  p.indices32 = {0, 1, 2, 0, 2, 3};
  p.mesh = {{reinterpret_cast<const unsigned char*>(p.positions.data()), sizeof(glm::vec3), 0}, 4,
            {p.indices32.data(), 6, cullkit::IndexFormat::uint32}};
  return p;
}

glm::mat4 placed(glm::vec3 at, float yaw, glm::vec3 scale) {
  return glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), at), yaw, glm::vec3(0, 1, 0)), scale);
}

/// A triangle of the frame, in the world, for the ray caster.
struct WorldTriangle {
  glm::dvec3 a, b, c;
  int owner;        // object number, or -1 moving occluder, -2 the car
  bool occludes;
};

void add_triangles(std::vector<WorldTriangle>& out, const cullkit::StridedMesh& mesh, const glm::mat4& model, int owner,
                   bool occludes) {
  const glm::dmat4 m(model);
  const bool mirrored = glm::determinant(glm::dmat3(m)) < 0.0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    glm::vec3 p[3];
    if (!cullkit::triangle_positions(mesh, t, p)) continue;
    if (mirrored) std::swap(p[1], p[2]);
    glm::dvec3 w[3];
    for (int k = 0; k < 3; ++k) w[k] = glm::dvec3(m * glm::dvec4(glm::dvec3(p[k]), 1.0));
    out.push_back({w[0], w[1], w[2], owner, occludes});
  }
}

/// Distance along the ray to the front face of the triangle, or -1.
double hit(const glm::dvec3& o, const glm::dvec3& d, const WorldTriangle& tr) {
  const glm::dvec3 e1 = tr.b - tr.a, e2 = tr.c - tr.a;
  if (!(glm::dot(glm::cross(e1, e2), d) < 0.0)) return -1.0;
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  const glm::dvec3 s = o - tr.a;
  const double u = glm::dot(s, p) / det;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) / det;
  if (u < -1e-9 || v < -1e-9 || u + v > 1.0 + 1e-9) return -1.0;
  return glm::dot(e2, q) / det;
}

cullkit::support::Rgb color_of(int owner) {
  if (owner == -1) return {230, 140, 40};
  if (owner == -2) return {40, 190, 60};
  const auto h = static_cast<std::uint32_t>(owner) * 2654435761u;
  return {static_cast<std::uint8_t>(90 + (h >> 8) % 120), static_cast<std::uint8_t>(90 + (h >> 16) % 120),
          static_cast<std::uint8_t>(90 + (h >> 24) % 120)};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  const Prefab box = block(), quad = panel();
  constexpr float pi = 3.14159265f;
  // The level: instances of the two prefabs. Objects are one instance each.
  std::vector<cullkit::MeshInstance> instances;
  std::vector<std::string> names;
  const auto add = [&](const Prefab& p, const glm::mat4& model, const char* name) {
    instances.push_back({p.mesh, model});
    names.push_back(name);
    return static_cast<std::uint32_t>(instances.size() - 1);
  };
  add(quad, glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-30, 0, 30)), -pi / 2, glm::vec3(1, 0, 0)),
                       glm::vec3(60, 60, 1)),
      "ground");
  add(quad, placed({-8, 0, -6}, 0, {6.5f, 4, 1}), "wall left");
  add(quad, placed({1.5f, 0, -6}, 0, {6.5f, 4, 1}), "wall right");
  add(quad, placed({-1.5f, 2, -6}, 0, {3, 2, 1}), "wall over the openings");
  const std::uint32_t glass = add(quad, placed({-1.5f, 0, -6}, 0, {1.5f, 2, 1}), "glass pane");
  const std::uint32_t door = add(quad, placed({0, 0, -6}, 0, {1.5f, 2, 1}), "door");
  for (int i = 0; i < 6; ++i) {
    // Houses behind the wall; every other one mirrored (its matrix has a negative determinant).
    const float sx = i % 2 ? -4.0f : 4.0f;
    add(box, placed({-10.0f + 4.0f * float(i), 0, -16.0f - float(i % 3) * 3.0f}, 0.3f * float(i), {sx, 3.0f + float(i), 4}), "house");
  }
  for (int i = 0; i < 5; ++i) add(box, placed({-4.0f + 2.0f * float(i), 0, -9}, 0, {0.8f, 0.8f, 0.8f}), "crate");
  std::vector<cullkit::MeshObject> objects;
  std::uint32_t first = 0;
  for (const auto& in : instances) {
    const auto n = static_cast<std::uint32_t>(in.mesh.triangle_count());
    objects.push_back({first, n});
    first += n;
  }
  objects[glass].occludes = false;  // drawn, but every ray goes through it
  cullkit::MeshOcclusionCuller<glm::vec3> culler(instances.data(), instances.size(), objects.data(), objects.size());

  cullkit::Camera cam;
  cam.eye = glm::vec3(0.8f, 1.7f, 4.0f);
  cam.width = 320;
  cam.height = 180;
  cam.view_proj = glm::perspective(glm::radians(60.0f), 16.0f / 9.0f, 0.1f, 200.0f) *
                  glm::lookAt(cam.eye, glm::vec3(0.0f, 1.5f, -6.0f), glm::vec3(0, 1, 0));
  const Aabb car_box{{-1.0f, 0.0f, -0.5f}, {1.0f, 1.2f, 0.5f}};
  cullkit::MeshOcclusionContext context;
  std::vector<std::uint32_t> kept;
  cullkit::support::Image picture(4 * cam.width, cam.height, {0, 0, 0});
  int wrong = 0;
  for (int frame = 0; frame < 4; ++frame) {
    // The door opens from frame 2 on: the level's door stops occluding, its leaf swings as a moving
    // occluder. A truck passes in front of the wall; the car drives behind it.
    const bool open = frame >= 2;
    culler.set_occludes(door, !open);
    std::vector<cullkit::MovingOccluder> moving;
    moving.push_back({box.mesh, placed({-9.0f + 5.0f * float(frame), 0, -2.5f}, 0, {3, 2.5f, 1.6f})});  // truck
    if (open) moving.push_back({quad.mesh, placed({0, 0, -6}, 1.4f, {1.5f, 2, 1})});                 // door leaf
    const glm::mat4 car = placed({-6.0f + 4.0f * float(frame), 0, -10.5f}, 0.2f, {1, 1, 1});
    culler.cull(cam, context, kept, moving.data(), moving.size());
    const bool draw_car = !context.is_hidden(car_box, car);
    // Check by ray casting, and draw this frame's picture.
    std::vector<WorldTriangle> world;
    for (std::size_t i = 0; i < instances.size(); ++i)
      add_triangles(world, instances[i].mesh, instances[i].model, int(i), culler.occludes(std::uint32_t(i)));
    for (const auto& m : moving) add_triangles(world, m.mesh, m.model, -1, true);
    const glm::dmat4 car_inverse = glm::inverse(glm::dmat4(car));
    std::vector<std::uint8_t> seen(instances.size(), 0), is_kept(instances.size(), 0);
    for (std::uint32_t o : kept) is_kept[o] = 1;
    bool car_seen = false;
    const cullkit::PixelRays rays(cam);
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const glm::dvec3 o(cam.eye), d(rays.ray(x, y).direction);
        double stop = 1e30;
        int nearest = -3;
        for (const auto& tr : world) {
          const double t = hit(o, d, tr);
          if (t > 0.1 && t < stop && tr.occludes) stop = t, nearest = tr.owner;
        }
        if (nearest >= 0) seen[std::size_t(nearest)] = 1;
        cullkit::support::Rgb c = nearest == -3 ? cullkit::support::Rgb{150, 190, 230} : color_of(nearest);
        if (nearest >= 0 && !is_kept[std::size_t(nearest)]) c = {255, 0, 0};  // a false cull, if any
        // The car: its box, met before the ray stops.
        const glm::dvec3 lo = glm::dvec3(car_inverse * glm::dvec4(o, 1.0)), ld = glm::dvec3(car_inverse * glm::dvec4(d, 0.0));
        double enter = 0.1, leave = stop;
        for (int a = 0; a < 3 && enter <= leave; ++a) {
          double t0 = (double(car_box.min[a]) - lo[a]) / ld[a], t1 = (double(car_box.max[a]) - lo[a]) / ld[a];
          if (t0 > t1) std::swap(t0, t1);
          enter = std::max(enter, t0);
          leave = std::min(leave, t1);
        }
        if (enter <= leave) {
          car_seen = true;
          c = draw_car ? color_of(-2) : cullkit::support::Rgb{255, 0, 0};
        }
        picture.set(frame * cam.width + x, y, c);
        // Glass in front of what the ray stops at: drawn tinted, and seen.
        for (const auto& tr : world) {
          const double t = hit(o, d, tr);
          if (!tr.occludes && t > 0.1 && t < std::min(stop, enter <= leave ? enter : stop)) {
            seen[std::size_t(tr.owner)] = 1;
            picture.blend(frame * cam.width + x, y, {60, 120, 255}, 0.35f);
            break;
          }
        }
      }
    int false_culls = 0;
    for (std::size_t o = 0; o < seen.size(); ++o) false_culls += seen[o] && !is_kept[o];
    const bool car_wrong = car_seen && !draw_car;
    wrong += false_culls + (car_wrong ? 1 : 0);
    std::printf("frame %d: door %s, %zu moving occluders (%zu triangles), %zu of %zu objects kept, car %s%s; "
                "false culls %d\n",
                frame, open ? "open" : "closed", moving.size(), context.stats().moving_triangles, kept.size(),
                objects.size(), draw_car ? "drawn" : "hidden", car_wrong ? " (WRONG: it is seen)" : "", false_culls);
  }
  const std::string path = dir + "/engine_frame_occlusion.png";
  const bool written = picture.write_png(path);
  std::printf("%s %s\n", written ? "wrote" : "could not write", path.c_str());
  return wrong == 0 ? 0 : 1;
}
