#include "hexmerge/occ/mesher/surface_check.h"

// CGAL before OpenCASCADE: OCCT's Handle() macro breaks CGAL's headers.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_MapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"

namespace hexmerge::mesher {
namespace {

// Whether CAD edge `edge` bounds face `face` (both numbered from 0).
bool edge_bounds(const Shape& s, int edge, int face) {
  const std::vector<int>& faces = s.edge_faces[static_cast<std::size_t>(edge)];
  return std::find(faces.begin(), faces.end(), face) != faces.end();
}

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;

Point point(const Vec3& p) { return Point(p.x, p.y, p.z); }

// The pairs of faces a description names at most.
constexpr std::size_t kListed = 3;

// Whether triangles a and b (node indices) cross, given their shared nodes: none, a general
// test; one, whether the side of either opposite the shared node meets the other (where two
// triangles with a common node meet beyond it, one of those sides reaches the other triangle);
// two or three (a common side), not tested: the surface's folds are removed before.
// Whether points p lie strictly on one side of the plane through a, b, c, by a margin far above
// the rounding of the floating-point test (false when unsure: the exact test decides then).
template <std::size_t N>
bool one_side(const Vec3& a, const Vec3& b, const Vec3& c, const std::array<Vec3, N>& p) {
  const Vec3 n = (b - a).cross(c - a);
  const double reach = (b - a).norm() + (c - a).norm();
  int sign = 0;
  for (const Vec3& q : p) {
    const double d = n.dot(q - a);
    if (std::abs(d) <= 1e-12 * n.norm() * (reach + (q - a).norm())) return false;
    const int s = d > 0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return true;
}

// Whether segment pq and triangle abc are certainly apart: some axis (the triangle's normal, its
// sides' normals in its plane, the segment's direction across each side and the segment's normal
// in the plane) on which their projections lie apart by far more than rounding can close. False
// when unsure (touching, crossing, or too close to tell): CGAL's exact test decides then. On the
// core's lattice faces most pairs tested touch a plane exactly, where CGAL's filtered
// predicates fail over to exact arithmetic: this takes most of them first.
bool clearly_apart(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 pa = p - a, qa = q - a, ba = b - a, ca = c - a;
  const Vec3 d = q - p, e0 = ba, e1 = c - b, e2 = a - c, n = ba.cross(ca);
  const double extent = std::max({pa.norm(), qa.norm(), ba.norm(), ca.norm()});
  const double far = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z)});
  const double tolerance = 1e-9 * (extent + 1e-5 * far);
  const Vec3 axes[8] = {n,           n.cross(e0), n.cross(e1), n.cross(e2),
                        d.cross(e0), d.cross(e1), d.cross(e2), n.cross(d)};
  for (const Vec3& axis : axes) {
    const double length = axis.norm();
    if (!(length > 0)) continue;
    const double s0 = axis.dot(pa), s1 = axis.dot(qa);
    const double t1 = axis.dot(ba), t2 = axis.dot(ca);  // (a projects to 0)
    const double gap = std::max(std::min({0.0, t1, t2}) - std::max(s0, s1),
                                std::min(s0, s1) - std::max({0.0, t1, t2}));
    if (gap > tolerance * length) return true;
  }
  return false;
}

// Whether triangle p has no area: CGAL's exact test where the floating-point area is too small to
// tell (its collinearity test fails over to exact arithmetic on every triangle in an axis plane).
bool degenerate(const std::array<Vec3, 3>& p, const Triangle& t) {
  const Vec3 u = p[1] - p[0], v = p[2] - p[0];
  if (u.cross(v).norm() > 1e-10 * u.norm() * v.norm()) return false;
  return t.is_degenerate();
}

