// cullkit/portal_graph.hpp: cells and portals. Indoor scenes are rooms (cells) joined by door and
// window openings (portals); from the eye's cell, only what is seen through a chain of openings can
// be visible, and only inside the view volume that chain narrows down to.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "config.hpp"
#include "detail/portals/clip.hpp"
#include "geometry/aabb.hpp"
#include "geometry/convex_volume.hpp"
#include "geometry/frustum.hpp"
#include "geometry/plane.hpp"

namespace cullkit {

/// One reached cell and the volume of one chain of portals leading to it.
struct PortalView {
  std::uint32_t cell;
  ConvexVolume volume;  ///< the view volume narrowed by the portals on one path to it
};

/// Limits of one traversal. A cell reached along many paths is listed once per path, up to these
/// budgets; past them the answer widens (a cell is never dropped for a budget).
struct PortalParams {
  /// Entries one cell may get from paths. A path that would add one more, entering through portal
  /// p, lists the cell once more with the volume of p alone (the frustum narrowed by p as if p were
  /// in the eye's cell) and continues from there; later paths entering through p stop, covered by
  /// that entry. Each side of each portal widens at most once, so the work stays bounded in graphs
  /// with many loops. Lower: faster, coarser volumes.
  std::uint32_t max_views_per_cell = 8;
  /// Entries in one answer. Past it the traversal stops, and every cell the graph joins to the eye's
  /// cell that has no wide entry yet gets one with the frustum's volume.
  std::uint32_t max_views = 4096;
};

/// What a graph was given and could not use (each still has a defined, conservative meaning).
struct PortalGraphStats {
  std::size_t cells = 0;
  std::size_t portals = 0;
  /// Portals whose polygon cannot narrow anything (fewer than 3 or more than 16 corners, a
  /// non-finite corner, no area, not planar): they let every ray through, the volume unchanged.
  std::size_t open_portals = 0;
  /// `add_portal` calls naming a cell that does not exist: nothing added, `no_portal` returned.
  std::size_t rejected_portals = 0;
};

/// What one traversal did.
struct PortalTraversalStats {
  std::size_t portals_tested = 0;  ///< portal polygons clipped
  std::size_t widened_arrivals = 0;  ///< (portal, side) entries widened by `max_views_per_cell`
  bool budget_exhausted = false;   ///< `max_views` was reached (the wide fallback was taken)
  bool eye_outside = false;        ///< no usable eye cell or eye: every cell was listed
};

namespace detail {
struct PortalFrame {
  std::uint32_t cell;
  std::uint32_t chain;  ///< last node of this path in the chain list, or `no_chain`
  VolumeMask crossed;   ///< planes of `volume` that are crossed portal planes
  ConvexVolume volume;
};
struct PortalChainNode {
  std::uint32_t portal;
  std::uint32_t parent;
};
struct PortalLink {
  std::uint32_t portal;
  std::uint32_t next;
};
constexpr std::uint32_t no_chain = 0xFFFFFFFFu;
}  // namespace detail

/// Reusable memory for `PortalGraph::visible_cells` and `CellObjects::cull`: once warm, a traversal
/// allocates nothing. One per thread.
class PortalScratch {
 public:
  /// What the last traversal through this scratch did.
  [[nodiscard]] const PortalTraversalStats& stats() const noexcept { return stats_; }

