// The RGB canvas, the top-down map and the colour helpers behind image.hpp; PNG through stb.
#include <algorithm>
#include <cmath>

#include <cullkit_support/image.hpp>

#ifdef CULLKIT_HAVE_STB
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
#endif

namespace cullkit::support {

namespace {
std::uint8_t mix(std::uint8_t under, std::uint8_t over, float alpha) {
  const float v = static_cast<float>(under) + (static_cast<float>(over) - static_cast<float>(under)) * alpha;
  return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
}
bool finite2(float a, float b) { return std::isfinite(a) && std::isfinite(b); }
}  // namespace

Image::Image(int width, int height, Rgb fill) : width_(std::max(width, 0)), height_(std::max(height, 0)) {
  rgb_.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3);
  for (std::size_t i = 0; i < rgb_.size(); i += 3) {
    rgb_[i] = fill.r;
    rgb_[i + 1] = fill.g;
    rgb_[i + 2] = fill.b;
  }
}

void Image::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  const std::size_t i = (static_cast<std::size_t>(y) * width_ + x) * 3;
  rgb_[i] = c.r;
  rgb_[i + 1] = c.g;
  rgb_[i + 2] = c.b;
}

void Image::blend(int x, int y, Rgb c, float alpha) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_ || !(alpha > 0.0f)) return;  // NaN alpha: nothing
  alpha = std::min(alpha, 1.0f);
  const std::size_t i = (static_cast<std::size_t>(y) * width_ + x) * 3;
  rgb_[i] = mix(rgb_[i], c.r, alpha);
  rgb_[i + 1] = mix(rgb_[i + 1], c.g, alpha);
  rgb_[i + 2] = mix(rgb_[i + 2], c.b, alpha);
}

Rgb Image::get(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return {0, 0, 0};
  const std::size_t i = (static_cast<std::size_t>(y) * width_ + x) * 3;
  return {rgb_[i], rgb_[i + 1], rgb_[i + 2]};
}

void Image::fill_rect(int x0, int y0, int x1, int y1, Rgb c, float alpha) {
  // Both corners inclusive, in either order; clipped to the image.
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width_ - 1);
  y1 = std::min(y1, height_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) blend(x, y, c, alpha);
}

void Image::line(float x0, float y0, float x1, float y1, Rgb c, float alpha) {
  if (!finite2(x0, y0) || !finite2(x1, y1)) return;
  // Clip to the image (grown by a pixel) first (Liang–Barsky), so a huge line costs what it shows.
  // A clipped end is placed exactly on the bound that clipped it, with the other coordinate from the
  // slope: interpolating p0 + t * d would lose the visible part under the far endpoint's magnitude.
  double t0 = 0.0, t1 = 1.0;
  int axis0 = -1, axis1 = -1;
  const double p0[2] = {x0, y0}, d[2] = {double(x1) - x0, double(y1) - y0};
  const double lo[2] = {-1.0, -1.0}, hi[2] = {width_ + 1.0, height_ + 1.0};
  double bound0 = 0, bound1 = 0;
  for (int a = 0; a < 2; ++a) {
    if (d[a] == 0.0) {
      if (p0[a] < lo[a] || p0[a] > hi[a]) return;
      continue;
    }
    double ta = (lo[a] - p0[a]) / d[a], tb = (hi[a] - p0[a]) / d[a];
    double ba = lo[a], bb = hi[a];
    if (ta > tb) {
      std::swap(ta, tb);
      std::swap(ba, bb);
    }
    if (ta > t0) t0 = ta, axis0 = a, bound0 = ba;
    if (tb < t1) t1 = tb, axis1 = a, bound1 = bb;
    if (t0 > t1) return;
  }
  auto clipped = [&](int axis, double bound, double fx, double fy, float out[2]) {
    if (axis < 0) {
      out[0] = static_cast<float>(fx);
      out[1] = static_cast<float>(fy);
      return;
    }
    const int o = 1 - axis;
    out[axis] = static_cast<float>(bound);
    out[o] = static_cast<float>(p0[o] + (bound - p0[axis]) * (d[o] / d[axis]));
  };
  float pa[2], pb[2];
  clipped(axis0, bound0, x0, y0, pa);
  clipped(axis1, bound1, x1, y1, pb);
  const float ax = pa[0], ay = pa[1], bx = pb[0], by = pb[1];
  // DDA: one pixel per step along the major axis.
  const float len = std::max(std::fabs(bx - ax), std::fabs(by - ay));
  const int steps = static_cast<int>(std::ceil(len));
  for (int i = 0; i <= steps; ++i) {
    const float t = steps == 0 ? 0.0f : static_cast<float>(i) / static_cast<float>(steps);
    blend(static_cast<int>(std::floor(ax + (bx - ax) * t)), static_cast<int>(std::floor(ay + (by - ay) * t)), c, alpha);
  }
}

