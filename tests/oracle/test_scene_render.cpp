// The generated scenes through Embree: closed solids are wound outward (a ray aimed at a box from
// just outside hits that box's near face at the expected distance; from inside a building nothing of
// it is seen), terrain is hit from above where the generator says the ground is, and a street-level
// view of the city sees rooftop props, buildings and ground. Ids are the scene's own triangle ids.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <check.hpp>
#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>
#include <embree_oracle.hpp>

using namespace cullkit;
using oracle::EmbreeScene;
using oracle::HitBuffer;
using support::Scene;
using support::SceneObject;

namespace {

bool starts_with(const std::string& s, const char* p) { return s.rfind(p, 0) == 0; }

void add_scene(EmbreeScene& e, const Scene& s) {
  CHECK(e.add_mesh(s.positions.data(), s.positions.size(), s.indices.data(), s.indices.size()) == 0);
  e.commit();
  CHECK(e.triangle_count() == s.triangle_count());
}

// Aims one ray at each box object from `gap` metres outside the middle of each side face, toward
// the box's centre; the first hit must be on that object at distance `gap` (unless something else
// stands in that gap, which the generators avoid for the prefixes tested).
void boxes_hit_from_outside(const Scene& s, const EmbreeScene& e, const char* prefix, float gap, int& tested,
                            int& wrong) {
  for (const SceneObject& o : s.objects) {
    if (!o.is_box || !starts_with(o.name, prefix)) continue;
    const glm::vec3 c = o.bounds.center(), ext = o.bounds.extent();
    for (int axis : {0, 2})
      for (int side : {-1, 1}) {
        if (ext[axis] <= 0.0f) continue;
        glm::vec3 eye = c, dir(0.0f);
        eye[axis] = (side < 0 ? o.bounds.min[axis] : o.bounds.max[axis]) + gap * static_cast<float>(side);
        dir[axis] = -1.0f * side;
        float t = 0;
        const std::uint32_t id = e.first_hit(Ray{eye, dir}, &t);
        ++tested;
        const bool mine = id != HitBuffer::miss && id >= o.first_triangle && id < o.first_triangle + o.triangle_count;
        if (!mine || std::fabs(t - gap) > 1e-3f) {
          if (++wrong <= 5)
            std::fprintf(stderr, "%s axis %d side %d: hit %u at %g\n", o.name.c_str(), axis, side, id, double(t));
        }
      }
  }
}

void test_city() {
  const Scene s = support::make_city(3, 5);
  EmbreeScene e;
  add_scene(e, s);
  int tested = 0, wrong = 0;
  boxes_hit_from_outside(s, e, "building_", 0.5f, tested, wrong);
  CHECK_MSG(wrong == 0, "city: %d of %d rays at buildings miss their near face", wrong, tested);
  CHECK(tested >= 4 * 50);
  // From inside a building every one of its faces is a back face: a ray upward from inside a
  // building passes through its roof and sees only what is above (a rooftop prop, or nothing).
  int inside_hits = 0, inside_tested = 0;
  for (const SceneObject& o : s.objects) {
    if (!starts_with(o.name, "building_")) continue;
    for (const glm::vec3& d : {glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, -1, 0)}) {
      const std::uint32_t id = e.first_hit(Ray{o.bounds.center(), d});
      ++inside_tested;
      inside_hits += id != HitBuffer::miss && id >= o.first_triangle && id < o.first_triangle + o.triangle_count;
    }
  }
  CHECK_MSG(inside_hits == 0, "city: %d rays from inside a building hit its own faces", inside_hits);
  CHECK(inside_tested > 100);
  // A view over the city from above one corner: the picture holds ground, buildings and rooftop props.
  const Camera cam = support::make_camera({s.bounds.min.x - 20, 120, s.bounds.min.z - 20}, s.bounds.center(), 60, 320,
                                          240, 0.5f, 2000);
  const HitBuffer h = e.render(cam);
  int ground = 0, building = 0, roof = 0, miss = 0;
  for (std::uint32_t id : h.triangle) {
    if (id == HitBuffer::miss) {
      ++miss;
      continue;
    }
    const auto it = std::upper_bound(s.objects.begin(), s.objects.end(), id,
                                     [](std::uint32_t v, const SceneObject& o) { return v < o.first_triangle; });
    const std::string& name = (it - 1)->name;
    ground += starts_with(name, "ground_");
    building += starts_with(name, "building_");
    roof += starts_with(name, "roof_");
  }
  CHECK_MSG(ground > 1000 && building > 10000 && roof > 20 && miss > 1000,
            "city view: ground %d, buildings %d, rooftop props %d, sky %d", ground, building, roof, miss);
  std::printf("city(3, 5) view: %zu visible triangles of %zu; pixels: ground %d, buildings %d, rooftop props %d, sky %d\n",
              oracle::visible_triangles(h).size(), s.triangle_count(), ground, building, roof, miss);
}

