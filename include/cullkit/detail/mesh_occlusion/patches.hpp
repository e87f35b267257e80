// cullkit/detail/mesh_occlusion/patches.hpp: objects cut into surface patches at build time.
//
// Why: a big object (a terrain, a house of thousands of triangles) is either all occluder or none
// when occluders are whole objects, and a budget then skips it whole, though the part of it in
// front of the eye would hide most of the view. And one box for a big or L-shaped object is a poor
// stand-in for it in the object test. A patch is a run of at most `patch_triangles` triangles of
// one object, grown breadth-first over shared edges from a seed, so it is edge-connected and compact;
// occluders are chosen patch by patch, and an object is hidden when the boxes of all its patches
// are. Fusion across patch borders needs nothing more: the coverage grid cancels every edge used by
// two inserted triangles, whichever patch they came from.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/ext/vector_double3.hpp>

#include "../../geometry/aabb.hpp"
#include "../../mesh_occlusion_params.hpp"
#include "tjunctions.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// A patch: triangles patch_triangles[first, first + count) of the index, all of `object`.
struct Patch {
  std::uint32_t first;
  std::uint32_t count;
  std::uint32_t object;
  Aabb box;
};

/// The patches of all usable objects. Object o's patches are patches[object_first[o],
/// object_first[o + 1]). Triangles that can never be seen or occlude (degenerate, corner[3t] ==
/// none) belong to no patch, so an object of only such triangles has none.
struct PatchSet {
  std::vector<Patch> patches;
  std::vector<std::uint32_t> triangles;     // grouped by patch
  std::vector<std::uint32_t> object_first;  // object_count + 1 entries
  // Per patch, 1 when one of its triangles is also in another patch (objects that overlap): only
  // such patches need a frame's check that a triangle goes in once.
  std::vector<std::uint8_t> shares_triangles;
  // Per patch, the box of its triangles' corners and of the whole triangles its cut parts come from
  // (its triangles' keys in a frame's sort reach the whole's corners); `box` when it holds no part.
  std::vector<Aabb> key_box;
  std::uint32_t largest = 0;  // the most triangles of any patch
  // The welded corners of patch p's triangles, and of the whole triangles its cut parts come from,
  // each once: vertices[vertex_first[p], vertex_first[p + 1]). A frame projects its occluders' corners
  // from these lists.
  std::vector<std::uint32_t> vertex_first, vertices;
  // Per triangle, which of its edges' twins a frame must look up: bit k when edge k's twin may be
  // in the same patch (a run's shared edges, insert_run), bit 3 + k when it may be in another
  // (the seams with earlier patches, insert_strip_in_order). A triangle and twin each in one patch
  // are in the same or not; one in several patches sets both bits; an edge with no twin, neither.
  std::vector<std::uint8_t> twin_reach;
};

/// Bits of PatchSet::twin_reach: edges whose twin may be in the triangle's own patch, or in another.
inline constexpr unsigned twin_in_patch = 0x7u, twin_elsewhere = 0x38u;

