// cullkit demo: a generated city, a camera walking down a street, and what culling keeps.
//
//   ./dev.sh demo            (or: build/release/examples/cullkit_demo [output-dir])
//
// Writes two pictures for the first frame of a short camera path:
//  * <dir>/demo_topdown.png: the city from above; each object coloured by what culling reported
//    (green: visible, light grey: outside the frustum, orange: hidden by the occlusion tree), the
//    buildings that served as occluders outlined dark with their shadow wedges shaded, the
//    AdaptiveBinaryTree's leaf boxes drawn faintly, and the view's edges;
//  * <dir>/demo_view.png (when built with Embree): the camera's view ray-cast by Embree, with the
//    boxes of occlusion-culled objects outlined in red where they would be on screen.
// Prints, per frame, nodes visited and objects reported by frustum culling alone and by frustum +
// occlusion culling, and checks the occlusion result against Embree: objects Embree sees that
// culling dropped (must be 0).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/image.hpp>
#include <cullkit_support/scene.hpp>
#ifdef CULLKIT_DEMO_HAVE_EMBREE
#include <embree_oracle.hpp>
#endif

using namespace cullkit;

namespace {

constexpr support::Rgb kVisible{46, 160, 67};
constexpr support::Rgb kFrustumCulled{205, 205, 205};
constexpr support::Rgb kOccluded{240, 140, 30};
constexpr support::Rgb kHiddenOutline{230, 20, 20};
constexpr support::Rgb kOccluder{40, 40, 40};
constexpr support::Rgb kShadow{90, 90, 90};
constexpr support::Rgb kLeaf{120, 70, 170};
constexpr support::Rgb kView{30, 60, 200};

// A street to walk down: the line z = const (at eye height) near the middle of the city that
// crosses the fewest buildings, so the eye is in the open, not inside a block.
float find_street(const support::Scene& city) {
  const Aabb& b = city.bounds;
  float best_z = b.center().z;
  int best = 1 << 30;
  for (int k = 0; k <= 400; ++k) {
    const float z = b.min.z + (b.max.z - b.min.z) * (0.3f + 0.4f * float(k) / 400.0f);
    int crossed = 0;
    for (const auto& o : city.objects) {
      crossed += o.bounds.max.y > 0.5f && o.bounds.min.y < 1.7f && o.bounds.min.z <= z && z <= o.bounds.max.z;
    }
    if (crossed < best) best = crossed, best_z = z;
  }
  return best_z;
}

Camera camera_at(const support::Scene& city, float street_z, float t) {
  // Walk along the street in +x at eye height, looking a little to one side, then the other.
  const Aabb& b = city.bounds;
  const glm::vec3 eye(b.min.x + (b.max.x - b.min.x) * (0.05f + 0.4f * t), 1.7f, street_z);
  const glm::vec3 target = eye + glm::vec3(1.0f, 0.02f, 0.3f - 0.6f * t);
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

  // Which objects may occlude: the solid box buildings.
  std::vector<std::uint8_t> is_occluder(bounds.size());
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    is_occluder[i] = city.objects[i].major_occluder && city.objects[i].is_box;
  }
  const BoxOccluderSource occluders{bounds.data(), is_occluder.data()};
  OcclusionTree occlusion(glm::vec3(0.0f));
  const float street_z = find_street(city);

