// The NormalClassIndex the tests build: the library's own, with NciParams::crowded_path taken from
// the environment variable CULLKIT_NCI_CROWDED_PATH (walk, rays or auto) when it is set, so that the
// whole suite can run on each path without a copy of every test per path (the paths must give the
// same answers). Without the variable it is NormalClassIndex exactly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <cullkit/normal_class_index.hpp>

namespace nci_test {

inline cullkit::NciParams with_env_path(cullkit::NciParams params) {
  if (const char* v = std::getenv("CULLKIT_NCI_CROWDED_PATH")) {
    const std::string path(v);
    if (path == "walk") params.crowded_path = cullkit::NciCrowdedPath::walk_only;
    if (path == "rays") params.crowded_path = cullkit::NciCrowdedPath::rays_only;
    if (path == "auto") params.crowded_path = cullkit::NciCrowdedPath::automatic;
  }
  return params;
}

template <class Vertex, class Index = std::uint32_t>
class TestIndex : public cullkit::NormalClassIndex<Vertex, Index> {
  using Base = cullkit::NormalClassIndex<Vertex, Index>;

 public:
  explicit TestIndex(cullkit::MeshView<Vertex, Index> mesh, const cullkit::NciParams& params = {})
      : Base(mesh, with_env_path(params)) {}
  explicit TestIndex(const cullkit::StridedMesh& mesh, const cullkit::NciParams& params = {})
      : Base(mesh, with_env_path(params)) {}
  TestIndex(const cullkit::StridedPositions& positions, std::size_t vertex_count, const Index* indices,
            std::size_t index_count, const cullkit::NciParams& params = {})
      : Base(positions, vertex_count, indices, index_count, with_env_path(params)) {}
};

}  // namespace nci_test
