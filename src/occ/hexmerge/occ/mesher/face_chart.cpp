#include "hexmerge/occ/mesher/face_chart.h"
// CGAL (outline_cdt.h) before OpenCASCADE: OCCT's Handle() macro breaks CGAL's headers.
// clang-format off
#include "hexmerge/occ/mesher/outline_cdt.h"
// clang-format on

#include <BRepAdaptor_Surface.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"

namespace hexmerge::mesher {
namespace {

using cgal2::Cdt;
using cgal2::Kernel;
using cgal2::mark_inside;

double distance2(const P2& a, const P2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

}  // namespace

double cross2(const P2& a, const P2& b, const P2& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}
double to_segment(const P2& p, const P2& a, const P2& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return distance2(p, {a[0] + t * dx, a[1] + t * dy});
}
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

std::pair<Vec3, Vec3> plane_box(std::initializer_list<P2> points, double margin) {
  Vec3 lo{points.begin()[0][0], points.begin()[0][1], 0}, hi = lo;
  for (const P2& p : points) {
    lo.x = std::min(lo.x, p[0]), lo.y = std::min(lo.y, p[1]);
    hi.x = std::max(hi.x, p[0]), hi.y = std::max(hi.y, p[1]);
  }
  const double grow = margin * (1 + 1e-9) + 1e-12 * (std::abs(hi.x) + std::abs(hi.y) + 1);
  return {lo - Vec3{grow, grow, 0}, hi + Vec3{grow, grow, 0}};
}
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
  // The grids: cells about a triangle wide; the triangles' boxes grown by a millionth of their
  // size (place_in() takes a point up to 1e-9 outside).
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
  chart.outline_grid = plane_grid(chart.xy, cell, [&](const auto& add) {
    for (std::size_t s = 0; s < chart.outline.size(); ++s)
      add(static_cast<int>(s), plane_box({chart.xy[static_cast<std::size_t>(chart.outline[s][0])],
                                          chart.xy[static_cast<std::size_t>(chart.outline[s][1])]},
                                         0));
  });
  return chart;
}

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

std::optional<P2> place_clear(const FaceChart& chart, UV& uv, double h) {
  const std::optional<P2> placed = place_in(chart, uv);
  const bool clear = placed.has_value() &&
                     !any_outline_side_near(
                         chart, {*placed}, kQuadEdgeClearance * h, [&](const P2& a, const P2& b) {
                           return !(to_segment(*placed, a, b) >= kQuadEdgeClearance * h);
                         });
  return clear ? placed : std::nullopt;
}

bool quad_clear(const FaceChart& chart, const std::array<P2, 4>& xy, double h) {
  const double s0 = cross2(xy[0], xy[1], xy[2]), s1 = cross2(xy[0], xy[2], xy[3]);
  bool ok = s0 != 0 && (s0 > 0) == (s1 > 0);
  for (int k = 0; k < 4 && ok; ++k)
    ok = !any_outline_side_near(
        chart, {xy[k], xy[(k + 1) % 4]}, 0.5 * kQuadEdgeClearance * h,
        [&](const P2& a, const P2& b) {
          return !(!segments_meet(xy[k], xy[(k + 1) % 4], a, b) &&
                   to_segment(a, xy[k], xy[(k + 1) % 4]) >= 0.5 * kQuadEdgeClearance * h);
        });
  return ok;
}

std::vector<char> nodes_on_several_faces(const Surface& surface) {
  std::vector<char> several(surface.nodes.size(), 0);
  std::vector<int> first_face(surface.nodes.size(), -1);
  for (const SurfaceTriangle& t : surface.triangles)
    for (const int n : t.node) {
      int& f = first_face[static_cast<std::size_t>(n)];
      if (f < 0) f = t.face;
      if (f != t.face) several[static_cast<std::size_t>(n)] = 1;
    }
  return several;
}

std::vector<int> put_in_surface(Surface& surface, const std::map<int, Retriangulated>& remeshed,
                                const std::vector<Vec3>& tops, double h) {
  std::vector<int> node(tops.size(), -1);
  for (const auto& [face, made] : remeshed)
    for (const auto& t : made.node)
      for (const int n : t)
        if (n < 0) {
          const auto k = static_cast<std::size_t>(-1 - n);
          if (node[k] >= 0) continue;
          node[k] = static_cast<int>(surface.nodes.size());
          surface.nodes.push_back(tops[k]);
          surface.node_face.push_back(face);
          if (!surface.seed.empty()) surface.seed.push_back(static_cast<int>(surface.seed.size()));
        }
  std::vector<SurfaceTriangle> kept;
  kept.reserve(surface.triangles.size());
  for (const SurfaceTriangle& t : surface.triangles)
    if (!remeshed.count(t.face)) kept.push_back(t);
  for (const auto& [face, made] : remeshed)
    for (std::size_t k = 0; k < made.node.size(); ++k) {
      SurfaceTriangle t;
      for (int c = 0; c < 3; ++c) {
        const int n = made.node[k][static_cast<std::size_t>(c)];
        t.node[static_cast<std::size_t>(c)] = n >= 0 ? n : node[static_cast<std::size_t>(-1 - n)];
      }
      t.uv = made.uv[k];
      t.face = face;
      kept.push_back(t);
    }
  surface.triangles = std::move(kept);
  drop_unused_nodes(surface);
  NodeHash renumbered(surface.nodes, h);
  for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) renumbered.add(n);
  for (std::size_t k = 0; k < tops.size(); ++k)
    if (node[k] >= 0) node[k] = renumbered.find(tops[k], 1e-9 * h);
  return node;
}

