// Must NOT compile: from_getter with a callable that does not return bounds.
#include <cullkit/adaptive_binary_tree.hpp>

struct MyEngineBadGetter {
  int operator()(std::uint32_t i) const { return static_cast<int>(i); }
};

int main() {
  const auto tree = cullkit::AdaptiveBinaryTree<cullkit::Aabb>::from_getter(4, MyEngineBadGetter{});
  return static_cast<int>(tree.size());
}
