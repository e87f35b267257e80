// bench/bench_portals.cpp: cells and portals on the generated office, against frustum culling alone
// and frustum + occlusion culling, with what Embree really sees and a false-cull count.
//
// Scenes: make_office(1, 10, 10) (100 rooms), make_office(1, 10, 8) (the seed paper's office size),
// make_office(1, 32, 25) (800 rooms). Cells are the rooms, portals the door openings, both reported by
// the generator; objects go to every room their box meets (CellObjects).
// Cameras (seeded): `office_cameras` in tests/portals/office_portals.hpp: eyes in random rooms
// 1.0-1.8 m high, clear of furniture, random heading, pitch -20..+10 degrees, 60-90 degree vertical
// field of view, near 0.1, far the scene diagonal.
//
// Columns (triangles of the kept objects, as a share of the scene's triangles, mean over cameras):
//   frustum %       AdaptiveBinaryTree::cull(frustum)
//   frustum+occl %  cull_with_occlusion (ABT front to back, wall boxes grown into an OcclusionTree)
//   portals %       PortalGraph::visible_cells + CellObjects::cull
//   portals+occl %  the portal set, nearest first, each object tested against an OcclusionTree grown
//                   from the wall boxes of the portal set found visible (the occluders of visible
//                   cells hide what the portals let through)
//   visible %       objects some pixel of an Embree render sees (one ray per pixel centre, front
//                   faces, hit beyond the near plane)
//   x visible       portals % / visible %, and portals+occl % / visible %
//   views           PortalView entries per frame; rooms: distinct rooms reached per frame
//   false culls     (object, camera) pairs Embree sees that the portal set, or the portal+occlusion
//                   set, left out. Must be 0 (the program exits with 1 otherwise).
// Times: median over repetitions of the time to cull every camera once, divided by the camera count
// (single thread), for each contestant interleaved (race.hpp): frustum (ABT), portals (locate_cell +
// visible_cells + cull), portals+occl, frustum+occl. The CSV race rows come first, the table last.
//
// Usage: bench_portals [cameras=100] [width=320] [height=240]
// CULLKIT_BENCH_SMOKE=1: the 10x10 office only, 4 cameras, 80x60.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "../tests/oracle/embree_oracle.hpp"
#include "../tests/portals/office_portals.hpp"
#include "race.hpp"

using namespace cullkit;
using namespace portal_test;

namespace {

struct Culler {
  const OfficePortals& o;
  PortalScratch scratch;
  std::vector<PortalView> views;
  std::vector<std::uint32_t> kept, order;
  std::vector<std::pair<float, std::uint32_t>> by_distance;
  OcclusionTree tree{glm::vec3(0.0f)};

  explicit Culler(const OfficePortals& office) : o(office) {}

