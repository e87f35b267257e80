#include <check.hpp>
#include <cullkit/cullkit.hpp>
int main() {
  cullkit::Aabb b{glm::vec3(0), glm::vec3(1)};
  CHECK(cullkit::is_valid(b));
  return cullkit_test::report("test_geometry");
}
