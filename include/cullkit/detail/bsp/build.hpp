// cullkit/detail/bsp/build.hpp: the BSP builder behind BspTree. Not templated on the user's types:
// BspTree reads the triangles through its traits and hands plain corner arrays to `build`.
//
// Steps: triangle planes (double) and dropping of unusable triangles; then work items (a node to
// make and the convex polygons it receives, each item owning its polygons) processed depth first:
// choose a splitter plane, keep polygons in that plane at the node, send the others to the front or
// back item, cutting those that straddle it. Large inputs are cut on the calling thread until there
// are enough independent subtrees, which the caller's task runner (or the shared pool) then builds;
// the result is laid out in one canonical order afterwards, so it does not depend on the thread
// count.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "../../bsp_params.hpp"
#include "../../config.hpp"
#include "../parallel.hpp"

namespace cullkit {

namespace detail::bsp {

struct DPlane {
  glm::dvec3 normal;
  double d;
};
struct Corner {
  glm::dvec3 p;
  glm::dvec2 uv;  // barycentric (u, v) in the source triangle
};
struct Poly {
  std::uint32_t triangle, first, count;
};

/// A node to build and the polygons it receives (owned: items are independent of each other).
struct Item {
  std::uint32_t parent = kBspNone;
  bool front_side = false;  // which child of `parent` it becomes
  std::uint32_t depth = 1;
  std::vector<Corner> corners;
  std::vector<Poly> polys;
};

/// Nodes and fragments made by one builder (the calling thread or one worker), numbered locally.
struct Output {
  std::vector<BspNode> nodes;
  std::vector<BspFragment> fragments;
  std::vector<glm::vec3> corners;
  std::vector<glm::vec2> barycentrics;
  std::size_t cuts = 0, depth = 0;
};

/// The whole tree, in canonical order (nodes in preorder, front child first; fragments by node).
struct Data {
  std::vector<BspNode> nodes;
  std::vector<BspFragment> fragments;
  std::vector<glm::vec3> corners;
  std::vector<glm::vec2> barycentrics;
  BspStats stats;
  double relative_epsilon = 0;  // BspParams::epsilon, for validate()
};

/// What the on-plane tolerance of a triangle depends on.
struct TriangleScale {
  double magnitude;     // largest coordinate magnitude of its corners
  double longest_edge;
};

struct Context {
  const std::vector<DPlane>* planes;         // per input triangle
  const std::vector<TriangleScale>* scales;  // per input triangle
  double relative;                           // BspParams::epsilon
  const BspParams* params;
  std::atomic<std::size_t> placed{0}, pending{0};
};

enum class Side { front, back, on, straddle };

/// Smallest relative tolerance: about two float ulps of the coordinates.
inline constexpr double kToleranceFloor = 0x1p-22;
/// Largest tolerance, relative to the shorter longest edge of the two triangles.
inline constexpr double kToleranceSizeCap = 1e-3;

/// The on-plane tolerance between two triangles of the given scales (see BspParams::epsilon).
inline double tolerance(const TriangleScale& a, const TriangleScale& b, double relative) {
  const double m = std::max(a.magnitude, b.magnitude);
  const double cap = kToleranceSizeCap * std::min(a.longest_edge, b.longest_edge);
  return std::max(std::min(relative, kToleranceFloor) * m, std::min(relative * m, cap));
}
/// The on-plane tolerance between a polygon of triangle `tested` and the plane of `splitter`.
inline double tolerance(const Context& ctx, std::uint32_t splitter, std::uint32_t tested) {
  return tolerance((*ctx.scales)[splitter], (*ctx.scales)[tested], ctx.relative);
}

inline Side classify(const Corner* c, std::uint32_t count, const DPlane& plane, double eps) {
  bool f = false, b = false;
  for (std::uint32_t i = 0; i < count; ++i) {
    const double s = glm::dot(plane.normal, c[i].p) + plane.d;
    f |= s > eps;
    b |= s < -eps;
  }
  return f ? (b ? Side::straddle : Side::front) : (b ? Side::back : Side::on);
}

inline void append_poly(Item& to, std::uint32_t triangle, const Corner* c, std::uint32_t count) {
  to.polys.push_back(Poly{triangle, static_cast<std::uint32_t>(to.corners.size()), count});
  to.corners.insert(to.corners.end(), c, c + count);
}

/// Cuts a polygon that straddles the plane (some corner beyond the tolerance on each side) exactly
/// where it crosses: corners go by the sign of their distance, a corner at distance 0 to both
/// pieces, and each edge whose ends have opposite signs gets a new corner (position and
/// barycentrics interpolated alike) on both. The two pieces tile the polygon. (Sending every corner
/// within the tolerance to both pieces would not: two or more such corners in a row make the pieces
/// overlap.)
inline void cut(const Poly& poly, const Corner* c, const DPlane& plane, Item& front, Item& back) {
  const std::uint32_t f0 = static_cast<std::uint32_t>(front.corners.size());
  const std::uint32_t b0 = static_cast<std::uint32_t>(back.corners.size());
  for (std::uint32_t i = 0; i < poly.count; ++i) {
    const std::uint32_t j = i + 1 == poly.count ? 0 : i + 1;
    const double di = glm::dot(plane.normal, c[i].p) + plane.d;
    const double dj = glm::dot(plane.normal, c[j].p) + plane.d;
    const int si = di > 0 ? 1 : (di < 0 ? -1 : 0);
    const int sj = dj > 0 ? 1 : (dj < 0 ? -1 : 0);
    if (si >= 0) front.corners.push_back(c[i]);
    if (si <= 0) back.corners.push_back(c[i]);
    if (si * sj < 0) {
      const double t = di / (di - dj);
      const Corner x{c[i].p + (c[j].p - c[i].p) * t, c[i].uv + (c[j].uv - c[i].uv) * t};
      front.corners.push_back(x);
      back.corners.push_back(x);
    }
  }
  front.polys.push_back(Poly{poly.triangle, f0, static_cast<std::uint32_t>(front.corners.size()) - f0});
  back.polys.push_back(Poly{poly.triangle, b0, static_cast<std::uint32_t>(back.corners.size()) - b0});
}

/// The polygon whose plane splits `item` best (lowest score over a sample of its polygons).
inline std::size_t choose_splitter(const Item& item, const Context& ctx) {
  const std::size_t n = item.polys.size();
  const BspParams& prm = *ctx.params;
  const std::size_t cand = std::max<std::size_t>(1, std::min<std::size_t>(prm.candidates, n));
  if (cand == 1) return 0;
  const std::size_t sample = std::max<std::size_t>(1, std::min<std::size_t>(prm.sample, n));
  std::size_t best = 0;
  double best_score = 0;
  for (std::size_t k = 0; k < cand; ++k) {
    const std::size_t pi = k * n / cand;
    const std::uint32_t splitter = item.polys[pi].triangle;
    const DPlane& plane = (*ctx.planes)[splitter];
    std::size_t front = 0, back = 0, on = 0, cuts = 0;
    for (std::size_t s = 0; s < sample; ++s) {
      const Poly& q = item.polys[s * n / sample];
      switch (classify(item.corners.data() + q.first, q.count, plane, tolerance(ctx, splitter, q.triangle))) {
        case Side::front: ++front; break;
        case Side::back: ++back; break;
        case Side::on: ++on; break;
        case Side::straddle: ++cuts; break;
      }
    }
    const double balance = front > back ? double(front - back) : double(back - front);
    const double score = prm.split_weight * double(cuts) + prm.balance_weight * balance -
                         prm.coplanar_weight * double(on);
    if (k == 0 || score < best_score) {
      best = pi;
      best_score = score;
    }
  }
  return best;
}

/// Makes the node of `item` in `out` and pushes its non-empty children onto `stack`.
inline void process(Item& item, Output& out, std::vector<Item>& stack, Context& ctx) {
  const std::uint32_t splitter_triangle = item.polys[choose_splitter(item, ctx)].triangle;
  const DPlane& plane = (*ctx.planes)[splitter_triangle];
  const std::uint32_t node = static_cast<std::uint32_t>(out.nodes.size());
  out.nodes.push_back(BspNode{plane.normal, plane.d, kBspNone, kBspNone, item.parent,
                              static_cast<std::uint32_t>(out.fragments.size()), 0});
  if (item.parent != kBspNone) (item.front_side ? out.nodes[item.parent].front : out.nodes[item.parent].back) = node;
  out.depth = std::max<std::size_t>(out.depth, item.depth);
  Item front, back;
  front.parent = back.parent = node;
  front.front_side = true;
  front.depth = back.depth = item.depth + 1;
  std::size_t placed = 0, cuts = 0;
  for (const Poly& poly : item.polys) {
    const Corner* c = item.corners.data() + poly.first;
    // Pieces of the splitter's own triangle lie in its plane by construction; saying so explicitly
    // guarantees progress whatever the tolerance.
    const Side side = poly.triangle == splitter_triangle
                          ? Side::on
                          : classify(c, poly.count, plane, tolerance(ctx, splitter_triangle, poly.triangle));
    if (side == Side::on) {
      out.fragments.push_back(BspFragment{poly.triangle, static_cast<std::uint32_t>(out.corners.size()), poly.count});
      for (std::uint32_t i = 0; i < poly.count; ++i) {
        out.corners.push_back(glm::vec3(c[i].p));
        out.barycentrics.push_back(glm::vec2(c[i].uv));
      }
      ++placed;
    } else if (side == Side::front) {
      append_poly(front, poly.triangle, c, poly.count);
    } else if (side == Side::back) {
      append_poly(back, poly.triangle, c, poly.count);
    } else {
      cut(poly, c, plane, front, back);
      ++cuts;
    }
  }
  out.nodes[node].fragment_count = static_cast<std::uint32_t>(placed);
  out.cuts += cuts;
  ctx.placed.fetch_add(placed, std::memory_order_relaxed);
  ctx.pending.fetch_add(cuts, std::memory_order_relaxed);
  ctx.pending.fetch_sub(placed, std::memory_order_relaxed);
  item = Item();  // free the parent's polygons before the children are built
  if (!back.polys.empty()) stack.push_back(std::move(back));
  if (!front.polys.empty()) stack.push_back(std::move(front));
}

/// Builds the whole subtree of `root` depth first into `out` (the item's node is out's node 0 if
/// `out` was empty). With `report`, calls the progress callback every 1024 nodes.
inline void build_subtree(Item root, Output& out, Context& ctx, bool report) {
  std::vector<Item> stack;
  stack.push_back(std::move(root));
  for (std::size_t made = 1; !stack.empty(); ++made) {
    Item item = std::move(stack.back());
    stack.pop_back();
    process(item, out, stack, ctx);
    if (report && made % 1024 == 0) ctx.params->progress(BspProgress{ctx.placed.load(), ctx.pending.load()});
  }
}

/// Triangle planes in double, what each triangle's on-plane tolerance depends on, and the first
/// work item holding every usable triangle.
template <class Positions>
Item gather(std::size_t triangle_count, const Positions& triangle_corners, const BspParams& params,
            std::vector<DPlane>& planes, std::vector<TriangleScale>& scales, BspStats& stats) {
  glm::vec3 t[3];
  planes.assign(triangle_count, DPlane{glm::dvec3(0.0), 0.0});
  scales.assign(triangle_count, TriangleScale{0.0, 0.0});
  Item item;
  for (std::size_t i = 0; i < triangle_count; ++i) {
    if (!triangle_corners(i, t)) {
      ++stats.dropped_bad_index;
      continue;
    }
    bool finite = true;
    double magnitude = 0;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) {
        finite = finite && std::isfinite(t[k][a]);
        magnitude = std::max(magnitude, double(std::fabs(t[k][a])));
      }
    if (!finite) {
      ++stats.dropped_non_finite;
      continue;
    }
    const glm::dvec3 a(t[0]), b(t[1]), c(t[2]);
    const glm::dvec3 p[3] = {a, b, c};
    // The normal from the two shorter edges (the better-conditioned cross product). Float corners
    // are exact in double and so are their differences, so the normal is accurate for any triangle
    // whose cross product is not 0, slivers included: only a triangle whose plane misses its own
    // corners by more than an eighth of the smallest tolerance it can meet (thinner than about 1e-9
    // of its length) has no usable plane and is dropped with the zero-area triangles.
    int apex = 0;  // the corner opposite the longest edge
    double longest = -1;
    for (int k = 0; k < 3; ++k) {
      const double l = glm::length(p[(k + 2) % 3] - p[(k + 1) % 3]);
      if (l > longest) {
        longest = l;
        apex = k;
      }
    }
    const glm::dvec3 n = glm::cross(p[(apex + 1) % 3] - p[apex], p[(apex + 2) % 3] - p[apex]);
    const double len = glm::length(n);
    if (!(len > 0.0) || !std::isfinite(len)) {
      ++stats.dropped_degenerate;
      continue;
    }
    const glm::dvec3 unit = n / len;
    const DPlane plane{unit, -glm::dot(unit, (a + b + c) / 3.0)};
    bool flat = true;
    const double smallest_tolerance = std::min(double(params.epsilon), kToleranceFloor) * magnitude;
    for (int k = 0; k < 3; ++k)
      flat = flat && std::fabs(glm::dot(unit, p[k]) + plane.d) <= 0.125 * smallest_tolerance;
    if (!flat) {
      ++stats.dropped_degenerate;
      continue;
    }
    scales[i] = TriangleScale{magnitude, longest};
    stats.epsilon = std::max(stats.epsilon, tolerance(scales[i], scales[i], double(params.epsilon)));
    planes[i] = plane;
    const Corner corners[3] = {{a, glm::dvec2(0, 0)}, {b, glm::dvec2(1, 0)}, {c, glm::dvec2(0, 1)}};
    append_poly(item, static_cast<std::uint32_t>(i), corners, 3);
  }
  return item;
}

/// Appends `part` to `data`, shifting its node, fragment and corner numbers; returns its node offset.
inline std::uint32_t append_output(Data& data, const Output& part) {
  const auto node0 = static_cast<std::uint32_t>(data.nodes.size());
  const auto frag0 = static_cast<std::uint32_t>(data.fragments.size());
  const auto corner0 = static_cast<std::uint32_t>(data.corners.size());
  for (BspNode n : part.nodes) {
    if (n.front != kBspNone) n.front += node0;
    if (n.back != kBspNone) n.back += node0;
    if (n.parent != kBspNone) n.parent += node0;
    n.first_fragment += frag0;
    data.nodes.push_back(n);
  }
  for (BspFragment f : part.fragments) {
    f.first_corner += corner0;
    data.fragments.push_back(f);
  }
  data.corners.insert(data.corners.end(), part.corners.begin(), part.corners.end());
  data.barycentrics.insert(data.barycentrics.end(), part.barycentrics.begin(), part.barycentrics.end());
  return node0;
}

/// Renumbers nodes in preorder (front child first) and fragments and corners by node, so that the
/// arrays do not depend on which thread built which subtree.
inline void canonical_order(Data& data) {
  if (data.nodes.empty()) return;
  Data out;
  out.stats = data.stats;
  out.nodes.reserve(data.nodes.size());
  out.fragments.reserve(data.fragments.size());
  out.corners.reserve(data.corners.size());
  out.barycentrics.reserve(data.barycentrics.size());
  std::vector<std::uint32_t> new_id(data.nodes.size(), kBspNone);
  std::vector<std::uint32_t> stack;
  stack.push_back(0);
  while (!stack.empty()) {
    const std::uint32_t old = stack.back();
    stack.pop_back();
    BspNode n = data.nodes[old];
    new_id[old] = static_cast<std::uint32_t>(out.nodes.size());
    if (n.parent != kBspNone) n.parent = new_id[n.parent];
    const std::uint32_t f0 = n.first_fragment;
    n.first_fragment = static_cast<std::uint32_t>(out.fragments.size());
    for (std::uint32_t f = f0; f < f0 + n.fragment_count; ++f) {
      BspFragment frag = data.fragments[f];
      const std::uint32_t c0 = frag.first_corner;
      frag.first_corner = static_cast<std::uint32_t>(out.corners.size());
      out.corners.insert(out.corners.end(), data.corners.begin() + c0, data.corners.begin() + c0 + frag.corner_count);
      out.barycentrics.insert(out.barycentrics.end(), data.barycentrics.begin() + c0,
                              data.barycentrics.begin() + c0 + frag.corner_count);
      out.fragments.push_back(frag);
    }
    out.nodes.push_back(n);
    if (n.back != kBspNone) stack.push_back(n.back);
    if (n.front != kBspNone) stack.push_back(n.front);
  }
  for (BspNode& n : out.nodes) {  // children were numbered after their parents: fix them now
    if (n.front != kBspNone) n.front = new_id[n.front];
    if (n.back != kBspNone) n.back = new_id[n.back];
  }
  data = std::move(out);
}

/// Runs `items` as up to `threads` tasks of the shared WorkerPool (the calling thread is task 0),
/// each item into its own Output; returns the outputs in item order. Progress is reported from
/// the calling thread only: while it builds (every 1024 nodes) and, once no item is left to take,
/// every 20 ms until the other tasks have finished theirs.
inline std::vector<Output> build_parallel(std::vector<Item>& items, unsigned threads, Context& ctx) {
  struct Job {
    std::vector<Item>* items;
    std::vector<Output> outs;
    Context* ctx;
    std::atomic<std::size_t> next{0}, done{0};
  } job{&items, std::vector<Output>(items.size()), &ctx, {}, {}};
  const std::size_t count = std::min<std::size_t>(std::max(1u, threads), items.size());
  detail::run_tasks(ctx.params->task_runner,
      count,
      [](void* p, std::size_t task) {
        Job& j = *static_cast<Job*>(p);
        const std::size_t n = j.items->size();
        const bool report = task == 0 && static_cast<bool>(j.ctx->params->progress);
        for (std::size_t i = j.next.fetch_add(1); i < n; i = j.next.fetch_add(1)) {
          build_subtree(std::move((*j.items)[i]), j.outs[i], *j.ctx, report);
          j.done.fetch_add(1);
        }
        // Only task 0 waits here, and only for items other tasks have already taken: when the
        // pool runs every task on this thread instead, task 0 has taken them all.
        if (!report) return;
        while (j.done.load() < n) {
          j.ctx->params->progress(BspProgress{j.ctx->placed.load(), j.ctx->pending.load()});
          detail::sleep_milliseconds(20);
        }
      },
      &job);
  return std::move(job.outs);
}

/// The tree over the work item `root` (every usable triangle, from `gather`) and the triangles'
/// planes: cuts, merges the parallel parts and lays the result out canonically in `data`.
CULLKIT_CORE_FN void build_tree(Data& data, Item root, const std::vector<DPlane>& planes,
                                const std::vector<TriangleScale>& scales, const BspParams& params);

#if CULLKIT_CORE_BODIES
CULLKIT_CORE_FN void build_tree(Data& data, Item root, const std::vector<DPlane>& planes,
                                const std::vector<TriangleScale>& scales, const BspParams& params) {
  Context ctx;
  ctx.planes = &planes;
  ctx.scales = &scales;
  ctx.relative = double(params.epsilon);
  ctx.params = &params;
  ctx.pending = root.polys.size();
  unsigned threads = resolve_threads(params.threads, std::numeric_limits<unsigned>::max());
  if (root.polys.size() < params.parallel_min_triangles) threads = 1;
  std::size_t cuts = 0, depth = 0;
  if (!root.polys.empty()) {
    // Cut on this thread, biggest item first, until there are enough subtrees to share out.
    Output top;
    std::vector<Item> items;
    items.push_back(std::move(root));
    const std::size_t want = threads > 1 ? std::size_t(threads) * 8 : 1;
    const std::size_t small = std::max<std::size_t>(64, params.parallel_min_triangles / 16);
    while (items.size() < want) {
      auto biggest = std::max_element(items.begin(), items.end(),
                                      [](const Item& a, const Item& b) { return a.polys.size() < b.polys.size(); });
      if (biggest == items.end() || biggest->polys.size() < small) break;
      Item item = std::move(*biggest);
      items.erase(biggest);
      process(item, top, items, ctx);
      if (params.progress) params.progress(BspProgress{ctx.placed.load(), ctx.pending.load()});
    }
    // Subtree roots hang below nodes of `top`: their links are made after the merge.
    std::vector<std::uint32_t> link_parent(items.size());
    std::vector<bool> link_front(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
      link_parent[i] = items[i].parent;
      link_front[i] = items[i].front_side;
      items[i].parent = kBspNone;
    }
    std::vector<Output> outs = build_parallel(items, threads, ctx);
    append_output(data, top);
    cuts += top.cuts;
    depth = top.depth;
    for (std::size_t i = 0; i < outs.size(); ++i) {
      const std::uint32_t offset = append_output(data, outs[i]);
      // Each subtree's root is its output's first node; `top` sits at offset 0.
      if (link_parent[i] != kBspNone) {
        data.nodes[offset].parent = link_parent[i];
        BspNode& parent = data.nodes[link_parent[i]];
        (link_front[i] ? parent.front : parent.back) = offset;
      }
      cuts += outs[i].cuts;
      depth = std::max(depth, outs[i].depth);
    }
    canonical_order(data);
  }
  data.stats.cuts = cuts;
  data.stats.depth = depth;
  data.stats.fragments = data.fragments.size();
  data.stats.nodes = data.nodes.size();
  if (params.progress) params.progress(BspProgress{ctx.placed.load(), 0});
}
#endif

/// The whole build. `triangle_corners(i, out3)` reads triangle i (false: bad index).
template <class Positions>
void build(std::size_t triangle_count, const Positions& triangle_corners, const BspParams& params, Data& data) {
  const auto t0 = std::chrono::steady_clock::now();
  data = Data();
  data.stats.triangles = triangle_count;
  std::vector<DPlane> planes;
  std::vector<TriangleScale> scales;
  Item root = gather(triangle_count, triangle_corners, params, planes, scales, data.stats);
  build_tree(data, std::move(root), planes, scales, params);
  data.relative_epsilon = double(params.epsilon);
  data.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace detail::bsp
}  // namespace cullkit
