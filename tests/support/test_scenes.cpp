// The scene generators and the OBJ loader: deterministic output, valid indices, objects that
// partition the triangles, tight bounds, outward winding on boxes and closed solids, rooftop props
// resting on their roofs; OBJ parsing of quads, negative indices and o/g groups; the real scenes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

using namespace cullkit;
using support::Scene;
using support::SceneObject;

namespace {

bool finite3(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

bool same_box(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

glm::dvec3 tri_normal(const Scene& s, std::size_t t) {
  const glm::dvec3 a(s.positions[s.indices[3 * t]]), b(s.positions[s.indices[3 * t + 1]]),
      c(s.positions[s.indices[3 * t + 2]]);
  return glm::cross(b - a, c - a);
}

// Signed volume of an object's triangles (positive for a closed, outward-wound solid).
double signed_volume(const Scene& s, const SceneObject& o) {
  double v = 0;
  const glm::dvec3 ref(o.bounds.center());
  for (std::uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t) {
    const glm::dvec3 a = glm::dvec3(s.positions[s.indices[3 * t]]) - ref;
    const glm::dvec3 b = glm::dvec3(s.positions[s.indices[3 * t + 1]]) - ref;
    const glm::dvec3 c = glm::dvec3(s.positions[s.indices[3 * t + 2]]) - ref;
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

// Everything every scene must satisfy. Returns the number of problems found (printed when
// `verbose`), so that tests can also prove it notices broken scenes.
#define PROBLEM(cond, ...)                                   \
  do {                                                       \
    if (!(cond)) {                                           \
      ++problems;                                            \
      if (verbose) std::fprintf(stderr, "    " __VA_ARGS__); \
      if (verbose) std::fprintf(stderr, "\n");              \
    }                                                        \
  } while (0)

int validate(const Scene& s, bool all_finite = true, bool verbose = true) {
  const char* name = s.name.c_str();
  int problems = 0;
  PROBLEM(s.indices.size() % 3 == 0, "%s: index count %zu", name, s.indices.size());
  std::size_t bad_index = 0, bad_pos = 0;
  for (std::uint32_t i : s.indices) bad_index += i >= s.positions.size();
  for (const glm::vec3& p : s.positions) bad_pos += !finite3(p);
  PROBLEM(bad_index == 0, "%s: %zu indices out of range", name, bad_index);
  if (all_finite) PROBLEM(bad_pos == 0, "%s: %zu non-finite positions", name, bad_pos);
  if (bad_index) return problems;
  // Objects partition the triangles, in order.
  std::uint32_t next = 0;
  bool partition = true;
  Aabb all = Aabb::empty();
  std::size_t loose = 0, bad_box = 0;
  for (const SceneObject& o : s.objects) {
    partition = partition && o.first_triangle == next && o.triangle_count > 0;
    next = o.first_triangle + o.triangle_count;
    if (next > s.triangle_count()) {
      partition = false;
      break;
    }
    Aabb tight = Aabb::empty();
    for (std::uint32_t t = o.first_triangle; t < next; ++t)
      for (int k = 0; k < 3; ++k)
        if (finite3(s.positions[s.indices[3 * t + k]])) tight = merge(tight, s.positions[s.indices[3 * t + k]]);
    loose += !same_box(tight, o.bounds);
    all = merge(all, o.bounds);
    if (o.is_box) {
      // Exactly the 12 outward triangles of `bounds`: corners on the box's corners, every normal
      // axis-aligned and pointing away from the centre, the six faces' areas adding up.
      bool ok = o.triangle_count == 12;
      const glm::dvec3 c(o.bounds.center());
      double area[6] = {0, 0, 0, 0, 0, 0};
      for (std::uint32_t t = o.first_triangle; ok && t < next; ++t) {
        for (int k = 0; k < 3; ++k) {
          const glm::vec3 p = s.positions[s.indices[3 * t + k]];
          for (int a = 0; a < 3; ++a) ok = ok && (p[a] == o.bounds.min[a] || p[a] == o.bounds.max[a]);
        }
        const glm::dvec3 n = tri_normal(s, t);
        const glm::dvec3 centroid = (glm::dvec3(s.positions[s.indices[3 * t]]) + glm::dvec3(s.positions[s.indices[3 * t + 1]]) +
                                     glm::dvec3(s.positions[s.indices[3 * t + 2]])) / 3.0;
        ok = ok && glm::dot(n, centroid - c) > 0.0;
        int axis = -1;
        for (int a = 0; a < 3; ++a)
          if (n[a] != 0.0) axis = axis == -1 ? a : 3;
        ok = ok && axis >= 0 && axis < 3;
        if (ok) area[2 * axis + (n[axis] > 0)] += std::fabs(n[axis]) * 0.5;
      }
      const glm::dvec3 e(o.bounds.extent());
      const double want[3] = {e.y * e.z, e.x * e.z, e.x * e.y};
      for (int f = 0; ok && f < 6; ++f) ok = std::fabs(area[f] - want[f / 2]) <= 1e-6 * (1 + want[f / 2]);
      bad_box += !ok;
    }
  }
  partition = partition && next == s.triangle_count();
  PROBLEM(partition, "%s: objects do not partition the %zu triangles", name, s.triangle_count());
  PROBLEM(loose == 0, "%s: %zu objects with bounds that are not tight", name, loose);
  PROBLEM(bad_box == 0, "%s: %zu is_box objects are not 12 outward triangles of their bounds", name, bad_box);
  PROBLEM(same_box(all, s.bounds), "%s: scene bounds are not the union of the object bounds", name);
  return problems;
}

bool identical(const Scene& a, const Scene& b) {
  if (a.positions.size() != b.positions.size() || a.indices.size() != b.indices.size() ||
      a.objects.size() != b.objects.size())
    return false;
  if (std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::vec3)) != 0) return false;
  if (a.indices != b.indices) return false;
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const SceneObject &x = a.objects[i], &y = b.objects[i];
    if (x.name != y.name || x.first_triangle != y.first_triangle || x.triangle_count != y.triangle_count ||
        !same_box(x.bounds, y.bounds) || x.major_occluder != y.major_occluder || x.is_box != y.is_box)
      return false;
  }
  return true;
}

// FNV-1a over positions, indices and object ranges: printed, so builds by different compilers can be
// compared (the generators must not depend on argument evaluation order or library distributions).
std::uint64_t fingerprint(const Scene& s) {
  std::uint64_t h = 1469598103934665603ull;
  auto eat = [&](const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  eat(s.positions.data(), s.positions.size() * sizeof(glm::vec3));
  eat(s.indices.data(), s.indices.size() * sizeof(std::uint32_t));
  for (const SceneObject& o : s.objects) {
    eat(&o.first_triangle, sizeof o.first_triangle);
    eat(o.name.data(), o.name.size());
  }
  return h;
}

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

void test_add_helpers() {
  Scene s;
  s.name = "helpers";
  const std::uint32_t b = s.add_box({{0, 0, 0}, {1, 2, 3}}, "box", true);
  const std::uint32_t t = s.add_triangles({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}}, "tri");  // 4th corner ignored
  const std::uint32_t m = s.add_mesh({{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}}, {0, 1, 2, 2, 1, 0}, "mesh");
  const std::uint32_t e = s.add_mesh({}, {0, 1, 2}, "empty");
  CHECK(b == 0 && t == 1 && m == 2 && e == 3);
  CHECK(s.objects[0].is_box && s.objects[0].major_occluder && s.objects[0].triangle_count == 12);
  CHECK(!s.objects[1].is_box && !s.objects[1].major_occluder && s.objects[1].triangle_count == 1);
  CHECK(s.objects[2].triangle_count == 2 && s.objects[2].first_triangle == 13);
  CHECK(s.objects[3].triangle_count == 0 && is_empty(s.objects[3].bounds));
  CHECK(s.triangle_count() == 15);
  CHECK(same_box(s.bounds, Aabb{{-1, -1, -1}, {1, 2, 3}}));
  CHECK(s.object_bounds().size() == 4 && same_box(s.object_bounds()[1], Aabb{{0, 0, 0}, {1, 1, 0}}));
  CHECK(signed_volume(s, s.objects[0]) > 5.99 && signed_volume(s, s.objects[0]) < 6.01);
  s.objects.pop_back();  // the empty object is allowed by add_mesh but not by validate
  CHECK(validate(s) == 0);
  // validate() notices broken scenes: a flipped box triangle, loose bounds, a bad index, a gap.
  {
    Scene bad = s;
    std::swap(bad.indices[1], bad.indices[2]);
    CHECK(validate(bad, true, false) > 0);
  }
  {
    Scene bad = s;
    bad.objects[1].bounds.max.x += 0.5f;
    CHECK(validate(bad, true, false) > 0);
  }
  {
    Scene bad = s;
    bad.indices.back() = 99;
    CHECK(validate(bad, true, false) > 0);
  }
  {
    Scene bad = s;
    bad.objects[1].triangle_count = 0;
    CHECK(validate(bad, true, false) > 0);
  }
  {
    Scene bad = s;
    bad.bounds.min.y = -2;
    CHECK(validate(bad, true, false) > 0);
  }
  const auto mv = s.mesh();
  CHECK(mv.vertex_count == s.positions.size() && mv.index_count == s.indices.size());
}

void test_city() {
  const Scene a = support::make_city(1, 8), b = support::make_city(1, 8), c = support::make_city(2, 8);
  CHECK(validate(a) == 0);
  CHECK(validate(c) == 0);
  CHECK(identical(a, b));
  CHECK(!identical(a, c));
  CHECK(support::make_city(1, 0).triangle_count() == 0 && support::make_city(1, -3).objects.empty());
  const Scene one = support::make_city(7, 1);
  CHECK(validate(one) == 0);
  CHECK(one.objects.size() >= 6);
  const std::size_t n8 = a.triangle_count();
  CHECK_MSG(n8 >= 3000 && n8 <= 16000, "make_city(1, 8): %zu triangles", n8);
  const Scene big = support::make_city(1, 26);
  CHECK(validate(big) == 0);
  const double ratio = double(big.triangle_count()) / double(n8);
  CHECK_MSG(ratio > 8 && ratio < 13, "make_city(1, 26) / make_city(1, 8) = %g", ratio);

  // Buildings: boxes, major occluders, 8..80 m, standing on the ground; the props are not occluders.
  std::map<std::string, const SceneObject*> buildings;
  int tiles = 0, roof = 0, street = 0, towers = 0;
  double tile_area = 0;
  for (const SceneObject& o : a.objects) {
    if (starts_with(o.name, "building_")) {
      buildings[o.name] = &o;
      CHECK(o.is_box && o.major_occluder);
      CHECK(o.bounds.min.y == 0.0f && o.bounds.max.y >= 8.0f && o.bounds.max.y <= 80.0f);
      towers += o.bounds.max.y > 40.0f;
    } else {
      CHECK_MSG(!o.major_occluder, "%s is flagged as a major occluder", o.name.c_str());
    }
    if (starts_with(o.name, "ground_")) {
      ++tiles;
      CHECK(o.bounds.min.y == 0.0f && o.bounds.max.y == 0.0f && o.triangle_count == 2);
      for (std::uint32_t t = o.first_triangle; t < o.first_triangle + 2; ++t) {
        const glm::dvec3 n = tri_normal(a, t);
        CHECK(n.y > 0 && n.x == 0 && n.z == 0);
      }
      tile_area += double(o.bounds.extent().x) * o.bounds.extent().z;
    }
    if (starts_with(o.name, "lamp_") || starts_with(o.name, "bench_") || starts_with(o.name, "car_")) {
      ++street;
      CHECK(o.is_box && o.bounds.min.y == 0.0f);
    }
  }
  CHECK(tiles == 64);
  // The tiles pave the city's footprint exactly (no gaps, no overlaps: areas add up).
  const double footprint = double(a.bounds.extent().x) * a.bounds.extent().z;
  CHECK_MSG(std::fabs(tile_area - footprint) <= 1e-4 * footprint, "tiles %g vs footprint %g", tile_area, footprint);
  CHECK(buildings.size() >= 64 * 2 && towers > 3);
  CHECK(street >= 64 * 3);
  for (const SceneObject& o : a.objects) {
    if (!starts_with(o.name, "roof_")) continue;
    ++roof;
    const std::string owner = o.name.substr(o.name.find("building_"));
    const auto it = buildings.find(owner);
    CHECK_MSG(it != buildings.end(), "%s has no building", o.name.c_str());
    if (it == buildings.end()) continue;
    const Aabb& r = it->second->bounds;
    CHECK_MSG(o.bounds.min.y == r.max.y, "%s floats or sinks: %.9g vs roof %.9g", o.name.c_str(), o.bounds.min.y, r.max.y);
    CHECK_MSG(o.bounds.min.x >= r.min.x && o.bounds.max.x <= r.max.x && o.bounds.min.z >= r.min.z &&
                  o.bounds.max.z <= r.max.z,
              "%s overhangs its roof", o.name.c_str());
  }
  CHECK(roof >= 64);
  // Nothing but rooftop props touches a building, and buildings do not overlap one another.
  int clashes = 0;
  for (const SceneObject& o : a.objects) {
    if (starts_with(o.name, "ground_") || starts_with(o.name, "roof_")) continue;
    for (const auto& [bn, bo] : buildings) {
      if (bn == o.name) continue;
      const Aabb i = intersection(o.bounds, bo->bounds);
      if (i.min.x < i.max.x && i.min.y < i.max.y && i.min.z < i.max.z) ++clashes;
    }
  }
  CHECK_MSG(clashes == 0, "%d objects intersect a building", clashes);
  std::printf("city(1, 8): %zu triangles, %zu objects, %zu buildings, fingerprint %016llx; city(1, 26): %zu triangles\n",
              n8, a.objects.size(), buildings.size(), static_cast<unsigned long long>(fingerprint(a)), big.triangle_count());
}

void test_office() {
  const Scene a = support::make_office(1, 10, 8), b = support::make_office(1, 10, 8), c = support::make_office(2, 10, 8);
  CHECK(validate(a) == 0);
  CHECK(validate(c) == 0);
  CHECK(identical(a, b));
  CHECK(!identical(a, c));
  CHECK(support::make_office(1, 0, 5).objects.empty() && support::make_office(1, 3, -1).objects.empty());
  const Scene one = support::make_office(3, 1, 1);
  CHECK(validate(one) == 0);
  const std::size_t n = a.triangle_count();
  CHECK_MSG(n >= 25000 && n <= 36000, "make_office(1, 10, 8): %zu triangles (the seed's office: 30,343)", n);
  int floors = 0, lintels = 0, walls = 0, furniture = 0, clashes = 0;
  std::vector<const SceneObject*> wall_objects;
  for (const SceneObject& o : a.objects) {
    if (starts_with(o.name, "wall_")) {
      ++walls;
      wall_objects.push_back(&o);
      CHECK(o.is_box && o.major_occluder && o.bounds.max.y == 3.0f);
      lintels += o.name.find("_lintel") != std::string::npos;
      if (o.name.find("_lintel") != std::string::npos) CHECK(o.bounds.min.y > 2.0f);
      else CHECK(o.bounds.min.y == 0.0f);
    } else {
      CHECK_MSG(!o.major_occluder, "%s is flagged as a major occluder", o.name.c_str());
      if (starts_with(o.name, "floor_")) ++floors;
      else ++furniture;
      CHECK(o.bounds.min.y == 0.0f || starts_with(o.name, "monitor_"));
    }
  }
  CHECK(floors == 80);
  CHECK(lintels == 9 * 8 + 10 * 7);  // one door in every wall between two rooms
  CHECK(walls >= 80 * 2 + 18 && furniture >= 80 * 6);
  // Furniture keeps clear of the walls.
  for (const SceneObject& o : a.objects) {
    if (starts_with(o.name, "wall_") || starts_with(o.name, "floor_")) continue;
    for (const SceneObject* w : wall_objects) {
      const Aabb i = intersection(o.bounds, w->bounds);
      clashes += i.min.x < i.max.x && i.min.y < i.max.y && i.min.z < i.max.z;
    }
  }
  CHECK_MSG(clashes == 0, "%d furniture objects run into a wall", clashes);
  // Every furniture piece is made of closed, outward boxes: positive volume.
  int inward = 0;
  for (const SceneObject& o : a.objects)
    if (!starts_with(o.name, "floor_")) inward += !(signed_volume(a, o) > 0.0);
  CHECK(inward == 0);
  std::printf("office(1, 10, 8): %zu triangles, %zu objects, %d wall boxes, fingerprint %016llx\n", n, a.objects.size(),
              walls, static_cast<unsigned long long>(fingerprint(a)));
}

// Height of the terrain surface under (x, z), by brute force over every terrain triangle (double).
bool terrain_height(const Scene& s, double x, double z, double& y) {
  for (const SceneObject& o : s.objects) {
    if (!starts_with(o.name, "terrain_")) continue;
    for (std::uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t) {
      const glm::dvec3 a(s.positions[s.indices[3 * t]]), b(s.positions[s.indices[3 * t + 1]]), c(s.positions[s.indices[3 * t + 2]]);
      const double det = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
      if (det == 0) continue;
      const double u = ((x - a.x) * (c.z - a.z) - (c.x - a.x) * (z - a.z)) / det;
      const double v = ((b.x - a.x) * (z - a.z) - (x - a.x) * (b.z - a.z)) / det;
      if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9) continue;
      y = a.y + u * (b.y - a.y) + v * (c.y - a.y);
      return true;
    }
  }
  return false;
}

void test_forest() {
  const Scene a = support::make_forest(1, 64, 300), b = support::make_forest(1, 64, 300), c = support::make_forest(2, 64, 300);
  CHECK(validate(a) == 0);
  CHECK(validate(c) == 0);
  CHECK(identical(a, b));
  CHECK(!identical(a, c));
  CHECK(support::make_forest(1, 0, 10).objects.empty());
  const Scene odd = support::make_forest(5, 13, 0);  // chunks of 8 and 5 cells
  CHECK(validate(odd) == 0);
  CHECK(odd.objects.size() == 4 && odd.triangle_count() == 2u * 13 * 13);
  CHECK(a.triangle_count() == 2u * 64 * 64 + 300u * (12 + 16));
  int chunks = 0, trunks = 0, crowns = 0, floating = 0, down = 0, bad_crown = 0;
  double min_y = 1e9, max_y = -1e9;
  for (const SceneObject& o : a.objects) {
    if (starts_with(o.name, "terrain_")) {
      ++chunks;
      for (std::uint32_t t = o.first_triangle; t < o.first_triangle + o.triangle_count; ++t) down += !(tri_normal(a, t).y > 0);
      min_y = std::min(min_y, double(o.bounds.min.y));
      max_y = std::max(max_y, double(o.bounds.max.y));
    } else if (starts_with(o.name, "trunk_")) {
      ++trunks;
      CHECK(o.is_box && !o.major_occluder);
      const glm::vec3 cxz = o.bounds.center();
      double ground = 0;
      const bool found = terrain_height(a, cxz.x, cxz.z, ground);
      // The trunk starts 0.5 m below the surface under its centre.
      if (!found || std::fabs(double(o.bounds.min.y) + 0.5 - ground) > 1e-3) ++floating;
      // Its crown (the next object) starts exactly at its top and is a closed outward cone.
      const SceneObject& crown = *(&o + 1);
      CHECK(starts_with(crown.name, "crown_") && crown.bounds.min.y == o.bounds.max.y);
      const double vol = signed_volume(a, crown);
      // Octagon of circumradius r: area 2*sqrt(2)*r^2; r from the base ring's first vertex
      // (crown vertices: apex, base centre, ring).
      const glm::dvec3 centre(a.positions[a.indices[3 * crown.first_triangle + 5]]);
      const glm::dvec3 ring(a.positions[a.indices[3 * crown.first_triangle]]);
      const double r = glm::length(ring - centre);
      const double cone = 2.0 * std::sqrt(2.0) * r * r * crown.bounds.extent().y / 3.0;
      if (!(vol > 0.999 * cone && vol < 1.001 * cone)) ++bad_crown;
    } else if (starts_with(o.name, "crown_")) {
      ++crowns;
    }
  }
  CHECK(chunks == 64 && trunks == 300 && crowns == 300);
  CHECK_MSG(down == 0, "%d terrain triangles face down", down);
  CHECK_MSG(floating == 0, "%d trunks are not planted 0.5 m into the terrain", floating);
  CHECK_MSG(bad_crown == 0, "%d crowns are not closed outward cones", bad_crown);
  CHECK_MSG(max_y - min_y > 5.0, "terrain is flat: %g .. %g", min_y, max_y);
  std::printf("forest(1, 64, 300): %zu triangles, %zu objects, terrain %.1f .. %.1f m, fingerprint %016llx\n",
              a.triangle_count(), a.objects.size(), min_y, max_y, static_cast<unsigned long long>(fingerprint(a)));
}

void test_obj_tiny() {
  namespace fs = std::filesystem;
  const fs::path path = fs::temp_directory_path() /
                        ("cullkit_test_scenes_" + std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()) + ".obj");
  {
    std::ofstream f(path);
    f << "# written by test_scenes\n"
         "mtllib missing.mtl\n"
         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
         "o quad\nusemtl nothing\nf 1 2 3 4\n"
         "g tri_neg\nv 5 5 5\nf -2/1 -5 -4\n"    // relative: vertices 5, 2, 3 (1-based)
         "o bad\nf 1 2 99\nf 1//1 2//1 3//1 4//1 5//1\n"  // one face out of range, one pentagon
         "o empty\nf 1 2 77\n";
  }
  support::ObjLoadStats stats;
  const auto loaded = support::load_obj(path.string(), &stats);
  std::error_code ec;
  fs::remove(path, ec);
  CHECK(loaded.has_value());
  if (!loaded) return;
  const Scene& s = *loaded;
  CHECK(validate(s) == 0);
  CHECK(s.name == path.stem().string());
  CHECK(s.positions.size() == 6);
  CHECK_MSG(s.objects.size() == 3, "%zu objects", s.objects.size());
  if (s.objects.size() != 3) return;
  CHECK(s.objects[0].name == "quad" && s.objects[1].name == "tri_neg" && s.objects[2].name == "bad");
  CHECK(s.objects[0].triangle_count == 2 && s.objects[1].triangle_count == 1 && s.objects[2].triangle_count == 3);
  // Fans keep the file's winding: the quad faces +z.
  const std::vector<std::uint32_t> want = {0, 1, 2, 0, 2, 3, 4, 1, 2, 0, 1, 2, 0, 2, 3, 0, 3, 4};
  CHECK(s.indices == want);
  CHECK(tri_normal(s, 0).z > 0 && tri_normal(s, 1).z > 0);
  CHECK(same_box(s.objects[1].bounds, Aabb{{0, 0, 0}, {1, 1, 1}}));
  CHECK(same_box(s.bounds, Aabb{{0, 0, 0}, {1, 1, 1}}));  // vertex 6 is used by no face
  CHECK_MSG(stats.faces == 5 && stats.skipped_faces == 2 && stats.empty_shapes == 1 && stats.nonfinite_vertices == 0,
            "faces %zu, skipped %zu, empty %zu, non-finite %zu", stats.faces, stats.skipped_faces, stats.empty_shapes,
            stats.nonfinite_vertices);
  CHECK(!support::load_obj((fs::temp_directory_path() / "cullkit_no_such_file.obj").string()).has_value());
  {  // An index of 0 is not OBJ: tinyobjloader stops, and so the load fails (documented).
    std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n";
    CHECK(!support::load_obj(path.string()).has_value());
    std::ofstream(path) << "";  // an empty file is an empty scene
    const auto empty = support::load_obj(path.string());
    CHECK(empty.has_value() && empty->triangle_count() == 0 && empty->objects.empty());
    fs::remove(path, ec);
  }
  CHECK(!support::load_obj(fs::temp_directory_path().string()).has_value());
}

