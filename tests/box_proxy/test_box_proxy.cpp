// BoxProxy against brute force (oracle: the definition, evaluated independently in double).
//  * The region table re-derived from scratch: silhouette edges = edges of the front faces that only
//    one front face has, chained into a loop, oriented counter-clockwise seen from the eye.
//  * box_silhouette equals that brute-force outline (same corners, same cyclic order) for eyes in all
//    26 outside regions, exactly on face planes and edge lines, far away (1e6), for flat, thin and
//    point-like boxes; the outline is convex and counter-clockwise seen from the eye.
//  * proxy_hides (front_faces) agrees with a double-precision slab ray-box test on random points: it
//    never hides a visible point, and misses a hidden one only within 1e-5 relative of the boundary.
//  * The seed's centre plane hides a visible rooftop antenna (the flaw stays demonstrated).
//  * Bad input: NaN/inf eye, invalid box, eye inside or on the box.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include <cullkit/box_proxy.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"

using namespace cullkit;
using glm::dvec3;

namespace {

constexpr std::uint64_t kSeed = 0xB0C5'2024ull;

struct Outline {
  int count = 0;
  int ids[6] = {0, 0, 0, 0, 0, 0};
  int face_count = 0;
  int faces[3] = {0, 0, 0};  // 2 * axis + side
};

dvec3 dcorner(const Aabb& b, int i) { return dvec3(corner(b, i)); }

// The definition, nothing shared with the library: a face with area is front when the eye is
// strictly on the outer side of its plane; the outline is the boundary of the union of front faces.
Outline brute_outline(const Aabb& b, const dvec3& eye) {
  Outline out;
  if (!is_valid(b)) return out;
  int edge_uses[8][8] = {};
  for (int a = 0; a < 3; ++a) {
    const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
    if (!(b.max[b1] > b.min[b1]) || !(b.max[b2] > b.min[b2])) continue;  // no area
    for (int s = 0; s < 2; ++s) {
      dvec3 outward(0.0);
      outward[a] = s ? 1.0 : -1.0;
      const dvec3 on_face = s ? dvec3(b.max) : dvec3(b.min);
      if (!(glm::dot(outward, eye - on_face) > 0.0)) continue;
      out.faces[out.face_count++] = 2 * a + s;
      const int base = s << a;
      const int cyc[4] = {base, base | (1 << b1), base | (1 << b1) | (1 << b2), base | (1 << b2)};
      for (int k = 0; k < 4; ++k) {
        const int u = cyc[k], v = cyc[(k + 1) % 4];
        ++edge_uses[u][v];
        ++edge_uses[v][u];
      }
    }
  }
  if (out.face_count == 0) return out;
  // Boundary edges: used once. Chain them from the smallest corner id.
  int start = -1;
  for (int u = 0; u < 8 && start < 0; ++u)
    for (int v = 0; v < 8; ++v)
      if (edge_uses[u][v] == 1) {
        start = u;
        break;
      }
  if (start < 0) return out;
  int prev = -1, cur = start;
  for (int step = 0; step < 8; ++step) {
    out.ids[out.count++] = cur;
    int next = -1;
    for (int v = 0; v < 8; ++v)
      if (edge_uses[cur][v] == 1 && v != prev) {
        next = v;
        break;
      }
    if (next < 0 || next == start || out.count == 6) break;
    prev = cur;
    cur = next;
  }
  // Orientation: Newell normal toward the eye means counter-clockwise seen from the eye.
  dvec3 normal(0.0);
  for (int i = 0; i < out.count; ++i)
    normal += glm::cross(dcorner(b, out.ids[i]), dcorner(b, out.ids[(i + 1) % out.count]));
  if (glm::dot(normal, eye - dcorner(b, out.ids[0])) < 0.0) {
    for (int i = 1, j = out.count - 1; i < j; ++i, --j) std::swap(out.ids[i], out.ids[j]);
  }
  return out;
}

// Same cyclic sequence of positions (any start, same direction)?
bool same_cycle(const glm::vec3* got, std::size_t n, const Aabb& b, const Outline& want) {
  if (n != static_cast<std::size_t>(want.count)) return false;
  if (n == 0) return true;
  for (std::size_t k = 0; k < n; ++k) {
    bool all = true;
    for (std::size_t i = 0; i < n && all; ++i) all = got[(i + k) % n] == corner(b, want.ids[i]);
    if (all) return true;
  }
  return false;
}

// Convex and counter-clockwise seen from the eye: every turn is left (or straight, when two outline
// edges lie in a face plane through the eye), and the polygon has area.
bool convex_ccw(const glm::vec3* c, std::size_t n, const dvec3& eye) {
  if (n < 3) return false;
  double scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) scale = std::max(scale, glm::length(dvec3(c[i]) - eye));
  bool some_left = false;
  for (std::size_t i = 0; i < n; ++i) {
    const dvec3 a(c[i]), b(c[(i + 1) % n]), d(c[(i + 2) % n]);
    const dvec3 e1 = b - a, e2 = d - b;
    const double turn = glm::dot(glm::cross(e1, e2), eye - b);
    const double tol = 1e-12 * glm::length(e1) * glm::length(e2) * scale;
    if (turn < -tol) return false;
    if (turn > tol) some_left = true;
  }
  return some_left;
}

