// cullkit/detail/mesh_occlusion/index.hpp: what MeshOcclusionCuller builds: welded corners,
// opposite-edge pairs across the whole mesh, object bounds and the frustum tree.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/ext/vector_double3.hpp>

#include "../../adaptive_binary_tree.hpp"
#include "../../geometry/aabb.hpp"
#include "../../mesh_occlusion_params.hpp"
#include "patches.hpp"
#include "tjunctions.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

inline constexpr std::uint32_t none = 0xffffffffu;

/// The flat arrays a culler queries. Triangle t keeps its mesh number; a triangle that cannot
/// occlude (unusable or degenerate) has corner[3t] == none. A triangle cut at T-junctions keeps its
/// first part in its slot; its other parts follow the user's triangles (`parts`).
struct MeshIndex {
  std::size_t object_count = 0;
  MeshOcclusionBuildStats build_stats;
  std::vector<glm::vec3> positions;       // welded corner positions
  std::vector<std::uint32_t> corners;     // 3 per triangle slot: welded ids
  TrianglePartsMap parts;                 // slots past the user's triangles: parts of cut triangles
  std::vector<std::uint32_t> twins;       // 3 per triangle: the opposite directed edge (3u + l), or none
  std::vector<MeshObject> objects;        // clamped ranges (usable objects only are ever walked)
  std::vector<Aabb> bounds;               // per object; meaningful for usable objects only
  std::vector<std::uint32_t> tree_objects;  // tree position -> object
  std::vector<std::uint32_t> unusable;    // objects always reported visible
  AdaptiveBinaryTree<Aabb> tree;          // over the usable objects' bounds
  PatchSet patches;                       // the objects cut into surface patches
  std::vector<std::uint8_t> solid_box;    // per object: its triangles are a closed box (is_solid_box)
};

inline MeshOcclusionParams sanitize(MeshOcclusionParams p) {
  p.grid_width = std::clamp(p.grid_width, 8, 4096);
  p.grid_height = std::clamp(p.grid_height, 8, 4096);
  if (!(p.min_occluder_screen_fraction >= 0.0f)) p.min_occluder_screen_fraction = 0.0f;
  if (!(p.min_occluder_cells_per_triangle >= 0.0f)) p.min_occluder_cells_per_triangle = 0.0f;
  if (!(p.min_occluder_width_cells >= 0.0f)) p.min_occluder_width_cells = 0.0f;
  p.patch_triangles = std::clamp<std::uint32_t>(p.patch_triangles, 1, 65536);
  return p;
}

inline std::uint64_t mix64(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  x ^= x >> 33;
  return x;
}

inline std::size_t table_size_for(std::size_t n) {
  std::size_t size = 16;
  while (size < 2 * n + 16) size *= 2;
  return size;
}

/// Welds positions by exact float equality (+0 and -0 are one value), open addressing.
class PositionWelder {
 public:
  explicit PositionWelder(std::size_t expected) : slots_(table_size_for(expected), none) {}
  std::uint32_t id(const glm::vec3& p, std::vector<glm::vec3>& positions) {
    const glm::vec3 q = p + glm::vec3(0.0f);  // -0 becomes +0
    std::uint32_t bits[3];
    std::memcpy(bits, &q, sizeof bits);
    const std::uint64_t h = mix64((std::uint64_t(bits[0]) << 32 | bits[1]) ^ mix64(bits[2] + 0x9e3779b97f4a7c15ull));
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = h & mask;; i = (i + 1) & mask) {
      if (slots_[i] == none) {
        if (2 * (positions.size() + 1) > slots_.size()) {
          grow(positions);
          return id(p, positions);
        }
        slots_[i] = static_cast<std::uint32_t>(positions.size());
        positions.push_back(q);
        return slots_[i];
      }
      const glm::vec3& r = positions[slots_[i]];
      if (r.x == q.x && r.y == q.y && r.z == q.z) return slots_[i];
    }
  }

 private:
  void grow(const std::vector<glm::vec3>& positions) {
    std::vector<std::uint32_t> old;
    old.swap(slots_);
    slots_.assign(old.size() * 2, none);
    const std::size_t mask = slots_.size() - 1;
    for (std::uint32_t v : old) {
      if (v == none) continue;
      std::uint32_t bits[3];
      std::memcpy(bits, &positions[v], sizeof bits);
      const std::uint64_t h = mix64((std::uint64_t(bits[0]) << 32 | bits[1]) ^ mix64(bits[2] + 0x9e3779b97f4a7c15ull));
      std::size_t i = h & mask;
      while (slots_[i] != none) i = (i + 1) & mask;
      slots_[i] = v;
    }
  }
  std::vector<std::uint32_t> slots_;
};

