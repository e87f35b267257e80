// MeshOcclusionCuller::cull with moving occluders, against Embree truth: walls (subdivided, 16-bit
// indices, one-sided), vehicles (closed, interleaved vertices, 32-bit indices) and doors (one-sided
// panels, opened at any angle) placed along the walks each frame by world matrices, rotated, scaled
// non-uniformly and mirrored, often seen from behind. No object truly seen may be culled, and no
// moving occluder's box that is_hidden hides may be seen. Power: a wall filling most of the view
// 3 m ahead of the eye hides most of the objects that Embree says are hidden with it. Also the
// shortest cases: a wall and a mirrored wall hide a crate; a mirrored wall seen from its back, a
// non-affine, singular or NaN matrix, and bad indices hide nothing.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "check.hpp"
#include "frame_truth.hpp"
#include "walk_cameras.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

constexpr int kWalk = MESH_OCC_SLOW ? 3 : 10;

/// A moving occluder's own buffers and what the truth needs of it.
struct Shape {
  std::vector<glm::vec3> positions;           // for the truth
  std::vector<std::uint32_t> indices;         // for the truth
  std::vector<float> interleaved;             // position + normal per vertex (vehicles)
  std::vector<std::uint16_t> indices16;       // walls and doors
  std::vector<std::uint32_t> indices32;       // vehicles
  [[nodiscard]] StridedMesh mesh() const {
    if (!interleaved.empty())
      return StridedMesh{{reinterpret_cast<const unsigned char*>(interleaved.data()), 24, 0}, positions.size(), {indices32.data(), indices32.size(), IndexFormat::uint32}};
    return StridedMesh{{reinterpret_cast<const unsigned char*>(positions.data()), sizeof(glm::vec3), 0}, positions.size(), {indices16.data(), indices16.size(), IndexFormat::uint16}};
  }
};

/// A cut panel (cut_panel) as a wall or door: 16-bit indices.
Shape panel(int n) {
  Shape s;
  cut_panel(n, s.positions, s.indices);
  for (std::uint32_t v : s.indices) s.indices16.push_back(static_cast<std::uint16_t>(v));
  return s;
}

/// A vehicle: a body box and a cab box on it, closed, outward; interleaved position + normal.
Shape vehicle() {
  Shape s;
  const auto add_box = [&](const Aabb& box) {
    const auto base = static_cast<std::uint32_t>(s.positions.size());
    for (int k = 0; k < 8; ++k) s.positions.push_back(corner(box, k));
    for (std::uint32_t v : support::kBoxTriangleCorners) s.indices.push_back(base + v);
  };
  add_box(Aabb{{-0.5f, 0.0f, -0.5f}, {0.5f, 0.5f, 0.5f}});
  add_box(Aabb{{-0.3f, 0.5f, -0.4f}, {0.2f, 0.9f, 0.4f}});
  for (const glm::vec3& p : s.positions)
    for (float f : {p.x, p.y, p.z, 0.0f, 1.0f, 0.0f}) s.interleaved.push_back(f);
  s.indices32 = s.indices;
  return s;
}

