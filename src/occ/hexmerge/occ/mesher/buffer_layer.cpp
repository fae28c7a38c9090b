// CGAL before OpenCASCADE: OCCT's Handle() macro breaks CGAL's headers.
#include "hexmerge/occ/mesher/buffer_layer.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface_check.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge::mesher {

namespace {

// A top lies at least kLowest h and at most kHighest h from its base's corner, within kTilt
// degrees of the base's normal. The hexahedron meets the recombination's defaults
// (RecombineParameters: min_scaled_jacobian, its quad faces' folds inside the shape and on its
// surface, max_face_angle), or it is not found (a chord quad of a curved face folds by about its
// width over the radius; a cylinder's quads between two of its lines do not); a side pyramid
// keeps kCorePyramidFloor.
constexpr double kLowest = 0.15;
constexpr double kHighest = 1.5;
constexpr double kTilt = 35.0;
// Their tets (the lattice's split) keep kTetFloor, the mesher's floor for the tets it makes:
// where the recombination does not take a hexahedron or pyramid, its tets stay.
constexpr double kTetFloor = 0.2;
// Tops lie at least kEdgeClearance h inside their face's edges, and the face's inner nodes
// nearer than kNodeClearance h to a top's quad go (the triangles between are no needles).
constexpr double kEdgeClearance = 0.3;
constexpr double kNodeClearance = 0.35;
// A face triangulated again keeps its area to this fraction, and no new triangle's smallest
// angle falls under the smaller of kLeastAngle degrees and the face's own smallest.
constexpr double kAreaChange = 0.02;
// A top's quad is a chord of its face: its middle at most kSagitta h off the face's triangles.
constexpr double kSagitta = 0.05;
constexpr double kLeastAngle = 15.0;

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using FaceInfo = CGAL::Triangulation_face_base_with_info_2<signed char, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceInfo>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::No_constraint_intersection_tag>;

using P2 = std::array<double, 2>;

double cross2(const P2& a, const P2& b, const P2& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}
double distance2(const P2& a, const P2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }
// Distance from p to segment ab.
double to_segment(const P2& p, const P2& a, const P2& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return distance2(p, {a[0] + t * dx, a[1] + t * dy});
}
// Whether segments ab and cd cross or touch.
bool segments_meet(const P2& a, const P2& b, const P2& c, const P2& d) {
  const double d1 = cross2(a, b, c), d2 = cross2(a, b, d), d3 = cross2(c, d, a),
               d4 = cross2(c, d, b);
  return ((d1 > 0) != (d2 > 0) || d1 == 0 || d2 == 0) &&
         ((d3 > 0) != (d4 > 0) || d3 == 0 || d4 == 0) &&
         std::min(a[0], b[0]) <= std::max(c[0], d[0]) &&
         std::min(c[0], d[0]) <= std::max(a[0], b[0]) &&
         std::min(a[1], b[1]) <= std::max(c[1], d[1]) &&
         std::min(c[1], d[1]) <= std::max(a[1], b[1]);
}

// Boxes in a chart's plane as BucketGrid's (z = 0): lo and hi of points, grown by `margin` (and a
// hair more, so that a test at exactly the margin still finds them).
std::pair<Vec3, Vec3> plane_box(std::initializer_list<P2> points, double margin) {
  Vec3 lo{points.begin()[0][0], points.begin()[0][1], 0}, hi = lo;
  for (const P2& p : points) {
    lo.x = std::min(lo.x, p[0]), lo.y = std::min(lo.y, p[1]);
    hi.x = std::max(hi.x, p[0]), hi.y = std::max(hi.y, p[1]);
  }
  const double grow = margin * (1 + 1e-9) + 1e-12 * (std::abs(hi.x) + std::abs(hi.y) + 1);
  return {lo - Vec3{grow, grow, 0}, hi + Vec3{grow, grow, 0}};
}
// A grid over the chart's plane of cells about `cell` wide (at most about 1,000 across) holding
// each item's box: items(add) calls add(item, box) for every item.
template <typename Items>
BucketGrid plane_grid(const std::vector<P2>& xy, double cell, const Items& items) {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  if (!xy.empty()) std::tie(lo, hi) = plane_box({xy[0]}, 0);
  for (const P2& p : xy)
    lo.x = std::min(lo.x, p[0]), lo.y = std::min(lo.y, p[1]), hi.x = std::max(hi.x, p[0]),
    hi.y = std::max(hi.y, p[1]);
  BucketGrid grid(lo, hi, std::max({cell, (hi.x - lo.x) / 1000, (hi.y - lo.y) / 1000, 1e-300}));
  items([&](int item, const std::pair<Vec3, Vec3>& box) { grid.add(item, box.first, box.second); });
  return grid;
}

// A base corner's projection onto the surface: its face, parameters and place (frame).
struct Top {
  int face = -1;
  UV uv;
  Vec3 at;
};

// One face's triangles in its parameters scaled by their mean metric (x = a u + b v, y = c v):
// a vertex per node and parameters (a node on the seam is two), its sides used once (its edges
// and seams), and whether its triangles go counter-clockwise.
struct FaceChart {
  int face = -1;
  double a = 1, b = 0, c = 1;
  double u_period = 0, v_period = 0;        // 0: not periodic
  std::vector<int> triangles;               // into the surface's
  std::vector<int> node;                    // per vertex
  std::vector<UV> uv;                       // per vertex
  std::vector<P2> xy;                       // per vertex
  std::vector<std::array<int, 3>> corners;  // per triangle, its vertices
  std::vector<std::array<int, 2>> outline;  // sides used once
  std::vector<char> on_outline;             // per vertex
  bool counter_clockwise = true;
  double area = 0;                          // of its triangles (3D)
  double smallest_angle = 0;                // of its triangles, degrees
  std::optional<BucketGrid> triangle_grid;  // its triangles by their boxes (place_in())