// Exact-ish oracle: does the segment eye -> p pass through the closed box before reaching p?
// Slab method in double. Points inside the box count as hidden.
bool segment_hidden(const Aabb& b, const dvec3& eye, const dvec3& p) {
  const dvec3 dir = p - eye;
  double t_in = -std::numeric_limits<double>::infinity();
  double t_out = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double lo = b.min[a], hi = b.max[a];
    if (dir[a] == 0.0) {
      if (eye[a] < lo || eye[a] > hi) return false;
      continue;
    }
    double t0 = (lo - eye[a]) / dir[a], t1 = (hi - eye[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  return t_in <= t_out && t_out >= 0.0 && t_in < 1.0;
}

Aabb grown(const Aabb& b, float rel) {
  const float s = rel * std::max(1.0f, glm::length(b.max - b.min));
  return Aabb{b.min - glm::vec3(s), b.max + glm::vec3(s)};
}

Aabb random_box(support::Rng& rng, float lo_extent, float hi_extent) {
  const glm::vec3 c(rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50));
  const glm::vec3 h(rng.uniform(lo_extent, hi_extent), rng.uniform(lo_extent, hi_extent),
                    rng.uniform(lo_extent, hi_extent));
  return Aabb{c - h, c + h};
}

// A random eye in region r of box b (coordinates strictly below, strictly within, strictly above).
glm::vec3 eye_in_region(support::Rng& rng, const Aabb& b, int r) {
  const int digit[3] = {r % 3, (r / 3) % 3, r / 9};
  glm::vec3 e;
  for (int a = 0; a < 3; ++a) {
    const float ext = std::max(b.max[a] - b.min[a], 1e-3f);
    if (digit[a] == 0) e[a] = b.min[a] - rng.uniform(0.01f, 5.0f) * ext;
    else if (digit[a] == 2) e[a] = b.max[a] + rng.uniform(0.01f, 5.0f) * ext;
    else e[a] = b.min[a] + rng.uniform(0.0f, 1.0f) * (b.max[a] - b.min[a]);
  }
  return e;
}

int g_outlines_checked = 0;

// Checks box_silhouette and make_box_proxy against the brute force for one eye.
void check_outline(const Aabb& b, const glm::vec3& eye, const char* what, std::uint64_t seed_info) {
  ++g_outlines_checked;
  glm::vec3 got[6];
  const std::size_t n = box_silhouette(b, eye, got);
  const Outline want = brute_outline(b, dvec3(eye));
  CHECK_MSG(same_cycle(got, n, b, want),
            "%s (seed %llu): box (%g %g %g)-(%g %g %g) eye (%.9g %.9g %.9g): got %zu corners, want %d", what,
            static_cast<unsigned long long>(seed_info), b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z,
            eye.x, eye.y, eye.z, n, want.count);
  if (n != 0) {
    CHECK_MSG(convex_ccw(got, n, dvec3(eye)), "%s: outline not convex/CCW, eye (%.9g %.9g %.9g)", what, eye.x,
              eye.y, eye.z);
    // No repeated corners.
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) CHECK_MSG(got[i] != got[j], "%s: repeated corner", what);
  }
  const BoxProxy proxy = make_box_proxy(b, eye);
  CHECK(proxy.corner_count == n);
  CHECK(proxy.region == box_region(b, eye));
  if (n != 0) {
    // Front faces: the brute-force set (flat boxes: only the faces with area), planes facing away
    // from the eye and holding their face's corners.
    CHECK_MSG(proxy.face_count == want.face_count, "%s: %d front faces, want %d", what, int(proxy.face_count),
              want.face_count);
    for (int f = 0; f < proxy.face_count && f < want.face_count; ++f) {
      const int axis = want.faces[f] >> 1, side = want.faces[f] & 1;
      CHECK(proxy.face_axis[f] == axis);
      CHECK(proxy.faces[f].normal[axis] == (side ? -1.0f : 1.0f));
      CHECK(signed_distance(proxy.faces[f], eye) < 0.0f);
      CHECK(signed_distance(proxy.faces[f], side ? b.max : b.min) == 0.0f);
    }
    // Beam planes contain the eye (within rounding) and have every outline corner on their inside.
    Plane beam[6];
    CHECK(proxy_beam_planes(proxy, eye, beam) == n);
    const double scale = std::max(1.0, double(glm::length(eye)) + double(glm::length(b.max - b.min)));
    for (std::size_t i = 0; i < n; ++i) {
      CHECK(is_valid(beam[i]));
      for (std::size_t j = 0; j < n; ++j)
        CHECK_MSG(double(signed_distance(beam[i], got[j])) >= -2e-6 * scale, "%s: corner %zu outside beam plane %zu",
                  what, j, i);
    }
  } else {
    CHECK(proxy.face_count == 0);
    CHECK(!proxy.valid());
  }
}

