// libFuzzer target: a NormalClassIndex built from bytes (corners may be NaN, inf, huge, repeated;
// indices may be out of range), then a camera from bytes (eye possibly inside geometry, extreme
// aspect ratios, tiny screens), checked against a brute-force float first-hit per pixel.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include <cullkit/normal_class_index.hpp>

#include "../tests/nci/nci_touches_eye.hpp"

namespace {

struct Reader {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t byte() {
    if (!n) return 0;
    --n;
    return *p++;
  }
  float coord() {  // mostly small grid values (coplanar, shared edges), sometimes wild floats
    const std::uint8_t k = byte();
    if (k < 200) return static_cast<float>(static_cast<int>(k % 17) - 8) * 0.5f;
    if (k < 250) return static_cast<float>(static_cast<std::int8_t>(byte())) * 0.0371f;
    float f;
    std::uint8_t b[4] = {byte(), byte(), byte(), byte()};
    std::memcpy(&f, b, 4);
    return f;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const int nv = 3 + in.byte() % 24;
  const int nt = in.byte() % 24;
  std::vector<glm::vec3> v(static_cast<std::size_t>(nv));
  for (auto& p : v) p = glm::vec3(in.coord(), in.coord(), in.coord());
  std::vector<std::uint32_t> idx;
  for (int i = 0; i < 3 * nt; ++i) idx.push_back(in.byte() % static_cast<unsigned>(nv + 2));  // some out of range
  cullkit::NciParams params;
  params.classes = 1 + in.byte() % 40;
  params.grid = 1 + in.byte() % 70;
  const int tile = in.byte() % 64;
  params.tile_size = tile == 0 ? 0 : 1 + tile;  // 0 (automatic) or 2..64
  params.threads = 1 + in.byte() % 3;
  params.build_threads = 1;
  const cullkit::NormalClassIndex<glm::vec3> index(cullkit::MeshView<glm::vec3>{v.data(), v.size(), idx.data(), idx.size()},
                                                   params);
  const int w = 1 + in.byte() % 40, h = 1 + in.byte() % 40;
  cullkit::Camera cam;
  cam.eye = glm::vec3(in.coord(), in.coord(), in.coord());
  glm::vec3 target(in.coord(), in.coord(), in.coord());
  if (!(glm::length(target - cam.eye) > 1e-3f)) target = cam.eye + glm::vec3(0.3f, -0.2f, -1.0f);
  const glm::vec3 fwd = glm::normalize(target - cam.eye);
  const glm::vec3 up = std::fabs(fwd.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  const float fov = glm::radians(5.0f + static_cast<float>(in.byte() % 160));
  cam.width = w;
  cam.height = h;
  cam.depth = (in.byte() & 1) ? cullkit::DepthRange::zero_to_one : cullkit::DepthRange::negative_one_to_one;
  const glm::mat4 proj = cam.depth == cullkit::DepthRange::zero_to_one
                             ? glm::perspectiveRH_ZO(fov, float(w) / float(h), 0.01f, 1000.0f)
                             : glm::perspectiveRH_NO(fov, float(w) / float(h), 0.01f, 1000.0f);
  cam.view_proj = proj * glm::lookAtRH(cam.eye, target, up);

  cullkit::NciContext ctx;
  cullkit::VisibleSet set;
  cullkit::NciPixels px;
  index.select_visible(cam, ctx, set, &px);
  if (px.triangle.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) std::abort();

  // Every pixel's triangle is a kept one; the set is sorted, unique and holds them.
  for (std::uint32_t t : px.triangle)
    if (t != cullkit::NciPixels::miss && (t >= static_cast<std::uint32_t>(nt) || index.triangle_class(t) < 0)) std::abort();
  for (std::size_t i = 1; i < set.triangles.size(); ++i)
    if (!(set.triangles[i - 1] < set.triangles[i])) std::abort();
  for (std::uint32_t t : px.triangle)
    if (t != cullkit::NciPixels::miss && !std::binary_search(set.triangles.begin(), set.triangles.end(), t)) std::abort();

  // Triangles the eye touches within float rounding (nci_test::touches_eye) on their front side
  // (exactly on the plane they are never hit): the float test is noise for them, and the index may
  // drop their hits where the exact geometry rules them out (documented), so pixels whose brute
  // force answer is one are not compared.
  std::vector<char> touching(static_cast<std::size_t>(nt), 0);
  for (int t = 0; t < nt; ++t) {
    if (index.triangle_class(static_cast<std::uint32_t>(t)) < 0) continue;
    const glm::vec3& p0 = v[idx[static_cast<std::size_t>(3 * t)]];
    const glm::vec3& p1 = v[idx[static_cast<std::size_t>(3 * t + 1)]];
    const glm::vec3& p2 = v[idx[static_cast<std::size_t>(3 * t + 2)]];
    touching[static_cast<std::size_t>(t)] = cullkit::detail::faces_eye(p0, p1, p2, glm::dvec3(cam.eye)) &&
                                            nci_test::touches_eye(p0, p1, p2, glm::dvec3(cam.eye));
  }

  // Brute force with the same float test and tie rule, over the triangles the index kept.
  const cullkit::PixelRays rays(cam);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto wr = cullkit::detail::WatertightRay<float>::make(rays.ray(x, y).direction);
      float best = std::numeric_limits<float>::infinity();
      std::uint32_t best_tri = cullkit::NciPixels::miss;
      const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      const std::uint32_t got = px.triangle[pixel];
      bool got_hit = got == cullkit::NciPixels::miss;  // the index reports only hits of the float test, at their depth
      for (int t = 0; t < nt; ++t) {
        if (index.triangle_class(static_cast<std::uint32_t>(t)) < 0) continue;
        const glm::vec3& p0 = v[idx[static_cast<std::size_t>(3 * t)]];
        const glm::vec3& p1 = v[idx[static_cast<std::size_t>(3 * t + 1)]];
        const glm::vec3& p2 = v[idx[static_cast<std::size_t>(3 * t + 2)]];
        if (!cullkit::detail::faces_eye(p0, p1, p2, glm::dvec3(cam.eye))) continue;
        float r[3][3];
        for (int k = 0; k < 3; ++k)
          for (int a = 0; a < 3; ++a) r[k][a] = v[idx[static_cast<std::size_t>(3 * t + k)]][a] - cam.eye[a];
        float th;
        const bool hit = cullkit::detail::watertight_hit(wr, r[0], r[1], r[2], th);
        if (hit && static_cast<std::uint32_t>(t) == got) got_hit = th == px.depth[pixel];
        if (hit && th < best) {
          best = th;
          best_tri = static_cast<std::uint32_t>(t);
        }
      }
      if (!got_hit) {
        std::fprintf(stderr, "pixel (%d,%d): index %u at %g is no hit of the float test\n", x, y, got, double(px.depth[pixel]));
        std::abort();
      }
      if (got != best_tri && !(best_tri != cullkit::NciPixels::miss && touching[best_tri])) {
        std::fprintf(stderr, "pixel (%d,%d): index %u, brute force %u\n", x, y, got, best_tri);
        std::abort();
      }
    }
  }
  return 0;
}
