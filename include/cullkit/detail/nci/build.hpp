// cullkit/detail/nci/build.hpp: the build of a NormalClassIndex from its valid triangles: grid,
// normal classes, per-class cells and grids, internal numbering, flat arrays and narrow forms.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <array>
#include <atomic>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "triangle_bvh.hpp"
#include "kmeans.hpp"
#include "overlap.hpp"
#include "../bits.hpp"
#include "../parallel.hpp"
#include "core.hpp"
#include "index_data.hpp"
#include "tolerances.hpp"

namespace cullkit::detail::nci {

// ---------------------------------------------------------------- build

// One class's cells and grids, with offsets local to the class.
struct ClassGrids {
  std::vector<std::uint32_t> cell_tri_begin{0};
  std::vector<std::uint32_t> cell_tris;
  std::vector<std::uint32_t> slice_rows[3];  // dims[a] + 1 entries: row ranges per slice
  std::vector<std::uint16_t> row_coord[3];
  std::vector<std::uint32_t> row_begin[3];   // one per row (no sentinel; the next row's begin ends it)
  std::vector<std::uint16_t> cell_col[3];
  std::vector<std::uint32_t> cell_id[3];
};

// `corners`: the three corners of tris[i] at 3 i, 3 i + 1 and 3 i + 2.
inline void build_class(const IndexData& data, const std::uint32_t* tris, const glm::vec3* corners, std::size_t count,
                        ClassGrids& out) {
  struct Pair {
    std::uint64_t key;
    std::uint32_t place;  // Morton code of the centroid (clamped into the cell) within the cell
    std::uint32_t tri;
  };
  std::vector<Pair> pairs;
  pairs.reserve(count + count / 2);
  const std::uint64_t ny = static_cast<std::uint64_t>(data.dims[1]), nz = static_cast<std::uint64_t>(data.dims[2]);
  const double half[3] = {0.5 * data.h + data.delta, 0.5 * data.h + data.delta, 0.5 * data.h + data.delta};
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t tri = tris[i];
    double v[3][3];
    double mn[3], mx[3];
    for (std::size_t k = 0; k < 3; ++k) {
      const glm::vec3& p = corners[3 * i + k];
      for (int a = 0; a < 3; ++a) v[k][a] = p[a];
    }
    int c0[3], c1[3];
    for (int a = 0; a < 3; ++a) {
      mn[a] = std::min({v[0][a], v[1][a], v[2][a]});
      mx[a] = std::max({v[0][a], v[1][a], v[2][a]});
      c0[a] = data.cell_of(mn[a] - data.delta, a);
      c1[a] = data.cell_of(mx[a] + data.delta, a);
    }
    const bool single = c0[0] == c1[0] && c0[1] == c1[1] && c0[2] == c1[2];
    for (int x = c0[0]; x <= c1[0]; ++x) {
      for (int y = c0[1]; y <= c1[1]; ++y) {
        for (int z = c0[2]; z <= c1[2]; ++z) {
          if (!single) {
            const double center[3] = {data.lo[0] + (x + 0.5) * data.h, data.lo[1] + (y + 0.5) * data.h, data.lo[2] + (z + 0.5) * data.h};
            if (!detail::triangle_box_overlap(center, half, v)) continue;
          }
          const std::uint64_t key = (static_cast<std::uint64_t>(x) * ny + static_cast<std::uint64_t>(y)) * nz +
                                    static_cast<std::uint64_t>(z);
          double u[3];
          const int cell[3] = {x, y, z};
          for (int a = 0; a < 3; ++a) {
            const double cen = (v[0][a] + v[1][a] + v[2][a]) / 3.0;
            u[a] = std::clamp((cen - (data.lo[a] + cell[a] * data.h)) / data.h, 0.0, 1.0);
          }
          pairs.push_back(Pair{key, detail::nci_morton(u), tri});
        }
      }
    }
  }
  // Pairs in (cell, place, triangle) order. When the grid has not many more cells than there are
  // pairs, by cell through a count per cell, then each cell's run by place and triangle: the same
  // order as one comparison sort of every pair, at a fraction of its cost on large classes.
  const auto by_place = [](const Pair& a, const Pair& b) {
    return a.place != b.place ? a.place < b.place : a.tri < b.tri;
  };
  const std::uint64_t grid_cells = static_cast<std::uint64_t>(data.dims[0]) * ny * nz;
  if (grid_cells <= 4 * std::uint64_t{pairs.size()} + 1024) {
    std::vector<std::uint32_t> first(static_cast<std::size_t>(grid_cells) + 1, 0u);
    for (const Pair& q : pairs) ++first[static_cast<std::size_t>(q.key) + 1];
    for (std::size_t k = 1; k < first.size(); ++k) first[k] += first[k - 1];
    std::vector<Pair> by_cell(pairs.size());
    for (const Pair& q : pairs) by_cell[first[static_cast<std::size_t>(q.key)]++] = q;
    pairs.swap(by_cell);
    for (std::size_t b = 0, e = 0; b < pairs.size(); b = e) {
      for (e = b + 1; e < pairs.size() && pairs[e].key == pairs[b].key;) ++e;
      if (e - b > 1)
        std::sort(pairs.begin() + static_cast<std::ptrdiff_t>(b), pairs.begin() + static_cast<std::ptrdiff_t>(e), by_place);
    }
  } else {
    std::sort(pairs.begin(), pairs.end(),
              [&](const Pair& a, const Pair& b) { return a.key != b.key ? a.key < b.key : by_place(a, b); });
  }
  // Cells in (x, y, z) order.
  std::vector<std::uint64_t> cell_key;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (i == 0 || pairs[i].key != pairs[i - 1].key) {
      if (i > 0) out.cell_tri_begin.push_back(static_cast<std::uint32_t>(out.cell_tris.size()));
      cell_key.push_back(pairs[i].key);
    }
    out.cell_tris.push_back(pairs[i].tri);
  }
  if (!pairs.empty()) out.cell_tri_begin.push_back(static_cast<std::uint32_t>(out.cell_tris.size()));
  pairs.clear();
  pairs.shrink_to_fit();
  const std::size_t cells = cell_key.size();
  std::vector<std::array<std::uint16_t, 3>> coord(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    const std::uint64_t k = cell_key[i];
    coord[i][2] = static_cast<std::uint16_t>(k % nz);
    coord[i][1] = static_cast<std::uint16_t>((k / nz) % ny);
    coord[i][0] = static_cast<std::uint16_t>(k / nz / ny);
  }
  std::vector<std::uint32_t> order(cells);
  for (std::size_t a = 0; a < 3; ++a) {
    const std::size_t b = (a + 1) % 3, c = (a + 2) % 3;
    for (std::size_t i = 0; i < cells; ++i) order[i] = static_cast<std::uint32_t>(i);
    if (a != 0) {
      std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
        const auto& u = coord[p];
        const auto& w = coord[q];
        if (u[a] != w[a]) return u[a] < w[a];
        if (u[b] != w[b]) return u[b] < w[b];
        return u[c] < w[c];
      });
    }
    auto& slice_rows = out.slice_rows[a];
    slice_rows.assign(static_cast<std::size_t>(data.dims[a]) + 1, 0u);
    std::size_t i = 0;
    for (int s = 0; s < data.dims[a]; ++s) {
      slice_rows[static_cast<std::size_t>(s)] = static_cast<std::uint32_t>(out.row_coord[a].size());
      while (i < cells && coord[order[i]][a] == s) {
        const std::uint16_t row = coord[order[i]][b];
        out.row_coord[a].push_back(row);
        out.row_begin[a].push_back(static_cast<std::uint32_t>(out.cell_col[a].size()));
        while (i < cells && coord[order[i]][a] == s && coord[order[i]][b] == row) {
          out.cell_col[a].push_back(coord[order[i]][c]);
          out.cell_id[a].push_back(order[i]);
          ++i;
        }
      }
    }
    slice_rows[static_cast<std::size_t>(data.dims[a])] = static_cast<std::uint32_t>(out.row_coord[a].size());
  }
}