bool cross(const std::vector<Vec3>& nodes, const std::array<int, 3>& a,
           const std::array<int, 3>& b) {
  int shared = 0, in_a = -1, in_b = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (a[i] == b[j]) ++shared, in_a = i, in_b = j;
  if (shared > 1) return false;
  const std::array<Vec3, 3> pa{nodes[a[0]], nodes[a[1]], nodes[a[2]]};
  const std::array<Vec3, 3> pb{nodes[b[0]], nodes[b[1]], nodes[b[2]]};
  const Triangle ta(point(pa[0]), point(pa[1]), point(pa[2]));
  const Triangle tb(point(pb[0]), point(pb[1]), point(pb[2]));
  if (shared == 0) {
    // Most pairs near each other lie on one side of the other's plane.
    if (one_side(pa[0], pa[1], pa[2], pb) || one_side(pb[0], pb[1], pb[2], pa)) return false;
    // Triangles that meet meet where a side of one meets the other.
    bool apart = true;
    for (int k = 0; k < 3 && apart; ++k)
      apart = clearly_apart(pa[k], pa[(k + 1) % 3], pb[0], pb[1], pb[2]) &&
              clearly_apart(pb[k], pb[(k + 1) % 3], pa[0], pa[1], pa[2]);
    if (apart) return false;
    return !degenerate(pa, ta) && !degenerate(pb, tb) && CGAL::do_intersect(ta, tb);
  }
  if (degenerate(pa, ta) || degenerate(pb, tb)) return false;  // collinear nodes: no area
  // The side of each opposite the shared node, against the other triangle.
  const std::array<Vec3, 2> side_a{pa[(in_a + 1) % 3], pa[(in_a + 2) % 3]};
  const std::array<Vec3, 2> side_b{pb[(in_b + 1) % 3], pb[(in_b + 2) % 3]};
  return (!one_side(pb[0], pb[1], pb[2], side_a) &&
          !clearly_apart(side_a[0], side_a[1], pb[0], pb[1], pb[2]) &&
          CGAL::do_intersect(Segment(point(side_a[0]), point(side_a[1])), tb)) ||
         (!one_side(pa[0], pa[1], pa[2], side_b) &&
          !clearly_apart(side_b[0], side_b[1], pa[0], pa[1], pa[2]) &&
          CGAL::do_intersect(Segment(point(side_b[0]), point(side_b[1])), ta));
}

Vec3 centroid(const std::vector<Vec3>& nodes, const SurfaceTriangle& t) {
  return (nodes[t.node[0]] + nodes[t.node[1]] + nodes[t.node[2]]) * (1.0 / 3);
}

using Box = std::pair<Vec3, Vec3>;

bool boxes_overlap(const Box& a, const Box& b) {
  return !(a.second.x < b.first.x || b.second.x < a.first.x || a.second.y < b.first.y ||
           b.second.y < a.first.y || a.second.z < b.first.z || b.second.z < a.first.z);
}

Box box_of(const std::vector<Vec3>& nodes, const std::array<int, 3>& v) {
  return {vmin(nodes[v[0]], vmin(nodes[v[1]], nodes[v[2]])),
          vmax(nodes[v[0]], vmax(nodes[v[1]], nodes[v[2]]))};
}

// Triangles' boxes, in a grid of buckets about their median side wide (not finer than 1/500 of
// their extent: the buckets stay under 1.25e8), so that a triangle meets a few dozen others'.
struct BoxedTriangles {
  std::vector<Box> box;
  BucketGrid grid;
};

template <typename Corners>  // corners(t): triangle t's node indices
BoxedTriangles boxed_triangles(const std::vector<Vec3>& nodes, std::size_t count,
                               const Corners& corners) {
  std::vector<Box> box(count);
  Vec3 lo = nodes[corners(0)[0]], hi = lo;
  std::vector<double> sides;
  for (std::size_t t = 0; t < count; ++t) {
    const std::array<int, 3>& v = corners(t);
    box[t] = box_of(nodes, v);
    lo = vmin(lo, box[t].first);
    hi = vmax(hi, box[t].second);
    if (t % 16 == 0) sides.push_back((nodes[v[0]] - nodes[v[1]]).norm());
  }
  std::nth_element(sides.begin(), sides.begin() + sides.size() / 2, sides.end());
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const double cell = std::max({sides[sides.size() / 2], extent / 500, 1e-12});
  BucketGrid grid(lo, hi, cell);
  for (std::size_t t = 0; t < count; ++t)
    grid.add(static_cast<int>(t), box[t].first, box[t].second);
  return {std::move(box), std::move(grid)};
}

}  // namespace