void test_table_rederived() {
  const Aabb unit{glm::vec3(0.0f), glm::vec3(1.0f)};
  for (int r = 0; r < 27; ++r) {
    const detail::BoxOutlineEntry& e = detail::box_outline_table[r];
    if (r == 13) {
      CHECK(e.corner_count == 0 && e.face_count == 0);
      continue;
    }
    const int digit[3] = {r % 3, (r / 3) % 3, r / 9};
    const glm::vec3 eye(digit[0] == 0 ? -1.0f : digit[0] == 1 ? 0.5f : 2.0f,
                        digit[1] == 0 ? -1.0f : digit[1] == 1 ? 0.5f : 2.0f,
                        digit[2] == 0 ? -1.0f : digit[2] == 1 ? 0.5f : 2.0f);
    CHECK(box_region(unit, eye) == r);
    const Outline want = brute_outline(unit, dvec3(eye));
    const int outside_axes = (digit[0] != 1) + (digit[1] != 1) + (digit[2] != 1);
    CHECK(e.face_count == outside_axes);
    CHECK(e.corner_count == (outside_axes == 1 ? 4 : 6));
    CHECK_MSG(e.corner_count == want.count, "region %d", r);
    // Same ids, same cyclic order.
    bool match = false;
    for (int k = 0; k < want.count && !match; ++k) {
      bool all = true;
      for (int i = 0; i < want.count && all; ++i) all = e.corners[(i + k) % want.count] == want.ids[i];
      match = all;
    }
    CHECK_MSG(match, "region %d: table outline differs from the brute force", r);
    CHECK(e.face_count == want.face_count);
    for (int f = 0; f < want.face_count; ++f) CHECK_MSG(e.faces[f] == want.faces[f], "region %d face %d", r, f);
    // Every corner id is a box corner, none repeated; an outline never holds the corner nearest
    // the eye when three faces are seen (the inner point of the seed's Figure 2).
    for (int i = 0; i < e.corner_count; ++i) {
      CHECK(e.corners[i] < 8);
      for (int j = i + 1; j < e.corner_count; ++j) CHECK(e.corners[i] != e.corners[j]);
    }
  }
}

void test_regions_random(support::Rng& rng) {
  for (int trial = 0; trial < 300; ++trial) {
    const Aabb b = random_box(rng, 0.05f, 20.0f);
    for (int r = 0; r < 27; ++r) {
      const glm::vec3 eye = eye_in_region(rng, b, r);
      CHECK_MSG(box_region(b, eye) == r, "trial %d region %d", trial, r);
      check_outline(b, eye, "random region", kSeed);
      if (r == 13) CHECK(!make_box_proxy(b, eye).valid());
    }
  }
}