// The grid: cubic cells, `grid` along the longest axis.
inline void make_grid(IndexData& data) {
  const glm::dvec3 lo(data.box.min), hi(data.box.max);
  const glm::dvec3 ext = hi - lo;
  const double longest = std::max({ext.x, ext.y, ext.z});
  data.h = longest > 0 ? longest / data.params.grid : 1.0;
  for (int a = 0; a < 3; ++a) {
    int d = std::max(1, static_cast<int>(std::ceil(ext[a] / data.h)));
    while (lo[a] + d * data.h < hi[a]) ++d;
    data.dims[a] = std::min(d, 65535);
    data.stats.dims[a] = data.dims[a];
  }
  data.stats.cell_size = data.h;
  data.lo = lo;
  const double max_abs = std::max({std::fabs(lo.x), std::fabs(lo.y), std::fabs(lo.z), std::fabs(hi.x),
                                   std::fabs(hi.y), std::fabs(hi.z)});
  data.delta = std::max(1e-3 * data.h, 64.0 * double(std::numeric_limits<float>::epsilon()) * max_abs);
}

// Normal classes (spherical k-means), then each class's axis as the mean of its members and the
// cone around it. Returns each kept triangle's class (in gathering order); frees `normals`.
inline std::vector<std::uint16_t> make_classes(IndexData& data, std::vector<glm::vec3>& normals) {
  const std::size_t n = data.tri_original.size();
  std::vector<std::uint16_t> class_of;  // kept triangle (input order) -> class
  {
    std::vector<std::uint32_t> cls;
    detail::cluster_normals(normals, data.params.classes, data.params.seed, cls, data.class_axis);
    class_of.assign(cls.begin(), cls.end());  // at most 4096 classes: 16 bits
  }
  const std::size_t classes = data.class_axis.size();
  data.stats.classes = classes;
  {
    // Recompute each axis as the mean of its members and measure the cone around it.
    std::vector<glm::dvec3> sum(classes, glm::dvec3(0.0));
    for (std::size_t i = 0; i < n; ++i) sum[class_of[i]] += glm::dvec3(normals[i]);
    for (std::size_t c = 0; c < classes; ++c) {
      const double len = glm::length(sum[c]);
      if (len > 1e-9) data.class_axis[c] = glm::vec3(sum[c] / len);
    }
    std::vector<double> min_dot(classes, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
      const double d = glm::dot(glm::dvec3(normals[i]), glm::dvec3(data.class_axis[class_of[i]]));
      min_dot[class_of[i]] = std::min(min_dot[class_of[i]], d);
    }
    data.class_sin.resize(classes);
    data.class_cos.resize(classes);
    for (std::size_t c = 0; c < classes; ++c) {
      // Half-angle plus a margin for the float normals and the float ray test.
      const double angle = std::acos(std::clamp(min_dot[c], -1.0, 1.0)) + tolerance::cone_angle;
      if (angle >= 1.5707963267948966) {
        data.class_sin[c] = 2.0f;  // never skipped
        data.class_cos[c] = 0.0f;
      } else {
        data.class_sin[c] = static_cast<float>(std::sin(angle));
        data.class_cos[c] = static_cast<float>(std::cos(angle));
      }
    }
  }
  normals.clear();
  normals.shrink_to_fit();
  return class_of;
}

