// Views beyond one frustum: AdaptiveBinaryTree::cull(ConvexVolume) and cull_views against brute
// force, and shadow_caster_volume against the exact set of casters.
// Oracles: every box tested corner by corner in double against the planes (volumes, views); for
// casters, the exact test "the box swept along the light meets the view" (a 1-D interval problem
// over the planes of the Minkowski sum of the frustum and the box), and sampled casters for
// infinite frusta.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include "../abt/abt_oracle.hpp"

using namespace cullkit;

namespace {

glm::vec3 random_unit(support::Rng& rng) {
  for (;;) {
    const glm::vec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const float l = glm::length(v);
    if (l > 0.1f && l <= 1.0f) return v / l;
  }
}

// Box meets the volume's planes (double, all 8 corners): not all corners strictly outside one plane.
bool volume_meets(const ConvexVolume& v, const Aabb& b) {
  for (std::size_t i = 0; i < v.plane_count(); ++i) {
    const Plane& p = v.plane(i);
    bool out = true;
    for (int c = 0; c < 8 && out; ++c) {
      const glm::vec3 q = corner(b, c);
      out = double(p.normal.x) * q.x + double(p.normal.y) * q.y + double(p.normal.z) * q.z + double(p.d) < 0.0;
    }
    if (out) return false;
  }
  return true;
}

void volume_cull() {
  support::Rng rng(21);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 5000, 100.0f, 3.0f);
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  std::vector<std::uint32_t> out;
  std::size_t kept_total = 0, truly_total = 0;
  for (int k = 0; k < 150; ++k) {
    ConvexVolume v;
    const int planes = 1 + k % 32;
    const glm::vec3 centre(rng.uniform(-60, 60), rng.uniform(-60, 60), rng.uniform(-60, 60));
    for (int i = 0; i < planes; ++i) {
      const glm::vec3 n = random_unit(rng);
      v.add_plane(Plane{n, -glm::dot(n, centre) + rng.uniform(5, 80)});
    }
    tree.cull(v, out);
    std::vector<std::uint8_t> mark(boxes.size(), 0);
    bool dup = false;
    for (std::uint32_t i : out) {
      dup = dup || mark[i];
      mark[i] = 1;
    }
    std::size_t missed = 0, truly = 0;
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
      if (!volume_meets(v, boxes[i])) continue;
      ++truly;
      missed += !mark[i];
    }
    CHECK_MSG(missed == 0 && !dup, "volume %d (%d planes): %zu missed", k, planes, missed);
    kept_total += out.size();
    truly_total += truly;
  }
  // Non-vacuity: the volumes cut (some objects kept, many not).
  CHECK(truly_total > 0 && kept_total < 150 * boxes.size() / 2);
  std::printf("volume cull: %zu kept, %zu meet (brute force), over 150 volumes\n", kept_total, truly_total);
  tree.cull(ConvexVolume{}, out);
  CHECK(out.size() == boxes.size());
}

