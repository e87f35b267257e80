// cullkit/detail/mesh_occlusion/row_strips.hpp: the insertion of a frame's occluder patches into the
// coverage grid, strip by strip: on several tasks the grid's rows are cut into strips (as many as
// the grid's height sets, cut where the frame's triangles give them their shares of the work) and
// every patch goes into each strip's rows on their own, so the strips can be inserted on several
// tasks; one thread inserts the whole grid as one strip.
//
// Why a strip can go in alone: every per-cell operation of the grid reads and writes cells of its
// own row only (an edge's crossings per row, counts summed left to right along the row, outline
// marks, depth bounds, freezing, a patch's grid added into the union), so a strip's rows end as the
// whole grid's would after the same operations clamped to them. What a strip decides on its own
// rows are the skips: a triangle whose cells in the strip are all covered is dropped there, and a
// patch none of whose cells in the strip is open is skipped there. Either is inserting fewer
// occluders into the strip (as if the triangle or patch were no occluder), which only covers less,
// and a triangle dropped over covered cells changes nothing in the strip: the outline marks its
// neighbours' edges then keep fall on cells of its box, all covered, which every later operation
// skips; its crossings sum to its own winding, zero outside it along a row. Covered cells never
// change again, so every strip count leaves the same uncovered cells and the same covered cells'
// depths: the one-strip answer (test_mesh_occlusion_threads, fuzz_mesh_occlusion). See
// docs/mesh_occlusion.md, "One cull on several threads".
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "../bits.hpp"
#include "coverage.hpp"
#include "frame.hpp"
#include "gather_on_demand.hpp"
#include "index.hpp"
#include "occluders.hpp"
#include "parallel_frame.hpp"
#include "strip_gather.hpp"

