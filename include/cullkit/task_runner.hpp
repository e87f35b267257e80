// cullkit/task_runner.hpp: TaskRunner, the hook through which a query hands its parallel work to
// the caller's own job system instead of cullkit's worker pool.
#pragma once

#include <cstddef>

namespace cullkit {

/// A caller's job system, seen by cullkit as one function. A query that splits its work into
/// `task_count` tasks calls `dispatch(context, task_count, run, job)`; `dispatch` must call
/// `run(job, i)` exactly once for every i in [0, task_count), on any threads, in any order, and
/// return only when every call has returned. Several calls may run at once (each task has its own
/// scratch); running them one after the other on the calling thread is correct too: the result
/// never depends on how the tasks are spread.
///
/// The tasks take their work from a shared counter, so a task that starts late finds little or
/// nothing left: handing them to busy workers costs little. `run` does not throw and does not
/// allocate once the query's context is warm. The default (`dispatch == nullptr`) uses cullkit's
/// own persistent worker pool (detail::WorkerPool), whose threads are started once, on first use;
/// after each dispatch a pool thread spins for up to 200 us before it sleeps, so the next parallel
/// step of the same query finds it awake (give your own job system to keep those cores free).
struct TaskRunner {
  /// The job system's entry point, or nullptr for cullkit's worker pool.
  void (*dispatch)(void* context, std::size_t task_count, void (*run)(void* job, std::size_t task),
                   void* job) = nullptr;
  /// Passed to `dispatch` unchanged (the job system's own state).
  void* context = nullptr;
};

}  // namespace cullkit