 private:
  friend class PortalGraph;
  friend class CellObjects;
  std::vector<detail::PortalFrame> stack_;
  std::vector<detail::PortalChainNode> chain_;
  std::vector<std::uint32_t> views_per_cell_;
  std::vector<std::uint8_t> wide_;          // per cell: listed with the frustum's whole volume
  std::vector<std::uint8_t> wide_arrival_;  // per portal side: listed with the portal's own volume
  std::vector<std::uint32_t> queue_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_value_ = 0;
  PortalTraversalStats stats_;
};

/// Cells joined by portals, for visibility through doors and windows (a cell-and-portal graph).
///
/// A cell is a region whose walls block every ray except through its portals; a portal is a planar
/// convex polygon shared by two cells. From the eye's cell, `visible_cells` walks the portals the
/// view volume sees, narrowing the volume by each portal, and lists every cell reached with the
/// volume of each path (Luebke and Georges' portal culling, with a conservative clip).
///
/// Conventions: planes face inward (`Plane`); portal polygons may wind either way; the eye is the
/// frustum's centre of projection. Cell geometry (`set_cell_bounds`, `set_cell_planes`) is optional:
/// the traversal needs only the portals; `locate_cell` and `CellObjects` use it.
///
/// Thread safety: `visible_cells` and `locate_cell` are const and may run concurrently, each thread
/// with its own `PortalScratch`; adding cells or portals must not overlap them.
class PortalGraph {
 public:
  static constexpr std::uint32_t no_cell = 0xFFFFFFFFu;
  static constexpr std::uint32_t no_portal = 0xFFFFFFFFu;
  static constexpr std::size_t max_portal_corners = 16;

  PortalGraph() = default;
  explicit PortalGraph(const PortalParams& params) : params_(params) {}

  [[nodiscard]] const PortalParams& params() const noexcept { return params_; }
  [[nodiscard]] const PortalGraphStats& stats() const noexcept { return stats_; }
  [[nodiscard]] std::uint32_t cell_count() const noexcept { return static_cast<std::uint32_t>(first_link_.size()); }
  [[nodiscard]] std::uint32_t portal_count() const noexcept { return static_cast<std::uint32_t>(portals_.size()); }

  /// Adds a cell with no geometry; returns its index (0, 1, 2, ...). Amortized O(1).
  std::uint32_t add_cell() {
    first_link_.push_back(detail::no_chain);
    cell_shape_.push_back(CellShape{});
    ++stats_.cells;
    return cell_count() - 1;
  }

  /// A portal between cells `a` and `b`: a planar convex polygon (3 to 16 corners, either winding)
  /// through which each cell sees the other. Returns its index, or `no_portal` (nothing added, counted
  /// in `stats().rejected_portals`) when `a` or `b` is not a cell. A polygon that cannot narrow a
  /// volume (see `PortalGraphStats::open_portals`) is kept as an open portal: it lets every ray
  /// through. A portal from a cell to itself is kept and never followed (it leads nowhere new).
  /// pre: `polygon` points to `count` corners (may be null when `count` is 0). Cost: O(count).
  std::uint32_t add_portal(std::uint32_t a, std::uint32_t b, const glm::vec3* polygon, std::size_t count) {
    CULLKIT_ASSERT(polygon != nullptr || count == 0, "add_portal: polygon is null");
    if (a >= cell_count() || b >= cell_count()) {
      ++stats_.rejected_portals;
      return no_portal;
    }
    detail::PortalRecord r;
    r.cells[0] = a;
    r.cells[1] = b;
    r.first_corner = static_cast<std::uint32_t>(corners_.size());
    r.open = !(count >= 3 && count <= max_portal_corners && polygon != nullptr);
    if (!r.open) {
      for (std::size_t i = 0; i < count; ++i) corners_.push_back(polygon[i]);
      r.corner_count = static_cast<std::uint32_t>(count);
      r.open = !fit_plane(r);
    }
    if (r.open) ++stats_.open_portals;
    const auto id = static_cast<std::uint32_t>(portals_.size());
    portals_.push_back(r);
    links_.push_back({id, first_link_[a]});
    first_link_[a] = static_cast<std::uint32_t>(links_.size() - 1);
    if (b != a) {
      links_.push_back({id, first_link_[b]});
      first_link_[b] = static_cast<std::uint32_t>(links_.size() - 1);
    }
    ++stats_.portals;
    return id;
  }