  void portals(const Camera& cam, const Frustum& f) {
    o.graph.visible_cells(o.graph.locate_cell(cam.eye), cam.eye, f, views, scratch);
    o.objects.cull(f, views, kept, scratch);
  }
  // Nearest first; an object is dropped only if the walls already inserted hide its box.
  void occlude(const Camera& cam, std::vector<std::uint32_t>& out) {
    by_distance.clear();
    for (std::uint32_t k : kept) {
      const Aabb& b = o.bounds[k];
      const glm::vec3 d = glm::max(glm::max(b.min - cam.eye, cam.eye - b.max), glm::vec3(0.0f));
      by_distance.push_back({glm::dot(d, d), k});
    }
    std::sort(by_distance.begin(), by_distance.end());
    tree.reset(cam.eye);
    out.clear();
    for (const auto& [dist, k] : by_distance) {
      (void)dist;
      if (!tree.empty() && tree.is_occluded(o.bounds[k])) continue;
      out.push_back(k);
      const support::SceneObject& so = o.scene.objects[k];
      if (so.is_box && so.major_occluder) tree.insert_box_occluder(so.bounds);
    }
  }
};

struct Row {
  std::string scene;
  std::size_t triangles = 0, objects = 0, rooms = 0, cameras = 0;
  double frustum = 0, frustum_occ = 0, portals = 0, portals_occ = 0, visible = 0, views = 0, reached = 0;
  long false_portals = 0, false_portals_occ = 0;
  double ns_frustum = 0, ns_portals = 0, ns_portals_occ = 0, ns_frustum_occ = 0;
};

std::size_t triangles_of(const support::Scene& s, const std::vector<std::uint32_t>& objs) {
  std::size_t n = 0;
  for (std::uint32_t k : objs) n += s.objects[k].triangle_count;
  return n;
}

Row run(const std::string& name, std::uint32_t seed, int rx, int rz, int ncam, int width, int height) {
  OfficePortals o;
  build_office(o, seed, rx, rz);
  Row row;
  row.scene = name;
  row.triangles = o.scene.triangle_count();
  row.objects = o.scene.objects.size();
  row.rooms = o.cells.rooms.size();
  const AdaptiveBinaryTree<Aabb> abt(o.bounds.data(), o.bounds.size());
  std::vector<std::uint8_t> box_flag(o.bounds.size());
  for (std::size_t k = 0; k < box_flag.size(); ++k) box_flag[k] = o.scene.objects[k].is_box && o.scene.objects[k].major_occluder;
  const BoxOccluderSource source{o.bounds.data(), box_flag.data()};
  oracle::EmbreeScene embree;
  embree.add_mesh(o.scene.positions.data(), o.scene.positions.size(), o.scene.indices.data(), o.scene.indices.size());
  embree.commit();
  const auto ocams = office_cameras(o, 0xBE7C0 + seed, ncam, width, height, false);
  std::vector<Camera> cams;
  std::vector<Frustum> frusta;
  for (const auto& oc : ocams) {
    cams.push_back(oc.camera);
    frusta.push_back(Frustum::from_matrix(oc.camera.view_proj));
  }
  row.cameras = cams.size();
  Culler c(o);
  std::vector<std::uint32_t> frustum_set, occ_set, portal_occ_set;
  OcclusionTree ftree(glm::vec3(0.0f));
  const double total = static_cast<double>(row.triangles);
  for (std::size_t i = 0; i < cams.size(); ++i) {
    const Camera& cam = cams[i];
    const Frustum& f = frusta[i];
    abt.cull(f, frustum_set);
    ftree.reset(cam.eye);
    cull_with_occlusion(abt, f, ftree, source, occ_set);
    c.portals(cam, f);
    c.occlude(cam, portal_occ_set);
    std::vector<char> reached(row.rooms, 0);
    for (const PortalView& v : c.views) reached[v.cell] = 1;
    row.views += static_cast<double>(c.views.size());
    row.reached += static_cast<double>(std::count(reached.begin(), reached.end(), 1));
    // Ground truth: objects hit by some pixel beyond the near plane.
    const oracle::HitBuffer hits = embree.render(cam, 1);
    const PixelRays rays(cam);
    std::vector<char> seen(row.objects, 0), in_p(row.objects, 0), in_po(row.objects, 0);
    for (std::uint32_t k : c.kept) in_p[k] = 1;
    for (std::uint32_t k : portal_occ_set) in_po[k] = 1;
    for (int y = 0; y < hits.height; ++y)
      for (int x = 0; x < hits.width; ++x) {
        const std::uint32_t tri = hits.at(x, y);
        if (tri == oracle::HitBuffer::miss) continue;
        const Ray r = rays.ray(x, y);
        const glm::vec3 p = r.origin + r.direction * hits.distance[static_cast<std::size_t>(y) * hits.width + x];
        if (signed_distance(f.plane(Frustum::near_plane), p) < -1e-4f) continue;
        seen[o.object_of_triangle[tri]] = 1;
      }
    std::vector<std::uint32_t> seen_list;
    for (std::uint32_t k = 0; k < row.objects; ++k) {
      if (!seen[k]) continue;
      seen_list.push_back(k);
      row.false_portals += !in_p[k];
      row.false_portals_occ += !in_po[k];
    }
    row.frustum += triangles_of(o.scene, frustum_set) / total;
    row.frustum_occ += triangles_of(o.scene, occ_set) / total;
    row.portals += triangles_of(o.scene, c.kept) / total;
    row.portals_occ += triangles_of(o.scene, portal_occ_set) / total;
    row.visible += triangles_of(o.scene, seen_list) / total;
  }
  const double n = static_cast<double>(cams.size());
  for (double* v : {&row.frustum, &row.frustum_occ, &row.portals, &row.portals_occ, &row.visible, &row.views, &row.reached})
    *v /= n;
  const auto res = cullkit_bench::race(
      name, {{"frustum_abt", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { abt.cull(frusta[i], frustum_set); cullkit_bench::keep(frustum_set); } }},
             {"portals", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { c.portals(cams[i], frusta[i]); cullkit_bench::keep(c.kept); } }},
             {"portals_occlusion", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { c.portals(cams[i], frusta[i]); c.occlude(cams[i], portal_occ_set); cullkit_bench::keep(portal_occ_set); } }},
             {"frustum_occlusion_abt", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { ftree.reset(cams[i].eye); cull_with_occlusion(abt, frusta[i], ftree, source, occ_set); cullkit_bench::keep(occ_set); } }}},
      15);
  row.ns_frustum = res[0].median_ns / n;
  row.ns_portals = res[1].median_ns / n;
  row.ns_portals_occ = res[2].median_ns / n;
  row.ns_frustum_occ = res[3].median_ns / n;
  return row;
}


