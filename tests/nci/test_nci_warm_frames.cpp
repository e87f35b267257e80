// NormalClassIndex::select_visible on a per-frame path: once its NciContext is warm a frame
// allocates nothing and starts no thread (global operator new is replaced here to count), the
// default `threads = 0` uses as many workers as hardware threads, and a caller's job system
// (NciParams::task_runner) receives the tasks and gives the same answer as the library's pool, a
// single thread, or tasks run in reverse order on the calling thread. Warm frames are checked on a
// generated city and on a small forest (meshes of unshared triangles keep further per-worker lists).
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <new>
#include <thread>
#include <vector>

#include "check.hpp"
#include "count_allocations.hpp"
#include "nci_test_util.hpp"
#include "nci_index.hpp"


using namespace cullkit;
using cullkit::support::Scene;

namespace {

struct Answer {
  VisibleSet set;
  NciPixels pixels;
};

bool same(const Answer& a, const Answer& b) {
  return a.set.triangles == b.set.triangles && a.set.triangles_tested == b.set.triangles_tested &&
         a.pixels.triangle == b.pixels.triangle && a.pixels.depth == b.pixels.depth;
}

// A caller's job system: persistent threads that take tasks from a queue of one job at a time.
class JobSystem {
 public:
  explicit JobSystem(unsigned threads) {
    for (unsigned i = 0; i < threads; ++i) threads_.emplace_back([this] { serve(); });
  }
  ~JobSystem() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }
  static void dispatch(void* self, std::size_t count, void (*run)(void*, std::size_t), void* job) {
    auto& js = *static_cast<JobSystem*>(self);
    ++js.dispatches;
    js.last_count = count;
    {
      std::lock_guard<std::mutex> lock(js.mutex_);
      js.run_ = run;
      js.job_ = job;
      js.next_ = 0;
      js.count_ = count;
      js.done_ = 0;
    }
    js.wake_.notify_all();
    std::unique_lock<std::mutex> lock(js.mutex_);
    js.finished_.wait(lock, [&] { return js.done_ == js.count_; });
    js.count_ = 0;
  }
  std::size_t dispatches = 0, last_count = 0;
  std::atomic<std::size_t> runs{0};

 private:
  void serve() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || next_ < count_; });
      if (stop_) return;
      const std::size_t i = next_++;
      lock.unlock();
      run_(job_, i);
      ++runs;
      lock.lock();
      if (++done_ == count_) finished_.notify_all();
    }
  }
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  void (*run_)(void*, std::size_t) = nullptr;
  void* job_ = nullptr;
  std::size_t next_ = 0, count_ = 0, done_ = 0;
  bool stop_ = false;
};

// Runs every task on the calling thread, last first, and records which ran.
struct Reverse {
  std::vector<int> ran;
  static void dispatch(void* self, std::size_t count, void (*run)(void*, std::size_t), void* job) {
    auto& r = *static_cast<Reverse*>(self);
    r.ran.assign(count, 0);
    for (std::size_t i = count; i-- > 0;) {
      run(job, i);
      ++r.ran[i];
    }
  }
};

Answer select(const nci_test::TestIndex<glm::vec3>& index, const Camera& cam) {
  Answer a;
  NciContext ctx;
  index.select_visible(cam, ctx, a.set, &a.pixels);
  return a;
}

void test_warm_frames_allocate_nothing(const Scene& city, const std::vector<Camera>& cams) {
  for (unsigned threads : {0u, 1u, 3u}) {
    NciParams params;
    params.threads = threads;
    const nci_test::TestIndex<glm::vec3> index(city.mesh(), params);
    NciContext ctx;
    VisibleSet set;
    NciPixels pixels;
    // The counter sees the cold frame's allocations (buffers growing): it can fail.
    const long long before_cold = cullkit_test::allocations().load();
    index.select_visible(cams[0], ctx, set, &pixels);
    CHECK_MSG(cullkit_test::allocations().load() > before_cold, "threads=%u: the cold frame allocated nothing?", threads);
    for (const Camera& cam : cams) index.select_visible(cam, ctx, set, &pixels);  // every view once
    const std::size_t pool_threads = detail::pool_thread_count();
    const long long before = cullkit_test::allocations().load();
    std::size_t selected = 0;
    for (int frame = 0; frame < 20; ++frame) {
      index.select_visible(cams[static_cast<std::size_t>(frame) % cams.size()], ctx, set, &pixels);
      selected += set.triangles.size();
    }
    const long long warm = cullkit_test::allocations().load() - before;
    CHECK_MSG(warm == 0, "threads=%u: 20 warm frames allocated %lld times", threads, warm);
    CHECK_MSG(detail::pool_thread_count() == pool_threads, "threads=%u: warm frames started threads",
              threads);
    CHECK(selected > 0);
    // A fresh context per frame does allocate: the count above is not blind to the frame's work.
    const long long before_fresh = cullkit_test::allocations().load();
    (void)select(index, cams[1]);
    CHECK(cullkit_test::allocations().load() - before_fresh > 0);
  }
  // The pool holds at most the largest worker count asked for minus the caller.
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  CHECK(detail::pool_thread_count() + 1 <= std::max(3u, hw));
}