void views_cull() {
  support::Rng rng(22);
  const std::vector<Aabb> boxes = abt_test::random_boxes(rng, 6000, 100.0f, 3.0f);
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  std::vector<std::uint32_t> out, bits;
  std::size_t wrong = 0, missing = 0, extra_bits = 0, total_bits = 0;
  for (int k = 0; k < 60; ++k) {
    const int n = k < 20 ? 2 : 1 + rng.range(0, 31);
    std::vector<Frustum> fr;
    std::vector<abt_test::OracleFrustum> oracles;
    for (int v = 0; v < n; ++v) {
      const abt_test::View view = abt_test::random_view(rng, Aabb{glm::vec3(-130), glm::vec3(130)}, k * 32 + v);
      fr.push_back(Frustum::from_matrix(view.view_proj, view.depth));
      oracles.emplace_back(view.view_proj, view.depth);
    }
    tree.cull_views(fr.data(), fr.size(), out, bits);
    CHECK(out.size() == bits.size());
    std::vector<std::uint32_t> got(boxes.size(), 0);
    std::vector<std::uint8_t> seen(boxes.size(), 0);
    for (std::size_t j = 0; j < out.size(); ++j) {
      wrong += seen[out[j]] || bits[j] == 0;
      seen[out[j]] = 1;
      got[out[j]] = bits[j];
    }
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
      for (int v = 0; v < n; ++v) {
        const bool meets = oracles[std::size_t(v)].meets(boxes[i]);
        const bool bit = (got[i] >> v) & 1u;
        missing += meets && !bit;
        extra_bits += !meets && bit;
        total_bits += bit;
      }
    }
    // Each view's bits are exactly what a single cull of that view reports (random views share no
    // plane, so nothing merges).
    for (int v = 0; v < n; ++v) {
      std::vector<std::uint32_t> single;
      tree.cull(fr[std::size_t(v)], single);
      std::size_t same = 0;
      for (std::uint32_t i : single) same += (got[i] >> v) & 1u;
      std::size_t with_bit = 0;
      for (std::uint32_t i = 0; i < boxes.size(); ++i) with_bit += (got[i] >> v) & 1u;
      CHECK_MSG(same == single.size() && with_bit == single.size(), "set %d view %d: bits differ from a single cull", k, v);
    }
  }
  CHECK_MSG(missing == 0 && wrong == 0, "%zu missing bits, %zu wrong entries", missing, wrong);
  CHECK(total_bits > 0);
  std::printf("cull_views: %zu bits set, %zu beyond the brute force (rounding slack)\n", total_bits, extra_bits);
  const Frustum none[1] = {};
  tree.cull_views(none, 0, out, bits);
  CHECK(out.empty() && bits.empty());
}

// The frustum's planes with every offset moved outward by `relative` of its magnitude: what a view
// of cull_views may report at most, where its planes were merged with other views' copies.
ConvexVolume loosened(const Frustum& f, float relative) {
  ConvexVolume v;
  for (int i = 0; i < Frustum::max_planes; ++i) {
    if (!f.has_plane(i)) continue;
    Plane p = f.plane(i);
    p.d += relative * std::fabs(p.d) + 1e-30f;
    v.add_plane(p);
  }
  return v;
}

struct ViewsCheck {
  std::size_t entries = 0;
  std::size_t beyond_single = 0;  // bits a single cull of that view does not report
};

// Checks one cull_views call: every object once, every bit a single cull of the view reports is
// set, every bit a box meeting the view (brute force) needs is set, and no bit is set for an
// object outside the view's planes loosened by twice the merge tolerance. Not "equal to the single
// cull": the contract only asks that a bit is never clear where the box meets the view, and planes
// that views share up to rounding are tested once at the looser offset (detail/abt/views_merged.hpp).
ViewsCheck check_views(const AdaptiveBinaryTree<Aabb>& tree, const std::vector<Aabb>& boxes,
                       const std::vector<Frustum>& fr, const std::vector<const abt_test::OracleFrustum*>& oracles,
                       const char* what) {
  constexpr float merge_bound = 2.0f * detail::AbtMergedPlanes::merge_tolerance;
  std::vector<std::uint32_t> out, bits, single, loose;
  tree.cull_views(fr.data(), fr.size(), out, bits);
  CHECK(out.size() == bits.size());
  std::vector<std::uint32_t> got(boxes.size(), 0);
  std::size_t wrong = 0, missing = 0, below_single = 0, beyond_loose = 0;
  ViewsCheck result;
  for (std::size_t j = 0; j < out.size(); ++j) {
    wrong += out[j] >= boxes.size() || got[out[j]] != 0 || bits[j] == 0;
    if (out[j] < boxes.size()) got[out[j]] = bits[j];
  }
  for (std::size_t v = 0; v < fr.size(); ++v) {
    tree.cull(fr[v], single);
    tree.cull(loosened(fr[v], merge_bound), loose);
    std::vector<std::uint8_t> in_single(boxes.size(), 0), in_loose(boxes.size(), 0);
    for (std::uint32_t i : single) in_single[i] = 1;
    for (std::uint32_t i : loose) in_loose[i] = 1;
    for (std::uint32_t i = 0; i < boxes.size(); ++i) {
      const bool bit = (got[i] >> v) & 1u;
      below_single += in_single[i] && !bit;
      result.beyond_single += bit && !in_single[i];
      beyond_loose += bit && !in_loose[i];
      const bool meets = !is_valid(boxes[i]) || oracles[v] == nullptr || oracles[v]->meets(boxes[i]);
      missing += meets && !bit;
    }
  }
  CHECK_MSG(wrong == 0 && missing == 0 && below_single == 0 && beyond_loose == 0,
            "%s: %zu wrong entries, %zu missing bits, %zu bits a single cull has and cull_views not, %zu bits "
            "beyond the loosened planes",
            what, wrong, missing, below_single, beyond_loose);
  result.entries = out.size();
  return result;
}

