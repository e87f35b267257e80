// The proof by a real renderer: Mesa's OpenGL rasterizer (llvmpipe through headless OSMesa) draws a
// triangle-ID image twice, (a) the triangles with the depth test on and (b) the BSP fragments in
// back_to_front order with the depth test off, and the two must agree at every pixel except
//  * pixel centres on a triangle edge: the nearest triangle differs between rays offset by
//    kEdgeOffset pixels around the centre (the rasterizer snaps vertices to its sub-pixel grid, and
//    float rounding of cut corners moves fragment edges by that little), and
//  * coplanar ties: the two nearest surfaces along the centre's ray lie within kTieDepth of each
//    other in window depth (coplanar overlaps, interpenetration lines, and what a 24-bit depth
//    buffer cannot tell apart).
// A third, found on real scenes: a pixel centre within kEdgeOffset of a cut inside a triangle
// (see cut_edge). Each exception is counted and printed. The first two are decided by a
// double-precision ray cast over the triangles, the third by projecting the fragments. Every scene
// is drawn with back faces kept and with back faces culled (the order must serve both).
// Scenes: cyclically overlapping and interpenetrating triangles, a random interpenetrating soup, a
// generated office, and a chunk (the triangles nearest a point) of each real scene, from eyes inside
// and outside. Mutants: painting the fragments front to back, and in centroid-sorted order, must
// leave unexcused pixels, so the comparison can fail.
#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <cullkit/bsp_tree.hpp>
#include <cullkit/depth_sort.hpp>
#include <cullkit_support/scene.hpp>

#include "bsp_oracle.hpp"
#include "check.hpp"

namespace {

using cullkit::support::Scene;
using Tree = cullkit::BspTree<glm::vec3>;

constexpr int kWidth = 192, kHeight = 144;
constexpr double kEdgeOffset = 1.0 / 32.0;  // pixels
constexpr double kTieDepth = 4e-6;          // window depth in [0, 1]

struct View {
  glm::vec3 eye;
  glm::mat4 view_proj;  // of positions relative to the eye (p - eye, taken in double): exact far from the origin
};

// Immediate-mode drawing of triangle ids (id + 1 in RGB; 0 is the background).
void set_id_color(std::uint32_t id) {
  const std::uint32_t c = id + 1;
  glColor3ub(GLubyte(c & 0xFF), GLubyte((c >> 8) & 0xFF), GLubyte((c >> 16) & 0xFF));
}

void begin_frame(const View& v, bool cull, bool depth_test) {
  glViewport(0, 0, kWidth, kHeight);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixf(&v.view_proj[0][0]);
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glDisable(GL_DITHER);
  glDisable(GL_LIGHTING);
  glDisable(GL_BLEND);
  glShadeModel(GL_FLAT);
  glFrontFace(GL_CCW);
  if (cull) {
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }
  if (depth_test) {
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
  } else {
    glDisable(GL_DEPTH_TEST);
  }
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

std::vector<std::uint32_t> read_ids(const std::vector<std::uint8_t>& rgba) {
  glFinish();
  std::vector<std::uint32_t> ids(std::size_t(kWidth) * kHeight);
  for (std::size_t i = 0; i < ids.size(); ++i)
    ids[i] = std::uint32_t(rgba[4 * i]) | (std::uint32_t(rgba[4 * i + 1]) << 8) | (std::uint32_t(rgba[4 * i + 2]) << 16);
  return ids;
}

std::vector<std::uint32_t> draw_depth_tested(const Scene& s, const View& v, bool cull, const std::vector<std::uint8_t>& buf) {
  begin_frame(v, cull, true);
  glBegin(GL_TRIANGLES);
  for (std::size_t t = 0; t < s.triangle_count(); ++t) {
    set_id_color(static_cast<std::uint32_t>(t));
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 p = glm::dvec3(s.positions[s.indices[3 * t + std::size_t(k)]]) - glm::dvec3(v.eye);
      glVertex3d(p.x, p.y, p.z);
    }
  }
  glEnd();
  return read_ids(buf);
}

std::vector<std::uint32_t> draw_in_order(const Tree& tree, const std::vector<std::uint32_t>& order, const View& v,
                                         bool cull, const std::vector<std::uint8_t>& buf) {
  begin_frame(v, cull, false);
  for (std::uint32_t f : order) {
    const auto& fr = tree.fragments()[f];
    set_id_color(fr.triangle);
    glBegin(GL_TRIANGLE_FAN);
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) {
      const glm::dvec3 p = glm::dvec3(tree.corners()[fr.first_corner + i]) - glm::dvec3(v.eye);
      glVertex3d(p.x, p.y, p.z);
    }
    glEnd();
  }
  return read_ids(buf);
}

