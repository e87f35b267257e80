// bench/bench_views.cpp: what a renderer's frame asks of the AdaptiveBinaryTree beyond one view.
//
//  stereo_*   two eyes 6.4 cm apart: one cull_views call (reference) against two AdaptiveBinaryTree
//             culls and two Bullet btDbvt k-DOP culls, on the same boxes, in this process.
//  cascades_* four shadow-cascade-like frusta (nested depth slices of one view): the same race.
//  light_cascades_* the four slices' light-space boxes for a directional light: the same race.
//  casters_*  the shadow-caster volume of a view culled through cull(ConvexVolume), against the
//             view frustum alone (what it costs to keep the off-screen casters).
//  refit_*    one frame of motion: plain refit (reference), repairing refit, full rebuild; the
//             quality each keeps after 300 frames is printed to stderr.
// Scenes: a generated city (object boxes and triangle boxes) and 60,000 random boxes.
// CSV on stdout (race.hpp), a summary on stderr. CULLKIT_BENCH_SMOKE=1 for a smoke run.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>


#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>

#include <cullkit/cullkit.hpp>
#include <cullkit_support/scene.hpp>

#include "dbvt_peer.hpp"
#include "race.hpp"

using namespace cullkit;
using cullkit::bench::DbvtPeer;
using cullkit::bench::random_boxes;

