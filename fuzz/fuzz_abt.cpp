// libFuzzer target for AdaptiveBinaryTree: bytes -> build parameters, a view-projection matrix and
// boxes (raw floats, so NaN, inf, huge and inverted values all pass through; or small integers,
// so realistic scenes are reached too). Builds, validates, culls and checks against a brute-force
// oracle in double (objects without valid bounds must always be reported); cull_views and the
// ConvexVolume cull must agree with it; refits (plain and repairing) with moved boxes and checks
// again; exercises the occlusion overload and
// the traversals. Any violation calls __builtin_trap().
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include <cullkit/adaptive_binary_tree.hpp>

using namespace cullkit;

namespace {

#define FUZZ_REQUIRE(cond) \
  do {                     \
    if (!(cond)) __builtin_trap(); \
  } while (0)

class Reader {
 public:
  Reader(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  std::uint8_t byte() { return pos_ < n_ ? d_[pos_++] : 0; }
  float raw_float() {
    std::uint8_t b[4] = {byte(), byte(), byte(), byte()};
    float f;
    std::memcpy(&f, b, 4);
    return f;
  }
  /// A float that is raw bits or a small integer, by mode.
  float coord(bool raw) { return raw ? raw_float() : float(static_cast<std::int8_t>(byte())); }
  [[nodiscard]] std::size_t left() const { return n_ - pos_; }

 private:
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
};

// Planes of the matrix in double, unnormalized; degenerate ones dropped (as at infinity).
struct Oracle {
  double planes[6][4];
  int count = 0;
  Oracle(const glm::mat4& m4, DepthRange depth) {
    double m[4][4];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[r][c] = double(m4[c][r]);
    const int rows[6] = {0, 0, 1, 1, 2, 2};
    const double signs[6] = {1, -1, 1, -1, 1, -1};
    for (int i = 0; i < 6; ++i) {
      const double w = (i == 4 && depth == DepthRange::zero_to_one) ? 0.0 : 1.0;
      double p[4];
      // (w == 0: the row alone; 0 * NaN would poison it.)
      for (int k = 0; k < 4; ++k) p[k] = (w != 0.0 ? m[3][k] : 0.0) + signs[i] * m[rows[i]][k];
      const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      const double scale = std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]) + std::fabs(p[3]);
      if (!(len > 1e-6 * scale) || !std::isfinite(len) || !std::isfinite(p[3])) continue;
      std::memcpy(planes[count++], p, sizeof p);
    }
  }
  [[nodiscard]] bool meets(const Aabb& b) const {
    for (int i = 0; i < count; ++i) {
      const double* p = planes[i];
      bool all_out = true;
      for (int c = 0; c < 8 && all_out; ++c) {
        const double x = (c & 1) ? b.max.x : b.min.x, y = (c & 2) ? b.max.y : b.min.y, z = (c & 4) ? b.max.z : b.min.z;
        if (p[0] * x + p[1] * y + p[2] * z + p[3] >= 0.0) all_out = false;
      }
      if (all_out) return false;
    }
    return true;
  }
};

void check_cull(const AdaptiveBinaryTree<Aabb>& tree, const std::vector<Aabb>& boxes, const Frustum& f,
                const Oracle& oracle) {
  std::vector<std::uint32_t> out;
  tree.cull(f, out);
  std::vector<std::uint8_t> mark(boxes.size(), 0);
  for (const std::uint32_t i : out) {
    FUZZ_REQUIRE(i < boxes.size() && !mark[i]);
    mark[i] = 1;
  }
  // Objects without valid bounds are always reported.
  for (std::size_t i = 0; i < boxes.size(); ++i)
    if (!is_valid(boxes[i]) || oracle.meets(boxes[i])) FUZZ_REQUIRE(mark[i]);
  // Two copies of the view in one cull_views walk: the same set, both bits on every entry; and
  // the frustum as a ConvexVolume: the same set.
  const Frustum pair[2] = {f, f};
  std::vector<std::uint32_t> multi, bits, vol;
  tree.cull_views(pair, 2, multi, bits);
  FUZZ_REQUIRE(multi.size() == out.size() && bits.size() == multi.size());
  for (std::size_t j = 0; j < multi.size(); ++j) FUZZ_REQUIRE(multi[j] < boxes.size() && mark[multi[j]] && bits[j] == 3u);
  tree.cull(ConvexVolume(f), vol);
  FUZZ_REQUIRE(vol.size() == out.size());
  for (const std::uint32_t i : vol) FUZZ_REQUIRE(i < boxes.size() && mark[i]);
}

