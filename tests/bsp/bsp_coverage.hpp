// bsp_coverage.hpp: does every input triangle come out of a BspTree covered exactly once by its
// fragments? Shared by the BSP tests and the benchmark.
//
// Per triangle, the areas of its fragments (in 3D, from their float corners, in double) must add up
// to the triangle's own area within 1e-4 relative, plus what rounding the fragments' new corners to
// float can change (half a float ulp of the largest coordinate per corner, times the fragment's
// perimeter): a lost piece or a piece listed twice changes the sum by far more. The same sum over
// the fragments' barycentrics (in the triangle's (u, v) plane, where a whole triangle has area 1/2)
// must agree too: it does not depend on where the triangle lies.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cullkit/bsp_tree.hpp>
#include <cullkit_support/scene.hpp>

namespace bsp_test {

struct Coverage {
  std::size_t usable = 0;          // triangles a renderer draws: finite, indices in range, area > 2^-21 x longest^2
  std::size_t no_fragment = 0;     // usable, and not one fragment
  std::size_t under = 0;           // usable, fragments short of its area (some lost)
  std::size_t over = 0;            // usable, fragments beyond its area (some doubled)
  std::size_t uv_mismatch = 0;     // usable, fragments' barycentric areas not adding up to 1/2
  std::size_t with_fragments = 0;  // triangles (usable or not) with at least one fragment
  std::size_t accounted = 0;       // with_fragments + every drop counter of stats()
  std::size_t float_rounding = 0;  // usable, 3D sum off by more than 1e-4 but within the float allowance
  double worst_uv = 0;             // largest |barycentric area / (1/2) - 1| over usable triangles
  std::size_t worst_triangle = 0;
  [[nodiscard]] std::size_t wrong() const { return no_fragment + under + over + uv_mismatch; }
};

inline double fragment_float_slack(const glm::vec3* c, std::uint32_t count) {
  double perimeter = 0, magnitude = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    perimeter += glm::length(glm::dvec3(c[(i + 1) % count]) - glm::dvec3(c[i]));
    for (int a = 0; a < 3; ++a) magnitude = std::max(magnitude, double(std::fabs(c[i][a])));
  }
  // Half an ulp per coordinate moves a corner by at most sqrt(3)/2 ulp; each corner touches two
  // edges. 2^-23 is one float ulp at magnitude 1.
  return perimeter * magnitude * 0x1p-23 * 1.8;
}

template <class Tree>
Coverage check_coverage(const cullkit::support::Scene& scene, const Tree& tree, bool print_failures = false) {
  const std::size_t nt = scene.triangle_count();
  std::vector<double> area(nt, 0.0), slack(nt, 0.0), uv_area(nt, 0.0);
  std::vector<std::uint32_t> pieces(nt, 0);
  for (const auto& fr : tree.fragments()) {
    if (fr.triangle >= nt) continue;
    const glm::vec3* c = tree.corners().data() + fr.first_corner;
    const glm::vec2* uv = tree.barycentrics().data() + fr.first_corner;
    glm::dvec3 n(0.0);
    double uv2 = 0;
    for (std::uint32_t i = 0; i < fr.corner_count; ++i) {
      const std::uint32_t j = (i + 1) % fr.corner_count;
      // Relative to the first corner: keeps the cross products small far from the origin.
      n += glm::cross(glm::dvec3(c[i]) - glm::dvec3(c[0]), glm::dvec3(c[j]) - glm::dvec3(c[0]));
      uv2 += double(uv[i].x) * double(uv[j].y) - double(uv[j].x) * double(uv[i].y);
    }
    area[fr.triangle] += 0.5 * glm::length(n);
    uv_area[fr.triangle] += 0.5 * uv2;
    slack[fr.triangle] += fragment_float_slack(c, fr.corner_count);
    ++pieces[fr.triangle];
  }
  Coverage cov;
  for (std::size_t t = 0; t < nt; ++t) {
    if (pieces[t] > 0) ++cov.with_fragments;
    const std::uint32_t* idx = scene.indices.data() + 3 * t;
    if (idx[0] >= scene.positions.size() || idx[1] >= scene.positions.size() || idx[2] >= scene.positions.size())
      continue;
    const glm::dvec3 a(scene.positions[idx[0]]), b(scene.positions[idx[1]]), c(scene.positions[idx[2]]);
    bool finite = true;
    for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(a[k]) && std::isfinite(b[k]) && std::isfinite(c[k]);
    if (!finite) continue;
    const double want = 0.5 * glm::length(glm::cross(b - a, c - a));
    const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    if (!(want > 0x1p-21 * longest * longest)) continue;
    ++cov.usable;
    const double off = area[t] - want;
    const double uv_off = uv_area[t] - 0.5;
    const bool bad3d = std::fabs(off) > 1e-4 * want + slack[t];
    const bool bad_uv = std::fabs(uv_off) > 1e-4 * 0.5 + 1e-6 * pieces[t];
    if (pieces[t] == 0) {
      ++cov.no_fragment;
    } else if (bad3d) {
      ++(off < 0 ? cov.under : cov.over);
    } else if (bad_uv) {
      ++cov.uv_mismatch;
    }
    if (pieces[t] > 0 && !bad3d && std::fabs(off) > 1e-4 * want) ++cov.float_rounding;
    if (std::fabs(uv_off) * 2.0 > cov.worst_uv) {
      cov.worst_uv = std::fabs(uv_off) * 2.0;
      cov.worst_triangle = t;
    }
    if (print_failures && (pieces[t] == 0 || bad3d || bad_uv) && cov.wrong() <= 5)
      std::printf("  %s: triangle %zu: %u fragments covering %.6f of it (uv %.6f)\n", scene.name.c_str(), t, pieces[t],
                  area[t] / want, uv_area[t] * 2.0);
  }
  const auto& s = tree.stats();
  cov.accounted = cov.with_fragments + s.dropped_bad_index + s.dropped_non_finite + s.dropped_degenerate;
  return cov;
}

}  // namespace bsp_test