// The ray oracle in double. Pixel (x, row) has row 0 at the bottom (OSMesa's default).
class RayOracle {
 public:
  RayOracle(const Scene& s, const View& v) : scene_(s), vp_(v.view_proj), inv_(glm::inverse(glm::dmat4(v.view_proj))), eye_(v.eye) {}

  struct Hit {
    double window_depth;
    std::uint32_t triangle;
  };
  // Hits of the ray through (px, py) in pixel units (centre of pixel x is x + 0.5), nearest first,
  // beyond the near plane; front faces only when `cull`.
  std::vector<Hit> hits(double px, double py, bool cull) const {
    const glm::dvec4 far_h = inv_ * glm::dvec4(2.0 * px / kWidth - 1.0, 2.0 * py / kHeight - 1.0, 1.0, 1.0);
    const glm::dvec3 dir = glm::dvec3(far_h) / far_h.w;  // the view's frame has the eye at its origin
    std::vector<Hit> out;
    for (std::size_t t = 0; t < scene_.triangle_count(); ++t) {
      const glm::dvec3 a(scene_.positions[scene_.indices[3 * t]]), b(scene_.positions[scene_.indices[3 * t + 1]]),
          c(scene_.positions[scene_.indices[3 * t + 2]]);
      const glm::dvec3 e1 = b - a, e2 = c - a, n = glm::cross(e1, e2);
      if (cull && !(glm::dot(n, eye_ - a) > 0)) continue;
      const glm::dvec3 pv = glm::cross(dir, e2);
      const double det = glm::dot(e1, pv);
      if (det == 0) continue;
      const glm::dvec3 tv = eye_ - a;
      const double u = glm::dot(tv, pv) / det;
      const glm::dvec3 qv = glm::cross(tv, e1);
      const double w = glm::dot(dir, qv) / det;
      const double t_hit = glm::dot(e2, qv) / det;
      if (u < 0 || w < 0 || u + w > 1 || !(t_hit > 0)) continue;
      const glm::dvec4 clip = glm::dmat4(vp_) * glm::dvec4(dir * t_hit, 1.0);
      const double z = clip.z / clip.w;
      if (!(clip.w > 0) || z < -1 || z > 1) continue;  // clipped by the near or far plane
      out.push_back({0.5 * z + 0.5, static_cast<std::uint32_t>(t)});
    }
    std::sort(out.begin(), out.end(), [](const Hit& p, const Hit& q) { return p.window_depth < q.window_depth; });
    return out;
  }
  // The id the depth-tested image should show (0: background).
  std::uint32_t nearest_id(double px, double py, bool cull) const {
    const auto h = hits(px, py, cull);
    return h.empty() ? 0 : h[0].triangle + 1;
  }
  enum class Verdict { edge, tie, clear };  // clear: neither, so the pixel has one right id
  Verdict explain(int x, int row, bool cull) const {
    const double cx = x + 0.5, cy = row + 0.5;
    const std::uint32_t id = nearest_id(cx, cy, cull);
    const double o[4][2] = {{kEdgeOffset, 0}, {-kEdgeOffset, 0}, {0, kEdgeOffset}, {0, -kEdgeOffset}};
    for (const auto& d : o)
      if (nearest_id(cx + d[0], cy + d[1], cull) != id) return Verdict::edge;
    const auto h = hits(cx, cy, cull);
    if (h.size() >= 2 && h[1].window_depth - h[0].window_depth < kTieDepth) return Verdict::tie;
    return Verdict::clear;
  }

 private:
  const Scene& scene_;
  glm::mat4 vp_;
  glm::dmat4 inv_;
  glm::dvec3 eye_;
};

struct Compare {
  std::size_t differing = 0, edge = 0, tie = 0, cut_edge = 0, wrong = 0, examined = 0;
};

