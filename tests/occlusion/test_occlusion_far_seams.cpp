// Seams far from the eye: triangle strips, fans and runs of exactly collinear edges whose edges span
// tiny angles (down to a few times `min_angle`), 1e3 to 1e7 units from the eye, some with large
// coordinate offsets. The assumptions a seam's copies carry, the collinear-edge rule and the dropping
// of copies trust the true plane through the eye and the edge's world corners, so the copies must
// reach the margin across that plane; an edge node's own plane, built from eye-relative corners
// rounded to float, parts from it most for a short edge far away.
// Point queries, small boxes, long thin boxes and thin polygons are placed just in front of, just
// behind and just beside the surface and its edges. Every query the tree calls hidden is checked with
// certified ray casts: a sample point of the query counts as seen only when the double-precision
// orientation tests prove that the segment from the eye to it misses every triangle (each
// determinant's sign proven by an error bound; undecided samples prove nothing). One seen sample of
// a hidden query is a false cull. The count of hidden answers is checked too, so the test cannot
// pass by hiding nothing. Mutant: the seam copies cut at the edge node's own plane (from rounded
// eye-relative corners) instead of the seam's true plane: the gap case hides 179 of its 3,200 quads,
// each with a seen sample (179 failed checks); the random scenes do not reach that case.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <cullkit/occlusion_tree.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"

using namespace cullkit;
using cullkit::support::Rng;