// Eyes whose coordinates are exactly min or max (face planes, edge lines, corner points).
void test_on_planes_and_edges(support::Rng& rng) {
  for (int trial = 0; trial < 40; ++trial) {
    const Aabb b = random_box(rng, 0.1f, 10.0f);
    for (int combo = 0; combo < 125; ++combo) {
      const int choice[3] = {combo % 5, (combo / 5) % 5, combo / 25};
      glm::vec3 eye;
      int on_planes = 0;
      for (int a = 0; a < 3; ++a) {
        const float ext = b.max[a] - b.min[a];
        switch (choice[a]) {
          case 0: eye[a] = b.min[a] - rng.uniform(0.1f, 3.0f) * ext; break;
          case 1: eye[a] = b.min[a]; ++on_planes; break;
          case 2: eye[a] = b.min[a] + rng.uniform(0.1f, 0.9f) * ext; break;
          case 3: eye[a] = b.max[a]; ++on_planes; break;
          default: eye[a] = b.max[a] + rng.uniform(0.1f, 3.0f) * ext; break;
        }
      }
      const bool in_or_on = contains(b, eye);
      glm::vec3 out[6];
      const std::size_t n = box_silhouette(b, eye, out);
      if (in_or_on) CHECK_MSG(n == 0, "eye on/in box, combo %d", combo);
      check_outline(b, eye, on_planes >= 2 ? "on edge line" : "on face plane", kSeed);
      // On a face plane, that face is edge-on: the region digit is "within".
      for (int a = 0; a < 3; ++a) {
        if (choice[a] == 1 || choice[a] == 3) {
          const int r = box_region(b, eye);
          CHECK((a == 0 ? r % 3 : a == 1 ? (r / 3) % 3 : r / 9) == 1);
        }
      }
    }
  }
}