  /// The two cells of portal `p` (pre: p < portal_count()).
  [[nodiscard]] std::uint32_t portal_cell(std::uint32_t p, int side) const noexcept {
    return portals_[p].cells[side & 1];
  }
  /// The corners of portal `p` as given (none for a portal given fewer than 3 or more than 16).
  [[nodiscard]] const glm::vec3* portal_corners(std::uint32_t p) const noexcept {
    return corners_.data() + portals_[p].first_corner;
  }
  [[nodiscard]] std::size_t portal_corner_count(std::uint32_t p) const noexcept { return portals_[p].corner_count; }
  /// False for a portal that lets every ray through unnarrowed (see `PortalGraphStats`).
  [[nodiscard]] bool portal_usable(std::uint32_t p) const noexcept { return !portals_[p].open; }

  /// Gives cell `cell` a box (for `locate_cell` and `CellObjects`). A cell has a box or planes, not
  /// both: this replaces planes given before. Returns false (nothing changed) for a bad cell index
  /// or a box that is not `is_valid`.
  bool set_cell_bounds(std::uint32_t cell, const Aabb& bounds) {
    if (cell >= cell_count() || !is_valid(bounds)) return false;
    CellShape& s = cell_shape_[cell];
    s.kind = CellShape::box;
    s.bounds = bounds;
    s.volume = ConvexVolume();
    return true;
  }
  /// Gives cell `cell` a convex shape: the points inside all of `planes` (normals inward, up to
  /// 32). Returns false (nothing changed) for a bad cell index or more than 32 planes.
  bool set_cell_planes(std::uint32_t cell, const Plane* planes, std::size_t count) {
    if (cell >= cell_count() || count > ConvexVolume::max_planes || (planes == nullptr && count > 0)) return false;
    CellShape& s = cell_shape_[cell];
    s.kind = CellShape::planes;
    s.volume = ConvexVolume();
    for (std::size_t i = 0; i < count; ++i) s.volume.add_plane(planes[i]);
    return true;
  }
  /// True when the cell has a box or planes.
  [[nodiscard]] bool cell_has_shape(std::uint32_t cell) const noexcept {
    return cell < cell_count() && cell_shape_[cell].kind != CellShape::none;
  }
  /// The cell's box (for a cell given planes or nothing: the unbounded box is not representable, so
  /// this returns `Aabb::empty()`).
  [[nodiscard]] Aabb cell_bounds(std::uint32_t cell) const noexcept {
    return cell < cell_count() && cell_shape_[cell].kind == CellShape::box ? cell_shape_[cell].bounds : Aabb::empty();
  }

  /// Point location: the cell whose box or planes hold `p`, the one `p` is deepest inside where
  /// several do (a point on a shared wall); `no_cell` if none does, `p` is not finite or no cell has
  /// a shape. Points within float rounding of a shape count as inside. Cost: O(cells x planes).
  [[nodiscard]] std::uint32_t locate_cell(const glm::vec3& p) const noexcept {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return no_cell;
    std::uint32_t best = no_cell;
    float best_depth = -std::numeric_limits<float>::infinity();
    for (std::uint32_t c = 0; c < cell_count(); ++c) {
      float depth;
      if (!shape_depth(c, p, depth)) continue;
      if (depth > best_depth) {
        best_depth = depth;
        best = c;
      }
    }
    return best;
  }

  /// True if `bounds` may meet the shape of `cell` (false for a cell without a shape).
  [[nodiscard]] bool cell_meets(std::uint32_t cell, const Aabb& bounds) const noexcept {
    if (cell >= cell_count()) return false;
    const CellShape& s = cell_shape_[cell];
    if (s.kind == CellShape::box) {
      const glm::vec3 pad = slack(s.bounds);
      return overlaps(Aabb{s.bounds.min - pad, s.bounds.max + pad}, bounds);
    }
    if (s.kind == CellShape::planes) return s.volume.classify(bounds) != Containment::outside;
    return false;
  }

