// Occluder fusion: a surface given in pieces must hide what the whole surface hides. A wall as one
// quad, as two triangles, as a jittered triangle mesh (shared vertices, slightly curved) and as two
// boxes side by side; small cubes behind every seam, seen from many eyes. Every cube whose
// margin-grown copy is blocked at every sample (double-precision brute force) must be hidden, cubes
// peeking past the wall's outer edges must stay visible, and every hidden answer is checked against
// the brute force (no false culls). Then random triangulated surfaces and rows of boxes, every hidden
// answer checked against the brute force.
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/occlusion_tree.hpp>

#include "brute.hpp"
#include "check.hpp"

using namespace cullkit;
using cullkit::support::Rng;
using occlusion_test::Occluders;

// Random vectors are built with braces: their components are then drawn left to right on every
// compiler (argument order in parentheses is unspecified), so gcc and clang test the same scenes.
namespace {

// The wall spans x in [-wx, wx], y in [0, wy] at z = 0; eyes look at it from z < 0.
constexpr float wx = 5.0f, wy = 4.0f;

enum class WallKind { quad, two_triangles, mesh, two_boxes };

const char* kind_name(WallKind k) {
  switch (k) {
    case WallKind::quad: return "quad";
    case WallKind::two_triangles: return "two triangles";
    case WallKind::mesh: return "jittered mesh";
    case WallKind::two_boxes: return "two boxes";
  }
  return "?";
}

struct Wall {
  Occluders occ;
  std::vector<glm::vec3> seam_points;  // points on the seams (where the pieces meet)
};

// The wall as pieces. The mesh is a grid of (n+1) x (m+1) vertices, interior ones jittered in the
// plane and off it (a gently curved wall), each cell split into two triangles along a random diagonal.
Wall make_wall(WallKind kind, Rng& rng) {
  Wall w;
  const glm::vec3 a(-wx, 0, 0), b(wx, 0, 0), c(wx, wy, 0), d(-wx, wy, 0);
  switch (kind) {
    case WallKind::quad:
      w.occ.polygons.push_back({a, b, c, d});
      for (int i = 0; i <= 20; ++i) w.seam_points.push_back(a + (c - a) * (float(i) / 20.0f));
      break;
    case WallKind::two_triangles:
      w.occ.polygons.push_back({a, b, c});
      w.occ.polygons.push_back({a, c, d});
      for (int i = 0; i <= 20; ++i) w.seam_points.push_back(a + (c - a) * (float(i) / 20.0f));
      break;
    case WallKind::mesh: {
      const int n = 6, m = 4;
      std::vector<glm::vec3> v;
      for (int j = 0; j <= m; ++j)
        for (int i = 0; i <= n; ++i) {
          glm::vec3 p(-wx + 2 * wx * i / n, wy * j / m, 0.0f);
          if (i > 0 && i < n && j > 0 && j < m)
            p += glm::vec3{rng.uniform(-0.3f, 0.3f), rng.uniform(-0.3f, 0.3f), rng.uniform(-0.05f, 0.05f)};
          v.push_back(p);
        }
      const auto at = [&](int i, int j) { return v[static_cast<std::size_t>(j * (n + 1) + i)]; };
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < n; ++i) {
          const glm::vec3 p00 = at(i, j), p10 = at(i + 1, j), p11 = at(i + 1, j + 1), p01 = at(i, j + 1);
          if (rng.uniform() < 0.5f) {
            w.occ.polygons.push_back({p00, p10, p11});
            w.occ.polygons.push_back({p00, p11, p01});
            for (int k = 1; k < 8; ++k) w.seam_points.push_back(p00 + (p11 - p00) * (float(k) / 8.0f));
          } else {
            w.occ.polygons.push_back({p00, p10, p01});
            w.occ.polygons.push_back({p10, p11, p01});
            for (int k = 1; k < 8; ++k) w.seam_points.push_back(p10 + (p01 - p10) * (float(k) / 8.0f));
          }
          for (int k = 0; k < 8; ++k) {
            w.seam_points.push_back(p00 + (p10 - p00) * (float(k) / 8.0f));
            w.seam_points.push_back(p00 + (p01 - p00) * (float(k) / 8.0f));
          }
        }
      break;
    }
    case WallKind::two_boxes:
      w.occ.boxes.push_back(Aabb{{-wx, 0, 0}, {0, wy, 1}});
      w.occ.boxes.push_back(Aabb{{0, 0, 0}, {wx, wy, 1}});
      for (int i = 0; i <= 20; ++i) w.seam_points.push_back(glm::vec3(0, wy * float(i) / 20.0f, 0));
      break;
  }
  return w;
}

