// cullkit/detail/parallel.hpp: how the library runs work on several threads, as declarations only
// (users never name this). The pool behind them is in worker_pool.hpp, compiled where the cores are
// (see CULLKIT_SEPARATE_CORE in config.hpp): its <thread>, <mutex> and <condition_variable> are the
// heaviest standard headers the library uses.
#pragma once

#include <cstddef>

#include "../config.hpp"
#include "../task_runner.hpp"

namespace cullkit::detail {

/// One task of a parallel job: called once per task index.
using ParallelTask = void (*)(void* job, std::size_t task);

/// Worker count for an option where 0 means "all hardware threads" (hardware_concurrency may
/// report 0 when unknown: then one), capped at `limit` (at least 1).
[[nodiscard]] CULLKIT_CORE_FN unsigned resolve_threads(unsigned requested, std::size_t limit) noexcept;

/// Calls task(job, i) once for every i in [0, count) on the process's one worker pool and returns
/// when all calls have returned; task 0 runs on the calling thread (WorkerPool::run).
CULLKIT_CORE_FN void run_on_pool(std::size_t count, ParallelTask task, void* job);

/// Runs task(job, i) for i in [0, count): through `runner` when it has a dispatch function,
/// otherwise on the shared pool.
CULLKIT_CORE_FN void run_tasks(const TaskRunner& runner, std::size_t count, ParallelTask task, void* job);

/// Blocks the calling thread for about `ms` milliseconds (a progress loop's pause).
CULLKIT_CORE_FN void sleep_milliseconds(unsigned ms);

/// Threads the shared pool has started so far (they live until the process ends).
[[nodiscard]] CULLKIT_CORE_FN std::size_t pool_thread_count();

}  // namespace cullkit::detail

#if CULLKIT_CORE_BODIES
#include "worker_pool.hpp"
#endif
