// mesh_occlusion_picture: what MeshOcclusionCuller keeps and hides from one player's view. On the
// OpenArena map oacmpdm9 when present (else the generated office; argv[2] may name another scene),
// from the walk camera whose culler hides the most, writes into argv[1]:
//   mesh_occlusion_topdown.png  the level from above, cut just above the eye (no ceilings): triangles
//                               of objects outside the frustum grey, then of kept objects green, then
//                               of objects hidden by occlusion red on top, and the occluders the
//                               culler used (the triangles it put in its coverage grid, and the solid
//                               boxes it put in its box tree) orange over all; the camera and its
//                               view edges in blue.
//   mesh_occlusion_view.png     the camera's view (Embree first hits, shaded by facing; kept objects
//                               tinted green) with the edges of the hidden objects' triangles drawn
//                               in red through the walls that hide them.
// Prints the counts and the number of truly visible objects the culler left out (must be 0).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include <cullkit/mesh_occlusion_culler.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

#include "../tests/mesh_occlusion/embree_truth.hpp"
#include "../tests/mesh_occlusion/walk_cameras.hpp"

using namespace cullkit;
using namespace mesh_occlusion_test;

namespace {

enum class Fate : std::uint8_t { outside, hidden, kept };

const support::Rgb kColour[3] = {{170, 170, 170}, {220, 40, 40}, {40, 170, 60}};

support::Image top_down(const support::Scene& scene, const ObjectMap& map, const std::vector<Fate>& fate,
                        const std::vector<std::uint8_t>& occluder, const Camera& cam, float cut_height,
                        float view_length) {
  // The map frames the objects that are not a large part of the whole scene (a sky box or a kill
  // plane under the level would shrink the level to a corner), and leaves those out.
  const float diag = glm::length(scene.bounds.max - scene.bounds.min);
  std::vector<std::uint8_t> drawn(scene.objects.size(), 0);
  Aabb frame = Aabb::empty();
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const Aabb& b = scene.objects[o].bounds;
    if (!(glm::length(b.max - b.min) < 0.5f * diag)) continue;
    drawn[o] = 1;
    frame = merge(frame, b);
  }
  if (is_empty(frame)) frame = scene.bounds;
  support::TopDownMap top(frame, 1200);
  top.image().fill_rect(0, 0, top.image().width(), top.image().height(), {255, 255, 255});
  // Outside first, then kept, then hidden: the hidden objects are mostly small things in rooms whose
  // kept floors and walls would otherwise paint over them.
  for (const int pass : {0, 2, 1}) {
    for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
      const std::uint32_t o = map.triangle_object[t];
      if (o == no_object || !drawn[o] || static_cast<int>(fate[o]) != pass) continue;
      const glm::vec3 a = scene.positions[scene.indices[3 * t]], b = scene.positions[scene.indices[3 * t + 1]],
                      c = scene.positions[scene.indices[3 * t + 2]];
      if (std::min({a.y, b.y, c.y}) > cut_height) continue;
      top.image().fill_triangle(top.to_pixel(a), top.to_pixel(b), top.to_pixel(c), kColour[pass], pass == 0 ? 0.25f : 0.5f);
    }
  }
  for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
    if (!occluder[t]) continue;
    const glm::vec3 a = scene.positions[scene.indices[3 * t]], b = scene.positions[scene.indices[3 * t + 1]],
                    c = scene.positions[scene.indices[3 * t + 2]];
    if (std::min({a.y, b.y, c.y}) > cut_height) continue;
    top.image().fill_triangle(top.to_pixel(a), top.to_pixel(b), top.to_pixel(c), {245, 150, 20}, 0.5f);
  }
  top.camera(cam, view_length, {30, 60, 230});
  const glm::vec2 e = top.to_pixel(cam.eye);
  top.image().fill_rect(static_cast<int>(e.x) - 4, static_cast<int>(e.y) - 4, static_cast<int>(e.x) + 5,
                        static_cast<int>(e.y) + 5, {30, 60, 230});
  return std::move(top.image());
}

support::Image view(const support::Scene& scene, const ObjectMap& map, const std::vector<Fate>& fate,
                    const oracle::EmbreeScene& embree, const Camera& cam) {
  support::Image img(cam.width, cam.height, {25, 25, 35});
  const PixelRays rays(cam);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const glm::vec3 dir = rays.ray(x, y).direction;
      std::uint32_t tri = 0;
      const std::uint32_t o = first_object(embree, map, cam, dir, &tri);
      if (o == no_object) continue;
      const glm::vec3 a = scene.positions[scene.indices[3 * tri]], b = scene.positions[scene.indices[3 * tri + 1]],
                      c = scene.positions[scene.indices[3 * tri + 2]];
      const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
      const float shade = 0.25f + 0.75f * std::fabs(glm::dot(n, dir));
      const support::Rgb base = fate[o] == Fate::kept ? support::Rgb{120, 230, 130} : support::Rgb{255, 0, 255};
      img.set(x, y, {static_cast<std::uint8_t>(base.r * shade), static_cast<std::uint8_t>(base.g * shade),
                     static_cast<std::uint8_t>(base.b * shade)});
    }
  }
  // Hidden objects' triangle edges, projected; triangles reaching behind the eye plane are skipped.
  const auto project = [&](const glm::vec3& p, glm::vec2& out) {
    const glm::vec4 c = cam.view_proj * glm::vec4(p, 1.0f);
    if (!(c.w > 1e-4f)) return false;
    out = glm::vec2((c.x / c.w * 0.5f + 0.5f) * cam.width, (0.5f - c.y / c.w * 0.5f) * cam.height);
    return std::fabs(out.x) < 1e5f && std::fabs(out.y) < 1e5f;
  };
  for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
    const std::uint32_t o = map.triangle_object[t];
    if (o == no_object || fate[o] != Fate::hidden) continue;
    glm::vec2 q[3];
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) ok = project(scene.positions[scene.indices[3 * t + k]], q[k]);
    if (!ok) continue;
    for (int k = 0; k < 3; ++k) img.line(q[k].x, q[k].y, q[(k + 1) % 3].x, q[(k + 1) % 3].y, {230, 40, 40}, 0.45f);
  }
  return img;
}