  std::vector<std::uint32_t> in_frustum, visible;
  const int frames = 8;
  for (int f = 0; f < frames; ++f) {
    const Camera cam = camera_at(city, street_z, float(f) / float(frames - 1));
    const Frustum frustum = frustum_of(cam);

    t0 = std::chrono::steady_clock::now();
    tree.cull(frustum, in_frustum);
    const double frustum_ms = ms_since(t0);

    t0 = std::chrono::steady_clock::now();
    occlusion.reset(cam.eye);  // reused frame to frame: no allocation once warm
    OcclusionCullStats stats;
    cull_with_occlusion(tree, frustum, occlusion, occluders, visible, &stats);
    const double occlusion_ms = ms_since(t0);

    std::printf("frame %d: frustum: %4zu nodes visited, %5zu objects (%4.1f%%) in %.3f ms | "
                "+occlusion: %4llu nodes, %5zu objects (%4.1f%%), %u occluders, %.3f ms\n",
                f, nodes_visited(tree, frustum), in_frustum.size(), 100.0 * double(in_frustum.size()) / double(bounds.size()),
                frustum_ms, static_cast<unsigned long long>(stats.nodes_visited), visible.size(),
                100.0 * double(visible.size()) / double(bounds.size()), occlusion.stats().occluders_inserted, occlusion_ms);
    if (f != 0) continue;

    std::vector<std::uint8_t> state(bounds.size(), 0);  // 0 frustum-culled, 1 occluded, 2 visible
    for (std::uint32_t i : in_frustum) state[i] = 1;
    for (std::uint32_t i : visible) state[i] = 2;

    support::TopDownMap map(city.bounds, 1400);
    // Shadow wedges first (under everything): each visible occluder's footprint seen from the eye,
    // extended away from it.
    const glm::vec2 eye2 = map.to_pixel(cam.eye);
    for (std::uint32_t i : visible) {
      if (!is_occluder[i]) continue;
      glm::vec2 c[4];
      for (int k = 0; k < 4; ++k) c[k] = map.to_pixel(corner(bounds[i], (k & 1) | ((k & 2) << 1)));
      for (int a = 0; a < 4; ++a) {
        for (int b = a + 1; b < 4; ++b) {
          const glm::vec2 far_a = c[a] + (c[a] - eye2) * 40.0f, far_b = c[b] + (c[b] - eye2) * 40.0f;
          map.image().fill_triangle(c[a], far_a, far_b, kShadow, 0.05f);
          map.image().fill_triangle(c[a], far_b, c[b], kShadow, 0.05f);
        }
      }
    }
    for (std::size_t i = 0; i < bounds.size(); ++i) {
      const support::Rgb color = state[i] == 2 ? kVisible : (state[i] == 1 ? kOccluded : kFrustumCulled);
      map.box(bounds[i], color, city.objects[i].major_occluder ? 1.0f : 0.8f);
    }
    for (std::uint32_t i : visible) {
      if (is_occluder[i]) map.outline(bounds[i], kOccluder, 1.0f);
    }
    for (const AbtNode& node : tree.nodes()) {
      if (node.is_leaf()) map.outline(node.bounds, kLeaf, 0.2f);
    }
    map.camera(cam, 0.6f * glm::length(city.bounds.extent()), kView);
    const std::string path = dir + "/demo_topdown.png";
    if (!map.image().write_png(path)) {
      std::fprintf(stderr, "could not write %s\n", path.c_str());
      return 1;
    }
    std::printf("wrote %s (green: visible, orange: occlusion-culled, grey: frustum-culled, dark outline: "
                "occluders, purple: tree leaves)\n", path.c_str());

#ifdef CULLKIT_DEMO_HAVE_EMBREE
    // The camera's own view, by Embree, and the ground-truth check.
    oracle::EmbreeScene embree;
    embree.add_mesh(city.positions.data(), city.positions.size(), city.indices.data(), city.indices.size());
    embree.commit();
    const Camera small{cam.eye, cam.view_proj, 960, 540, cam.depth};
    const oracle::HitBuffer hits = embree.render(small);
    std::vector<std::uint32_t> object_of(city.triangle_count());
    for (std::uint32_t o = 0; o < city.objects.size(); ++o) {
      for (std::uint32_t t = 0; t < city.objects[o].triangle_count; ++t) object_of[city.objects[o].first_triangle + t] = o;
    }
    support::Image view(small.width, small.height, support::Rgb{170, 200, 235});
    std::size_t seen = 0, wrongly_culled = 0;
    std::vector<std::uint8_t> seen_object(bounds.size());
    for (int y = 0; y < small.height; ++y) {
      for (int x = 0; x < small.width; ++x) {
        const std::uint32_t t = hits.at(x, y);
        if (t == oracle::HitBuffer::miss) continue;
        const std::uint32_t o = object_of[t];
        seen_object[o] = 1;
        const support::Rgb base = support::id_color(o);
        const glm::vec3* p = &city.positions[0];
        const std::uint32_t* tri = &city.indices[3 * std::size_t(t)];
        const glm::vec3 n = glm::normalize(glm::cross(p[tri[1]] - p[tri[0]], p[tri[2]] - p[tri[0]]));
        const float light = 0.55f + 0.45f * std::fabs(glm::dot(n, glm::normalize(glm::vec3(0.4f, 0.8f, 0.3f))));
        const float shade = (state[o] == 2 ? 0.85f : 0.4f) * light;
        view.set(x, y, support::Rgb{std::uint8_t(base.r * shade), std::uint8_t(base.g * shade), std::uint8_t(base.b * shade)});
      }
    }
    for (std::size_t o = 0; o < bounds.size(); ++o) {
      seen += seen_object[o];
      wrongly_culled += seen_object[o] && state[o] != 2;
    }
    // Outline the boxes of occlusion-culled objects: the hidden work the renderer skips.
    const glm::dmat4 vp(cam.view_proj);
    for (std::size_t o = 0; o < bounds.size(); ++o) {
      if (state[o] != 1) continue;
      for (int a = 0; a < 8; ++a) {
        for (int bit = 1; bit < 8; bit <<= 1) {
          const int b = a | bit;
          if (b == a) continue;
          const glm::dvec4 pa = vp * glm::dvec4(glm::dvec3(corner(bounds[o], a)), 1.0);
          const glm::dvec4 pb = vp * glm::dvec4(glm::dvec3(corner(bounds[o], b)), 1.0);
          if (pa.w <= 0.1 || pb.w <= 0.1) continue;
          const auto px = [&](const glm::dvec4& p) {
            return glm::vec2(float((p.x / p.w + 1.0) * 0.5 * small.width), float((1.0 - p.y / p.w) * 0.5 * small.height));
          };
          const glm::vec2 u = px(pa), v = px(pb);
          view.line(u.x, u.y, v.x, v.y, kHiddenOutline, 0.45f);
        }
      }
    }
    const std::string view_path = dir + "/demo_view.png";
    if (!view.write_png(view_path)) {
      std::fprintf(stderr, "could not write %s\n", view_path.c_str());
      return 1;
    }
    std::printf("wrote %s (Embree's view; red: boxes of occlusion-culled objects)\n", view_path.c_str());
    std::printf("embree check: %zu objects seen on screen, %zu of them culled (must be 0)\n", seen, wrongly_culled);
    if (wrongly_culled != 0) return 1;
#endif
  }
  return 0;
}
