#include "hexmerge/occ/mesher/smooth_nodes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge {
namespace {

// A node on a surface may make the smallest angle of the boundary triangles at it smaller only
// while it stays above this (degrees).
constexpr double kRimAngle = 10.0;
// A node off the surface ends its compass search at steps this fraction of its shortest edge
// (1e-3 until cff8ad9: the real parts' sliver stage took about a third longer in all, for as
// many elements under 0.2 at both sizes and the same hex volume).
constexpr double kSearchEnd = 1e-2;

// Items by node (compressed rows): item i names the nodes keys[per_item * i] to
// keys[per_item * (i + 1) - 1]; the items naming node v are of[start[v]] to of[start[v + 1] - 1],
// in item order.
struct RowsByNode {
  std::vector<std::size_t> start;
  std::vector<index_t> of;
};
RowsByNode rows_by_node(index_t nb_nodes, const std::vector<index_t>& keys, std::size_t per_item) {
  RowsByNode rows;
  rows.start.assign(static_cast<std::size_t>(nb_nodes) + 1, 0);
  for (index_t v : keys) ++rows.start[v + 1];
  for (index_t v = 0; v < nb_nodes; ++v) rows.start[v + 1] += rows.start[v];
  rows.of.resize(rows.start.back());
  std::vector<std::size_t> fill(rows.start.begin(), rows.start.end() - 1);
  for (std::size_t k = 0; k < keys.size(); ++k)
    rows.of[fill[keys[k]]++] = static_cast<index_t>(k / per_item);
  return rows;
}

}  // namespace

