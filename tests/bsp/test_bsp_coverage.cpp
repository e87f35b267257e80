// Every triangle covered exactly once by its fragments (bsp_coverage.hpp): on generated scenes made
// to stress the on-plane tolerance (small triangles far from the origin, slivers, fans of nearly
// coplanar triangles, meshes scaled by 1e-3 and 1e3) and on every triangle of every real scene in
// ../shared/scenes (the two largest only in optimized builds without sanitizers). stats() must
// account for every input triangle. Prints one row per scene (the table of docs/bsp.md).
// Arguments: scene names (generated or real file names) to run only those.
// Mutants: a fragment stored twice and the smallest piece of a cut dropped must each fail here.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <cullkit/bsp_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "bsp_coverage.hpp"
#include "bsp_oracle.hpp"
#include "check.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define BSP_SLOW_BUILD 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BSP_SLOW_BUILD 1
#endif
#endif
#if !defined(BSP_SLOW_BUILD) && !defined(__OPTIMIZE__)
#define BSP_SLOW_BUILD 1
#endif
#ifndef BSP_SLOW_BUILD
#define BSP_SLOW_BUILD 0
#endif

namespace {

using cullkit::support::Scene;
using Tree = cullkit::BspTree<glm::vec3>;

void check_scene(const Scene& scene) {
  const Tree tree(scene.mesh());
  const auto cov = bsp_test::check_coverage(scene, tree, true);
  const auto& s = tree.stats();
  const std::size_t kept = s.triangles - s.dropped_bad_index - s.dropped_non_finite - s.dropped_degenerate;
  std::printf("| %s | %zu | %zu | %zu | %zu | %.2f | %zu | %zu | %zu | %zu | %zu | %.1e | %.2f |\n",
              scene.name.c_str(), s.triangles, cov.usable, s.dropped_degenerate, s.fragments,
              double(s.fragments) / double(kept > 0 ? kept : 1), cov.no_fragment, cov.under, cov.over,
              cov.uv_mismatch, cov.float_rounding, cov.worst_uv, s.seconds);
  std::fflush(stdout);
  CHECK_MSG(cov.wrong() == 0, "%s: %zu of %zu usable triangles not covered exactly (worst in (u, v): triangle %zu, off by %.3g)",
            scene.name.c_str(), cov.wrong(), cov.usable, cov.worst_triangle, cov.worst_uv);
  CHECK_MSG(cov.accounted == s.triangles, "%s: stats account for %zu of %zu triangles", scene.name.c_str(),
            cov.accounted, s.triangles);
  CHECK_MSG(s.fragments == tree.fragments().size(), "%s: stats().fragments", scene.name.c_str());
  CHECK_MSG(BSP_SLOW_BUILD || scene.triangle_count() > 100000 || tree.validate(), "%s: validate", scene.name.c_str());
}

bool wanted(const std::vector<std::string>& only, const std::string& name) {
  if (only.empty()) return true;
  for (const auto& o : only)
    if (o == name) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> only(argv + 1, argv + argc);
  std::printf("| scene | triangles | usable | dropped | fragments | per kept triangle | no fragment | short | over "
              "| (u, v) off | within float rounding | worst (u, v) | build s |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<Scene> generated;
  generated.push_back(bsp_test::small_far_cloud(1, 3000));
  generated.back().name = "small_far";
  generated.push_back(bsp_test::sliver_soup(2, 600));
  generated.back().name = "slivers";
  generated.push_back(bsp_test::near_coplanar_fans(3, 40, 24, 1e-4f));
  generated.back().name = "fans_1e-4";
  generated.push_back(bsp_test::near_coplanar_fans(4, 40, 24, 1e-6f));
  generated.back().name = "fans_1e-6";
  const Scene office = cullkit::support::make_office(1, 3, 2);
  const Scene soup = bsp_test::random_soup(5, 400, 3.0f, 2.0f);
  generated.push_back(bsp_test::scaled(office, 1e-3f, "office_x1e-3"));
  generated.push_back(bsp_test::scaled(office, 1e3f, "office_x1e3"));
  generated.push_back(bsp_test::scaled(soup, 1e-3f, "soup_x1e-3"));
  generated.push_back(bsp_test::scaled(soup, 1e3f, "soup_x1e3"));
  generated.push_back(bsp_test::scaled(generated[0], 1e-3f, "small_far_x1e-3"));
  for (const Scene& s : generated)
    if (wanted(only, s.name)) check_scene(s);
  for (const std::string& file : cullkit::support::real_scene_files()) {
    if (!wanted(only, file)) continue;
    auto scene = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + file);
    if (!scene) continue;
    if (BSP_SLOW_BUILD && scene->triangle_count() > 100000) {
      std::printf("| %s | %zu | skipped in this build (sanitizers or no optimization) |\n", file.c_str(),
                  scene->triangle_count());
      continue;
    }
    scene->name = file;
    check_scene(*scene);
  }
  if (cullkit::support::scenes_dir().empty()) std::printf("no real scenes (../shared/scenes): generated only\n");
  return cullkit_test::report("test_bsp_coverage");
}
