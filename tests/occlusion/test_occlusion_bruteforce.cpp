// OcclusionTree against a double-precision brute force: for random occluder sets (quads, boxes) and
// random query boxes, every box the tree calls hidden is sampled (corners, face grids, random
// points) and each segment eye->sample must be blocked by some occluder. Zero false culls asserted;
// the number of hidden answers is checked too, so the test cannot pass by hiding nothing.
#include <cstdio>
#include <vector>

#include <cullkit/occlusion_tree.hpp>

#include "brute.hpp"
#include "check.hpp"

using namespace cullkit;
using cullkit::support::Rng;
using occlusion_test::Occluders;

namespace {

glm::vec3 random_unit(Rng& rng) {
  for (;;) {
    const glm::vec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const float l = glm::length(v);
    if (l > 0.1f && l <= 1.0f) return v / l;
  }
}

// A rectangle with center c, normal n, half sizes hx, hy; random in-plane rotation.
std::vector<glm::vec3> make_quad(Rng& rng, glm::vec3 c, glm::vec3 n, float hx, float hy) {
  glm::vec3 t = glm::cross(n, glm::vec3(0.3f, 1.0f, 0.2f));
  if (glm::length(t) < 1e-3f) t = glm::cross(n, glm::vec3(1, 0, 0));
  t = glm::normalize(t);
  glm::vec3 b = glm::cross(n, t);
  const float angle = rng.uniform(0.0f, 6.2831853f);
  const glm::vec3 u = std::cos(angle) * t + std::sin(angle) * b;
  const glm::vec3 v = glm::cross(n, u);
  std::vector<glm::vec3> q = {c - hx * u - hy * v, c + hx * u - hy * v, c + hx * u + hy * v, c - hx * u + hy * v};
  if (rng.uniform() < 0.5f) std::reverse(q.begin(), q.end());
  return q;
}

Aabb make_box(glm::vec3 c, glm::vec3 half) { return Aabb{c - half, c + half}; }

struct Tally {
  long queries = 0, hidden = 0, false_culls = 0;
  long faces_hidden = 0;  // queries whose every front face, asked as a polygon, is hidden
  long faces_hidden_box_visible = 0;  // ... while the box query says visible (precision lost)
};

// The box's front faces (world coordinates) as polygons, asked one by one: the exact face-splitting
// walk, which the box query's outline cone must match in precision.
bool front_faces_hidden(const OcclusionTree& tree, const Aabb& box) {
  const glm::vec3 e = tree.eye();
  int faces = 0;
  for (int axis = 0; axis < 3; ++axis) {
    int side;
    if (e[axis] < box.min[axis]) side = 0;
    else if (e[axis] > box.max[axis]) side = 1;
    else continue;
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3, base = side << axis;
    ConvexPolygon face;
    for (int c : {base, base | (1 << a1), base | (1 << a1) | (1 << a2), base | (1 << a2)}) face.push_back(corner(box, c));
    if (!tree.is_occluded(face)) return false;
    ++faces;
  }
  return faces > 0;
}

// Checks every hidden answer of `tree` for `queries` against the brute force.
void check_queries(const OcclusionTree& tree, const Occluders& occ, const std::vector<Aabb>& queries, Rng& rng,
                   Tally& tally, unsigned seed, const char* scenario) {
  for (std::size_t i = 0; i < queries.size(); ++i) {
    ++tally.queries;
    const bool hidden = tree.is_occluded(queries[i]);
    if (front_faces_hidden(tree, queries[i])) {
      ++tally.faces_hidden;
      tally.faces_hidden_box_visible += hidden ? 0 : 1;
    }
    if (!hidden) continue;
    ++tally.hidden;
    glm::dvec3 w;
    const bool visible = occlusion_test::find_visible_sample(occ, tree.eye(), queries[i], rng, 5, 24, &w);
    if (visible) ++tally.false_culls;
    CHECK_MSG(!visible, "%s seed %u query %zu: hidden but point (%.9g %.9g %.9g) is visible", scenario, seed, i,
              w.x, w.y, w.z);
  }
}

void random_scenes(const OcclusionParams& params, const char* name, Tally& tally) {
  for (unsigned seed = 1; seed <= 120; ++seed) {
    Rng rng(seed * 7919u + (params.azimuth_planes ? 17u : 0u));
    const glm::vec3 eye(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    OcclusionTree tree(eye, params);
    Occluders occ;
    const int kind = seed % 3;  // 0 quads, 1 boxes, 2 both
    const int count = rng.range(1, 40);
    for (int k = 0; k < count; ++k) {
      const glm::vec3 dir = random_unit(rng);
      const glm::vec3 c = eye + dir * rng.uniform(1.5f, 8.0f);
      const bool box = kind == 1 || (kind == 2 && rng.uniform() < 0.5f);
      if (box) {
        const Aabb b = make_box(c, glm::vec3(rng.uniform(0.2f, 2.5f), rng.uniform(0.2f, 2.5f), rng.uniform(0.2f, 2.5f)));
        occ.boxes.push_back(b);
        tree.insert_box_occluder(b);
      } else {
        // Mostly facing the eye, sometimes oblique.
        glm::vec3 n = glm::normalize(-dir + random_unit(rng) * rng.uniform(0.0f, 1.2f));
        const auto q = make_quad(rng, c, n, rng.uniform(0.3f, 3.0f), rng.uniform(0.3f, 3.0f));
        occ.polygons.push_back(q);
        tree.insert_occluder(q.data(), q.size());
      }
    }
    std::vector<Aabb> queries;
    for (int k = 0; k < 150; ++k) {
      const glm::vec3 c = eye + random_unit(rng) * rng.uniform(2.0f, 20.0f);
      const float s = rng.uniform() < 0.3f ? 0.01f : rng.uniform(0.05f, 2.0f);
      queries.push_back(make_box(c, glm::vec3(s * rng.uniform(0.2f, 1.0f), s, s * rng.uniform(0.2f, 1.0f))));
    }
    check_queries(tree, occ, queries, rng, tally, seed, name);
  }
}

// A wall of touching quads (and a wall of touching boxes): boxes behind a seam are hidden only by
// the union. A gap between two walls must keep what is seen through it visible.
void walls(Tally& tally) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    Rng rng(seed);
    const glm::vec3 eye(rng.uniform(-0.5f, 0.5f), rng.uniform(-0.5f, 0.5f), 0.0f);
    const float zw = -rng.uniform(2.0f, 6.0f);
    OcclusionTree tree(eye);
    Occluders occ;
    // 4x4 touching tiles covering [-4,4]^2 at z = zw, alternately wound.
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const float x0 = -4.0f + 2.0f * i, y0 = -4.0f + 2.0f * j;
        std::vector<glm::vec3> q = {{x0, y0, zw}, {x0 + 2, y0, zw}, {x0 + 2, y0 + 2, zw}, {x0, y0 + 2, zw}};
        if ((i + j) % 2) std::reverse(q.begin(), q.end());
        occ.polygons.push_back(q);
        tree.insert_occluder(q.data(), q.size());
      }
    std::vector<Aabb> queries;
    for (int k = 0; k < 40; ++k) {
      // Behind the wall, inside its shadow, many straddling the shadows of seams.
      const glm::vec3 c(rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f), zw - rng.uniform(0.5f, 3.0f));
      queries.push_back(make_box(c, glm::vec3(0.4f)));
    }
    // Boxes inside the shadow of one tile (no seam): all must be hidden.
    int single = 0, single_hidden = 0;
    for (int k = 0; k < 20; ++k) {
      const int i = rng.range(0, 3), j = rng.range(0, 3);
      const float depth = rng.uniform(0.2f, 2.0f);
      const float s = (zw - depth - eye.z) / (zw - eye.z);  // shadow scale at that depth
      const glm::vec3 tile_center(-3.0f + 2.0f * i, -3.0f + 2.0f * j, zw);
      const glm::vec3 c = eye + (tile_center - eye) * s;
      const Aabb b = make_box(c, glm::vec3(0.3f, 0.3f, 0.1f));
      ++single;
      single_hidden += tree.is_occluded(b) ? 1 : 0;
      queries.push_back(b);
    }
    CHECK_MSG(single_hidden == single, "tiles seed %u: %d of %d boxes behind one tile hidden", seed, single_hidden,
              single);
    Tally local;
    check_queries(tree, occ, queries, rng, local, seed, "tiles");
    tally.queries += local.queries;
    tally.hidden += local.hidden;
    tally.false_culls += local.false_culls;

    // Two walls with a gap of 1e-4 (relative to a scene of size ~10) between them.
    for (int axis_case = 0; axis_case < 2; ++axis_case) {
      OcclusionTree t2(eye);
      Occluders o2;
      const float g = 1e-3f;  // gap width: 1e-4 of the 10-unit scene
      // Box walls have depth: look straight through the slot (the gap is at the eye's x).
      const float gx = axis_case == 0 ? rng.uniform(-1.0f, 1.0f) : eye.x;
      if (axis_case == 0) {
        std::vector<glm::vec3> a = {{-5, -5, zw}, {gx - g / 2, -5, zw}, {gx - g / 2, 5, zw}, {-5, 5, zw}};
        std::vector<glm::vec3> b = {{gx + g / 2, -5, zw}, {5, -5, zw}, {5, 5, zw}, {gx + g / 2, 5, zw}};
        o2.polygons = {a, b};
        t2.insert_occluder(a.data(), 4);
        t2.insert_occluder(b.data(), 4);
      } else {
        const Aabb a{{-5, -5, zw - 1}, {gx - g / 2, 5, zw}};
        const Aabb b{{gx + g / 2, -5, zw - 1}, {5, 5, zw}};
        o2.boxes = {a, b};
        t2.insert_box_occluder(a);
        t2.insert_box_occluder(b);
      }
      // A point seen through the gap, and a small box around it.
      const glm::vec3 through(gx, rng.uniform(-1.0f, 1.0f), zw);
      const glm::vec3 dir = glm::normalize(through - eye);
      const glm::vec3 p = through + dir * rng.uniform(1.5f, 4.0f);
      CHECK(!o2.blocks(glm::dvec3(eye), glm::dvec3(p)));
      const Aabb q = make_box(p, glm::vec3(0.05f));
      CHECK_MSG(!t2.is_occluded(q), "gap seed %u case %d: a box seen through the gap is hidden", seed, axis_case);
      // While a box beside the gap, behind one wall, is hidden.
      const glm::vec3 side(gx - 2.0f, through.y, zw - 2.0f);
      const Aabb q2 = make_box(side, glm::vec3(0.1f));
      CHECK_MSG(t2.is_occluded(q2), "gap seed %u case %d: a box behind a wall is not hidden", seed, axis_case);
    }
  }
}