/// A crate face at z = -3 (and a floor tile beside it, so there are two objects), eye at z = 5;
/// moving walls at z = 0.
void shortest_cases() {
  const std::vector<glm::vec3> positions = {{-0.5f, -0.5f, -3}, {0.5f, -0.5f, -3}, {0.5f, 0.5f, -3}, {-0.5f, 0.5f, -3},
                                            {40, -5, -40}, {41, -5, -40}, {41, -5, -41}};
  const std::vector<std::uint32_t> indices = {0, 1, 2, 0, 2, 3, 4, 5, 6};
  const MeshObject objects[2] = {{0, 2}, {2, 1}};
  const MeshOcclusionCuller<glm::vec3> culler(MeshView<glm::vec3>{positions.data(), positions.size(), indices.data(), indices.size()},
                                              objects, 2);
  const Camera cam = look_at({0, 0, 5}, {0, 0, 0});
  const Shape wall = panel(3);
  MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  const glm::mat4 at = glm::translate(glm::mat4(1.0f), glm::vec3(0, -2, 0));
  const auto run = [&](const glm::mat4& model) {
    const MovingOccluder moving{wall.mesh(), model};
    culler.cull(cam, context, out, &moving, 1);
    return !lists(out, 0);
  };
  CHECK_MSG(run(glm::scale(at, glm::vec3(4, 4, 1))), "a moving wall hides the crate");
  CHECK(context.stats().moving_triangles > 0);
  CHECK_MSG(run(glm::scale(at, glm::vec3(-4, 4, 1))), "a mirrored moving wall (scale x -4) hides the crate");
  // Turned away (its back to the eye): hides nothing, mirrored or not. Mirrored through its own
  // plane (scale z -1), its front (+z in its own space) faces away too; turned round, it hides.
  const glm::mat4 back = glm::rotate(at, 3.14159265f, glm::vec3(0, 1, 0));
  CHECK_MSG(!run(glm::scale(back, glm::vec3(4, 4, 1))), "a wall seen from its back hides nothing");
  CHECK_MSG(!run(glm::scale(back, glm::vec3(-4, 4, 1))), "a mirrored wall seen from its back hides nothing");
  CHECK_MSG(!run(glm::scale(at, glm::vec3(4, 4, -1))), "a wall mirrored through its plane faces away: hides nothing");
  CHECK_MSG(run(glm::scale(back, glm::vec3(4, 4, -1))), "a wall mirrored through its plane, turned round, hides the crate");
  CHECK_MSG(!run(glm::scale(at, glm::vec3(4, 4, 0))), "a singular matrix hides nothing");
  glm::mat4 projective = glm::scale(at, glm::vec3(4, 4, 1));
  projective[2][3] = 0.1f;
  CHECK_MSG(!run(projective), "a non-affine matrix hides nothing");
  CHECK_MSG(!run(glm::mat4(std::numeric_limits<float>::quiet_NaN())), "a NaN matrix hides nothing");
  // Bad indices: the triangles that hold one hide nothing, the rest still do.
  std::vector<std::uint16_t> bad = wall.indices16;
  for (std::size_t i = 0; i < bad.size(); i += 6) bad[i] = 999;
  const MovingOccluder broken{StridedMesh{{reinterpret_cast<const unsigned char*>(wall.positions.data()), sizeof(glm::vec3), 0}, wall.positions.size(),
                                          {bad.data(), bad.size(), IndexFormat::uint16}},
                              glm::scale(at, glm::vec3(4, 4, 1))};
  culler.cull(cam, context, out, &broken, 1);
  CHECK(lists(out, 0));
  culler.cull(cam, context, out, nullptr, 0);
  CHECK(lists(out, 0) && context.stats().moving_triangles == 0);
  // The box query sees the moving wall: a box behind it is hidden, the crate's box too.
  culler.cull(cam, context, out, std::vector<MovingOccluder>{{wall.mesh(), glm::scale(at, glm::vec3(4, 4, 1))}}.data(), 1);
  CHECK(context.is_hidden(Aabb{{-0.2f, -0.2f, -2.0f}, {0.2f, 0.2f, -1.0f}}));
  CHECK(!context.is_hidden(Aabb{{-0.2f, -0.2f, 1.0f}, {0.2f, 0.2f, 2.0f}}));  // in front of the wall
}

struct Placed {
  const Shape* shape;
  glm::mat4 model;
  bool mirrored;
};

/// Moving occluders along the view: walls, vehicles and doors at 1.5 to 15 m, yawed at random (so
/// often seen from behind), scaled non-uniformly, a third of them mirrored.
std::vector<Placed> place(const Camera& cam, const WalkSpec& spec, const Shape* shapes, support::Rng& rng, int count) {
  const PixelRays rays(cam);
  const float m = spec.metre;
  std::vector<Placed> out;
  for (int i = 0; i < count; ++i) {
    const int kind = i % 3;
    glm::vec3 dir = rays.ray_at(double(rng.uniform()) * cam.width, double(rng.uniform()) * cam.height).direction;
    const glm::vec3 at = cam.eye + dir * (m * rng.uniform(1.5f, 15.0f)) - glm::vec3(0.0f, spec.eye_height * rng.uniform(0.3f, 1.0f), 0.0f);
    glm::mat4 model = glm::translate(glm::mat4(1.0f), at);
    model = glm::rotate(model, rng.uniform(0.0f, 6.2831853f), glm::vec3(0, 1, 0));
    glm::vec3 scale = kind == 0   ? glm::vec3(rng.uniform(2.0f, 8.0f), rng.uniform(2.0f, 4.0f), 1.0f)
                      : kind == 1 ? glm::vec3(rng.uniform(3.5f, 5.0f), rng.uniform(1.3f, 2.0f), rng.uniform(1.6f, 2.2f))
                                  : glm::vec3(rng.uniform(0.8f, 1.2f), rng.uniform(2.0f, 2.3f), 1.0f);
    scale *= m;
    const bool mirrored = rng.range(0, 2) == 0;
    if (mirrored) (rng.range(0, 1) ? scale.x : scale.z) *= -1.0f;
    out.push_back({&shapes[kind], glm::scale(model, scale), mirrored});
  }
  return out;
}

