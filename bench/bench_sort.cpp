// bench_sort: order_back_to_front (radix sort) against std::sort and std::stable_sort of
// (depth, index) pairs, the same keys, one core, in one process. Each contestant produces the
// back-to-front index list from the depth array. Prints the race CSV (medians, ratios to the radix
// sort) and then one summary row per size: keys per second of each and the radix/stable_sort ratio.
// Depths are uniform in [1, 1000) (finite, so that the comparison sorts' `>` is a valid order).
// Flags: --max N (largest size, default 10000000). CULLKIT_BENCH_SMOKE=1: 1k and 10k keys only.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <utility>
#include <vector>

#include <cullkit/depth_sort.hpp>
#include <cullkit_support/scene.hpp>

#include "race.hpp"

int main(int argc, char** argv) {
  std::size_t max_size = 10000000;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--max") == 0) max_size = static_cast<std::size_t>(std::atoll(argv[i + 1]));
  if (cullkit_bench::smoke()) max_size = 10000;
  struct Row {
    std::size_t n;
    double radix, sort, stable;
  };
  std::vector<Row> rows;
  for (std::size_t n = 1000; n <= max_size; n *= 10) {
    cullkit::support::Rng rng(42 + n);
    std::vector<float> depth(n);
    for (auto& d : depth) d = rng.uniform(1.0f, 1000.0f);
    cullkit::DepthSortScratch scratch;
    std::vector<std::uint32_t> order;
    std::vector<std::pair<float, std::uint32_t>> pairs(n);
    std::vector<std::uint32_t> peer_order(n);
    auto fill_pairs = [&] {
      for (std::size_t i = 0; i < n; ++i) pairs[i] = {depth[i], static_cast<std::uint32_t>(i)};
    };
    auto emit = [&] {
      for (std::size_t i = 0; i < n; ++i) peer_order[i] = pairs[i].second;
      cullkit_bench::keep(peer_order[n / 2]);
    };
    auto far_first = [](const std::pair<float, std::uint32_t>& a, const std::pair<float, std::uint32_t>& b) {
      return a.first > b.first;
    };
    const int reps = n >= 10000000 ? 7 : (n >= 1000000 ? 15 : 31);
    const auto res = cullkit_bench::race(
        "sort_" + std::to_string(n),
        {{"radix", [&] {
            cullkit::order_back_to_front(depth.data(), nullptr, n, order, scratch);
            cullkit_bench::keep(order[n / 2]);
          }},
         {"std_sort_pairs", [&] {
            fill_pairs();
            // (depth, index) pairs: ties broken by index keeps the result equal to the stable one.
            std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
              return a.first > b.first || (a.first == b.first && a.second < b.second);
            });
            emit();
          }},
         {"std_stable_sort_pairs", [&] {
            fill_pairs();
            std::stable_sort(pairs.begin(), pairs.end(), far_first);
            emit();
          }}},
        reps);
    // Same answer as the stable sort (checked once per size, outside the timing).
    if (order != peer_order) {
      std::fprintf(stderr, "bench_sort: radix and stable_sort disagree at n=%zu\n", n);
      return 1;
    }
    rows.push_back({n, res[0].median_ns, res[1].median_ns, res[2].median_ns});
  }
  std::printf("\nsummary,n,radix_Mkeys_per_s,std_sort_Mkeys_per_s,stable_sort_Mkeys_per_s,radix_over_stable_time\n");
  for (const auto& r : rows) {
    std::printf("summary,%zu,%.1f,%.1f,%.1f,%.3f\n", r.n, r.n / r.radix * 1e3, r.n / r.sort * 1e3, r.n / r.stable * 1e3,
                r.radix / r.stable);
  }
  return 0;
}