void test_far_eyes(support::Rng& rng) {
  for (int trial = 0; trial < 2000; ++trial) {
    const Aabb b = random_box(rng, 0.5f, 5.0f);
    glm::vec3 dir(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (glm::length(dir) < 1e-3f) continue;
    // Snap some components to 0 so the far eye is also exactly in the middle slab on some axes.
    for (int a = 0; a < 3; ++a)
      if (rng.uniform() < 0.25f) dir[a] = 0.0f;
    if (glm::length(dir) == 0.0f) continue;
    const glm::vec3 eye = b.center() + glm::normalize(dir) * 1.0e6f;
    check_outline(b, eye, "far eye 1e6", kSeed);
  }
}

void test_flat_and_thin(support::Rng& rng) {
  for (int trial = 0; trial < 100; ++trial) {
    // Thin: 1e-3 x 10 x 10, along a random axis.
    Aabb thin = random_box(rng, 5.0f, 5.0f);
    const int axis = rng.range(0, 2);
    thin.max[axis] = thin.min[axis] + 1e-3f;
    // Flat: zero extent on one axis (a rectangle), on two (a segment), on three (a point).
    Aabb flat = random_box(rng, 0.5f, 5.0f);
    flat.max[axis] = flat.min[axis];
    Aabb segment = flat;
    segment.max[(axis + 1) % 3] = segment.min[(axis + 1) % 3];
    const Aabb point{flat.min, flat.min};
    for (int r = 0; r < 27; ++r) {
      check_outline(thin, eye_in_region(rng, thin, r), "thin box", kSeed);
      const glm::vec3 eye = eye_in_region(rng, flat, r);
      check_outline(flat, eye, "flat box", kSeed);
      const int digit[3] = {r % 3, (r / 3) % 3, r / 9};
      glm::vec3 out[6];
      const std::size_t n = box_silhouette(flat, eye, out);
      // The rectangle: 4 corners from either side of its plane, none from within the plane.
      CHECK_MSG(n == (digit[axis] == 1 ? 0u : 4u), "flat box region %d axis %d: %zu corners", r, axis, n);
      if (n == 4) {
        const BoxProxy p = make_box_proxy(flat, eye);
        CHECK(p.face_count == 1 && p.face_axis[0] == axis && p.region == r);
      }
      CHECK(box_silhouette(segment, eye_in_region(rng, segment, r), out) == 0);
      CHECK(box_silhouette(point, eye_in_region(rng, point, r), out) == 0);
      check_outline(segment, eye_in_region(rng, segment, r), "segment box", kSeed);
    }
  }
}

void test_bad_input() {
  const Aabb b{glm::vec3(0.0f), glm::vec3(1.0f)};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  glm::vec3 out[6];
  CHECK(box_silhouette(b, glm::vec3(nan, 2, 2), out) == 0);
  CHECK(box_silhouette(b, glm::vec3(2, 2, inf), out) == 0);
  CHECK(box_silhouette(b, glm::vec3(-inf, 0.5f, 0.5f), out) == 0);
  CHECK(box_region(b, glm::vec3(nan)) == 13);
  CHECK(box_silhouette(Aabb::empty(), glm::vec3(2), out) == 0);
  CHECK(box_silhouette(Aabb{glm::vec3(1), glm::vec3(0)}, glm::vec3(2), out) == 0);
  CHECK(box_silhouette(Aabb{glm::vec3(0, nan, 0), glm::vec3(1)}, glm::vec3(2), out) == 0);
  CHECK(box_silhouette(Aabb{glm::vec3(0), glm::vec3(1, inf, 1)}, glm::vec3(2), out) == 0);
  // Inside, on a face, on an edge, on a corner.
  CHECK(box_silhouette(b, glm::vec3(0.5f), out) == 0);
  CHECK(box_silhouette(b, glm::vec3(0.5f, 1.0f, 0.5f), out) == 0);
  CHECK(box_silhouette(b, glm::vec3(0.0f, 1.0f, 0.5f), out) == 0);
  CHECK(box_silhouette(b, glm::vec3(1.0f), out) == 0);
  CHECK(box_region(b, glm::vec3(1.0f)) == 13);
  // Just off a corner: 6 corners.
  CHECK(box_silhouette(b, glm::vec3(std::nextafter(1.0f, 2.0f)), out) == 6);
  // proxy_hides on an invalid proxy or a bad point: never hidden.
  const glm::vec3 eye(-1, -1, -1);
  CHECK(!proxy_hides(make_box_proxy(b, glm::vec3(0.5f)), glm::vec3(0.5f), glm::vec3(5)));
  const BoxProxy p = make_box_proxy(b, eye);
  CHECK(proxy_hides(p, eye, glm::vec3(3)));
  CHECK(!proxy_hides(p, eye, glm::vec3(nan, 3, 3)));
  CHECK(!proxy_hides(p, eye, glm::vec3(inf)));
  const BoxProxy empty{};
  CHECK(!empty.valid() && !proxy_hides(empty, eye, glm::vec3(3)));
  // Region numbering spot checks.
  CHECK(box_region(b, glm::vec3(-1, -1, -1)) == 0);
  CHECK(box_region(b, glm::vec3(2, 0.5f, 0.5f)) == 14);
  CHECK(box_region(b, glm::vec3(0.5f, 2, 0.5f)) == 16);
  CHECK(box_region(b, glm::vec3(0.5f, 0.5f, 2)) == 22);
  CHECK(box_region(b, glm::vec3(2, 2, 2)) == 26);
}

// proxy_hides (front_faces) against the slab test. Points are aimed through the box's neighbourhood
// so that both answers are common and many points lie near the outline.
void test_hides_vs_raycast(support::Rng& rng) {
  long hidden = 0, visible = 0, false_hidden = 0, missed_deep = 0, missed_near_boundary = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const std::uint64_t trial_seed = kSeed + static_cast<std::uint64_t>(trial);
    const bool thin = trial % 5 == 0;
    Aabb b = random_box(rng, 0.2f, 10.0f);
    if (thin) b.max[trial % 3] = b.min[trial % 3] + 1e-3f;
    const int r = rng.range(0, 26);
    if (r == 13) continue;
    const glm::vec3 eye = eye_in_region(rng, b, r);
    const BoxProxy proxy = make_box_proxy(b, eye);
    CHECK(proxy.valid());
    const Aabb around = grown(b, 0.3f);
    const Aabb shrunk = grown(b, -1e-5f);
    for (int k = 0; k < 40; ++k) {
      const glm::vec3 target(rng.uniform(around.min.x, around.max.x), rng.uniform(around.min.y, around.max.y),
                             rng.uniform(around.min.z, around.max.z));
      const glm::vec3 p = eye + (target - eye) * rng.uniform(0.3f, 3.0f);
      const bool got = proxy_hides(proxy, eye, p);
      const bool truth = segment_hidden(b, dvec3(eye), dvec3(p));
      (truth ? hidden : visible)++;
      if (got && !truth) {
        ++false_hidden;
        CHECK_MSG(!(got && !truth), "trial seed %llu: visible point hidden, p (%.9g %.9g %.9g)",
                  static_cast<unsigned long long>(trial_seed), p.x, p.y, p.z);
      }
      if (!got && truth) {
        // Allowed only near the boundary: hidden by a box shrunk by 1e-5 means deep inside.
        if (is_valid(shrunk) && segment_hidden(shrunk, dvec3(eye), dvec3(p))) {
          ++missed_deep;
          CHECK_MSG(false, "trial seed %llu: hidden point (deep) reported visible, p (%.9g %.9g %.9g)",
                    static_cast<unsigned long long>(trial_seed), p.x, p.y, p.z);
        } else {
          ++missed_near_boundary;
        }
      }
    }
    // Corners and the centre: the box's own surface facing the eye is visible, points beyond the
    // far side along the view line through the centre are hidden.
    const glm::vec3 behind = b.center() + (b.center() - eye) * 0.5f + glm::normalize(b.center() - eye) * 0.01f;
    CHECK_MSG(proxy_hides(proxy, eye, behind) == segment_hidden(b, dvec3(eye), dvec3(behind)),
              "trial seed %llu: point behind the centre", static_cast<unsigned long long>(trial_seed));
    for (int i = 0; i < proxy.corner_count; ++i) CHECK(!proxy_hides(proxy, eye, proxy.corners[i]));
  }
  std::printf("proxy_hides vs slab ray-box: %ld hidden, %ld visible, %ld visible-but-hidden, %ld missed deep, "
              "%ld missed within 1e-5 of the boundary\n",
              hidden, visible, false_hidden, missed_deep, missed_near_boundary);
  CHECK(hidden > 1000 && visible > 1000);  // the sample exercises both answers
}

