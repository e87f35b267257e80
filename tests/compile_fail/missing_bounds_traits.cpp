// Must NOT compile: an object type with no BoundsTraits specialization.
#include <cullkit/cullkit.hpp>

struct MyEngineObjectWithoutBounds {
  int id;
};

int main() {
#ifdef CULLKIT_COMPILE_FAIL_WITH_TREE
  const MyEngineObjectWithoutBounds objects[1] = {};
  cullkit::AdaptiveBinaryTree<MyEngineObjectWithoutBounds> tree(objects, 1);
  (void)tree;
#else
  (void)cullkit::require_bounds_traits<MyEngineObjectWithoutBounds>::value;
#endif
  return 0;
}
