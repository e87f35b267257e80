// order_back_to_front against a brute-force oracle: std::stable_sort of indices with the contract's
// comparator (larger depth first, NaN before every number, -0 equal to +0), on random and
// adversarial key sets of many sizes, in both the index and the key-and-payload form.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <cullkit/depth_sort.hpp>
#include <cullkit_support/scene.hpp>

#include "check.hpp"

namespace {

using cullkit::support::Rng;

// The contract, written as a strict weak order: a comes before b.
bool before(float a, float b) {
  const bool na = std::isnan(a), nb = std::isnan(b);
  if (na || nb) return na && !nb;
  return a > b;  // -0 > +0 is false both ways: equal
}

std::vector<std::uint32_t> oracle(const std::vector<float>& depth) {
  std::vector<std::uint32_t> idx(depth.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  std::stable_sort(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) { return before(depth[a], depth[b]); });
  return idx;
}

float from_bits(std::uint32_t b) {
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

// Key sets that exercise every digit, skipped passes and the special values.
std::vector<float> make_keys(int kind, std::size_t n, Rng& rng) {
  std::vector<float> d(n);
  const float inf = std::numeric_limits<float>::infinity();
  const float specials[] = {0.0f, -0.0f, inf, -inf, std::numeric_limits<float>::quiet_NaN(),
                            -std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::denorm_min(),
                            -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max(),
                            std::numeric_limits<float>::lowest(), 1.0f, -1.0f};
  for (std::size_t i = 0; i < n; ++i) {
    switch (kind) {
      case 0: d[i] = rng.uniform(-1000.0f, 1000.0f); break;                        // plain depths
      case 1: d[i] = from_bits(static_cast<std::uint32_t>(rng.next())); break;      // any bits, NaNs too
      case 2: d[i] = specials[rng.next() % (sizeof specials / sizeof specials[0])]; break;
      case 3: d[i] = static_cast<float>(rng.range(0, 7)); break;                    // many ties
      case 4: d[i] = 5.0f; break;                                                   // all equal
      case 5: d[i] = from_bits(0x3F800000u | static_cast<std::uint32_t>(rng.next() & 0x7FFu)); break;  // low digit only
      case 6: d[i] = from_bits(static_cast<std::uint32_t>(rng.next() & 0xFFC00000u)); break;  // high digit only
      default: d[i] = (i % 3 == 0) ? -0.0f : 0.0f; break;                            // signed zeros
    }
  }
  return d;
}

void test_against_oracle() {
  Rng rng(7);
  const std::size_t sizes[] = {0, 1, 2, 3, 17, 1000, 4096, 100000};
  cullkit::DepthSortScratch scratch;
  std::vector<std::uint32_t> order, order_tl, payload_out;
  for (int kind = 0; kind < 8; ++kind) {
    for (std::size_t n : sizes) {
      const auto depth = make_keys(kind, n, rng);
      const auto want = oracle(depth);
      order.assign(3, 99u);  // stale content must be cleared
      cullkit::order_back_to_front(depth.data(), n, order, scratch);
      CHECK_MSG(order == want, "kind %d, n %zu", kind, n);
      cullkit::order_back_to_front(depth.data(), n, order_tl);
      CHECK_MSG(order_tl == want, "thread-local scratch: kind %d, n %zu", kind, n);
      // Key-and-payload: the payload of item i is some value p[i]; the result is p in sorted order.
      std::vector<std::uint32_t> payload(n);
      for (std::size_t i = 0; i < n; ++i) payload[i] = static_cast<std::uint32_t>(rng.next());
      cullkit::order_back_to_front(depth.data(), payload.data(), n, payload_out, scratch);
      bool same = payload_out.size() == n;
      for (std::size_t i = 0; same && i < n; ++i) same = payload_out[i] == payload[want[i]];
      CHECK_MSG(same, "payload form: kind %d, n %zu", kind, n);
    }
  }
}

// The oracle must be able to tell a wrong sort: on tied keys an unstable order (std::sort) and an
// ascending order differ from it, so a radix sort that lost stability or direction would fail.
void test_oracle_discriminates() {
  Rng rng(11);
  const auto depth = make_keys(3, 5000, rng);
  const auto want = oracle(depth);
  std::vector<std::uint32_t> unstable = want;
  std::sort(unstable.begin(), unstable.end(), [&](std::uint32_t a, std::uint32_t b) {
    return before(depth[a], depth[b]) || (!before(depth[b], depth[a]) && a > b);  // ties reversed
  });
  CHECK(unstable != want);
  std::vector<std::uint32_t> ascending = want;
  std::reverse(ascending.begin(), ascending.end());
  CHECK(ascending != want);
  // NaN first, signed zeros tied, the extremes in their places.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> d = {1.0f, -0.0f, nan, inf, 0.0f, -inf, -nan, -2.0f};
  std::vector<std::uint32_t> order;
  cullkit::order_back_to_front(d.data(), d.size(), order);
  const std::vector<std::uint32_t> expect = {2, 6, 3, 0, 1, 4, 7, 5};
  CHECK(order == expect);
}

// Once the scratch and the output have grown, sorting again allocates nothing.
void test_no_allocation_when_warm() {
  Rng rng(3);
  const auto depth = make_keys(0, 50000, rng);
  cullkit::DepthSortScratch scratch;
  std::vector<std::uint32_t> order;
  cullkit::order_back_to_front(depth.data(), depth.size(), order, scratch);
  const std::size_t bytes = scratch.bytes();
  const auto* data = order.data();
  CHECK(bytes == 2 * depth.size() * sizeof(std::uint64_t));
  for (int r = 0; r < 3; ++r) {
    cullkit::order_back_to_front(depth.data(), depth.size() - static_cast<std::size_t>(r) * 1000, order, scratch);
    CHECK(scratch.bytes() == bytes);
    CHECK(order.data() == data);
  }
  scratch.release();
  CHECK(scratch.bytes() == 0);
}

}  // namespace

int main() {
  test_against_oracle();
  test_oracle_discriminates();
  test_no_allocation_when_warm();
  return cullkit_test::report("test_depth_sort");
}
