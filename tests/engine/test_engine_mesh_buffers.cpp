// Every container that reads a mesh takes raw engine buffers (StridedMesh: positions through a
// pointer, an odd byte stride and an unaligned offset; 16- or 32-bit indices chosen at run time)
// and gives exactly what it gives for the same mesh as MeshView<glm::vec3, uint32_t> and
// MeshView<glm::vec3, uint16_t>: NormalClassIndex's per-pixel answers and sets, MeshOcclusionCuller's
// kept sets over many cameras, BspTree's fragments, corners and orders. Also: 16-bit indices out of
// range are skipped and counted like 32-bit ones, null buffers with non-zero counts are caught by
// the assertion hook and read as empty (the containers used to read through the null pointer),
// and a buffer read 4 bytes off is seen as a different mesh (the comparisons can fail).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

// Count broken preconditions instead of aborting, so that the release-build answer to them is
// what the test sees in every build type.
static int g_asserts = 0;
#define CULLKIT_ASSERT(condition, message) ((condition) ? (void)0 : (void)++g_asserts)

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"
#include "../nci/nci_test_util.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

// The scene's positions in an interleaved buffer: vertex v at byte 1 + v * 27, position at byte 5
// of it (so neither the vertex nor the position is 4-byte aligned); the other bytes are junk.
struct Interleaved {
  static constexpr std::size_t stride = 27, offset = 5;
  std::vector<unsigned char> bytes;
  std::vector<unsigned char> idx16, idx32;  // the indices at byte 1 of each buffer (unaligned)
  StridedMesh mesh16, mesh32;

  explicit Interleaved(const Scene& s) : bytes(1 + s.positions.size() * stride + 8, 0xCD) {
    for (std::size_t v = 0; v < s.positions.size(); ++v)
      std::memcpy(&bytes[1 + v * stride + offset], &s.positions[v], 3 * sizeof(float));
    idx16.assign(1 + 2 * s.indices.size(), 0);
    idx32.assign(1 + 4 * s.indices.size(), 0);
    for (std::size_t i = 0; i < s.indices.size(); ++i) {
      const auto i16 = static_cast<std::uint16_t>(s.indices[i]);
      std::memcpy(&idx16[1 + 2 * i], &i16, 2);
      std::memcpy(&idx32[1 + 4 * i], &s.indices[i], 4);
    }
    const StridedPositions pos{bytes.data() + 1, stride, offset};
    mesh16 = StridedMesh{pos, s.positions.size(), {idx16.data() + 1, s.indices.size(), IndexFormat::uint16}};
    mesh32 = StridedMesh{pos, s.positions.size(), {idx32.data() + 1, s.indices.size(), IndexFormat::uint32}};
  }
};

// ---------------------------------------------------------------- NormalClassIndex
struct NciAnswer {
  VisibleSet set;
  NciPixels pixels;
};

template <class Index>
std::vector<NciAnswer> nci_answers(const Index& index, const std::vector<Camera>& cams) {
  std::vector<NciAnswer> out(cams.size());
  NciContext ctx;
  for (std::size_t c = 0; c < cams.size(); ++c) index.select_visible(cams[c], ctx, out[c].set, &out[c].pixels);
  return out;
}

int nci_differences(const std::vector<NciAnswer>& a, const std::vector<NciAnswer>& b) {
  int diff = 0;
  for (std::size_t c = 0; c < a.size(); ++c)
    diff += a[c].set.triangles != b[c].set.triangles || a[c].pixels.triangle != b[c].pixels.triangle ||
            a[c].pixels.depth != b[c].pixels.depth;
  return diff;
}

bool same(const NciStats& a, const NciStats& b) {
  return a.triangles_input == b.triangles_input && a.triangles_indexed == b.triangles_indexed &&
         a.skipped_out_of_range == b.skipped_out_of_range && a.skipped_non_finite == b.skipped_non_finite &&
         a.skipped_degenerate == b.skipped_degenerate && a.classes == b.classes && a.cells == b.cells &&
         a.cell_entries == b.cell_entries;
}

void check_nci(const Scene& city, const Interleaved& buf) {
  const std::vector<Camera> cams = nci_test::cameras_for(city.bounds, 6, 96, 72, 777);
  std::vector<std::uint16_t> small(city.indices.begin(), city.indices.end());
  const NormalClassIndex<glm::vec3> plain(city.mesh());
  const auto want = nci_answers(plain, cams);
  std::size_t shown = 0;
  for (const auto& a : want) shown += a.set.triangles.size();
  CHECK(shown > 0);
  const NormalClassIndex<glm::vec3, std::uint16_t> narrow(
      MeshView<glm::vec3, std::uint16_t>{city.positions.data(), city.positions.size(), small.data(), small.size()});
  const NormalClassIndex s16(buf.mesh16);  // deduces NormalClassIndex<glm::vec3>
  const NormalClassIndex<glm::vec3> s32(buf.mesh32, NciParams{});
  for (const NciStats* st : {&narrow.stats(), &s16.stats(), &s32.stats()}) CHECK(same(*st, plain.stats()));
  CHECK_MSG(nci_differences(nci_answers(narrow, cams), want) == 0, "NCI: MeshView<uint16_t> differs");
  CHECK_MSG(nci_differences(nci_answers(s16, cams), want) == 0, "NCI: StridedMesh uint16 differs");
  CHECK_MSG(nci_differences(nci_answers(s32, cams), want) == 0, "NCI: StridedMesh uint32 differs");
  // Read 4 bytes off: another mesh, and the comparison sees it.
  StridedMesh off = buf.mesh16;
  off.positions.offset_bytes += 4;
  CHECK(nci_differences(nci_answers(NormalClassIndex<glm::vec3>(off), cams), want) > 0);
}