namespace {

std::vector<Aabb> triangle_boxes(const support::Scene& s) {
  std::vector<Aabb> out;
  for (std::size_t t = 0; t < s.triangle_count(); ++t) {
    glm::vec3 p[3] = {};
    if (triangle_positions(s.mesh(), t, p)) out.push_back(merge(merge(Aabb{p[0], p[0]}, p[1]), p[2]));
  }
  return out;
}

glm::mat4 view_matrix(const glm::vec3& eye, const glm::vec3& target) {
  return glm::lookAtRH(eye, target, glm::vec3(0, 1, 0));
}

struct Summary {
  std::string name;
  double views_vs_two, views_vs_dbvt, views_vs_two_alone;
};
std::vector<Summary> summaries;

void views_race(const std::string& name, const std::vector<Aabb>& boxes, const std::vector<Frustum>& frusta) {
  const AdaptiveBinaryTree<Aabb> abt(boxes.data(), boxes.size());
  DbvtPeer dbvt(boxes);
  std::vector<std::uint32_t> out, bits;
  std::vector<std::vector<std::uint32_t>> sep(frusta.size()), bt(frusta.size());
  abt.cull_views(frusta.data(), frusta.size(), out, bits);
  std::size_t single_total = 0;
  for (std::size_t v = 0; v < frusta.size(); ++v) {
    abt.cull(frusta[v], sep[v]);
    single_total += sep[v].size();
  }
  std::fprintf(stderr, "%s: %zu boxes, %zu views: union %zu, per-view total %zu\n", name.c_str(), boxes.size(),
               frusta.size(), out.size(), single_total);
  const auto r = cullkit_bench::race(
      name, {{"cullkit_cull_views", [&] { abt.cull_views(frusta.data(), frusta.size(), out, bits); }},
             {"cullkit_cull_separately", [&] {
                for (std::size_t v = 0; v < frusta.size(); ++v) abt.cull(frusta[v], sep[v]);
              }},
             {"bullet_btdbvt_separately", [&] {
                for (std::size_t v = 0; v < frusta.size(); ++v) dbvt.cull(frusta[v], bt[v]);
              }}});
  // The same two cullkit contestants without btDbvt between them, separate culls first: btDbvt's
  // milliseconds of work evict the tree from the caches before whichever contestant runs next.
  const auto pair = cullkit_bench::race(
      name + "_cullkit_only", {{"cullkit_cull_separately", [&] {
                                 for (std::size_t v = 0; v < frusta.size(); ++v) abt.cull(frusta[v], sep[v]);
                               }},
                               {"cullkit_cull_views", [&] { abt.cull_views(frusta.data(), frusta.size(), out, bits); }}});
  summaries.push_back(Summary{name, r[0].median_ns / r[1].median_ns, r[0].median_ns / r[2].median_ns,
                              pair[1].median_ns / pair[0].median_ns});
}

void stereo_and_cascades(const std::string& scene, const std::vector<Aabb>& boxes, const glm::vec3& eye,
                         const glm::vec3& target) {
  const glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(90.0f), 1.0f, 0.1f, 600.0f);
  const glm::vec3 fwd = glm::normalize(target - eye);
  const glm::vec3 right = glm::normalize(glm::cross(fwd, glm::vec3(0, 1, 0)));
  std::vector<Frustum> stereo;
  for (float s : {-0.032f, 0.032f})
    stereo.push_back(Frustum::from_matrix(proj * view_matrix(eye + right * s, target + right * s), DepthRange::zero_to_one));
  views_race("stereo_" + scene, boxes, stereo);
  // A headset's pair as an XR runtime gives it: a pose per eye (the head's pose times the eye's
  // 32 mm offset, turned and tilted), each eye's view matrix the inverse of its own pose, and
  // mirrored off-axis tangents (the outer side wider). The eyes' shared planes then agree only up
  // to rounding, normals included.
  std::vector<Frustum> headset;
  const glm::vec3 tilted_up = glm::normalize(glm::vec3(0.15f, 1.0f, 0.05f));
  const glm::mat4 head_pose = glm::inverse(glm::lookAt(eye, eye + fwd, tilted_up));
  for (int e = 0; e < 2; ++e) {
    const float n = 0.1f, l = e == 0 ? -1.25f : -0.85f, r = e == 0 ? 0.85f : 1.25f;
    const glm::mat4 eye_pose = head_pose * glm::translate(glm::mat4(1.0f), glm::vec3(e == 0 ? -0.032f : 0.032f, 0, 0));
    const glm::mat4 p = glm::frustumRH_ZO(l * n, r * n, -1.2f * n, 1.0f * n, n, 600.0f);
    headset.push_back(Frustum::from_matrix(p * glm::inverse(eye_pose), DepthRange::zero_to_one));
  }
  {
    detail::AbtMergedPlanes mp;
    if (mp.assign(headset.data(), 2))
      std::fprintf(stderr, "headset_%s: %u distinct planes of 12\n", scene.c_str(), mp.count());
  }
  views_race("headset_" + scene, boxes, headset);
  std::vector<Frustum> cascades;
  const float splits[5] = {0.1f, 20.0f, 60.0f, 180.0f, 600.0f};
  for (int c = 0; c < 4; ++c) {
    const glm::mat4 p = glm::perspectiveRH_ZO(glm::radians(70.0f), 16.0f / 9.0f, splits[c], splits[c + 1]);
    cascades.push_back(Frustum::from_matrix(p * view_matrix(eye, target), DepthRange::zero_to_one));
  }
  views_race("cascades_" + scene, boxes, cascades);
  // Cascades as a renderer builds them for a directional light: each depth slice's corners fitted
  // by a box in the light's space, the box stretched towards the sun to catch the casters. All
  // four boxes share the light's orientation, so their 24 planes have 6 normals but 24 offsets.
  std::vector<Frustum> light_cascades;
  {
    const glm::vec3 sun_dir = glm::normalize(glm::vec3(0.6f, -0.5f, 0.3f));
    const glm::mat4 light_view = glm::lookAtRH(glm::vec3(0.0f), sun_dir, glm::vec3(0, 1, 0));
    for (int c = 0; c < 4; ++c) {
      const glm::mat4 p = glm::perspectiveRH_ZO(glm::radians(70.0f), 16.0f / 9.0f, splits[c], splits[c + 1]);
      const glm::mat4 slice_to_world = glm::inverse(p * view_matrix(eye, target));
      glm::vec3 lo(HUGE_VALF), hi(-HUGE_VALF);
      for (int k = 0; k < 8; ++k) {
        const glm::vec4 q = slice_to_world * glm::vec4((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, (k & 4) ? 1.0f : 0.0f, 1.0f);
        const glm::vec3 in_light = glm::vec3(light_view * glm::vec4(glm::vec3(q) / q.w, 1.0f));
        lo = glm::min(lo, in_light);
        hi = glm::max(hi, in_light);
      }
      const glm::mat4 o = glm::orthoRH_ZO(lo.x, hi.x, lo.y, hi.y, -hi.z - 500.0f, -lo.z);
      light_cascades.push_back(Frustum::from_matrix(o * light_view, DepthRange::zero_to_one));
    }
  }
  views_race("light_cascades_" + scene, boxes, light_cascades);

  // Shadow casters of the first eye for a low sun: the volume against the frustum alone.
  const AdaptiveBinaryTree<Aabb> abt(boxes.data(), boxes.size());
  const glm::vec3 sun = glm::normalize(glm::vec3(0.6f, -0.5f, 0.3f));
  const ConvexVolume casters = shadow_caster_volume(stereo[0], sun);
  std::vector<std::uint32_t> o1, o2;
  abt.cull(stereo[0], o1);
  abt.cull(casters, o2);
  std::fprintf(stderr, "casters_%s: view %zu objects, caster volume (%zu planes) %zu objects\n", scene.c_str(),
               o1.size(), casters.plane_count(), o2.size());
  cullkit_bench::race("casters_" + scene, {{"cullkit_cull_view", [&] { abt.cull(stereo[0], o1); }},
                                           {"cullkit_cull_caster_volume", [&] { abt.cull(casters, o2); }}});
}

void refit_race(std::size_t count) {
  support::Rng rng(77);
  std::vector<Aabb> boxes(count);
  std::vector<glm::vec3> vel(count);
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 c(rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(-100, 100));
    const glm::vec3 h(rng.uniform(0, 1.5f), rng.uniform(0, 1.5f), rng.uniform(0, 1.5f));
    boxes[i] = Aabb{c - h, c + h};
    vel[i] = glm::vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
  }
  const auto step = [&] {
    for (std::size_t i = 0; i < count; ++i) {
      const glm::vec3 c = boxes[i].center() + vel[i];
      for (int a = 0; a < 3; ++a)
        if (std::fabs(c[a]) > 100.0f) vel[i][a] = -vel[i][a];
      boxes[i] = Aabb{boxes[i].min + vel[i], boxes[i].max + vel[i]};
    }
  };
  AdaptiveBinaryTree<Aabb> plain(boxes.data(), boxes.size()), repaired(boxes.data(), boxes.size());
  const int frames = cullkit_bench::smoke() ? 3 : 300;
  for (int f = 0; f < frames; ++f) {
    step();
    plain.refit(boxes.data());
    repaired.refit(boxes.data(), AbtRefitParams{});
  }
  std::fprintf(stderr, "refit_%zu: after %d frames quality plain %.2f, repairing %.2f\n", count, frames,
               plain.refit_quality(), repaired.refit_quality());
  // Timed: the plain refit and the rebuild on the current boxes; the repairing contestant also
  // moves the objects one more frame per repetition (an O(n) loop), so that it has work to repair.
  cullkit_bench::race("refit_" + std::to_string(count),
                      {{"cullkit_refit_plain", [&] { plain.refit(boxes.data()); }},
                       {"cullkit_refit_repairing", [&] {
                          step();
                          repaired.refit(boxes.data(), AbtRefitParams{});
                        }},
                       {"cullkit_rebuild", [&] {
                          const AdaptiveBinaryTree<Aabb> fresh(boxes.data(), boxes.size());
                          cullkit_bench::keep(fresh);
                        }}},
                      15);
}
// Incremental changes: the same random insert / remove / move operations applied to an
// AdaptiveBinaryTree (insert, remove, update) and to Bullet's btDbvt (insert, remove, update), then
// a cull of each after the churn against a fresh build of the same objects.
void churn_race(std::size_t count) {
  std::vector<Aabb> boxes = random_boxes(count);
  support::Rng rng(99);
  AdaptiveBinaryTree<Aabb> abt(boxes.data(), boxes.size());
  DbvtPeer dbvt(boxes);
  std::vector<std::uint32_t> abt_ids(count), dbvt_ids(count);
  std::vector<Aabb> abt_box = boxes, dbvt_box = boxes;  // current box by id
  for (std::uint32_t i = 0; i < count; ++i) abt_ids[i] = dbvt_ids[i] = i;
  struct Op {
    int kind;
    double pick;
    Aabb box;
  };
  const auto make_ops = [&](std::size_t n) {
    std::vector<Op> ops(n);
    for (Op& op : ops) {
      op.kind = rng.range(0, 5);  // 0 insert, 1 remove, 2..5 move
      op.pick = rng.uniform();
      const glm::vec3 c(rng.uniform(-500, 500), rng.uniform(0, 50), rng.uniform(-500, 500));
      const glm::vec3 h(rng.uniform(0.5f, 5), rng.uniform(0.5f, 10), rng.uniform(0.5f, 5));
      op.box = Aabb{c - h, c + h};
    }
    return ops;
  };
  // A move is a step of up to 2 units from the object's current box (an object in motion), four
  // in six operations; inserts (at random places) and removes keep the count steady.
  const auto apply_abt = [&](const std::vector<Op>& ops) {
    for (const Op& op : ops) {
      const std::size_t j = std::size_t(op.pick * double(abt_ids.size() - 1));
      if (op.kind == 0) {
        abt_ids.push_back(abt.insert(op.box));
        abt_box.resize(std::max<std::size_t>(abt_box.size(), abt_ids.back() + 1u));
        abt_box[abt_ids.back()] = op.box;
      } else if (op.kind == 1) {
        abt.remove(abt_ids[j]);
        abt_ids[j] = abt_ids.back();
        abt_ids.pop_back();
      } else {
        const glm::vec3 step = (op.box.center() - glm::vec3(0, 25, 0)) * 0.004f;
        Aabb& moved = abt_box[abt_ids[j]];
        moved = Aabb{moved.min + step, moved.max + step};
        abt.update(abt_ids[j], moved);
      }
    }
  };
  const auto apply_dbvt = [&](const std::vector<Op>& ops) {
    for (const Op& op : ops) {
      const std::size_t j = std::size_t(op.pick * double(dbvt_ids.size() - 1));
      if (op.kind == 0) {
        dbvt_ids.push_back(dbvt.insert(op.box));
        dbvt_box.push_back(op.box);
      } else if (op.kind == 1) {
        dbvt.remove(dbvt_ids[j]);
        dbvt_ids[j] = dbvt_ids.back();
        dbvt_ids.pop_back();
      } else {
        const glm::vec3 step = (op.box.center() - glm::vec3(0, 25, 0)) * 0.004f;
        Aabb& moved = dbvt_box[dbvt_ids[j]];
        moved = Aabb{moved.min + step, moved.max + step};
        dbvt.update(dbvt_ids[j], moved);
      }
    }
  };
  const std::size_t batch = cullkit_bench::smoke() ? 100 : 1000;
  std::vector<Op> ops = make_ops(batch);
  const auto r = cullkit_bench::race("churn_ops_" + std::to_string(count),
                                     {{"cullkit_insert_remove_update", [&] { apply_abt(ops); }},
                                      {"bullet_btdbvt_insert_remove_update", [&] { apply_dbvt(ops); }}},
                                     cullkit_bench::smoke() ? 2 : 21);
  std::fprintf(stderr, "churn_ops_%zu: %zu operations per repetition: cullkit %.0f ns/op, btDbvt %.0f ns/op\n", count,
               batch, r[0].median_ns / double(batch), r[1].median_ns / double(batch));
  // 10,000 more operations, then cull: after churn, fresh rebuild, btDbvt after the same churn.
  ops = make_ops(cullkit_bench::smoke() ? 500 : 10000);
  apply_abt(ops);
  apply_dbvt(ops);
  std::vector<Aabb> live;
  for (std::size_t p = 0; p < abt.order().size(); ++p)
    if (abt.order()[p] != detail::abt_removed_slot) live.push_back(abt.object_bounds()[p]);
  const AdaptiveBinaryTree<Aabb> fresh(live.data(), live.size());
  double area = 0, fresh_area = 0;
  for (const AbtNode& n : abt.nodes()) area += detail::abt_measured_area(n.bounds);
  for (const AbtNode& n : fresh.nodes()) fresh_area += detail::abt_measured_area(n.bounds);
  const glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(90.0f), 1.0f, 0.1f, 600.0f);
  const Frustum f = Frustum::from_matrix(proj * view_matrix(glm::vec3(-520, 30, -520), glm::vec3(0, 10, 0)),
                                         DepthRange::zero_to_one);
  std::vector<std::uint32_t> o1, o2, o3;
  const auto c = cullkit_bench::race("churn_cull_" + std::to_string(count),
                                     {{"cullkit_after_churn", [&] { abt.cull(f, o1); }},
                                      {"cullkit_fresh_build", [&] { fresh.cull(f, o2); }},
                                      {"bullet_btdbvt_after_churn", [&] { dbvt.cull(f, o3); }}});
  std::fprintf(stderr,
               "churn_cull_%zu: after churn %zu objects (%zu pending, %zu held in the tree), node area / fresh build "
               "%.3f, cull time / fresh build %.3f, / btDbvt %.3f\n",
               count, abt.size(), abt.order().size() - abt.nodes().front().end, std::size_t(abt.nodes().front().end),
               area / fresh_area, c[0].median_ns / c[1].median_ns, c[0].median_ns / c[2].median_ns);
}
}  // namespace

