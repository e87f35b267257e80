// bench/race.hpp: a plain side-by-side race harness. Each contestant runs the same work on the
// same input in this process; we report the median of many timed repetitions and the ratio to the
// first contestant (the reference), as CSV on stdout:
//   race,contestant,median_ns,min_ns,reps,ratio_to_reference
// `CULLKIT_BENCH_SMOKE=1` in the environment runs each contestant only a couple of times (the CTest
// smoke run, which only proves the benchmark still builds and runs).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

namespace cullkit_bench {

inline bool smoke() {
  const char* s = std::getenv("CULLKIT_BENCH_SMOKE");
  return s && *s && *s != '0';
}

struct Contestant {
  std::string name;
  std::function<void()> run;  ///< one repetition of the work
};

struct RaceResult {
  std::string name;
  double median_ns = 0, min_ns = 0;
  int reps = 0;
};

/// Keeps the optimizer from discarding a result.
template <class T>
inline void keep(const T& value) {
  asm volatile("" : : "g"(&value) : "memory");
}

inline void print_header() {
  static bool printed = false;
  if (!printed) std::printf("race,contestant,median_ns,min_ns,reps,ratio_to_reference\n");
  printed = true;
}

/// Runs every contestant `reps` times (interleaved, so a slow phase of the machine hits them all
/// alike) after one warm-up run each; prints one CSV row per contestant and returns the results.
/// The order changes from one repetition to the next (every rotation, forward and backward), so
/// each contestant runs right after each other one about equally often: a contestant that evicts
/// the caches (a slow peer) then costs all of them alike instead of always the one after it.
inline std::vector<RaceResult> race(const std::string& race_name, const std::vector<Contestant>& contestants,
                                    int reps = 31) {
  if (smoke()) reps = 2;
  print_header();
  std::vector<std::vector<double>> times(contestants.size());
  for (auto& c : contestants) c.run();
  for (int r = 0; r < reps; ++r) {
    const std::size_t n = contestants.size(), k = std::size_t(r) % (2 * n), first = k % n;
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = k < n ? (first + j) % n : (first + n - 1 - j) % n;
      const auto t0 = std::chrono::steady_clock::now();
      contestants[i].run();
      const auto t1 = std::chrono::steady_clock::now();
      times[i].push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
    }
  }
  std::vector<RaceResult> out;
  for (std::size_t i = 0; i < contestants.size(); ++i) {
    auto& t = times[i];
    std::sort(t.begin(), t.end());
    RaceResult res;
    res.name = contestants[i].name;
    res.median_ns = t[t.size() / 2];
    res.min_ns = t.front();
    res.reps = reps;
    out.push_back(res);
  }
  for (auto& r : out) {
    std::printf("%s,%s,%.0f,%.0f,%d,%.3f\n", race_name.c_str(), r.name.c_str(), r.median_ns, r.min_ns, r.reps,
                r.median_ns / out.front().median_ns);
  }
  std::fflush(stdout);
  return out;
}

}  // namespace cullkit_bench