void insert(OcclusionTree& tree, const Occluders& occ, bool reversed) {
  const std::size_t np = occ.polygons.size(), nb = occ.boxes.size();
  for (std::size_t k = 0; k < np; ++k) {
    const auto& p = occ.polygons[reversed ? np - 1 - k : k];
    tree.insert_occluder(p.data(), p.size());
  }
  for (std::size_t k = 0; k < nb; ++k) tree.insert_box_occluder(occ.boxes[reversed ? nb - 1 - k : k]);
}

Aabb cube(const glm::vec3& c, float h) { return Aabb{c - glm::vec3(h), c + glm::vec3(h)}; }

// Every sample of the cube grown by `grow` blocked: hidden with room to spare.
bool clearly_hidden(const Occluders& occ, const glm::vec3& eye, const Aabb& box, float grow, Rng& rng) {
  const Aabb big{box.min - glm::vec3(grow), box.max + glm::vec3(grow)};
  return !occlusion_test::find_visible_sample(occ, eye, big, rng, 6, 16, nullptr);
}

struct Tally {
  long expected_hidden = 0, hidden = 0, peeking = 0, peeking_visible = 0, false_culls = 0;
};

void run(WallKind kind, Tally& tally) {
  for (unsigned seed = 1; seed <= 40; ++seed) {
    Rng rng(seed * 104729u + static_cast<unsigned>(kind));
    const Wall w = make_wall(kind, rng);
    glm::vec3 eye{rng.uniform(-7.0f, 7.0f), rng.uniform(-2.0f, 9.0f), -rng.uniform(3.0f, 30.0f)};
    if (seed % 5 == 0) eye.x = 0.0f;  // in the plane of the boxes' shared face
    // Near that plane (not in it) two boxes' outlines overlap by less than the margin and do not
    // fuse (a documented limit, measured by near_plane_boxes): keep other eyes clear of it.
    else if (kind == WallKind::two_boxes && std::fabs(eye.x) < 0.25f) eye.x = eye.x < 0.0f ? eye.x - 0.25f : eye.x + 0.25f;
    if (seed % 5 == 1) eye.y = wy;    // in the plane of the top
    OcclusionTree tree(eye);
    insert(tree, w.occ, seed % 2 == 1);
    const long missed_before = tally.expected_hidden - tally.hidden;
    const float back = kind == WallKind::two_boxes ? 1.0f : 0.06f;  // behind every piece
    // Cubes behind seam points, on the ray from the eye through the seam.
    for (int k = 0; k < 40; ++k) {
      const glm::vec3 s = w.seam_points[rng.next() % w.seam_points.size()];
      const float h = rng.uniform(0.02f, 0.2f);
      const float z = back + h + rng.uniform(0.05f, 4.0f);
      const glm::vec3 dir = s - eye;
      const glm::vec3 c = eye + dir * ((z - eye.z) / dir.z);
      const Aabb q = cube(c, h);
      const bool hidden = tree.is_occluded(q);
      glm::dvec3 witness;
      const bool visible = occlusion_test::find_visible_sample(w.occ, eye, q, rng, 5, 16, &witness);
      if (hidden && visible) {
        ++tally.false_culls;
        CHECK_MSG(false, "%s seed %u: cube at (%g %g %g) hidden but (%.9g %.9g %.9g) is visible", kind_name(kind),
                  seed, c.x, c.y, c.z, witness.x, witness.y, witness.z);
      }
      if (clearly_hidden(w.occ, eye, q, 0.02f * (1.0f + h), rng)) {
        ++tally.expected_hidden;
        tally.hidden += hidden ? 1 : 0;
        CHECK_MSG(hidden, "%s seed %u (eye %g %g %g): cube at (%g %g %g) half %g behind a seam is not hidden",
                  kind_name(kind), seed, eye.x, eye.y, eye.z, c.x, c.y, c.z, h);
      }
    }
    if (tally.expected_hidden - tally.hidden > missed_before)
      std::fprintf(stderr, "%s seed %u (eye %g %g %g): %ld cubes behind seams not hidden\n", kind_name(kind), seed, eye.x,
                   eye.y, eye.z, tally.expected_hidden - tally.hidden - missed_before);
    // Cubes peeking past the wall's outer edges: centred on the ray through an outer edge point.
    for (int k = 0; k < 12; ++k) {
      glm::vec3 s;
      const float t = rng.uniform(0.1f, 0.9f);
      switch (k % 4) {
        case 0: s = glm::vec3(-wx, wy * t, 0); break;
        case 1: s = glm::vec3(wx, wy * t, 0); break;
        case 2: s = glm::vec3(wx * (2 * t - 1), 0, 0); break;
        default: s = glm::vec3(wx * (2 * t - 1), wy, 0); break;
      }
      const float h = rng.uniform(0.05f, 0.2f);
      const float z = back + 1.0f + h + rng.uniform(0.0f, 3.0f);
      const glm::vec3 dir = s - eye;
      const Aabb q = cube(eye + dir * ((z - eye.z) / dir.z), h);
      glm::dvec3 witness;
      if (!occlusion_test::find_visible_sample(w.occ, eye, q, rng, 5, 16, &witness)) continue;
      ++tally.peeking;
      const bool hidden = tree.is_occluded(q);
      tally.peeking_visible += hidden ? 0 : 1;
      if (hidden) ++tally.false_culls;
      CHECK_MSG(!hidden, "%s seed %u: cube peeking past the outer edge is hidden", kind_name(kind), seed);
    }
  }
}


