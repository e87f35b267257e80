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
    for (std::size_t i = 0; i < boxes.size(); ++i) leaves_.push_back(tree_.insert(volume(boxes[i]), tag(i)));
    tree_.optimizeTopDown();
  }
  // Incremental use, btDbvt's own operations (ids: positions in leaves_, never reused here).
  std::uint32_t insert(const Aabb& b) {
    leaves_.push_back(tree_.insert(volume(b), tag(leaves_.size())));
    return static_cast<std::uint32_t>(leaves_.size() - 1);
  }
  void remove(std::uint32_t id) {
    tree_.remove(leaves_[id]);
    leaves_[id] = nullptr;
  }
  void update(std::uint32_t id, const Aabb& b) {
    btDbvtVolume v = volume(b);
    tree_.update(leaves_[id], v);
  }
  // Bullet's per-frame incremental re-optimization (a few leaf reinsertions).
  void optimize(int passes) { tree_.optimizeIncremental(passes); }
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
  static btDbvtVolume volume(const Aabb& b) {
    return btDbvtVolume::FromMM(btVector3(b.min.x, b.min.y, b.min.z), btVector3(b.max.x, b.max.y, b.max.z));
  }
  static void* tag(std::size_t i) { return reinterpret_cast<void*>(static_cast<std::uintptr_t>(i)); }
  btDbvt tree_;
  std::vector<btDbvtNode*> leaves_;
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