// ---- OpenArena "The Sanctuary" (oacmpdm9): leaves as cells, the compiled PVS as the reference ----

// A minimal JSON reader for the scene sidecar (objects, numbers, strings, arrays; no escapes
// beyond \" \\ \n \t).
struct Json {
  enum Kind { null, number, string, array, object } kind = null;
  double num = 0;
  std::string str;
  std::vector<Json> items;
  std::vector<std::pair<std::string, Json>> fields;
  const Json* get(const std::string& key) const {
    for (const auto& [k, v] : fields)
      if (k == key) return &v;
    return nullptr;
  }
};

struct JsonReader {
  const std::string& s;
  std::size_t i = 0;
  void ws() { while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i; }
  std::string text() {
    std::string out;
    ++i;  // opening quote
    while (i < s.size() && s[i] != '"') {
      if (s[i] == '\\' && i + 1 < s.size()) {
        ++i;
        out += s[i] == 'n' ? '\n' : (s[i] == 't' ? '\t' : s[i]);
      } else {
        out += s[i];
      }
      ++i;
    }
    ++i;
    return out;
  }
  Json value() {
    ws();
    Json v;
    if (i >= s.size()) return v;
    const char c = s[i];
    if (c == '{') {
      v.kind = Json::object;
      ++i;
      for (ws(); i < s.size() && s[i] != '}'; ws()) {
        if (s[i] == ',') { ++i; continue; }
        std::string key = text();
        ws();
        ++i;  // colon
        v.fields.emplace_back(std::move(key), value());
      }
      ++i;
    } else if (c == '[') {
      v.kind = Json::array;
      ++i;
      for (ws(); i < s.size() && s[i] != ']'; ws()) {
        if (s[i] == ',') { ++i; continue; }
        v.items.push_back(value());
      }
      ++i;
    } else if (c == '"') {
      v.kind = Json::string;
      v.str = text();
    } else if (c == 'n' || c == 't' || c == 'f') {
      while (i < s.size() && std::isalpha(static_cast<unsigned char>(s[i]))) ++i;
    } else {
      v.kind = Json::number;
      char* end = nullptr;
      v.num = std::strtod(s.c_str() + i, &end);
      i = static_cast<std::size_t>(end - s.c_str());
    }
    return v;
  }
};

glm::vec3 vec3_of(const Json* a) {
  return a && a->items.size() == 3 ? glm::vec3(float(a->items[0].num), float(a->items[1].num), float(a->items[2].num))
                                   : glm::vec3(0.0f);
}

std::vector<std::uint8_t> base64(const std::string& in) {
  std::vector<std::uint8_t> out;
  unsigned acc = 0;
  int bits = 0;
  for (char ch : in) {
    int v;
    if (ch >= 'A' && ch <= 'Z') v = ch - 'A';
    else if (ch >= 'a' && ch <= 'z') v = ch - 'a' + 26;
    else if (ch >= '0' && ch <= '9') v = ch - '0' + 52;
    else if (ch == '+') v = 62;
    else if (ch == '/') v = 63;
    else continue;
    acc = (acc << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFFu));
    }
  }
  return out;
}

struct OaRow {
  std::size_t cameras = 0, leaves = 0, portals = 0, open_portals = 0;
  double frustum = 0, pvs = 0, portals_kept = 0, seen = 0, views = 0;  // objects per camera
  long false_pvs = 0, false_portals = 0, cameras_false_portals = 0;
  double ns_frustum = 0, ns_portals = 0;
};