// Conservativeness of fused occluders: random triangulated surfaces (terrain height fields, curved
// walls on a cylinder, rows of touching boxes), every shared edge a seam, random query boxes around
// and behind them. Every hidden answer is checked with the double-precision brute force.
struct RandomTally {
  long queries = 0, hidden = 0, false_culls = 0;
};

void add_grid(Occluders& occ, OcclusionTree& tree, int n, int m, const std::vector<glm::vec3>& v) {
  const auto at = [&](int i, int j) { return v[static_cast<std::size_t>(j * (n + 1) + i)]; };
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const glm::vec3 t1[3] = {at(i, j), at(i + 1, j), at(i + 1, j + 1)};
      const glm::vec3 t2[3] = {at(i, j), at(i + 1, j + 1), at(i, j + 1)};
      for (const glm::vec3* t : {t1, t2}) {
        occ.polygons.push_back({t[0], t[1], t[2]});
        tree.insert_occluder(t, 3);
      }
    }
}

void random_surfaces(RandomTally& tally) {
  for (unsigned seed = 1; seed <= 60; ++seed) {
    Rng rng(seed * 2654435761u);
    const glm::vec3 eye{rng.uniform(-3, 3), rng.uniform(0.5f, 4.0f), rng.uniform(-3, 3)};
    OcclusionTree tree(eye);
    Occluders occ;
    const int kind = seed % 3;
    if (kind == 0) {  // terrain: a height field under and around the eye
      const int n = 10;
      std::vector<glm::vec3> v;
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
          v.emplace_back(-10.0f + 2.0f * i, rng.uniform(-0.5f, 2.5f), -10.0f + 2.0f * j);
      add_grid(occ, tree, n, n, v);
    } else if (kind == 1) {  // a curved wall: a cylinder piece around the eye
      const int n = 12, m = 3;
      const float r = rng.uniform(3.0f, 6.0f), a0 = rng.uniform(0.0f, 6.28f);
      std::vector<glm::vec3> v;
      for (int j = 0; j <= m; ++j)
        for (int i = 0; i <= n; ++i) {
          const float a = a0 + 3.0f * float(i) / n;
          const float rr = r + rng.uniform(-0.2f, 0.2f);
          v.push_back(eye + glm::vec3(rr * std::cos(a), -2.0f + 5.0f * float(j) / m + rng.uniform(-0.1f, 0.1f),
                                      rr * std::sin(a)));
        }
      add_grid(occ, tree, n, m, v);
    } else {  // a row of touching boxes, sometimes with the eye in the plane of a shared face
      const float z = eye.z + rng.uniform(2.0f, 5.0f);
      float x = -8.0f;
      for (int k = 0; k < 8; ++k) {
        const float w = rng.uniform(0.5f, 2.5f);
        const Aabb b{{x, 0.0f, z}, {x + w, rng.uniform(1.0f, 6.0f), z + rng.uniform(0.2f, 3.0f)}};
        occ.boxes.push_back(b);
        tree.insert_box_occluder(b);
        x += w;
      }
    }
    for (int k = 0; k < 150; ++k) {
      const glm::vec3 dir = glm::normalize(glm::vec3{rng.uniform(-1, 1), rng.uniform(-1, 0.3f), rng.uniform(-1, 1)});
      const glm::vec3 c = eye + dir * rng.uniform(2.0f, 25.0f);
      const float h = rng.uniform() < 0.3f ? 0.02f : rng.uniform(0.05f, 1.0f);
      const Aabb q{c - glm::vec3(h, h * rng.uniform(0.3f, 1.0f), h), c + glm::vec3(h)};
      ++tally.queries;
      if (!tree.is_occluded(q)) continue;
      ++tally.hidden;
      glm::dvec3 w;
      const bool visible = occlusion_test::find_visible_sample(occ, eye, q, rng, 6, 24, &w);
      tally.false_culls += visible ? 1 : 0;
      CHECK_MSG(!visible, "random surface seed %u query %d: hidden but (%.9g %.9g %.9g) is visible", seed, k, w.x, w.y,
                w.z);
    }
  }
}

