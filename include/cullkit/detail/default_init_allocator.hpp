// cullkit/detail/default_init_allocator.hpp: an allocator whose value-less construction leaves a
// trivially constructible element uninitialized, so that `resize` on a per-frame buffer only makes
// room: every slot is written before it is read, and zeroing tens of thousands of them each frame
// would cost more than filling them.
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace cullkit {
namespace detail {

template <class T>
class DefaultInitAllocator : public std::allocator<T> {
 public:
  using value_type = T;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };

  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

  /// Default-initialization: no zeroing for trivial types.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T, class U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
  return true;
}
template <class T, class U>
bool operator!=(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
  return false;
}

}  // namespace detail
}  // namespace cullkit