struct HalfSpace {
  glm::vec3 eye_;
  float k;
  [[nodiscard]] const glm::vec3& eye() const { return eye_; }
  [[nodiscard]] bool is_occluded(const Aabb& b) const { return b.max.y < k; }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(data, size);
  const std::uint8_t flags = in.byte();
  const bool raw_boxes = flags & 1, raw_matrix = flags & 2;
  AbtParams p;
  p.max_leaf_size = in.byte() % 12;
  p.max_depth = in.byte() % 80;
  p.candidates = (flags & 4) ? AbtCandidates::sampling : AbtCandidates::binning;
  p.candidate_count = in.byte() % 40;
  if (flags & 8) {
    p.weight_axis = in.raw_float();
    p.weight_volume = in.raw_float();
    p.weight_count = in.raw_float();
    p.weight_straddle = in.raw_float();
  }
  p.threads = (flags >> 4) & 3;
  p.parallel_grain = 8;
  p.seed = in.byte();
  const DepthRange depth = (flags & 64) ? DepthRange::zero_to_one : DepthRange::negative_one_to_one;
  glm::mat4 m(1.0f);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = raw_matrix ? in.raw_float() : float(static_cast<std::int8_t>(in.byte())) / 16.0f;

  std::vector<Aabb> boxes;
  while (in.left() >= 6 && boxes.size() < 3000) {
    Aabb b;
    for (int a = 0; a < 3; ++a) b.min[a] = in.coord(raw_boxes);
    for (int a = 0; a < 3; ++a) b.max[a] = in.coord(raw_boxes);
    if (!raw_boxes) {  // mostly valid small boxes: sort the corners
      const glm::vec3 lo = glm::min(b.min, b.max), hi = glm::max(b.min, b.max);
      b = Aabb{lo, hi};
    }
    boxes.push_back(b);
  }

  AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size(), p);
  FUZZ_REQUIRE(tree.validate());
  std::size_t valid = 0;
  for (const Aabb& b : boxes) valid += is_valid(b) ? 1 : 0;
  FUZZ_REQUIRE(tree.size() == boxes.size() && tree.stats().skipped == 0 &&
               tree.stats().unbounded == boxes.size() - valid);

  const Frustum f = Frustum::from_matrix(m, depth);
  const Oracle oracle(m, depth);
  check_cull(tree, boxes, f, oracle);

  // Occlusion overload: exactly the frustum survivors that the mock does not hide (superset check).
  // A box wider than the largest float on some axis is `is_unbounded`: the tree never queries the
  // occlusion for it and reports it, as for boxes without valid bounds.
  const HalfSpace occ{glm::vec3(m[3]), float(static_cast<std::int8_t>(flags))};
  std::vector<std::uint32_t> out;
  tree.cull(f, occ, out);
  std::vector<std::uint8_t> mark(boxes.size(), 0);
  for (const std::uint32_t i : out) {
    FUZZ_REQUIRE(i < boxes.size() && !mark[i] &&
                 (!is_valid(boxes[i]) || is_unbounded(boxes[i]) || !occ.is_occluded(boxes[i])));
    mark[i] = 1;
  }
  for (std::size_t i = 0; i < boxes.size(); ++i)
    if (!is_valid(boxes[i]) || (oracle.meets(boxes[i]) && !occ.is_occluded(boxes[i]))) FUZZ_REQUIRE(mark[i]);

  std::size_t visits = 0;
  tree.traverse_front_to_back(glm::vec3(m[3]), [&](std::uint32_t, const AbtNode&) { ++visits; });
  FUZZ_REQUIRE(visits == tree.nodes().size());

  // Refit with every box moved by a shared offset (some new boxes may be bad: reported always),
  // then a repairing refit with the boxes scattered by their index.
  const glm::vec3 shift(float(static_cast<std::int8_t>(flags)) * 0.5f, 1.0f, -2.0f);
  std::vector<Aabb> moved = boxes;
  for (Aabb& b : moved) b = Aabb{b.min + shift, b.max + shift};
  tree.refit(moved.data());
  FUZZ_REQUIRE(tree.validate());
  check_cull(tree, moved, f, oracle);
  FUZZ_REQUIRE(!(tree.refit_quality() < 0.0));
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const glm::vec3 d(float(i % 7) * 3.0f - 9.0f, float(i % 5) * -2.0f, float(i % 3) * 4.0f);
    moved[i] = Aabb{moved[i].min + d, moved[i].max + d};
  }
  AbtRefitParams rp;
  rp.rebuild_threshold = double(flags % 10) / 10.0;
  tree.refit(moved.data(), rp);
  FUZZ_REQUIRE(tree.validate() && tree.size() == boxes.size());
  check_cull(tree, moved, f, oracle);
  return 0;
}
