// The picture helpers: pixel access, blending, rectangles, lines, triangles (counted against their
// exact areas), PNG output (signature and header read back), the top-down map and the colours.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <vector>

#include <check.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;
using support::Image;
using support::Rgb;

namespace {

bool eq(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

int count(const Image& im, Rgb c) {
  int n = 0;
  for (int y = 0; y < im.height(); ++y)
    for (int x = 0; x < im.width(); ++x) n += eq(im.get(x, y), c);
  return n;
}

const Rgb white{255, 255, 255}, black{0, 0, 0}, red{255, 0, 0};

void test_canvas() {
  Image im(40, 30);
  CHECK(im.width() == 40 && im.height() == 30);
  CHECK(count(im, white) == 1200);
  im.set(3, 4, red);
  CHECK(eq(im.get(3, 4), red));
  im.set(-1, 0, red);
  im.set(40, 0, red);
  im.set(0, 30, red);
  CHECK(count(im, red) == 1);
  CHECK(eq(im.get(-5, 2), black) && eq(im.get(2, 99), black));
  Image grey(2, 1, {200, 100, 0});
  grey.blend(0, 0, {0, 0, 200}, 0.5f);
  CHECK(eq(grey.get(0, 0), Rgb{100, 50, 100}));
  grey.blend(1, 0, {0, 0, 0}, std::numeric_limits<float>::quiet_NaN());
  grey.blend(1, 0, {0, 0, 0}, 0.0f);
  CHECK(eq(grey.get(1, 0), Rgb{200, 100, 0}));
  grey.blend(1, 0, {1, 2, 3}, 7.0f);  // clamped to 1
  CHECK(eq(grey.get(1, 0), Rgb{1, 2, 3}));

  Image r(20, 20);
  r.fill_rect(15, 12, 5, 2, red);  // corners inclusive, either order
  CHECK(count(r, red) == 11 * 11);
  CHECK(eq(r.get(5, 2), red) && eq(r.get(15, 12), red) && eq(r.get(16, 12), white));
  r.fill_rect(-100, -100, 200, 0, black);
  CHECK(count(r, black) == 20);

  Image l(50, 50);
  l.line(2.5f, 10.5f, 40.5f, 10.5f, red);
  CHECK(count(l, red) == 39);
  CHECK(eq(l.get(2, 10), red) && eq(l.get(40, 10), red));
  Image d(50, 50);
  d.line(0.5f, 0.5f, 49.5f, 49.5f, red);
  CHECK(count(d, red) == 50);
  for (int i = 0; i < 50; ++i) CHECK(eq(d.get(i, i), red));
  Image huge(50, 50);
  huge.line(-1e30f, 25.5f, 1e30f, 25.5f, red);  // clipped, not walked
  CHECK(count(huge, red) == 50);
  huge.line(std::numeric_limits<float>::quiet_NaN(), 0, 10, 10, black);
  CHECK(count(huge, black) == 0);

  // Triangles: pixel centres inside, either winding; the count is close to the exact area.
  for (int flip = 0; flip < 2; ++flip) {
    Image t(120, 120);
    const glm::vec2 a(10, 10), b(110, 10), c(10, 110);
    if (flip) t.fill_triangle(a, c, b, red);
    else t.fill_triangle(a, b, c, red);
    const int n = count(t, red);
    CHECK_MSG(std::abs(n - 5000) <= 110, "triangle covers %d pixels, want about 5000", n);
    CHECK(eq(t.get(11, 11), red) && eq(t.get(100, 100), white));
  }
  Image flat(10, 10);
  flat.fill_triangle({1, 1}, {5, 5}, {9, 9}, red);
  CHECK(count(flat, red) == 0);

  Image big(10, 10);
  Image small(3, 2, red);
  big.paste(small, 8, 9);  // clipped
  CHECK(count(big, red) == 2);
  CHECK(eq(big.get(8, 9), red) && eq(big.get(9, 9), red));
}

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}

void test_png() {
  namespace fs = std::filesystem;
  const fs::path path = fs::temp_directory_path() / ("cullkit_test_image_" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()) + ".png");
  Image im(37, 21, {10, 20, 30});
  im.fill_triangle({0, 0}, {36, 0}, {0, 20}, support::id_color(7));
  const bool ok = im.write_png(path.string());
#ifdef CULLKIT_TEST_HAVE_STB
  CHECK(ok);
#endif
  if (ok) {
    std::ifstream f(path, std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    CHECK(bytes.size() > 33);
    if (bytes.size() > 33) {
      const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
      CHECK(std::equal(sig, sig + 8, bytes.begin()));
      CHECK(be32(&bytes[16]) == 37 && be32(&bytes[20]) == 21);  // IHDR width, height
      CHECK(bytes[24] == 8 && bytes[25] == 2);                  // 8-bit RGB
    }
    std::error_code ec;
    fs::remove(path, ec);
  }
  CHECK(!Image(0, 5).write_png(path.string()));
  CHECK(!im.write_png("/nonexistent-dir/x.png"));
}

void test_map_and_colors() {
  support::TopDownMap map(Aabb{{0, 0, 0}, {100, 10, 50}}, 200);
  CHECK(map.image().width() == 200 && map.image().height() == 100);
  const glm::vec2 p = map.to_pixel({50, 3, 25});
  CHECK_NEAR(p.x, 100, 1e-4);
  CHECK_NEAR(p.y, 50, 1e-4);
  CHECK(map.to_pixel({0, 0, 0}).y < map.to_pixel({0, 0, 10}).y);  // -Z is up the picture
  map.box(Aabb{{10, 0, 10}, {20, 5, 15}}, red);
  CHECK(count(map.image(), red) == 20 * 10);
  CHECK(eq(map.image().get(20, 20), red) && eq(map.image().get(39, 29), red) && eq(map.image().get(40, 30), white));
  map.outline(Aabb{{60, 0, 10}, {80, 5, 30}}, black);
  CHECK(eq(map.image().get(120, 40), black) && eq(map.image().get(130, 20), black) && eq(map.image().get(130, 40), white));
  const Camera cam = support::make_camera({50, 2, 45}, {50, 2, 0}, 60, 64, 48, 0.1f, 100);
  support::TopDownMap m2(Aabb{{0, 0, 0}, {100, 10, 50}}, 200);
  m2.camera(cam, 30, red);
  // The view edges go up the picture from the eye, symmetric about x = 100 pixels.
  int left = 0, right = 0;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 200; ++x)
      if (eq(m2.image().get(x, y), red)) (x < 100 ? left : right) += 1;
  CHECK(left > 20 && right > 20 && std::abs(left - right) < 8);
  CHECK(eq(m2.image().get(100, 90), red));  // the eye marker

  std::set<std::uint32_t> colors;
  for (std::uint32_t i = 0; i < 1000; ++i) {
    const Rgb c = support::id_color(i);
    CHECK(c.r >= 48 && c.g >= 48 && c.b >= 48 && c.r < 240 && c.g < 240 && c.b < 240);
    colors.insert((std::uint32_t(c.r) << 16) | (std::uint32_t(c.g) << 8) | c.b);
  }
  CHECK(colors.size() >= 995);
  CHECK(eq(support::id_color(5), support::id_color(5)));
  CHECK(eq(support::heat_color(0), Rgb{0, 0, 255}));
  CHECK(eq(support::heat_color(0.5f), Rgb{0, 255, 0}));
  CHECK(eq(support::heat_color(1), Rgb{255, 0, 0}));
  CHECK(eq(support::heat_color(7), Rgb{255, 0, 0}));
  CHECK(eq(support::heat_color(std::numeric_limits<float>::quiet_NaN()), Rgb{0, 0, 255}));
}

}  // namespace

int main() {
  test_canvas();
  test_png();
  test_map_and_colors();
  return cullkit_test::report("test_image");
}