// Per class: cells by separating axes, then the three grids. Classes in parallel, merged in
// class order so the index does not depend on the thread count.
// `class_begin` and `by_class` list the kept triangles class by class.
inline void build_class_grids(const IndexData& data, const std::vector<std::uint16_t>& class_of,
                              std::vector<std::uint32_t>& class_begin, std::vector<std::uint32_t>& by_class,
                              std::vector<ClassGrids>& parts) {
  const std::size_t n = class_of.size(), classes = data.class_axis.size();
  class_begin.assign(classes + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++class_begin[class_of[i] + 1];
  for (std::size_t c = 0; c < classes; ++c) class_begin[c + 1] += class_begin[c];
  by_class.resize(n);
  // Each triangle's corners beside it in class order: a class's pass then reads them in order,
  // where reading them through the vertex ids would miss the cache on nearly every triangle of a
  // large mesh (a class's triangles lie scattered over the mesh's arrays).
  std::vector<glm::vec3> corners(3 * n);
  {
    std::vector<std::uint32_t> fill(class_begin.begin(), class_begin.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t at = fill[class_of[i]]++;
      by_class[at] = static_cast<std::uint32_t>(i);
      for (std::size_t k = 0; k < 3; ++k) corners[3 * std::size_t{at} + k] = data.vertices[data.tri_vertices[3 * i + k]];
    }
  }
  parts.resize(classes);
  std::atomic<std::size_t> next{0}, done{0};
  const unsigned build_threads = detail::resolve_threads(data.params.build_threads, std::min<std::size_t>(classes, 64));
  // Task 0 reports progress (on the building thread unless the caller's task runner puts it elsewhere).
  auto work = [&](bool reporter) {
    for (;;) {
      const std::size_t c = next.fetch_add(1, std::memory_order_relaxed);
      if (c >= classes) break;
      build_class(data, by_class.data() + class_begin[c], corners.data() + 3 * std::size_t{class_begin[c]},
                  class_begin[c + 1] - class_begin[c], parts[c]);
      const std::size_t d = done.fetch_add(1) + 1;
      if (reporter) report(data, 0.2f + 0.7f * static_cast<float>(d) / static_cast<float>(classes));
    }
  };
  using Work = decltype(work);
  detail::run_tasks(data.params.task_runner, build_threads,
                    [](void* job, std::size_t task) { (*static_cast<Work*>(job))(task == 0); }, &work);
}

// Calls body(b, e) over consecutive blocks [b, e) of `block` items covering [0, n), on the build's
// threads (the caller's task runner or the pool): for passes whose items are independent.
template <class Body>
void for_blocks(const IndexData& data, std::size_t n, std::size_t block, const Body& body) {
  const std::size_t blocks = (n + block - 1) / block;
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t k = next.fetch_add(1, std::memory_order_relaxed); k < blocks; k = next.fetch_add(1, std::memory_order_relaxed))
      body(k * block, std::min(n, (k + 1) * block));
  };
  using Work = decltype(work);
  detail::run_tasks(data.params.task_runner, detail::resolve_threads(data.params.build_threads, blocks),
                    [](void* job, std::size_t) { (*static_cast<Work*>(job))(); }, &work);
}

