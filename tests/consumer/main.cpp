// A consumer of the installed package: includes the umbrella header and culls one box.
#include <cullkit/cullkit.hpp>
#include <glm/ext/matrix_clip_space.hpp>

int main() {
  const cullkit::Frustum f = cullkit::Frustum::from_matrix(glm::perspectiveRH_NO(1.0f, 1.0f, 0.1f, 10.0f));
  const cullkit::Aabb in_view{glm::vec3(-1, -1, -5), glm::vec3(1, 1, -4)};
  const cullkit::Aabb behind{glm::vec3(-1, -1, 4), glm::vec3(1, 1, 5)};
  return (f.classify(in_view) != cullkit::Containment::outside &&
          f.classify(behind) == cullkit::Containment::outside) ? 0 : 1;
}
