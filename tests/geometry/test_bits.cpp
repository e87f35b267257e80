// detail/bits.hpp against naive loops: every single-bit value, every pair of bits, and random
// values. Built twice, with the compiler's intrinsics and with the portable fallbacks forced
// (CULLKIT_PORTABLE_BITS), so both branches are checked on every compiler that runs the suite.
#include <cstdint>

#include <check.hpp>
#include <cullkit/detail/bits.hpp>

namespace {
int naive_low(std::uint64_t v) {
  int i = 0;
  while (!((v >> i) & 1u)) ++i;
  return i;
}
int naive_high(std::uint64_t v) {
  int i = 63;
  while (!((v >> i) & 1u)) --i;
  return i;
}
int naive_count(std::uint64_t v) {
  int n = 0;
  for (int i = 0; i < 64; ++i) n += static_cast<int>((v >> i) & 1u);
  return n;
}
void check_value(std::uint64_t v) {
  using namespace cullkit::detail;
  CHECK_MSG(popcount(v) == naive_count(v), "popcount(%llx)", static_cast<unsigned long long>(v));
  if (v == 0) return;
  CHECK_MSG(lowest_bit(v) == naive_low(v), "lowest_bit(%llx)", static_cast<unsigned long long>(v));
  CHECK_MSG(highest_bit(v) == naive_high(v), "highest_bit(%llx)", static_cast<unsigned long long>(v));
  const auto low32 = static_cast<std::uint32_t>(v);
  if (low32 != 0) CHECK(lowest_bit(low32) == naive_low(low32));
}
}  // namespace

int main() {
  check_value(0);
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j) check_value((std::uint64_t{1} << i) | (std::uint64_t{1} << j));
  std::uint64_t x = 0x9e3779b97f4a7c15ull;
  for (int k = 0; k < 100000; ++k) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    check_value(x);
    check_value(x >> (k % 64));
    check_value(~x);
  }
  int dummy = 0;
  cullkit::detail::prefetch(&dummy);
  return cullkit_test::report("test_bits");
}
