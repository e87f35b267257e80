// cullkit demo: a generated city, a camera walking down a street, and what culling keeps.
//
//   ./dev.sh demo            (or: build/release/examples/cullkit_demo [output-dir])
//
// Writes <dir>/demo_topdown.png: the city from above, each object coloured by what the
// AdaptiveBinaryTree reported for the first frame of the path (green: visible, light grey: outside
// the frustum), the tree's leaf boxes drawn faintly, and the view's edges. Prints, per frame of a
// short camera path, the nodes the cull visited and the objects it reported, next to brute force.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;

namespace {

constexpr support::Rgb kVisible{46, 160, 67};
constexpr support::Rgb kFrustumCulled{205, 205, 205};
constexpr support::Rgb kLeaf{120, 70, 170};
constexpr support::Rgb kView{30, 60, 200};

Camera camera_at(const support::Scene& city, float t) {
  // Walk along a street in +x at eye height, turning slowly to the right.
  const Aabb& b = city.bounds;
  const glm::vec3 eye(b.min.x + (b.max.x - b.min.x) * (0.1f + 0.3f * t), 1.7f, b.min.z + (b.max.z - b.min.z) * 0.37f);
  const glm::vec3 target = eye + glm::vec3(1.0f, -0.02f, 0.35f - 0.5f * t);
  return support::make_camera(eye, target, 70.0f, 1280, 720, 0.1f, 2000.0f);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Nodes a top-down cull visits, counted with the public node view (the same walk `cull` makes:
// a node is visited when its parent was not settled as outside or inside).
template <class Tree>
std::size_t nodes_visited(const Tree& tree, const Frustum& frustum) {
  if (tree.nodes().empty()) return 0;
  std::size_t visited = 0;
  std::vector<std::pair<std::uint32_t, PlaneMask>> stack{{0u, frustum.active_mask()}};
  while (!stack.empty()) {
    auto [index, mask] = stack.back();
    stack.pop_back();
    ++visited;
    const AbtNode& node = tree.nodes()[index];
    if (frustum.classify(node.bounds, mask) != Containment::intersecting || node.is_leaf()) continue;
    stack.push_back({node.left, mask});
    stack.push_back({node.left + 1, mask});
  }
  return visited;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  const support::Scene city = support::make_city(7, 12);
  const std::vector<Aabb> bounds = city.object_bounds();
  std::printf("city: %zu objects, %zu triangles\n", city.objects.size(), city.triangle_count());

  auto t0 = std::chrono::steady_clock::now();
  const AdaptiveBinaryTree<Aabb> tree(bounds.data(), bounds.size());
  std::printf("adaptive binary tree: %u nodes, %u leaves, depth %u, built in %.2f ms\n", tree.stats().nodes,
              tree.stats().leaves, tree.stats().depth, ms_since(t0));

  std::vector<std::uint32_t> reported;
  std::vector<std::uint8_t> visible(bounds.size());
  const int frames = 8;
  for (int f = 0; f < frames; ++f) {
    const Camera cam = camera_at(city, float(f) / float(frames - 1));
    const Frustum frustum = frustum_of(cam);

    t0 = std::chrono::steady_clock::now();
    tree.cull(frustum, reported);
    const double tree_ms = ms_since(t0);

    t0 = std::chrono::steady_clock::now();
    std::size_t brute = 0;
    for (const Aabb& b : bounds) brute += frustum.classify(b) != Containment::outside;
    const double brute_ms = ms_since(t0);

    std::printf("frame %d: tree visited %4zu of %u nodes, reported %5zu of %zu objects (%4.1f%%) in %.3f ms;"
                " brute force %zu in %.3f ms\n",
                f, nodes_visited(tree, frustum), tree.stats().nodes, reported.size(), bounds.size(),
                100.0 * double(reported.size()) / double(bounds.size()), tree_ms, brute, brute_ms);
    if (f != 0) continue;

    std::fill(visible.begin(), visible.end(), 0);
    for (std::uint32_t i : reported) visible[i] = 1;
    support::TopDownMap map(city.bounds, 1400);
    for (std::size_t i = 0; i < bounds.size(); ++i) {
      map.box(bounds[i], visible[i] ? kVisible : kFrustumCulled, city.objects[i].major_occluder ? 1.0f : 0.8f);
    }
    for (const AbtNode& node : tree.nodes()) {
      if (node.is_leaf()) map.outline(node.bounds, kLeaf, 0.25f);
    }
    map.camera(cam, 0.6f * glm::length(city.bounds.extent()), kView);
    const std::string path = dir + "/demo_topdown.png";
    if (!map.image().write_png(path)) {
      std::fprintf(stderr, "could not write %s\n", path.c_str());
      return 1;
    }
    std::printf("wrote %s (green: reported visible, grey: frustum-culled, purple: tree leaves)\n", path.c_str());
  }
  return 0;
}
