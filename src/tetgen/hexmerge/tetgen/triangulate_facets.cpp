#include "hexmerge/tetgen/triangulate_facets.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <optional>
#include <unordered_map>
#include <utility>

namespace hexmerge::tetgen {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using FaceInfo = CGAL::Triangulation_face_base_with_info_2<char, Kernel>;  // 1: left out
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceInfo>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Sides that cross, or a side through a point, throw: nothing is added.
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::No_constraint_intersection_tag>;

double coord(const Vec3& p, int axis) { return axis == 0 ? p.x : axis == 1 ? p.y : p.z; }
void set_coord(Vec3& p, int axis, double value) {
  (axis == 0 ? p.x : axis == 1 ? p.y : p.z) = value;
}

// Marks the faces reachable from `start` without crossing a side.
void leave_out(Cdt::Face_handle start) {
  if (start->info()) return;
  std::vector<Cdt::Face_handle> stack{start};
  start->info() = 1;
  while (!stack.empty()) {
    const Cdt::Face_handle f = stack.back();
    stack.pop_back();
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle next = f->neighbor(i);
      if (f->is_constrained(i) || next->info()) continue;
      next->info() = 1;
      stack.push_back(next);
    }
  }
}

// A facet's constrained Delaunay triangulation in the plane of two frame axes (u, v; the third,
// `axis`, the one its normal is closest to, dropped): its points (info: index + 1) and its
// polygons' sides; the faces outside it marked by mark_outside().
struct PlanarCdt {
  Cdt cdt;
  int axis = 0, u = 1, v = 2;
  Kernel::Point_2 in_plane(const Vec3& p) const { return {coord(p, u), coord(p, v)}; }
  // Marks the faces outside the facet's outer loops and inside its holes (info 1).
  void mark_outside(const Facet& facet) {
    for (Cdt::Face_handle f : cdt.all_face_handles()) f->info() = 0;
    leave_out(cdt.infinite_face());
    for (const Vec3& hole : facet.holes) leave_out(cdt.locate(in_plane(hole)));
  }
};

// The facet's triangulation, or nothing when it is left to TetGen (not planar to 1e-6 of its
// size, two points at one place in its plane, sides that cross).
std::optional<PlanarCdt> planar_cdt(const Facet& facet, const std::vector<Vec3>& points) {
  // Its plane: Newell's normal of its loops, the axis it is closest to dropped.
  Vec3 normal{0, 0, 0}, low{1e300, 1e300, 1e300}, high{-1e300, -1e300, -1e300};
  for (const auto& polygon : facet.polygons) {
    for (std::size_t k = 0; k < polygon.size(); ++k) {
      const Vec3& a = points[static_cast<std::size_t>(polygon[k])];
      low = {std::min(low.x, a.x), std::min(low.y, a.y), std::min(low.z, a.z)};
      high = {std::max(high.x, a.x), std::max(high.y, a.y), std::max(high.z, a.z)};
      if (polygon.size() < 3) continue;
      const Vec3& b = points[static_cast<std::size_t>(polygon[(k + 1) % polygon.size()])];
      normal = normal + Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x),
                             (a.x - b.x) * (a.y + b.y)};
    }
  }
  const double size = (high - low).norm();
  if (!(normal.norm() > 0) || !(size > 0)) return std::nullopt;
  normal = normal * (1 / normal.norm());
  const Vec3& origin = points[static_cast<std::size_t>(facet.polygons.front().front())];
  for (const auto& polygon : facet.polygons)
    for (int v : polygon)
      if (std::abs((points[static_cast<std::size_t>(v)] - origin).dot(normal)) > 1e-6 * size)
        return std::nullopt;
  const double n[3] = {std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)};
  PlanarCdt out;
  out.axis = static_cast<int>(std::max_element(n, n + 3) - n);
  out.u = (out.axis + 1) % 3, out.v = (out.axis + 2) % 3;
  Cdt& cdt = out.cdt;
  std::unordered_map<int, Cdt::Vertex_handle> vertex;
  for (const auto& polygon : facet.polygons)
    for (int id : polygon) {
      if (vertex.count(id)) continue;
      const std::size_t before = cdt.number_of_vertices();
      const Cdt::Vertex_handle h = cdt.insert(out.in_plane(points[static_cast<std::size_t>(id)]));
      if (cdt.number_of_vertices() == before) return std::nullopt;  // two points at one place
      h->info() = id + 1;
      vertex.emplace(id, h);
    }
  try {
    for (const auto& polygon : facet.polygons) {
      if (polygon.size() < 2) continue;
      const std::size_t sides = polygon.size() == 2 ? 1 : polygon.size();
      for (std::size_t k = 0; k < sides; ++k)
        cdt.insert_constraint(vertex.at(polygon[k]), vertex.at(polygon[(k + 1) % polygon.size()]));
    }
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    return std::nullopt;
  }
  if (cdt.number_of_vertices() != vertex.size()) return std::nullopt;
  return out;
}