// Two views whose planes merge (same normals, offsets 2^-20 apart in relative terms), with boxes
// whose farthest corner lies within a few such offsets of one plane: the merged walk must report
// what each single cull reports (the outside verdict at the larger offset) and nothing beyond the
// loosened planes (the inside verdict at the smaller one). Swapping the two offsets fails here.
void views_merged_planes() {
  support::Rng rng(25);
  std::size_t beyond = 0, entries = 0;
  for (int k = 0; k < 12; ++k) {
    const abt_test::View view = abt_test::random_view(rng, Aabb{glm::vec3(-130), glm::vec3(130)}, k);
    const Frustum f0 = Frustum::from_matrix(view.view_proj, view.depth);
    const glm::mat4 inv = glm::inverse(view.view_proj);
    // Boxes hugging the planes of f0 from both sides: centre on the plane, pushed so that the
    // farthest corner along the normal sits at t in [-4, 4] units of 2^-20 |d|.
    std::vector<Aabb> boxes;
    for (int b = 0; b < 3000; ++b) {
      const float lo = view.depth == DepthRange::zero_to_one ? 0.0f : -1.0f;
      const glm::vec4 ndc(rng.uniform(-0.9f, 0.9f), rng.uniform(-0.9f, 0.9f), rng.uniform(lo + 0.05f, 0.95f), 1.0f);
      glm::vec4 w = inv * ndc;
      if (!(std::fabs(w.w) > 1e-12f)) continue;
      const glm::vec3 q = glm::vec3(w) / w.w;
      const int i = rng.range(0, Frustum::max_planes - 1);
      if (!f0.has_plane(i)) continue;
      const Plane& p = f0.plane(i);
      const glm::vec3 e(rng.uniform(0.01f, 1.0f), rng.uniform(0.01f, 1.0f), rng.uniform(0.01f, 1.0f));
      const float r = std::fabs(p.normal.x) * e.x + std::fabs(p.normal.y) * e.y + std::fabs(p.normal.z) * e.z;
      const float t = rng.uniform(-4.0f, 4.0f) * std::fabs(p.d) / 1048576.0f;
      const glm::vec3 c = q - (glm::dot(p.normal, q) + p.d) * p.normal + (t - r) * p.normal;
      boxes.push_back(Aabb{c - e, c + e});
    }
    const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
    // The second view: the same matrix moved by 2^-20 of the offsets, so every plane keeps its
    // normal bit for bit and merges.
    const glm::vec3 shift = glm::normalize(glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))) *
                            (std::fabs(f0.plane(Frustum::left).d) + 1.0f) / 1048576.0f;
    const glm::mat4 m1 = view.view_proj * glm::translate(glm::mat4(1.0f), shift);
    const std::vector<Frustum> fr = {f0, Frustum::from_matrix(m1, view.depth)};
    const abt_test::OracleFrustum o0(view.view_proj, view.depth), o1(m1, view.depth);
    const ViewsCheck c = check_views(tree, boxes, fr, {&o0, &o1}, "merged planes");
    beyond += c.beyond_single;
    entries += c.entries;
  }
  CHECK(entries > 0);
  // Non-vacuity: the merge happened (some view reports objects its single cull leaves out).
  CHECK(beyond > 0);
  std::printf("cull_views merged planes: %zu entries over 12 pairs, %zu bits beyond single culls\n", entries, beyond);
}

