// cullkit/detail/nci/frame_tile.hpp: one screen tile served by the triangle hierarchy instead of the
// grid walk (NciCrowdedPath): the tile's rays are set up as for the walk, cast in packets of 8x8
// through the hierarchy (frame_cast.hpp), four packets taking turns, and every triangle of a leaf
// a packet reaches goes through the walk's own cuts and ray step: its grown box against the
// packet's rays, the front-face rule, the depth reject per ray, the 2D footprint, then test_ray
// (the watertight test, ties to the lower mesh index, edge-band records). Each cut drops only rays
// the float test could not report, so the per-pixel answer is the walk's.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "../bits.hpp"
#include "frame_cast.hpp"
#include "slice_walk.hpp"

namespace cullkit::detail::nci {

// A leaf's triangle takes the 2D footprint pre-test when at least this many rays of the packet reach
// its box and hold no nearer solid hit. Measured, one thread, 640x480 (`bench_nci --profile`):
// sportsCar from outside, cast, 34.0 ms without it, 28.7 / 28.4 / 28.8 ms from 1 / 4 / 8 rays
// (ray tests 573,059 -> 97,405 / 118,552 / 151,978); the 10.1M city seen whole, where most
// triangles reach one ray and the test removes almost none, lost 10-15 % from 1 ray and at most a
// few per cent from 4 (72.8-83.4 ms against 69.7-76.9 in alternating runs; 8: within noise of 4).
inline constexpr int frame_footprint_rays = 4;

// What a leaf of the triangle hierarchy does for one packet. It prefetches the leaf's ids when the
// leaf is pushed. With per-slot corners (in the leaves' order, IndexData::vertices): phase 0 loads
// the ids, finds the triangles of active classes and prefetches their corners, which lie at the
// leaf's own positions (no id to wait for); then the test. With shared vertices: phase 0 loads the
// ids and prefetches the vertex ids; phase 1 loads those and prefetches the corners; then the test.
// Measured on the 1.1M-triangle forest seen whole (one thread, processor time per frame, three
// alternating runs): 102.9-104.2 ms with the corners in internal order behind the ids, 92.2-93.8 in
// the leaves' order; prefetching every pushed leaf's corners instead (many are never tested: their
// rays hit nearer first) took 112-118 ms, and a second, empty phase cost 1-2 %.
struct FrameLeaf {
  const IndexData& data;
  const ViewSetup& f;
  TileState& r;
  Worker& worker;
  FrameSlot* slot;  // the packet taking this step (one FrameLeaf serves every packet of a tile)
  const std::uint8_t* class_on;  // per class: it may face some live ray of the tile (select_classes)
  std::size_t& met;
  int x0, y0;  // the tile's first pixel

  // Whether internal triangle tri's class may face a ray of the tile: classes are runs of ids, found
  // by a branch-free binary search of class_tri_begin. (Remembering the run last found and testing
  // it first cost more than it saved where a leaf's triangles face many ways: a branch the predictor
  // misses. Measured on the 1.1M-triangle forest seen whole and from above, processor time per
  // frame, one thread: 4 % less without it in an SSE2 build, 6-8 % with AVX2; the 10.1M city and
  // the real scenes within noise.)
  [[nodiscard]] bool active(std::uint32_t tri) const {
    const std::uint32_t* b = data.class_tri_begin.data();
    std::size_t lo = 0, n = data.class_tri_begin.size() - 1;  // the class lies in [lo, lo + n)
    while (n > 1) {
      const std::size_t half = n / 2;
      lo = b[lo + half] <= tri ? lo + half : lo;
      n -= half;
    }
    return class_on[lo] != 0;
  }

  // The preparation steps before a leaf's test.
  [[nodiscard]] std::uint32_t phases() const noexcept { return data.slot_vertices ? 1u : 2u; }

  void prefetch(std::uint32_t first, std::uint32_t) const { detail::prefetch(data.bvh.tris.data() + first); }