// The hash of a position's bits (`bits` receives them) for the vertex merge.
inline std::uint64_t position_hash(const glm::vec3& p, std::uint32_t bits[3]) noexcept {
  std::memcpy(bits, &p, 3 * sizeof(std::uint32_t));
  const std::uint64_t h = (std::uint64_t{bits[0]} * 0x9E3779B97F4A7C15ull) ^ (std::uint64_t{bits[1]} * 0xC2B2AE3D27D4EB4Full) ^
                          (std::uint64_t{bits[2]} * 0x165667B19E3779F9ull);
  return h ^ (h >> 29);
}

// A vertex in a bucket of the merge: its position's bits and its id.
struct BucketVertex {
  std::uint32_t bits[3];
  std::uint32_t id;
};

// Per vertex of `list` (ascending ids, one bucket), canon[id] becomes the id of the first vertex of
// the list with bitwise the same position, through an open-addressing table; returns how many are
// their own. A table entry holds a list position and the upper half of the hash, so that most probes
// settle without reading a position. `table` is scratch.
inline std::size_t merge_bucket(const BucketVertex* list, std::size_t count, std::vector<std::uint64_t>& table,
                                std::uint32_t* canon) {
  std::size_t size = 16;
  while (size < 2 * count) size *= 2;
  constexpr std::uint64_t vacant = ~std::uint64_t{0};
  table.assign(size, vacant);
  std::size_t distinct = 0;
  for (std::size_t v = 0; v < count; ++v) {
    std::uint32_t b[3];
    glm::vec3 p;
    std::memcpy(&p, list[v].bits, sizeof p);
    const std::uint64_t hash = position_hash(p, b);
    const std::uint64_t tag = hash >> 32 << 32;
    for (std::size_t at = static_cast<std::size_t>(hash) & (size - 1);; at = (at + 1) & (size - 1)) {
      const std::uint64_t entry = table[at];
      if (entry == vacant) {
        table[at] = tag | v;
        canon[list[v].id] = list[v].id;
        ++distinct;
        break;
      }
      if ((entry >> 32 << 32) != tag) continue;
      const BucketVertex& other = list[static_cast<std::uint32_t>(entry)];
      if (other.bits[0] == b[0] && other.bits[1] == b[1] && other.bits[2] == b[2]) {
        canon[list[v].id] = other.id;
        break;
      }
    }
  }
  return distinct;
}

// Per vertex, the first vertex with bitwise the same position (itself when none comes before it);
// `distinct` counts the vertices that are their own. Equal positions have equal hashes, so the
// vertices are first scattered into buckets by the hash's top bits (each bucket in ascending ids),
// then each bucket is merged on its own, on the build's threads: a bucket's table stays in cache,
// where one table over every vertex would miss on almost every probe.
inline std::vector<std::uint32_t> canonical_vertices(const IndexData& data, const std::vector<glm::vec3>& vertices,
                                                     std::size_t& distinct) {
  const std::size_t count = vertices.size();
  std::vector<std::uint32_t> canon(count);
  distinct = 0;
  if (count == 0) return canon;
  int bucket_bits = 0;
  while (bucket_bits < 12 && (count >> 14 >> bucket_bits) > 0) ++bucket_bits;
  const std::size_t buckets = std::size_t{1} << bucket_bits;
  const auto bucket_of = [&](std::size_t v) {
    std::uint32_t b[3];
    return bucket_bits == 0 ? std::size_t{0} : static_cast<std::size_t>(position_hash(vertices[v], b) >> (64 - bucket_bits));
  };
  // Per block of vertices, its count per bucket; then each (bucket, block) pair's first place.
  constexpr std::size_t block = std::size_t{1} << 16;
  const std::size_t blocks = (count + block - 1) / block;
  std::vector<std::size_t> place(blocks * buckets + 1, 0);  // bucket-major: [bucket][block]
  for_blocks(data, count, block, [&](std::size_t b, std::size_t e) {
    std::size_t* mine = place.data() + b / block;
    for (std::size_t v = b; v < e; ++v) ++mine[bucket_of(v) * blocks];
  });
  std::size_t sum = 0;
  for (std::size_t& p : place) {
    const std::size_t c = p;
    p = sum;
    sum += c;
  }
  // Every entry is written below: left uninitialized (zeroing it first took a tenth of the merge
  // on a 3.3M-vertex forest).
  const std::unique_ptr<BucketVertex[]> list(new BucketVertex[count]);
  for_blocks(data, count, block, [&](std::size_t b, std::size_t e) {
    std::vector<std::size_t> at(buckets);
    for (std::size_t k = 0; k < buckets; ++k) at[k] = place[k * blocks + b / block];
    for (std::size_t v = b; v < e; ++v) {
      BucketVertex& out = list[at[bucket_of(v)]++];
      std::memcpy(out.bits, &vertices[v], sizeof out.bits);
      out.id = static_cast<std::uint32_t>(v);
    }
  });
  std::atomic<std::size_t> own{0};
  for_blocks(data, buckets, 1, [&](std::size_t b, std::size_t e) {
    std::vector<std::uint64_t> table;
    for (std::size_t k = b; k < e; ++k) {
      const std::size_t first = place[k * blocks], last = place[(k + 1) * blocks];
      own += merge_bucket(list.get() + first, last - first, table, canon.data());
    }
  });
  distinct = own.load();
  return canon;
}