// A headset: two eyes 64 mm apart with mirrored off-axis tangents (the outer side wider), each eye's
// view matrix built on its own (lookAt from its own position), under random head poses. The eyes'
// top, bottom, near and far planes then agree only up to rounding in their normals too; they must
// still merge (8 distinct planes, not 12: a merged walk is then cheaper than two culls), and every
// bit a single cull of either eye reports, or that a box meeting the eye needs, must be set.
void views_headset_pairs() {
  support::Rng rng(26);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 20000, 60.0f, 1.5f);
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  std::size_t tilted = 0, pairs = 0;
  for (int k = 0; k < 24; ++k) {
    const glm::vec3 head(rng.uniform(-40, 40), rng.uniform(0.5f, 3), rng.uniform(-40, 40));
    const glm::vec3 forward = glm::normalize(glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.4f, 0.4f), rng.uniform(-1, 1)));
    const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
    const float outer = rng.uniform(1.0f, 1.4f), inner = rng.uniform(0.7f, 1.0f), up = rng.uniform(0.9f, 1.3f);
    const float down = rng.uniform(1.0f, 1.5f), n = 0.05f, f = rng.uniform(100.0f, 400.0f);
    std::vector<Frustum> fr;
    std::vector<glm::mat4> vps;
    for (int eye = 0; eye < 2; ++eye) {
      const float side = eye == 0 ? -1.0f : 1.0f;
      const glm::vec3 pos = head + right * (0.032f * side);
      // Left eye: wider to the left (outer), right eye mirrored.
      const float l = eye == 0 ? -outer : -inner, r = eye == 0 ? inner : outer;
      const glm::mat4 proj = glm::frustum(l * n, r * n, -down * n, up * n, n, f);
      vps.push_back(proj * glm::lookAt(pos, pos + forward, glm::vec3(0, 1, 0)));
      fr.push_back(Frustum::from_matrix(vps.back(), DepthRange::negative_one_to_one));
    }
    detail::AbtMergedPlanes mp;
    CHECK(mp.assign(fr.data(), 2));
    CHECK_MSG(mp.count() == 8, "pose %d: %u distinct planes, expected 8", k, mp.count());
    for (std::uint32_t u = 0; u < mp.count(); ++u) tilted += mp.tilt2()[u] > 0.0f;
    const abt_test::OracleFrustum o0(vps[0], DepthRange::negative_one_to_one), o1(vps[1], DepthRange::negative_one_to_one);
    std::vector<std::uint32_t> out, bits, single;
    tree.cull_views(fr.data(), fr.size(), out, bits);
    std::vector<std::uint32_t> got(boxes.size(), 0);
    for (std::size_t j = 0; j < out.size(); ++j) got[out[j]] = bits[j];
    std::size_t missing = 0, below_single = 0;
    for (int v = 0; v < 2; ++v) {
      tree.cull(fr[static_cast<std::size_t>(v)], single);
      for (std::uint32_t i : single) below_single += !((got[i] >> v) & 1u);
      const abt_test::OracleFrustum& o = v == 0 ? o0 : o1;
      for (std::uint32_t i = 0; i < boxes.size(); ++i) missing += o.meets(boxes[i]) && !((got[i] >> v) & 1u);
    }
    CHECK_MSG(missing == 0 && below_single == 0, "pose %d: %zu missing bits, %zu bits a single cull has", k, missing,
              below_single);
    ++pairs;
  }
  // Non-vacuity: some shared planes did differ in their normals' last bits and were merged.
  CHECK(tilted > 0);
  std::printf("cull_views headset pairs: %zu poses, %zu merged planes with tilted copies\n", pairs, tilted);
}