// True when the centre of pixel (x, row) lies within kEdgeOffset pixels of an edge of a fragment of
// either triangle (ids are triangle + 1). Cuts leave T-junctions inside a triangle (a later cut adds
// a corner on one side of an earlier cut only); its rounded corner lets a pixel centre lying exactly
// on the cut fall between the fragments.
bool cut_edge(const Tree& tree, std::uint32_t id_a, std::uint32_t id_b, int x, int row, const View& v) {
  const glm::dvec2 centre(x + 0.5, row + 0.5);
  const glm::dmat4 m(v.view_proj);
  for (const auto& fr : tree.fragments()) {
    if (fr.triangle + 1 != id_a && fr.triangle + 1 != id_b) continue;
    glm::dvec2 w[64];
    const std::uint32_t n = std::min<std::uint32_t>(fr.corner_count, 64);
    bool visible = true;
    for (std::uint32_t i = 0; i < n; ++i) {
      const glm::dvec4 q = m * glm::dvec4(glm::dvec3(tree.corners()[fr.first_corner + i]) - glm::dvec3(v.eye), 1.0);
      visible = visible && q.w > 0;
      w[i] = glm::dvec2((q.x / q.w * 0.5 + 0.5) * kWidth, (q.y / q.w * 0.5 + 0.5) * kHeight);
    }
    if (!visible) continue;
    for (std::uint32_t i = 0; i < n; ++i) {
      const glm::dvec2 a = w[i], b = w[(i + 1) % n], e = b - a;
      const double len2 = glm::dot(e, e);
      const double t = len2 > 0 ? std::clamp(glm::dot(centre - a, e) / len2, 0.0, 1.0) : 0.0;
      if (glm::length(a + e * t - centre) < kEdgeOffset) return true;
    }
  }
  return false;
}

Compare compare(const std::vector<std::uint32_t>& truth, const std::vector<std::uint32_t>& painted,
                const RayOracle& oracle, const Tree& tree, const View& v, bool cull, std::size_t max_examined) {
  Compare c;
  for (int row = 0; row < kHeight; ++row) {
    for (int x = 0; x < kWidth; ++x) {
      const std::size_t i = std::size_t(row) * kWidth + std::size_t(x);
      if (truth[i] == painted[i]) continue;
      ++c.differing;
      if (c.examined >= max_examined) continue;
      ++c.examined;
      switch (oracle.explain(x, row, cull)) {
        case RayOracle::Verdict::edge: ++c.edge; break;
        case RayOracle::Verdict::tie: ++c.tie; break;
        case RayOracle::Verdict::clear:
          if (cut_edge(tree, truth[i], painted[i], x, row, v)) {
            ++c.cut_edge;
          } else if (++c.wrong <= 3 && max_examined > 1000000) {
            std::fprintf(stderr, "    pixel (%d, %d from the bottom): depth-tested %u, painted %u\n", x, row, truth[i],
                         painted[i]);
          }
          break;
      }
    }
  }
  return c;
}

std::vector<std::uint32_t> centroid_order(const Tree& tree, const glm::vec3& eye) {
  std::vector<float> depth(tree.fragments().size());
  for (std::size_t f = 0; f < depth.size(); ++f) {
    const auto& fr = tree.fragments()[f];
    glm::vec3 c(0.0f);
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) c += tree.corners()[fr.first_corner + i];
    depth[f] = glm::length(c / float(fr.corner_count) - eye);
  }
  std::vector<std::uint32_t> order;
  cullkit::order_back_to_front(depth.data(), depth.size(), order);
  return order;
}

struct Totals {
  std::size_t pixels_compared = 0, covered = 0, differing = 0, edge = 0, tie = 0, cut_edge = 0;
  std::size_t mutant_wrong = 0, centroid_wrong = 0, oracle_agree = 0, oracle_sampled = 0;
};

View make_view(const glm::vec3& eye, const glm::vec3& target, float near_plane, float far_plane) {
  const glm::vec3 dir = glm::normalize(target - eye);
  const glm::vec3 up = std::fabs(dir.y) > 0.95f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const glm::mat4 proj = glm::perspectiveRH_NO(glm::radians(70.0f), float(kWidth) / float(kHeight), near_plane, far_plane);
  return View{eye, proj * glm::lookAtRH(glm::vec3(0.0f), target - eye, up)};
}

