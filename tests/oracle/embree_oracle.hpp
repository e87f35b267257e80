// tests/oracle/embree_oracle.hpp: the ground truth. Embree 3 casts one ray per pixel exactly as
// cullkit::Camera defines (cullkit::PixelRays), and reports each pixel's first-hit triangle and
// distance. Tests and benchmarks only; the library never depends on Embree.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>

namespace cullkit::oracle {

/// Per-pixel first hits, row-major from the top row.
struct HitBuffer {
  static constexpr std::uint32_t miss = 0xFFFFFFFFu;
  int width = 0, height = 0;
  std::vector<std::uint32_t> triangle;  ///< global triangle id (see EmbreeScene), or `miss`
  std::vector<float> distance;          ///< ray parameter t along the unit ray direction; +inf on miss
  [[nodiscard]] std::uint32_t at(int x, int y) const { return triangle[static_cast<std::size_t>(y) * width + x]; }
};

/// An Embree scene built from meshes and boxes. Triangle ids are global and dense, in the order
/// geometry was added: a mesh's triangles keep their order, a box adds 12 triangles.
class EmbreeScene {
 public:
  EmbreeScene();
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// Adds a triangle mesh; returns the global id of its first triangle. Triangles with indices
  /// out of range or non-finite corners are added as degenerate (never hit). `two_sided`: hit from
  /// both sides (occluder polygons); otherwise only from the front (counter-clockwise seen from
  /// the eye), the cullkit rule.
  std::uint32_t add_mesh(const glm::vec3* positions, std::size_t vertex_count,
                         const std::uint32_t* indices, std::size_t index_count, bool two_sided = false);
  /// Adds a closed box as 12 outward-facing triangles; returns the global id of the first.
  std::uint32_t add_box(const Aabb& box);
  /// Builds the BVH; call after adding geometry and before casting.
  void commit();
  [[nodiscard]] std::uint32_t triangle_count() const;

  /// One ray per pixel center by the cullkit::Camera rule; `threads` 0 means all hardware threads.
  [[nodiscard]] HitBuffer render(const Camera& camera, unsigned threads = 0) const;
  /// The first hit of one ray (t in [0, tfar]); `miss` if none.
  [[nodiscard]] std::uint32_t first_hit(const Ray& ray, float* distance = nullptr,
                                        float tfar = 3.0e38f) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The sorted unique triangle ids that some pixel sees first (`miss` excluded).
[[nodiscard]] std::vector<std::uint32_t> visible_triangles(const HitBuffer& hits);

}  // namespace cullkit::oracle