// Internal numbering (memory locality of the select walk): class by class, each class's
// triangles in the order their first cell comes in its X grid, so a cell's triangles are
// mostly one run of consecutive ids (and so are their vertices and per-thread records).
// data.tri_original maps back to the mesh; cell lists are rewritten and sorted in the new ids.
inline void renumber(IndexData& data, const std::vector<std::uint16_t>& class_of,
                     const std::vector<std::uint32_t>& class_begin, const std::vector<std::uint32_t>& by_class,
                     std::vector<ClassGrids>& parts) {
  const std::size_t n = data.tri_original.size(), classes = data.class_axis.size();
  {
    std::vector<std::uint32_t> new_id(n, no_triangle), order;
    order.reserve(n);
    data.class_tri_begin.assign(classes + 1, 0u);
    for (std::size_t c = 0; c < classes; ++c) {
      data.class_tri_begin[c] = static_cast<std::uint32_t>(order.size());
      for (std::uint32_t old : parts[c].cell_tris) {
        if (new_id[old] == no_triangle) {
          new_id[old] = static_cast<std::uint32_t>(order.size());
          order.push_back(old);
        }
      }
      for (std::uint32_t k = class_begin[c]; k < class_begin[c + 1]; ++k) {  // in no cell (never met)
        if (new_id[by_class[k]] == no_triangle) {
          new_id[by_class[k]] = static_cast<std::uint32_t>(order.size());
          order.push_back(by_class[k]);
        }
      }
    }
    // The classes' cell lists in the new ids, class by class on the build's threads.
    for_blocks(data, classes, 1, [&](std::size_t c, std::size_t) {
      auto& p = parts[c];
      for (auto& e : p.cell_tris) e = new_id[e];
      for (std::size_t k = 0; k + 1 < p.cell_tri_begin.size(); ++k)
        std::sort(p.cell_tris.begin() + p.cell_tri_begin[k], p.cell_tris.begin() + p.cell_tri_begin[k + 1]);
    });
    data.class_tri_begin[classes] = static_cast<std::uint32_t>(n);
    // Triangles, their mesh numbers and vertices in the new order; vertices renumbered by first
    // use and merged when their positions are bitwise equal (OBJ files often repeat a position
    // per normal or texture coordinate).
    std::size_t distinct = 0;
    const std::vector<std::uint32_t> canon = canonical_vertices(data, data.vertices, distinct);
    // Per-slot storage (corner k of triangle t at 3 t + k, no ids) when it takes no more bytes than
    // distinct vertices and their ids: meshes of unshared triangles, such as foliage.
    const std::size_t id_bytes = distinct <= 65536 ? 2 : 4;
    data.slot_vertices = 36 * n <= 12 * distinct + 3 * n * id_bytes;
    std::vector<glm::vec3> vertices;
    std::vector<std::uint32_t> tri_vertices(data.slot_vertices ? 0 : 3 * n), tri_original(n);
    if (data.slot_vertices) {
      // Each triangle's own corners: independent, so on the build's threads (a vertex and its
      // canonical one hold bitwise the same position).
      vertices.resize(3 * n);
      // The reads are scattered over the mesh: each triangle's ids are fetched 16 triangles
      // ahead, its corners and mesh number 8 ahead, so the misses overlap.
      for_blocks(data, n, std::size_t{1} << 16, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          if (k + 16 < e) detail::prefetch(&data.tri_vertices[3 * std::size_t{order[k + 16]}]);
          if (k + 8 < e) {
            detail::prefetch(&data.vertices[data.tri_vertices[3 * std::size_t{order[k + 8]}]]);
            detail::prefetch(&data.tri_original[order[k + 8]]);
          }
          const std::uint32_t old = order[k];
          tri_original[k] = data.tri_original[old];
          for (std::size_t j = 0; j < 3; ++j) vertices[3 * k + j] = data.vertices[data.tri_vertices[3 * old + j]];
        }
      });
    } else {
      std::vector<std::uint32_t> vmap(data.vertices.size(), no_triangle);
      vertices.reserve(distinct);
      for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t old = order[k];
        tri_original[k] = data.tri_original[old];
        for (std::size_t j = 0; j < 3; ++j) {
          const std::uint32_t v = canon[data.tri_vertices[3 * old + j]];
          if (vmap[v] == no_triangle) {
            vmap[v] = static_cast<std::uint32_t>(vertices.size());
            vertices.push_back(data.vertices[v]);
          }
          tri_vertices[3 * k + j] = vmap[v];
        }
      }
    }
    data.class_of.assign(data.stats.triangles_input, skipped_class);
    for (std::size_t i = 0; i < n; ++i) data.class_of[data.tri_original[i]] = class_of[i];
    data.vertices = std::move(vertices);
    data.tri_vertices = std::move(tri_vertices);
    data.tri_original = std::move(tri_original);
    data.wide_tris = false;
    for (std::size_t c = 0; c < classes; ++c) data.wide_tris = data.wide_tris || data.class_tri_begin[c + 1] - data.class_tri_begin[c] > 65536;
  }
}

