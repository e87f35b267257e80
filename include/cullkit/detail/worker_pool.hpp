// cullkit/detail/worker_pool.hpp: the library's one pool of worker threads.
//
// Threads are started on first use and then kept, so a per-frame query starts none once warm and
// a dispatch allocates nothing. One pool serves the whole process (WorkerPool::shared()); a
// dispatch that finds it busy (another caller's query, or a task dispatching from inside the pool)
// runs its tasks on the calling thread instead of waiting, so it can never deadlock.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "../config.hpp"
#include "../task_runner.hpp"
#include "parallel.hpp"

#if CULLKIT_HAS_SSE2
#include <emmintrin.h>
#endif

namespace cullkit::detail {

class WorkerPool {
 public:
  using Task = ParallelTask;

  /// The process-wide pool, created on first use and joined at exit.
  [[nodiscard]] static WorkerPool& shared() {
    static WorkerPool pool;
    return pool;
  }

  WorkerPool() = default;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      published_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }

  /// Calls task(job, i) once for every i in [0, count) and returns when all calls have returned.
  /// Task 0 runs on the calling thread; the others are claimed by whichever of the caller and the
  /// pool's threads is free first. Starts threads only while the pool has fewer than count - 1.
  void run(std::size_t count, Task task, void* job) {
    if (count == 0) return;
    std::unique_lock<std::mutex> owner(busy_, std::try_to_lock);
    if (count == 1 || !owner.owns_lock()) {
      for (std::size_t i = 0; i < count; ++i) task(job, i);
      return;
    }
    {
      std::unique_lock<std::mutex> lock(mutex_);
      // A thread still inside the previous dispatch's claim loop must leave it before the claim
      // counter is reset (it would otherwise take a task of this dispatch with the old job).
      idle_.wait(lock, [&] { return active_ == 0; });
      // A new thread joins this dispatch: it starts from the generation before it.
      while (threads_.size() + 1 < count) threads_.emplace_back([this, g = generation_] { serve(g); });
      task_ = task;
      job_ = job;
      count_ = count;
      next_.store(1, std::memory_order_relaxed);
      ++generation_;
      published_.store(generation_, std::memory_order_release);
    }
    wake_.notify_all();
    task(job, 0);
    claim(task, job, count);
    // The other threads' last tasks end a few microseconds apart from this one's in a frame's
    // steps: waiting for them without sleeping saves the wake-up that would follow.
    spin_while_active();
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [&] { return active_ == 0; });
  }

  /// Threads started so far (they are never stopped before the pool is destroyed).
  [[nodiscard]] std::size_t thread_count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return threads_.size();
  }

 private:
  void claim(Task task, void* job, std::size_t count) {
    for (std::size_t i = next_.fetch_add(1, std::memory_order_relaxed); i < count;
         i = next_.fetch_add(1, std::memory_order_relaxed))
      task(job, i);
  }

  // Waits up to `spin_time` for a dispatch after `seen` without sleeping: a frame's parallel steps
  // come a fraction of a millisecond apart, and a thread woken from its condition variable joins
  // a step late or not at all. Returns early once one is published.
  void spin_for_dispatch(std::uint64_t seen) const {
    const auto until = std::chrono::steady_clock::now() + spin_time;
    for (unsigned i = 1;; ++i) {
      if (published_.load(std::memory_order_acquire) != seen) return;
#if CULLKIT_HAS_SSE2
      _mm_pause();
#endif
      if ((i & 63u) == 0 && std::chrono::steady_clock::now() >= until) return;
    }
  }

  // Waits up to `spin_time` without sleeping for the pool's threads to leave the claim loop.
  void spin_while_active() const {
    const auto until = std::chrono::steady_clock::now() + spin_time;
    for (unsigned i = 1;; ++i) {
      if (active_.load(std::memory_order_acquire) == 0) return;
#if CULLKIT_HAS_SSE2
      _mm_pause();
#endif
      if ((i & 63u) == 0 && std::chrono::steady_clock::now() >= until) return;
    }
  }

  void serve(std::uint64_t seen) {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (!stop_ && generation_ == seen) {
        lock.unlock();
        spin_for_dispatch(seen);
        lock.lock();
      }
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      const Task task = task_;
      void* const job = job_;
      const std::size_t count = count_;
      ++active_;
      lock.unlock();
      claim(task, job, count);
      lock.lock();
      if (--active_ == 0) idle_.notify_all();
    }
  }

  std::mutex busy_;  // held by the dispatching caller for the whole dispatch
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::vector<std::thread> threads_;
  Task task_ = nullptr;
  void* job_ = nullptr;
  std::size_t count_ = 0;
  std::atomic<std::size_t> next_{0};
  std::uint64_t generation_ = 0;
  std::atomic<std::uint64_t> published_{0};  // generation_, and a change at stop, readable unlocked
  static constexpr std::chrono::microseconds spin_time{std::chrono::microseconds(200)};
  // Threads inside a claim loop: changed only under mutex_, read without it by a waiting caller.
  std::atomic<std::size_t> active_{0};
  bool stop_ = false;
};

#if CULLKIT_CORE_BODIES
CULLKIT_CORE_FN unsigned resolve_threads(unsigned requested, std::size_t limit) noexcept {
  unsigned n = requested != 0 ? requested : std::thread::hardware_concurrency();
  const std::size_t cap = std::max<std::size_t>(1, limit);
  return static_cast<unsigned>(std::clamp<std::size_t>(n, 1, cap));
}

CULLKIT_CORE_FN void run_on_pool(std::size_t count, ParallelTask task, void* job) {
  WorkerPool::shared().run(count, task, job);
}

CULLKIT_CORE_FN void run_tasks(const TaskRunner& runner, std::size_t count, ParallelTask task, void* job) {
  if (count == 0) return;
  if (runner.dispatch != nullptr && count > 1) {
    runner.dispatch(runner.context, count, task, job);
    return;
  }
  WorkerPool::shared().run(count, task, job);
}

CULLKIT_CORE_FN void sleep_milliseconds(unsigned ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

CULLKIT_CORE_FN std::size_t pool_thread_count() { return WorkerPool::shared().thread_count(); }
#endif

}  // namespace cullkit::detail