void check_scene(const std::string& name, const Scene& scene, const std::vector<View>& views,
                 const std::vector<std::uint8_t>& buf, Totals& totals) {
  const Tree tree(scene.mesh());
  CHECK_MSG(tree.validate(), "%s: validate", name.c_str());
  std::vector<std::uint32_t> order;
  for (std::size_t vi = 0; vi < views.size(); ++vi) {
    const View& v = views[vi];
    const RayOracle oracle(scene, v);
    tree.back_to_front(v.eye, order);
    for (int cull = 0; cull < 2; ++cull) {
      const auto truth = draw_depth_tested(scene, v, cull != 0, buf);
      const auto painted = draw_in_order(tree, order, v, cull != 0, buf);
      const Compare c = compare(truth, painted, oracle, tree, v, cull != 0, ~std::size_t(0) >> 1);
      CHECK_MSG(c.wrong == 0, "%s view %zu cull %d: %zu unexcused pixels (%zu differ: %zu on edges, %zu ties, %zu on cuts)",
                name.c_str(), vi, cull, c.wrong, c.differing, c.edge, c.tie, c.cut_edge);
      totals.pixels_compared += truth.size();
      totals.differing += c.differing;
      totals.edge += c.edge;
      totals.tie += c.tie;
      totals.cut_edge += c.cut_edge;
      for (std::uint32_t id : truth) totals.covered += id != 0;
      // The oracle sees what Mesa draws (else its excuses would mean nothing): sampled pixels.
      for (int k = 0; k < 40; ++k) {
        const int x = (k * 37 + int(vi) * 11) % kWidth, row = (k * 53 + cull * 7) % kHeight;
        if (oracle.explain(x, row, cull != 0) != RayOracle::Verdict::clear) continue;  // edge or tie: either is fine
        ++totals.oracle_sampled;
        totals.oracle_agree += oracle.nearest_id(x + 0.5, row + 0.5, cull != 0) == truth[std::size_t(row) * kWidth + std::size_t(x)];
      }
      // Mutants: front to back, and a centroid depth sort, painted the same way.
      std::vector<std::uint32_t> reversed(order.rbegin(), order.rend());
      totals.mutant_wrong += compare(truth, draw_in_order(tree, reversed, v, cull != 0, buf), oracle, tree, v, cull != 0, 200).wrong;
      totals.centroid_wrong +=
          compare(truth, draw_in_order(tree, centroid_order(tree, v.eye), v, cull != 0, buf), oracle, tree, v,
                  cull != 0, 200).wrong;
    }
  }
  std::printf("%s: %zu triangles, %zu fragments, %zu views\n", name.c_str(), scene.triangle_count(),
              tree.fragments().size(), views.size());
}

// The `count` triangles whose centroids are nearest `centre` (a compact chunk of a big scene).
Scene chunk(const Scene& s, const glm::vec3& centre, std::size_t count) {
  std::vector<std::pair<float, std::uint32_t>> d(s.triangle_count());
  for (std::size_t t = 0; t < d.size(); ++t) {
    const glm::vec3 c =
        (s.positions[s.indices[3 * t]] + s.positions[s.indices[3 * t + 1]] + s.positions[s.indices[3 * t + 2]]) / 3.0f;
    d[t] = {glm::length(c - centre), static_cast<std::uint32_t>(t)};
  }
  count = std::min(count, d.size());
  std::partial_sort(d.begin(), d.begin() + std::ptrdiff_t(count), d.end());
  std::sort(d.begin(), d.begin() + std::ptrdiff_t(count),
            [](const auto& a, const auto& b) { return a.second < b.second; });  // keep the input order
  std::vector<glm::vec3> corners;
  for (std::size_t i = 0; i < count; ++i)
    for (int k = 0; k < 3; ++k) corners.push_back(s.positions[s.indices[3 * std::size_t(d[i].second) + std::size_t(k)]]);
  Scene out;
  out.add_triangles(corners, s.name);
  return out;
}

// Views of a scene: one eye inside its box, looking across it, and two outside; with `on_mesh`,
// three more from eyes on the mesh (a triangle's corner, an edge's midpoint, a point in its plane)
// looking at the centre.
std::vector<View> views_of(const Scene& s, bool on_mesh = false) {
  const glm::vec3 lo = s.bounds.min, hi = s.bounds.max, c = (lo + hi) * 0.5f, size = hi - lo;
  const float diag = glm::length(size);
  std::vector<View> views = {
      make_view(c + size * glm::vec3(0.13f, 0.07f, -0.11f), c + size * glm::vec3(-0.4f, -0.1f, 0.3f), diag * 0.002f, diag * 3),
      make_view(c + size * glm::vec3(1.1f, 0.6f, 0.9f), c, diag * 0.05f, diag * 4),
      make_view(c + size * glm::vec3(-0.7f, -0.4f, -1.2f), c, diag * 0.05f, diag * 4)};
  if (on_mesh)
    for (const glm::vec3& eye : bsp_test::eyes_on_mesh(s, s.triangle_count() / 2))
      if (glm::length(c - eye) > diag * 0.01f) views.push_back(make_view(eye, c, diag * 0.002f, diag * 3));
  return views;
}

}  // namespace