/// The occluders of one cull: per triangle, 1 when the culler put it in its coverage grid or it
/// belongs to a solid box of the box tree. Runs the culler's frame at the detail level, where its
/// working memory can be read.
std::vector<std::uint8_t> occluders_of(const support::Scene& scene, const ObjectMap& map, const Camera& cam) {
  namespace dmo = cullkit::detail::mesh_occlusion;
  const MeshOcclusionParams params = dmo::sanitize(MeshOcclusionParams{});
  dmo::MeshIndex index;
  const auto mesh = scene.mesh();
  dmo::build_index(
      index, scene.triangle_count(),
      [&mesh](std::size_t t, glm::vec3 p[3]) { return triangle_positions<VertexTraits<glm::vec3>>(mesh, t, p); },
      map.objects.data(), map.objects.size(), params.tree, params.patch_triangles);
  dmo::Scratch s;
  std::vector<std::uint32_t> out;
  dmo::cull(index, params, cam, s, out);
  std::vector<std::uint8_t> occluder(scene.triangle_count(), 0);
  for (const auto& o : s.occluders) {
    const dmo::Patch& patch = index.patches.patches[o.second];
    for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
      const std::uint32_t t = index.patches.triangles[k];  // a user triangle, or a part of one (T-junction cut)
      if (s.triangle_stamp[t] == s.frame) occluder[index.parts.user_triangle(t, scene.triangle_count())] = 1;  // inserted
    }
  }
  for (const auto& c : s.box_candidates) {
    bool inserted = false;
    for (const Aabb& b : s.box_occluders) inserted = inserted || (b.min == index.bounds[c.second].min && b.max == index.bounds[c.second].max);
    if (!inserted) continue;
    const MeshObject& r = map.objects[c.second];
    for (std::uint32_t t = r.first_triangle; t < r.first_triangle + r.triangle_count; ++t) occluder[t] = 1;
  }
  return occluder;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  // argv[2] (optional): another scene, "city", "office" or a file name in the scenes folder.
  const std::string wanted = argc > 2 ? argv[2] : "oacmpdm9.obj";
  support::Scene scene;
  std::string name = "office";
  bool loaded = false;
  for (const auto& f : support::real_scene_files()) {
    if (f != wanted) continue;
    if (auto s = support::load_obj(support::scenes_dir() + "/" + f)) {
      scene = std::move(*s);
      name = f;
      loaded = true;
    }
  }
  if (!loaded && wanted == "city") {
    scene = support::make_city(1, 8);
    name = "city";
  } else if (!loaded) {
    scene = support::make_office(1, 10, 8);
  }
  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const ObjectMap map(scene);
  const MeshOcclusionCuller<glm::vec3> culler(scene.mesh(), map.objects.data(), map.objects.size());

  const int w = 640, h = 360;
  const WalkSpec spec = walk_spec(name, scene, embree, 7);
  const auto cams = walk(spec, scene, embree, 24, 3, w, h, 8);
  // The walk camera whose culler hides the most objects in its frustum.
  std::vector<std::uint32_t> kept;
  std::size_t best = 0, best_hidden = 0;
  MeshOcclusionContext context;
  for (std::size_t i = 0; i < cams.size(); ++i) {
    culler.cull(cams[i], context, kept);
    const std::size_t hidden = context.stats().objects_hidden;
    if (i == 0 || hidden > best_hidden) best = i, best_hidden = hidden;
  }
  if (cams.empty()) {
    std::fprintf(stderr, "no camera could be placed in %s\n", name.c_str());
    return 1;
  }
  const Camera& cam = cams[best];
  culler.cull(cam, context, kept);
  std::vector<Fate> fate(scene.objects.size(), Fate::outside);
  for (std::uint32_t o : frustum_objects(scene, cam)) fate[o] = Fate::hidden;
  for (std::uint32_t o : kept) fate[o] = Fate::kept;

  RaySet rays;
  const auto seen = truly_visible(embree, map, cam, rays);
  std::size_t counts[3] = {0, 0, 0}, visible = 0, false_culls = 0;
  for (std::size_t o = 0; o < fate.size(); ++o) {
    ++counts[static_cast<int>(fate[o])];
    visible += seen[o] != 0;
    false_culls += seen[o] && fate[o] != Fate::kept;
  }
  const std::vector<std::uint8_t> occluder = occluders_of(scene, map, cam);
  const support::Image top =
      top_down(scene, map, fate, occluder, cam, cam.eye.y + 0.5f * spec.eye_height, 40.0f * spec.step);
  const support::Image front = view(scene, map, fate, embree, cam);
  const bool ok = top.write_png(dir + "/mesh_occlusion_topdown.png") && front.write_png(dir + "/mesh_occlusion_view.png");
  std::printf("%s, walk camera %zu (eye %.1f %.1f %.1f): %zu objects kept, %zu hidden by occlusion, %zu outside "
              "the frustum; %zu truly visible, %zu of them left out\n",
              name.c_str(), best, cam.eye.x, cam.eye.y, cam.eye.z, counts[2], counts[1], counts[0], visible, false_culls);
  std::printf("%s %s/mesh_occlusion_topdown.png and %s/mesh_occlusion_view.png\n", ok ? "wrote" : "could not write",
              dir.c_str(), dir.c_str());
  return ok && false_culls == 0 ? 0 : 1;
}