// ---------------------------------------------------------------- MeshOcclusionCuller
template <class Culler>
std::vector<std::vector<std::uint32_t>> moc_answers(const Culler& culler, const std::vector<Camera>& cams) {
  std::vector<std::vector<std::uint32_t>> out(cams.size());
  MeshOcclusionContext ctx;
  for (std::size_t c = 0; c < cams.size(); ++c) {
    culler.cull(cams[c], ctx, out[c]);
    std::sort(out[c].begin(), out[c].end());
  }
  return out;
}

bool same(const MeshOcclusionBuildStats& a, const MeshOcclusionBuildStats& b) {
  return a.triangles == b.triangles && a.triangles_unusable == b.triangles_unusable &&
         a.triangles_degenerate == b.triangles_degenerate && a.welded_vertices == b.welded_vertices &&
         a.shared_edges == b.shared_edges && a.objects == b.objects && a.objects_unusable == b.objects_unusable;
}

void check_moc(const Scene& city, const Interleaved& buf) {
  std::vector<MeshObject> objects;
  for (const auto& o : city.objects) objects.push_back(MeshObject{o.first_triangle, o.triangle_count});
  const std::vector<Camera> cams = nci_test::cameras_for(city.bounds, 40, 320, 240, 991);
  std::vector<std::uint16_t> small(city.indices.begin(), city.indices.end());
  const MeshOcclusionCuller<glm::vec3> plain(city.mesh(), objects.data(), objects.size());
  const auto want = moc_answers(plain, cams);
  std::size_t hidden_somewhere = 0;
  for (const auto& w : want) hidden_somewhere += w.size() < objects.size();
  CHECK(hidden_somewhere > 0);  // some camera culls something: the sets say something
  const MeshOcclusionCuller<glm::vec3, std::uint16_t> narrow(
      MeshView<glm::vec3, std::uint16_t>{city.positions.data(), city.positions.size(), small.data(), small.size()},
      objects.data(), objects.size());
  const MeshOcclusionCuller s16(buf.mesh16, objects.data(), objects.size());
  const MeshOcclusionCuller<glm::vec3> s32(buf.mesh32, objects.data(), objects.size(), MeshOcclusionParams{});
  for (const auto* st : {&narrow.stats(), &s16.stats(), &s32.stats()})
    CHECK(same(*st, plain.stats()));
  CHECK_MSG(moc_answers(narrow, cams) == want, "MOC: MeshView<uint16_t> differs");
  CHECK_MSG(moc_answers(s16, cams) == want, "MOC: StridedMesh uint16 differs");
  CHECK_MSG(moc_answers(s32, cams) == want, "MOC: StridedMesh uint32 differs");
  StridedMesh off = buf.mesh32;
  off.positions.offset_bytes += 4;
  CHECK(moc_answers(MeshOcclusionCuller<glm::vec3>(off, objects.data(), objects.size()), cams) != want);
}

// ---------------------------------------------------------------- BspTree
template <class Tree>
bool same_tree(const Tree& a, const BspTree<glm::vec3>& b, const std::vector<glm::vec3>& eyes) {
  if (a.fragments().size() != b.fragments().size() || a.corners() != b.corners() ||
      a.barycentrics() != b.barycentrics())
    return false;
  for (std::size_t f = 0; f < a.fragments().size(); ++f) {
    const BspFragment &x = a.fragments()[f], &y = b.fragments()[f];
    if (x.triangle != y.triangle || x.first_corner != y.first_corner || x.corner_count != y.corner_count) return false;
  }
  std::vector<std::uint32_t> oa, ob;
  for (const glm::vec3& eye : eyes) {
    a.back_to_front(eye, oa);
    b.back_to_front(eye, ob);
    if (oa != ob) return false;
  }
  return true;
}