// The classes' grids merged into the flat arrays, class after class (each part freed once
// copied). Returns, per class, one past its last cell entry.
inline std::vector<std::uint32_t> flatten(IndexData& data, std::vector<ClassGrids>& parts) {
  const std::size_t classes = data.class_axis.size();
  std::size_t total_cells = 0, total_entries = 0, total_rows = 0, total_grid_cells = 0, total_slices = 0;
  data.wide_ids = false;
  for (const auto& p : parts) {
    total_cells += p.cell_tri_begin.size() - 1;
    data.wide_ids = data.wide_ids || p.cell_tri_begin.size() - 1 > 65536;
    total_entries += p.cell_tris.size();
    for (int a = 0; a < 3; ++a) {
      total_rows += p.row_coord[a].size();
      total_grid_cells += p.cell_col[a].size();
      total_slices += p.slice_rows[a].size();
    }
  }
  data.stats.cells = total_cells;
  data.stats.cell_entries = total_entries;
  data.cell_tri_begin.reserve(total_cells + 1);
  if (data.wide_tris) data.cell_tris.reserve(total_entries);
  else data.cell_tris16.reserve(total_entries);
  data.slice_rows.reserve(total_slices);
  data.row_coord.reserve(total_rows);
  data.row_begin.reserve(total_rows + 1);
  data.cell_col.reserve(total_grid_cells);
  if (data.wide_ids) data.cell_id.reserve(total_grid_cells - total_cells);
  else data.cell_id16.reserve(total_grid_cells - total_cells);
  data.class_cell_base.reserve(classes);
  data.grid_base.reserve(classes * 3);
  data.grid_shift.reserve(classes * 3);
  data.cell_tri_begin.push_back(0);
  std::vector<std::uint32_t> class_entry_end;  // per class: one past its last cell entry
  class_entry_end.reserve(classes);
  for (std::size_t c = 0; c < classes; ++c) {
    auto& p = parts[c];
    const std::uint32_t cell_base = static_cast<std::uint32_t>(data.cell_tri_begin.size() - 1);
    data.class_cell_base.push_back(data.wide_ids ? 0u : cell_base);
    const std::uint32_t entry_base = static_cast<std::uint32_t>(data.wide_tris ? data.cell_tris.size() : data.cell_tris16.size());
    for (std::size_t k = 1; k < p.cell_tri_begin.size(); ++k) data.cell_tri_begin.push_back(entry_base + p.cell_tri_begin[k]);
    if (data.wide_tris) {
      data.cell_tris.insert(data.cell_tris.end(), p.cell_tris.begin(), p.cell_tris.end());
    } else {
      for (std::uint32_t t : p.cell_tris) data.cell_tris16.push_back(static_cast<std::uint16_t>(t - data.class_tri_begin[c]));
    }
    class_entry_end.push_back(static_cast<std::uint32_t>(data.wide_tris ? data.cell_tris.size() : data.cell_tris16.size()));
    for (int a = 0; a < 3; ++a) {
      data.grid_base.push_back(static_cast<std::uint32_t>(data.slice_rows.size()));
      const std::uint32_t row_base = static_cast<std::uint32_t>(data.row_coord.size());
      const std::uint32_t col_base = static_cast<std::uint32_t>(data.cell_col.size());
      for (std::uint32_t s : p.slice_rows[a]) data.slice_rows.push_back(row_base + s);
      data.row_coord.insert(data.row_coord.end(), p.row_coord[a].begin(), p.row_coord[a].end());
      for (std::uint32_t b : p.row_begin[a]) data.row_begin.push_back(col_base + b);
      data.cell_col.insert(data.cell_col.end(), p.cell_col[a].begin(), p.cell_col[a].end());
      if (a == 0) {
        // The X grid lists the class's cells in id order: the id is the position, shifted.
        data.grid_shift.push_back(col_base - cell_base);
      } else {
        // Y and Z grids: the class's own cell number, in 16 bits when every class has at most
        // 65536 cells (2 bytes per grid cell saved), else the global cell in 32 bits.
        if (data.wide_ids) {
          data.grid_shift.push_back(col_base - static_cast<std::uint32_t>(data.cell_id.size()));
          for (std::uint32_t id : p.cell_id[a]) data.cell_id.push_back(cell_base + id);
        } else {
          data.grid_shift.push_back(col_base - static_cast<std::uint32_t>(data.cell_id16.size()));
          for (std::uint32_t id : p.cell_id[a]) data.cell_id16.push_back(static_cast<std::uint16_t>(id));
        }
      }
    }
    p = ClassGrids{};
  }
  data.row_begin.push_back(static_cast<std::uint32_t>(data.cell_col.size()));
  return class_entry_end;
}

