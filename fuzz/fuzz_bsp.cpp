// fuzz_bsp: BspTree and order_back_to_front on arbitrary bytes.
// Input layout: byte 0 picks the vertex count (1..16) and byte 1 the triangle count (0..31); then
// vertices as raw floats (any bits: NaN, infinities, subnormals, huge values), indices as bytes
// (values past the vertex count are out of range), an eye as raw floats, and whatever is left as
// depth keys. Checks: the build never crashes; validate() holds; back_to_front lists every fragment
// once and front_to_back is its reverse; each fragment's barycentrics are finite; the depth order is
// the stable order of the contract (compared with std::stable_sort).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <cullkit/bsp_tree.hpp>
#include <cullkit/depth_sort.hpp>

namespace {

struct Reader {
  const std::uint8_t* data;
  std::size_t size, at = 0;
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
  float number() {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits |= std::uint32_t(byte()) << (8 * i);
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
};

void check_at(bool ok, int line) {
  if (!ok) {
    std::fprintf(stderr, "fuzz_bsp.cpp:%d: check failed\n", line);
    std::abort();
  }
}
#define check(ok) check_at((ok), __LINE__)

bool before(float a, float b) {
  const bool na = std::isnan(a), nb = std::isnan(b);
  if (na || nb) return na && !nb;
  return a > b;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const std::size_t vertex_count = 1 + in.byte() % 16;
  const std::size_t triangle_count = in.byte() % 32;
  std::vector<glm::vec3> v(vertex_count);
  for (auto& p : v) p = glm::vec3(in.number(), in.number(), in.number());
  std::vector<std::uint32_t> idx(3 * triangle_count);
  for (auto& i : idx) i = in.byte() % 20;
  const glm::vec3 eye(in.number(), in.number(), in.number());

  cullkit::BspParams params;
  params.threads = 1 + (size % 2);
  params.parallel_min_triangles = 4;
  params.candidates = 1 + static_cast<unsigned>(size % 5);
  const cullkit::BspTree<glm::vec3> tree(cullkit::MeshView<glm::vec3>{v.data(), v.size(), idx.data(), idx.size()},
                                         params);
  check(tree.validate());
  const auto& s = tree.stats();
  // Every input triangle is either dropped by one rule or has fragments.
  std::vector<std::uint8_t> has_fragment(s.triangles, 0);
  for (const auto& fr : tree.fragments()) {
    check(fr.triangle < s.triangles);
    if (fr.triangle < s.triangles) has_fragment[fr.triangle] = 1;
  }
  std::size_t with_fragments = 0;
  for (std::uint8_t h : has_fragment) with_fragments += h;
  check(with_fragments + s.dropped_bad_index + s.dropped_non_finite + s.dropped_degenerate == s.triangles);
  std::vector<std::uint32_t> order, reverse;
  tree.back_to_front(eye, order);
  tree.front_to_back(eye, reverse);
  check(order.size() == tree.fragments().size());
  std::vector<std::uint8_t> seen(order.size(), 0);
  for (std::uint32_t f : order) {
    check(f < seen.size() && !seen[f]);
    seen[f] = 1;
  }
  std::reverse(reverse.begin(), reverse.end());
  check(reverse == order);
  for (const auto& uv : tree.barycentrics()) check(std::isfinite(uv.x) && std::isfinite(uv.y));

  std::vector<float> depth;
  while (in.at + 4 <= in.size) depth.push_back(in.number());
  std::vector<std::uint32_t> sorted, want(depth.size());
  cullkit::order_back_to_front(depth.data(), depth.size(), sorted);
  for (std::size_t i = 0; i < want.size(); ++i) want[i] = static_cast<std::uint32_t>(i);
  std::stable_sort(want.begin(), want.end(), [&](std::uint32_t a, std::uint32_t b) { return before(depth[a], depth[b]); });
  check(sorted == want);
  return 0;
}