std::vector<Crossing> find_crossings(const std::vector<Vec3>& nodes,
                                     const std::vector<SurfaceTriangle>& triangles) {
  std::vector<Crossing> found;
  if (triangles.empty()) return found;
  const BoxedTriangles boxed = boxed_triangles(
      nodes, triangles.size(), [&](std::size_t t) -> const auto& { return triangles[t].node; });
  const std::vector<Box>& box = boxed.box;
  std::vector<int> seen(triangles.size(), -1);
  std::set<std::pair<int, int>> faces_found;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    boxed.grid.any_in(box[t].first, box[t].second, [&](int j) {
      if (j <= i || seen[j] == i) return false;
      seen[j] = i;
      if (!boxes_overlap(box[t], box[j])) return false;
      const int fa = triangles[t].face, fb = triangles[j].face;
      const std::pair<int, int> faces{std::min(fa, fb), std::max(fa, fb)};
      if (!faces_found.count(faces) && cross(nodes, triangles[t].node, triangles[j].node)) {
        faces_found.insert(faces);
        found.push_back({i, j});
      }
      return false;
    });
  }
  return found;
}

std::vector<char> crosses_any(const std::vector<Vec3>& nodes,
                              const std::vector<std::array<int, 3>>& surface,
                              const std::vector<std::array<int, 3>>& inner) {
  std::vector<char> crosses(inner.size(), 0);
  if (surface.empty() || inner.empty()) return crosses;
  const BoxedTriangles boxed = boxed_triangles(
      nodes, surface.size(), [&](std::size_t t) -> const auto& { return surface[t]; });
  std::vector<int> seen(surface.size(), -1);
  for (std::size_t i = 0; i < inner.size(); ++i) {
    const Box b = box_of(nodes, inner[i]);
    boxed.grid.any_in(b.first, b.second, [&](int j) {
      if (seen[j] == static_cast<int>(i)) return false;
      seen[j] = static_cast<int>(i);
      if (!boxes_overlap(b, boxed.box[static_cast<std::size_t>(j)])) return false;
      if (cross(nodes, inner[i], surface[static_cast<std::size_t>(j)])) {
        crosses[i] = 1;
        return true;  // (stops the search for this one)
      }
      return false;
    });
  }
  return crosses;
}

std::vector<OverusedSide> find_overused_sides(const Surface& surface,
                                              const std::vector<std::vector<int>>& face_solids,
                                              const std::vector<std::vector<int>>& edge_faces) {
  const std::vector<SurfaceTriangle>& triangles = surface.triangles;
  std::unordered_map<std::uint64_t, std::vector<int>> at_side;  // triangles per side
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) at_side[side_key(triangles[t], c)].push_back(static_cast<int>(t));
  std::vector<OverusedSide> found;
  std::set<std::vector<int>> face_sets;
  for (const auto& [key, around] : at_side) {
    if (around.size() <= 2) continue;
    std::map<int, int> per_solid;
    for (int t : around)
      for (int solid : face_solids[static_cast<std::size_t>(triangles[t].face)]) ++per_solid[solid];
    if (std::none_of(per_solid.begin(), per_solid.end(),
                     [](const auto& count) { return count.second > 2; }))
      continue;
    std::vector<int> faces;
    for (int t : around) faces.push_back(triangles[t].face);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    const auto segment = surface.segments.find(key);
    if (segment != surface.segments.end()) {
      const std::vector<int>& bounded = edge_faces[static_cast<std::size_t>(segment->second.edge)];
      if (std::all_of(faces.begin(), faces.end(), [&](int f) {
            return std::find(bounded.begin(), bounded.end(), f) != bounded.end();
          }))
        continue;  // one edge of them all
    }
    if (face_sets.insert(faces).second) found.push_back({pair_lo(key), pair_hi(key), faces});
  }
  std::sort(found.begin(), found.end(),
            [](const OverusedSide& x, const OverusedSide& y) { return x.faces < y.faces; });
  return found;
}