/// Pairs the directed edges that `for_each_edge(visit)` visits (in its order, `count` of them, none
/// of them paired yet) among themselves: each (a, b) with the first unpaired (b, a) met before it.
/// Returns the pairs made.
template <class ForEachEdge>
std::size_t pair_listed_edges(const std::vector<std::uint32_t>& corners, std::vector<std::uint32_t>& twins,
                              std::size_t count, ForEachEdge&& for_each_edge) {
  struct Slot {
    std::uint64_t key;
    std::uint32_t edge;  // none: empty; dead: removed
  };
  constexpr std::uint32_t dead = none - 1;
  std::vector<Slot> table(table_size_for(count), Slot{0, none});
  const std::size_t mask = table.size() - 1;
  std::size_t pairs = 0;
  for_each_edge([&](std::uint32_t e) {
    const std::size_t t = e / 3, k = e % 3;
    const std::uint32_t a = corners[3 * t + k], b = corners[3 * t + (k + 1) % 3];
    const std::uint64_t opposite = std::uint64_t(b) << 32 | a;
    for (std::size_t i = mix64(opposite) & mask; table[i].edge != none; i = (i + 1) & mask) {
      if (table[i].edge != dead && table[i].key == opposite) {
        twins[e] = table[i].edge;
        twins[table[i].edge] = e;
        table[i].edge = dead;
        ++pairs;
        return;
      }
    }
    const std::uint64_t key = std::uint64_t(a) << 32 | b;
    std::size_t i = mix64(key) & mask;
    while (table[i].edge != none && table[i].edge != dead) i = (i + 1) & mask;
    table[i] = Slot{key, e};
  });
  return pairs;
}

/// Pairs every directed edge (a, b) with at most one edge (b, a) of another triangle, one to one,
/// so that the pair can cancel when both triangles occlude. Non-manifold edges pair greedily; the
/// unpaired rest simply stays on the outline (safe, only less fusion).
inline std::size_t pair_edges(const std::vector<std::uint32_t>& corners, std::vector<std::uint32_t>& twins) {
  const std::size_t edge_count = corners.size();
  twins.assign(edge_count, none);
  std::size_t live = 0;
  for (std::size_t t = 0; t < edge_count / 3; ++t) live += corners[3 * t] != none ? 3u : 0u;
  return pair_listed_edges(corners, twins, live, [&](auto&& visit) {
    for (std::size_t t = 0; t < edge_count / 3; ++t)
      if (corners[3 * t] != none)
        for (std::size_t k = 0; k < 3; ++k) visit(static_cast<std::uint32_t>(3 * t + k));
  });
}

/// After cut_tjunctions: the cut triangles' old pairs are undone, and the edges left unpaired (the
/// seams' and the parts') are paired among themselves. The pairs of uncut triangles stay as they
/// were, so this costs the unpaired edges, not the mesh. Returns the pairs now.
inline std::size_t pair_edges_after_cuts(const std::vector<std::uint32_t>& corners, std::vector<std::uint32_t>& twins,
                                         const TrianglePartsMap& parts, std::size_t pairs) {
  twins.resize(corners.size(), none);
  for (std::size_t t = 0; t < parts.whole.size() && t < parts.first.size() - 1; ++t) {
    if (parts.whole[t] == none) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t twin = twins[3 * t + k];
      if (twin == none) continue;
      twins[twin] = none;
      twins[3 * t + k] = none;
      --pairs;
    }
  }
  std::vector<std::uint32_t> open;
  for (std::size_t e = 0; e < corners.size(); ++e)
    if (twins[e] == none && corners[e - e % 3] != none) open.push_back(static_cast<std::uint32_t>(e));
  return pairs + pair_listed_edges(corners, twins, open.size(), [&](auto&& visit) {
           for (std::uint32_t e : open) visit(e);
         });
}

inline bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

/// The build after the triangles were read and welded (`index.positions`, `index.corners`, and per
/// triangle `unusable`: 1 unreadable, 2 degenerate): object bounds, edge pairs, solid boxes,
/// T-junction cuts, patches and the tree. A core entry point (CULLKIT_SEPARATE_CORE, config.hpp).
CULLKIT_CORE_FN void finish_index(MeshIndex& index, const std::vector<std::uint8_t>& unusable, std::size_t triangle_count,
                                  std::size_t kept, const MeshObject* objects, std::size_t object_count,
                                  const AbtParams& tree_params, std::uint32_t patch_triangles, bool cut);