namespace {

using glm::dvec3;
using Triangle = std::vector<glm::vec3>;

// a - b in double, or false when the difference is not exact (then no sign is certified).
bool exact_difference(const glm::vec3& a, const glm::vec3& b, dvec3& out) {
  for (int i = 0; i < 3; ++i) {
    const double x = double(a[i]), y = -double(b[i]);
    const double s = x + y;
    const double yv = s - x;
    const double xv = s - yv;
    if ((x - xv) + (y - yv) != 0.0) return false;
    out[i] = s;
  }
  return true;
}

// The sign of det[a - o; b - o; c - o], or 0 when double precision cannot prove it. Each of the six
// products is rounded at most twice and the sum five times: the error is below 8 * 2^-53 of the sum
// of their magnitudes; 1e-13 of it leaves a wide berth.
int certified_orientation(const glm::vec3& o, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  dvec3 p, q, r;
  if (!exact_difference(a, o, p) || !exact_difference(b, o, q) || !exact_difference(c, o, r)) return 0;
  const double t[6] = {p.x * q.y * r.z, p.y * q.z * r.x, p.z * q.x * r.y,
                       -p.x * q.z * r.y, -p.y * q.x * r.z, -p.z * q.y * r.x};
  double sum = 0.0, magnitude = 0.0;
  for (const double v : t) {
    sum += v;
    magnitude += std::fabs(v);
  }
  if (!(std::fabs(sum) > 1e-13 * magnitude) || !std::isfinite(sum)) return 0;
  return sum > 0.0 ? 1 : -1;
}

// True only if the segment from the eye to p provably misses the closed triangle: p strictly on the
// eye's side of its plane, or the line through the eye and p strictly beside two of its edges.
bool surely_misses(const glm::vec3& eye, const glm::vec3& p, const Triangle& t) {
  const int eye_side = certified_orientation(t[0], t[1], t[2], eye);
  if (eye_side == 0) return false;
  if (certified_orientation(t[0], t[1], t[2], p) == eye_side) return true;
  const int s0 = certified_orientation(eye, p, t[0], t[1]);
  const int s1 = certified_orientation(eye, p, t[1], t[2]);
  const int s2 = certified_orientation(eye, p, t[2], t[0]);
  return (s0 * s1 < 0) || (s1 * s2 < 0) || (s0 * s2 < 0);
}

bool surely_seen(const glm::vec3& eye, const glm::vec3& p, const std::vector<Triangle>& mesh) {
  for (const Triangle& t : mesh)
    if (!surely_misses(eye, p, t)) return false;
  return true;
}

struct Scene {
  glm::vec3 eye;
  std::vector<Triangle> mesh;
  float distance;  // from the eye to the surface
  dvec3 u, v, n;   // the surface's frame: two directions in it and its normal
};

struct Tally {
  long queries = 0, hidden = 0, checked_samples = 0, false_culls = 0;
  long hidden_points = 0, hidden_thin = 0;
  long covered = 0, covered_hidden = 0;  // queries wholly behind an occluder, away from seams
};

float quantize(double x) { return static_cast<float>(x); }

glm::vec3 to_float(const dvec3& p) { return glm::vec3(quantize(p.x), quantize(p.y), quantize(p.z)); }

dvec3 random_direction(Rng& rng) {
  for (;;) {
    const dvec3 v(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const double l = glm::length(v);
    if (l > 0.1 && l <= 1.0) return v / l;
  }
}

// 10^x for x uniform in [lo, hi].
double log_uniform(Rng& rng, double lo, double hi) { return std::pow(10.0, lo + (hi - lo) * double(rng.uniform())); }

// An angular step: mostly a few times min_angle (1e-6), sometimes a long one.
double step_angle(Rng& rng) { return rng.uniform() < 0.8f ? log_uniform(rng, -5.7, -4.5) : log_uniform(rng, -4.0, -2.5); }

// The eye and the surface's frame. The eye has low-order bits that the far corners lack (so
// eye-relative corners are rounded), and sometimes sits at a large offset from the origin.
Scene frame(Rng& rng) {
  Scene s;
  const double offset_scale = rng.uniform() < 0.5f ? 0.0 : log_uniform(rng, 3.0, 7.0);
  const dvec3 offset = random_direction(rng) * offset_scale;
  s.eye = to_float(offset + dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
  s.distance = float(log_uniform(rng, 3.0, 7.0));
  const dvec3 w = random_direction(rng);
  s.n = glm::normalize(-w + random_direction(rng) * double(rng.uniform(0.0f, 0.8f)));
  s.u = glm::normalize(glm::cross(s.n, random_direction(rng)));
  // Sometimes the strips run along an axis projected into the surface.
  if (rng.uniform() < 0.3f) {
    dvec3 axis(0.0);
    axis[rng.range(0, 2)] = 1.0;
    const dvec3 along = axis - s.n * glm::dot(axis, s.n);
    if (glm::length(along) > 0.3) s.u = glm::normalize(along);
  }
  s.v = glm::cross(s.n, s.u);
  // Often the surface's centre is where an eye-relative coordinate crosses a power of two: corners on
  // either side of it round differently.
  if (rng.uniform() < 0.6f) {
    const int axis = rng.range(0, 2);
    const double reach = std::fabs(s.n[axis]) * double(s.distance);
    if (reach > 1.0) s.distance = float(double(s.distance) * std::exp2(std::floor(std::log2(reach))) / reach);
  }
  return s;
}

dvec3 surface_centre(const Scene& s) { return dvec3(s.eye) - s.n * double(s.distance); }

// A strip along u: two rails of corners at steps of tiny angular size, joined by triangles; the rungs
// are the shared edges. Sometimes a second strip shares the lower rail, and sometimes the rails are
// only a few steps apart, so the long edges are slivers along the tiny ones.
void add_strip(Rng& rng, Scene& s) {
  const double r = double(s.distance);
  const dvec3 c = surface_centre(s);
  const int steps = rng.range(6, 24);
  const double width = r * (rng.uniform() < 0.3f ? log_uniform(rng, -5.5, -4.0) : log_uniform(rng, -4.0, -2.0));
  const double slope = rng.uniform() < 0.5f ? 0.0 : double(rng.uniform(-0.3f, 0.3f));
  std::vector<glm::vec3> low, high, below;
  double t = 0.0;
  for (int i = 0; i <= steps; ++i) {
    const double shift = rng.uniform() < 0.5f ? 0.0 : r * double(rng.uniform(-1.0f, 1.0f)) * 1e-6;
    low.push_back(to_float(c + s.u * t));
    high.push_back(to_float(c + s.u * (t + shift + slope * width) + s.v * width));
    below.push_back(to_float(c + s.u * (t - shift) - s.v * width * double(rng.uniform(0.3f, 1.5f))));
    t += r * step_angle(rng);
  }
  const bool twin = rng.uniform() < 0.5f;
  for (int i = 0; i < steps; ++i) {
    const auto k = static_cast<std::size_t>(i);
    s.mesh.push_back({low[k], low[k + 1], high[k]});
    s.mesh.push_back({low[k + 1], high[k + 1], high[k]});
    if (twin && rng.uniform() < 0.85f) {  // leave some holes below the shared rail
      s.mesh.push_back({low[k + 1], low[k], below[k]});
      s.mesh.push_back({below[k], below[k + 1], low[k + 1]});
    }
  }
}

// A fan around one corner: the rim is a line or an arc cut into steps of tiny angular size, and the
// centre is close (short shared spokes) or far along the rim's line (spokes that are slivers).
void add_fan(Rng& rng, Scene& s) {
  const double r = double(s.distance);
  const dvec3 c = surface_centre(s);
  const int count = rng.range(8, 40);
  std::vector<glm::vec3> rim;
  double t = 0.0;
  const double bend = rng.uniform() < 0.5f ? 0.0 : double(rng.uniform(-0.02f, 0.02f));
  for (int i = 0; i <= count; ++i) {
    rim.push_back(to_float(c + s.u * t + s.v * (bend * t * t / r)));
    t += r * step_angle(rng);
  }
  dvec3 centre;
  if (rng.uniform() < 0.5f) centre = c + s.u * (0.5 * t) + s.v * (r * log_uniform(rng, -5.5, -3.0));
  else centre = c - s.u * (t * double(rng.uniform(0.5f, 20.0f))) + s.v * (r * log_uniform(rng, -5.5, -3.0));
  const glm::vec3 hub = to_float(centre);
  const bool closed = rng.uniform() < 0.3f;  // a second fan on the rim's other side
  const dvec3 across = c + s.u * (0.5 * t) - s.v * (r * log_uniform(rng, -5.5, -3.0));
  const glm::vec3 hub2 = to_float(across);
  for (int i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    s.mesh.push_back({hub, rim[k], rim[k + 1]});
    if (closed && rng.uniform() < 0.85f) s.mesh.push_back({hub2, rim[k + 1], rim[k]});
  }
}

// Corners exactly on one line (a corner and integer multiples of a small float step, all exact), so
// their edges lie exactly in one plane through the eye: the collinear-edge rule applies. Triangles
// on one side cover the whole run, those on the other side only part of it.
void add_collinear_run(Rng& rng, Scene& s) {
  const double r = double(s.distance);
  const dvec3 c = surface_centre(s);
  // The step: u scaled to a tiny angular size, each coordinate rounded to a power of two times a
  // small integer so that every multiple stays exact.
  const double unit_length = r * log_uniform(rng, -6.0, -5.3);
  const int exponent = static_cast<int>(std::floor(std::log2(unit_length))) - 4;
  dvec3 step;
  for (int i = 0; i < 3; ++i) step[i] = std::ldexp(std::round(std::ldexp(s.u[i] * unit_length, -exponent)), exponent);
  const int base_exponent = static_cast<int>(std::floor(std::log2(r + glm::length(dvec3(s.eye))))) - 18;
  dvec3 origin;
  for (int i = 0; i < 3; ++i) origin[i] = std::ldexp(std::round(std::ldexp(c[i], -base_exponent)), base_exponent);
  const int count = rng.range(8, 30);
  std::vector<long> at(1, 0);
  for (int i = 0; i < count; ++i) at.push_back(at.back() + (rng.uniform() < 0.7f ? rng.range(1, 3) : rng.range(20, 400)));
  std::vector<glm::vec3> line;
  for (const long k : at) {
    const dvec3 p = origin + step * double(k);
    line.push_back(to_float(p));
    if (dvec3(line.back()) != p) return;  // not exact after all: skip this run
  }
  const double h1 = r * log_uniform(rng, -6.0, -3.0), h2 = r * log_uniform(rng, -6.0, -3.0);
  const auto first = static_cast<std::size_t>(rng.range(0, count / 2));
  const auto last = static_cast<std::size_t>(rng.range(static_cast<int>(first) + 1, count));
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const dvec3 mid = 0.5 * (dvec3(line[i]) + dvec3(line[i + 1]));
    s.mesh.push_back({line[i], line[i + 1], to_float(mid + s.v * h1)});
    if (i >= first && i < last) s.mesh.push_back({line[i + 1], line[i], to_float(mid - s.v * h2)});
  }
}

// Samples of a box (corners, face grids, random points), all floats inside it.
void box_samples(const Aabb& b, Rng& rng, std::vector<glm::vec3>& out) {
  out.clear();
  for (int c = 0; c < 8; ++c) out.push_back(corner(b, c));
  constexpr int grid = 4;
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i <= grid; ++i)
        for (int j = 0; j <= grid; ++j) {
          glm::vec3 p;
          p[axis] = side ? b.max[axis] : b.min[axis];
          p[a1] = quantize(double(b.min[a1]) + (double(b.max[a1]) - double(b.min[a1])) * i / grid);
          p[a2] = quantize(double(b.min[a2]) + (double(b.max[a2]) - double(b.min[a2])) * j / grid);
          out.push_back(glm::clamp(p, b.min, b.max));
        }
  }
  for (int k = 0; k < 24; ++k) {
    glm::vec3 p;
    for (int a = 0; a < 3; ++a) p[a] = quantize(double(b.min[a]) + (double(b.max[a]) - double(b.min[a])) * double(rng.uniform()));
    out.push_back(glm::clamp(p, b.min, b.max));
  }
}

