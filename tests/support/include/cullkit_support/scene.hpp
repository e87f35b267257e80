// cullkit_support/scene.hpp: triangle scenes for tests, benchmarks and demos: seeded generators
// (city, office, forest) and real OBJ scenes from ../shared/scenes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include <cullkit/cullkit.hpp>

namespace cullkit::support {

/// One object of a scene: a contiguous range of triangles.
struct SceneObject {
  std::string name;
  std::uint32_t first_triangle = 0;  ///< index of its first triangle (indices[3*first_triangle])
  std::uint32_t triangle_count = 0;
  Aabb bounds = Aabb::empty();       ///< tight bounds of its triangles
  bool major_occluder = false;       ///< a big closed solid (building, wall) worth occluding with
  bool is_box = false;               ///< exactly the 12 outward-facing triangles of `bounds`
};

/// An indexed triangle soup with objects. Triangles are counter-clockwise seen from their front
/// (outward for closed solids). Y is up.
struct Scene {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  std::vector<SceneObject> objects;
  Aabb bounds = Aabb::empty();

  [[nodiscard]] std::size_t triangle_count() const { return indices.size() / 3; }
  [[nodiscard]] MeshView<glm::vec3> mesh() const {
    return MeshView<glm::vec3>{positions.data(), positions.size(), indices.data(), indices.size()};
  }
  /// Bounds of every object, in object order (handy for the trees).
  [[nodiscard]] std::vector<Aabb> object_bounds() const;
  /// Adds a closed box as 12 outward-facing triangles forming one object; returns its object index.
  std::uint32_t add_box(const Aabb& box, const std::string& name, bool major_occluder);
  /// Appends raw triangles (positions given 3 per triangle) as one object; returns its object index.
  std::uint32_t add_triangles(const std::vector<glm::vec3>& corners, const std::string& name);
  /// Appends an indexed mesh (indices local to `mesh_positions`, 3 per triangle) as one object;
  /// returns its object index. Indices out of range are the caller's bug (asserted, then clamped to 0).
  std::uint32_t add_mesh(const std::vector<glm::vec3>& mesh_positions, const std::vector<std::uint32_t>& mesh_indices,
                         const std::string& name);
};

/// The 12 outward, counter-clockwise triangles of a box as 36 indices into its 8 corners
/// (`cullkit::corner(box, i)`: bit 0 x, bit 1 y, bit 2 z). Faces in the order -x, +x, -y, +y, -z, +z.
extern const std::uint32_t kBoxTriangleCorners[36];

/// A city: a grid of `blocks` x `blocks` blocks separated by streets, each block holding box
/// buildings of varied heights (major occluders), with props (lamp posts, benches, cars) on the
/// streets and small rooftop props (antennas, water tanks). About 125 triangles per block:
/// make_city(1, 8) has 7,904 triangles (the seed paper's city: 7,952), make_city(1, 26) 85,544.
/// Blocks are 60 m with 14 m streets, centred on the origin; buildings are boxes 8..80 m tall named
/// "building_<i>_<j>_<k>", rooftop props "roof_*_<building name>" with min.y exactly the roof's max.y,
/// one up-facing ground tile per block ("ground_<i>_<j>") paving block and half the streets around it.
/// The same seed gives the same bytes with any compiler (support::Rng only).
[[nodiscard]] Scene make_city(std::uint32_t seed, int blocks);
/// An office floor: a grid of `rooms_x` x `rooms_z` rooms with walls (major occluders, as boxes),
/// door gaps, desks, chairs and monitors. About 400 triangles per room: make_office(1, 10, 8) has
/// 31,528 (the seed's office: 30,343). Rooms are 6 x 5 m, walls 3 m high and 0.2 m thick; every wall
/// between two rooms has one door (pieces "_left", "_right", "_lintel"), outer walls have none.
[[nodiscard]] Scene make_office(std::uint32_t seed, int rooms_x, int rooms_z);
/// The rooms and door openings of an office, known by construction (for cells and portals).
struct OfficeCells {
  /// Room (i, j) is `rooms[j * rooms_x + i]`: from the floor (y = 0) to the top of the walls
  /// (y = 3), out to the centre lines of its walls, so neighbouring rooms share a face and a wall
  /// between two rooms meets both.
  std::vector<Aabb> rooms;
  /// A door gap between two rooms: the 1 x 2.1 m opening on the centre plane of its wall. `room_a`
  /// is on the lower side along the wall's normal; the corners' right-hand normal points into `room_b`.
  struct Door {
    std::uint32_t room_a = 0, room_b = 0;
    glm::vec3 corners[4];
  };
  std::vector<Door> doors;
};
/// As `make_office(seed, rooms_x, rooms_z)` (the same scene, byte for byte), and writes its rooms and
/// doors to `cells` when it is not null.
[[nodiscard]] Scene make_office(std::uint32_t seed, int rooms_x, int rooms_z, OfficeCells* cells);
/// A forest: a terrain height field of `terrain_cells` x `terrain_cells` quads and `trees` trees
/// (trunk box + crown cone), seeded placement. Cells are 4 m; one terrain object per 8 x 8 cells;
/// each tree is a trunk box (sunk 0.5 m into the surface) and a closed 8-sided cone crown.
[[nodiscard]] Scene make_forest(std::uint32_t seed, int terrain_cells, int trees);
/// Foliage: `trees_per_side` x `trees_per_side` places on a 6 m grid (a tenth left empty), each tree
/// a trunk box and a crown of `leaves` small leaf triangles (0.12-0.24 m, random facing) scattered
/// through an ellipsoid 3-6 m wide, over a waved ground of 4 m cells. Seen from outside, most pixels
/// over a crown see through several leaves before one stops the ray. make_foliage(1, 70, 2280) has
/// about 10.1M triangles.
[[nodiscard]] Scene make_foliage(std::uint32_t seed, int trees_per_side, int leaves);
/// A crowded field: `side` x `side` lots of 1 m centred on the origin, each paved by two up-facing
/// ground triangles and holding a small box (half of them turned about Y), a floating slab (an
/// overhang, closed), a tuft of 3-6 thin leaning slivers (both windings), or nothing; about 12
/// triangles per lot on average (make_crowd(1, 150, false) has about 270,000). Seen whole at a few
/// hundred pixels across, most triangles are smaller than a pixel. `mixed` adds, beside the field on
/// +X, a plaza 0.75 `side` deep of 12 large boxes (0.15-0.5 `side` tall) on one large ground quad, so
/// a view can hold crowded and large-triangle parts at once. One object per row of lots
/// ("crowd_row_<j>"), "plaza_ground", "plaza_block_<i>_<j>". Same seed, same bytes on any compiler.
[[nodiscard]] Scene make_crowd(std::uint32_t seed, int side, bool mixed);

/// Loads an OBJ (through tinyobjloader), fan-triangulating faces; every `o`/`g` object becomes a
/// SceneObject (groups without a usable face make none). Faces with an out-of-range index or a
/// non-finite corner are skipped and counted (see ObjLoadStats); nothing is printed. Returns nothing
/// if the file cannot be read, if tinyobjloader rejects it (a face index of 0, which OBJ forbids,
/// stops its parser), or if the loader is not available.
[[nodiscard]] std::optional<Scene> load_obj(const std::string& path);

/// What `load_obj` skipped (it never prints; callers that care print these).
struct ObjLoadStats {
  std::size_t faces = 0;               ///< faces read (polygons, before triangulation)
  std::size_t skipped_faces = 0;       ///< faces with an index out of range or fewer than 3 corners
  std::size_t nonfinite_vertices = 0;  ///< vertices with NaN/inf coordinates (faces using them are skipped)
  std::size_t empty_shapes = 0;        ///< `o`/`g` groups without a triangle (no object made)
};
/// As `load_obj(path)`, and reports what was skipped in `stats` (may be null).
[[nodiscard]] std::optional<Scene> load_obj(const std::string& path, ObjLoadStats* stats);

/// The folder of real scenes: $CULLKIT_SCENES if set, else ../shared/scenes beside the checkout.
/// Empty string if it does not exist (tests then skip real scenes and must still pass).
[[nodiscard]] std::string scenes_dir();
/// Real scene file names present in `scenes_dir()` (e.g. "fzk_haus.obj"), smallest first.
[[nodiscard]] std::vector<std::string> real_scene_files();

/// A right-handed look-at perspective camera (GLM conventions) for the given depth range.
/// `far_plane` <= 0 means an infinite far plane; `reversed_z` swaps near and far depths.
[[nodiscard]] Camera make_camera(const glm::vec3& eye, const glm::vec3& target, float fov_y_degrees,
                                 int width, int height, float near_plane, float far_plane,
                                 DepthRange depth = DepthRange::negative_one_to_one,
                                 bool reversed_z = false);

/// A deterministic pseudo-random generator (splitmix64), the same on every platform.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  float uniform() { return static_cast<float>(next() >> 40) * (1.0f / 16777216.0f); }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  int range(int lo, int hi_inclusive) {
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi_inclusive - lo + 1));
  }

 private:
  std::uint64_t state_;
};

}  // namespace cullkit::support