// Cells: the map's empty leaves (cluster >= 0), as their stored integer boxes. Portals: where two
// leaf boxes touch on a face (their overlap is flat on one axis), the rectangle of that overlap;
// where two boxes overlap with volume (a slanted split plane), the six faces of the overlap box
// (see below); boxes meeting only along an edge or at a corner get none. Eye cells: every leaf whose box holds
// the eye (boxes of slanted leaves overlap), the union of their answers.
bool run_openarena(int width, int height, OaRow& row) {
  const std::string dir = support::scenes_dir();
  if (dir.empty()) return false;
  std::FILE* fj = std::fopen((dir + "/oacmpdm9.json").c_str(), "rb");
  if (!fj) return false;
  std::string text;
  char buf[1 << 16];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, fj)) > 0;) text.append(buf, n);
  std::fclose(fj);
  const auto scene = support::load_obj(dir + "/oacmpdm9.obj");
  if (!scene) return false;
  JsonReader reader{text};
  const Json doc = reader.value();
  const Json* leafs = doc.get("leafs");
  const Json* pvs = doc.get("pvs");
  const Json* ents = doc.get("entities");
  if (!leafs || !pvs || !ents) return false;
  const int n_clusters = static_cast<int>(pvs->get("n_clusters")->num);
  const int row_bytes = static_cast<int>(pvs->get("bytes_per_cluster")->num);
  const std::vector<std::uint8_t> bits = base64(pvs->get("bits_base64")->str);

  PortalGraph graph;
  std::vector<Aabb> leaf_box;
  std::vector<int> leaf_cluster;
  for (const Json& l : leafs->items) {
    const int cluster = static_cast<int>(l.get("cluster")->num);
    const Aabb b{vec3_of(l.get("bbox_min")), vec3_of(l.get("bbox_max"))};
    if (cluster < 0 || !(volume(b) > 0.0f)) continue;
    graph.set_cell_bounds(graph.add_cell(), b);
    leaf_box.push_back(b);
    leaf_cluster.push_back(cluster);
  }
  for (std::uint32_t a = 0; a < leaf_box.size(); ++a)
    for (std::uint32_t b = a + 1; b < leaf_box.size(); ++b) {
      const Aabb i = intersection(leaf_box[a], leaf_box[b]);
      const glm::vec3 e = i.max - i.min;
      if (e.x < 0 || e.y < 0 || e.z < 0) continue;
      const int flat = (e.x == 0) + (e.y == 0) + (e.z == 0);
      if (flat > 1) continue;
      // The shared face lies in the overlap box; a ray from one leaf into the other enters that box
      // through one of its faces (or starts inside it: then the eye is in both leaves' boxes), and
      // what it reaches lies beyond that face. So each face of the overlap is a portal (one face
      // when the overlap is flat).
      for (int axis = 0; axis < 3; ++axis) {
        if (flat == 1 && e[axis] != 0) continue;
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int side = 0; side < (flat == 1 ? 1 : 2); ++side) {
          glm::vec3 q[4];
          const float uv[4][2] = {{i.min[u], i.min[v]}, {i.max[u], i.min[v]}, {i.max[u], i.max[v]}, {i.min[u], i.max[v]}};
          for (int k = 0; k < 4; ++k) {
            q[k][axis] = side ? i.max[axis] : i.min[axis];
            q[k][u] = uv[k][0];
            q[k][v] = uv[k][1];
          }
          graph.add_portal(a, b, q, 4);
        }
      }
    }
  row.leaves = leaf_box.size();
  row.portals = graph.stats().portals;
  row.open_portals = graph.stats().open_portals;
  const std::vector<Aabb> bounds = scene->object_bounds();
  const CellObjects cells(graph, bounds.data(), bounds.size());
  std::vector<std::uint32_t> object_of_triangle(scene->triangle_count());
  for (std::uint32_t k = 0; k < scene->objects.size(); ++k)
    for (std::uint32_t t = 0; t < scene->objects[k].triangle_count; ++t)
      object_of_triangle[scene->objects[k].first_triangle + t] = k;
  // Cameras: every deathmatch spawn, eye 26 units above its origin (Quake 3's view height), six
  // headings 60 degrees apart, level; 90 degree horizontal field of view, near 4 units.
  std::vector<Camera> cams;
  const std::string& e = ents->str;
  for (std::size_t pos = 0; (pos = e.find("info_player_deathmatch", pos)) != std::string::npos; ++pos) {
    const std::size_t o = e.find("\"origin\"", pos), close = e.find('}', pos);
    if (o == std::string::npos || o > close) continue;
    float x, y, z;
    if (std::sscanf(e.c_str() + o, "\"origin\" \"%f %f %f\"", &x, &y, &z) != 3) continue;
    const glm::vec3 eye(x, z + 26.0f, -y);
    for (int h = 0; h < 6; ++h) {
      const float yaw = 1.0471976f * static_cast<float>(h);
      const float fov_y = 2.0f * std::atan(std::tan(0.7853982f) * float(height) / float(width)) * 57.29578f;
      cams.push_back(support::make_camera(eye, eye + glm::vec3(std::cos(yaw), 0.0f, std::sin(yaw)), fov_y, width, height,
                                          4.0f, 20000.0f));
    }
  }
  if (cullkit_bench::smoke() && cams.size() > 6) cams.resize(6);
  row.cameras = cams.size();
  oracle::EmbreeScene embree;
  embree.add_mesh(scene->positions.data(), scene->positions.size(), scene->indices.data(), scene->indices.size());
  embree.commit();
  const AdaptiveBinaryTree<Aabb> abt(bounds.data(), bounds.size());
  PortalScratch scratch;
  std::vector<PortalView> views, all_views;
  std::vector<std::uint32_t> frustum_set, portal_set;
  auto portal_cull = [&](const Camera& cam, const Frustum& f) {
    all_views.clear();
    for (std::uint32_t c = 0; c < graph.cell_count(); ++c) {
      if (!contains(graph.cell_bounds(c), cam.eye)) continue;
      graph.visible_cells(c, cam.eye, f, views, scratch);
      all_views.insert(all_views.end(), views.begin(), views.end());
    }
    if (all_views.empty()) graph.visible_cells(PortalGraph::no_cell, cam.eye, f, all_views, scratch);
    cells.cull(f, all_views, portal_set, scratch);
  };
  std::vector<Frustum> frusta;
  for (const Camera& cam : cams) frusta.push_back(Frustum::from_matrix(cam.view_proj));
  for (std::size_t ci = 0; ci < cams.size(); ++ci) {
    const Camera& cam = cams[ci];
    const Frustum& f = frusta[ci];
    abt.cull(f, frustum_set);
    portal_cull(cam, f);
    row.views += static_cast<double>(all_views.size());
    // PVS row of every cluster whose leaf holds the eye; objects meeting a leaf of a visible
    // cluster, then the frustum.
    std::vector<char> cluster_seen(static_cast<std::size_t>(n_clusters), 0);
    for (std::uint32_t c = 0; c < leaf_box.size(); ++c) {
      if (!contains(leaf_box[c], cam.eye)) continue;
      const int from = leaf_cluster[c];
      for (int to = 0; to < n_clusters; ++to) {
        const std::size_t byte = static_cast<std::size_t>(from) * row_bytes + (to >> 3);
        if (byte < bits.size() && ((bits[byte] >> (to & 7)) & 1u)) cluster_seen[static_cast<std::size_t>(to)] = 1;
      }
    }
    std::vector<char> in_pvs(bounds.size(), 0), in_portals(bounds.size(), 0), seen(bounds.size(), 0);
    for (std::uint32_t c = 0; c < leaf_box.size(); ++c) {
      if (!cluster_seen[static_cast<std::size_t>(leaf_cluster[c])]) continue;
      for (const std::uint32_t* it = cells.cell_begin(c); it != cells.cell_end(c); ++it) in_pvs[*it] = 1;
    }
    for (std::uint32_t k : cells.loose_objects()) in_pvs[k] = 1;
    std::size_t pvs_count = 0;
    for (std::uint32_t k : frustum_set) pvs_count += in_pvs[k];
    for (std::uint32_t k : portal_set) in_portals[k] = 1;
    const oracle::HitBuffer hits = embree.render(cam, 1);
    const PixelRays rays(cam);
    for (int y = 0; y < hits.height; ++y)
      for (int x = 0; x < hits.width; ++x) {
        const std::uint32_t tri = hits.at(x, y);
        if (tri == oracle::HitBuffer::miss) continue;
        const Ray r = rays.ray(x, y);
        const glm::vec3 p = r.origin + r.direction * hits.distance[static_cast<std::size_t>(y) * hits.width + x];
        if (signed_distance(f.plane(Frustum::near_plane), p) < 0.0f) continue;
        seen[object_of_triangle[tri]] = 1;
      }
    long cam_false = 0;
    std::size_t seen_count = 0;
    for (std::size_t k = 0; k < bounds.size(); ++k) {
      if (!seen[k]) continue;
      ++seen_count;
      row.false_pvs += !in_pvs[k];
      cam_false += !in_portals[k];
    }
    row.false_portals += cam_false;
    row.cameras_false_portals += cam_false > 0;
    row.frustum += static_cast<double>(frustum_set.size());
    row.pvs += static_cast<double>(pvs_count);
    row.portals_kept += static_cast<double>(portal_set.size());
    row.seen += static_cast<double>(seen_count);
  }
  const double n = static_cast<double>(std::max<std::size_t>(cams.size(), 1));
  for (double* v : {&row.frustum, &row.pvs, &row.portals_kept, &row.seen, &row.views}) *v /= n;
  const auto res = cullkit_bench::race(
      "oacmpdm9", {{"frustum_abt", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { abt.cull(frusta[i], frustum_set); cullkit_bench::keep(frustum_set); } }},
                   {"portals", [&] { for (std::size_t i = 0; i < cams.size(); ++i) { portal_cull(cams[i], frusta[i]); cullkit_bench::keep(portal_set); } }}},
      11);
  row.ns_frustum = res[0].median_ns / n;
  row.ns_portals = res[1].median_ns / n;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const bool smoke = cullkit_bench::smoke();
  int ncam = argc > 1 ? std::atoi(argv[1]) : 100, width = argc > 2 ? std::atoi(argv[2]) : 320,
      height = argc > 3 ? std::atoi(argv[3]) : 240;
  if (smoke) {
    ncam = 4;
    width = 80;
    height = 60;
  }
  std::vector<Row> rows;
  rows.push_back(run("office 10x10 (100 rooms)", 1, 10, 10, ncam, width, height));
  if (!smoke) {
    rows.push_back(run("office 10x8 (80 rooms)", 1, 10, 8, ncam, width, height));
    rows.push_back(run("office 32x25 (800 rooms)", 1, 32, 25, ncam, width, height));
  }
  std::printf("\n| scene | triangles | cameras | frustum %% | frustum+occl %% | portals %% | portals+occl %% | visible %% | "
              "portals / visible | portals+occl / visible | views | rooms reached | false culls | frustum us | "
              "portals us | portals+occl us | frustum+occl us | portals / frustum time |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  long false_total = 0;
  for (const Row& r : rows) {
    std::printf("| %s | %zu | %zu | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f | %ld | %.1f | %.1f | %.1f | "
                "%.1f | %.2f |\n",
                r.scene.c_str(), r.triangles, r.cameras, 100 * r.frustum, 100 * r.frustum_occ, 100 * r.portals,
                100 * r.portals_occ, 100 * r.visible, r.portals / r.visible, r.portals_occ / r.visible, r.views, r.reached,
                r.false_portals + r.false_portals_occ, r.ns_frustum / 1e3, r.ns_portals / 1e3, r.ns_portals_occ / 1e3,
                r.ns_frustum_occ / 1e3, r.ns_portals / r.ns_frustum);
    false_total += r.false_portals + r.false_portals_occ;
  }
  OaRow oa;
  if (run_openarena(width, height, oa)) {
    std::printf("\n| scene | leaves (cells) | portals (open) | cameras | objects: frustum | PVS row + frustum | portals | "
                "seen | views | false culls: PVS | portals (cameras) | frustum us | portals us |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::printf("| oacmpdm9 | %zu | %zu (%zu) | %zu | %.0f | %.0f | %.0f | %.0f | %.1f | %ld | %ld (%ld) | %.1f | %.1f |\n",
                oa.leaves, oa.portals, oa.open_portals, oa.cameras, oa.frustum, oa.pvs, oa.portals_kept, oa.seen, oa.views,
                oa.false_pvs, oa.false_portals, oa.cameras_false_portals, oa.ns_frustum / 1e3, oa.ns_portals / 1e3);
  } else {
    std::printf("\n(oacmpdm9 not found: OpenArena row skipped)\n");
  }
  return false_total == 0 ? 0 : 1;
}
