// BoxProxy picture: a box, its outline from an eye in a corner region, the beam, and why the seed's
// centre plane is wrong.
//
//   build/release/examples/box_proxy_picture [output-dir]     (writes <dir>/box_proxy.png)
//
// Top left, a third-person view: the box (faces the eye sees tinted orange), the eye (blue dot),
// the six outline corners (dots coloured blue -> red in their counter-clockwise order as seen from
// the eye), the outline (red) and the beam: lines from the eye through each corner, and the beam's
// sides beyond the box shaded blue. Top right, the same box as the eye sees it: three front faces,
// the hexagonal outline, corners in the same colours (counter-clockwise on the screen).
// Bottom, a vertical section through a long building with an antenna on the far end of its roof,
// eye above and to the left: every pixel is classified by `proxy_hides` itself. Blue: hidden with
// the exact closure (front-face planes, green lines). Red: hidden only by the seed's centre plane
// (dark red line), which swallows the antenna (orange) although the eye sees it over the roof; the
// framed inset magnifies the far end of the roof.
#include <cmath>
#include <cstdio>
#include <string>

#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>

#include <cullkit/box_proxy.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;
using support::Image;
using support::Rgb;

namespace {

constexpr Rgb kEdge{90, 90, 90};
constexpr Rgb kOutline{210, 30, 30};
constexpr Rgb kEye{20, 60, 200};
constexpr Rgb kBeam{60, 110, 230};
constexpr Rgb kFrontFace{250, 190, 120};
constexpr Rgb kOtherFace{215, 215, 215};
constexpr Rgb kAntenna{240, 140, 20};
constexpr Rgb kFacePlane{30, 150, 60};
constexpr Rgb kCenterPlane{150, 0, 0};

// World to pixel through a camera's view-projection (points must be in front of the camera).
struct Projector {
  glm::mat4 view_proj;
  int width, height;
  glm::vec2 operator()(const glm::vec3& p) const {
    const glm::vec4 clip = view_proj * glm::vec4(p, 1.0f);
    return glm::vec2((clip.x / clip.w + 1.0f) * 0.5f * float(width), (1.0f - clip.y / clip.w) * 0.5f * float(height));
  }
};

void thick_line(Image& img, glm::vec2 a, glm::vec2 b, Rgb c, float width, float alpha = 1.0f) {
  const glm::vec2 d = b - a;
  const float len = std::sqrt(d.x * d.x + d.y * d.y);
  if (!(len > 0.0f)) return;
  const glm::vec2 n(-d.y / len, d.x / len);
  for (float o = -0.5f * width; o <= 0.5f * width; o += 0.5f) {
    img.line(a.x + n.x * o, a.y + n.y * o, b.x + n.x * o, b.y + n.y * o, c, alpha);
  }
}

void dot(Image& img, glm::vec2 p, Rgb c, int r) {
  img.fill_rect(int(p.x) - r, int(p.y) - r, int(p.x) + r, int(p.y) + r, Rgb{0, 0, 0});
  img.fill_rect(int(p.x) - r + 1, int(p.y) - r + 1, int(p.x) + r - 1, int(p.y) + r - 1, c);
}

void fill_quad(Image& img, glm::vec2 a, glm::vec2 b, glm::vec2 c, glm::vec2 d, Rgb color, float alpha) {
  img.fill_triangle(a, b, c, color, alpha);
  img.fill_triangle(a, c, d, color, alpha);
}

// The box's 6 faces as corner-id cycles (outward, counter-clockwise seen from outside).
struct Face {
  int axis, side;
  int ids[4];
};
constexpr Face kFaces[6] = {{0, 0, {0, 4, 6, 2}}, {0, 1, {1, 3, 7, 5}}, {1, 0, {0, 1, 5, 4}},
                            {1, 1, {2, 6, 7, 3}}, {2, 0, {0, 2, 3, 1}}, {2, 1, {4, 5, 7, 6}}};

bool faces_point(const Aabb& box, const Face& f, const glm::vec3& p) {
  return f.side ? p[f.axis] > box.max[f.axis] : p[f.axis] < box.min[f.axis];
}

// Draws the box's faces that `viewer` sees, tinted when `eye` sees them too, with their edges.
void draw_box(Image& img, const Projector& to_px, const Aabb& box, const glm::vec3& viewer, const glm::vec3& eye) {
  for (const Face& f : kFaces) {
    if (!faces_point(box, f, viewer)) continue;
    fill_quad(img, to_px(corner(box, f.ids[0])), to_px(corner(box, f.ids[1])), to_px(corner(box, f.ids[2])),
              to_px(corner(box, f.ids[3])), faces_point(box, f, eye) ? kFrontFace : kOtherFace, 1.0f);
  }
  for (const Face& f : kFaces) {
    if (!faces_point(box, f, viewer)) continue;
    for (int k = 0; k < 4; ++k) {
      const glm::vec2 a = to_px(corner(box, f.ids[k])), b = to_px(corner(box, f.ids[(k + 1) % 4]));
      img.line(a.x, a.y, b.x, b.y, kEdge);
    }
  }
}

void draw_outline(Image& img, const Projector& to_px, const BoxProxy& proxy) {
  for (int i = 0; i < proxy.corner_count; ++i) {
    thick_line(img, to_px(proxy.corners[i]), to_px(proxy.corners[(i + 1) % proxy.corner_count]), kOutline, 3.0f);
  }
  for (int i = 0; i < proxy.corner_count; ++i) {
    dot(img, to_px(proxy.corners[i]), support::heat_color(float(i) / float(proxy.corner_count - 1)), 6);
  }
}

Image third_person(const Aabb& box, const glm::vec3& eye, const BoxProxy& proxy) {
  const int w = 640, h = 480;
  Image img(w, h);
  const glm::vec3 viewer(9.0f, 13.0f, 19.0f);
  const Camera cam = support::make_camera(viewer, glm::vec3(1.5f, 2.0f, 3.0f), 44.0f, w, h, 0.1f, 100.0f);
  const Projector to_px{cam.view_proj, w, h};
  const float reach = 2.0f;  // the beam drawn out to twice each corner's distance from the eye
  // The beam's sides beyond the box, translucent, then the box over them where it is nearer.
  for (int i = 0; i < proxy.corner_count; ++i) {
    const glm::vec3 a = proxy.corners[i], b = proxy.corners[(i + 1) % proxy.corner_count];
    fill_quad(img, to_px(a), to_px(b), to_px(eye + (b - eye) * reach), to_px(eye + (a - eye) * reach), kBeam, 0.12f);
  }
  draw_box(img, to_px, box, viewer, eye);
  for (int i = 0; i < proxy.corner_count; ++i) {
    const glm::vec2 e = to_px(eye), c = to_px(proxy.corners[i]);
    const glm::vec2 far = to_px(eye + (proxy.corners[i] - eye) * reach);
    thick_line(img, e, c, kBeam, 1.5f, 0.9f);
    img.line(c.x, c.y, far.x, far.y, kBeam, 0.6f);
  }
  draw_outline(img, to_px, proxy);
  dot(img, to_px(eye), kEye, 8);
  return img;
}

Image eye_view(const Aabb& box, const glm::vec3& eye, const BoxProxy& proxy) {
  const int w = 640, h = 480;
  Image img(w, h, Rgb{245, 245, 250});
  const Camera cam = support::make_camera(eye, box.center(), 50.0f, w, h, 0.1f, 100.0f);
  const Projector to_px{cam.view_proj, w, h};
  draw_box(img, to_px, box, eye, eye);
  draw_outline(img, to_px, proxy);
  return img;
}

// Vertical section z = 5 through the rooftop-antenna scene over the world window [x0, x1] x [y0, y1]
// (uniform scale, centred), every pixel classified by proxy_hides.
Image antenna_section(int w, int h, float wx0, float wx1, float wy0, float wy1) {
  Image img(w, h);
  const Aabb building{glm::vec3(0, 0, 0), glm::vec3(100, 10, 10)};
  const Aabb antenna{glm::vec3(90, 10, 4), glm::vec3(94, 11, 6)};  // as in test_box_proxy_embree
  const glm::vec3 eye(-20, 60, 5);
  const BoxProxy exact = make_box_proxy(building, eye);
  const BoxProxy seed = make_box_proxy(building, eye, ProxyClosure::center_plane);
  const float scale = std::fmin(float(w) / (wx1 - wx0), float(h) / (wy1 - wy0));
  const float x0 = wx0 + 0.5f * ((wx1 - wx0) - float(w) / scale);
  const float y1 = wy1 - 0.5f * ((wy1 - wy0) - float(h) / scale);
  auto to_px = [&](float x, float y) { return glm::vec2((x - x0) * scale, (y1 - y) * scale); };
  for (int py = 0; py < h; ++py) {
    for (int px = 0; px < w; ++px) {
      const glm::vec3 p(x0 + (float(px) + 0.5f) / scale, y1 - (float(py) + 0.5f) / scale, 5.0f);
      if (proxy_hides(exact, eye, p)) img.set(px, py, Rgb{190, 205, 245});
      else if (proxy_hides(seed, eye, p)) img.set(px, py, Rgb{250, 190, 190});
    }
  }
  auto rect = [&](const Aabb& b, Rgb c) {
    const glm::vec2 a = to_px(b.min.x, b.max.y), d = to_px(b.max.x, b.min.y);
    img.fill_rect(int(a.x), int(a.y), int(d.x), int(d.y), c);
  };
  rect(building, Rgb{150, 150, 150});
  rect(antenna, kAntenna);
  auto seg = [&](glm::vec2 a, glm::vec2 b, Rgb c, float width) {
    thick_line(img, to_px(a.x, a.y), to_px(b.x, b.y), c, width);
  };
  // Front-face planes (x = 0 and y = 10 in this section) and the seed's centre plane.
  seg({0, -1000}, {0, 1000}, kFacePlane, 1.5f);
  seg({-1000, 10}, {1000, 10}, kFacePlane, 1.5f);
  const glm::vec2 c(50, 5), n(seed.faces[0].normal.x, seed.faces[0].normal.y);
  const glm::vec2 along(-n.y, n.x);
  seg(c - along * 200.0f, c + along * 200.0f, kCenterPlane, 2.0f);
  // The beam's edges in this section: from the eye through (0, 0) and (100, 10).
  seg({-20, 60}, {-20 + 20 * 20.0f, 60 - 60 * 20.0f}, kBeam, 1.5f);
  seg({-20, 60}, {-20 + 120 * 20.0f, 60 - 50 * 20.0f}, kBeam, 1.5f);
  dot(img, to_px(eye.x, eye.y), kEye, 8);
  return img;
}

void frame(Image& img, int x0, int y0, int x1, int y1) {
  const Rgb black{0, 0, 0};
  img.line(float(x0), float(y0), float(x1), float(y0), black);
  img.line(float(x1), float(y0), float(x1), float(y1), black);
  img.line(float(x1), float(y1), float(x0), float(y1), black);
  img.line(float(x0), float(y1), float(x0), float(y0), black);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  const Aabb box{glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(4.0f, 3.0f, 5.0f)};
  const glm::vec3 eye(-4.0f, 7.5f, 9.0f);  // below min x, above max y, above max z: region 24
  const BoxProxy proxy = make_box_proxy(box, eye);
  std::printf("eye region %d: %d outline corners, %d front faces\n", proxy.region, int(proxy.corner_count),
              int(proxy.face_count));
  for (int i = 0; i < proxy.corner_count; ++i)
    std::printf("  corner %d: (%g, %g, %g)\n", i, proxy.corners[i].x, proxy.corners[i].y, proxy.corners[i].z);

  Image canvas(1280, 480 + 400);
  canvas.paste(third_person(box, eye, proxy), 0, 0);
  canvas.paste(eye_view(box, eye, proxy), 640, 0);
  canvas.paste(antenna_section(1280, 400, -30.0f, 150.0f, -8.0f, 64.0f), 0, 480);
  // Inset: the far end of the roof magnified, the antenna inside the red (seed-only) wedge.
  canvas.paste(antenna_section(440, 180, 78.0f, 104.0f, 6.0f, 15.0f), 820, 492);
  frame(canvas, 820, 492, 1260, 672);
  canvas.line(639.5f, 0, 639.5f, 480, Rgb{0, 0, 0});
  canvas.line(0, 479.5f, 1280, 479.5f, Rgb{0, 0, 0});
  const std::string path = dir + "/box_proxy.png";
  if (!canvas.write_png(path)) {
    std::fprintf(stderr, "could not write %s\n", path.c_str());
    return 1;
  }
  std::printf("wrote %s\n", path.c_str());
  return 0;
}