  P2 scaled(const UV& p) const { return {a * p.u + b * p.v, c * p.v}; }
};

// The chart of face `face`, or none when its metric cannot be fitted.
std::optional<FaceChart> chart_of(const Shape& shape, const Surface& surface,
                                  const std::vector<int>& triangles, int face) {
  FaceChart chart;
  chart.face = face;
  chart.triangles = triangles;
  const BRepAdaptor_Surface adaptor(TopoDS::Face(shape.faces(face + 1)));
  if (adaptor.IsUPeriodic()) chart.u_period = adaptor.UPeriod();
  if (adaptor.IsVPeriodic()) chart.v_period = adaptor.VPeriod();
  // The metric (E, F, G) fitted to the triangles' sides by least squares.
  double m[3][3] = {}, r[3] = {};
  for (const int t : triangles) {
    const SurfaceTriangle& tri = surface.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      const double du = tri.uv[l].u - tri.uv[k].u, dv = tri.uv[l].v - tri.uv[k].v;
      const Vec3 side = surface.nodes[static_cast<std::size_t>(tri.node[l])] -
                        surface.nodes[static_cast<std::size_t>(tri.node[k])];
      const double length2 = side.dot(side);
      const double row[3] = {du * du, 2 * du * dv, dv * dv};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m[i][j] += row[i] * row[j];
        r[i] += row[i] * length2;
      }
    }
  }
  const auto det = [](const double(&q)[3][3]) {
    return q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) -
           q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
           q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
  };
  const double d = det(m);
  if (!(std::abs(d) > 0)) return std::nullopt;
  double efg[3];
  for (int i = 0; i < 3; ++i) {
    double q[3][3];
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) q[row][col] = col == i ? r[row] : m[row][col];
    efg[i] = det(q) / d;
  }
  const double e = efg[0], f = efg[1], g = efg[2];
  if (!(e > 0) || !(g > 0) || !(e * g - f * f > 0)) return std::nullopt;
  chart.a = std::sqrt(e), chart.b = f / chart.a, chart.c = std::sqrt(g - chart.b * chart.b);
  // The vertices: a node with its parameters (to 1e-9 of the face's parameter range).
  double range = 0;
  for (const int t : triangles)
    for (const UV& p : surface.triangles[static_cast<std::size_t>(t)].uv)
      range = std::max({range, std::abs(p.u), std::abs(p.v)});
  const double quantum = 1e-9 * std::max(range, 1.0);
  std::map<std::array<long long, 3>, int> vertex;
  int ccw = 0;
  chart.smallest_angle = 180;
  for (const int t : triangles) {
    const SurfaceTriangle& tri = surface.triangles[static_cast<std::size_t>(t)];
    std::array<int, 3> v{};
    for (int k = 0; k < 3; ++k) {
      const std::array<long long, 3> key{tri.node[k], std::llround(tri.uv[k].u / quantum),
                                         std::llround(tri.uv[k].v / quantum)};
      const auto [it, fresh] = vertex.emplace(key, static_cast<int>(chart.node.size()));
      if (fresh) {
        chart.node.push_back(tri.node[k]);
        chart.uv.push_back(tri.uv[k]);
        chart.xy.push_back(chart.scaled(tri.uv[k]));
      }
      v[k] = it->second;
    }
    chart.corners.push_back(v);
    ccw += cross2(chart.xy[v[0]], chart.xy[v[1]], chart.xy[v[2]]) > 0 ? 1 : -1;
    const Vec3 &p0 = surface.nodes[static_cast<std::size_t>(tri.node[0])],
               &p1 = surface.nodes[static_cast<std::size_t>(tri.node[1])],
               &p2 = surface.nodes[static_cast<std::size_t>(tri.node[2])];
    chart.area += 0.5 * (p1 - p0).cross(p2 - p0).norm();
    chart.smallest_angle = std::min(chart.smallest_angle, smallest_angle(p0, p1, p2) * 180 / M_PI);
  }
  chart.counter_clockwise = ccw >= 0;
  std::map<std::pair<int, int>, int> uses;
  for (const auto& v : chart.corners)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(v[k], v[(k + 1) % 3])];
  chart.on_outline.assign(chart.node.size(), 0);
  for (const auto& [side, count] : uses)
    if (count == 1) {
      chart.outline.push_back({side.first, side.second});
      chart.on_outline[static_cast<std::size_t>(side.first)] = 1;
      chart.on_outline[static_cast<std::size_t>(side.second)] = 1;
    }
  // (Cells about a triangle wide; boxes grown by a millionth of their size: place_in() takes a
  // point up to 1e-9 outside.)
  double area2 = 0;
  for (const auto& v : chart.corners)
    area2 += std::abs(cross2(chart.xy[static_cast<std::size_t>(v[0])],
                             chart.xy[static_cast<std::size_t>(v[1])],
                             chart.xy[static_cast<std::size_t>(v[2])]));
  const double cell =
      std::sqrt(area2 / static_cast<double>(std::max<std::size_t>(chart.corners.size(), 1)));
  chart.triangle_grid = plane_grid(chart.xy, cell, [&](const auto& add) {
    for (std::size_t t = 0; t < chart.corners.size(); ++t) {
      const auto& v = chart.corners[t];
      const P2 &a = chart.xy[static_cast<std::size_t>(v[0])],
               &b = chart.xy[static_cast<std::size_t>(v[1])],
               &c = chart.xy[static_cast<std::size_t>(v[2])];
      const auto [lo, hi] = plane_box({a, b, c}, 0);
      add(static_cast<int>(t), plane_box({a, b, c}, 1e-6 * (hi - lo).norm()));
    }
  });
  return chart;
}

// The scaled parameters of uv inside the chart's triangles (shifted by whole periods where the
// face is periodic), or none.
std::optional<P2> place_in(const FaceChart& chart, UV& uv) {
  for (int su = -1; su <= 1; ++su) {
    if (su != 0 && chart.u_period == 0) continue;
    for (int sv = -1; sv <= 1; ++sv) {
      if (sv != 0 && chart.v_period == 0) continue;
      const UV shifted{uv.u + su * chart.u_period, uv.v + sv * chart.v_period};
      const P2 p = chart.scaled(shifted);
      const auto [lo, hi] = plane_box({p}, 0);
      if (chart.triangle_grid->any_in(lo, hi, [&](int t) {
            const auto& v = chart.corners[static_cast<std::size_t>(t)];
            const P2 &a = chart.xy[v[0]], &b = chart.xy[v[1]], &c = chart.xy[v[2]];
            const double whole = cross2(a, b, c);
            if (whole == 0) return false;
            const double l0 = cross2(p, b, c) / whole, l1 = cross2(a, p, c) / whole,
                         l2 = cross2(a, b, p) / whole;
            return l0 >= -1e-9 && l1 >= -1e-9 && l2 >= -1e-9;
          })) {
        uv = shifted;
        return p;
      }
    }
  }
  return std::nullopt;
}