// The facet's triangles, or nothing when it is left to TetGen.
std::optional<std::vector<std::array<int, 3>>> triangulate(
    const Facet& facet, const std::vector<Vec3>& points,
    const std::unordered_set<std::uint64_t>* delaunay_edges) {
  std::optional<PlanarCdt> planar = planar_cdt(facet, points);
  if (!planar) return std::nullopt;
  Cdt& cdt = planar->cdt;
  // Four cocircular points: the side TetGen's own tetrahedralisation has (it would else recover
  // ours by flips, through the lattice's cells).
  if (delaunay_edges) {
    for (bool flipped = true; flipped;) {
      flipped = false;
      std::vector<std::pair<Cdt::Vertex_handle, Cdt::Vertex_handle>> sides;
      for (const Cdt::Edge& e : cdt.finite_edges())
        if (!cdt.is_constrained(e))
          sides.emplace_back(e.first->vertex(Cdt::cw(e.second)),
                             e.first->vertex(Cdt::ccw(e.second)));
      for (const auto& [a, b] : sides) {
        Cdt::Face_handle f;
        int i = 0;
        if (!cdt.is_edge(a, b, f, i)) continue;
        const Cdt::Face_handle g = f->neighbor(i);
        if (cdt.is_infinite(f) || cdt.is_infinite(g)) continue;
        const Cdt::Vertex_handle c = f->vertex(i), d = cdt.mirror_vertex(f, i);
        if (delaunay_edges->count(side_key(a->info() - 1, b->info() - 1)) ||
            !delaunay_edges->count(side_key(c->info() - 1, d->info() - 1)) ||
            cdt.side_of_oriented_circle(f, d->point(), false) != CGAL::ON_ORIENTED_BOUNDARY)
          continue;
        cdt.flip(f, i);
        flipped = true;
      }
    }
  }

  planar->mark_outside(facet);
  std::vector<std::array<int, 3>> triangles;
  for (Cdt::Face_handle f : cdt.finite_face_handles())
    if (!f->info())
      triangles.push_back(
          {f->vertex(0)->info() - 1, f->vertex(1)->info() - 1, f->vertex(2)->info() - 1});
  return triangles;
}

}  // namespace

