// cullkit/detail/mesh_occlusion/phase_times.hpp: optional per-phase timing of one
// MeshOcclusionCuller::cull, for the benchmark that shows where the time goes. Off by default:
// then each probe is one predictable branch on a thread-local flag.
#pragma once

#include <chrono>
#include <cstdint>

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// The named steps of one `cull`, in order.
enum Phase : int {
  phase_frustum,     // frustum tree walk
  phase_boxes,       // object boxes on screen
  phase_choose,      // occluder choice
  phase_gather,      // occluder triangles: facing, sort
  phase_project,     // vertex projection, wherever it happens (occluder triangles, per-triangle object tests)
  phase_bands,       // band assignment and the already-covered test
  phase_depth,       // depth bounds per cell
  phase_counts,      // winding counts at cell centres
  phase_edges,       // outline edge marking
  phase_end_band,    // prefix sums and freezing per band
  phase_patches,     // each patch's own grid: seeding it, adding it into the union, clearing it
  phase_finish,      // per-tile summaries
  phase_box_occluders,  // solid-box occluders: choice and their hidden region
  phase_tests,       // object tests
  phase_count
};

/// Ticks spent per phase, summed over the `cull` calls made on this thread while `enabled`.
/// Ticks are the processor's time-stamp counter where the compiler exposes it (x86), nanoseconds
/// otherwise; shares of the total are what the benchmark reports.
struct PhaseTimes {
  bool enabled = false;
  std::uint64_t ticks[phase_count] = {};
  std::uint64_t calls = 0;
};

inline PhaseTimes& phase_times() {
  thread_local PhaseTimes times;
  return times;
}

inline std::uint64_t phase_tick() {
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
  return __builtin_ia32_rdtsc();
#else
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count());
#endif
}

/// Adds the time since construction (or the last `next`) to a phase, when timing is enabled.
/// Vertex projection is called from inside other phases (one vertex at a time, by its own probe):
/// its time is taken out of the enclosing phase, so that every tick is charged exactly once.
class PhaseProbe {
 public:
  PhaseProbe()
      : times_(phase_times()), on_(times_.enabled), start_(on_ ? phase_tick() : 0),
        inner_(on_ ? times_.ticks[phase_project] : 0) {}
  /// Charges the time since the last mark, less the vertex projection done meanwhile, to `phase`
  /// and restarts the clock.
  void next(Phase phase) {
    if (!on_) return;
    const std::uint64_t now = phase_tick();
    const std::uint64_t inner = times_.ticks[phase_project] - inner_;
    const std::uint64_t spent = now - start_;
    times_.ticks[phase] += spent > inner ? spent - inner : 0;
    start_ = now;
    inner_ = times_.ticks[phase_project];
  }
  /// Restarts the clock without charging anything (the time was charged by an inner probe).
  void restart() {
    if (!on_) return;
    start_ = phase_tick();
    inner_ = times_.ticks[phase_project];
  }
  [[nodiscard]] bool on() const { return on_; }

 private:
  PhaseTimes& times_;
  bool on_;
  std::uint64_t start_;
  std::uint64_t inner_;  // ticks[phase_project] at the last mark
};

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