std::vector<int> faces_with_open_sides(const Surface& surface) {
  std::unordered_map<std::uint64_t, int> uses;
  for (const SurfaceTriangle& t : surface.triangles)
    for (int c = 0; c < 3; ++c) ++uses[side_key(t, c)];
  std::vector<int> faces;
  for (const SurfaceTriangle& t : surface.triangles)
    for (int c = 0; c < 3; ++c)
      if (uses[side_key(t, c)] == 1) faces.push_back(t.face);
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

std::string face_list(const std::vector<int>& faces, const std::vector<std::string>& face_names) {
  std::string text;
  for (std::size_t k = 0; k < faces.size(); ++k)
    text += (k == 0                  ? ""
             : k + 1 == faces.size() ? " and "
                                     : ", ") +
            face_names[static_cast<std::size_t>(faces[k])];
  return text;
}

std::string describe_overused_sides(const std::vector<Vec3>& nodes,
                                    const std::vector<OverusedSide>& overused,
                                    const std::vector<std::string>& face_names) {
  std::ostringstream text;
  text.precision(6);
  for (std::size_t i = 0; i < overused.size() && i < kListed; ++i) {
    text << (i == 0 ? "" : "; ") << face_list(overused[i].faces, face_names);
    const Vec3 at = (nodes[overused[i].a] + nodes[overused[i].b]) * 0.5;
    text << " meet near (" << at.x << ", " << at.y << ", " << at.z << ")";
  }
  if (overused.size() > kListed)
    text << "; and " << overused.size() - kListed << " more such places";
  return text.str();
}

bool faces_meet_along(const Shape& s, const std::vector<Vec3>& nodes, const OverusedSide& side,
                      double tolerance) {
  const Vec3 a = nodes[static_cast<std::size_t>(side.a)],
             b = nodes[static_cast<std::size_t>(side.b)];
  // Whether `at` lies within `tolerance` of an edge that faces x and y share: there they meet as
  // the CAD means them to.
  const auto on_common_edge = [&](int x, int y, const gp_Pnt& at) {
    const TopoDS_Vertex point = BRepBuilderAPI_MakeVertex(at).Vertex();
    for (TopExp_Explorer ex(s.faces(x + 1), TopAbs_EDGE); ex.More(); ex.Next()) {
      if (!edge_bounds(s, s.edges.FindIndex(ex.Current()) - 1, y)) continue;
      BRepExtrema_DistShapeShape distance(point, ex.Current());
      if (distance.IsDone() && distance.NbSolution() > 0 && distance.Value() <= tolerance)
        return true;
    }
    return false;
  };
  for (const double f : {0.25, 0.5, 0.75}) {
    const Vec3 p = a + (b - a) * f;
    const TopoDS_Vertex at = BRepBuilderAPI_MakeVertex(gp_Pnt(p.x, p.y, p.z)).Vertex();
    // The point of each face nearest p.
    std::vector<gp_Pnt> nearest;
    for (const int face : side.faces) {
      BRepExtrema_DistShapeShape distance(at, TopoDS::Face(s.faces(face + 1)));
      if (!distance.IsDone() || distance.NbSolution() == 0) return true;  // unsure: as before
      nearest.push_back(distance.PointOnShape2(1));
    }
    // Two faces meet there, but not along an edge they share: their nearest points are those
    // of a common edge where the side runs beside one (a random part's sphere and torus, their
    // curve of intersection 0.18 mm from the side, which a plane between them shares too: the
    // part was refused as broken at h 27).
    bool meet = false;
    for (std::size_t i = 0; i < nearest.size() && !meet; ++i)
      for (std::size_t j = i + 1; j < nearest.size() && !meet; ++j)
        meet = nearest[i].Distance(nearest[j]) <= tolerance &&
               !on_common_edge(side.faces[i], side.faces[j],
                               gp_Pnt((nearest[i].XYZ() + nearest[j].XYZ()) * 0.5));
    if (!meet) return false;
  }
  return true;
}

namespace {

// Whether the CAD's faces a and b meet where they share no edge, within `tolerance`.
bool faces_meet(const Shape& s, int a, int b, double tolerance) {
  // Whether an edge of face x that is not one of face y's runs on face y: its points at 1/4,
  // 1/2 and 3/4 within `tolerance` of it.
  auto edge_on = [&](int x, int y) {
    const TopoDS_Face& fa = TopoDS::Face(s.faces(x + 1));
    const TopoDS_Face& fb = TopoDS::Face(s.faces(y + 1));
    for (TopExp_Explorer ex(fa, TopAbs_EDGE); ex.More(); ex.Next()) {
      if (edge_bounds(s, s.edges.FindIndex(ex.Current()) - 1, y) ||
          BRep_Tool::Degenerated(TopoDS::Edge(ex.Current())))
        continue;
      const BRepAdaptor_Curve curve(TopoDS::Edge(ex.Current()));
      bool on = true;
      for (double f : {0.5, 0.25, 0.75}) {
        const gp_Pnt p = curve.Value(curve.FirstParameter() +
                                     f * (curve.LastParameter() - curve.FirstParameter()));
        BRepExtrema_DistShapeShape distance(BRepBuilderAPI_MakeVertex(p).Vertex(), fb);
        on = distance.IsDone() && distance.Value() <= tolerance;
        if (!on) break;
      }
      if (on) return true;
    }
    return false;
  };
  // Whether faces x and y, which share no vertex, touch: come within `tolerance` of each other
  // (a solid's surface touching itself at a point or along a curve that is no edge of it).
  auto touch = [&](int x, int y) {
    const TopoDS_Face& fa = TopoDS::Face(s.faces(x + 1));
    const TopoDS_Face& fb = TopoDS::Face(s.faces(y + 1));
    TopTools_MapOfShape vertices_of_b;  // by TopoDS_Shape::IsSame
    for (TopExp_Explorer ex(fb, TopAbs_VERTEX); ex.More(); ex.Next())
      vertices_of_b.Add(ex.Current());
    for (TopExp_Explorer ex(fa, TopAbs_VERTEX); ex.More(); ex.Next())
      if (vertices_of_b.Contains(ex.Current())) return false;
    BRepExtrema_DistShapeShape distance(fa, fb);
    return distance.IsDone() && distance.Value() <= tolerance;
  };
  return a != b && (edge_on(a, b) || edge_on(b, a) || touch(a, b));
}

// The faces of crossing c, the smaller first.
std::pair<int, int> faces_of(const std::vector<SurfaceTriangle>& triangles, const Crossing& c) {
  return std::minmax(triangles[c.first].face, triangles[c.second].face);
}

}  // namespace

bool any_faces_meet(const Shape& s, const std::vector<SurfaceTriangle>& triangles,
                    const std::vector<Crossing>& crossings, double tolerance) {
  return std::any_of(crossings.begin(), crossings.end(), [&](const Crossing& c) {
    const auto [a, b] = faces_of(triangles, c);
    return faces_meet(s, a, b, tolerance);
  });
}

std::string describe_crossings(const Shape& s, const std::vector<Vec3>& nodes,
                               const std::vector<SurfaceTriangle>& triangles,
                               const std::vector<Crossing>& crossings, double tolerance,
                               const std::vector<std::string>& face_names, bool& cad_at_fault) {
  cad_at_fault = false;
  // The pairs of faces (one crossing each, the smaller face first) whose CAD faces meet first,
  // then the others, in the faces' order.
  struct Pair {
    bool apart;
    std::pair<int, int> faces;
    Crossing crossing;
  };
  std::vector<Pair> order;
  for (const Crossing& c : crossings) {
    const auto [a, b] = faces_of(triangles, c);
    const bool meet = faces_meet(s, a, b, tolerance);
    cad_at_fault = cad_at_fault || meet;
    order.push_back({!meet, {a, b}, c});
  }
  std::sort(order.begin(), order.end(), [](const Pair& x, const Pair& y) {
    return std::tie(x.apart, x.faces) < std::tie(y.apart, y.faces);
  });
  const auto meeting = static_cast<std::size_t>(
      std::count_if(order.begin(), order.end(), [](const Pair& o) { return !o.apart; }));
  std::ostringstream text;
  text.precision(6);
  std::size_t listed = 0;
  for (const auto& [apart, faces, c] : order) {
    if (listed == kListed) {
      text << "; and " << order.size() - listed << " more pairs of faces";
      if (meeting > listed) text << ", " << meeting - listed << " of them meeting";
      break;
    }
    const auto [a, b] = faces;
    const Vec3 at =
        (centroid(nodes, triangles[c.first]) + centroid(nodes, triangles[c.second])) * 0.5;
    text << (listed ? "; " : "") << face_names[a];
    if (a != b) text << " and " << face_names[b];
    text << " near (" << at.x << ", " << at.y << ", " << at.z << ")";
    if (!apart) text << " (meeting there)";
    ++listed;
  }
  return text.str();
}

}  // namespace hexmerge::mesher