void test_real_scenes() {
  const std::string dir = support::scenes_dir();
  if (dir.empty()) {
    std::printf("real scenes: none (no scenes folder), skipped\n");
    return;
  }
  // The README's triangle and object counts (the first two triangle counts are rounded there).
  struct Expect {
    const char* file;
    double triangles, objects;
  };
  const Expect expect[] = {{"lasdunasarena.obj", 363000, 594}, {"oacmpdm9.obj", 35000, 10229},
                           {"fzk_haus.obj", 35906, 294},       {"sportsCar.obj", 300603, 1075},
                           {"stanford-bunny.obj", 69451, 1}};
  const auto files = support::real_scene_files();
  CHECK(!files.empty());
  for (const std::string& file : files) {
    support::ObjLoadStats stats;
    const auto t0 = std::chrono::steady_clock::now();
    const auto scene = support::load_obj(dir + "/" + file, &stats);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    CHECK_MSG(scene.has_value(), "%s did not load", file.c_str());
    if (!scene) continue;
    CHECK(validate(*scene) == 0);
    std::printf("real scene %s: %zu triangles, %zu objects, %zu vertices, %zu faces skipped, %zu empty groups (%.0f ms)\n",
                file.c_str(), scene->triangle_count(), scene->objects.size(), scene->positions.size(),
                stats.skipped_faces, stats.empty_shapes, ms);
    for (const Expect& e : expect) {
      if (file != e.file) continue;
      const double t = double(scene->triangle_count()), o = double(scene->objects.size());
      CHECK_MSG(std::fabs(t - e.triangles) <= 0.02 * e.triangles, "%s: %g triangles, README says %g", e.file, t, e.triangles);
      CHECK_MSG(std::fabs(o - e.objects) <= 0.02 * e.objects + 1, "%s: %g objects, README says %g", e.file, o, e.objects);
    }
  }
}

}  // namespace