int main() {
  std::vector<std::uint8_t> buf(std::size_t(kWidth) * kHeight * 4);
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!ctx || !OSMesaMakeCurrent(ctx, buf.data(), GL_UNSIGNED_BYTE, kWidth, kHeight)) {
    std::printf("test_bsp_osmesa: could not create an OSMesa context\n");
    return 1;
  }
  std::printf("renderer: %s\n", reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  Totals totals;
  {
    const Scene cyclic = bsp_test::cyclic_scene();
    check_scene("cyclic", cyclic,
                {make_view({0.2f, 6, 0.4f}, {0, 0.5f, 0}, 0.1f, 50), make_view({0.1f, 0.55f, 0.1f}, {3, 0.3f, 2}, 0.01f, 50),
                 make_view({4, 3, 6}, {4, 0.5f, 4}, 0.1f, 50), make_view({0, -5, 0.3f}, {0, 0.5f, 0}, 0.1f, 50)},
                buf, totals);
  }
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const Scene soup = bsp_test::random_soup(seed, 150, 4.0f, 2.0f);
    check_scene("soup", soup, {make_view({0.3f, 0.2f, 0.1f}, {3, 1, 2}, 0.01f, 50), make_view({14, 6, 9}, {0, 0, 0}, 0.5f, 60)},
                buf, totals);
  }
  const Scene office = cullkit::support::make_office(2, 3, 2);
  check_scene("office", office, views_of(office, true), buf, totals);
  // Scenes that stress the on-plane tolerance.
  const Scene small_far = bsp_test::small_far_cloud(21, 800);
  check_scene("small_far", small_far, views_of(small_far, true), buf, totals);
  const Scene slivers = bsp_test::sliver_soup(22, 200);
  {
    // Its far triangle (at x = 1000) only sets the largest coordinate: look at the slivers' box.
    std::vector<View> views = {make_view({0.3f, 0.2f, 0.1f}, {3, 1, 2}, 0.01f, 50), make_view({12, 7, 9}, {0, 0, 0}, 0.5f, 60)};
    for (const glm::vec3& eye : bsp_test::eyes_on_mesh(slivers, 101)) views.push_back(make_view(eye, {0, 0, 0}, 0.01f, 50));
    check_scene("slivers", slivers, views, buf, totals);
  }
  const Scene fans = bsp_test::near_coplanar_fans(23, 12, 16, 1e-4f);
  check_scene("fans", fans, views_of(fans, true), buf, totals);
  const Scene tiny_office = bsp_test::scaled(cullkit::support::make_office(3, 2, 2), 1e-3f, "office_x1e-3");
  check_scene("office_x1e-3", tiny_office, views_of(tiny_office, true), buf, totals);
  const Scene big_soup = bsp_test::scaled(bsp_test::random_soup(24, 150, 4.0f, 2.0f), 1e3f, "soup_x1e3");
  check_scene("soup_x1e3", big_soup, views_of(big_soup, true), buf, totals);
  for (const auto& file : cullkit::support::real_scene_files()) {
    const auto loaded = cullkit::support::load_obj(cullkit::support::scenes_dir() + "/" + file);
    if (!loaded) continue;
    const glm::vec3 centre = (loaded->bounds.min + loaded->bounds.max) * 0.5f;
    const Scene part = chunk(*loaded, centre, 4000);
    check_scene(file, part, views_of(part, true), buf, totals);
  }
  std::printf("pixels %zu, covered %zu, differing %zu (edge %zu, tie %zu, cut %zu); oracle agrees with Mesa at %zu of %zu "
              "sampled pixels; unexcused pixels with the reversed order %zu, with a centroid sort %zu\n",
              totals.pixels_compared, totals.covered, totals.differing, totals.edge, totals.tie, totals.cut_edge,
              totals.oracle_agree,
              totals.oracle_sampled, totals.mutant_wrong, totals.centroid_wrong);
  CHECK(totals.covered > totals.pixels_compared / 6);             // the images are not empty
  CHECK(totals.oracle_agree >= totals.oracle_sampled * 99 / 100);  // the oracle is aligned with Mesa
  CHECK(totals.oracle_sampled > 200);
  CHECK(totals.mutant_wrong > 100);  // a wrong order is seen
  CHECK(totals.centroid_wrong > 0);  // and a depth sort is not enough
  OSMesaDestroyContext(ctx);
  return cullkit_test::report("test_bsp_osmesa");
}