void test_office() {
  const Scene s = support::make_office(4, 4, 3);
  EmbreeScene e;
  add_scene(e, s);
  int tested = 0, wrong = 0;
  // Cabinets stand 0.1 m off their wall's face: aim from 5 cm away on every side.
  boxes_hit_from_outside(s, e, "cabinet_", 0.05f, tested, wrong);
  CHECK_MSG(wrong == 0 && tested >= 16, "office: %d of %d rays at cabinets miss their near face", wrong, tested);
  // Walls: from the middle of a room, every horizontal ray hits a wall (or furniture, or passes a
  // door into the next room, where it hits something else) and never escapes: the floor is closed.
  int escaped = 0, rays = 0;
  for (const SceneObject& o : s.objects) {
    if (!starts_with(o.name, "floor_")) continue;
    const glm::vec3 c = o.bounds.center() + glm::vec3(0, 1.5f, 0);  // below the lintels: through doors
    for (int k = 0; k < 16; ++k) {
      const float a = 6.2831853f * static_cast<float>(k) / 16.0f;
      ++rays;
      escaped += e.first_hit(Ray{c, glm::vec3(std::cos(a), 0.0f, std::sin(a))}) == HitBuffer::miss;
    }
  }
  CHECK_MSG(escaped == 0, "office: %d of %d horizontal rays escape the outer walls", escaped, rays);
}

void test_forest() {
  const Scene s = support::make_forest(6, 24, 40);
  EmbreeScene e;
  add_scene(e, s);
  int tested = 0, wrong = 0;
  boxes_hit_from_outside(s, e, "trunk_", 0.5f, tested, wrong);
  // A neighbouring trunk or crown can stand within 0.5 m now and then; most rays must hit their trunk.
  CHECK_MSG(wrong <= tested / 20, "forest: %d of %d rays at trunks miss their near face", wrong, tested);
  // Rays straight down from above hit the terrain (or a crown) everywhere inside the terrain.
  support::Rng rng(77);
  int missed = 0;
  for (int k = 0; k < 500; ++k) {
    const float half = 0.5f * 4.0f * 24 - 0.01f;
    const glm::vec3 eye{rng.uniform(-half, half), 500.0f, rng.uniform(-half, half)};
    missed += e.first_hit(Ray{eye, {0, -1, 0}}) == HitBuffer::miss;
  }
  CHECK_MSG(missed == 0, "forest: %d of 500 downward rays miss the terrain", missed);
  // From below, the terrain is a back face: upward rays from under it see nothing of it.
  int from_below = 0;
  for (int k = 0; k < 200; ++k) {
    const glm::vec3 eye{rng.uniform(-40, 40), -100.0f, rng.uniform(-40, 40)};
    const std::uint32_t id = e.first_hit(Ray{eye, {0, 1, 0}});
    from_below += id != HitBuffer::miss && id < 2u * 24 * 24;
  }
  CHECK(from_below == 0);
}

}  // namespace

int main() {
  test_city();
  test_office();
  test_forest();
  return cullkit_test::report("test_scene_render");
}