std::vector<Vec3> refine_facet(const Facet& facet, const std::vector<Vec3>& points,
                               double min_angle,
                               const std::function<double(const Vec3&)>& max_radius,
                               const std::function<bool(const Vec3&)>& accept,
                               std::size_t max_points) {
  std::vector<Vec3> added;
  std::optional<PlanarCdt> planar = planar_cdt(facet, points);
  if (!planar) return added;
  Cdt& cdt = planar->cdt;
  const double level =
      coord(points[static_cast<std::size_t>(facet.polygons.front().front())], planar->axis);
  const double cos_limit = std::cos(min_angle);
  const auto in_space = [&](const Kernel::Point_2& p) {
    Vec3 q{0, 0, 0};
    set_coord(q, planar->axis, level);
    set_coord(q, planar->u, p.x());
    set_coord(q, planar->v, p.y());
    return q;
  };
  const auto smallest_angle_cos = [](const Cdt::Face_handle f) {
    double most = -1;  // the cosine of the smallest angle: the largest cosine
    for (int k = 0; k < 3; ++k) {
      const auto& a = f->vertex(k)->point();
      const auto& b = f->vertex((k + 1) % 3)->point();
      const auto& c = f->vertex((k + 2) % 3)->point();
      const double ux = b.x() - a.x(), uy = b.y() - a.y(), wx = c.x() - a.x(), wy = c.y() - a.y();
      const double lu = std::hypot(ux, uy), lw = std::hypot(wx, wy);
      if (lu > 0 && lw > 0) most = std::max(most, (ux * wx + uy * wy) / (lu * lw));
    }
    return most;
  };
  // Rounds: the circumcentres of this round's skinny and large triangles, each where it lies
  // inside the facet, outside every side's diametral circle around it (it would make a thin
  // triangle on the side, which stays as it is) and clear of the points and of the round's
  // other centres by half its triangle's circumradius; then inserted together.
  while (added.size() < max_points) {
    planar->mark_outside(facet);
    // Skinny ones first (worst first: their smallest angle's cosine), then large ones (largest
    // first: 1 + their circumradius over max_radius).
    std::vector<std::pair<double, Cdt::Face_handle>> skinny;
    for (Cdt::Face_handle f : cdt.finite_face_handles()) {
      if (f->info()) continue;
      const double c = smallest_angle_cos(f);
      const double r2 =
          CGAL::squared_radius(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
      if (c > cos_limit) {
        skinny.emplace_back(-c, f);
        continue;
      }
      const double radius = max_radius(in_space(
          CGAL::circumcenter(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point())));
      if (r2 > radius * radius) skinny.emplace_back(1 - std::sqrt(r2) / radius, f);
    }
    std::sort(skinny.begin(), skinny.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<Kernel::Point_2> round;
    for (const auto& [worst, f] : skinny) {
      if (added.size() + round.size() >= max_points) break;
      const Kernel::Point_2 centre =
          CGAL::circumcenter(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point());
      const double r2 = CGAL::squared_distance(centre, f->vertex(0)->point());
      const Cdt::Face_handle at = cdt.locate(centre);
      if (cdt.is_infinite(at) || at->info()) continue;
      bool clear = true;
      for (int k = -1; k < 3 && clear; ++k) {
        const Cdt::Face_handle g = k < 0 ? at : at->neighbor(k);
        if (cdt.is_infinite(g)) continue;
        for (int e = 0; e < 3 && clear; ++e) {
          if (CGAL::squared_distance(centre, g->vertex(e)->point()) < 0.25 * r2) clear = false;
          if (!g->is_constrained(e)) continue;
          const auto& a = g->vertex(Cdt::cw(e))->point();
          const auto& b = g->vertex(Cdt::ccw(e))->point();
          if (CGAL::squared_distance(centre, CGAL::midpoint(a, b)) <
              0.25 * CGAL::squared_distance(a, b))
            clear = false;
        }
      }
      for (const Kernel::Point_2& other : round)
        if (clear && CGAL::squared_distance(centre, other) < 0.25 * r2) clear = false;
      if (!clear) continue;
      const Vec3 q = in_space(centre);
      if (!accept(q)) continue;
      round.push_back(centre);
      added.push_back(q);
    }
    if (round.empty()) break;
    for (const Kernel::Point_2& p : round) cdt.insert(p)->info() = 0;
  }
  return added;
}

bool has_loop(const Facet& facet) {
  return std::any_of(facet.polygons.begin(), facet.polygons.end(),
                     [](const auto& polygon) { return polygon.size() > 3; });
}

std::uint64_t side_key(int a, int b) {
  const auto [low, high] = std::minmax(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(low)) << 32) |
         static_cast<std::uint32_t>(high);
}

std::size_t triangulate_facets(std::vector<Facet>& facets, const std::vector<Vec3>& points,
                               const std::unordered_set<std::uint64_t>* delaunay_edges) {
  std::vector<Facet> out;
  std::size_t triangulated = 0;
  for (Facet& facet : facets) {
    std::optional<std::vector<std::array<int, 3>>> triangles;
    if (has_loop(facet)) triangles = triangulate(facet, points, delaunay_edges);
    if (!triangles) {
      out.push_back(std::move(facet));
      continue;
    }
    ++triangulated;
    for (const auto& t : *triangles) out.push_back(Facet{{{t[0], t[1], t[2]}}, {}, facet.marker});
  }
  facets = std::move(out);
  return triangulated;
}

}  // namespace hexmerge::tetgen
