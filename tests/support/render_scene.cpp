// render_scene: pictures of a scene for eyeballing the generators and loader.
//   render_scene <city|office|forest|path/to/file.obj> <output prefix> [seed]
// Writes <prefix>_view.png (Embree first hits coloured by object, shaded by facing) and
// <prefix>_map.png (top-down map of object bounds with the camera's view edges).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

using namespace cullkit;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s <city|office|forest|file.obj> <output prefix> [seed]\n", argv[0]);
    return 2;
  }
  const std::string what = argv[1], prefix = argv[2];
  const std::uint32_t seed = argc > 3 ? static_cast<std::uint32_t>(std::strtoul(argv[3], nullptr, 10)) : 1u;
  support::Scene scene;
  if (what == "city") scene = support::make_city(seed, 8);
  else if (what == "office") scene = support::make_office(seed, 10, 8);
  else if (what == "forest") scene = support::make_forest(seed, 64, 400);
  else {
    support::ObjLoadStats stats;
    auto loaded = support::load_obj(what, &stats);
    if (!loaded) {
      std::fprintf(stderr, "cannot load %s\n", what.c_str());
      return 1;
    }
    scene = std::move(*loaded);
    std::printf("%s: %zu faces, %zu skipped\n", what.c_str(), stats.faces, stats.skipped_faces);
  }
  if (scene.objects.empty()) {
    std::fprintf(stderr, "empty scene\n");
    return 1;
  }
  const Aabb b = scene.bounds;
  const glm::vec3 c = b.center(), e = b.extent();
  const float r = 0.5f * glm::length(e);
  // Looking at the centre from a raised corner, as far as the scene's size.
  const glm::vec3 eye = c + glm::vec3(-0.9f * r, 0.6f * r, -0.9f * r);
  const Camera cam = support::make_camera(eye, c, 55, 800, 600, 0.01f * r, 0.0f);
  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const oracle::HitBuffer hits = embree.render(cam);
  std::vector<std::uint32_t> owner(scene.triangle_count(), 0);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
    for (std::uint32_t t = 0; t < scene.objects[o].triangle_count; ++t) owner[scene.objects[o].first_triangle + t] = o;
  support::Image view(cam.width, cam.height, {235, 240, 250});
  const PixelRays rays(cam);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const std::uint32_t t = hits.at(x, y);
      if (t == oracle::HitBuffer::miss) continue;
      const glm::vec3 p0 = scene.positions[scene.indices[3 * t]], p1 = scene.positions[scene.indices[3 * t + 1]],
                      p2 = scene.positions[scene.indices[3 * t + 2]];
      const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
      const float shade = 0.35f + 0.65f * std::fabs(glm::dot(n, rays.ray(x, y).direction));
      const support::Rgb base = support::id_color(owner[t]);
      view.set(x, y, {static_cast<std::uint8_t>(base.r * shade), static_cast<std::uint8_t>(base.g * shade),
                      static_cast<std::uint8_t>(base.b * shade)});
    }
  support::TopDownMap map(b, 800);
  for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
    map.box(scene.objects[o].bounds, support::id_color(o), scene.objects[o].major_occluder ? 0.9f : 0.5f);
  }
  map.camera(cam, 2.0f * r, {200, 0, 0});
  const bool ok = view.write_png(prefix + "_view.png") && map.image().write_png(prefix + "_map.png");
  std::printf("%s: %zu triangles, %zu objects, %zu visible triangles; %s\n", scene.name.c_str(), scene.triangle_count(),
              scene.objects.size(), oracle::visible_triangles(hits).size(), ok ? "pictures written" : "PNG failed");
  return ok ? 0 : 1;
}