// Chunk boxes when cells are crowded (mean entries per cell >= data.chunk_min_mean): one box
// per data.chunk consecutive entries (chunks cut the entry array at fixed positions, so a chunk
// may span two cells: its box bounds both parts). A tile skips a chunk lying wholly outside
// its beam instead of meeting its triangles one by one.
inline void make_chunk_boxes(IndexData& data, const std::vector<std::uint32_t>& class_entry_end) {
  const std::size_t classes = data.class_axis.size(), total_cells = data.stats.cells, total_entries = data.stats.cell_entries;
  if (total_cells > 0 && total_entries >= data.chunk_min_mean * total_cells) {
    const std::size_t chunks = (total_entries + data.chunk - 1) / data.chunk;
    data.chunk_box.assign(6 * chunks, 0.0f);
    std::size_t e = 0;
    for (std::size_t c = 0; c < classes; ++c) {
      const std::size_t e_end = class_entry_end[c];
      for (; e < e_end; ++e) {
        const std::uint32_t tri = data.entry_triangle(static_cast<std::uint32_t>(e), static_cast<std::uint32_t>(c));
        float* box = &data.chunk_box[6 * (e / data.chunk)];
        for (int k = 0; k < 3; ++k) {
          const glm::vec3& q = data.corner(tri, k);
          for (int a = 0; a < 3; ++a) {
            if (e % data.chunk == 0 && k == 0) {
              box[a] = q[a];
              box[3 + a] = q[a];
            }
            box[a] = std::min(box[a], q[a]);
            box[3 + a] = std::max(box[3 + a], q[a]);
          }
        }
      }
    }
  }
}