// Views that share normals (the shared-arithmetic path): stereo eyes, cascades, 32 views, views
// inside which whole subtrees lie, a NaN frustum, objects with bad bounds.
void views_fast_paths() {
  support::Rng rng(24);
  std::vector<Aabb> boxes = abt_test::random_boxes(rng, 8000, 100.0f, 3.0f);
  for (std::size_t i = 0; i < boxes.size(); i += 797) boxes[i].min.y = std::numeric_limits<float>::quiet_NaN();
  boxes[5] = Aabb{glm::vec3(-std::numeric_limits<float>::infinity()), glm::vec3(std::numeric_limits<float>::infinity())};
  const AdaptiveBinaryTree<Aabb> tree(boxes.data(), boxes.size());
  std::size_t partial = 0, total = 0;
  for (int k = 0; k < 24; ++k) {
    const abt_test::View view = abt_test::random_view(rng, Aabb{glm::vec3(-130), glm::vec3(130)}, k);
    std::vector<Frustum> fr;
    std::vector<abt_test::OracleFrustum> own;
    own.reserve(32);
    const int n = k % 4 == 3 ? 32 : k % 4 == 2 ? 4 : 2;
    for (int v = 0; v < n; ++v) {
      // Eyes side by side (equal normals, offsets apart), and for k % 4 == 2 wider and narrower
      // copies (different normals: families of one).
      const glm::vec3 shift(0.032f * float(v - n / 2), 0.0f, 0.0f);
      glm::mat4 m = view.view_proj * glm::translate(glm::mat4(1.0f), shift);
      if (k % 4 == 2 && v >= 2) m = glm::scale(glm::mat4(1.0f), glm::vec3(v == 2 ? 0.3f : 3.0f, 1.0f, 1.0f)) * m;
      fr.push_back(Frustum::from_matrix(m, view.depth));
      own.emplace_back(m, view.depth);
    }
    if (k % 6 == 5) fr[1] = Frustum::from_matrix(glm::mat4(std::numeric_limits<float>::quiet_NaN()), view.depth);
    std::vector<const abt_test::OracleFrustum*> oracles;
    for (int v = 0; v < n; ++v) oracles.push_back(k % 6 == 5 && v == 1 ? nullptr : &own[std::size_t(v)]);
    total += check_views(tree, boxes, fr, oracles, "families").entries;
    // The NaN frustum keeps everything: every object carries its bit.
    if (k % 6 == 5) {
      std::vector<std::uint32_t> out, bits;
      tree.cull_views(fr.data(), fr.size(), out, bits);
      std::size_t with = 0;
      for (std::uint32_t b : bits) with += (b >> 1) & 1u;
      CHECK(out.size() == boxes.size() && with == boxes.size());
    }
  }
  // A huge frustum holding everything (whole subtrees inside all views) next to a narrow one
  // (inside some views only); unbounded objects carry every bit.
  const glm::mat4 wide = glm::orthoRH_ZO(-1000.0f, 1000.0f, -1000.0f, 1000.0f, -1000.0f, 1000.0f);
  const glm::mat4 narrow = glm::orthoRH_ZO(-20.0f, 20.0f, -20.0f, 20.0f, -1000.0f, 1000.0f);
  const abt_test::OracleFrustum ow(wide, DepthRange::zero_to_one), on(narrow, DepthRange::zero_to_one);
  const std::vector<Frustum> both = {Frustum::from_matrix(wide, DepthRange::zero_to_one),
                                     Frustum::from_matrix(narrow, DepthRange::zero_to_one)};
  CHECK(check_views(tree, boxes, both, {&ow, &on}, "wide and narrow").entries == boxes.size());
  std::vector<std::uint32_t> out, bits;
  tree.cull_views(both.data(), 2, out, bits);
  for (std::size_t j = 0; j < out.size(); ++j) {
    if (!is_valid(boxes[out[j]])) CHECK(bits[j] == 3u);
    partial += bits[j] == 1u;
  }
  CHECK(partial > 0);  // non-vacuity: objects in one view only
  std::printf("cull_views families: %zu entries over 24 view sets, %zu objects in the wide view only\n", total, partial);
}

