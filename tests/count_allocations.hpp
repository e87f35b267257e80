// tests/count_allocations.hpp: replaces the global operator new and delete with ones that count
// every allocation, for tests that claim a warm path allocates nothing. Include it in exactly one
// source file of a test program (the replacements are program-wide definitions).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace cullkit_test {
/// Allocations through any global operator new since the program started.
inline std::atomic<long long>& allocations() {
  static std::atomic<long long> n{0};
  return n;
}
}  // namespace cullkit_test

// The replacements pair malloc with free; GCC cannot see that through inlined callers.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(std::size_t size) {
  cullkit_test::allocations().fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  std::abort();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  cullkit_test::allocations().fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
