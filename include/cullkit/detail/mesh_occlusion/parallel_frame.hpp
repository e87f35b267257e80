// cullkit/detail/mesh_occlusion/parallel_frame.hpp: the parts of a frame of MeshOcclusionCuller::cull
// that run on several tasks (MeshOcclusionParams::threads), through the caller's TaskRunner or the
// library's pool: the projection of the objects' boxes (with the patch boxes the occluder choice
// reads), the occluder candidates, the projection of the occluders' corners, the gathering of their
// triangles, and the object tests against the finished grid. The occluder insertion runs on tasks
// strip by strip of the grid's rows (row_strips.hpp).
//
// Why the answer cannot depend on the tasks: each object's box, each patch's box, each candidate,
// each corner and each object's test is a function of the frame's view and finished grid alone,
// computed by the same code in every task; a task writes only the slots of the objects it took and
// its own caches; what tasks list (candidates, gathered occluders) is merged or joined in an order
// that does not depend on which task listed what.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../config.hpp"
#include "../../geometry/aabb.hpp"
#include "../../task_runner.hpp"
#include "../parallel.hpp"
#include "box_test.hpp"
#include "coverage.hpp"
#include "frame.hpp"
#include "index.hpp"
#include "object_tests.hpp"
#include "occluders.hpp"
#include "strip_gather.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// Objects per batch that a task takes at a time. A frame has a few hundred objects in the frustum,
/// and an occluder's patch boxes cost many times its own box: batches of 32 give each task several,
/// where a batch of 256 left most of the step on one task. An object test varies from one rectangle
/// to hundreds of triangles.
inline constexpr std::size_t box_batch = 32;
inline constexpr std::size_t test_batch = 16;
inline constexpr std::size_t corner_batch = 512;

/// Tasks for a frame of `objects` objects in the frustum: MeshOcclusionParams::threads resolved,
/// and no more than there are batches of object tests.
inline unsigned frame_tasks(const MeshOcclusionParams& params, std::size_t objects) {
  if (params.threads == 1) return 1;
  return resolve_threads(params.threads, (objects + test_batch - 1) / test_batch);
}

/// Hands out [0, count) in batches of `batch` to whichever task asks first.
class BatchCounter {
 public:
  BatchCounter(std::size_t count, std::size_t batch) : count_(count), batch_(batch) {}
  /// `tasks`, or fewer when there are fewer batches (a task with nothing to take would only cost its
  /// hand-out); at least 1.
  [[nodiscard]] unsigned tasks_for(unsigned tasks) const {
    return static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(tasks, (count_ + batch_ - 1) / batch_)));
  }
  /// The next batch [first, last); false when none is left.
  bool claim(std::size_t& first, std::size_t& last) {
    const std::size_t b = next_.fetch_add(1, std::memory_order_relaxed);
    if (b >= (count_ + batch_ - 1) / batch_) return false;
    first = b * batch_;
    last = std::min(count_, first + batch_);
    return true;
  }

 private:
  std::size_t count_, batch_;
  std::atomic<std::size_t> next_{0};
};

/// Calls run(task) once for every task in [0, tasks) through `runner` (on any threads, in any order);
/// one task runs on the calling thread directly.
template <class Run>
void run_each_task(const TaskRunner& runner, unsigned tasks, const Run& run) {
  if (tasks == 1) {
    run(std::size_t{0});
    return;
  }
  run_tasks(runner, tasks, [](void* job, std::size_t task) { (*static_cast<const Run*>(job))(task); },
            const_cast<void*>(static_cast<const void*>(&run)));
}