  /// Clears `out`, then writes {eye_cell, the frustum's volume} and every cell seen through a chain
  /// of portals with the volume of that chain. A point of a cell that some ray from `eye` through
  /// `frustum` reaches through portals lies inside the volume of at least one entry for that cell.
  ///
  /// Every volume holds the frustum's six planes (so nothing outside the frustum is ever in one),
  /// the last portal's plane and the planes through the eye and the edges of that portal as clipped
  /// by the path so far. Special cases, each conservative:
  /// - a portal nearer to the eye than the near plane still leads on (the near plane never clips a
  ///   portal; what lies before it is clipped out of the cells' volumes instead);
  /// - the eye on a portal's plane (standing in a doorway) passes that portal without narrowing;
  /// - a portal behind the eye, or outside the current volume, is not followed;
  /// - loops end: a path never crosses one portal twice (a straight ray cannot), a path back into the
  ///   eye's cell stops (the first entry covers it), and the budgets of `PortalParams` bound the
  ///   work, widening the answer past them, never dropping a cell;
  /// - `eye_cell` not a cell (`no_cell` when `locate_cell` found none), or a non-finite eye: there is
  ///   no cell to start from, so every cell is listed with the frustum's volume (all visible).
  /// The eye cell may appear again, with narrower volumes, when a loop of portals leads back to it.
  ///
  /// Cost: per entry, one clip of each portal of the cell (O(corners x planes)). Allocates only
  /// while `out` or the scratch grow. Thread safety: const; one scratch per thread.
  void visible_cells(std::uint32_t eye_cell, const glm::vec3& eye, const Frustum& frustum,
                     std::vector<PortalView>& out, PortalScratch& scratch) const {
    out.clear();
    PortalScratch& s = scratch;
    s.stats_ = PortalTraversalStats{};
    const ConvexVolume full(frustum);
    if (eye_cell >= cell_count() || !std::isfinite(eye.x) || !std::isfinite(eye.y) || !std::isfinite(eye.z)) {
      s.stats_.eye_outside = true;
      for (std::uint32_t c = 0; c < cell_count(); ++c) out.push_back(PortalView{c, full});
      return;
    }
    s.views_per_cell_.assign(cell_count(), 0u);
    s.wide_.assign(cell_count(), 0u);
    s.wide_arrival_.assign(2u * portals_.size(), 0u);
    s.stack_.clear();
    s.chain_.clear();
    const glm::dvec3 e(eye);
    out.push_back(PortalView{eye_cell, full});
    s.wide_[eye_cell] = 1;
    s.stack_.push_back(detail::PortalFrame{eye_cell, detail::no_chain, 0, full});
    detail::PortalPolygon poly;
    bool exhausted = false;
    while (!s.stack_.empty() && !exhausted) {
      const detail::PortalFrame f = s.stack_.back();
      s.stack_.pop_back();
      for (std::uint32_t l = first_link_[f.cell]; l != detail::no_chain; l = links_[l].next) {
        const std::uint32_t p = links_[l].portal;
        const detail::PortalRecord& r = portals_[p];
        const std::uint32_t next = r.cells[0] == f.cell ? r.cells[1] : r.cells[0];
        const std::size_t arrival = 2u * p + (next == r.cells[1] ? 1u : 0u);
        if (next == f.cell || s.wide_[next] || s.wide_arrival_[arrival] || on_chain(s, f.chain, p)) continue;
        ++s.stats_.portals_tested;
        ConvexVolume narrowed;
        VolumeMask crossed = 0;
        if (!pass_portal(r, e, f, full, poly, narrowed, crossed)) continue;
        if (out.size() >= params_.max_views) {
          exhausted = true;
          break;
        }
        if (s.views_per_cell_[next] >= params_.max_views_per_cell) {
          // Too many paths: list the cell once more with the volume through this portal alone (as
          // if seen straight from the eye's cell) and go on from there. Every path that enters the
          // cell through this portal is narrower and crosses fewer portals after it, so later ones
          // stop here.
          s.wide_arrival_[arrival] = 1;
          ++s.stats_.widened_arrivals;
          const detail::PortalFrame from_eye{f.cell, detail::no_chain, 0, full};
          if (!pass_portal(r, e, from_eye, full, poly, narrowed, crossed)) {
            narrowed = full;  // rounding only: never narrower than the path that got here
            crossed = 0;
          }
          s.chain_.push_back(detail::PortalChainNode{p, detail::no_chain});
          out.push_back(PortalView{next, narrowed});
          s.stack_.push_back(
              detail::PortalFrame{next, static_cast<std::uint32_t>(s.chain_.size() - 1), crossed, narrowed});
          continue;
        }
        ++s.views_per_cell_[next];
        s.chain_.push_back(detail::PortalChainNode{p, f.chain});
        out.push_back(PortalView{next, narrowed});
        s.stack_.push_back(
            detail::PortalFrame{next, static_cast<std::uint32_t>(s.chain_.size() - 1), crossed, narrowed});
      }
    }
    if (exhausted) list_reachable(eye_cell, full, s, out);
  }

