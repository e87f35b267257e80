// tests/oracle/embree_oracle.cpp: the Embree 3 ground truth behind embree_oracle.hpp.
//
// One RTCGeometry per add_mesh/add_box call; a global triangle id is the geometry's first id plus
// Embree's primID. Front-face-only geometry carries an intersection filter that rejects hits seen
// from the back (and exactly edge-on), so the oracle follows the cullkit rule: a triangle is hit only
// when its corners run counter-clockwise as seen from the ray origin.
#include "embree_oracle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include <embree3/rtcore.h>

namespace cullkit::oracle {
namespace {

// The sign of Embree's geometric normal Ng, measured rather than assumed: test_oracle.cpp renders a
// quad wound counter-clockwise toward the eye (must be hit at every pixel) and the same quad wound
// the other way (must never be hit). With Embree 3.13 Ng comes out as the right-handed normal
// (v1 - v0) x (v2 - v0), so a front face (CCW seen from the eye, normal toward the eye) has
// dot(direction, Ng) < 0.
constexpr float kFrontSign = -1.0f;

void front_face_filter(const RTCFilterFunctionNArguments* args) {
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const float dx = RTCRayN_dir_x(args->ray, args->N, i);
    const float dy = RTCRayN_dir_y(args->ray, args->N, i);
    const float dz = RTCRayN_dir_z(args->ray, args->N, i);
    const float nx = RTCHitN_Ng_x(args->hit, args->N, i);
    const float ny = RTCHitN_Ng_y(args->hit, args->N, i);
    const float nz = RTCHitN_Ng_z(args->hit, args->N, i);
    // Double precision so that an edge-on face (dot exactly 0 in exact arithmetic) is not pushed
    // to either side by float rounding of the products.
    const double d = double(dx) * nx + double(dy) * ny + double(dz) * nz;
    if (!(kFrontSign * d > 0.0)) args->valid[i] = 0;
  }
}

bool finite3(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<std::uint32_t> first_ids;  // by geomID
  std::uint32_t total = 0;
  bool committed = false;
};

EmbreeScene::EmbreeScene() : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
}

EmbreeScene::~EmbreeScene() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

std::uint32_t EmbreeScene::add_mesh(const glm::vec3* positions, std::size_t vertex_count,
                                    const std::uint32_t* indices, std::size_t index_count, bool two_sided) {
  const std::uint32_t first = impl_->total;
  const std::size_t tris = index_count / 3;
  if (tris == 0) return first;
  impl_->committed = false;

  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // At least one vertex, so that a degenerate triangle has somewhere to sit.
  const std::size_t nv = std::max<std::size_t>(vertex_count, 1);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
  std::vector<bool> bad_vertex(nv, false);
  for (std::size_t i = 0; i < nv; ++i) {
    glm::vec3 p(0.0f);
    if (i < vertex_count && positions) {
      p = positions[i];
      if (!finite3(p)) {
        bad_vertex[i] = true;
        p = glm::vec3(0.0f);
      }
    }
    v[3 * i + 0] = p.x;
    v[3 * i + 1] = p.y;
    v[3 * i + 2] = p.z;
  }
  auto* idx = static_cast<std::uint32_t*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), tris));
  for (std::size_t t = 0; t < tris; ++t) {
    bool ok = indices != nullptr;
    for (int k = 0; ok && k < 3; ++k) {
      const std::uint32_t i = indices[3 * t + k];
      ok = i < vertex_count && !bad_vertex[i];
    }
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = ok ? indices[3 * t + k] : 0u;  // degenerate: never hit
  }
  if (!two_sided) rtcSetGeometryIntersectFilterFunction(geom, front_face_filter);
  const unsigned id = rtcAttachGeometry(impl_->scene, geom);
  rtcCommitGeometry(geom);
  rtcReleaseGeometry(geom);
  if (impl_->first_ids.size() <= id) impl_->first_ids.resize(id + 1, 0);
  impl_->first_ids[id] = first;
  impl_->total += static_cast<std::uint32_t>(tris);
  return first;
}

std::uint32_t EmbreeScene::add_box(const Aabb& box) {
  glm::vec3 c[8];
  for (int i = 0; i < 8; ++i) c[i] = corner(box, i);
  // Outward, counter-clockwise seen from outside. Corner bits: 1 = x, 2 = y, 4 = z.
  static constexpr std::uint32_t kIdx[36] = {
      0, 4, 6, 0, 6, 2,  // -x
      1, 3, 7, 1, 7, 5,  // +x
      0, 1, 5, 0, 5, 4,  // -y
      2, 6, 7, 2, 7, 3,  // +y
      0, 2, 3, 0, 3, 1,  // -z
      4, 5, 7, 4, 7, 6,  // +z
  };
  return add_mesh(c, 8, kIdx, 36, false);
}

void EmbreeScene::commit() {
  rtcCommitScene(impl_->scene);
  impl_->committed = true;
}

std::uint32_t EmbreeScene::triangle_count() const { return impl_->total; }

std::uint32_t EmbreeScene::first_hit(const Ray& ray, float* distance, float tfar) const {
  if (distance) *distance = std::numeric_limits<float>::infinity();
  const glm::vec3& d = ray.direction;
  if (!impl_->committed || !finite3(ray.origin) || !finite3(d) || (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f))
    return HitBuffer::miss;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = ray.origin.x;
  rh.ray.org_y = ray.origin.y;
  rh.ray.org_z = ray.origin.z;
  rh.ray.dir_x = d.x;
  rh.ray.dir_y = d.y;
  rh.ray.dir_z = d.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = tfar;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.ray.time = 0.0f;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return HitBuffer::miss;
  if (distance) *distance = rh.ray.tfar;
  return impl_->first_ids[rh.hit.geomID] + rh.hit.primID;
}

HitBuffer EmbreeScene::render(const Camera& camera, unsigned threads) const {
  HitBuffer out;
  out.width = std::max(camera.width, 0);
  out.height = std::max(camera.height, 0);
  const std::size_t n = static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height);
  out.triangle.assign(n, HitBuffer::miss);
  out.distance.assign(n, std::numeric_limits<float>::infinity());
  if (n == 0) return out;
  const PixelRays rays(camera);
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(out.height));
  auto work = [&](unsigned k) {
    // Interleaved rows: neighbouring rows cost about the same, so threads stay balanced.
    for (int y = static_cast<int>(k); y < out.height; y += static_cast<int>(threads)) {
      for (int x = 0; x < out.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * out.width + x;
        out.triangle[i] = first_hit(rays.ray(x, y), &out.distance[i], std::numeric_limits<float>::infinity());
      }
    }
  };
  if (threads <= 1) {
    work(0);
    return out;
  }
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  for (unsigned k = 1; k < threads; ++k) pool.emplace_back(work, k);
  work(0);
  for (auto& t : pool) t.join();
  return out;
}

std::vector<std::uint32_t> visible_triangles(const HitBuffer& hits) {
  std::vector<std::uint32_t> out;
  out.reserve(hits.triangle.size() / 4);
  for (std::uint32_t t : hits.triangle)
    if (t != HitBuffer::miss) out.push_back(t);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace cullkit::oracle
