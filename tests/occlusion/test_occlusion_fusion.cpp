// Occluder fusion: a surface given in pieces must hide what the whole surface hides. A wall as one
// quad, as two triangles, as a jittered triangle mesh (shared vertices, slightly curved) and as two
// boxes side by side; small cubes behind every seam, seen from many eyes. Every cube whose
// margin-grown copy is blocked at every sample (double-precision brute force) must be hidden, cubes
// peeking past the wall's outer edges must stay visible, and every hidden answer is checked against
// the brute force (no false culls).
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/occlusion_tree.hpp>

#include "brute.hpp"
#include "check.hpp"

using namespace cullkit;
using cullkit::support::Rng;
using occlusion_test::Occluders;

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
            p += glm::vec3(rng.uniform(-0.3f, 0.3f), rng.uniform(-0.3f, 0.3f), rng.uniform(-0.05f, 0.05f));
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
    glm::vec3 eye(rng.uniform(-7.0f, 7.0f), rng.uniform(-2.0f, 9.0f), -rng.uniform(3.0f, 30.0f));
    if (seed % 5 == 0) eye.x = 0.0f;  // in the plane of the boxes' shared face
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
        // A jittered mesh fuses only in part (see docs/occlusion_fusion.md): counted, checked below.
        if (kind != WallKind::mesh)
          CHECK_MSG(hidden, "%s seed %u (eye %g %g %g): cube at (%g %g %g) half %g behind a seam is not hidden",
                    kind_name(kind), seed, eye.x, eye.y, eye.z, c.x, c.y, c.z, h);
      }
    }
    if (kind != WallKind::mesh && tally.expected_hidden - tally.hidden > missed_before)
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
    // Around a mesh vertex where many triangles meet, a copy may reach a part of the tree the
    // triangle covering it never reached; 1,149 of 1,301 here (0 without seams).
    if (kind == WallKind::mesh) CHECK(t.hidden * 100 >= t.expected_hidden * 85);
  }
  return cullkit_test::report("test_occlusion_fusion");
}