// Narrow forms: 16-bit vertex ids when there are at most 65536 vertices; cell entry ranges
// in 16 bits relative to their class when every class has at most 65535 entries (one extra
// end per class: class k's cells c read ranges at c + k and c + k + 1).
// The triangle hierarchy over every kept triangle (internal ids), its subtrees built on the worker pool.
inline void make_frame_hierarchy(IndexData& data) {
  const std::size_t n = data.triangle_count();
  std::vector<TriangleBvhItem> items(n);
  for_blocks(data, n, std::size_t{1} << 16, [&](std::size_t first, std::size_t end) {
    for (std::size_t i = first; i < end; ++i) {
      const std::uint32_t tri = static_cast<std::uint32_t>(i);
      const glm::vec3 &a = data.corner(tri, 0), &b = data.corner(tri, 1), &c = data.corner(tri, 2);
      for (int k = 0; k < 3; ++k) {
        items[i].lo[k] = std::min({a[k], b[k], c[k]});
        items[i].hi[k] = std::max({a[k], b[k], c[k]});
      }
    }
  });
  TriangleBvhBuilder builder(items, detail::resolve_threads(data.params.build_threads, 16), data.params.task_runner);
  builder.traversal_cost = frame_traversal_cost;
  data.bvh = builder.build();
  data.bvh.nodes.shrink_to_fit();
  if (data.slot_vertices) {
    // Per-slot corners move into the leaves' order (IndexData::vertices), on the build's threads.
    std::vector<glm::vec3> vertices(data.vertices.size());
    data.tri_slot.assign(n, 0u);
    for_blocks(data, n, std::size_t{1} << 16, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p) {
        if (p + 8 < e) {  // scattered reads and writes: fetched ahead so the misses overlap
          detail::prefetch(&data.vertices[3 * std::size_t{data.bvh.tris[p + 8]}]);
          detail::prefetch(&data.tri_slot[data.bvh.tris[p + 8]]);
        }
        const std::uint32_t tri = data.bvh.tris[p];
        data.tri_slot[tri] = static_cast<std::uint32_t>(p);
        for (std::size_t k = 0; k < 3; ++k) vertices[3 * p + k] = data.vertices[3 * std::size_t{tri} + k];
      }
    });
    data.vertices = std::move(vertices);
  }
}

inline void narrow_forms(IndexData& data) {
  const std::size_t classes = data.class_axis.size(), total_cells = data.stats.cells;
  if (!data.slot_vertices && data.vertices.size() <= 65536) {
    data.tri_vertices16.assign(data.tri_vertices.begin(), data.tri_vertices.end());
    std::vector<std::uint32_t>().swap(data.tri_vertices);
  }
  {
    bool narrow = !data.wide_ids;  // data.class_cell_base holds each class's first cell
    for (std::size_t c = 0; c < classes && narrow; ++c) {
      const std::uint32_t first = data.class_cell_base[c];
      const std::uint32_t last = c + 1 < classes ? data.class_cell_base[c + 1] : static_cast<std::uint32_t>(total_cells);
      narrow = data.cell_tri_begin[last] - data.cell_tri_begin[first] <= 65535u;
    }
    if (narrow) {
      data.class_entry_base.resize(classes);
      data.cell_begin16.reserve(total_cells + classes);
      for (std::size_t c = 0; c < classes; ++c) {
        const std::uint32_t first = data.class_cell_base[c];
        const std::uint32_t last = c + 1 < classes ? data.class_cell_base[c + 1] : static_cast<std::uint32_t>(total_cells);
        data.class_entry_base[c] = data.cell_tri_begin[first];
        for (std::uint32_t cell = first; cell <= last; ++cell)
          data.cell_begin16.push_back(static_cast<std::uint16_t>(data.cell_tri_begin[cell] - data.cell_tri_begin[first]));
      }
      std::vector<std::uint32_t>().swap(data.cell_tri_begin);
    }
  }
}

#if CULLKIT_CORE_BODIES
// The steps above, in order (declared in core.hpp).
CULLKIT_CORE_FN void build(IndexData& data, std::vector<glm::vec3>& normals) {
  data.stats.triangles_indexed = data.tri_original.size();
  report(data, 0.1f);
  if (data.tri_original.empty()) {
    std::vector<glm::vec3>().swap(data.vertices);  // the gathering's reserved room
    std::vector<std::uint32_t>().swap(data.tri_vertices);
    std::vector<std::uint32_t>().swap(data.tri_original);
    data.class_of.assign(data.stats.triangles_input, skipped_class);
    report(data, 1.0f);
    return;
  }
  make_grid(data);
  const std::vector<std::uint16_t> class_of = make_classes(data, normals);
  report(data, 0.2f);
  std::vector<std::uint32_t> class_begin, by_class;
  std::vector<ClassGrids> parts;
  build_class_grids(data, class_of, class_begin, by_class, parts);
  renumber(data, class_of, class_begin, by_class, parts);
  const std::vector<std::uint32_t> class_entry_end = flatten(data, parts);
  make_chunk_boxes(data, class_entry_end);
  narrow_forms(data);
  report(data, 0.9f);
  // The hierarchy serves only the cast: an index fixed to the walk never reads it (tri_slot stays
  // empty, so per-slot corners stay in internal order).
  if (data.params.crowded_path != NciCrowdedPath::walk_only) make_frame_hierarchy(data);
  data.vertices.shrink_to_fit();
  data.tri_vertices.shrink_to_fit();
  data.tri_original.shrink_to_fit();
  data.class_of.shrink_to_fit();
  report(data, 1.0f);
}
#endif

}  // namespace cullkit::detail::nci