  // Phase 0 finds the triangles of active classes (bit q of the carry: triangle first + q) and
  // prefetches their corners (per-slot corners: 36 bytes at the triangle's leaf position, at most
  // two lines) or their vertex ids; phase 1 prefetches the corners the ids name.
  std::uint32_t prepare(std::uint32_t first, std::uint32_t count, std::uint32_t phase, std::uint32_t carry) {
    if (phase == 0) carry = 0;
    for (std::uint32_t q = 0; q < count; ++q) {
      const std::uint32_t tri = data.bvh.tris[first + q];
      const std::size_t v = 3 * std::size_t{tri};
      if (phase == 0) {
        if (!active(tri)) continue;
        carry |= 1u << q;
        if (data.slot_vertices) {
          const glm::vec3* corners = &data.vertices[3 * std::size_t{first + q}];
          detail::prefetch(corners);
          detail::prefetch(reinterpret_cast<const char*>(corners) + 3 * sizeof(glm::vec3) - 1);
        } else if (data.tri_vertices.empty()) {
          detail::prefetch(&data.tri_vertices16[v]);
        } else {
          detail::prefetch(&data.tri_vertices[v]);
        }
      } else if (carry >> q & 1u) {
        for (int k = 0; k < 3; ++k) detail::prefetch(&data.corner(tri, k));
      }
    }
    return carry;
  }

  // The rays of `rays` (bits of the packet) whose pixel centres lie in the triangle's grown 2D
  // footprint (footprint_mask, the walk's own pre-test): the others cannot hit it nor fall in its
  // edge band.
  [[nodiscard]] std::uint64_t in_footprint(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2,
                                           std::uint64_t rays) const {
    TileState::Mask rows[TileState::max_tile], inside[TileState::max_tile];
    const int by = slot->by, bx = slot->bx;
    const int ry0 = by + detail::lowest_bit(rays) / 8, ry1 = by + (detail::highest_bit(rays)) / 8;
    for (int y = ry0; y <= ry1; ++y)
      rows[y] = static_cast<TileState::Mask>((rays >> (8 * (y - by))) & 0xFFu) << bx;
    if (!footprint_mask(f, p0, p1, p2, x0, y0, ry0, ry1, rows, inside, f.tile - 1)) return rays;
    std::uint64_t kept = 0;
    for (int y = ry0; y <= ry1; ++y)
      kept |= static_cast<std::uint64_t>((inside[y] >> bx) & 0xFFu) << (8 * (y - by));
    return kept & rays;
  }

  // A leaf triangle on its way through test: its corners relative to the eye as test_ray takes
  // them, their largest coordinates, their box, and the packet's rays that meet the grown box.
  struct Item {
    std::uint32_t tri, pos;  // the internal triangle and its leaf position
    float key;  // the smallest depth of a corner along the packet's mean ray
    float c[3][3];
    float mag[3], qlo[3], qhi[3];
    std::uint64_t meet;
  };

  // The triangle of leaf slot `slot_index` with the packet's rays of `mask`; false when no ray
  // meets its grown box (then it lies between the packet's pixel centres).
  bool make_item(std::uint32_t slot_index, std::uint64_t mask, Item& it) const {
    const float* dir = slot->dir;
    it.tri = data.bvh.tris[slot_index];
    it.pos = slot_index;
    float k = std::numeric_limits<float>::infinity();
    for (int c = 0; c < 3; ++c) {
      const glm::vec3& v = data.leaf_corner(slot_index, it.tri, c);
      it.c[c][0] = v.x - f.eye_f.x;
      it.c[c][1] = v.y - f.eye_f.y;
      it.c[c][2] = v.z - f.eye_f.z;
      k = std::min(k, it.c[c][0] * dir[0] + it.c[c][1] * dir[1] + it.c[c][2] * dir[2]);
    }
    it.key = k;
    // std::min / std::max of three as two nested calls: the same value as the initializer-list
    // forms (the first of equal operands), without their loops.
    const auto min3 = [](float x, float y, float z) { return std::min(std::min(x, y), z); };
    const auto max3 = [](float x, float y, float z) { return std::max(std::max(x, y), z); };
    const float(&a)[3] = it.c[0];
    const float(&b)[3] = it.c[1];
    const float(&c)[3] = it.c[2];
    for (int j = 0; j < 3; ++j) it.mag[j] = max3(std::fabs(it.c[j][0]), std::fabs(it.c[j][1]), std::fabs(it.c[j][2]));
    for (int j = 0; j < 3; ++j) {
      it.qlo[j] = min3(a[j], b[j], c[j]);
      it.qhi[j] = max3(a[j], b[j], c[j]);
    }
    // The triangle's box grown as the hierarchy's boxes are (frame_box_growth).
    const float grow = max3(it.mag[0], it.mag[1], it.mag[2]) * frame_box_growth;
    const float glo[3] = {it.qlo[0] - grow, it.qlo[1] - grow, it.qlo[2] - grow};
    const float ghi[3] = {it.qhi[0] + grow, it.qhi[1] + grow, it.qhi[2] + grow};
    it.meet = frame_rays_meet(slot->p, mask, glo, ghi);
    return it.meet != 0;
  }

