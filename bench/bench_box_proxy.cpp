// BoxProxy construction rate: the 27-region table (cullkit::make_box_proxy) against a brute-force
// outline (find the front faces by plane tests, count their edges, chain the edges used once into a
// loop, orient it by its Newell normal), on the same random boxes and eyes (every eye outside its
// box, regions mixed). CSV on stdout (race.hpp); proxies per second on stderr.
//   ./build/release/bench/bench_box_proxy
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <cullkit/box_proxy.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"

using namespace cullkit;

namespace {

// The generic silhouette of a convex polyhedron specialised to a box, written the obvious way a
// renderer without the table would: no region reasoning, just the definition.
std::size_t brute_force_outline(const Aabb& b, const glm::vec3& eye, glm::vec3 out[6]) {
  std::uint8_t uses[8][8] = {};
  int front = 0;
  for (int a = 0; a < 3; ++a) {
    const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
    for (int s = 0; s < 2; ++s) {
      const bool faces_eye = s ? eye[a] > b.max[a] : eye[a] < b.min[a];
      if (!faces_eye) continue;
      ++front;
      const int base = s << a;
      const int cyc[4] = {base, base | (1 << b1), base | (1 << b1) | (1 << b2), base | (1 << b2)};
      for (int k = 0; k < 4; ++k) {
        ++uses[cyc[k]][cyc[(k + 1) & 3]];
        ++uses[cyc[(k + 1) & 3]][cyc[k]];
      }
    }
  }
  if (front == 0) return 0;
  int start = -1;
  for (int u = 0; u < 8 && start < 0; ++u)
    for (int v = 0; v < 8; ++v)
      if (uses[u][v] == 1) {
        start = u;
        break;
      }
  int ids[6];
  std::size_t n = 0;
  int prev = -1, cur = start;
  while (n < 6) {
    ids[n++] = cur;
    int next = -1;
    for (int v = 0; v < 8; ++v)
      if (uses[cur][v] == 1 && v != prev) {
        next = v;
        break;
      }
    if (next < 0 || next == start) break;
    prev = cur;
    cur = next;
  }
  for (std::size_t i = 0; i < n; ++i) out[i] = corner(b, ids[i]);
  glm::vec3 normal(0.0f);
  for (std::size_t i = 0; i < n; ++i) normal += glm::cross(out[i], out[(i + 1) % n]);
  if (glm::dot(normal, eye - out[0]) < 0.0f) {
    for (std::size_t i = 1, j = n - 1; i < j; ++i, --j) std::swap(out[i], out[j]);
  }
  return n;
}

}  // namespace

int main() {
  const bool smoke = cullkit_bench::smoke();
  const std::size_t n = smoke ? 1000 : 200000;
  support::Rng rng(4004);
  std::vector<Aabb> boxes(n);
  std::vector<glm::vec3> eyes(n);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 c(rng.uniform(-500, 500), rng.uniform(0, 50), rng.uniform(-500, 500));
    const glm::vec3 h(rng.uniform(0.5f, 20), rng.uniform(0.5f, 40), rng.uniform(0.5f, 20));
    boxes[i] = Aabb{c - h, c + h};
    do {
      eyes[i] = glm::vec3(rng.uniform(-600, 600), rng.uniform(0, 100), rng.uniform(-600, 600));
    } while (contains(boxes[i], eyes[i]));
  }
  int by_count[7] = {};
  for (std::size_t i = 0; i < n; ++i) ++by_count[make_box_proxy(boxes[i], eyes[i]).corner_count];
  std::fprintf(stderr, "%zu boxes: %d with 4 outline corners, %d with 6\n", n, by_count[4], by_count[6]);

  // Both produce the same outlines (positions and order), checked once before timing.
  std::size_t differ = 0;
  for (std::size_t i = 0; i < n; ++i) {
    glm::vec3 a[6], b[6];
    const std::size_t na = box_silhouette(boxes[i], eyes[i], a);
    const std::size_t nb = brute_force_outline(boxes[i], eyes[i], b);
    bool same = false;
    for (std::size_t k = 0; na == nb && k < na && !same; ++k) {
      bool rotation = true;
      for (std::size_t j = 0; j < na && rotation; ++j) rotation = a[(j + k) % na] == b[j];
      same = rotation;
    }
    differ += !same;
  }
  std::fprintf(stderr, "outlines differing between table and brute force: %zu\n", differ);

  float sink = 0.0f;
  auto table = [&] {
    float s = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
      const BoxProxy p = make_box_proxy(boxes[i], eyes[i]);
      s += p.corners[p.corner_count - 1].x + p.faces[0].d;
    }
    sink += s;
  };
  auto table_outline_only = [&] {
    float s = 0.0f;
    glm::vec3 out[6];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = box_silhouette(boxes[i], eyes[i], out);
      s += out[k - 1].x;
    }
    sink += s;
  };
  auto brute = [&] {
    float s = 0.0f;
    glm::vec3 out[6];
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = brute_force_outline(boxes[i], eyes[i], out);
      s += out[k - 1].x;
    }
    sink += s;
  };
  const auto results = cullkit_bench::race("box_proxy_" + std::to_string(n),
                                           {{"brute_force_outline", brute},
                                            {"cullkit_box_silhouette_table", table_outline_only},
                                            {"cullkit_make_box_proxy_full", table}});
  for (const auto& r : results)
    std::fprintf(stderr, "%-30s %8.1f M proxies/s\n", r.name.c_str(), double(n) / r.median_ns * 1e3);
  cullkit_bench::keep(sink);
  return differ == 0 ? 0 : 1;
}
