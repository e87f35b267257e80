// nci_picture: what the NormalClassIndex selects, next to Embree's ground truth. For one camera on
// a real scene (fzk_haus.obj when present, else a generated city), writes nci_picture.png into
// argv[1] with four panels: Embree's first-hit triangles | ours (per-pixel first hits, coloured by
// triangle id; a pixel Embree sees whose triangle is missing from our set would be pure red),
// ours coloured by normal class | heat map of triangles tested per tile.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <cullkit/normal_class_index.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

using namespace cullkit;

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  support::Scene scene;
  std::string name = "generated city";
  bool loaded = false;
  for (const auto& f : support::real_scene_files()) {
    if (f != "fzk_haus.obj") continue;
    if (auto s = support::load_obj(support::scenes_dir() + "/" + f)) {
      scene = std::move(*s);
      name = f;
      loaded = true;
    }
  }
  if (!loaded) scene = support::make_city(5, 6);
  const int w = 480, h = 360;
  const Aabb b = scene.bounds;
  const glm::vec3 c = b.center(), e = b.extent();
  const Camera cam = support::make_camera(c + glm::vec3(0.9f, 0.45f, 0.75f) * glm::length(e) * 0.55f,
                                          c - glm::vec3(0, 0.1f, 0) * e.y, 55, w, h, 0.1f, 0.0f);

  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const oracle::HitBuffer truth = embree.render(cam);

  NciParams params;
  params.tile_size = 16;
  const NormalClassIndex<glm::vec3> index(scene.mesh(), params);
  NciContext ctx;
  VisibleSet set;
  NciPixels px;
  index.select_visible(cam, ctx, set, &px);

  support::Image embree_img(w, h, {20, 20, 30}), ours(w, h, {20, 20, 30}), classes(w, h, {20, 20, 30}),
      heat(w, h, {0, 0, 0});
  std::size_t missing = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      const std::uint32_t want = truth.triangle[p], have = px.triangle[p];
      if (want != oracle::HitBuffer::miss) {
        embree_img.set(x, y, support::id_color(want));
        // Missing and not a tie (a shared edge or coplanar overlap at the same distance).
        if (!std::binary_search(set.triangles.begin(), set.triangles.end(), want) &&
            !(have != NciPixels::miss && std::fabs(px.depth[p] - truth.distance[p]) <= 1e-5f * std::max(1.0f, truth.distance[p]))) {
          ++missing;
          ours.set(x, y, {255, 0, 0});
          continue;
        }
      }
      if (have != NciPixels::miss) {
        ours.set(x, y, support::id_color(have));
        classes.set(x, y, support::id_color(static_cast<std::uint32_t>(index.triangle_class(have)) * 7919u + 13u));
      }
    }
  }
  std::uint32_t most = 1;
  for (auto n : ctx.tile_tested) most = std::max(most, n);
  const int tile = ctx.tile_size;
  for (std::size_t t = 0; t < ctx.tile_tested.size(); ++t) {
    const int tx = static_cast<int>(t % static_cast<std::size_t>(ctx.tiles_x)), ty = static_cast<int>(t / static_cast<std::size_t>(ctx.tiles_x));
    heat.fill_rect(tx * tile, ty * tile, std::min(w, (tx + 1) * tile) - 1, std::min(h, (ty + 1) * tile) - 1,
                   support::heat_color(static_cast<float>(ctx.tile_tested[t]) / static_cast<float>(most)));
  }
  support::Image all(2 * w + 4, 2 * h + 4, {255, 255, 255});
  all.paste(embree_img, 0, 0);
  all.paste(ours, w + 4, 0);
  all.paste(classes, 0, h + 4);
  all.paste(heat, w + 4, h + 4);
  const std::string path = dir + "/nci_picture.png";
  const bool ok = all.write_png(path);
  // Precision: distinct triangles tested over those Embree sees first.
  const std::size_t truly_visible = oracle::visible_triangles(truth).size();
  std::printf("%s: %zu triangles, %zu classes; camera %dx%d: %zu selected (Embree sees %zu), %zu tested (%.2f per "
              "triangle Embree sees), max %u per tile, %zu pixels missing; %s %s\n",
              name.c_str(), scene.triangle_count(), index.class_count(), w, h, set.triangles.size(), truly_visible,
              set.triangles_tested, double(set.triangles_tested) / double(std::max<std::size_t>(1, truly_visible)),
              most, missing, ok ? "wrote" : "could not write", path.c_str());
  return ok && missing == 0 ? 0 : 1;
}
