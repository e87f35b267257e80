// NormalClassIndex against Embree: every triangle Embree sees first at some pixel centre must be in
// the selected set, except explicit ties (the set holds a triangle our own test hits at that pixel
// at the same distance within 1e-5 relative: a shared edge or a coplanar overlap). Generated city
// and office scenes and the real scenes when present, many cameras (outside, inside the scene box,
// axis-aligned views whose rays run nearly parallel to the slices), several class/grid settings,
// and one thread against many (identical answers).
#include <algorithm>
#include <cstdio>
#include <string>

#include <embree_oracle.hpp>

#include "check.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

struct Totals {
  std::size_t tested = 0, visible = 0, ties = 0, misses = 0, cameras = 0;
};

void run_scene(const std::string& label, const Scene& scene, const std::vector<NciParams>& settings, int cameras,
               int width, int height, std::uint64_t seed) {
  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const auto cams = nci_test::cameras_for(scene.bounds, cameras, width, height, seed);
  std::vector<oracle::HitBuffer> truth;
  for (const auto& cam : cams) truth.push_back(embree.render(cam, 2));
  for (const NciParams& base : settings) {
    NciParams one = base, many = base;
    one.threads = 1;
    many.threads = 3;
    const nci_test::TestIndex<glm::vec3> index(scene.mesh(), one);
    const nci_test::TestIndex<glm::vec3> index_many(scene.mesh(), many);
    Totals tot;
    NciContext ctx;
    for (std::size_t ci = 0; ci < cams.size(); ++ci) {
      const Camera& cam = cams[ci];
      VisibleSet set;
      NciPixels px;
      index.select_visible(cam, ctx, set, &px);
      const VisibleSet set_many = index_many.select_visible(cam);
      CHECK_MSG(set.triangles == set_many.triangles && set.triangles_tested == set_many.triangles_tested,
                "%s classes %d grid %d cam %zu: 1 thread and 3 threads disagree (seed %llu)", label.c_str(),
                base.classes, base.grid, ci, static_cast<unsigned long long>(seed));
      const auto& hits = truth[ci];
      const auto visible = oracle::visible_triangles(hits);
      std::size_t misses = 0;
      for (int y = 0; y < hits.height; ++y) {
        for (int x = 0; x < hits.width; ++x) {
          const std::uint32_t want = hits.at(x, y);
          if (want == oracle::HitBuffer::miss) continue;
          if (std::binary_search(set.triangles.begin(), set.triangles.end(), want)) continue;
          const std::size_t p = static_cast<std::size_t>(y) * hits.width + x;
          const std::uint32_t have = px.triangle[p];
          float t = 0;
          const float te = hits.distance[p];
          if (have != NciPixels::miss && nci_test::own_hit(scene, cam, have, x, y, t) &&
              std::fabs(t - te) <= 1e-5f * std::max(1.0f, te)) {
            ++tot.ties;
            continue;
          }
          if (++misses <= 3)
            std::fprintf(stderr,
                         "  MISS %s classes %d grid %d cam %zu pixel (%d,%d): embree %u t=%g, ours %u t=%g "
                         "(seed %llu)\n",
                         label.c_str(), base.classes, base.grid, ci, x, y, want, double(te), have,
                         double(px.depth[p]), static_cast<unsigned long long>(seed));
        }
      }
      CHECK_MSG(misses == 0, "%s classes %d grid %d cam %zu: %zu pixels miss", label.c_str(), base.classes,
                base.grid, ci, misses);
      tot.misses += misses;
      tot.tested += set.triangles_tested;
      tot.visible += visible.size();
      ++tot.cameras;
    }
    std::printf("%-22s %8zu tris  classes %4d grid %4d: %zu cameras, tested/visible %.2f, ties %zu, misses %zu\n",
                label.c_str(), scene.triangle_count(), base.classes, base.grid, tot.cameras,
                tot.visible ? double(tot.tested) / double(tot.visible) : 0.0, tot.ties, tot.misses);
  }
}

NciParams params(int classes, int grid) {
  NciParams p;
  p.classes = classes;
  p.grid = grid;
  return p;
}

}  // namespace

int main() {
  const int W = NCI_SANITIZED ? 80 : 160, H = NCI_SANITIZED ? 60 : 120;
  run_scene("city", support::make_city(21, 4), {params(32, 64), params(128, 32), params(512, 128)}, 15, W, H, 201);
  run_scene("office", support::make_office(22, 3, 3), {params(32, 64), params(8, 200)}, 15, W, H, 202);
  nci_test::for_each_real_scene([&](const std::string& file, const Scene& scene) {
    run_scene(file, scene, {params(32, 64)}, NCI_SANITIZED ? 3 : 6, W, H, 203);
  });
  return cullkit_test::report("test_nci_embree");
}