// A point of the surface near which queries are placed: a corner, a point on an edge (often a short
// one), or a point inside a triangle.
dvec3 surface_point(Rng& rng, const Scene& s, dvec3& along) {
  const Triangle& t = s.mesh[static_cast<std::size_t>(rng.next() % s.mesh.size())];
  const int i = rng.range(0, 2);
  const dvec3 a(t[static_cast<std::size_t>(i)]), b(t[static_cast<std::size_t>((i + 1) % 3)]), c(t[static_cast<std::size_t>((i + 2) % 3)]);
  along = glm::length(b - a) > 0.0 ? glm::normalize(b - a) : s.u;
  const float kind = rng.uniform();
  if (kind < 0.25f) return a;
  if (kind < 0.7f) return a + (b - a) * double(rng.uniform());
  double x = double(rng.uniform()), y = double(rng.uniform());
  if (x + y > 1.0) {
    x = 1.0 - x;
    y = 1.0 - y;
  }
  return a + (b - a) * x + (c - a) * y;
}

void check_scene(const Scene& s, Rng& rng, const OcclusionParams& params, Tally& tally, unsigned seed) {
  std::vector<Triangle> order = s.mesh;
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[static_cast<std::size_t>(rng.next() % i)]);
  OcclusionTree tree(s.eye, params);
  for (const Triangle& t : order) tree.insert_occluder(t.data(), t.size());
  const double r = double(s.distance);
  const dvec3 eye(s.eye);
  std::vector<glm::vec3> samples;
  for (int k = 0; k < 250; ++k) {
    dvec3 along;
    dvec3 p = surface_point(rng, s, along);
    // Just in front of or behind the surface (along the ray), then just beside it.
    const double depth = rng.uniform() < 0.4f ? -log_uniform(rng, -9.0, -4.0) : log_uniform(rng, -7.0, -2.0);
    p = eye + (p - eye) * (1.0 + depth);
    const dvec3 sideways = rng.uniform() < 0.5f ? s.v : glm::normalize(glm::cross(s.n, along));
    p += sideways * (r * log_uniform(rng, -9.0, -4.0) * (rng.uniform() < 0.5f ? -1.0 : 1.0));
    const float kind = rng.uniform();
    bool hidden = false;
    bool thin = false;
    samples.clear();
    if (kind < 0.25f) {  // a point
      const glm::vec3 q = to_float(p);
      hidden = tree.query(Aabb{q, q}).answer == OcclusionAnswer::hidden;
      samples.push_back(q);
    } else if (kind < 0.75f) {  // a small box, or a long thin one along an axis
      dvec3 half(r * log_uniform(rng, -9.0, -4.5));
      if (kind >= 0.5f) {
        half[rng.range(0, 2)] = r * log_uniform(rng, -5.0, -2.5);
        thin = true;
      }
      const Aabb b{to_float(p - half), to_float(p + half)};
      hidden = tree.is_occluded(b);
      box_samples(b, rng, samples);
    } else {  // a thin quad along the edge's direction, reaching far past its ends
      const double length = r * log_uniform(rng, -5.0, -2.0), width = r * log_uniform(rng, -9.0, -5.0);
      const dvec3 across = glm::normalize(glm::cross(along, s.n));
      const dvec3 corners[4] = {p - along * length, p + along * length, p + along * length + across * width,
                                p - along * length + across * width};
      ConvexPolygon poly;
      for (const dvec3& c : corners) poly.push_back(to_float(c));
      hidden = tree.is_occluded(poly);
      thin = true;
      // The corners, then points on the edges between them (rounding keeps them within a unit in
      // the last place of the quad, far less than the certified margin of a seen point).
      for (std::size_t i = 0; i < 4; ++i) {
        samples.push_back(poly[i]);
        for (int j = 1; j < 16; ++j)
          samples.push_back(to_float(dvec3(poly[i]) + (dvec3(poly[(i + 1) % 4]) - dvec3(poly[i])) * (j / 16.0)));
      }
    }
    ++tally.queries;
    if (!hidden) continue;
    ++tally.hidden;
    if (kind < 0.25f) ++tally.hidden_points;
    if (thin) ++tally.hidden_thin;
    for (const glm::vec3& q : samples) {
      ++tally.checked_samples;
      if (!surely_seen(s.eye, q, s.mesh)) continue;
      ++tally.false_culls;
      CHECK_MSG(false, "seed %u: query %d hidden but (%.9g %.9g %.9g) is seen from eye (%.9g %.9g %.9g), surface %g away", seed,
                k, double(q.x), double(q.y), double(q.z), double(s.eye.x), double(s.eye.y), double(s.eye.z), r);
      break;
    }
  }
}


