// cullkit_support/image.hpp: tiny RGB canvas for the pictures demos and tests write (PNG via stb).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>

namespace cullkit::support {

struct Rgb {
  std::uint8_t r, g, b;
};

class Image {
 public:
  Image(int width, int height, Rgb fill = {255, 255, 255});
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  void set(int x, int y, Rgb c);
  /// Alpha-blends `c` over the pixel with weight `alpha` in [0, 1].
  void blend(int x, int y, Rgb c, float alpha);
  [[nodiscard]] Rgb get(int x, int y) const;
  void fill_rect(int x0, int y0, int x1, int y1, Rgb c, float alpha = 1.0f);
  void line(float x0, float y0, float x1, float y1, Rgb c, float alpha = 1.0f);
  void fill_triangle(glm::vec2 a, glm::vec2 b, glm::vec2 c, Rgb color, float alpha = 1.0f);
  /// Copies `other` into this image with its top-left at (x, y).
  void paste(const Image& other, int x, int y);
  /// Writes a PNG; false if it could not (or if stb is not available).
  bool write_png(const std::string& path) const;

 private:
  int width_, height_;
  std::vector<std::uint8_t> rgb_;
};

/// Maps the scene's X/Z plane (seen from above, -Z up the picture) onto an image.
class TopDownMap {
 public:
  TopDownMap(const Aabb& world, int max_pixels);
  Image& image() { return image_; }
  [[nodiscard]] glm::vec2 to_pixel(const glm::vec3& world) const;
  void box(const Aabb& b, Rgb fill, float alpha = 1.0f);
  void outline(const Aabb& b, Rgb color, float alpha = 1.0f);
  void segment(const glm::vec3& a, const glm::vec3& b, Rgb color, float alpha = 1.0f);
  /// Draws the frustum's footprint: the lines from the eye along the left/right edges of the view.
  void camera(const Camera& camera, float length, Rgb color);

 private:
  Aabb world_;
  float scale_;
  Image image_;
};

/// A distinct colour for an integer id (for triangles, classes, objects).
[[nodiscard]] Rgb id_color(std::uint32_t id);
/// Blue→red heat colour for t in [0, 1].
[[nodiscard]] Rgb heat_color(float t);

}  // namespace cullkit::support
