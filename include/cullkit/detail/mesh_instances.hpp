// cullkit/detail/mesh_instances.hpp: several meshes placed by world matrices read as one mesh,
// triangle by triangle, for the instance constructors of MeshOcclusionCuller and BspTree.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/ext/matrix_double4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec3.hpp>

#include "../mesh_buffers.hpp"

namespace cullkit::detail {

/// Reads triangle t of the instances' triangles numbered one after another: found by binary search
/// over the instances' first triangles, its corners placed by the instance's matrix in double
/// precision and rounded to float, its winding reversed for a mirroring matrix.
class InstanceReader {
 public:
  InstanceReader(const MeshInstance* instances, std::size_t count) : instances_(instances) {
    first_.reserve(count + 1);
    first_.push_back(0);
    placement_.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
      const StridedMesh mesh = checked_mesh(instances[i].mesh);
      first_.push_back(first_.back() + mesh.triangle_count());
      const glm::dmat4 m(instances[i].model);
      bool usable = m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == 0.0 && m[3][3] == 1.0;
      for (int c = 0; c < 4 && usable; ++c)
        for (int r = 0; r < 3; ++r) usable = usable && std::isfinite(m[c][r]);
      const double det = glm::determinant(glm::dmat3(m));
      placement_.push_back(Placement{m, usable, det < 0.0, m == glm::dmat4(1.0)});
    }
  }

  [[nodiscard]] std::size_t triangle_count() const noexcept { return first_.back(); }

  /// False when the triangle cannot be read: an index out of range or an instance whose matrix is
  /// not affine or not finite. A corner placed at a non-finite point is left to the caller's check.
  /// Reads in increasing t are cheapest (the instance of the last read is tried first).
  bool read(std::size_t t, glm::vec3 p[3]) {
    if (!(t >= first_[cursor_] && t < first_[cursor_ + 1]))
      cursor_ = static_cast<std::size_t>(std::upper_bound(first_.begin(), first_.end(), t) - first_.begin()) - 1;
    const std::size_t i = cursor_;
    const Placement& place = placement_[i];
    if (!place.usable) return false;
    glm::vec3 local[3];
    if (!triangle_positions(checked_mesh(instances_[i].mesh), t - first_[i], local)) return false;
    if (place.mirrored) std::swap(local[1], local[2]);
    for (int k = 0; k < 3; ++k)
      p[k] = place.identity ? local[k] : glm::vec3(place.model * glm::dvec4(glm::dvec3(local[k]), 1.0));
    return true;
  }

 private:
  struct Placement {
    glm::dmat4 model;
    bool usable, mirrored, identity;
  };
  const MeshInstance* instances_;
  std::vector<std::size_t> first_;  // per instance, its first triangle; then the total
  std::vector<Placement> placement_;
  std::size_t cursor_ = 0;  // the instance of the last read
};

}  // namespace cullkit::detail