// Two boxes with the eye 1e-4 to 0.1 beside the plane of their shared face: reported, not
// required (see docs/occlusion_fusion.md, limits); false culls are still checked.
void near_plane_boxes() {
  long behind = 0, hidden = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    Rng rng(seed * 7727u);
    const Wall w = make_wall(WallKind::two_boxes, rng);
    const float offset = std::pow(10.0f, rng.uniform(-4.0f, -1.0f));
    const glm::vec3 eye{seed % 2 ? offset : -offset, rng.uniform(-2.0f, 9.0f), -rng.uniform(3.0f, 30.0f)};
    OcclusionTree tree(eye);
    insert(tree, w.occ, seed % 2 == 1);
    for (int k = 0; k < 20; ++k) {
      const glm::vec3 s = w.seam_points[rng.next() % w.seam_points.size()];
      const float h = rng.uniform(0.02f, 0.2f);
      const float z = 1.0f + h + rng.uniform(0.05f, 4.0f);
      const glm::vec3 dir = s - eye;
      const Aabb q = cube(eye + dir * ((z - eye.z) / dir.z), h);
      const bool is_hidden = tree.is_occluded(q);
      if (is_hidden) CHECK(!occlusion_test::find_visible_sample(w.occ, eye, q, rng, 5, 16, nullptr));
      if (!clearly_hidden(w.occ, eye, q, 0.02f * (1.0f + h), rng)) continue;
      ++behind;
      hidden += is_hidden ? 1 : 0;
    }
  }
  std::printf("two boxes, eye 1e-4..0.1 beside the shared face's plane: %ld of %ld cubes behind the seam hidden\n",
              hidden, behind);
}

}  // namespace

int main() {
  for (WallKind kind : {WallKind::quad, WallKind::two_triangles, WallKind::mesh, WallKind::two_boxes}) {
    Tally t;
    run(kind, t);
    std::printf("%-14s %ld of %ld cubes behind seams hidden; %ld of %ld peeking cubes visible; %ld false culls\n",
                kind_name(kind), t.hidden, t.expected_hidden, t.peeking_visible, t.peeking, t.false_culls);
    // The scenes must exercise both answers.
    CHECK(t.expected_hidden >= 200);
    CHECK(t.peeking >= 100);
  }
  near_plane_boxes();
  RandomTally random;
  random_surfaces(random);
  std::printf("random surfaces: %ld queries, %ld hidden, %ld false culls\n", random.queries, random.hidden,
              random.false_culls);
  CHECK(random.hidden >= random.queries / 10);  // the scenes must hide a good share
  return cullkit_test::report("test_occlusion_fusion");
}