  void test(std::uint32_t first, std::uint32_t count, std::uint64_t mask, std::uint32_t carry) {
    FramePacket& p = slot->p;
    const int stride = r.stride, by = slot->by, bx = slot->bx;
    const auto pixel = [&](int k) { return (by + k / 8) * stride + bx + k % 8; };
    // First the box test against the packet's rays: the packet's depths (p.t) do not change
    // during a leaf's test, so it may come before the order is known, and the triangles between
    // pixel centres (about half of those met on a crowded view) take no other step.
    Item item[TriangleBvhNode::leaf_max];
    std::uint8_t order[TriangleBvhNode::leaf_max];
    std::uint32_t kept = 0;
    for (std::uint32_t q = 0; q < count; ++q) {
      if (!(carry >> q & 1u)) continue;  // a back face for every ray of the tile
      ++met;
      Item& it = item[kept];
      if (!make_item(first + q, mask, it)) {
        ++worker.stats.triangles_no_pixel;  // between the packet's pixel centres (or a back face)
        continue;
      }
      // Nearest first along the packet's mean ray (as the walk sorts its candidates), so that
      // near hits let the depth rejects drop the triangles behind them.
      std::uint32_t at = kept++;
      for (; at > 0 && (item[order[at - 1]].key > it.key ||
                        (item[order[at - 1]].key == it.key && item[order[at - 1]].tri > it.tri));
           --at)
        order[at] = order[at - 1];
      order[at] = static_cast<std::uint8_t>(kept - 1);
    }
    std::uint64_t tested = 0;
    for (std::uint32_t q = 0; q < kept; ++q) {
      const Item& it = item[order[q]];
      const std::uint32_t tri = it.tri;
      const glm::vec3 &p0 = data.leaf_corner(it.pos, tri, 0), &p1 = data.leaf_corner(it.pos, tri, 1),
                      &p2 = data.leaf_corner(it.pos, tri, 2);
      // The front-face rule in double. (A float pre-test of the triple product, clear of its
      // rounding, settles almost no triangle on a crowded view: they are small against their
      // distance from the eye, so it only added its cost to the double test's.)
      if (!detail::faces_eye(p0, p1, p2, f.eye)) {
        ++worker.stats.triangles_no_pixel;
        continue;
      }
      std::uint64_t rays = 0;
      for (std::uint64_t m = it.meet; m; m &= m - 1) {
        const int k = detail::lowest_bit(m);
        if (ray_behind(r, pixel(k), it.qlo, it.qhi)) continue;
        rays |= std::uint64_t{1} << k;
      }
      if (f.footprint && at_least_footprint_rays(rays)) rays = in_footprint(p0, p1, p2, rays);
      if (!rays) continue;
      for (std::uint64_t m = rays; m; m &= m - 1)
        test_ray(data, r, worker, pixel(detail::lowest_bit(m)), tri, it.c[0], it.c[1], it.c[2], it.mag);
      worker.mark_tested(tri);
      ++worker.tested_count;  // (triangle, packet) pairs: a triangle is met once per packet
      tested |= rays;
    }
    // Only a tested ray's solid hit can have moved (a pixel belongs to one packet of the tile).
    for (std::uint64_t m = tested; m; m &= m - 1) {
      const int k = detail::lowest_bit(m);
      p.t[k] = r.solid_t[pixel(k)];
    }
  }