// The sharpest case: two tiny triangles sharing a short edge are inserted first, so every query meets
// that edge's plane at the root. The edge's corners straddle a power of two in one eye-relative
// coordinate, so their rounding differs and the plane built from the rounded corners turns away from
// the true one about the edge's midpoint. Far along the edge's line, beside it, a long quad leaves a
// gap one margin or two wide next to the line; thin quads reaching from behind the long quad into the
// gap are queried. Their part in the gap is seen. Copies cut at the turned plane stand there for the
// wrong side of the true plane and may be dropped as standing for nothing, which hid the quads.
void gap_beside_far_line(Rng& rng, Tally& tally, unsigned seed) {
  const double r = log_uniform(rng, 3.0, 7.0);
  const glm::vec3 eye(quantize(rng.uniform(-1, 1)), quantize(rng.uniform(-1, 1)), quantize(rng.uniform(-1, 1)));
  const dvec3 w = glm::normalize(dvec3(rng.uniform(0.4f, 1.0f), rng.uniform(0.4f, 1.0f), rng.uniform(0.4f, 1.0f)));
  const dvec3 t1 = glm::normalize(glm::cross(w, dvec3(0, 0, 1))), t2 = glm::cross(w, t1);
  const double alpha = double(rng.uniform(0.0f, 6.2831853f));
  const dvec3 u = std::cos(alpha) * t1 + std::sin(alpha) * t2, n = -std::sin(alpha) * t1 + std::cos(alpha) * t2;
  const double edge = r * log_uniform(rng, -5.6, -5.0);
  // The midpoint where the eye-relative x coordinate is a power of two.
  const double x = w.x * r;
  const dvec3 mid = dvec3(eye) + w * (r * std::exp2(std::floor(std::log2(x))) / x);
  const glm::vec3 a = to_float(mid - u * (0.5 * edge)), b = to_float(mid + u * (0.5 * edge));
  const dvec3 centre = 0.5 * (dvec3(a) + dvec3(b));
  std::vector<Triangle> mesh;
  mesh.push_back({a, b, to_float(centre + n * (0.5 * edge))});
  mesh.push_back({b, a, to_float(centre - n * (0.5 * edge))});
  const double m = 1.1e-5 * r;  // about the queries' margin
  const double gap = m * double(rng.uniform(1.0f, 3.0f));
  std::vector<std::vector<glm::vec3>> quads;
  for (const double side : {-1.0, 1.0}) {
    const double near = side * 1e-3 * r, far = side * 4e-2 * r, depth = gap + 2e-3 * r;
    quads.push_back({to_float(centre + u * near - n * gap), to_float(centre + u * far - n * gap),
                     to_float(centre + u * far - n * depth), to_float(centre + u * near - n * depth)});
    mesh.push_back({quads.back()[0], quads.back()[1], quads.back()[2]});
    mesh.push_back({quads.back()[0], quads.back()[2], quads.back()[3]});
  }
  OcclusionTree tree(eye);
  tree.insert_occluder(mesh[0].data(), 3);
  tree.insert_occluder(mesh[1].data(), 3);
  for (const auto& q : quads) tree.insert_occluder(q.data(), q.size());
  const dvec3 e(eye);
  for (const double side : {-1.0, 1.0})
    for (int k = 0; k < 40; ++k) {
      const double along = side * r * (2e-3 + 9e-4 * k), length = 2e-4 * r;
      const double low = -gap - 4e-4 * r, high = -gap * double(rng.uniform(0.2f, 0.8f));
      const dvec3 corners[4] = {centre + u * along + n * low, centre + u * (along + length) + n * low,
                                centre + u * (along + length) + n * high, centre + u * along + n * high};
      ConvexPolygon poly;
      for (const dvec3& c : corners) poly.push_back(to_float(e + (c - e) * (1.0 + 1e-4)));  // just behind
      // The same quad moved down out of the gap, behind the long quad: hidden, with or without seams.
      ConvexPolygon covered;
      for (const dvec3& c : corners) covered.push_back(to_float(e + (c - n * (high + gap + 2.0 * m) - e) * (1.0 + 1e-4)));
      ++tally.covered;
      tally.covered_hidden += tree.is_occluded(covered) ? 1 : 0;
      ++tally.queries;
      if (!tree.is_occluded(poly)) continue;
      ++tally.hidden;
      ++tally.hidden_thin;
      for (int j = 0; j <= 16; ++j) {
        const glm::vec3 q = to_float(dvec3(poly[3]) + (dvec3(poly[2]) - dvec3(poly[3])) * (j / 16.0));
        ++tally.checked_samples;
        if (!surely_seen(eye, q, mesh)) continue;
        ++tally.false_culls;
        CHECK_MSG(false, "gap beside a far line, seed %u: quad %d hidden but (%.9g %.9g %.9g) is seen from eye (%.9g %.9g %.9g)",
                  seed, k, double(q.x), double(q.y), double(q.z), double(eye.x), double(eye.y), double(eye.z));
        break;
      }
    }
}

}  // namespace

