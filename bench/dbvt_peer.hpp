// bench/dbvt_peer.hpp: the frustum-culling peer the tree benchmarks race (Bullet's btDbvt with the
// frustum planes as a k-DOP query) and their seeded box field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

// Bullet's Classify() leaves two corners uninitialized on a path GCC cannot prove dead; once inlined
// the warning is attributed to the including file.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include <cullkit/geometry.hpp>
#include <cullkit_support/scene.hpp>

namespace cullkit::bench {

// Bullet's dynamic AABB tree with the frustum planes as a k-DOP query.
class DbvtPeer {
 public:
  explicit DbvtPeer(const std::vector<Aabb>& boxes) {
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const btDbvtVolume v = btDbvtVolume::FromMM(btVector3(boxes[i].min.x, boxes[i].min.y, boxes[i].min.z),
                                                  btVector3(boxes[i].max.x, boxes[i].max.y, boxes[i].max.z));
      tree_.insert(v, reinterpret_cast<void*>(static_cast<std::uintptr_t>(i)));
    }
    tree_.optimizeTopDown();
  }
  void cull(const Frustum& f, std::vector<std::uint32_t>& out) {
    btVector3 normals[6];
    btScalar offsets[6];
    int count = 0;
    for (int p = 0; p < Frustum::max_planes; ++p) {
      if (!f.has_plane(p)) continue;
      normals[count] = btVector3(f.plane(p).normal.x, f.plane(p).normal.y, f.plane(p).normal.z);
      offsets[count] = f.plane(p).d;
      ++count;
    }
    struct Collect : btDbvt::ICollide {
      std::vector<std::uint32_t>* out;
      void Process(const btDbvtNode* n) override {
        out->push_back(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(n->data)));
      }
    } collect;
    collect.out = &out;
    out.clear();
    btDbvt::collideKDOP(tree_.m_root, normals, offsets, count, collect);
  }

 private:
  btDbvt tree_;
};

inline std::vector<Aabb> random_boxes(std::size_t n) {
  support::Rng rng(60000);  // the same distribution as bench_frustum
  std::vector<Aabb> boxes(n);
  for (auto& b : boxes) {
    const glm::vec3 c(rng.uniform(-500, 500), rng.uniform(0, 50), rng.uniform(-500, 500));
    const glm::vec3 h(rng.uniform(0.5f, 5), rng.uniform(0.5f, 10), rng.uniform(0.5f, 5));
    b = Aabb{c - h, c + h};
  }
  return boxes;
}

}  // namespace cullkit::bench
