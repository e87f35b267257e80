// NormalClassIndex from an engine's own buffers: positions read through a pointer and a byte
// stride (StridedPositions, an interleaved and unaligned vertex buffer) and 16-bit indices give
// the same index and the same per-pixel answers as the plain glm::vec3 / 32-bit mesh. The
// comparison is shown able to fail: a buffer read 4 bytes off gives different answers.
#include <cstdio>
#include <cstring>
#include <vector>

#include "check.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"

using namespace cullkit;
using cullkit::support::Scene;

namespace {

struct Answer {
  VisibleSet set;
  NciPixels pixels;
};

template <class IndexT>
std::vector<Answer> answers(const IndexT& index, const std::vector<Camera>& cams) {
  std::vector<Answer> out(cams.size());
  NciContext ctx;
  for (std::size_t c = 0; c < cams.size(); ++c) index.select_visible(cams[c], ctx, out[c].set, &out[c].pixels);
  return out;
}

int differences(const std::vector<Answer>& a, const std::vector<Answer>& b) {
  int diff = 0;
  for (std::size_t c = 0; c < a.size(); ++c)
    diff += a[c].set.triangles != b[c].set.triangles || a[c].set.triangles_tested != b[c].set.triangles_tested ||
            a[c].pixels.triangle != b[c].pixels.triangle || a[c].pixels.depth != b[c].pixels.depth;
  return diff;
}

bool same_stats(const NciStats& a, const NciStats& b) {
  return a.triangles_input == b.triangles_input && a.triangles_indexed == b.triangles_indexed &&
         a.skipped_out_of_range == b.skipped_out_of_range && a.skipped_non_finite == b.skipped_non_finite &&
         a.skipped_degenerate == b.skipped_degenerate && a.classes == b.classes && a.cells == b.cells &&
         a.cell_entries == b.cell_entries;
}

}  // namespace

int main() {
  const Scene city = support::make_city(1, 8);
  const std::vector<Camera> cams = nci_test::cameras_for(city.bounds, 5, 128, 96, 4242);
  const std::size_t vertex_count = city.positions.size();
  CHECK_MSG(vertex_count <= 65536, "the scene fits 16-bit indices (%zu vertices)", vertex_count);

  const nci_test::TestIndex<glm::vec3> plain(city.mesh());
  const std::vector<Answer> want = answers(plain, cams);
  std::size_t selected = 0;
  for (const auto& a : want) selected += a.set.triangles.size();
  CHECK(selected > 0);

  // Interleaved vertices of 28 bytes (uv, position, a pad), starting one byte into the buffer:
  // positions are neither 4-byte aligned nor packed.
  constexpr std::size_t stride = 28, offset = 9;
  std::vector<unsigned char> buffer(1 + vertex_count * stride + 16, 0xAB);
  for (std::size_t v = 0; v < vertex_count; ++v)
    std::memcpy(&buffer[1 + v * stride + 8], &city.positions[v], 3 * sizeof(float));
  const StridedPositions strided{buffer.data(), stride, offset};
  const nci_test::TestIndex<glm::vec3> from_buffer(strided, vertex_count, city.indices.data(), city.indices.size());
  CHECK(same_stats(from_buffer.stats(), plain.stats()));
  CHECK_MSG(differences(answers(from_buffer, cams), want) == 0, "strided positions answer differently");

  std::vector<std::uint16_t> small(city.indices.begin(), city.indices.end());
  const nci_test::TestIndex<glm::vec3, std::uint16_t> narrow(
      MeshView<glm::vec3, std::uint16_t>{city.positions.data(), vertex_count, small.data(), small.size()});
  CHECK(same_stats(narrow.stats(), plain.stats()));
  CHECK_MSG(differences(answers(narrow, cams), want) == 0, "16-bit indices answer differently");
  const nci_test::TestIndex<glm::vec3, std::uint16_t> both(strided, vertex_count, small.data(), small.size());
  CHECK(same_stats(both.stats(), plain.stats()));
  CHECK_MSG(differences(answers(both, cams), want) == 0, "strided positions with 16-bit indices answer differently");

  // A buffer read 4 bytes off (y, z and the pad as x, y, z) is another mesh: the comparison sees it.
  const nci_test::TestIndex<glm::vec3> shifted(StridedPositions{buffer.data(), stride, offset + 4}, vertex_count,
                                            city.indices.data(), city.indices.size());
  CHECK(differences(answers(shifted, cams), want) > 0);

  // 16-bit indices past the vertex count are skipped and counted, as 32-bit ones.
  std::vector<std::uint16_t> bad = small;
  bad[0] = 65535;
  bad[5] = static_cast<std::uint16_t>(vertex_count);
  const nci_test::TestIndex<glm::vec3, std::uint16_t> skipping(strided, vertex_count, bad.data(), bad.size());
  CHECK(skipping.stats().skipped_out_of_range == 2);
  CHECK(skipping.triangle_count() + 2 == plain.triangle_count());

  // No positions at all: an empty index that selects nothing.
  const nci_test::TestIndex<glm::vec3, std::uint16_t> empty(StridedPositions{nullptr, stride, 0}, 0, nullptr, 0);
  CHECK(empty.triangle_count() == 0);
  CHECK(empty.select_visible(cams[0]).triangles.empty());
  return cullkit_test::report("test_nci_mesh_input");
}