/// Makes a task's caches fit `index` and starts a new frame in them. Allocates only when the
/// index is new to this task: then about 40 bytes per welded vertex and 60 per patch.
inline void begin_task_frame(const MeshIndex& index, TaskScratch& t) {
  if (t.owner != &index || t.vertex_stamp.size() != index.positions.size() ||
      t.patch_stamp.size() != index.patches.patches.size()) {
    t.owner = &index;
    t.vertex_stamp.assign(index.positions.size(), 0);
    t.projected.resize(index.positions.size());
    t.patch_stamp.assign(index.patches.patches.size(), 0);
    t.patch_boxes.resize(index.patches.patches.size());
    t.frame = 0;
  }
  if (++t.frame == 0) {
    std::fill(t.vertex_stamp.begin(), t.vertex_stamp.end(), 0);
    std::fill(t.patch_stamp.begin(), t.patch_stamp.end(), 0);
    t.frame = 1;
  }
}

/// What an object test reads of a finished frame, with a task's own caches for what the frame has
/// not projected: the frame is only read, so several tasks test objects at once. The members carry
/// the names object_tests.hpp reads of a Scratch.
struct TaskFrame {
  const Scratch& frame;
  TaskScratch& own;
  const CoverageGrid& grid;
  const View& view;
  const Frustum& frustum;
  const std::vector<std::uint32_t>& in_frustum;
  const std::vector<BoxView>& boxes;
};

/// project_vertex for a task: the frame's projection when it has one, else the task's own (the
/// same function of the same view: the same value).
inline const Projected& project_vertex(const MeshIndex& index, TaskFrame& f, std::uint32_t v) {
  const Scratch& s = f.frame;
  if (s.vertex_stamp[v] == s.frame) return s.projected[s.vertex_slot[v]];
  TaskScratch& t = f.own;
  if (t.vertex_stamp[v] != t.frame) {
    t.vertex_stamp[v] = t.frame;
    const glm::vec3& p = index.positions[v];
    t.projected[v] = s.view.project(p.x, p.y, p.z);
  }
  return t.projected[v];
}

/// patch_box for a task, as project_vertex above.
inline const BoxView& patch_box(const MeshIndex& index, TaskFrame& f, std::uint32_t patch) {
  const Scratch& s = f.frame;
  if (s.patch_stamp[patch] == s.frame) return s.patch_boxes[patch];
  TaskScratch& t = f.own;
  if (t.patch_stamp[patch] != t.frame) {
    t.patch_stamp[patch] = t.frame;
    t.patch_boxes[patch] = project_box(s.view, index.patches.patches[patch].box);
  }
  return t.patch_boxes[patch];
}

inline bool box_hidden(const TaskFrame& f, const BoxView& b, const Aabb& box) { return box_hidden(f.frame, b, box); }
inline const Scratch& frame_scratch(const TaskFrame& f) { return f.frame; }

/// s.boxes[i] for every object in the frustum, on `tasks` tasks; and, for the objects that may be
/// occluders (those object_candidates measures patch by patch), their patches' boxes in the frame's
/// cache (only those inside the frustum: choose_occluders_on_tasks reads that from the cache).
/// Each object's patches are its own: no two tasks write the same slot. The first task to start
/// also empties the frame's grid (already of the parameters' size: its size is all the others read
/// of it). Returns how far the objects reach (measure_reach), each task measuring the objects it took.
inline ObjectReach project_boxes_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s,
                                          unsigned tasks) {
  const double min_cells = min_occluder_cells(params, s.grid);
  const PatchSet& ps = index.patches;
  BatchCounter batches(s.in_frustum.size(), box_batch);
  const unsigned used = batches.tasks_for(tasks);
  if (s.tasks.size() < used) s.tasks.resize(used);
  for (unsigned k = 0; k < used; ++k) s.tasks[k].reach = ObjectReach{};
  std::atomic<bool> grid_taken{false};
  run_each_task(params.task_runner, used, [&](std::size_t task) {
    if (!grid_taken.exchange(true, std::memory_order_relaxed)) s.grid.reset(params.grid_width, params.grid_height);
    ObjectReach& reach = s.tasks[task].reach;
    std::size_t first, last;
    while (batches.claim(first, last))
      for (std::size_t i = first; i < last; ++i) {
        const std::uint32_t o = s.in_frustum[i];
        s.boxes[i] = project_box(s.view, index.bounds[o]);
        measure_reach(index, s, i, reach);
        const std::uint32_t p0 = ps.object_first[o], p1 = ps.object_first[o + 1];
        if (p1 - p0 < 2 || !index.objects[o].occludes || screen_cells(s.boxes[i], s.grid) < min_cells) continue;
        for (std::uint32_t p = p0; p < p1; ++p)
          if (s.frustum.classify(ps.patches[p].box) != Containment::outside) patch_box(index, s, p);
      }
  });
  ObjectReach reach;
  for (unsigned k = 0; k < used; ++k) reach.add(s.tasks[k].reach);
  return reach;
}

