// libFuzzer target for PortalGraph: bytes -> a row of box rooms along X (some stacked in Y), portals
// on their shared faces (convex polygons from bytes, or raw float garbage: NaN, inf, too many or too
// few corners, bad cell indices), budgets, an eye and a perspective view. Checks the answer's shape
// (first entry the eye's cell with the frustum's planes, cells in range), then traces rays room by
// room through the portal polygons and requires every sampled point inside the frustum to be inside
// an entry of its room. Any violation calls __builtin_trap().
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include <cullkit/portal_graph.hpp>

using namespace cullkit;

namespace {

#define FUZZ_REQUIRE(cond)         \
  do {                             \
    if (!(cond)) __builtin_trap(); \
  } while (0)

class Reader {
 public:
  Reader(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  std::uint8_t byte() { return pos_ < n_ ? d_[pos_++] : 0; }
  float unit() { return static_cast<float>(byte()) / 255.0f; }
  float raw_float() {
    std::uint8_t b[4] = {byte(), byte(), byte(), byte()};
    float f;
    std::memcpy(&f, b, 4);
    return f;
  }

 private:
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
};

constexpr float kRoom = 4.0f;  // rooms are 4 x 3 x 4, room i at x in [4i, 4i + 4]

struct Portal {
  std::uint32_t a, b;
  std::vector<glm::vec3> corners;
  bool convex_on_face;  // a genuine convex polygon on the shared face x = 4(a + 1)
  bool open = false;    // the graph could not use the polygon: it lets every ray through
};

Aabb room_box(std::uint32_t i) {
  return Aabb{glm::vec3(kRoom * static_cast<float>(i), 0.0f, 0.0f), glm::vec3(kRoom * static_cast<float>(i + 1), 3.0f, kRoom)};
}

// Is p (on the plane x = const) inside the convex polygon (either winding, inclusive)?
bool in_polygon(const std::vector<glm::vec3>& q, const glm::dvec3& p) {
  double sign = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const glm::dvec3 a(q[i]), b(q[(i + 1) % q.size()]);
    const double cr = (b.y - a.y) * (p.z - a.z) - (b.z - a.z) * (p.y - a.y);
    if (cr == 0.0) continue;
    if (sign == 0.0) sign = cr;
    else if ((cr > 0) != (sign > 0)) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(data, size);
  const std::uint32_t rooms = 1 + in.byte() % 6;
  PortalParams params;
  params.max_views_per_cell = 1 + in.byte() % 8;
  params.max_views = 1 + in.byte() % 64;
  PortalGraph graph(params);
  for (std::uint32_t i = 0; i < rooms; ++i) graph.set_cell_bounds(graph.add_cell(), room_box(i));
  std::vector<Portal> portals;
  const int count = in.byte() % 12;
  for (int k = 0; k < count; ++k) {
    const std::uint8_t mode = in.byte();
    Portal p{in.byte() % (rooms + 1), 0, {}, false};
    p.b = p.a + 1;
    if (mode % 4 == 0) {  // garbage: raw floats, any corner count, any cells
      const int n = in.byte() % 20;
      for (int i = 0; i < n; ++i) p.corners.push_back(glm::vec3(in.raw_float(), in.raw_float(), in.raw_float()));
      p.b = in.byte() % (rooms + 2);
    } else {  // a convex polygon on the shared face: corners on an ellipse at increasing angles
      const int n = 3 + in.byte() % 14;
      const float cy = 0.3f + 2.4f * in.unit(), cz = 0.3f + 3.4f * in.unit();
      const float ry = 0.05f + 0.25f * in.unit(), rz = 0.05f + 0.25f * in.unit();
      const float x = kRoom * static_cast<float>(p.a + 1);
      for (int i = 0; i < n; ++i) {
        const float t = 6.2831853f * (static_cast<float>(i) + 0.9f * in.unit()) / static_cast<float>(n);
        p.corners.push_back(glm::vec3(x, cy + ry * std::cos(t), cz + rz * std::sin(t)));
      }
      if (mode & 4) std::vector<glm::vec3>(p.corners.rbegin(), p.corners.rend()).swap(p.corners);
      p.convex_on_face = p.b < rooms;
    }
    const std::uint32_t id = graph.add_portal(p.a, p.b, p.corners.data(), p.corners.size());
    p.open = id != PortalGraph::no_portal && !graph.portal_usable(id);
    portals.push_back(std::move(p));
  }
  // The eye: in a room (or anywhere, raw), looking anywhere, near plane 0.01 to 5.
  const bool raw_eye = in.byte() % 8 == 0;
  const std::uint32_t eye_room = in.byte() % rooms;
  const Aabb box = room_box(eye_room);
  const glm::vec3 eye = raw_eye ? glm::vec3(in.raw_float(), in.raw_float(), in.raw_float())
                                : box.min + (box.max - box.min) * glm::vec3(in.unit(), in.unit(), in.unit());
  const glm::vec3 dir(in.unit() - 0.5f + 0.6f, in.unit() - 0.5f, in.unit() - 0.5f);
  const float near_plane = 0.01f + 5.0f * in.unit();
  const glm::mat4 proj = glm::perspective(glm::radians(20.0f + 140.0f * in.unit()), 1.0f + in.unit(), near_plane, 100.0f);
  const glm::mat4 view = glm::lookAt(eye, eye + dir, glm::vec3(0, 1, 0));
  const glm::mat4 vp = proj * view;
  const Frustum frustum = Frustum::from_matrix(vp);
  const std::uint32_t eye_cell = raw_eye ? graph.locate_cell(eye) : eye_room;
  std::vector<PortalView> views;
  PortalScratch scratch;
  graph.visible_cells(eye_cell, eye, frustum, views, scratch);
  for (const PortalView& v : views) FUZZ_REQUIRE(v.cell < rooms);
  if (eye_cell < rooms && std::isfinite(eye.x) && std::isfinite(eye.y) && std::isfinite(eye.z)) {
    FUZZ_REQUIRE(!views.empty() && views[0].cell == eye_cell);
    FUZZ_REQUIRE(views[0].volume.plane_count() == ConvexVolume(frustum).plane_count());
  } else {
    FUZZ_REQUIRE(views.size() == rooms);
    return 0;
  }
  if (raw_eye) return 0;
  // Rays through the frustum, traced room by room along X.
  const glm::dmat4 inv = glm::inverse(glm::dmat4(vp));
  for (int r = 0; r < 16; ++r) {
    const glm::dvec4 far_point = inv * glm::dvec4(2.0 * in.unit() - 1.0, 2.0 * in.unit() - 1.0, 1.0, 1.0);
    glm::dvec3 d = glm::dvec3(far_point) / far_point.w - glm::dvec3(eye);
    if (!(glm::length(d) > 0.0)) continue;
    d /= glm::length(d);
    std::uint32_t cell = eye_room;
    double t0 = 0.0;
    for (int step = 0; step < 8; ++step) {
      const Aabb b = room_box(cell);
      double t1 = 1e9;
      int axis = -1;
      for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0) continue;
        const double t = ((d[a] > 0 ? b.max[a] : b.min[a]) - eye[a]) / d[a];
        if (t < t1) { t1 = t; axis = a; }
      }
      t1 = std::fmax(t1, t0);
      for (int k = 0; k <= 4; ++k) {
        const glm::dvec3 p = glm::dvec3(eye) + d * (t0 + (t1 - t0) * 0.25 * k);
        bool inside_frustum = true;
        for (int i = 0; i < Frustum::max_planes; ++i)
          if (frustum.has_plane(i) &&
              glm::dot(glm::dvec3(frustum.plane(i).normal), p) + static_cast<double>(frustum.plane(i).d) < 1e-3)
            inside_frustum = false;
        if (!inside_frustum) continue;
        bool covered = false;
        for (const PortalView& v : views) covered = covered || (v.cell == cell && v.volume.contains(glm::vec3(p)));
        FUZZ_REQUIRE(covered);
      }
      if (axis != 0) break;
      const std::uint32_t next = d.x > 0 ? cell + 1 : cell - 1;
      if ((d.x < 0 && cell == 0) || next >= rooms) break;
      const glm::dvec3 x = glm::dvec3(eye) + d * t1;
      bool through = false;
      for (const Portal& p : portals) {
        if (!((p.a == cell && p.b == next) || (p.a == next && p.b == cell))) continue;
        // An open portal lets every ray through; a face polygon only its inside. A usable polygon
        // anywhere else is no hole in this face.
        through = through || p.open || (p.convex_on_face && in_polygon(p.corners, x));
      }
      if (!through) break;
      cell = next;
      t0 = t1;
    }
  }
  return 0;
}