void test_crowd() {
  const Scene a = support::make_crowd(1, 40, false), b = support::make_crowd(1, 40, false);
  const Scene c = support::make_crowd(2, 40, false), m = support::make_crowd(1, 40, true);
  CHECK(validate(a) == 0);
  CHECK(validate(c) == 0);
  CHECK(validate(m) == 0);
  CHECK(identical(a, b));
  CHECK(!identical(a, c));
  CHECK(support::make_crowd(1, 0, true).triangle_count() == 0 && support::make_crowd(1, -2, false).objects.empty());
  CHECK(a.objects.size() == 40 && m.objects.size() == 40 + 1 + 12);
  // The mixed scene is the same field (same bytes) plus the plaza.
  CHECK(std::equal(a.indices.begin(), a.indices.end(), m.indices.begin()));
  const double per_lot = double(a.triangle_count()) / (40.0 * 40.0);
  CHECK_MSG(per_lot > 9 && per_lot < 15, "make_crowd: %g triangles per lot", per_lot);
  // Tufts may lean up to 1.8 m out of the field.
  CHECK(a.bounds.min.x <= -20.0f && a.bounds.min.x > -22.0f && a.bounds.max.x >= 20.0f && a.bounds.max.x < 22.0f);
  CHECK(a.bounds.min.y == 0.0f && a.bounds.max.y < 4.0f);
  CHECK(m.bounds.max.x == 50.0f && m.bounds.max.y > 5.0f && m.bounds.max.y <= 20.0f);
  // Every lot is paved: ground triangles (y == 0 at all corners, area > 0) face up and cover the
  // field exactly; closed slabs enclose positive volume (their undersides face down).
  double ground_area = 0;
  std::size_t down_ground = 0, up = 0, down = 0, side = 0;
  for (std::size_t t = 0; t < a.triangle_count(); ++t) {
    const glm::dvec3 n = tri_normal(a, t);
    bool flat = true;
    for (int k = 0; k < 3; ++k) flat = flat && a.positions[a.indices[3 * t + k]].y == 0.0f;
    if (flat && glm::length(n) > 0) {
      ground_area += 0.5 * glm::length(n);
      down_ground += !(n.y > 0);
    }
    up += n.y > 1e-9;
    down += n.y < -1e-9;
    side += !(n.y > 1e-9) && !(n.y < -1e-9);
  }
  CHECK_MSG(std::fabs(ground_area - 1600.0) < 1e-3 && down_ground == 0, "ground area %g, %zu facing down",
            ground_area, down_ground);
  CHECK(up > 0 && down > 0 && side > up);
}

int main() {
  test_add_helpers();
  test_city();
  test_office();
  test_forest();
  test_crowd();
  test_obj_tiny();
  test_real_scenes();
  return cullkit_test::report("test_scenes");
}
