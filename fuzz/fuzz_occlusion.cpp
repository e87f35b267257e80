// libFuzzer target: occluders (polygons, triangle strips sharing edges, boxes, oriented boxes) and
// query boxes from raw bytes (NaN, inf, huge and tiny values included), inserted and queried; no crash, no sanitizer report. Cheap soundness check:
// a query box that contains the eye, or that lies wholly in front of every occluder's bounding
// box (nearer to the eye along every axis-separated direction), is never hidden.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include <cullkit/occlusion_tree.hpp>

namespace {
struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  bool take(void* out, std::size_t n) {
    if (size < n) return false;
    std::memcpy(out, data, n);
    data += n;
    size -= n;
    return true;
  }
  bool vec(glm::vec3& v) {
    float f[3];
    if (!take(f, sizeof f)) return false;
    v = glm::vec3(f[0], f[1], f[2]);
    return true;
  }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader r{data, size};
  glm::vec3 eye;
  std::uint8_t config = 0;
  if (!r.vec(eye) || !r.take(&config, 1)) return 0;
  cullkit::OcclusionParams params;
  params.azimuth_planes = config & 7;
  params.elevation_planes = (config >> 3) & 3;
  cullkit::OcclusionTree tree(eye, params);
  cullkit::Aabb all_occluders = cullkit::Aabb::empty();
  std::uint8_t op = 0;
  int ops = 0;
  while (r.take(&op, 1) && ops++ < 64) {
    if (op % 3 == 0) {
      glm::vec3 poly[8];
      const std::size_t n = 3 + op / 3 % 6;
      std::size_t got = 0;
      while (got < n && r.vec(poly[got])) ++got;
      if (op & 128) {
        // A triangle strip: neighbours share an edge bit for bit (seams).
        for (std::size_t i = 0; i + 2 < got; ++i) tree.insert_occluder(poly + i, 3);
      } else {
        tree.insert_occluder(poly, got);
      }
      for (std::size_t i = 0; i < got; ++i) all_occluders = cullkit::merge(all_occluders, poly[i]);
    } else if (op % 3 == 1) {
      // One box, or (bit 4) a batch of 1-4 through insert_box_occluders.
      cullkit::Aabb b[4];
      const std::size_t want = (op & 16) ? 1 + (op >> 5) % 4 : 1;
      std::size_t got = 0;
      while (got < want && r.vec(b[got].min) && r.vec(b[got].max)) ++got;
      if (got == 0) break;
      if (op & 16) {
        tree.insert_box_occluders(b, got);
      } else if (op & 4) {
        // An oriented box: the box and the top three rows of an affine matrix.
        float m[12];
        if (!r.take(m, sizeof m)) break;
        glm::mat4 model(1.0f);
        for (int c = 0; c < 4; ++c)
          for (int row = 0; row < 3; ++row) model[c][row] = m[3 * c + row];
        tree.insert_box_occluder(b[0], model);
        for (int k = 0; k < 8; ++k) {
          const glm::vec4 w = model * glm::vec4(cullkit::corner(b[0], k), 1.0f);
          all_occluders = cullkit::merge(all_occluders, glm::vec3(w));
        }
      } else {
        tree.insert_box_occluder(b[0]);
      }
      for (std::size_t i = 0; i < got; ++i)
        all_occluders = cullkit::merge(cullkit::merge(all_occluders, b[i].min), b[i].max);
    } else {
      cullkit::Aabb q;
      if (!r.vec(q.min) || !r.vec(q.max)) break;
      const auto res = tree.query(q, cullkit::OcclusionTree::whole_tree, (op & 8) != 0);
      if (res.answer == cullkit::OcclusionAnswer::hidden) {
        if (!cullkit::is_valid(q) || cullkit::contains(q, eye)) __builtin_trap();
        if (tree.empty()) __builtin_trap();
        // A query not overlapping the occluders' box, with the eye's ray to it unable to cross
        // that box, cannot be hidden: checked for the simple case of an eye and query on the
        // same side of the occluders' box along some axis.
        for (int a = 0; a < 3; ++a) {
          if (cullkit::is_valid(all_occluders) && eye[a] < all_occluders.min[a] && q.max[a] < all_occluders.min[a])
            __builtin_trap();
          if (cullkit::is_valid(all_occluders) && eye[a] > all_occluders.max[a] && q.min[a] > all_occluders.max[a])
            __builtin_trap();
        }
        // A contained box starting at `together` is hidden too (monotonic refinement 2).
        const glm::vec3 c = q.center();
        const cullkit::Aabb inner{glm::mix(q.min, c, 0.5f), glm::mix(q.max, c, 0.5f)};
        if (cullkit::is_valid(inner) && tree.query(inner, res.together).answer != cullkit::OcclusionAnswer::hidden &&
            tree.query(inner).answer == cullkit::OcclusionAnswer::hidden)
          __builtin_trap();
      }
    }
  }
  return 0;
}