int main() {
  const char* names[3] = {"strips", "fans", "collinear runs"};
  Tally tallies[3];
  for (unsigned seed = 1; seed <= 300; ++seed) {
    Rng rng(seed * 104729u + 11u);
    Scene s = frame(rng);
    const int family = static_cast<int>(seed % 3);
    const int parts = rng.range(1, 3);
    for (int p = 0; p < parts; ++p) {
      if (family == 0) add_strip(rng, s);
      else if (family == 1) add_fan(rng, s);
      else add_collinear_run(rng, s);
    }
    if (s.mesh.empty()) continue;
    OcclusionParams params;
    if (seed % 5 == 0) params.azimuth_planes = 4;
    check_scene(s, rng, params, tallies[family], seed);
  }
  Tally gaps;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    Rng rng(seed * 7877u + 5u);
    gap_beside_far_line(rng, gaps, seed);
  }
  std::printf("gap beside a far line: %ld quads reaching into the gap, %ld hidden, %ld false culls; %ld of %ld quads "
              "below the gap hidden\n",
              gaps.queries, gaps.hidden, gaps.false_culls, gaps.covered_hidden, gaps.covered);
  CHECK(gaps.covered_hidden == gaps.covered);
  long false_culls = gaps.false_culls;
  for (int f = 0; f < 3; ++f) {
    const Tally& t = tallies[f];
    std::printf("%-14s %5ld queries, %4ld hidden (%ld points, %ld thin boxes or quads), %5ld samples of hidden queries "
                "cast, %ld false culls\n",
                names[f], t.queries, t.hidden, t.hidden_points, t.hidden_thin, t.checked_samples, t.false_culls);
    false_culls += t.false_culls;
    CHECK_MSG(t.hidden >= 150, "%s: only %ld hidden answers", names[f], t.hidden);
  }
  CHECK(false_culls == 0);
  return cullkit_test::report("test_occlusion_far_seams");
}