  /// As above, with a scratch made for this call (allocates every call).
  void visible_cells(std::uint32_t eye_cell, const glm::vec3& eye, const Frustum& frustum,
                     std::vector<PortalView>& out) const {
    PortalScratch scratch;
    visible_cells(eye_cell, eye, frustum, out, scratch);
  }

 private:
  struct CellShape {
    enum Kind : std::uint8_t { none, box, planes } kind = none;
    Aabb bounds = Aabb::empty();
    ConvexVolume volume;
  };

  static glm::vec3 slack(const Aabb& b) noexcept {
    const glm::vec3 m = glm::max(glm::abs(b.min), glm::abs(b.max));
    return m * (8.0f * std::numeric_limits<float>::epsilon()) + glm::vec3(std::numeric_limits<float>::min());
  }

  // How deep `p` is inside the cell's shape (negative: outside by that much); false when outside
  // beyond rounding or the cell has no shape.
  bool shape_depth(std::uint32_t c, const glm::vec3& p, float& depth) const noexcept {
    const CellShape& s = cell_shape_[c];
    if (s.kind == CellShape::box) {
      const glm::vec3 lo = p - s.bounds.min, hi = s.bounds.max - p;
      depth = std::fmin(std::fmin(std::fmin(lo.x, lo.y), lo.z), std::fmin(std::fmin(hi.x, hi.y), hi.z));
      const glm::vec3 pad = slack(s.bounds);
      return depth >= -std::fmax(pad.x, std::fmax(pad.y, pad.z));
    }
    if (s.kind == CellShape::planes) {
      if (!s.volume.contains(p)) return false;
      depth = std::numeric_limits<float>::infinity();
      for (std::size_t i = 0; i < s.volume.plane_count(); ++i)
        depth = std::fmin(depth, signed_distance(s.volume.plane(i), p));
      return true;
    }
    return false;
  }