/// Objects per batch that a task measures as occluders at a time: few objects are occluders, and
/// each costs a look at every patch, so small batches share them evenly.
inline constexpr std::size_t choice_batch = 16;

/// choose_occluders on `tasks` tasks, with the same result, after project_boxes_on_tasks (its
/// `reach`): each task lists the candidate patches of the objects it takes and sorts its list; the
/// lists are merged in the candidates' total order (bigger_candidate), which is the one sorted list
/// of them all, and the occluders taken from it on the calling thread. A patch inside the frustum is
/// one whose box the projection step put in the frame's cache.
inline void choose_occluders_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s, unsigned tasks,
                                      const ObjectReach& reach) {
  BatchCounter batches(s.in_frustum.size(), choice_batch);
  const unsigned used = batches.tasks_for(tasks);
  if (s.tasks.size() < used) s.tasks.resize(used);
  const auto patch_view = [&s](std::uint32_t p) -> const BoxView* {
    return s.patch_stamp[p] == s.frame ? &s.patch_boxes[p] : nullptr;
  };
  run_each_task(params.task_runner, used, [&](std::size_t task) {
    std::vector<std::pair<float, std::uint32_t>>& list = s.tasks[task].candidates;
    list.clear();
    std::size_t first, last;
    while (batches.claim(first, last))
      for (std::size_t i = first; i < last; ++i) object_candidates(index, params, s, i, reach, patch_view, list);
    std::sort(list.begin(), list.end(), bigger_candidate);
  });
  s.candidates.clear();
  for (unsigned k = 0; k < used; ++k) {
    const auto& list = s.tasks[k].candidates;
    s.candidate_merge.resize(s.candidates.size() + list.size());
    std::merge(s.candidates.begin(), s.candidates.end(), list.begin(), list.end(), s.candidate_merge.begin(), bigger_candidate);
    s.candidates.swap(s.candidate_merge);
  }
  // However the objects fall to the tasks next time, no list outgrows what the frame held (the
  // merge's two buffers trade places, each holding a first task's list one time, all the next).
  for (unsigned k = 0; k < used; ++k) s.tasks[k].candidates.reserve(s.candidates.size());
  s.candidate_merge.reserve(s.candidates.size());
  take_occluders(index, params, s);
}

/// Gives the corners of the chosen occluders' patches (PatchSet::vertices) their slots in the
/// frame's cache from `first_slot` on, in the order the occluders list them, each once, into
/// `s.corner_list`'s places; after each occluder, `listed` tells how many have one (release: the
/// places and slots before it are written). Returns the count.
inline std::size_t list_occluder_corners(const MeshIndex& index, Scratch& s, std::size_t first_slot,
                                         std::atomic<std::size_t>* listed) {
  const PatchSet& ps = index.patches;
  std::size_t count = 0;
  for (const auto& occluder : s.occluders) {
    for (std::uint32_t i = ps.vertex_first[occluder.second]; i < ps.vertex_first[occluder.second + 1]; ++i) {
      const std::uint32_t v = ps.vertices[i];
      if (s.vertex_stamp[v] == s.frame) continue;
      s.vertex_stamp[v] = s.frame;
      s.vertex_slot[v] = static_cast<std::uint32_t>(first_slot + count);
      s.corner_list[count++] = v;
    }
    if (listed != nullptr) listed->store(count, std::memory_order_release);
  }
  return count;
}