// A face triangulated again: its triangles (nodes: the surface's, or -1 - k for the k-th top)
// and their parameters.
struct Retriangulated {
  std::vector<std::array<int, 3>> node;
  std::vector<std::array<UV, 3>> uv;
};

// The chart's face triangulated again with the quads `quads` (tops by index into `tops`, around
// as the bases' corners, split on the diagonal from the first to the third) in it, or none.
std::optional<Retriangulated> retriangulate(const FaceChart& chart, const Surface& surface,
                                            const std::vector<std::array<int, 4>>& quads,
                                            const std::vector<P2>& top_xy,
                                            const std::vector<UV>& top_uv,
                                            const std::vector<Vec3>& top_world,
                                            const std::vector<char>& node_elsewhere, double h) {
  // The face's inner vertices near a quad go; one that another face uses too stays, and then
  // the face gets no tops.
  const std::size_t nv = chart.node.size();
  std::vector<char> gone(nv, 0);
  // The quads by their boxes grown by the clearance: those a vertex may be near or in.
  const BucketGrid near_quads = plane_grid(chart.xy, h, [&](const auto& add) {
    for (std::size_t i = 0; i < quads.size(); ++i) {
      const auto& q = quads[i];
      const auto at = [&](int k) { return top_xy[static_cast<std::size_t>(q[k])]; };
      add(static_cast<int>(i), plane_box({at(0), at(1), at(2), at(3)}, kNodeClearance * h));
    }
  });
  for (std::size_t v = 0; v < nv; ++v) {
    if (chart.on_outline[v]) continue;
    const P2& p = chart.xy[v];
    const auto [lo, hi] = plane_box({p}, 0);
    bool elsewhere = false;
    near_quads.any_in(lo, hi, [&](int i) {
      const auto& q = quads[static_cast<std::size_t>(i)];
      const bool turn =
          cross2(top_xy[static_cast<std::size_t>(q[0])], top_xy[static_cast<std::size_t>(q[1])],
                 top_xy[static_cast<std::size_t>(q[2])]) > 0;
      bool inside = true;
      for (int k = 0; k < 4 && inside; ++k) {
        const P2 &a = top_xy[static_cast<std::size_t>(q[k])],
                 &b = top_xy[static_cast<std::size_t>(q[(k + 1) % 4])];
        inside = (cross2(a, b, p) > 0) == turn;
      }
      bool near = inside;
      for (int k = 0; k < 4 && !near; ++k)
        near = to_segment(p, top_xy[static_cast<std::size_t>(q[k])],
                          top_xy[static_cast<std::size_t>(q[(k + 1) % 4])]) < kNodeClearance * h;
      if (!near) return false;
      elsewhere = node_elsewhere[static_cast<std::size_t>(chart.node[v])];
      gone[v] = 1;
      return true;
    });
    if (elsewhere) return std::nullopt;
  }
  Cdt cdt;
  std::vector<Cdt::Vertex_handle> handle(nv + top_xy.size());
  std::size_t inserted = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (gone[v]) continue;
    handle[v] = cdt.insert(Kernel::Point_2(chart.xy[v][0], chart.xy[v][1]));
    handle[v]->info() = static_cast<int>(v);
    ++inserted;
  }
  std::vector<char> used_top(top_xy.size(), 0);
  for (const auto& q : quads)
    for (const int t : q) used_top[static_cast<std::size_t>(t)] = 1;
  for (std::size_t t = 0; t < top_xy.size(); ++t) {
    if (!used_top[t]) continue;
    handle[nv + t] = cdt.insert(Kernel::Point_2(top_xy[t][0], top_xy[t][1]));
    handle[nv + t]->info() = static_cast<int>(nv + t);
    ++inserted;
  }
  if (cdt.number_of_vertices() != inserted) return std::nullopt;  // two at one place
  std::set<std::pair<int, int>> outline;
  try {
    for (const auto& side : chart.outline) {
      if (gone[static_cast<std::size_t>(side[0])] || gone[static_cast<std::size_t>(side[1])])
        return std::nullopt;
      cdt.insert_constraint(handle[static_cast<std::size_t>(side[0])],
                            handle[static_cast<std::size_t>(side[1])]);
      outline.insert(std::minmax(side[0], side[1]));
    }
    std::set<std::pair<int, int>> sides;  // each once
    for (const auto& q : quads)
      for (const auto& [a, b] : {std::pair<int, int>{q[0], q[1]}, std::pair<int, int>{q[1], q[2]},
                                 std::pair<int, int>{q[2], q[3]}, std::pair<int, int>{q[3], q[0]},
                                 std::pair<int, int>{q[0], q[2]}})
        if (sides.insert(std::minmax(a, b)).second)
          cdt.insert_constraint(handle[nv + static_cast<std::size_t>(a)],
                                handle[nv + static_cast<std::size_t>(b)]);
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    return std::nullopt;
  }
  if (cdt.number_of_vertices() != inserted) return std::nullopt;
  // Inside: reached from outside across an odd number of the outline's sides.
  for (Cdt::Face_handle f : cdt.all_face_handles()) f->info() = -1;
  std::vector<Cdt::Face_handle> stack;
  for (Cdt::Face_handle f : cdt.all_face_handles())
    if (cdt.is_infinite(f)) f->info() = 0, stack.push_back(f);
  while (!stack.empty()) {
    const Cdt::Face_handle f = stack.back();
    stack.pop_back();
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle next = f->neighbor(i);
      const Cdt::Vertex_handle a = f->vertex(Cdt::cw(i)), b = f->vertex(Cdt::ccw(i));
      const bool crossing = !cdt.is_infinite(a) && !cdt.is_infinite(b) && f->is_constrained(i) &&
                            outline.count(std::minmax(a->info(), b->info()));
      const signed char state = static_cast<signed char>(crossing ? 1 - f->info() : f->info());
      if (next->info() == -1) {
        next->info() = state;
        stack.push_back(next);
      } else if (next->info() != state) {
        return std::nullopt;  // the outline does not bound a region
      }
    }
  }
  // The new triangles, in the face's orientation; each quad's two among them.
  const auto world = [&](int v) {
    return v < static_cast<int>(nv)
               ? surface.nodes[static_cast<std::size_t>(chart.node[static_cast<std::size_t>(v)])]
               : top_world[static_cast<std::size_t>(v) - nv];
  };
  Retriangulated out;
  std::set<std::array<int, 3>> made;
  double area = 0, smallest = 180;
  for (Cdt::Face_handle f : cdt.finite_face_handles()) {
    if (f->info() != 1) continue;
    std::array<int, 3> v{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    if (!chart.counter_clockwise) std::swap(v[1], v[2]);
    std::array<int, 3> node{};
    std::array<UV, 3> uv;
    for (int k = 0; k < 3; ++k) {
      const auto w = static_cast<std::size_t>(v[k]);
      node[k] = w < nv ? chart.node[w] : -1 - static_cast<int>(w - nv);
      uv[k] = w < nv ? chart.uv[w] : top_uv[w - nv];
    }
    const Vec3 p0 = world(v[0]), p1 = world(v[1]), p2 = world(v[2]);
    area += 0.5 * (p1 - p0).cross(p2 - p0).norm();
    smallest = std::min(smallest, smallest_angle(p0, p1, p2) * 180 / M_PI);
    std::array<int, 3> key = v;
    std::sort(key.begin(), key.end());
    made.insert(key);
    out.node.push_back(node);
    out.uv.push_back(uv);
  }
  for (const auto& q : quads)
    for (const std::array<int, 3> t :
         {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      std::array<int, 3> key{static_cast<int>(nv) + t[0], static_cast<int>(nv) + t[1],
                             static_cast<int>(nv) + t[2]};
      std::sort(key.begin(), key.end());
      if (!made.count(key)) return std::nullopt;
    }
  if (std::abs(area - chart.area) > kAreaChange * chart.area) return std::nullopt;
  if (smallest < std::min(kLeastAngle, chart.smallest_angle)) return std::nullopt;
  return out;
}

// The hexahedron of base corners b (base_corners() order, the base facing +axis when `up`) and
// tops t, in cell_type.h's order: its scaled Jacobian.
double hex_quality(const std::array<Vec3, 4>& b, const std::array<Vec3, 4>& t, bool up) {
  double xyz[24];
  for (int m = 0; m < 4; ++m) {
    xyz[3 * m] = b[m].x, xyz[3 * m + 1] = b[m].y, xyz[3 * m + 2] = b[m].z;
    xyz[12 + 3 * m] = t[m].x, xyz[13 + 3 * m] = t[m].y, xyz[14 + 3 * m] = t[m].z;
  }
  static const index_t kUp[8] = {0, 1, 2, 3, 4, 5, 6, 7}, kDown[8] = {0, 3, 2, 1, 4, 7, 6, 5};
  return scaled_jacobian(CellType::Hex, xyz, up ? kUp : kDown);
}

double tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double xyz[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
  static const index_t kTet[4] = {0, 1, 2, 3};
  return scaled_jacobian(CellType::Tet, xyz, kTet);
}

// The smallest scaled Jacobian of the six tets around the hexahedron's diagonal from its base's
// first corner to its top's third (base corners b in base_corners() order, the base facing +axis
// when `up`; the bits u, v swapped when not, as emit_core() splits it), each taken positive.
double worst_split_tet(const std::array<Vec3, 4>& b, const std::array<Vec3, 4>& t, bool up) {
  const std::array<Vec3, 8> corner = buffer_hex_corners(b, t, up);
  double worst = 1;
  for (const auto& q : kKuhnPaths)
    worst =
        std::min(worst, std::abs(tet_quality(corner[0], corner[q[0]], corner[q[1]], corner[7])));
  return worst;
}

// Whether quad abcd (around) has a dihedral angle of at least `dihedral` degrees across either
// diagonal and no corner wider than `widest` degrees.
bool flat_enough(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double dihedral,
                 double widest) {
  const double pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z}, pc[3] = {c.x, c.y, c.z},
               pd[3] = {d.x, d.y, d.z};
  return quad_dihedral_angle(pa, pb, pc, pd) >= dihedral &&
         quad_dihedral_angle(pb, pc, pd, pa) >= dihedral &&
         quad_max_corner_angle(pa, pb, pc, pd) <= widest;
}

