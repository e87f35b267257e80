// cullkit/detail/abt/build.hpp: the AdaptiveBinaryTree builder (users never name this).
//
// Three named steps fill the tree's flat arrays:
//  1. `abt_build_node` splits a range of build items recursively (scores from split.hpp,
//     then an in-place partition by centroid), appending child pairs to a raw node array;
//  2. `abt_build_raw` runs step 1 over the whole input, serially or on the shared WorkerPool (top
//     levels on the calling thread, then each deferred subtree into its own array, stitched);
//  3. `abt_relayout` renumbers the raw nodes in the canonical pre-order layout, so the result is
//     identical for every thread count and for every order in which subtrees were (re)built.
// The same steps rebuild a subtree in place during a repairing refit.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <mutex>
#include <vector>

#include "../../abt_params.hpp"
#include "../../geometry/aabb.hpp"
#include "../../geometry/sphere.hpp"
#include "split.hpp"
#include "../parallel.hpp"

namespace cullkit::detail {

/// A subtree deferred by the top-level pass of a parallel build.
struct AbtBuildTask {
  std::uint32_t node;  // index in the top-level raw array (a placeholder until stitched)
  std::uint32_t begin, end, depth;
  Aabb box, centroids;
};

/// Everything a build step reads besides the items' own data.
struct AbtBuildContext {
  AbtBuildItem* items = nullptr;
  AbtSplitConfig cfg{};
  std::uint32_t leaf_size = 16;
  std::uint32_t max_depth = 48;
  std::uint32_t grain = 0;  // > 0: defer subtrees below this size as tasks (top-level pass)
  std::vector<AbtBuildTask>* tasks = nullptr;
  TaskRunner runner{};  // where the deferred subtrees are built (AbtParams::task_runner)
  // progress
  const std::function<void(float)>* progress = nullptr;
  std::atomic<std::uint32_t>* done = nullptr;
  std::mutex* progress_mutex = nullptr;
  float* progress_last = nullptr;
  std::uint32_t total = 0;
};

/// The split configuration a set of parameters asks for (bad weights are turned off).
[[nodiscard]] inline AbtSplitConfig abt_split_config(const AbtParams& params) noexcept {
  AbtSplitConfig cfg{};
  cfg.weights[0] = params.weight_axis;
  cfg.weights[1] = params.weight_volume;
  cfg.weights[2] = params.weight_count;
  cfg.weights[3] = params.weight_straddle;
  for (float& w : cfg.weights) w = std::isfinite(w) && w > 0.0f ? w : 0.0f;
  cfg.candidates = std::clamp<std::uint32_t>(params.candidate_count, 1u, 1024u);
  cfg.sampling = params.candidates == AbtCandidates::sampling;
  cfg.seed = params.seed;
  cfg.sample_limit = params.score_sample_limit;
  return cfg;
}

/// Appends the nodes of `sub` (a raw array whose root is sub[0]) to `raw`, its root replacing
/// `raw[at]`; child links are shifted accordingly.
CULLKIT_CORE_FN void abt_stitch(std::vector<AbtNode>& raw, std::uint32_t at, const std::vector<AbtNode>& sub);

/// Builds a raw node array (root at 0) over items [begin, end), the root at `depth`. `threads`
/// follows AbtParams::threads (0: all hardware threads, 1: the calling thread only); with more
/// than one and enough items, subtrees below `grain` items are deferred as tasks and built on
/// `ctx.runner` (the caller's job system, or the shared WorkerPool). Split choices depend only on a node's own items and key, and each task
/// writes its own array, stitched in task order, so the tree is the same for every thread count.
CULLKIT_CORE_FN std::vector<AbtNode> abt_build_raw(AbtBuildContext ctx, std::uint32_t begin, std::uint32_t end,
                                                   std::uint32_t depth, unsigned threads, std::uint32_t grain);

/// Canonical layout: pre-order, each inner node's children allocated as a pair when the node is
/// visited, left subtree before right. Nodes of `raw` unreachable from raw[0] are dropped.
/// Fills `nodes`, `from` (new index -> raw index) and the shape statistics of `stats`.
CULLKIT_CORE_FN void abt_relayout(const std::vector<AbtNode>& raw, std::vector<AbtNode>& nodes,
                                  std::vector<std::uint32_t>& from, AbtStats& stats);

// The definitions: compiled where the cores are (CULLKIT_SEPARATE_CORE, config.hpp).
#if CULLKIT_CORE_BODIES
/// Bounds of items [begin, end) and of their centroids.
inline void abt_range_bounds(const AbtBuildItem* items, std::uint32_t begin, std::uint32_t end, Aabb& box,
                             Aabb& centroids) noexcept {
  box = Aabb::empty();
  centroids = Aabb::empty();
  for (std::uint32_t i = begin; i < end; ++i) {
    box = merge(box, items[i].box);
    centroids = merge(centroids, items[i].centroid);
  }
}

inline void abt_report_leaf(const AbtBuildContext& ctx, std::uint32_t count) {
  if (ctx.progress == nullptr) return;
  const std::uint32_t before = ctx.done->fetch_add(count);
  const std::uint32_t step = std::max<std::uint32_t>(1u, ctx.total / 50u);
  if ((before + count) / step == before / step) return;
  std::lock_guard<std::mutex> lock(*ctx.progress_mutex);
  const float f = std::min(0.999f, float(double(ctx.done->load()) / double(ctx.total)));
  if (f > *ctx.progress_last) {
    *ctx.progress_last = f;
    (*ctx.progress)(f);
  }
}

/// Builds the subtree of `nodes[node]` over items [begin, end); children are appended as pairs.
/// `box` and `centroids` are the bounds of the items and of their centroids (from the parent's
/// partition pass, so each level reads the items twice: once to score, once to partition).
inline void abt_build_node(std::vector<AbtNode>& nodes, std::uint32_t node, std::uint32_t begin, std::uint32_t end,
                           std::uint32_t depth, const Aabb& box, const Aabb& centroids, const AbtBuildContext& ctx,
                           AbtSplitScratch& scratch) {
  AbtBuildItem* items = ctx.items;
  {
    AbtNode& n = nodes[node];
    n.bounds = box;
    n.sphere = bounding_sphere(box);
    n.begin = begin;
    n.end = end;
    n.left = 0;
    n.axis = 0;
    n.split = 0.0f;
  }
  const std::uint32_t count = end - begin;
  if (ctx.grain > 0 && count < ctx.grain) {
    ctx.tasks->push_back(AbtBuildTask{node, begin, end, depth, box, centroids});
    return;
  }
  if (count <= ctx.leaf_size || depth >= ctx.max_depth) {
    abt_report_leaf(ctx, count);
    return;
  }
  const std::uint64_t key = (std::uint64_t{begin} << 32) ^ std::uint64_t{end} ^ (std::uint64_t{depth} << 58);
  const AbtSplit split = abt_find_split(items, begin, end, box, centroids, ctx.cfg, key, scratch);
  if (!split.found) {
    abt_report_leaf(ctx, count);
    return;
  }
  const int axis = split.axis;
  const float pos = split.position;
  // Partition (centroid < pos goes left), gathering both children's bounds on the way.
  Aabb lbox = Aabb::empty(), lcen = Aabb::empty(), rbox = Aabb::empty(), rcen = Aabb::empty();
  std::uint32_t i = begin, j = end;
  for (;;) {
    while (i < j && items[i].centroid[axis] < pos) {
      lbox = merge(lbox, items[i].box);
      lcen = merge(lcen, items[i].centroid);
      ++i;
    }
    while (i < j && !(items[j - 1].centroid[axis] < pos)) {
      rbox = merge(rbox, items[j - 1].box);
      rcen = merge(rcen, items[j - 1].centroid);
      --j;
    }
    if (i >= j) break;
    std::swap(items[i], items[j - 1]);  // now items[i] goes left, items[j - 1] right
  }
  const std::uint32_t m = i;
  if (m == begin || m == end) {  // rounding left one side empty: nothing separates
    abt_report_leaf(ctx, count);
    return;
  }
  const auto left = static_cast<std::uint32_t>(nodes.size());
  nodes[node].left = left;
  nodes[node].axis = static_cast<std::uint8_t>(axis);
  nodes[node].split = pos;
  nodes.emplace_back();
  nodes.emplace_back();
  abt_build_node(nodes, left, begin, m, depth + 1, lbox, lcen, ctx, scratch);
  abt_build_node(nodes, left + 1, m, end, depth + 1, rbox, rcen, ctx, scratch);
}

CULLKIT_CORE_FN void abt_stitch(std::vector<AbtNode>& raw, std::uint32_t at, const std::vector<AbtNode>& sub) {
  const auto offset = static_cast<std::uint32_t>(raw.size()) - 1u;  // sub[1] lands at raw.size()
  AbtNode root = sub[0];
  if (!root.is_leaf()) root.left += offset;
  raw[at] = root;
  for (std::size_t k = 1; k < sub.size(); ++k) {
    AbtNode nd = sub[k];
    if (!nd.is_leaf()) nd.left += offset;
    raw.push_back(nd);
  }
}

CULLKIT_CORE_FN std::vector<AbtNode> abt_build_raw(AbtBuildContext ctx, std::uint32_t begin, std::uint32_t end,
                                                   std::uint32_t depth, unsigned threads, std::uint32_t grain) {
  std::vector<AbtNode> raw(1);
  raw.reserve(2 * ((end - begin) / ctx.leaf_size + 1));
  AbtSplitScratch scratch;
  scratch.reserve(ctx.cfg.candidates);
  Aabb box, centroids;
  abt_range_bounds(ctx.items, begin, end, box, centroids);
  const unsigned workers = resolve_threads(threads, std::numeric_limits<unsigned>::max());
  if (workers <= 1 || end - begin < 2 * grain) {
    abt_build_node(raw, 0, begin, end, depth, box, centroids, ctx, scratch);
    return raw;
  }
  std::vector<AbtBuildTask> tasks;
  ctx.grain = grain;
  ctx.tasks = &tasks;
  abt_build_node(raw, 0, begin, end, depth, box, centroids, ctx, scratch);
  ctx.grain = 0;
  ctx.tasks = nullptr;
  // Each pool task is one worker with its own scratch, pulling subtrees from a shared counter.
  struct Job {
    const AbtBuildContext* ctx;
    const std::vector<AbtBuildTask>* tasks;
    std::vector<std::vector<AbtNode>> local;
    std::atomic<std::size_t> next{0};
  } job{&ctx, &tasks, std::vector<std::vector<AbtNode>>(tasks.size()), {}};
  const std::size_t count = std::min<std::size_t>(workers, tasks.size());
  detail::run_tasks(
      ctx.runner, count,
      [](void* p, std::size_t) {
        Job& j = *static_cast<Job*>(p);
        AbtSplitScratch s;
        s.reserve(j.ctx->cfg.candidates);
        for (std::size_t t = j.next.fetch_add(1); t < j.tasks->size(); t = j.next.fetch_add(1)) {
          const AbtBuildTask& task = (*j.tasks)[t];
          std::vector<AbtNode>& sub = j.local[t];
          sub.resize(1);
          abt_build_node(sub, 0, task.begin, task.end, task.depth, task.box, task.centroids, *j.ctx, s);
        }
      },
      &job);
  for (std::size_t t = 0; t < tasks.size(); ++t) abt_stitch(raw, tasks[t].node, job.local[t]);
  return raw;
}

CULLKIT_CORE_FN void abt_relayout(const std::vector<AbtNode>& raw, std::vector<AbtNode>& nodes,
                                  std::vector<std::uint32_t>& from, AbtStats& stats) {
  struct Move {
    std::uint32_t from, to, depth;
  };
  nodes.clear();
  from.clear();
  stats.depth = 0;
  stats.leaves = 0;
  stats.max_leaf_objects = 0;
  std::vector<Move> stack;
  stack.push_back(Move{0, 0, 0});
  nodes.resize(1);
  from.resize(1);
  while (!stack.empty()) {
    const Move mv = stack.back();
    stack.pop_back();
    AbtNode nd = raw[mv.from];
    stats.depth = std::max(stats.depth, mv.depth);
    if (nd.is_leaf()) {
      ++stats.leaves;
      stats.max_leaf_objects = std::max(stats.max_leaf_objects, nd.count());
    } else {
      const auto l = static_cast<std::uint32_t>(nodes.size());
      nodes.resize(nodes.size() + 2);
      from.resize(from.size() + 2);
      stack.push_back(Move{nd.left + 1, l + 1, mv.depth + 1});
      stack.push_back(Move{nd.left, l, mv.depth + 1});
      nd.left = l;
    }
    nodes[mv.to] = nd;
    from[mv.to] = mv.from;
  }
  stats.nodes = static_cast<std::uint32_t>(nodes.size());
}
#endif  // CULLKIT_CORE_BODIES

/// Surface area in double of a box, 0 for boxes that are empty or `is_unbounded` (a quality
/// measure must not be swamped by the stand-in box of objects without bounds).
[[nodiscard]] inline double abt_measured_area(const Aabb& b) noexcept {
  return is_unbounded(b) ? 0.0 : abt_area(b);
}

}  // namespace cullkit::detail