// The seed gives up on a box straddling an occluder's own plane; we split it. A box crossing the
// plane of a far wall, all of it behind a nearer wall, must be hidden whatever the insertion order.
void straddling_own_plane() {
  for (int order = 0; order < 2; ++order) {
    OcclusionTree tree(glm::vec3(0.0f));
    const std::vector<glm::vec3> far_wall = {{-10, -10, -8}, {10, -10, -8}, {10, 10, -8}, {-10, 10, -8}};
    const std::vector<glm::vec3> near_wall = {{-1, -1, -2}, {1, -1, -2}, {1, 1, -2}, {-1, 1, -2}};
    if (order == 0) {
      tree.insert_occluder(far_wall.data(), 4);
      tree.insert_occluder(near_wall.data(), 4);
    } else {
      tree.insert_occluder(near_wall.data(), 4);
      tree.insert_occluder(far_wall.data(), 4);
    }
    CHECK_MSG(tree.is_occluded(Aabb{{-1, -1, -9}, {1, 1, -7}}), "order %d: box across the far wall's plane", order);
    CHECK_MSG(tree.is_occluded(Aabb{{5, 5, -12}, {6, 6, -9}}), "order %d: box behind the far wall only", order);
    CHECK_MSG(!tree.is_occluded(Aabb{{5, 5, -7.5f}, {6, 6, -6}}), "order %d: box in front of the far wall", order);
    // A query polygon too.
    ConvexPolygon poly;
    for (auto p : {glm::vec3(-1, -1, -5), glm::vec3(1, -1, -5), glm::vec3(1, 1, -5)}) poly.push_back(p);
    CHECK(tree.is_occluded(poly));
  }
}

}  // namespace