// The pyramid of base corners q (around) and apex: its scaled Jacobian, the base taken round
// whichever way puts the apex on its inner side.
double pyramid_quality(const std::array<Vec3, 4>& q, const Vec3& apex) {
  return closing_pyramid_quality(q, apex, det3(q[1] - q[0], q[2] - q[0], apex - q[0]) > 0);
}

std::uint64_t edge_key(std::size_t a, std::size_t b) {
  return pair_key(static_cast<int>(std::min(a, b)), static_cast<int>(std::max(a, b)));
}

}  // namespace

BufferCells buffer_layer(const Shape& shape, const Lattice& lattice, const CoreLayout& layout,
                         const std::vector<Vec3>& nodes, const Surroundings& around,
                         const std::vector<char>& eligible, double h, Surface& surface,
                         BufferReport& report) {
  BufferCells out;
  const std::vector<PyramidFace>& faces = layout.pyramid_faces;
  if (faces.empty()) return out;
  const auto cell_of = [&](const int(&c)[3]) {
    return (static_cast<std::size_t>(c[2]) * lattice.cells[1] + c[1]) * lattice.cells[0] + c[0];
  };
  // 1. The bases whose pyramid's apex closes no other base.
  std::unordered_map<std::size_t, int> at_apex;
  for (const PyramidFace& f : faces) ++at_apex[cell_of(f.n)];
  // 2. The base corners' projections onto the nearest face: the nearest point of the surface's
  // triangles, then Newton's method on the face's surface from its parameters there.
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(
      static_cast<std::size_t>(shape.faces.Extent()));
  std::unordered_map<std::size_t, std::optional<Top>> top_cache;
  const auto top_of = [&](std::size_t p) -> const std::optional<Top>& {
    const auto found = top_cache.find(p);
    if (found != top_cache.end()) return found->second;
    std::optional<Top>& top = top_cache[p];
    const Vec3 q = layout.point_at(lattice, p);
    int nearest = -1;
    double best = kHighest * h * kHighest * h;
    around.every_face.any_within(q, kHighest * h, [&](int i) {
      const SurfaceTriangle& t = surface.triangles[static_cast<std::size_t>(i)];
      const double d2 = squared_distance_to_triangle(q, nodes[static_cast<std::size_t>(t.node[0])],
                                                     nodes[static_cast<std::size_t>(t.node[1])],
                                                     nodes[static_cast<std::size_t>(t.node[2])]);
      if (d2 < best) best = d2, nearest = i;
      return false;
    });
    if (nearest < 0) return top;
    const SurfaceTriangle& t = surface.triangles[static_cast<std::size_t>(nearest)];
    if (!eligible[static_cast<std::size_t>(t.face)]) return top;
    const int its_face = t.face;
    double s = 0, r = 0;
    const Vec3 on = nearest_on_triangle(q, nodes[static_cast<std::size_t>(t.node[0])],
                                        nodes[static_cast<std::size_t>(t.node[1])],
                                        nodes[static_cast<std::size_t>(t.node[2])], s, r);
    std::unique_ptr<ShapeAnalysis_Surface>& a = analysis[static_cast<std::size_t>(t.face)];
    if (!a)
      a = std::make_unique<ShapeAnalysis_Surface>(
          BRep_Tool::Surface(TopoDS::Face(shape.faces(t.face + 1))));
    const UV guess{t.uv[0].u + s * (t.uv[1].u - t.uv[0].u) + r * (t.uv[2].u - t.uv[0].u),
                   t.uv[0].v + s * (t.uv[1].v - t.uv[0].v) + r * (t.uv[2].v - t.uv[0].v)};
    const Vec3 world = lattice.frame.to_world(q);
    const gp_Pnt2d found_uv = a->NextValueOfUV(gp_Pnt2d(guess.u, guess.v),
                                               gp_Pnt(world.x, world.y, world.z), 1e-7 * h, -1.0);
    const Vec3 at = lattice.frame.to_frame(of(a->Value(found_uv)));
    if ((at - on).norm() > 0.1 * h) return top;  // Newton went elsewhere
    // Clear of the other faces (across a thin wall or a concave edge), as of its face's edges.
    if (around.every_face.any_within(at, kEdgeClearance * h, [&](int i) {
          return surface.triangles[static_cast<std::size_t>(i)].face != its_face;
        }))
      return top;
    top = Top{t.face, UV{found_uv.X(), found_uv.Y()}, at};
    return top;
  };
  // 3. The hexahedra each base could have.
  const RecombineParameters recombine;
  const double tilt = std::cos(kTilt * M_PI / 180);
  std::vector<char> chosen(faces.size(), 0);
  std::vector<std::array<std::size_t, 4>> base_of(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const PyramidFace& f = faces[i];
    if (at_apex[cell_of(f.n)] != 1) continue;
    // The cell across is beside no other core cell (one on the boundary needs no pyramid).
    bool alone = true;
    for (int dir = 0; dir < 6 && alone; ++dir) {
      int n[3] = {f.n[0], f.n[1], f.n[2]};
      n[dir / 2] += dir % 2 ? 1 : -1;
      if (n[0] == f.c[0] && n[1] == f.c[1] && n[2] == f.c[2]) continue;
      alone = n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= lattice.cells[0] ||
              n[1] >= lattice.cells[1] || n[2] >= lattice.cells[2] || !layout.core[cell_of(n)];
    }
    if (!alone) continue;
    base_of[i] = base_corners(lattice, f);
    const int axis = f.dir / 2;
    Vec3 normal{0, 0, 0};
    set_coord(normal, axis, f.dir % 2 ? 1.0 : -1.0);
    std::array<Vec3, 4> b, t;
    int face = -1;
    bool ok = true;
    for (int m = 0; m < 4 && ok; ++m) {
      const std::optional<Top>& top = top_of(base_of[i][m]);
      if (!top || (face >= 0 && top->face != face)) {
        ok = false;
        break;
      }
      face = top->face;
      b[m] = layout.point_at(lattice, base_of[i][m]);
      t[m] = top->at;
      const Vec3 d = t[m] - b[m];
      const double length = d.norm();
      ok = length >= kLowest * h && length <= kHighest * h && d.dot(normal) >= tilt * length;
    }
    ok = ok && hex_quality(b, t, f.dir % 2 == 1) >= recombine.min_scaled_jacobian &&
         worst_split_tet(b, t, f.dir % 2 == 1) >= kTetFloor &&
         flat_enough(t[0], t[1], t[2], t[3], recombine.min_boundary_dihedral_angle,
                     recombine.max_face_angle);
    for (int m = 0; m < 4 && ok; ++m)
      ok = flat_enough(b[m], b[(m + 1) % 4], t[(m + 1) % 4], t[m], recombine.min_dihedral_angle,
                       recombine.max_face_angle);
    if (ok) chosen[i] = 1;
  }
  // 4. Per face, its chart; the tops placed in it, clear of its edges.
  std::unordered_map<int, std::vector<int>> face_triangles;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    face_triangles[surface.triangles[t].face].push_back(static_cast<int>(t));
  std::map<int, FaceChart> charts;
  std::map<int, BucketGrid> outline_grids;  // per chart, its outline's sides by their boxes
  std::unordered_map<std::size_t, P2> top_xy;
  std::unordered_map<std::size_t, UV> top_uv;
  const auto face_of = [&](std::size_t i) { return top_of(base_of[i][0])->face; };
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!chosen[i]) continue;
    const int face = face_of(i);
    auto it = charts.find(face);
    if (it == charts.end()) {
      std::optional<FaceChart> chart = chart_of(shape, surface, face_triangles[face], face);
      if (!chart) {
        chosen[i] = 0;
        continue;
      }
      it = charts.emplace(face, std::move(*chart)).first;
      const FaceChart& made = it->second;
      outline_grids.emplace(
          face, plane_grid(made.xy, h, [&](const auto& add) {
            for (std::size_t s = 0; s < made.outline.size(); ++s)
              add(static_cast<int>(s),
                  plane_box({made.xy[static_cast<std::size_t>(made.outline[s][0])],
                             made.xy[static_cast<std::size_t>(made.outline[s][1])]},
                            0));
          }));
    }
    const FaceChart& chart = it->second;
    const BucketGrid& outline_grid = outline_grids.at(face);
    // The sides of the outline whose boxes come within `margin` of the points' box: f(side)
    // until it returns true; whether it did.
    const auto any_side_near = [&](std::initializer_list<P2> points, double margin, const auto& f) {
      const auto [lo, hi] = plane_box(points, margin);
      return outline_grid.any_in(lo, hi, [&](int s) {
        return f(chart.xy[static_cast<std::size_t>(chart.outline[static_cast<std::size_t>(s)][0])],
                 chart.xy[static_cast<std::size_t>(chart.outline[static_cast<std::size_t>(s)][1])]);
      });
    };
    std::array<P2, 4> xy;
    for (int m = 0; m < 4 && chosen[i]; ++m) {
      const std::size_t p = base_of[i][m];
      if (!top_xy.count(p)) {
        UV uv = top_of(p)->uv;
        const std::optional<P2> placed = place_in(chart, uv);
        const bool clear =
            placed.has_value() &&
            !any_side_near({*placed}, kEdgeClearance * h, [&](const P2& a, const P2& b) {
              return !(to_segment(*placed, a, b) >= kEdgeClearance * h);
            });
        if (!clear) {
          chosen[i] = 0;
          break;
        }
        top_xy[p] = *placed;
        top_uv[p] = uv;
      }
      xy[m] = top_xy[p];
    }
    if (!chosen[i]) continue;
    // The quad in the chart: its two triangles turning the same way, its sides crossing no edge
    // and passing the edges' nodes at half the clearance.
    const double s0 = cross2(xy[0], xy[1], xy[2]), s1 = cross2(xy[0], xy[2], xy[3]);
    bool ok = s0 != 0 && (s0 > 0) == (s1 > 0);
    for (int k = 0; k < 4 && ok; ++k)
      ok = !any_side_near(
          {xy[k], xy[(k + 1) % 4]}, 0.5 * kEdgeClearance * h, [&](const P2& a, const P2& b) {
            return !(!segments_meet(xy[k], xy[(k + 1) % 4], a, b) &&
                     to_segment(a, xy[k], xy[(k + 1) % 4]) >= 0.5 * kEdgeClearance * h);
          });
    if (ok) {
      Vec3 middle{0, 0, 0};
      for (int m = 0; m < 4; ++m) middle = middle + top_of(base_of[i][m])->at * 0.25;
      ok = around.every_face.any_within(middle, kSagitta * h);
    }
    if (!ok) chosen[i] = 0;
  }
  // The quads of one face lie side by side: a quad whose sides or diagonal cross those of one
  // taken before on its face, or that holds a corner of one or has a corner in one, goes.
  {
    struct Taken {
      std::array<std::size_t, 4> top;
      std::array<P2, 4> xy;
      P2 lo, hi;
    };
    std::map<int, std::vector<Taken>> taken;
    const auto strictly_inside = [](const P2& p, const std::array<P2, 4>& q) {
      const bool turn = cross2(q[0], q[1], q[2]) > 0;
      for (int k = 0; k < 4; ++k) {
        const double side = cross2(q[k], q[(k + 1) % 4], p);
        if (side == 0 || (side > 0) != turn) return false;
      }
      return true;
    };
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (!chosen[i]) continue;
      Taken quad;
      for (int m = 0; m < 4; ++m)
        quad.top[m] = base_of[i][m], quad.xy[m] = top_xy.at(base_of[i][m]);
      quad.lo = quad.hi = quad.xy[0];
      for (const P2& p : quad.xy)
        for (int a = 0; a < 2; ++a)
          quad.lo[a] = std::min(quad.lo[a], p[a]), quad.hi[a] = std::max(quad.hi[a], p[a]);
      // Its sides and diagonal, by their tops.
      const int segment[5][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}};
      bool ok = true;
      for (const Taken& other : taken[face_of(i)]) {
        if (!ok) break;
        if (other.hi[0] < quad.lo[0] || quad.hi[0] < other.lo[0] || other.hi[1] < quad.lo[1] ||
            quad.hi[1] < other.lo[1])
          continue;
        for (int m = 0; m < 4 && ok; ++m) {
          const bool shared =
              std::find(other.top.begin(), other.top.end(), quad.top[m]) != other.top.end();
          ok = shared || !strictly_inside(quad.xy[m], other.xy);
          const bool theirs_shared =
              std::find(quad.top.begin(), quad.top.end(), other.top[m]) != quad.top.end();
          ok = ok && (theirs_shared || !strictly_inside(other.xy[m], quad.xy));
        }
        for (const auto& s : segment)
          for (const auto& t : segment) {
            if (!ok) break;
            const std::size_t a = quad.top[s[0]], b = quad.top[s[1]], c = other.top[t[0]],
                              d = other.top[t[1]];
            if (a == c || a == d || b == c || b == d) continue;  // they meet at a top
            ok = !segments_meet(quad.xy[s[0]], quad.xy[s[1]], other.xy[t[0]], other.xy[t[1]]);
          }
      }
      if (ok)
        taken[face_of(i)].push_back(quad);
      else
        chosen[i] = 0;
    }
  }
  // The corners of base i (base_of is filled for the bases whose apex closes no other).
  const auto base_of_face = [&](std::size_t i) { return base_corners(lattice, faces[i]); };
  // Per base side (its two lattice points), the bases that have it.
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> side_bases;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::array<std::size_t, 4> b = base_corners(lattice, faces[i]);
    for (int m = 0; m < 4; ++m) side_bases[edge_key(b[m], b[(m + 1) % 4])].push_back(i);
  }
  // 5. The side pyramids, the hexahedra that cannot have them dropped, until none drops; then
  // each face with tops triangulated again, a face where that fails losing its hexahedra, and
  // again. (The surface nodes any other face uses stay.)
  std::vector<char> node_elsewhere(surface.nodes.size(), 0);
  {
    std::vector<int> first_face(surface.nodes.size(), -1);
    for (const SurfaceTriangle& t : surface.triangles)
      for (const int n : t.node) {
        int& f = first_face[static_cast<std::size_t>(n)];
        if (f < 0) f = t.face;
        if (f != t.face) node_elsewhere[static_cast<std::size_t>(n)] = 1;
      }
  }
  std::vector<BufferCells::SidePyramid> pyramids;
  const auto close_sides = [&]() {
    for (bool dropped = true; dropped;) {
      dropped = false;
      pyramids.clear();
      for (std::size_t i = 0; i < faces.size(); ++i) {
        if (!chosen[i]) continue;
        for (int m = 0; m < 4 && chosen[i]; ++m) {
          const std::size_t p = base_of[i][m], q = base_of[i][(m + 1) % 4];
          const std::vector<std::size_t>& having = side_bases[edge_key(p, q)];
          if (having.size() != 2) {  // the core touches itself along the side
            chosen[i] = 0;
            break;
          }
          const std::size_t other = having[0] == i ? having[1] : having[0];
          if (chosen[other]) continue;
          const std::size_t apex_cell = cell_of(faces[other].n);
          const std::size_t lo = std::min(p, q), hi = std::max(p, q);
          const std::array<Vec3, 4> side{layout.point_at(lattice, lo), layout.point_at(lattice, hi),
                                         top_of(hi)->at, top_of(lo)->at};
          const Vec3 apex = layout.apex_at(lattice, apex_cell);
          if (pyramid_quality(side, apex) < kCorePyramidFloor ||
              std::abs(tet_quality(side[0], side[1], side[2], apex)) < kTetFloor ||
              std::abs(tet_quality(side[0], side[2], side[3], apex)) < kTetFloor) {
            chosen[i] = 0;
            break;
          }
          pyramids.push_back({lo, hi, apex_cell});
        }
        dropped = dropped || !chosen[i];
      }
    }
  };
  // Steps 5 to 7 again from the surface as it was while step 7 drops a hexahedron (its quad
  // left in the face, the tets on it flat).
  const Surface original = surface;
  std::unordered_map<std::size_t, int> top_node;  // per lattice point, its top's node
  std::vector<Vec3> frame_points;                 // the surface's nodes, frame coordinates
  std::map<int, Retriangulated> remeshed;
  for (bool again = true; again;) {
    again = false;
    surface = original;
    for (bool failed = true; failed;) {
      failed = false;
      close_sides();
      remeshed.clear();
      std::map<int, std::vector<std::size_t>> on_face;
      for (std::size_t i = 0; i < faces.size(); ++i)
        if (chosen[i]) on_face[face_of(i)].push_back(i);
      for (const auto& [face, bases] : on_face) {
        std::unordered_map<std::size_t, int> index;
        std::vector<P2> xy;
        std::vector<UV> uv;
        std::vector<Vec3> world;
        std::vector<std::array<int, 4>> quads;
        for (const std::size_t i : bases) {
          std::array<int, 4> q{};
          for (int m = 0; m < 4; ++m) {
            const std::size_t p = base_of[i][m];
            const auto [it, fresh] = index.emplace(p, static_cast<int>(xy.size()));
            if (fresh) {
              xy.push_back(top_xy.at(p));
              uv.push_back(top_uv.at(p));
              world.push_back(lattice.frame.to_world(top_of(p)->at));
            }
            q[m] = it->second;
          }
          quads.push_back(q);
        }
        std::optional<Retriangulated> made =
            retriangulate(charts.at(face), surface, quads, xy, uv, world, node_elsewhere, h);
        if (!made) {
          for (const std::size_t i : bases) chosen[i] = 0;
          failed = true;
          continue;
        }
        // Tops by lattice point: -1 - k is the k-th of this face's.
        std::vector<std::size_t> point(index.size());
        for (const auto& [p, k] : index) point[static_cast<std::size_t>(k)] = p;
        for (auto& t : made->node)
          for (int& n : t)
            if (n < 0) n = -1 - static_cast<int>(point[static_cast<std::size_t>(-1 - n)]);
        remeshed.emplace(face, std::move(*made));
      }
    }
    if (remeshed.empty()) {
      surface = original;
      return out;
    }
    // 6. The surface with the new triangles and tops.
    top_node.clear();
    for (const auto& [face, made] : remeshed)
      for (const auto& t : made.node)
        for (const int n : t)
          if (n < 0) {
            const auto p = static_cast<std::size_t>(-1 - n);
            if (top_node.count(p)) continue;
            top_node[p] = static_cast<int>(surface.nodes.size());
            surface.nodes.push_back(lattice.frame.to_world(top_of(p)->at));
            surface.node_face.push_back(face);
            if (!surface.seed.empty())
              surface.seed.push_back(static_cast<int>(surface.seed.size()));
          }
    {
      std::vector<SurfaceTriangle> kept;
      kept.reserve(surface.triangles.size());
      for (const SurfaceTriangle& t : surface.triangles)
        if (!remeshed.count(t.face)) kept.push_back(t);
      for (const auto& [face, made] : remeshed)
        for (std::size_t k = 0; k < made.node.size(); ++k) {
          SurfaceTriangle t;
          for (int c = 0; c < 3; ++c) {
            const int n = made.node[k][c];
            t.node[c] = n >= 0 ? n : top_node.at(static_cast<std::size_t>(-1 - n));
          }
          t.uv = made.uv[k];
          t.face = face;
          kept.push_back(t);
        }
      surface.triangles = std::move(kept);
    }
    drop_unused_nodes(surface);
    {
      NodeHash renumbered(surface.nodes, h);
      for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) renumbered.add(n);
      for (auto& [p, n] : top_node)
        n = renumbered.find(lattice.frame.to_world(top_of(p)->at), 1e-9 * h);
    }
    report.nb_faces = remeshed.size();
    // 7. The cells whose faces cross the surface, or that hold a surface node or a point of the
    // core, go; then steps 5 to 7 again without them.
    frame_points.resize(surface.nodes.size());
    for (std::size_t n = 0; n < frame_points.size(); ++n)
      frame_points[n] = lattice.frame.to_frame(surface.nodes[n]);
    NodeHash node_at(frame_points, h);
    for (int n = 0; n < static_cast<int>(frame_points.size()); ++n) node_at.add(n);
    std::vector<std::array<int, 3>> surface_triangles;
    for (const SurfaceTriangle& t : surface.triangles) surface_triangles.push_back(t.node);
    {
      bool dropped = false;
      // The core's points: its cells' corners and the apexes of the pyramids left.
      PointSet core_points(around.box_lo, around.box_hi, h);
      for (std::size_t p = 0; p < layout.core_corner.size(); ++p)
        if (layout.core_corner[p]) core_points.add(layout.point_at(lattice, p));
      {
        std::unordered_set<std::size_t> left;
        for (std::size_t i = 0; i < faces.size(); ++i)
          if (!chosen[i] && left.insert(cell_of(faces[i].n)).second)
            core_points.add(layout.apex_at(lattice, cell_of(faces[i].n)));
      }
      // The cells' corners and their faces but the tops' (by index into `points`).
      std::vector<Vec3> points = frame_points;
      std::unordered_map<std::size_t, int> base_point;
      const auto base_index = [&](std::size_t p) {
        const auto [it, fresh] = base_point.emplace(p, static_cast<int>(points.size()));
        if (fresh) points.push_back(layout.point_at(lattice, p));
        return it->second;
      };
      const auto top_index = [&](std::size_t p) { return top_node.at(p); };
      std::vector<std::array<int, 3>> inner;
      std::vector<std::size_t> owner;  // per inner triangle: its base (a side pyramid: its hex's)
      std::vector<char> bad(faces.size(), 0);
      for (std::size_t i = 0; i < faces.size(); ++i) {
        if (!chosen[i]) continue;
        const std::array<std::size_t, 4>& b = base_of[i];
        bool all_tops = true;
        for (const std::size_t p : b) all_tops = all_tops && top_node.count(p);
        if (!all_tops) {
          bad[i] = 1;
          continue;
        }
        for (int m = 0; m < 4; ++m) {
          std::size_t lo = b[m], hi = b[(m + 1) % 4];
          if (lo > hi) std::swap(lo, hi);
          inner.push_back({base_index(lo), base_index(hi), top_index(hi)});
          inner.push_back({base_index(lo), top_index(hi), top_index(lo)});
          owner.push_back(i), owner.push_back(i);
        }
        // A point inside the hexahedron (its six tets) goes with it.
        std::array<Vec3, 4> base_at, top_at;
        for (int m = 0; m < 4; ++m) {
          base_at[m] = layout.point_at(lattice, b[m]);
          top_at[m] = frame_points[static_cast<std::size_t>(top_node.at(b[m]))];
        }
        const std::array<Vec3, 8> corner =
            buffer_hex_corners(base_at, top_at, faces[i].dir % 2 == 1);
        Vec3 lo_box = corner[0], hi_box = corner[0];
        for (const Vec3& c : corner) lo_box = vmin(lo_box, c), hi_box = vmax(hi_box, c);
        const Vec3 centre = (lo_box + hi_box) * 0.5;
        const double radius = 0.5 * (hi_box - lo_box).norm();
        // (On its faces too: TetGen would split them there; not at its corners.)
        const auto holds = [&](const Vec3& q) {
          for (const Vec3& c : corner)
            if ((c - q).norm() <= 1e-6 * h) return false;
          for (const auto& path : kKuhnPaths)
            if (in_tet(q, corner[0], corner[path[0]], corner[path[1]], corner[7], -1e-6))
              return true;
          return false;
        };
        bool holds_node = false;
        node_at.for_each_within(centre, std::min(radius, h), [&](int n) {
          holds_node = holds_node || holds(frame_points[static_cast<std::size_t>(n)]);
        });
        if (radius > h)  // (the node hash looks one cell around)
          for (std::size_t n = 0; n < frame_points.size() && !holds_node; ++n)
            holds_node = (frame_points[n] - centre).norm() <= radius && holds(frame_points[n]);
        if (holds_node || core_points.any_within(centre, radius, holds)) bad[i] = 1;
      }
      std::unordered_map<std::size_t, int> apex_point;  // the side pyramids' apexes
      for (const BufferCells::SidePyramid& p : pyramids) {
        const auto [at, fresh] = apex_point.emplace(p.apex_cell, static_cast<int>(points.size()));
        if (fresh) points.push_back(layout.apex_at(lattice, p.apex_cell));
        const int apex = at->second;
        const int id[4] = {base_index(p.lo), base_index(p.hi), top_index(p.hi), top_index(p.lo)};
        // Its hexahedron: the chosen base with side (lo, hi).
        std::size_t hex = 0;
        for (const std::size_t i : side_bases[edge_key(p.lo, p.hi)])
          if (chosen[i]) hex = i;
        for (int m = 0; m < 4; ++m) {
          inner.push_back({id[m], id[(m + 1) % 4], apex});
          owner.push_back(hex);
        }
      }
      // Against the surface, each other and the core's pyramids whose apexes they share (TetGen
      // stops on constraints that cross).
      std::vector<std::array<int, 3>> against = surface_triangles;
      against.insert(against.end(), inner.begin(), inner.end());
      {
        for (std::size_t i = 0; i < faces.size(); ++i) {
          const auto it = apex_point.find(cell_of(faces[i].n));
          if (chosen[i] || it == apex_point.end()) continue;
          for (int m = 0; m < 4; ++m)
            against.push_back({base_index(base_of_face(i)[m]),
                               base_index(base_of_face(i)[(m + 1) % 4]), it->second});
        }
      }
      const std::vector<char> crossing = crosses_any(points, against, inner);
      for (std::size_t k = 0; k < inner.size(); ++k)
        if (crossing[k]) bad[owner[k]] = 1;
      for (std::size_t i = 0; i < faces.size(); ++i)
        if (bad[i] && chosen[i]) chosen[i] = 0, dropped = true;
      again = dropped;
    }
  }
  // 8. The cells.
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!chosen[i]) continue;
    BufferCells::Hex hex;
    hex.face = i;
    for (int m = 0; m < 4; ++m) {
      const std::size_t p = base_of[i][m];
      hex.top[m] = frame_points[static_cast<std::size_t>(top_node.at(p))];
      out.top_of[p] = hex.top[m];
    }
    out.hexes.push_back(hex);
  }
  out.pyramids = pyramids;
  report.nb_hexes = out.hexes.size();
  report.nb_pyramids = out.pyramids.size();
  return out;
}

}  // namespace hexmerge::mesher