std::optional<Retriangulated> retriangulate(
    const FaceChart& chart, const Surface& surface, const std::vector<std::array<int, 4>>& quads,
    const std::vector<P2>& top_xy, const std::vector<UV>& top_uv,
    const std::vector<Vec3>& top_world, const std::vector<char>& node_elsewhere, double h,
    const RetriangulateLimits& limits, std::vector<int>* poor_tops) {
  // The face's inner vertices near a quad go; one that another face uses too stays, and then
  // the face gets no tops.
  const std::size_t nv = chart.node.size();
  std::vector<char> gone(nv, 0);
  // The quads by their boxes grown by the clearance: those a vertex may be near or in.
  const BucketGrid near_quads = plane_grid(chart.xy, h, [&](const auto& add) {
    for (std::size_t i = 0; i < quads.size(); ++i) {
      const auto& q = quads[i];
      const auto at = [&](int k) { return top_xy[static_cast<std::size_t>(q[k])]; };
      add(static_cast<int>(i), plane_box({at(0), at(1), at(2), at(3)}, limits.node_clearance * h));
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
                          top_xy[static_cast<std::size_t>(q[(k + 1) % 4])]) <
               limits.node_clearance * h;
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
  if (!mark_inside(cdt, outline)) return std::nullopt;  // the outline bounds no region
  // The new triangles, in the face's orientation; each quad's two among them.
  const auto world = [&](int v) {
    return v < static_cast<int>(nv)
               ? surface.nodes[static_cast<std::size_t>(chart.node[static_cast<std::size_t>(v)])]
               : top_world[static_cast<std::size_t>(v) - nv];
  };
  Retriangulated out;
  std::set<std::array<int, 3>> made;
  double area = 0, smallest = 180;
  const double least = std::min(limits.least_angle, chart.smallest_angle);
  std::vector<std::array<int, 3>> poor;  // the triangles under `least` (chart vertices)
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
    const double angle = smallest_angle(p0, p1, p2) * 180 / M_PI;
    smallest = std::min(smallest, angle);
    if (angle < least) poor.push_back(v);
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
  if (std::abs(area - chart.area) > limits.area_change * chart.area) return std::nullopt;
  if (smallest < least) {
    if (poor_tops) {
      std::set<int> blamed;
      for (const std::array<int, 3>& t : poor) {
        bool has_top = false;
        for (const int v : t)
          if (v >= static_cast<int>(nv)) blamed.insert(v - static_cast<int>(nv)), has_top = true;
        if (has_top) continue;
        for (const int v : t) {
          const auto [lo, hi] = plane_box({chart.xy[static_cast<std::size_t>(v)]}, 0);
          near_quads.any_in(lo, hi, [&](int i) {
            for (const int top : quads[static_cast<std::size_t>(i)]) blamed.insert(top);
            return false;
          });
        }
      }
      poor_tops->assign(blamed.begin(), blamed.end());
    }
    return std::nullopt;
  }
  return out;
}

}  // namespace hexmerge::mesher