/// The corners of the chosen occluders' triangles (and of the whole triangles their cut parts come
/// from, PatchSet::vertices) projected on `tasks` tasks (one: on the calling thread) into the
/// frame's cache, so that gathering finds them there: the slots are given out in the order the
/// occluders list them (list_occluder_corners), and each is filled by one task with what
/// project_vertex would put there (the same view, its final clipping level included). Projecting
/// them in one pass, from each patch's list of its corners, costs less than looking each triangle's
/// three up as it is gathered. On several tasks the first task to start makes room for them and
/// gives out the slots while the others project the corners listed so far (it joins them when
/// done): a task waits only while that task runs. `beside()` runs once meanwhile, on the second task
/// to start (on one task, after the corners): work that reads and writes nothing the corners do,
/// which would otherwise leave the other tasks idle while the first makes room and lists (making
/// room alone, about 10,000 slots on lasdunasarena, took 20 us). Call after choose_occluders.
template <class Beside>
inline void project_occluder_corners_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s,
                                              unsigned tasks, const Beside& beside) {
  const PatchSet& ps = index.patches;
  const std::size_t first_slot = s.projected.size();
  std::size_t places = 0;  // every corner each occluder lists: room for the ones given slots
  for (const auto& occluder : s.occluders) places += ps.vertex_first[occluder.second + 1] - ps.vertex_first[occluder.second];
  const auto make_room = [&] {
    s.corner_list.resize(places);
    s.projected.resize(first_slot + places);
  };
  const auto project = [&](std::size_t first, std::size_t last) {
    for (std::size_t j = first; j < last; ++j) {
      const glm::vec3& p = index.positions[s.corner_list[j]];
      s.projected[first_slot + j] = s.view.project(p.x, p.y, p.z);
    }
  };
  const unsigned used = BatchCounter(places, corner_batch).tasks_for(tasks);
  std::size_t count = 0;
  if (used == 1) {
    make_room();
    count = list_occluder_corners(index, s, first_slot, nullptr);
    project(0, count);
    beside();
  } else {
    std::atomic<std::size_t> listed{0}, next{0};
    std::atomic<unsigned> roles{0};
    std::atomic<bool> all_listed{false};
    run_each_task(params.task_runner, used, [&](std::size_t) {
      const unsigned role = roles.fetch_add(1, std::memory_order_relaxed);
      if (role == 0) {
        make_room();  // before the first release of `listed`: no task reads the room earlier
        list_occluder_corners(index, s, first_slot, &listed);
        all_listed.store(true, std::memory_order_release);
      } else if (role == 1) {
        beside();
      }
      // Claims up to a batch of the corners listed so far; once all are listed and claimed, done.
      std::size_t first = next.load(std::memory_order_relaxed);
      for (;;) {
        const bool over = all_listed.load(std::memory_order_acquire);
        const std::size_t ready = listed.load(std::memory_order_acquire);
        if (first >= ready) {
          if (over) return;
          first = next.load(std::memory_order_relaxed);
          continue;
        }
        const std::size_t last = std::min(ready, first + corner_batch);
        if (!next.compare_exchange_weak(first, last, std::memory_order_relaxed)) continue;
        project(first, last);
        first = next.load(std::memory_order_relaxed);
      }
    });
    count = listed.load(std::memory_order_relaxed);
  }
  s.corner_list.resize(count);
  s.projected.resize(first_slot + count);
}

/// Occluders per batch that a task gathers at a time (patches of up to a few hundred triangles).
inline constexpr std::size_t gather_batch = 4;