// Exact caster test for a finite frustum given by its 8 corners: does the box swept along `d`
// (t >= 0) meet the frustum? Equivalently: does the ray {t d} meet F - B (Minkowski)?
struct ExactCasters {
  std::array<glm::dvec3, 8> corners;
  std::vector<glm::dvec3> normals;

  explicit ExactCasters(const glm::mat4& view_proj, DepthRange depth) {
    const glm::dmat4 inv = glm::inverse(glm::dmat4(view_proj));
    const double z0 = depth == DepthRange::zero_to_one ? 0.0 : -1.0;
    for (int i = 0; i < 8; ++i) {
      const glm::dvec4 h = inv * glm::dvec4((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : z0, 1.0);
      corners[std::size_t(i)] = glm::dvec3(h) / h.w;
    }
    std::vector<glm::dvec3> edges;
    for (int i = 0; i < 8; ++i)
      for (int b = 1; b < 8; b <<= 1)
        if (!(i & b)) edges.push_back(corners[std::size_t(i | b)] - corners[std::size_t(i)]);
    const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto& a : axes) normals.push_back(a);
    for (std::size_t i = 0; i < edges.size(); ++i) {
      for (std::size_t j = i + 1; j < edges.size(); ++j) normals.push_back(glm::cross(edges[i], edges[j]));
      for (const auto& a : axes) normals.push_back(glm::cross(edges[i], a));
    }
  }

  bool caster(const Aabb& b, const glm::dvec3& d) const {
    double lo = 0.0, hi = std::numeric_limits<double>::infinity();
    for (const glm::dvec3& n0 : normals) {
      for (double s : {1.0, -1.0}) {
        const glm::dvec3 n = n0 * s;
        if (glm::dot(n, n) < 1e-18) continue;
        // Ray point t d must satisfy n.(t d) <= h_F(n) + h_{-B}(n).
        double hf = -1e300;
        for (const auto& c : corners) hf = std::max(hf, glm::dot(n, c));
        double hb = -1e300;
        for (int k = 0; k < 8; ++k) hb = std::max(hb, -glm::dot(n, glm::dvec3(corner(b, k))));
        const double rhs = hf + hb, a = glm::dot(n, d);
        const double eps = 1e-9 * (std::fabs(hf) + std::fabs(hb) + 1.0);
        if (std::fabs(a) < 1e-15) {
          if (rhs < -eps) return false;
        } else if (a > 0) {
          hi = std::min(hi, (rhs + eps) / a);
        } else {
          lo = std::max(lo, (rhs + eps) / a);
        }
      }
    }
    return lo <= hi;
  }
};