void Image::fill_triangle(glm::vec2 a, glm::vec2 b, glm::vec2 c, Rgb color, float alpha) {
  if (!finite2(a.x, a.y) || !finite2(b.x, b.y) || !finite2(c.x, c.y)) return;
  const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (area == 0.0f) return;
  const float s = area > 0.0f ? 1.0f : -1.0f;  // either winding
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
  const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
  const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
  auto edge = [](glm::vec2 p, glm::vec2 q, float x, float y) { return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x); };
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const float px = static_cast<float>(x) + 0.5f, py = static_cast<float>(y) + 0.5f;
      if (s * edge(a, b, px, py) >= 0.0f && s * edge(b, c, px, py) >= 0.0f && s * edge(c, a, px, py) >= 0.0f)
        blend(x, y, color, alpha);
    }
}

void Image::paste(const Image& other, int x, int y) {
  for (int j = 0; j < other.height_; ++j)
    for (int i = 0; i < other.width_; ++i) set(x + i, y + j, other.get(i, j));
}

bool Image::write_png(const std::string& path) const {
#ifdef CULLKIT_HAVE_STB
  if (width_ <= 0 || height_ <= 0) return false;
  return stbi_write_png(path.c_str(), width_, height_, 3, rgb_.data(), width_ * 3) != 0;
#else
  (void)path;
  return false;
#endif
}

TopDownMap::TopDownMap(const Aabb& world, int max_pixels)
    : world_(world), scale_(1.0f), image_(1, 1) {
  max_pixels = std::max(max_pixels, 1);
  if (!is_valid(world_)) world_ = Aabb{glm::vec3(0.0f), glm::vec3(1.0f)};
  const float span = std::max(world_.max.x - world_.min.x, world_.max.z - world_.min.z);
  scale_ = span > 0.0f ? static_cast<float>(max_pixels) / span : 1.0f;
  const int w = std::clamp(static_cast<int>(std::ceil((world_.max.x - world_.min.x) * scale_)), 1, max_pixels);
  const int h = std::clamp(static_cast<int>(std::ceil((world_.max.z - world_.min.z) * scale_)), 1, max_pixels);
  image_ = Image(w, h);
}

glm::vec2 TopDownMap::to_pixel(const glm::vec3& world) const {
  // X to the right; Z down the picture, so -Z is up.
  return {(world.x - world_.min.x) * scale_, (world.z - world_.min.z) * scale_};
}

void TopDownMap::box(const Aabb& b, Rgb fill, float alpha) {
  const glm::vec2 p = to_pixel(b.min), q = to_pixel(b.max);
  if (!finite2(p.x, p.y) || !finite2(q.x, q.y)) return;
  image_.fill_rect(static_cast<int>(std::floor(p.x)), static_cast<int>(std::floor(p.y)),
                   static_cast<int>(std::ceil(q.x)) - 1, static_cast<int>(std::ceil(q.y)) - 1, fill, alpha);
}

void TopDownMap::outline(const Aabb& b, Rgb color, float alpha) {
  const glm::vec2 p = to_pixel(b.min), q = to_pixel(b.max);
  image_.line(p.x, p.y, q.x, p.y, color, alpha);
  image_.line(q.x, p.y, q.x, q.y, color, alpha);
  image_.line(q.x, q.y, p.x, q.y, color, alpha);
  image_.line(p.x, q.y, p.x, p.y, color, alpha);
}

void TopDownMap::segment(const glm::vec3& a, const glm::vec3& b, Rgb color, float alpha) {
  const glm::vec2 p = to_pixel(a), q = to_pixel(b);
  image_.line(p.x, p.y, q.x, q.y, color, alpha);
}

void TopDownMap::camera(const Camera& cam, float length, Rgb color) {
  if (cam.width <= 0 || cam.height <= 0) return;
  const PixelRays rays(cam);
  const double mid = 0.5 * cam.height;
  const Ray left = rays.ray_at(0.0, mid), right = rays.ray_at(static_cast<double>(cam.width), mid);
  const glm::vec3 l = cam.eye + left.direction * length, r = cam.eye + right.direction * length;
  segment(cam.eye, l, color);
  segment(cam.eye, r, color);
  segment(l, r, color, 0.5f);
  const glm::vec2 e = to_pixel(cam.eye);
  image_.fill_rect(static_cast<int>(e.x) - 1, static_cast<int>(e.y) - 1, static_cast<int>(e.x) + 1,
                   static_cast<int>(e.y) + 1, color);
}

Rgb id_color(std::uint32_t id) {
  // Hash the id (a 32-bit finalizer), then keep each channel in [48, 239] so no colour is near black
  // or white (background and lines stay readable).
  std::uint32_t h = id + 0x9E3779B9u;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  auto ch = [](std::uint32_t v) { return static_cast<std::uint8_t>(48 + (v & 0xFFu) * 191 / 255); };
  return {ch(h), ch(h >> 8), ch(h >> 16)};
}

Rgb heat_color(float t) {
  if (!(t >= 0.0f)) t = 0.0f;  // NaN and negatives: cold
  t = std::min(t, 1.0f);
  // Blue → cyan → green → yellow → red, four equal linear segments.
  static constexpr float stops[5][3] = {{0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
  const float f = t * 4.0f;
  const int i = std::min(static_cast<int>(f), 3);
  const float u = f - static_cast<float>(i);
  auto lerp = [&](int c) {
    return static_cast<std::uint8_t>(std::lround(stops[i][c] + (stops[i + 1][c] - stops[i][c]) * u));
  };
  return {lerp(0), lerp(1), lerp(2)};
}

}  // namespace cullkit::support