void check_bsp(const Scene& scene, const Interleaved& buf) {
  support::Rng rng(55);
  std::vector<glm::vec3> eyes;
  for (int k = 0; k < 20; ++k)
    eyes.push_back(scene.bounds.min + glm::vec3(rng.uniform(-0.2f, 1.2f), rng.uniform(-0.2f, 1.2f),
                                                rng.uniform(-0.2f, 1.2f)) * scene.bounds.extent());
  std::vector<std::uint16_t> small(scene.indices.begin(), scene.indices.end());
  BspParams params;
  params.threads = 1;
  const BspTree<glm::vec3> plain(scene.mesh(), params);
  CHECK(plain.validate());
  CHECK(plain.stats().cuts > 0);  // the scene has cut fragments: corners and barycentrics matter
  const BspTree<glm::vec3, std::uint16_t> narrow(
      MeshView<glm::vec3, std::uint16_t>{scene.positions.data(), scene.positions.size(), small.data(), small.size()},
      params);
  const BspTree s16(buf.mesh16, params);
  const BspTree<glm::vec3> s32(buf.mesh32);
  CHECK_MSG(same_tree(narrow, plain, eyes), "BSP: MeshView<uint16_t> differs");
  CHECK_MSG(same_tree(s16, plain, eyes), "BSP: StridedMesh uint16 differs");
  CHECK_MSG(same_tree(s32, plain, eyes), "BSP: StridedMesh uint32 differs (default threads)");
  StridedMesh off = buf.mesh16;
  off.positions.offset_bytes += 4;
  CHECK(!same_tree(BspTree<glm::vec3>(off, params), plain, eyes));
}

// ---------------------------------------------------------------- bad input
// 16-bit indices past the vertex count (65535 and vertex_count itself) are skipped and counted.
void check_out_of_range(const Scene& scene) {
  std::vector<std::uint16_t> bad(scene.indices.begin(), scene.indices.end());
  bad[0] = 65535;                                             // triangle 0
  bad[7] = static_cast<std::uint16_t>(scene.positions.size());  // triangle 2
  std::vector<unsigned char> pos(scene.positions.size() * 12);
  std::memcpy(pos.data(), scene.positions.data(), pos.size());
  const StridedMesh m{{pos.data(), 12, 0}, scene.positions.size(), {bad.data(), bad.size(), IndexFormat::uint16}};
  glm::vec3 p[3];
  CHECK(!triangle_positions(m, 0, p) && !triangle_positions(m, 2, p) && triangle_positions(m, 1, p));
  const NormalClassIndex<glm::vec3> nci(m);
  CHECK(nci.stats().skipped_out_of_range == 2);
  CHECK(nci.triangle_class(0) == -1 && nci.triangle_class(2) == -1 && nci.triangle_class(1) >= 0);
  const MeshObject whole{0, static_cast<std::uint32_t>(scene.triangle_count())};
  const MeshOcclusionCuller<glm::vec3> moc(m, &whole, 1);
  CHECK(moc.stats().triangles_unusable == 2);
  const BspTree<glm::vec3> bsp(m);
  CHECK(bsp.stats().dropped_bad_index == 2);
  for (const BspFragment& f : bsp.fragments()) CHECK(f.triangle != 0 && f.triangle != 2);
}

// Null buffers with non-zero counts: the precondition is reported, and the mesh is read as empty.
void check_null(const Scene& scene) {
  const std::vector<Camera> cams = nci_test::cameras_for(scene.bounds, 1, 32, 24, 5);
  const StridedMesh no_positions{{nullptr, 12, 0}, 100, {scene.indices.data(), 30, IndexFormat::uint32}};
  const StridedMesh no_indices{{reinterpret_cast<const unsigned char*>(scene.positions.data()), 12, 0}, 100,
                               {nullptr, 30, IndexFormat::uint16}};
  const MeshView<glm::vec3> view_no_vertices{nullptr, 100, scene.indices.data(), 30};
  const MeshView<glm::vec3> view_no_indices{scene.positions.data(), 100, nullptr, 30};
  int before = g_asserts;
  for (const StridedMesh& m : {no_positions, no_indices}) {
    const NormalClassIndex<glm::vec3> nci(m);
    CHECK(nci.triangle_count() == 0 && nci.select_visible(cams[0]).triangles.empty());
    const MeshOcclusionCuller<glm::vec3> moc(m, nullptr, 0);
    CHECK(moc.object_count() == 0);
    const BspTree<glm::vec3> bsp(m);
    CHECK(bsp.fragments().empty());
  }
  for (const MeshView<glm::vec3>& m : {view_no_vertices, view_no_indices}) {
    const NormalClassIndex<glm::vec3> nci(m);
    CHECK(nci.triangle_count() == 0);
    const MeshOcclusionCuller<glm::vec3> moc(m, nullptr, 0);
    CHECK(moc.object_count() == 0);
    const BspTree<glm::vec3> bsp(m);
    CHECK(bsp.fragments().empty());
  }
  CHECK_MSG(g_asserts - before >= 12, "every null buffer reported (%d)", g_asserts - before);
}

}  // namespace

int main() {
  static_assert(index_size(IndexFormat::uint16) == 2 && index_size(IndexFormat::uint32) == 4, "index widths");
  const Scene city = support::make_city(1, 8);
  CHECK(city.positions.size() <= 65535);
  const Interleaved buf(city);
  check_nci(city, buf);
  check_moc(city, buf);
  const Scene small = support::make_office(3, 1, 1);
  const Interleaved small_buf(small);
  check_bsp(small, small_buf);
  check_out_of_range(small);
  check_null(small);
  return cullkit_test::report("test_engine_mesh_buffers");
}