  // Computes the portal's best-fit plane and thickness; false if the polygon cannot be used.
  bool fit_plane(detail::PortalRecord& r) const noexcept {
    const glm::vec3* q = corners_.data() + r.first_corner;
    const std::size_t n = r.corner_count;
    glm::dvec3 normal(0.0), centre(0.0);
    double extent = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const glm::dvec3 a(q[i]), b(q[i + 1 == n ? 0 : i + 1]);
      if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(a.z)) return false;
      normal += glm::cross(a, b);
      centre += a;
      extent = std::fmax(extent, std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z));
    }
    centre /= static_cast<double>(n);
    double size = 0.0;
    for (std::size_t i = 0; i < n; ++i) size = std::fmax(size, glm::length(glm::dvec3(q[i]) - centre));
    const double len = glm::length(normal);
    if (!(len > 1e-9 * size * size) || !std::isfinite(len)) return false;
    r.normal = normal / len;
    r.d = -glm::dot(r.normal, centre);
    double thick = 0.0;
    for (std::size_t i = 0; i < n; ++i) thick = std::fmax(thick, std::fabs(glm::dot(r.normal, glm::dvec3(q[i])) + r.d));
    // Planar within float rounding of the corners (relative to the portal's size and position).
    if (thick > 1e-5 * size + detail::rounding_slack(extent)) return false;
    r.thickness = thick + detail::rounding_slack(extent);
    return true;
  }

  static bool on_chain(const PortalScratch& s, std::uint32_t node, std::uint32_t portal) noexcept {
    for (; node != detail::no_chain; node = s.chain_[node].parent)
      if (s.chain_[node].portal == portal) return true;
    return false;
  }

  // One step through portal `r` from frame `f`: false if no ray of the frame's volume crosses it.
  bool pass_portal(const detail::PortalRecord& r, const glm::dvec3& eye, const detail::PortalFrame& f,
                   const ConvexVolume& full, detail::PortalPolygon& poly, ConvexVolume& narrowed,
                   VolumeMask& crossed) const noexcept {
    if (r.open) {
      narrowed = f.volume;
      crossed = f.crossed;
      return true;
    }
    detail::clip_portal(corners_.data() + r.first_corner, r.corner_count, eye, f.volume, f.crossed, poly);
    if (poly.n < 3) return false;
    const double at_eye = glm::dot(r.normal, eye) + r.d;
    const double eye_slack = r.thickness + detail::rounding_slack(std::fabs(eye.x) + std::fabs(eye.y) +
                                                                  std::fabs(eye.z) + std::fabs(r.d));
    if (std::fabs(at_eye) <= eye_slack) {
      // The eye is on the portal's plane (in the doorway): rays cross it at any angle, so the
      // portal narrows nothing.
      narrowed = f.volume;
      crossed = f.crossed;
      return true;
    }
    return detail::portal_volume(r, poly, eye, full, narrowed, crossed);
  }

  // The budget fallback: every cell joined to `eye_cell` by portals that has no wide entry yet
  // gets one (a superset of whatever the unfinished paths could have listed).
  void list_reachable(std::uint32_t eye_cell, const ConvexVolume& full, PortalScratch& s,
                      std::vector<PortalView>& out) const {
    s.stats_.budget_exhausted = true;
    s.queue_.clear();
    // views_per_cell_ is reused as the "queued" mark; wide_ says "already has the frustum's volume".
    s.views_per_cell_.assign(cell_count(), 0u);
    s.views_per_cell_[eye_cell] = 1;
    s.queue_.push_back(eye_cell);
    for (std::size_t head = 0; head < s.queue_.size(); ++head) {
      const std::uint32_t c = s.queue_[head];
      if (!s.wide_[c]) {
        s.wide_[c] = 1;
        out.push_back(PortalView{c, full});
      }
      for (std::uint32_t l = first_link_[c]; l != detail::no_chain; l = links_[l].next) {
        const detail::PortalRecord& r = portals_[links_[l].portal];
        const std::uint32_t n = r.cells[0] == c ? r.cells[1] : r.cells[0];
        if (!s.views_per_cell_[n]) {
          s.views_per_cell_[n] = 1;
          s.queue_.push_back(n);
        }
      }
    }
  }

  PortalParams params_;
  PortalGraphStats stats_;
  std::vector<std::uint32_t> first_link_;  // per cell: first link, or no_chain
  std::vector<detail::PortalLink> links_;  // two per portal (one per side), singly linked per cell
  std::vector<detail::PortalRecord> portals_;
  std::vector<glm::vec3> corners_;
  std::vector<CellShape> cell_shape_;
};

/// Which objects each cell holds, and the portal cull of a scene: an object is kept when its bounds
/// meet the volume of some entry of a cell it is in.
///
/// An object goes to every cell whose shape its bounds meet (an object straddling a doorway is in
/// both rooms). Objects in no cell (a cell without a shape holds nothing), and objects whose bounds
/// are not usable (NaN, infinite, inverted), are never left out by portals: the first are tested
/// against the frustum only, the second always kept.
///
/// Build cost: O(objects x cells) (a linear pass; fine for hundreds of cells). Cull cost: one box
/// test per object per entry of its cells. Thread safety: `cull` is const; one scratch per thread.
class CellObjects {
 public:
  CellObjects() = default;
  CellObjects(const PortalGraph& graph, const Aabb* bounds, std::size_t count) { build(graph, bounds, count); }