/// Cuts the objects into patches. `corners` (3 per triangle, none for triangles that cannot occlude)
/// and `twins` (the opposite directed edge or none) are the index's; `objects[o].triangle_count` is 0
/// for unusable objects. Slots past `user_count` are parts of cut triangles (`parts`, see
/// tjunctions.hpp): they belong to the objects of their user triangle, and each is seeded right after
/// it. O(triangles), allocates.
inline void build_patches(PatchSet& set, const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& corners,
                          const std::vector<std::uint32_t>& twins, const std::vector<MeshObject>& objects,
                          std::uint32_t max_triangles, const TrianglePartsMap& parts, std::size_t user_count) {
  constexpr std::uint32_t none = 0xffffffffu;
  if (max_triangles == 0) max_triangles = 1;
  set.patches.clear();
  set.triangles.clear();
  set.object_first.assign(objects.size() + 1, 0);
  // owner[t] == o once triangle t is in a patch of object o (objects may overlap: a triangle of two
  // objects is in a patch of each).
  std::vector<std::uint32_t> owner(corners.size() / 3, none);
  std::vector<std::uint32_t> queue;
  for (std::size_t o = 0; o < objects.size(); ++o) {
    set.object_first[o] = static_cast<std::uint32_t>(set.patches.size());
    const std::uint32_t first = objects[o].first_triangle, end = first + objects[o].triangle_count;
    const auto object = static_cast<std::uint32_t>(o);
    const auto in_object = [&](std::uint32_t u) {
      const std::uint32_t t = parts.user_triangle(u, user_count);
      return t >= first && t < end;
    };
    // Seeds: each user triangle's slot, then the slots of its other parts.
    std::uint32_t next_user = first, part = 0, part_end = 0;
    for (;;) {
      std::uint32_t seed;
      if (part < part_end) {
        seed = static_cast<std::uint32_t>(user_count) + part++;
      } else if (next_user < end) {
        seed = next_user++;
        if (!parts.first.empty()) {
          part = parts.first[seed];
          part_end = parts.first[seed + 1];
        }
      } else {
        break;
      }
      if (corners[3 * std::size_t(seed)] == none || owner[seed] == object) continue;
      Patch p{static_cast<std::uint32_t>(set.triangles.size()), 0, object,
              Aabb{glm::vec3(std::numeric_limits<float>::infinity()), glm::vec3(-std::numeric_limits<float>::infinity())}};
      queue.clear();
      queue.push_back(seed);
      owner[seed] = object;
      // Breadth-first: the patch grows as a disc around its seed, so its box stays small.
      for (std::size_t head = 0; head < queue.size() && p.count < max_triangles; ++head) {
        const std::uint32_t t = queue[head];
        set.triangles.push_back(t);
        ++p.count;
        for (int k = 0; k < 3; ++k) p.box = merge(p.box, positions[corners[3 * std::size_t(t) + std::size_t(k)]]);
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t twin = twins[3 * std::size_t(t) + std::size_t(k)];
          if (twin == none) continue;
          const std::uint32_t u = twin / 3;
          if (!in_object(u) || owner[u] == object || corners[3 * std::size_t(u)] == none) continue;
          owner[u] = object;
          queue.push_back(u);
        }
      }
      // Queued but not taken: free again for a later seed.
      for (std::size_t i = p.count; i < queue.size(); ++i) owner[queue[i]] = none;
      set.patches.push_back(p);
    }
  }
  set.object_first[objects.size()] = static_cast<std::uint32_t>(set.patches.size());
  // Triangles in several patches, and the patches holding one.
  std::vector<std::uint8_t> patch_count(corners.size() / 3, 0);
  for (const std::uint32_t t : set.triangles)
    if (patch_count[t] < 2) ++patch_count[t];
  set.shares_triangles.assign(set.patches.size(), 0);
  set.key_box.resize(set.patches.size());
  set.largest = 0;
  set.vertex_first.assign(set.patches.size() + 1, 0);
  set.vertices.clear();
  std::vector<std::uint32_t> vertex_patch(positions.size(), none);
  const auto add_corners = [&](const std::uint32_t* c, std::uint32_t p) {
    for (int k = 0; k < 3; ++k)
      if (vertex_patch[c[k]] != p) {
        vertex_patch[c[k]] = p;
        set.vertices.push_back(c[k]);
      }
  };
  for (std::size_t p = 0; p < set.patches.size(); ++p) {
    const Patch& patch = set.patches[p];
    set.largest = std::max(set.largest, patch.count);
    const auto id = static_cast<std::uint32_t>(p);
    set.key_box[p] = patch.box;
    for (std::uint32_t k = patch.first; k < patch.first + patch.count; ++k) {
      const std::uint32_t t = set.triangles[k];
      if (patch_count[t] > 1) set.shares_triangles[p] = 1;
      add_corners(&corners[3 * std::size_t(t)], id);
      if (!parts.whole.empty() && parts.whole[t] != none) {
        const std::uint32_t* whole = &parts.whole_corners[3 * std::size_t(parts.whole[t])];
        for (int c = 0; c < 3; ++c) set.key_box[p] = merge(set.key_box[p], positions[whole[c]]);
        add_corners(whole, id);
      }
    }
    set.vertex_first[p + 1] = static_cast<std::uint32_t>(set.vertices.size());
  }
  // The patch of each triangle in exactly one (none for those in none or several).
  std::vector<std::uint32_t> only_patch(corners.size() / 3, none);
  for (std::size_t p = 0; p < set.patches.size(); ++p)
    for (std::uint32_t k = set.patches[p].first; k < set.patches[p].first + set.patches[p].count; ++k)
      if (patch_count[set.triangles[k]] == 1) only_patch[set.triangles[k]] = static_cast<std::uint32_t>(p);
  set.twin_reach.assign(corners.size() / 3, 0);
  for (std::size_t t = 0; t < corners.size() / 3; ++t) {
    if (patch_count[t] == 0) continue;
    unsigned reach = 0;
    for (unsigned k = 0; k < 3; ++k) {
      const std::uint32_t twin = twins[3 * t + k];
      if (twin == none) continue;
      const std::uint32_t a = only_patch[t], b = only_patch[twin / 3];
      const bool sure = a != none && b != none;
      if (!sure || a == b) reach |= 1u << k;
      if (!sure || a != b) reach |= 8u << k;
    }
    set.twin_reach[t] = static_cast<std::uint8_t>(reach);
  }
}

/// True when object o's usable triangles are exactly a closed, outward-wound surface on the faces of
/// its bounds (12 triangles, every edge paired within the object, every corner a box corner, each
/// triangle lying on a face and facing out) and the box has volume. Every ray into such a box meets
/// one of its front faces first, so the box is a solid: everything it hides is hidden by the object.
inline bool is_solid_box(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& corners,
                         const std::vector<std::uint32_t>& twins, const MeshObject& object, const Aabb& box) {
  constexpr std::uint32_t none = 0xffffffffu;
  if (!(box.max.x > box.min.x && box.max.y > box.min.y && box.max.z > box.min.z)) return false;
  const std::uint32_t first = object.first_triangle, end = first + object.triangle_count;
  int live = 0;
  for (std::uint32_t t = first; t < end; ++t) {
    const std::uint32_t* c = &corners[3 * std::size_t(t)];
    if (c[0] == none) continue;
    if (++live > 12) return false;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t twin = twins[3 * std::size_t(t) + std::size_t(k)];
      if (twin == none || twin / 3 < first || twin / 3 >= end) return false;
    }
    const glm::vec3 p[3] = {positions[c[0]], positions[c[1]], positions[c[2]]};
    for (const glm::vec3& q : p)
      for (int a = 0; a < 3; ++a)
        if (q[a] != box.min[a] && q[a] != box.max[a]) return false;
    // The face it lies on, and its winding: the normal points out of the box along that axis.
    const glm::dvec3 n = glm::cross(glm::dvec3(p[1]) - glm::dvec3(p[0]), glm::dvec3(p[2]) - glm::dvec3(p[0]));
    bool on_face = false;
    for (int a = 0; a < 3 && !on_face; ++a) {
      if (p[0][a] != p[1][a] || p[0][a] != p[2][a]) continue;
      on_face = p[0][a] == box.max[a] ? n[a] > 0.0 : n[a] < 0.0;
    }
    if (!on_face) return false;
  }
  return live == 12;
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