void smooth_nodes(TetMesh& mesh, const std::vector<char>& movable,
                  const SmoothNodesParameters& parameters, SmoothNodesReport& report,
                  SurfacePath* surface, const std::vector<std::array<index_t, 5>>& pyramids,
                  std::vector<char>* settled, const std::function<bool(index_t)>& keeps) {
  if (!(parameters.target > 0 && parameters.target <= 1) ||
      !(parameters.nudge_target > 0 && parameters.nudge_target <= 1) ||
      !(parameters.floor > 0 && parameters.floor <= 1) ||
      !(parameters.pyramid_floor > 0 && parameters.pyramid_floor <= 1) || parameters.max_passes < 1)
    throw InputError(
        "smooth_nodes: target, nudge_target, floor and pyramid_floor must be in (0, 1], "
        "max_passes >= 1",
        Entity::Parameter);
  if (movable.size() != mesh.nb_vertices())
    throw InputError("smooth_nodes: one movable flag per node (" +
                         std::to_string(mesh.nb_vertices()) + "), not " +
                         std::to_string(movable.size()),
                     Entity::Parameter);
  if (settled != nullptr && settled->size() != mesh.nb_vertices())
    throw InputError("smooth_nodes: one settled flag per node (" +
                         std::to_string(mesh.nb_vertices()) + "), not " +
                         std::to_string(settled->size()),
                     Entity::Parameter);
  report = SmoothNodesReport{};
  const index_t nv = mesh.nb_vertices(), nt = mesh.nb_tets();
  // The tets at each node.
  const RowsByNode tets_at = rows_by_node(nv, mesh.tets, 4);
  const std::vector<std::size_t>& start = tets_at.start;
  const std::vector<index_t>& at = tets_at.of;
  auto quality = [&](index_t t) {
    return scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t));
  };
  // The kept pyramids at each apex, and the least each may fall to.
  std::vector<index_t> apexes(pyramids.size());
  for (std::size_t i = 0; i < pyramids.size(); ++i) {
    for (index_t w : pyramids[i])
      if (w >= nv)
        throw InputError("smooth_nodes: kept pyramid " + std::to_string(i) + " has node " +
                             std::to_string(w) + ", out of range (" + std::to_string(nv) +
                             " nodes)",
                         Entity::Parameter);
    apexes[i] = pyramids[i][4];
  }
  const RowsByNode pyramids_at = rows_by_node(nv, apexes, 1);
  const std::vector<std::size_t>& apex_start = pyramids_at.start;
  const std::vector<index_t>& apex_of = pyramids_at.of;
  auto pyramid_quality = [&](std::size_t i) {
    return scaled_jacobian(CellType::Pyramid, mesh.points.data(), pyramids[i].data());
  };
  std::vector<double> pyramid_bound(pyramids.size());
  for (std::size_t i = 0; i < pyramids.size(); ++i)
    pyramid_bound[i] = std::min(parameters.pyramid_floor, pyramid_quality(i));
  // Per node: its search would leave it where it stands (it did, and no node of a tet at it
  // moved since). An apex whose pyramid is under the floor has a bound of this call's (higher
  // than the call's before, where its search ran): searched again.
  std::vector<char> still(nv, 0);
  if (settled != nullptr) still = *settled;
  for (std::size_t i = 0; i < pyramids.size(); ++i)
    if (pyramid_bound[i] < parameters.pyramid_floor) still[pyramids[i][4]] = 0;
  // Whether node v's kept pyramids are all at their bounds where it stands now.
  auto pyramids_kept = [&](index_t v) {
    for (std::size_t i = apex_start[v]; i < apex_start[v + 1]; ++i)
      if (pyramid_quality(apex_of[i]) < pyramid_bound[apex_of[i]]) return false;
    return true;
  };
  // The worst tet around node v where it stands now.
  auto worst_at = [&](index_t v) {
    double q = std::numeric_limits<double>::infinity();
    for (std::size_t i = start[v]; i < start[v + 1]; ++i) q = std::min(q, quality(at[i]));
    return q;
  };
  // The same, but only when it is above `bound`: else some value <= bound, found as soon as one
  // tet is no better (the tet that was the worst last goes first: most tries fail on it). When
  // it is above, every tet was seen: `under` is then how many are under the floor.
  std::size_t last_worst = 0;
  auto worst_above = [&](index_t v, double bound, std::size_t& under) {
    double q = std::numeric_limits<double>::infinity();
    std::size_t worst = last_worst;
    under = 0;
    // Whether tet i is no better than `bound`; q the least seen (as std::min: a NaN passed over).
    const auto no_better = [&](std::size_t i) {
      const double qi = quality(at[i]);
      if (qi < q) q = qi, worst = i;
      under += qi < parameters.floor;
      return qi <= bound;
    };
    bool failed = no_better(last_worst);
    for (std::size_t i = start[v]; i < start[v + 1] && !failed; ++i)
      if (i != last_worst) failed = no_better(i);
    last_worst = worst;
    return q;
  };
  auto place = [&](index_t v, const Vec3& p) {
    double* x = &mesh.points[3 * static_cast<std::size_t>(v)];
    x[0] = p.x, x[1] = p.y, x[2] = p.z;
  };
  report.min_before = std::numeric_limits<double>::infinity();
  for (index_t t = 0; t < nt; ++t) report.min_before = std::min(report.min_before, quality(t));

  // The search directions: the axes and the cube's diagonals, unit length.
  std::vector<Vec3> directions;
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) {
      Vec3 d{0, 0, 0};
      (a == 0 ? d.x : a == 1 ? d.y : d.z) = s;
      directions.push_back(d);
    }
  const double r3 = 1 / std::sqrt(3.0);
  for (int c = 0; c < 8; ++c)
    directions.push_back(Vec3{c & 1 ? r3 : -r3, c & 2 ? r3 : -r3, c & 4 ? r3 : -r3});

  // On a surface: its two parameter directions and their diagonals, in (a, b).
  const double r2 = 1 / std::sqrt(2.0);
  const double plane[8][2] = {{1, 0},   {-1, 0},   {0, 1},    {0, -1},
                              {r2, r2}, {r2, -r2}, {-r2, r2}, {-r2, -r2}};

  for (int pass = 0; pass < parameters.max_passes; ++pass) {
    std::size_t moved = 0;
    for (index_t v = 0; v < nv; ++v) {
      if (movable[v] == kFixed || start[v] == start[v + 1] || still[v]) continue;
      // Searched now: where it ends, it stays unless a node of a tet at it moves after.
      still[v] = 1;
      const auto unsettle_around = [&] {
        for (std::size_t i = start[v]; i < start[v + 1]; ++i)
          for (int k = 0; k < 4; ++k) still[mesh.tet(at[i])[k]] = 0;
      };
      const bool on_surface = movable[v] == kOnSurface;
      if (on_surface && (!surface || surface->dimension(v) == 0)) continue;
      const bool nudged = movable[v] == kNudged;
      const double target = nudged || on_surface ? parameters.nudge_target : parameters.target;
      double best = worst_at(v);
      if (best >= target) continue;
      const Vec3 origin = Vec3::of(mesh.point(v));
      Vec3 here = origin, centroid{0, 0, 0};
      double shortest = std::numeric_limits<double>::infinity();
      int count = 0;
      for (std::size_t i = start[v]; i < start[v + 1]; ++i)
        for (int k = 0; k < 4; ++k) {
          const index_t w = mesh.tet(at[i])[k];
          if (w == v) continue;
          const Vec3 p = Vec3::of(mesh.point(w));
          centroid = centroid + p, ++count;
          shortest = std::min(shortest, (p - origin).norm());
        }
      centroid = centroid * (1.0 / count);
      last_worst = start[v];
      // The tets at v below the floor where it stands now.
      const auto below_floor = [&] {
        std::size_t below = 0;
        for (std::size_t i = start[v]; i < start[v + 1]; ++i)
          below += quality(at[i]) < parameters.floor;
        return below;
      };
      std::size_t below = below_floor();
      // Off the surface, the last position the search reached with no more of them below the
      // floor than where the node stood, and its worst tet (see the end of the search).
      Vec3 kept_here = Vec3::of(mesh.point(v));
      double kept_worst = best;
      // Tries position p: kept (and the node left there) when strictly better.
      auto try_at = [&](const Vec3& p) {
        place(v, p);
        std::size_t now = 0;
        const double q = worst_above(v, best + 1e-12, now);
        if (q > best + 1e-12 && pyramids_kept(v) && (!keeps || keeps(v))) {
          best = q, here = p;
          if (!on_surface && now <= below) kept_here = p, kept_worst = q;
          return true;
        }
        place(v, here);
        return false;
      };
      if (on_surface) {
        // Lengths (a, b) along the surface from where the node stood; the tets below the floor.
        double a = 0, b = 0;
        // The boundary triangles at v: the faces at v of one tet around it (a face at v between
        // two tets is in both, and both are around v).
        std::vector<std::array<index_t, 2>> rim;
        {
          std::vector<std::array<index_t, 2>> sides;
          for (std::size_t i = start[v]; i < start[v + 1]; ++i) {
            const index_t* t = mesh.tet(at[i]);
            index_t others[3], n = 0;
            for (int k = 0; k < 4; ++k)
              if (t[k] != v) others[n++] = t[k];
            for (int k = 0; k < 3; ++k)
              sides.push_back({std::min(others[k], others[(k + 1) % 3]),
                               std::max(others[k], others[(k + 1) % 3])});
          }
          std::sort(sides.begin(), sides.end());
          for (std::size_t i = 0; i < sides.size();) {
            std::size_t j = i;
            while (j < sides.size() && sides[j] == sides[i]) ++j;
            if (j - i == 1) rim.push_back(sides[i]);
            i = j;
          }
        }
        // The smallest angle of those triangles: a move keeps it at least as large, or above
        // kRimAngle.
        const auto rim_angle = [&] {
          double least = M_PI;
          const Vec3 p = Vec3::of(mesh.point(v));
          for (const auto& [x, y] : rim)
            least = std::min(
                least, mesher::smallest_angle(p, Vec3::of(mesh.point(x)), Vec3::of(mesh.point(y))));
          return least * 180 / M_PI;
        };
        double angle = rim_angle();
        auto try_along = [&](double ta, double tb) {
          Vec3 p;
          if (!surface->at(v, ta, tb, p)) return false;
          const double was = best;
          const Vec3 stood = here;
          if (!try_at(p)) return false;
          const std::size_t now = below_floor();
          const double now_angle = rim_angle();
          if (now > below || now_angle < std::min(angle, kRimAngle)) {  // back
            best = was, here = stood;
            place(v, here);
            return false;
          }
          below = now, angle = now_angle, a = ta, b = tb;
          return true;
        };
        Vec3 along_u, along_v;
        surface->tangents(v, along_u, along_v);
        const Vec3 to_centroid = centroid - origin;
        try_along(to_centroid.dot(along_u), to_centroid.dot(along_v)) ||
            try_along(0.5 * to_centroid.dot(along_u), 0.5 * to_centroid.dot(along_v));
        const int directions_on_path = surface->dimension(v) == 1 ? 2 : 8;
        for (double step = 0.25 * shortest; step > 1e-3 * shortest;) {
          bool better = false;
          for (int d = 0; d < directions_on_path; ++d)
            better |= try_along(a + plane[d][0] * step, b + plane[d][1] * step);
          if (!better) step *= 0.5;
        }
        if ((here - origin).norm() > 0)
          surface->moved(v, a, b), ++moved, ++report.moves, ++report.surface_moves,
              unsettle_around();
        continue;
      }
      if (!nudged) try_at(centroid) || try_at((here + centroid) * 0.5);
      for (double step = (nudged ? 0.05 : 0.25) * shortest;
           step > kSearchEnd * shortest && !(nudged && best >= target);) {
        bool better = false;
        for (const Vec3& d : directions) {
          better |= try_at(here + d * step);
          if (nudged && best >= target) break;
        }
        if (!better) step *= 0.5;
      }
      // The search lifts the worst tet, and may push others below the floor doing so (the
      // second round's moves on gmsh_U_Joint_2 at its 50k size took its tets under 0.2 from 291
      // to 385): where it left more of them there than before, the node goes back to the last
      // position it reached without that, unless the worst tet there was still under half the
      // floor (lifting a nearly flat tet is worth a tet just under the floor: always going back
      // gave the real parts 27 % fewer elements under 0.2 at their 50k sizes but a smallest
      // scaled Jacobian below Gmsh's on three more parts; so, 6 % fewer and none more).
      if (kept_worst >= 0.5 * parameters.floor && below_floor() > below)
        here = kept_here, place(v, here);
      if ((here - origin).norm() > 0) ++moved, ++report.moves, unsettle_around();
    }
    if (moved == 0) break;
  }
  if (settled != nullptr) *settled = std::move(still);
  report.min_after = std::numeric_limits<double>::infinity();
  for (index_t t = 0; t < nt; ++t) report.min_after = std::min(report.min_after, quality(t));
}

}  // namespace hexmerge