struct Tally {
  std::size_t frames = 0, moving_hidden_boxes = 0;
  long false_culls = 0, false_box_hides = 0;
  std::size_t wall_truly_hidden = 0, wall_culler_hidden = 0;
};

void run_scene(const std::string& name, const support::Scene& scene, std::uint64_t seed, Tally& all) {
  oracle::EmbreeScene walker;
  walker.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  walker.commit();
  const ObjectMap map(scene);
  const MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), map.objects.data(), map.objects.size());
  const WalkSpec spec = walk_spec(name, scene, walker, seed);
  const auto cams = walk_then_hard_cameras(spec, scene, walker, kWalk, kFrameWidth, kFrameHeight, seed + 1);
  const Shape shapes[3] = {panel(4), vehicle(), panel(1)};
  support::Rng rng(seed * 13 + 5);
  MeshOcclusionContext context;
  std::vector<std::uint32_t> out;
  Tally tally;
  RaySet set = frame_rays(0);
  const auto seen_by = [&](const FrameOccluders& occ, const Camera& cam) {
    const auto rays = cast_frame(occ, map, cam, set);
    std::vector<std::uint8_t> seen(scene.objects.size(), 0);
    for (const TruthRay& r : rays)
      if (r.object != no_object) seen[r.object] = 1;
    return std::make_pair(seen, rays);
  };
  const auto missing = [](const std::vector<std::uint32_t>& answer, const std::vector<std::uint8_t>& seen) {
    std::vector<std::uint8_t> kept(seen.size(), 0);
    for (std::uint32_t o : answer) kept[o] = 1;
    long n = 0;
    for (std::size_t o = 0; o < seen.size(); ++o) n += seen[o] && !kept[o];
    return n;
  };
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci].camera;
    set.seed = seed * 1000 + ci;
    const auto placed = place(cam, spec, shapes, rng, 6);
    std::vector<MovingOccluder> moving;
    std::vector<std::vector<glm::vec3>> world;
    for (const Placed& p : placed) {
      moving.push_back({p.shape->mesh(), p.model});
      world.push_back(world_triangles(p.shape->positions, p.shape->indices, p.model));
    }
    const FrameOccluders occ(scene, {}, world);
    const auto [seen, rays] = seen_by(occ, cam);
    culler.cull(cam, context, out, moving.data(), moving.size());
    const long fc = missing(out, seen);
    CHECK_MSG(fc == 0, "%s camera %zu (%s): %ld false culls with moving occluders", name.c_str(), ci,
              cams[ci].name.c_str(), fc);
    tally.false_culls += fc;
    // A vehicle tested by is_hidden: its world box, against the others.
    const glm::dvec3 eye(cam.eye);
    for (std::size_t i = 0; i < placed.size(); ++i) {
      Aabb box = Aabb::empty();
      for (const glm::vec3& p : world[i]) box = merge(box, p);
      if (!context.is_hidden(box)) continue;
      ++tally.moving_hidden_boxes;
      bool box_seen = false;
      for (const TruthRay& r : rays) box_seen = box_seen || ray_sees_box(eye, r, box);
      CHECK_MSG(!box_seen, "%s camera %zu: a moving occluder's box reported hidden is seen", name.c_str(), ci);
      tally.false_box_hides += box_seen;
    }
    ++tally.frames;
    // Power: a wall filling most of the view 3 m ahead.
    if (cams[ci].name.rfind("walk", 0) != 0) continue;
    const glm::mat4 inv = glm::inverse(cam.view_proj);
    const auto unproject = [&](float x, float y) {
      const glm::vec4 h = inv * glm::vec4(x, y, 0.5f, 1.0f);
      return glm::normalize(glm::vec3(h) / h.w - cam.eye);
    };
    const glm::vec3 ahead = unproject(0, 0), right = glm::normalize(unproject(1, 0) - unproject(-1, 0)),
                    up = glm::normalize(unproject(0, 1) - unproject(0, -1));
    const float d = 3.0f * spec.metre;
    // Scale to 0.9 of the view's half extents at distance d.
    const float half_w = 0.9f * d * glm::length(unproject(1, 0) / glm::dot(unproject(1, 0), ahead) - ahead);
    const float half_h = 0.9f * d * glm::length(unproject(0, 1) / glm::dot(unproject(0, 1), ahead) - ahead);
    glm::mat4 wall_model(1.0f);
    wall_model[0] = glm::vec4(right * (2.0f * half_w), 0.0f);
    wall_model[1] = glm::vec4(up * (2.0f * half_h), 0.0f);
    wall_model[2] = glm::vec4(-ahead, 0.0f);
    wall_model[3] = glm::vec4(cam.eye + ahead * d - up * half_h, 1.0f);
    const MovingOccluder wall{shapes[0].mesh(), wall_model};
    const FrameOccluders with_wall(scene, {}, {world_triangles(shapes[0].positions, shapes[0].indices, wall_model)});
    const auto seen_wall = seen_by(with_wall, cam).first;
    culler.cull(cam, context, out, &wall, 1);
    CHECK_MSG(missing(out, seen_wall) == 0, "%s camera %zu: false culls behind the wall 3 m ahead", name.c_str(), ci);
    std::vector<std::uint8_t> kept(scene.objects.size(), 0);
    for (std::uint32_t o : out) kept[o] = 1;
    const Frustum frustum = frustum_of(cam);
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
      if (seen_wall[o] || frustum.classify(scene.objects[o].bounds) == Containment::outside) continue;
      ++tally.wall_truly_hidden;
      tally.wall_culler_hidden += !kept[o];
    }
  }
  std::printf("| %s | %zu | %ld | %zu | %ld | %zu | %.1f |\n", name.c_str(), tally.frames, tally.false_culls,
              tally.moving_hidden_boxes, tally.false_box_hides, tally.wall_truly_hidden,
              100.0 * double(tally.wall_culler_hidden) / double(std::max<std::size_t>(tally.wall_truly_hidden, 1)));
  std::fflush(stdout);
  CHECK_MSG(tally.wall_culler_hidden * 10 >= tally.wall_truly_hidden * 8,
            "%s: the wall 3 m ahead hides %zu of the %zu objects truly hidden with it (at least 80%% expected)", name.c_str(),
            tally.wall_culler_hidden, tally.wall_truly_hidden);
  all.moving_hidden_boxes += tally.moving_hidden_boxes;
}

}  // namespace

int main() {
  shortest_cases();
  std::printf("| scene | frames | false culls | moving boxes hidden | of them seen | objects truly hidden by the wall 3 m "
              "ahead | culler hides %% of them |\n|---|---:|---:|---:|---:|---:|---:|\n");
  Tally all;
  run_scene("city", support::make_city(3, MESH_OCC_SLOW ? 4 : 8), 31, all);
  run_scene("office", support::make_office(3, MESH_OCC_SLOW ? 5 : 10, MESH_OCC_SLOW ? 4 : 8), 37, all);
  std::uint64_t seed = 41;
  for (const auto& file : support::real_scene_files()) {
    if (file.find("oacmpdm9") == std::string::npos && file.find("fzk_haus") == std::string::npos) continue;
    if (const auto scene = support::load_obj(support::scenes_dir() + "/" + file)) run_scene(file, *scene, seed++, all);
  }
  CHECK_MSG(all.moving_hidden_boxes > 0, "no moving occluder's box was ever hidden: the box checks prove nothing");
  return cullkit_test::report("test_mesh_occlusion_moving");
}