#if CULLKIT_CORE_BODIES
CULLKIT_CORE_FN void finish_index(MeshIndex& index, const std::vector<std::uint8_t>& unusable, std::size_t triangle_count,
                                  std::size_t kept, const MeshObject* objects, std::size_t object_count,
                                  const AbtParams& tree_params, std::uint32_t patch_triangles, bool cut) {
  MeshOcclusionBuildStats& stats = index.build_stats;
  stats.triangles_unusable += triangle_count - kept;
  stats.welded_vertices = index.positions.size();

  // Object bounds (degenerate triangles included: they are drawn, if as nothing).
  index.objects.assign(objects, objects + object_count);
  index.bounds.assign(object_count, Aabb{glm::vec3(0.0f), glm::vec3(0.0f)});
  std::vector<Aabb> tree_bounds;
  for (std::size_t o = 0; o < object_count; ++o) {
    const std::uint64_t first = objects[o].first_triangle;
    const std::uint64_t end = first + objects[o].triangle_count;
    bool ok = objects[o].triangle_count > 0 && end <= kept;
    Aabb box{glm::vec3(std::numeric_limits<float>::infinity()), glm::vec3(-std::numeric_limits<float>::infinity())};
    for (std::uint64_t t = first; ok && t < end; ++t) {
      if (unusable[t] == 1) {
        ok = false;
        break;
      }
      for (int k = 0; k < 3; ++k) box = merge(box, index.positions[index.corners[3 * t + static_cast<std::size_t>(k)]]);
    }
    if (!ok || !is_valid(box)) {
      index.unusable.push_back(static_cast<std::uint32_t>(o));
      index.objects[o].triangle_count = 0;
      continue;
    }
    index.bounds[o] = box;
    index.tree_objects.push_back(static_cast<std::uint32_t>(o));
    tree_bounds.push_back(box);
  }
  stats.objects_unusable = index.unusable.size();
  // Degenerate triangles bound their object but never occlude; drop their corners now.
  for (std::size_t t = 0; t < kept; ++t)
    if (unusable[t] == 2) index.corners[3 * t] = index.corners[3 * t + 1] = index.corners[3 * t + 2] = none;
  stats.shared_edges = pair_edges(index.corners, index.twins);
  // Solid boxes are judged on the user's triangles (a box has no unpaired edge, so it is never cut).
  index.solid_box.assign(object_count, 0);
  for (std::size_t o = 0; o < object_count; ++o)
    if (index.objects[o].triangle_count > 0)
      index.solid_box[o] = is_solid_box(index.positions, index.corners, index.twins, index.objects[o], index.bounds[o]);
  const TjunctionCuts cuts =
      cut ? cut_tjunctions(index.positions, index.corners, index.twins, index.parts) : TjunctionCuts{};
  stats.tjunction_corners = cuts.corners_on_edges;
  stats.triangles_cut = cuts.triangles_cut;
  stats.triangle_parts_added = cuts.parts_added;
  if (cuts.triangles_cut > 0)
    stats.shared_edges = pair_edges_after_cuts(index.corners, index.twins, index.parts, stats.shared_edges);
  build_patches(index.patches, index.positions, index.corners, index.twins, index.objects, patch_triangles, index.parts,
                kept);
  index.tree = AdaptiveBinaryTree<Aabb>(tree_bounds.data(), tree_bounds.size(), tree_params);
}
#endif  // CULLKIT_CORE_BODIES

/// Fills `index`. `read(t, p)` reads triangle t's corners, false when an index is out of range.
/// `cut`: cut triangles at T-junctions (MeshOcclusionParams::cut_tjunctions).
template <class ReadTriangle>
void build_index(MeshIndex& index, std::size_t triangle_count, ReadTriangle&& read, const MeshObject* objects,
                 std::size_t object_count, const AbtParams& tree_params, std::uint32_t patch_triangles,
                 bool cut = true) {
  index = MeshIndex{};
  // Triangle numbers are 32-bit; a larger mesh keeps only what fits (the rest is unusable).
  const std::size_t kept = std::min<std::size_t>(triangle_count, none / 3 - 1);
  MeshOcclusionBuildStats& stats = index.build_stats;
  stats.triangles = triangle_count;
  stats.objects = object_count;
  index.object_count = object_count;
  index.corners.assign(3 * kept, none);
  std::vector<std::uint8_t> unusable(kept, 0);
  PositionWelder welder(kept);
  for (std::size_t t = 0; t < kept; ++t) {
    glm::vec3 p[3];
    if (!read(t, p) || !finite(p[0]) || !finite(p[1]) || !finite(p[2])) {
      unusable[t] = 1;
      ++stats.triangles_unusable;
      continue;
    }
    std::uint32_t id[3];
    for (int k = 0; k < 3; ++k) id[k] = welder.id(p[k], index.positions);
    // Exactly zero area (in double, from float input the cross product is nearly exact; a tiny
    // area is handled per frame by the screen-area test anyway).
    const glm::dvec3 a(p[0]), b(p[1]), c(p[2]);
    const glm::dvec3 n = glm::cross(b - a, c - a);
    if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2] || (n.x == 0.0 && n.y == 0.0 && n.z == 0.0)) {
      ++stats.triangles_degenerate;
      // Keep the corners for the object's bounds, but mark it as no occluder below.
      index.corners[3 * t] = id[0];
      index.corners[3 * t + 1] = id[1];
      index.corners[3 * t + 2] = id[2];
      unusable[t] = 2;
      continue;
    }
    for (int k = 0; k < 3; ++k) index.corners[3 * t + static_cast<std::size_t>(k)] = id[k];
  }
  finish_index(index, unusable, triangle_count, kept, objects, object_count, tree_params, patch_triangles, cut);
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
