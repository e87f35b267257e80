// tests/check.hpp: the whole test framework. CHECK counts failures and prints file:line: expression;
// a test's main returns cullkit_test::report(), non-zero when anything failed.
#pragma once

#include <cmath>
#include <cstdio>

namespace cullkit_test {
inline int& failures() {
  static int n = 0;
  return n;
}
inline int& checks() {
  static int n = 0;
  return n;
}
inline bool record(bool ok, const char* file, int line, const char* expr) {
  ++checks();
  if (!ok) {
    ++failures();
    if (failures() <= 50) std::fprintf(stderr, "%s:%d: check failed: %s\n", file, line, expr);
  }
  return ok;
}
/// Prints the summary line and returns the exit code.
inline int report(const char* name) {
  std::printf("%s: %d checks, %d failed\n", name, checks(), failures());
  if (checks() == 0) {
    std::printf("%s: no checks ran, which is a failure\n", name);
    return 1;
  }
  return failures() == 0 ? 0 : 1;
}
}  // namespace cullkit_test

/// CHECK(expr): records a failure with file:line and the expression text; evaluates to expr.
/// Variadic so that template arguments with commas need no extra parentheses.
#define CHECK(...) ::cullkit_test::record(static_cast<bool>(__VA_ARGS__), __FILE__, __LINE__, #__VA_ARGS__)
/// CHECK_MSG(expr, fmt, ...): as CHECK, and prints a printf-style context line on failure
/// (use it to print the seed, camera or index that failed).
#define CHECK_MSG(expr, ...)                                                  \
  do {                                                                        \
    if (!CHECK(expr) && ::cullkit_test::failures() <= 50) {                   \
      std::fprintf(stderr, "    ");                                           \
      std::fprintf(stderr, __VA_ARGS__);                                      \
      std::fprintf(stderr, "\n");                                             \
    }                                                                         \
  } while (0)
/// CHECK_NEAR(a, b, tol)
#define CHECK_NEAR(a, b, tol) CHECK(std::fabs(double(a) - double(b)) <= double(tol))
