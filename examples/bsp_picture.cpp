// bsp_picture: transparent panes blended back to front, two ways, side by side in
// <dir>/bsp_panes.png (argv[1], default "."):
//   left:  the fragments of a BspTree in back_to_front order (exact from any eye);
//   right: the same panes' triangles sorted by the distance of their centroids (order_back_to_front),
//          which is what a renderer does without a BSP.
//   third: black where the two differ.
// The panes pierce each other and three of them overlap cyclically, so no order of whole triangles
// is right: on the right, wherever a pane passes through another, one of the two halves is blended
// in the wrong order and its colour is wrong. Each pixel blends, in painting order, every polygon
// whose projection holds the pixel centre (alpha 0.6 over a white background). A third panel marks in
// black the pixels where the two differ by more than a rounding step.
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <cullkit/bsp_tree.hpp>
#include <cullkit/depth_sort.hpp>
#include <cullkit_support/image.hpp>

namespace {

using cullkit::support::Image;
using cullkit::support::Rgb;

constexpr int kW = 480, kH = 360;

struct Pane {
  glm::vec3 corner, edge_u, edge_v;  // a parallelogram
  Rgb color;
};

// A polygon in pixel coordinates painted over `image`, strictly inside its edges (either winding).
void blend_polygon(Image& image, const std::vector<glm::vec2>& p, Rgb color, float alpha) {
  float area = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const glm::vec2 a = p[i], b = p[(i + 1) % p.size()];
    area += a.x * b.y - a.y * b.x;
  }
  if (area == 0) return;
  const float s = area > 0 ? 1.0f : -1.0f;
  float x0 = 1e9f, x1 = -1e9f, y0 = 1e9f, y1 = -1e9f;
  for (const auto& q : p) {
    x0 = std::min(x0, q.x);
    x1 = std::max(x1, q.x);
    y0 = std::min(y0, q.y);
    y1 = std::max(y1, q.y);
  }
  for (int y = std::max(0, int(y0)); y <= std::min(kH - 1, int(y1) + 1); ++y) {
    for (int x = std::max(0, int(x0)); x <= std::min(kW - 1, int(x1) + 1); ++x) {
      const float px = float(x) + 0.5f, py = float(y) + 0.5f;
      bool inside = true;
      for (std::size_t i = 0; inside && i < p.size(); ++i) {
        const glm::vec2 a = p[i], b = p[(i + 1) % p.size()];
        inside = s * ((b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)) > 0;
      }
      if (inside) image.blend(x, y, color, alpha);
    }
  }
}

glm::vec2 to_pixel(const glm::mat4& vp, const glm::vec3& p) {
  const glm::vec4 c = vp * glm::vec4(p, 1.0f);
  return {(c.x / c.w * 0.5f + 0.5f) * kW, (0.5f - c.y / c.w * 0.5f) * kH};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  // Three panes overlapping cyclically (a pinwheel, each tilted over the next), two crossing
  // upright panes, and a wide pane pierced by both.
  std::vector<Pane> panes;
  const Rgb cyc[3] = {{220, 40, 40}, {40, 170, 60}, {40, 80, 220}};
  for (int k = 0; k < 3; ++k) {
    const float a = 2.0943951f * float(k);
    const glm::vec3 along(std::cos(a), 0, std::sin(a)), side(-along.z, 0, along.x);
    const glm::vec3 base = -along * 2.2f + side * 0.5f + glm::vec3(0, 0.3f, 0);
    panes.push_back({base - side * 0.45f, along * 4.2f + glm::vec3(0, 0.9f, 0), side * 0.9f, cyc[k]});
  }
  panes.push_back({{2.0f, -0.6f, -1.6f}, {2.2f, 0, 2.2f}, {0, 2.4f, 0}, {240, 180, 20}});
  panes.push_back({{4.2f, -0.6f, -1.6f}, {-2.2f, 0, 2.2f}, {0, 2.4f, 0}, {170, 40, 200}});
  panes.push_back({{1.6f, 0.5f, -2.0f}, {3.2f, 0, 0}, {0, 0.15f, 3.6f}, {30, 190, 200}});
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  std::vector<Rgb> tri_color;
  for (const auto& p : panes) {
    const auto base = static_cast<std::uint32_t>(positions.size());
    positions.insert(positions.end(), {p.corner, p.corner + p.edge_u, p.corner + p.edge_u + p.edge_v, p.corner + p.edge_v});
    indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    tri_color.insert(tri_color.end(), {p.color, p.color});
  }
  const cullkit::BspTree<glm::vec3> tree(
      cullkit::MeshView<glm::vec3>{positions.data(), positions.size(), indices.data(), indices.size()});
  const glm::vec3 eye(0.9f, 4.4f, 5.8f), target(1.3f, 0.3f, 0.0f);
  const glm::mat4 vp = glm::perspectiveRH_NO(glm::radians(48.0f), float(kW) / float(kH), 0.1f, 100.0f) *
                       glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
  const float alpha = 0.6f;

  Image bsp(kW, kH), sorted(kW, kH);
  std::vector<std::uint32_t> order;
  tree.back_to_front(eye, order);
  for (std::uint32_t f : order) {
    const auto& fr = tree.fragments()[f];
    std::vector<glm::vec2> poly;
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) poly.push_back(to_pixel(vp, tree.corners()[fr.first_corner + i]));
    blend_polygon(bsp, poly, tri_color[fr.triangle], alpha);
  }
  const std::size_t nt = indices.size() / 3;
  std::vector<float> depth(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const glm::vec3 c = (positions[indices[3 * t]] + positions[indices[3 * t + 1]] + positions[indices[3 * t + 2]]) / 3.0f;
    depth[t] = glm::length(c - eye);
  }
  cullkit::order_back_to_front(depth.data(), nt, order);
  for (std::uint32_t t : order) {
    std::vector<glm::vec2> poly;
    for (int k = 0; k < 3; ++k) poly.push_back(to_pixel(vp, positions[indices[3 * t + std::size_t(k)]]));
    blend_polygon(sorted, poly, tri_color[t], alpha);
  }
  Image diff(kW, kH);
  std::size_t differing = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const Rgb a = bsp.get(x, y), b = sorted.get(x, y);
      const int d = std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
      const bool covered = a.r != 255 || a.g != 255 || a.b != 255;
      diff.set(x, y, d > 6 ? Rgb{0, 0, 0} : (covered ? Rgb{215, 215, 215} : Rgb{255, 255, 255}));
      differing += d > 6;
    }
  Image both(3 * kW + 16, kH, Rgb{60, 60, 60});
  both.paste(bsp, 0, 0);
  both.paste(sorted, kW + 8, 0);
  both.paste(diff, 2 * kW + 16, 0);
  const std::string path = dir + "/bsp_panes.png";
  const bool ok = both.write_png(path);
  std::printf("bsp_picture: %zu triangles, %zu fragments, %zu pixels differ; %s %s\n", nt, tree.fragments().size(),
              differing, ok ? "wrote" : "could not write", path.c_str());
  return ok ? 0 : 1;
}