int main() {
  const support::Scene city = support::make_city(1, 26);
  const std::vector<Aabb> objects = city.object_bounds();
  const std::vector<Aabb> tris = triangle_boxes(city);
  const std::vector<Aabb> random = random_boxes(60000);
  stereo_and_cascades("city_objects", objects, glm::vec3(-300, 1.7f, -310), glm::vec3(300, 1.7f, 250));
  stereo_and_cascades("city_triangles", tris, glm::vec3(-300, 1.7f, -310), glm::vec3(300, 1.7f, 250));
  stereo_and_cascades("random_60k", random, glm::vec3(-520, 30, -520), glm::vec3(0, 10, 0));
  stereo_and_cascades("random_60k_overhead", random, glm::vec3(0, 400, 0.1f), glm::vec3(0, 0, 0));
  refit_race(cullkit_bench::smoke() ? 2000 : 20000);
  churn_race(cullkit_bench::smoke() ? 3000 : 60000);
  std::fprintf(stderr, "\nsummary (median time ratios, same run):\n");
  for (const Summary& s : summaries)
    std::fprintf(stderr, "  %-30s cull_views / separate culls %.3f (without btDbvt between: %.3f)   / btDbvt %.3f\n",
                 s.name.c_str(), s.views_vs_two, s.views_vs_two_alone, s.views_vs_dbvt);
  return 0;
}