void test_task_runner(const Scene& city, const std::vector<Camera>& cams) {
  NciParams serial;
  serial.threads = 1;
  const nci_test::TestIndex<glm::vec3> reference(city.mesh(), serial);
  for (unsigned threads : {0u, 2u, 5u}) {
    JobSystem jobs(3);
    NciParams params;
    params.threads = threads;
    params.task_runner = TaskRunner{&JobSystem::dispatch, &jobs};
    const nci_test::TestIndex<glm::vec3> index(city.mesh(), params);
    // The build's tasks go to the job system too (build_threads 0: every hardware thread).
    if (std::thread::hardware_concurrency() > 1)
      CHECK_MSG(jobs.dispatches > 0, "threads=%u: the build did not use the task runner", threads);
    const std::size_t build_runs = jobs.runs.load();
    Reverse reverse;
    NciParams reversed = params;
    reversed.task_runner = TaskRunner{&Reverse::dispatch, &reverse};
    const nci_test::TestIndex<glm::vec3> reverse_index(city.mesh(), reversed);
    const unsigned want = threads != 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
    int disagree = 0;
    for (const Camera& cam : cams) {
      const std::size_t dispatches = jobs.dispatches;
      const Answer one = select(reference, cam);
      const Answer job = select(index, cam);
      const Answer rev = select(reverse_index, cam);
      disagree += !same(one, job) + !same(one, rev);
      if (want > 1) {
        CHECK_MSG(jobs.dispatches == dispatches + 1, "threads=%u: one dispatch per frame", threads);
        CHECK_MSG(jobs.last_count == want, "threads=%u: %zu tasks, want %u", threads, jobs.last_count, want);
        CHECK(reverse.ran == std::vector<int>(want, 1));
      } else {
        CHECK_MSG(jobs.dispatches == dispatches, "one worker runs on the calling thread");
      }
      CHECK(!one.set.triangles.empty());
    }
    CHECK_MSG(disagree == 0, "threads=%u: %d answers differ from one thread", threads, disagree);
    if (want > 1) CHECK(jobs.runs.load() - build_runs == want * cams.size());
  }
}

// Two callers at once on one index: the pool serves one, the other runs its tasks itself.
void test_concurrent_callers(const Scene& city, const std::vector<Camera>& cams) {
  NciParams params;
  params.threads = 2;
  const nci_test::TestIndex<glm::vec3> index(city.mesh(), params);
  std::vector<Answer> expect;
  for (const Camera& cam : cams) expect.push_back(select(index, cam));
  std::atomic<int> disagree{0};
  auto caller = [&](std::size_t first) {
    NciContext ctx;
    for (int round = 0; round < 4; ++round)
      for (std::size_t k = 0; k < cams.size(); ++k) {
        const std::size_t c = (first + k) % cams.size();
        Answer a;
        index.select_visible(cams[c], ctx, a.set, &a.pixels);
        if (!same(a, expect[c])) ++disagree;
      }
  };
  std::thread other(caller, 1);
  caller(0);
  other.join();
  CHECK_MSG(disagree.load() == 0, "%d concurrent answers differ", disagree.load());
}

}  // namespace

int main() {
  const Scene city = support::make_city(1, 8);
  std::vector<Camera> cams = nci_test::cameras_for(city.bounds, 5, 256, 192, 9001);
  test_warm_frames_allocate_nothing(city, cams);
  test_task_runner(city, cams);
  test_concurrent_callers(city, cams);
  // A small forest: unshared leaf triangles (per-slot corners), whose walk keeps its own lists of
  // the triangles met per slice; they too grow to what any worker needed.
  const Scene forest = support::make_foliage(1, 4, 300);
  test_warm_frames_allocate_nothing(forest, nci_test::cameras_for(forest.bounds, 5, 256, 192, 9002));
  return cullkit_test::report("test_nci_warm_frames");
}