// Points just outside and just inside each outline edge (1e-4 of the way to the outline's centroid),
// pushed to twice their distance from the eye: the beam must neither grow nor shrink by more.
void test_hides_near_outline(support::Rng& rng) {
  int outside = 0, inside = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Aabb b = random_box(rng, 0.2f, 10.0f);
    const int r = rng.range(0, 26);
    if (r == 13) continue;
    const glm::vec3 eye = eye_in_region(rng, b, r);
    const BoxProxy proxy = make_box_proxy(b, eye);
    dvec3 centroid(0.0);
    for (int i = 0; i < proxy.corner_count; ++i) centroid += dvec3(proxy.corners[i]);
    centroid /= double(proxy.corner_count);
    for (int i = 0; i < proxy.corner_count; ++i) {
      const dvec3 m = 0.5 * (dvec3(proxy.corners[i]) + dvec3(proxy.corners[(i + 1) % proxy.corner_count]));
      for (int side = 0; side < 2; ++side) {
        const dvec3 q = m + (side ? -1e-4 : 1e-4) * (m - centroid);
        const glm::vec3 p(dvec3(eye) + 2.0 * (q - dvec3(eye)));
        const bool truth = segment_hidden(b, dvec3(eye), dvec3(p));
        const bool got = proxy_hides(proxy, eye, p);
        CHECK_MSG(got == truth, "trial %d region %d edge %d side %d: proxy %d, ray-box %d", trial, r, i, side,
                  int(got), int(truth));
        CHECK(truth == (side == 1));  // the construction does what it says
        (truth ? inside : outside)++;
      }
    }
  }
  std::printf("near the outline: %d points just outside, %d just inside, all agreeing\n", outside, inside);
}

// The seed's flaw without Embree: a long low box seen obliquely from above, an antenna on the far
// end of its roof. The centre plane hides the antenna's tip, which the eye sees.
void test_center_plane_flaw() {
  const Aabb building{glm::vec3(0, 0, 0), glm::vec3(100, 10, 10)};
  const glm::vec3 eye(-20, 60, 5);
  const glm::vec3 tip(98, 10.5f, 5);  // half a unit above the roof, near the far end
  CHECK(!segment_hidden(building, dvec3(eye), dvec3(tip)));
  const BoxProxy exact = make_box_proxy(building, eye);
  const BoxProxy seed = make_box_proxy(building, eye, ProxyClosure::center_plane);
  CHECK(seed.closure == ProxyClosure::center_plane && seed.face_count == 1 && seed.face_axis[0] == 3);
  CHECK(seed.corner_count == exact.corner_count);
  CHECK(!proxy_hides(exact, eye, tip));
  CHECK(proxy_hides(seed, eye, tip));  // wrong, and kept wrong on purpose: the seed's answer
  // Both agree on a point under the far end of the box, seen through it.
  const glm::vec3 below(60, -5, 5);
  CHECK(segment_hidden(building, dvec3(eye), dvec3(below)));
  CHECK(proxy_hides(exact, eye, below));
}

}  // namespace

int main() {
  support::Rng rng(kSeed);
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  test_table_rederived();
  test_regions_random(rng);
  test_on_planes_and_edges(rng);
  test_far_eyes(rng);
  test_flat_and_thin(rng);
  test_bad_input();
  test_hides_vs_raycast(rng);
  test_hides_near_outline(rng);
  test_center_plane_flaw();
  std::printf("outlines checked against the brute force: %d\n", g_outlines_checked);
  return cullkit_test::report("test_box_proxy");
}