  // Whether `rays` holds at least frame_footprint_rays rays (no popcount instruction is assumed).
  [[nodiscard]] static bool at_least_footprint_rays(std::uint64_t rays) noexcept {
    for (int n = 1; n < frame_footprint_rays && rays; ++n) rays &= rays - 1;
    return rays != 0;
  }
};

// Opens the next 8x8 block of the tile that holds live rays into `slot`; false when none is left.
inline bool open_frame_block(const IndexData& data, const TileState& r, const Mask* live, int tw, int th, int& next,
                             FrameSlot& slot) {
  const int nbx = (tw + 7) / 8, nby = (th + 7) / 8;
  while (next < nbx * nby) {
    const int b = next++;
    slot.bx = (b % nbx) * 8;
    slot.by = (b / nbx) * 8;
    slot.bw = std::min(8, tw - slot.bx);
    slot.bh = std::min(8, th - slot.by);
    std::uint64_t packet = 0;
    slot.dir[0] = slot.dir[1] = slot.dir[2] = 0.0f;
    for (int j = 0; j < slot.bh; ++j) {
      const Mask bits = (live[slot.by + j] >> slot.bx) & TileState::columns(0, slot.bw - 1);
      for (Mask m = bits; m; m &= m - 1) {
        const int x = TileState::low_bit(m), k = 8 * j + x, i = (slot.by + j) * r.stride + slot.bx + x;
        slot.p.ix[k] = frame_inverse(r.dx[i]);
        slot.p.iy[k] = frame_inverse(r.dy[i]);
        slot.p.iz[k] = frame_inverse(r.dz[i]);
        slot.p.t[k] = r.solid_t[i];
        slot.dir[0] += r.dx[i];
        slot.dir[1] += r.dy[i];
        slot.dir[2] += r.dz[i];
      }
      packet |= static_cast<std::uint64_t>(bits) << (8 * j);
    }
    if (!packet) continue;
    slot.cur.start(data.bvh, packet);
    slot.busy = true;
    return true;
  }
  return false;
}

// The live rays of a tile (`live`, their hits so far in `r`) cast through the triangle hierarchy in
// packets of 8x8, four taking turns, triangles of the classes in worker.active_classes only. Every
// hit they can still take is found: a packet's rays start from their solid hits.
inline void cast_live_rays(const IndexData& data, const ViewSetup& f, int x0, int y0, int tw, int th, const Mask* live,
                           TileState& r, Worker& worker) {
  worker.class_on.assign(data.class_axis.size(), 0u);
  for (const std::uint16_t k : worker.active_classes) worker.class_on[k] = 1u;
  ++worker.stats.tiles_ray_cast;
  if (worker.frame_slots.size() != frame_turns) worker.frame_slots.resize(frame_turns);
  const float eye[3] = {f.eye_f.x, f.eye_f.y, f.eye_f.z};
  std::size_t met = 0;
  FrameCastStats cast;
  int next = 0, active = 0;
  for (FrameSlot& slot : worker.frame_slots) {
    slot.busy = false;
    active += open_frame_block(data, r, live, tw, th, next, slot);
  }
  FrameLeaf leaf{data, f, r, worker, nullptr, worker.class_on.data(), met, x0, y0};
  while (active > 0) {
    for (FrameSlot& slot : worker.frame_slots) {
      if (!slot.busy) continue;
      leaf.slot = &slot;
      frame_cursor_step(data.bvh, eye, slot.p, slot.cur, leaf, cast);
      if (!slot.cur.done()) continue;
      slot.busy = false;
      if (!open_frame_block(data, r, live, tw, th, next, slot)) --active;
    }
  }
  worker.stats.triangles_met += met;
}

// One screen tile (x0, y0)..(x1, y1) through the triangle hierarchy: the same outputs as
// process_tile (slice_walk.hpp).
inline void process_tile_frame(const IndexData& data, const ViewSetup& f, int x0, int y0, int x1, int y1, TileState& r,
                               Worker& worker, Scratch& scratch) {
  drive_tile(data, f, x0, y0, x1, y1, r, worker, scratch, [&](int tw, int th, TileMasks& m, const glm::dvec3& cone_sum) {
    select_classes(data, r, tw, th, m.live, cone_sum, worker.active_classes);
    cast_live_rays(data, f, x0, y0, tw, th, m.live, r, worker);
  });
}

}  // namespace cullkit::detail::nci