/// The occluders gathered before the strips (`s.gather_first`, prepare_strip_gathering) on `tasks`
/// tasks: those whose patches share no triangle with another patch are gathered on the tasks, each
/// into its own region of the frame's arrays (gather_patch writes nothing else of the frame but the
/// slots of its own triangles), the polygons of the triangles a task clips into the task's list, and
/// each task then sorts the occluders it took (order_gathered: keys, depth bands, extents); those
/// whose patches share triangles (objects that overlap) are gathered and sorted on the calling thread
/// in order, so a triangle goes in with the first occluder that keeps it, as on one thread. Each
/// occluder's triangles end sorted by key with ties in the patch's order, as one sort of them all
/// leaves them. Then lists them for the strips (list_gathered_first).
inline void gather_first_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s, unsigned tasks) {
  const PatchSet& ps = index.patches;
  const std::size_t n = s.occluders.size();
  const std::size_t total = s.region_first[n];
  BatchCounter batches(n, gather_batch);
  const unsigned used = batches.tasks_for(tasks);
  if (s.tasks.size() < used) s.tasks.resize(used);
  for (unsigned k = 0; k < used; ++k) {
    // Room for any share of the frame, however the occluders fall to the tasks.
    TaskScratch& own = s.tasks[k];
    own.clipped.clear();
    own.clipped_triangles.clear();
    own.gathered.clear();
    own.gathered.reserve(n);
    own.items.reserve(total);
  }
  run_each_task(params.task_runner, used, [&](std::size_t task) {
    TaskScratch& own = s.tasks[task];
    std::size_t first, last;
    while (batches.claim(first, last))
      for (std::size_t q = first; q < last; ++q)
        if (s.gather_first[q] && !ps.shares_triangles[s.occluders[q].second]) {
          s.gathered_count[q] = gather_patch(index, s, q, own.clipped, &own.clipped_triangles, params.min_occluder_width_cells);
          own.gathered.push_back(static_cast<std::uint32_t>(q));
        }
    order_gathered(params, s, own.gathered.data(), own.gathered.size(), own.items, own.sort_buffer);
  });
  for (unsigned k = 0; k < used; ++k) {
    const TaskScratch& own = s.tasks[k];
    for (std::size_t j = 0; j < own.clipped.size(); ++j) {
      s.clip_slot[own.clipped_triangles[j]] = static_cast<std::uint32_t>(s.clipped.size());
      s.clipped.push_back(own.clipped[j]);
    }
  }
  TaskScratch& serial = s.tasks[0];  // the tasks are done: its lists are free
  serial.gathered.clear();
  for (std::size_t q = 0; q < n; ++q)
    if (ps.shares_triangles[s.occluders[q].second]) {
      s.gathered_count[q] = gather_patch(index, s, q, s.clipped, nullptr, params.min_occluder_width_cells);
      serial.gathered.push_back(static_cast<std::uint32_t>(q));
    }
  if (!serial.gathered.empty())
    order_gathered(params, s, serial.gathered.data(), serial.gathered.size(), serial.items, serial.sort_buffer);
  // However the occluders fall to the tasks next time, no task's list outgrows what the frame held.
  for (unsigned k = 0; k < used; ++k) {
    s.tasks[k].clipped.reserve(s.clipped.size());
    s.tasks[k].clipped_triangles.reserve(s.clipped.size());
    s.tasks[k].sort_buffer.reserve(total);
  }
  list_gathered_first(s);
}

/// The object tests against the finished frame on `tasks` tasks: appends the objects not hidden
/// to `out` in the order of `in_frustum`, as the tests one after the other do, and returns how
/// many were hidden. Allocates only while the context grows (task memory, answer slots).
inline std::size_t test_objects_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s,
                                         unsigned tasks, std::vector<std::uint32_t>& out) {
  const std::size_t n = s.in_frustum.size();
  s.hidden.resize(n);
  if (s.tasks.size() < tasks) s.tasks.resize(tasks);
  BatchCounter batches(n, test_batch);
  run_each_task(params.task_runner, batches.tasks_for(tasks), [&](std::size_t task) {
    TaskScratch& own = s.tasks[task];
    begin_task_frame(index, own);
    TaskFrame f{s, own, s.grid, s.view, s.frustum, s.in_frustum, s.boxes};
    std::size_t first, last;
    while (batches.claim(first, last))
      for (std::size_t i = first; i < last; ++i) s.hidden[i] = object_hidden(index, params, f, i) ? 1 : 0;
  });
  std::size_t hidden = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (s.hidden[i]) ++hidden;
    else out.push_back(s.in_frustum[i]);
  }
  return hidden;
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