namespace cullkit {
namespace detail {
namespace mesh_occlusion {

/// Strips of a grid `height` rows high on several tasks: one per 32 rows, 1 to 8 (4 for the default
/// 144 rows), never a function of the task count. More strips split the work finer between tasks,
/// but a triangle reaching several strips is set up in each (on one thread, 4 strips cost 3 to 7% of
/// the frame over 1, 6 strips 8 to 15%, `bench_mesh_occlusion --hash`): one thread takes one strip.
inline int strip_count(int height) { return std::max(1, std::min(8, height / 32)); }

/// Makes a task's memory fit `index`, a grid of width x height and patches of up to `largest`
/// gathered triangles, whichever strips the task takes (so a warm context allocates nothing however
/// the strips fall to the tasks); `own_grid`: the task keeps the union's rows in a grid of its own,
/// emptied here.
inline void begin_strip_task(const MeshIndex& index, StripTask& task, int width, int height, std::size_t largest,
                             bool own_grid) {
  const std::size_t triangles = index.corners.size() / 3;
  if (task.member_stamp.size() != triangles || task.done_stamp.size() != triangles) {
    task.member_stamp.assign(triangles, 0);
    task.done_stamp.assign(triangles, 0);
    task.member_value = 0;
    task.done_value = 0;
  }
  task.run.reserve(largest);
  task.patch_grid.reset(width, height);
  if (own_grid) task.grid.reset(width, height);
}

/// True when every depth bound the frame's occluder triangles give is positive: add_depth bounds a
/// triangle's cells from below by the inverse of its largest corner depth, rounded to float, and
/// every corner lies in the level's box (the frustum tree's root), whose largest depth gives a
/// positive float here. Then so is every running bound and frozen depth of the grid.
inline bool depth_bounds_positive(const MeshIndex& index, const View& view) {
  if (index.tree.nodes().empty()) return false;
  const double w_max = project_box(view, index.tree.nodes().front().bounds).w_max;
  return static_cast<float>((1.0 / w_max) * (1.0 - 0x1p-20)) > 0.0f;
}

/// Inserts every patch into the rows of `strip`, in the order `next` gives (below), with the memory
/// of `task`, into `grid` (the union: the frame's grid or the task's own). Per patch, its
/// triangles whose cells reach the strip's rows are its run there; its own grid is seeded from the
/// union over the run's box (a cell the union covers at least as near as the run's nearest point
/// starts covered: the run can change nothing there), the run goes in by depth bands, the patch's
/// grid is added into the union, and the edges the run shares with triangles this strip inserted
/// from earlier patches leave the union's outline. A patch with no run, or none of whose cells is
/// open, is skipped in the strip. Reads `s` only (`grid` may be the frame's, which only this task
/// writes while it runs).
///
/// Why a patch's grid can be added into the union as it is: the patch's grid leaves out the cells it
/// holds as covered (seeded from the union, or covered by the patch alone in an earlier band) when it
/// marks outline edges, so the union may lack such a mark there; a later patch taking that edge out
/// again may then leave the cell's outline counter low, and the cell may count as covered. Seeded
/// cells are covered in the union already and never change again; a cell the patch covers alone is
/// covered by the union too, and its bound holds (the triangles that covered it gave their bounds
/// there before it was left out). So no cell that the union does not cover counts as covered.
///
/// With `direct`, a run whose cells the union has not used yet (`CoverageGrid::untouched` over the
/// run's box: no count, bound, depth or covered bit there, nor in the next cell of each row) goes
/// straight into the union, its bands ending there, and leaves what its own grid added into the
/// union would leave:
/// - seeding its grid would mark no cell (the union covers none there), and each operation of the
///   run stays within those cells, so the run meets the same empty cells in either grid and leaves
///   there the same counts, running bounds, frozen depths and covered bits;
/// - adding its grid into those empty cells gives the union its counts and bounds. A cell the run
///   covered froze at its running bound then, d, at least its last bound b (bounds only fall):
///   where its count is still at least one, the union freezes it at b and takes the nearer d
///   (`patch_layers`); where a later band's crossings lowered its count (crossings do not skip
///   covered cells) the union takes d alone, as d > 0 (`direct` asks for positive bounds). So the
///   union holds d and the covered bit, as the run left them; any other cell has a count below one
///   and no depth both ways;
/// - the edges shared with earlier patches are then taken out of the same union, as before.
/// Without `patch_layers` the union drops the covered cells whose count fell, so `direct` needs them.
///
/// The patches come from `next(q, group, place, count)`: occluder q's sorted triangles group[0,
/// count), at places [place, place + count) of the occluders' regions of `s.triangles` (read for
/// their extents on several strips); false when none is left.
template <class NextPatch>
inline void insert_strip_in_order(const MeshIndex& index, const MeshOcclusionParams& params, const Scratch& s,
                                  Strip& strip, StripTask& task, CoverageGrid& grid, bool direct, NextPatch&& next) {
  const int width = grid.width(), height = grid.height();
  const int orient = s.view.orient;
  grid.set_rows(strip.first_row, strip.last_row);
  if (++task.done_value == 0) {
    std::fill(task.done_stamp.begin(), task.done_stamp.end(), 0);
    task.done_value = 1;
  }
  // The whole grid as one strip (one thread) takes every triangle, with its gathered box, and counts
  // what it inserts directly: nothing to share with other strips.
  const bool whole = strip.first_row == 0 && strip.last_row == height - 1 && s.triangle_extents.empty();
  std::size_t inserted = 0;
  std::uint32_t q = 0, place = 0, count = 0;
  const std::pair<std::uint32_t, std::uint32_t>* group = nullptr;
  while (next(q, group, place, count)) {
    if (++task.member_value == 0) {
      std::fill(task.member_stamp.begin(), task.member_stamp.end(), 0);
      task.member_value = 1;
    }
    task.run.clear();
    double x0 = HUGE_VAL, y0 = HUGE_VAL, x1 = -HUGE_VAL, y1 = -HUGE_VAL, w_min = HUGE_VAL;
    for (std::uint32_t i = place; i < place + count; ++i) {
      const std::uint32_t t = group[i - place].second;
      double bx0, by0, bx1, by1, bw;
      if (whole) {
        const OccluderBox& box = occluder_box(s, t);
        bx0 = box.xmin, by0 = box.ymin, bx1 = box.xmax, by1 = box.ymax, bw = box.wmin;
      } else {
        const TriangleExtent& x = s.triangle_extents[i];
        // The patch's nearest point over all its triangles, as the whole grid takes it: a strip
        // then seeds the cells the whole grid seeds on its rows, and drops what it drops.
        w_min = std::min(w_min, x.w_min);
        if (x.row1 < strip.first_row || x.row0 > strip.last_row) continue;
        bx0 = x.x0, by0 = x.y0, bx1 = x.x1, by1 = x.y1, bw = x.w_min;
      }
      task.run.emplace_back(i, t);
      task.member_stamp[t] = task.member_value;
      x0 = std::min(x0, bx0);
      y0 = std::min(y0, by0);
      x1 = std::max(x1, bx1);
      y1 = std::max(y1, by1);
      w_min = std::min(w_min, bw);
    }
    if (task.run.empty()) continue;
    const CellRect cells = grid.cells_of(x0, y0, x1, y1);
    const float nearest = static_cast<float>(1.0 / w_min);
    const RunMembers members{task.member_stamp, task.member_value};
    const auto* first = task.run.data();
    if (direct && nearest > 0.0f && grid.untouched(cells)) {
      insert_run(index, s, grid, first, first + task.run.size(), members, inserted);
      grid.end_band();
    } else {
      task.patch_grid.reset(width, height);
      task.patch_grid.set_rows(strip.first_row, strip.last_row);
      if (!task.patch_grid.seed_frozen(grid, cells, nearest)) continue;
      insert_run(index, s, task.patch_grid, first, first + task.run.size(), members, inserted);
      grid.absorb(task.patch_grid, params.patch_layers);
    }
    for (const auto& member : task.run) {
      const std::uint32_t t = member.second;
      if (!members.has(t)) continue;  // dropped over covered cells
      if (!whole) strip.inserted[member.first] = 1;
      task.done_stamp[t] = task.done_value;
      // Only the edges whose twin may be in another patch (PatchSet::twin_reach) can be such seams.
      const unsigned elsewhere = (index.patches.twin_reach[t] & twin_elsewhere) >> 3;
      for (int k = 0; k < 3; ++k) {
        if (!((elsewhere >> k) & 1u)) continue;
        const std::uint32_t twin = index.twins[3 * std::size_t(t) + std::size_t(k)];
        if (twin == none || task.done_stamp[twin / 3] != task.done_value || s.triangle_owner[twin / 3] == q) continue;
        double ex0, ey0, ex1, ey1;
        if (!edge_segment(index, s, t, k, ex0, ey0, ex1, ey1)) continue;
        grid.touch_edge(ex1, ey1, ex0, ey0, orient, -1);  // the earlier patch's edge, as its triangle runs
        grid.touch_edge(ex0, ey0, ex1, ey1, orient, -1);  // this patch's
      }
    }
    grid.end_band();
  }
  strip.inserted_count = whole ? inserted : 0;
}

/// One thread: inserts the occluders into the frame's grid as one strip, in the order of a
/// gathering of all of them, gathering each only when its turn may come (next_on_demand): one whose
/// box's cells are all covered near enough by then is never gathered, and goes in nowhere, as
/// insert_strip_in_order would have skipped it. The same grid and the same count of inserted
/// triangles.
inline void insert_on_demand(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const int width = s.grid.width(), height = s.grid.height();
  if (s.strips.empty()) s.strips.resize(1);
  if (s.strip_tasks.empty()) s.strip_tasks.resize(1);
  Strip& strip = s.strips[0];
  strip.first_row = 0;
  strip.last_row = height - 1;
  begin_strip_task(index, s.strip_tasks[0], width, height, index.patches.largest, false);
  const bool direct = params.patch_layers && depth_bounds_positive(index, s.view);
  // Gathering writes `s` while insert_strip_in_order reads it: never the same entries (a gathered
  // occluder's region, slots and bands are not written again this frame).
  insert_strip_in_order(index, params, s, strip, s.strip_tasks[0], s.grid, direct,
                        [&](std::uint32_t& q, const std::pair<std::uint32_t, std::uint32_t>*& group,
                            std::uint32_t& place, std::uint32_t& count) {
                          if (!next_on_demand(index, params, s, q)) return false;
                          place = s.region_first[q];
                          count = s.gathered_count[q];
                          group = s.triangles.data() + place;
                          return true;
                        });
  s.grid.set_rows(0, height - 1);
  s.stats.occluder_triangles += strip.inserted_count;
}

/// What a gathered triangle's setup in a strip costs, in rows of its walks along the grid: the
/// strips are cut on these weights.
inline constexpr std::uint32_t strip_setup_rows = 4;

/// Adds `amount` to the rows [first, last] of the difference array `diff` (a row more than the
/// grid's): unsigned sums wrap, and the running sums come out right.
inline void add_to_rows(std::uint32_t* diff, int first, int last, std::uint32_t amount) {
  diff[first] += amount;
  diff[last + 1] -= amount;
}

/// Estimates each row's insertion work before the strips gather (a triangle weighs its rows and a
/// setup, as a strip walks it) into s.row_work[0, height): the triangles gathered before the strips
/// by their extents; an occluder waiting ungathered, of c triangles, spread over its box's rows as
/// sqrt(c) triangles across all of them (a patch's triangles are about that many rows tall each),
/// with its setups evenly over them. Dropped occluders count too: the estimate only cuts the strips.
inline void estimate_row_work(const MeshIndex& index, Scratch& s, int height) {
  const auto rows = static_cast<std::size_t>(height);
  s.row_work.assign(3 * rows + 2, 0);
  std::uint32_t* open = s.row_work.data() + rows;  // difference arrays, rows + 1 each
  std::uint32_t* setup = open + rows + 1;
  for (const auto& first : s.gathered_first) {
    const std::uint32_t q = first.second, place = s.region_first[q];
    for (std::uint32_t k = 0; k < s.gathered_count[q]; ++k)
      if (const TriangleExtent& e = s.triangle_extents[place + k]; e.row0 <= e.row1) {
        add_to_rows(open, e.row0, e.row1, 1);
        add_to_rows(setup, e.row0, e.row0, strip_setup_rows);
      }
  }
  for (const auto& waiting : s.ungathered) {
    const std::uint32_t q = waiting.second;
    const CellRect& cells = s.drop_cells[q];
    if (cells.empty()) continue;
    const std::uint32_t count = index.patches.patches[s.occluders[q].second].count;
    const auto tall = static_cast<std::uint32_t>(cells.y1 - cells.y0 + 1);
    add_to_rows(open, cells.y0, cells.y1, static_cast<std::uint32_t>(std::lround(std::sqrt(double(count)))));
    add_to_rows(setup, cells.y0, cells.y1, (strip_setup_rows * count + tall - 1) / tall);
  }
  std::uint32_t* work = s.row_work.data();
  std::uint32_t reaching = 0, setups = 0;
  for (std::size_t j = 0; j < rows; ++j) {
    reaching += open[j];
    setups += setup[j];
    work[j] = reaching + setups;
  }
}

/// Strip k's weight among `strips` (cut_strips): from 3 strips on, the first half (rounded up)
/// weigh 2 and the rest 1. The strips are handed out biggest first, so each task starts on a big
/// one, and the small ones left for last even out where the tasks end. The first strips also
/// gather most of the occluders (the first strip to need one gathers it), work the estimate leaves
/// out: with four strips of equal estimates the tasks ended 120-130 us apart on lasdunasarena and
/// 85-95 on sportsCar, with 2:2:1:1 about 80 and 75 (`bench_mesh_occlusion --threads=2`).
inline std::uint64_t strip_weight(int k, int strips) { return strips >= 3 && k >= (strips + 1) / 2 ? 1 : 2; }

/// Cuts the grid's `height` rows into `strips` strips of estimated work (estimate_row_work) in
/// proportion to their weights (strip_weight), each at least one row, into s.strips[0, strips) in
/// row order, with their work in s.strip_work. Where a strip's rows end changes no answer (every row
/// ends as the whole grid's would), only how evenly the tasks share the insertion.
inline void cut_strips(Scratch& s, int height, int strips) {
  const std::uint32_t* work = s.row_work.data();
  std::uint64_t total = 0;
  for (int j = 0; j < height; ++j) total += work[j];
  std::uint64_t weights = 0;
  for (int k = 0; k < strips; ++k) weights += strip_weight(k, strips);
  // Strip k ends at the first row where the work so far reaches the weights of strips 0 to k over
  // all weights, of the total, leaving a row to each strip after it.
  int first = 0, j = 0;
  std::uint64_t done = 0, weight_so_far = 0;
  for (int k = 0; k < strips; ++k) {
    const bool last_strip = k + 1 == strips;
    weight_so_far += strip_weight(k, strips);
    const std::uint64_t goal = total * weight_so_far / weights;
    const int last_allowed = height - (strips - k);
    std::uint64_t strip_work = 0;
    do {
      strip_work += work[j];
      done += work[j];
      ++j;
    } while (j <= last_allowed && (last_strip || done < goal));
    Strip& strip = s.strips[static_cast<std::size_t>(k)];
    strip.first_row = first;
    strip.last_row = j - 1;
    s.strip_work[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(std::min<std::uint64_t>(strip_work, 0xffffffffu));
    first = j;
  }
}

/// Several threads: inserts the chosen occluders into the frame's grid strip by strip of its rows
/// (strip_count), the strips on up to MeshOcclusionParams::threads tasks (through its task_runner),
/// however few objects the frame has; each strip gathers the occluders it needs on demand
/// (strip_gather.hpp: those gathered before the strips, prepare_strip_gathering and
/// gather_first_on_tasks, wait from the start). Counts the triangles inserted (into some strip) into
/// the statistics.
inline void insert_strips_on_tasks(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  const int width = s.grid.width(), height = s.grid.height();
  const int strips = strip_count(height);
  const unsigned tasks = resolve_threads(params.threads, static_cast<std::size_t>(strips));
  const std::size_t places = s.region_first[s.occluders.size()];
  const bool direct = params.patch_layers && depth_bounds_positive(index, s.view);
  if (s.strips.size() < static_cast<std::size_t>(strips)) s.strips.resize(static_cast<std::size_t>(strips));
  s.strip_work.resize(static_cast<std::size_t>(strips));
  estimate_row_work(index, s, height);
  cut_strips(s, height, strips);
  // The strips that cost most are handed out first, so the last ones are short: the order only
  // decides which task takes a strip, never what the strip becomes.
  s.strip_order.resize(static_cast<std::size_t>(strips));
  for (int k = 0; k < strips; ++k) s.strip_order[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(k);
  std::sort(s.strip_order.begin(), s.strip_order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return s.strip_work[a] > s.strip_work[b] || (s.strip_work[a] == s.strip_work[b] && a < b);
  });
  BatchCounter batches(static_cast<std::size_t>(strips), 1);
  const unsigned used = batches.tasks_for(tasks);
  if (s.strip_tasks.size() < used) s.strip_tasks.resize(used);
  run_each_task(params.task_runner, used, [&](std::size_t task) {
    StripTask& own = s.strip_tasks[task];
    begin_strip_task(index, own, width, height, index.patches.largest, task > 0);
    own.waiting.reserve(s.occluders.size());
    own.pending.reserve(s.occluders.size());
    CoverageGrid& grid = task == 0 ? s.grid : own.grid;
    std::size_t first, last;
    while (batches.claim(first, last)) {
      Strip& strip = s.strips[s.strip_order[first]];
      strip.inserted.assign(places, 0);
      StripWalk walk{own.waiting, own.pending};
      begin_strip_walk(s, walk);
      // Gathering writes `s` while insert_strip_in_order reads it: never the same entries (an
      // occluder's region, slots and bands are written once, before any strip reads them).
      insert_strip_in_order(index, params, s, strip, own, grid, direct,
                            [&](std::uint32_t& q, const std::pair<std::uint32_t, std::uint32_t>*& group,
                                std::uint32_t& place, std::uint32_t& count) {
                              if (!next_in_strip(params, index, s, strip, grid, walk, own.unused_clipped, q)) return false;
                              place = s.region_first[q];
                              count = s.gathered_count[q];
                              group = s.triangles.data() + place;
                              return true;
                            });
    }
    // A task with a grid of its own copies its rows into the frame's as soon as it has no strip
    // left, while the others still insert: the strips' rows are disjoint, and the frame's grid's
    // bookkeeping (which rows are used) is taken over after the tasks, on the calling thread.
    if (task > 0) s.grid.copy_rows(own.grid);
  });
  for (unsigned k = 1; k < used; ++k) s.grid.adopt_rows(s.strip_tasks[k].grid);
  s.grid.set_rows(0, height - 1);
  // A triangle counts once, in whichever strips it went in: the strips' flags (0 or 1) ORed eight
  // at a time, then counted.
  std::size_t inserted = 0, i = 0;
  for (; i + 8 <= places; i += 8) {
    std::uint64_t any = 0;
    for (int k = 0; k < strips; ++k) {
      std::uint64_t flags;
      std::memcpy(&flags, s.strips[static_cast<std::size_t>(k)].inserted.data() + i, sizeof flags);
      any |= flags;
    }
    inserted += static_cast<std::size_t>(detail::popcount(any));
  }
  for (; i < places; ++i) {
    std::uint8_t any = 0;
    for (int k = 0; k < strips; ++k) any = static_cast<std::uint8_t>(any | s.strips[static_cast<std::size_t>(k)].inserted[i]);
    inserted += any;
  }
  s.stats.occluder_triangles += inserted;
}

/// Inserts every chosen occluder into the frame's grid, patch by patch (a patch's nearest triangle
/// first decides its turn), each patch alone into a grid of its own in depth bands, then added into
/// the frame's grid: on one thread as one strip (insert_on_demand), on several by strips of rows
/// (insert_strips_on_tasks).
///
/// The frame's grid holds the union of all occluders: an edge that a patch shares with a patch
/// inserted before it is no outline there, so the earlier patch's mark of it and this patch's (its
/// own grid's, now added) are both taken out again, and the seam fuses. The patch's own grid says
/// which cells the patch covers by itself, at the patch's own depth bound: where that is nearer than
/// the union's, the cell takes it (`patch_layers`). A wall standing on a floor that went in before
/// it leaves its own depth, not the floor's, in front of what is behind it.
inline void insert_patches(const MeshIndex& index, const MeshOcclusionParams& params, Scratch& s) {
  if (s.on_demand) insert_on_demand(index, params, s);
  else insert_strips_on_tasks(index, params, s);
}

}  // namespace mesh_occlusion
}  // namespace detail
}  // namespace cullkit