  void build(const PortalGraph& graph, const Aabb* bounds, std::size_t count) {
    CULLKIT_ASSERT(bounds != nullptr || count == 0, "CellObjects: bounds is null");
    bounds_.assign(bounds, bounds + count);
    first_.assign(graph.cell_count() + 1u, 0u);
    items_.clear();
    loose_.clear();
    always_.clear();
    std::vector<std::uint8_t> placed(count, 0u);
    for (std::uint32_t c = 0; c < graph.cell_count(); ++c) {
      first_[c] = static_cast<std::uint32_t>(items_.size());
      for (std::size_t o = 0; o < count; ++o) {
        if (!is_valid(bounds[o]) || !graph.cell_meets(c, bounds[o])) continue;
        items_.push_back(static_cast<std::uint32_t>(o));
        placed[o] = 1;
      }
    }
    first_[graph.cell_count()] = static_cast<std::uint32_t>(items_.size());
    for (std::size_t o = 0; o < count; ++o) {
      if (!is_valid(bounds[o])) always_.push_back(static_cast<std::uint32_t>(o));
      else if (!placed[o]) loose_.push_back(static_cast<std::uint32_t>(o));
    }
  }

  [[nodiscard]] std::size_t object_count() const noexcept { return bounds_.size(); }
  /// The objects of cell `c` (pre: c < the graph's cell count at build).
  [[nodiscard]] const std::uint32_t* cell_begin(std::uint32_t c) const noexcept { return items_.data() + first_[c]; }
  [[nodiscard]] const std::uint32_t* cell_end(std::uint32_t c) const noexcept { return items_.data() + first_[c + 1]; }
  /// Objects in no cell (culled by the frustum only).
  [[nodiscard]] const std::vector<std::uint32_t>& loose_objects() const noexcept { return loose_; }

  /// Clears `out`, then writes, once each in any order, every object whose bounds may meet the
  /// volume of an entry of `views` for a cell it is in, the loose objects the frustum does not
  /// reject, and the objects with unusable bounds. Entries for cells the build did not know are
  /// ignored. Allocates only while `out` or the scratch grow.
  void cull(const Frustum& frustum, const std::vector<PortalView>& views, std::vector<std::uint32_t>& out,
            PortalScratch& scratch) const {
    out.clear();
    std::vector<std::uint32_t>& stamp = scratch.stamp_;
    if (stamp.size() < bounds_.size()) stamp.assign(bounds_.size(), 0u);
    if (++scratch.stamp_value_ == 0) {
      std::fill(stamp.begin(), stamp.end(), 0u);
      scratch.stamp_value_ = 1;
    }
    const std::uint32_t mark = scratch.stamp_value_;
    const std::uint32_t cells = static_cast<std::uint32_t>(first_.size()) - 1u;
    for (const PortalView& v : views) {
      if (v.cell >= cells) continue;
      for (std::uint32_t i = first_[v.cell]; i < first_[v.cell + 1]; ++i) {
        const std::uint32_t o = items_[i];
        if (stamp[o] == mark) continue;
        if (v.volume.classify(bounds_[o]) == Containment::outside) continue;
        stamp[o] = mark;
        out.push_back(o);
      }
    }
    for (std::uint32_t o : loose_)
      if (frustum.classify(bounds_[o]) != Containment::outside) out.push_back(o);
    for (std::uint32_t o : always_) out.push_back(o);
  }

 private:
  std::vector<Aabb> bounds_;
  std::vector<std::uint32_t> first_;  // per cell, a range of items_
  std::vector<std::uint32_t> items_;
  std::vector<std::uint32_t> loose_;
  std::vector<std::uint32_t> always_;
};

}  // namespace cullkit