void shadow_casters() {
  support::Rng rng(23);
  std::size_t exact_total = 0, kept_total = 0, missed = 0, view_only = 0;
  for (int k = 0; k < 24; ++k) {
    const glm::vec3 eye(rng.uniform(-20, 20), rng.uniform(2, 20), rng.uniform(-20, 20));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.5f, 0.2f), rng.uniform(-1, 1)) * 10.0f;
    const DepthRange depth = k % 2 ? DepthRange::zero_to_one : DepthRange::negative_one_to_one;
    const Camera cam = support::make_camera(eye, target, rng.uniform(40, 90), 64, 64, 0.5f, rng.uniform(30, 80), depth,
                                            depth == DepthRange::zero_to_one && k % 4 == 1);
    glm::vec3 light = random_unit(rng);
    if (light.y > 0) light.y = -light.y;
    const Frustum view = frustum_of(cam);
    const ConvexVolume vol = shadow_caster_volume(view, light);
    const ExactCasters exact(cam.view_proj, depth);
    const glm::dvec3 d(light);
    for (int i = 0; i < 1500; ++i) {
      const glm::vec3 c(rng.uniform(-120, 120), rng.uniform(-5, 60), rng.uniform(-120, 120));
      const glm::vec3 h(rng.uniform(0.1f, 4), rng.uniform(0.1f, 4), rng.uniform(0.1f, 4));
      const Aabb b{c - h, c + h};
      const bool is_caster = exact.caster(b, d);
      const bool kept = vol.classify(b) != Containment::outside;
      exact_total += is_caster;
      kept_total += kept;
      missed += is_caster && !kept;
      view_only += is_caster && view.classify(b) == Containment::outside;
    }
  }
  CHECK_MSG(missed == 0, "%zu casters left out", missed);
  CHECK(view_only > 0);  // non-vacuity: casters outside the view exist and were kept
  std::printf("shadow casters: exact %zu, kept %zu (tightness %.3f), %zu casters outside the view\n", exact_total,
              kept_total, double(kept_total) / double(std::max<std::size_t>(exact_total, 1)), view_only);

  // Infinite far planes (standard and reversed-Z): casters sampled as small boxes around q - t d
  // for points q in the view, must all be kept.
  std::size_t samples = 0, lost = 0, planes_total = 0;
  for (int k = 0; k < 20; ++k) {
    const glm::vec3 eye(rng.uniform(-20, 20), rng.uniform(2, 20), rng.uniform(-20, 20));
    const glm::vec3 target = eye + glm::vec3(rng.uniform(-1, 1), rng.uniform(-0.5f, 0.2f), rng.uniform(-1, 1)) * 10.0f;
    const bool reversed = k % 2 == 1;
    const Camera cam = support::make_camera(eye, target, 70, 64, 64, 0.5f, 0.0f, DepthRange::zero_to_one, reversed);
    const glm::vec3 light = glm::normalize(glm::vec3(rng.uniform(-1, 1), -1.0f, rng.uniform(-1, 1)));
    const Frustum view = frustum_of(cam);
    const ConvexVolume vol = shadow_caster_volume(view, light);
    // A light shining along the view's infinite cone makes every point a possible caster (the
    // swept cone covers space): no planes is then the exact answer.
    planes_total += vol.plane_count();
    const PixelRays rays(cam);
    for (int i = 0; i < 400; ++i) {
      const Ray r = rays.ray_at(rng.uniform(0, 64), rng.uniform(0, 64));
      const glm::vec3 q = r.origin + r.direction * rng.uniform(1.0f, 500.0f);
      const glm::vec3 p = q - light * rng.uniform(0.0f, 300.0f);
      const Aabb b{p - 0.01f, p + 0.01f};
      ++samples;
      lost += vol.classify(b) == Containment::outside;
    }
  }
  CHECK_MSG(lost == 0, "%zu of %zu sampled casters lost (infinite far)", lost, samples);
  CHECK(planes_total >= 40);  // the volumes do cut
  // Degenerate input: everything may cast.
  CHECK(shadow_caster_volume(Frustum{}, glm::vec3(0, -1, 0)).plane_count() == 0);
  CHECK(shadow_caster_volume(frustum_of(support::make_camera(glm::vec3(0), glm::vec3(1), 60, 8, 8, 1, 10)), glm::vec3(0))
            .plane_count() == 0);
}
}  // namespace

int main() {
  volume_cull();
  views_cull();
  views_fast_paths();
  views_merged_planes();
  views_headset_pairs();
  shadow_casters();
  return cullkit_test::report("test_engine_views");
}