int main() {
  Tally plain, top, wall;
  random_scenes(OcclusionParams{}, "random", plain);
  OcclusionParams two_level;
  two_level.azimuth_planes = 4;
  two_level.elevation_planes = 3;
  random_scenes(two_level, "random+top", top);
  walls(wall);
  straddling_own_plane();
  std::printf("random:     %ld queries, %ld hidden, %ld false culls\n", plain.queries, plain.hidden, plain.false_culls);
  std::printf("random+top: %ld queries, %ld hidden, %ld false culls\n", top.queries, top.hidden, top.false_culls);
  std::printf("walls:      %ld queries, %ld hidden, %ld false culls\n", wall.queries, wall.hidden, wall.false_culls);
  for (const Tally* t : {&plain, &top, &wall})
    std::printf("precision:  %ld boxes with every front face hidden, %ld of them called visible\n", t->faces_hidden,
                t->faces_hidden_box_visible);
  // The box query (outline cone, faces only where the front straddles an occluder's plane) may differ
  // from the face-by-face walk only by margin effects: a handful, never a trend.
  for (const Tally* t : {&plain, &top, &wall}) CHECK(t->faces_hidden_box_visible * 200 <= t->faces_hidden);
  CHECK(plain.hidden > plain.queries / 20);  // the test must exercise hidden answers
  CHECK(top.hidden > top.queries / 20);
  return cullkit_test::report("test_occlusion_bruteforce");
}
