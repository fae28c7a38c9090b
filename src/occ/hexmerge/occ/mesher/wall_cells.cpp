#include "hexmerge/occ/mesher/wall_cells.h"

#include <BRepAdaptor_Surface.hxx>
#include <ElSLib.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/face_chart.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface_check.h"

namespace hexmerge::mesher {

namespace {

// The quads' limits are the buffer layer's (face_chart.h: kQuadEdgeClearance, kQuadAreaChange,
// kQuadLeastAngle), but the face's inner nodes nearer than kNodeClearance h to a quad go; where
// a face fails so, it is tried again with kWideNodeClearance (else the quads blamed go): a
// column whose corners come within kQuadEdgeClearance h of a seam or an edge is not made, and
// the nodes left in such a strip, up to a column and that clearance wide, made triangles of 9
// degrees with the seam's nodes on a tube at h 3. (Everywhere, the wide clearance lost walls:
// flanged_tee at h 5.512 66.0 -> 55.1 % hex volume.)
constexpr double kNodeClearance = 0.5;
constexpr double kWideNodeClearance = 1.5;
// A cell's six tets keep the mesher's floor (where the recombination does not take the cell,
// its tets stay).
constexpr double kTetFloor = 0.2;
// Two cylinders are coaxial when their axes' directions differ by less than this (radians) and
// each axis passes within kAxisOffset h of the other's origin.
constexpr double kAxisAngle = 1e-9;
constexpr double kAxisOffset = 1e-6;
// A quad's side in its face's chart is at most this many times its length on the face.
constexpr double kChartStretch = 1.5;
// A wall keeps its cells where at least this share of its columns is clear of the core.
constexpr double kLeastWallShare = 0.5;
// A cell is at most this many times as long (along the axis, across the wall) as it is wide.
constexpr double kCellStretch = 2.0;

// A cylinder of the shape: its face, axis, radius, and whether the solid lies inside it (the
// outer face of a wall) or outside (a bore).
struct Cylinder {
  int face;
  gp_Cylinder surface;
  bool outer;
};

// A wall: coaxial cylinders of one radius outside and one inside, their faces.
struct Wall {
  gp_Pnt origin;
  gp_Dir axis, x_dir, y_dir;
  double outer_radius, inner_radius;
  std::vector<int> outer_faces, inner_faces;
  double z_lo = 0, z_hi = 0;  // the faces' common length along the axis
};

// The triangles of a cell's faces, as its six tets (kKuhnPaths) split them (corners in
// kKuhnPaths' order), but those of its inner face (`on_surface` bit 1) and of its outer face (bit
// 2) where those are the surface's.
std::vector<std::array<int, 3>> cell_face_triangles(int on_surface) {
  std::vector<std::array<int, 3>> out;
  for (const auto& q : kKuhnPaths) {
    const int tet[4] = {0, q[0], q[1], 7};
    for (int f = 0; f < 4; ++f) {
      const int a = tet[(f + 1) % 4], b = tet[(f + 2) % 4], d = tet[(f + 3) % 4];
      const int shared = ~(a ^ b) & ~(a ^ d) & 7;  // the bits its corners share: its face
      if (shared == 0) continue;
      if ((shared & 4) && (on_surface & ((a & 4) ? 2 : 1))) continue;
      out.push_back({a, b, d});
    }
  }
  return out;
}

}  // namespace

WallCells wall_cells(const Shape& shape, const Frame& frame, const std::vector<char>& eligible,
                     const PointSet& obstacles, double h, double deflection, Surface& surface,
                     WallReport& report) {
  WallCells out;
  // 1. The cylinders, which side the solid is on by their triangles' outward normals.
  std::vector<std::vector<int>> face_triangles(static_cast<std::size_t>(shape.faces.Extent()));
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    face_triangles[static_cast<std::size_t>(surface.triangles[t].face)].push_back(
        static_cast<int>(t));
  std::vector<Cylinder> cylinders;
  for (int f = 0; f < shape.faces.Extent(); ++f) {
    if (!eligible[static_cast<std::size_t>(f)] ||
        face_triangles[static_cast<std::size_t>(f)].empty())
      continue;
    const BRepAdaptor_Surface s(TopoDS::Face(shape.faces(f + 1)), false);
    if (s.GetType() != GeomAbs_Cylinder) continue;
    const gp_Cylinder c = s.Cylinder();
    double outward = 0;
    for (const int t : face_triangles[static_cast<std::size_t>(f)]) {
      const auto& n = surface.triangles[static_cast<std::size_t>(t)].node;
      const Vec3 a = surface.nodes[static_cast<std::size_t>(n[0])],
                 b = surface.nodes[static_cast<std::size_t>(n[1])],
                 d = surface.nodes[static_cast<std::size_t>(n[2])];
      const Vec3 centre = (a + b + d) * (1.0 / 3);
      const gp_Vec from(c.Location(), gp_Pnt(centre.x, centre.y, centre.z));
      const gp_Vec radial = from - gp_Vec(c.Axis().Direction()) * from.Dot(c.Axis().Direction());
      const Vec3 normal = (b - a).cross(d - a);
      outward += normal.x * radial.X() + normal.y * radial.Y() + normal.z * radial.Z();
    }
    if (outward == 0) continue;
    cylinders.push_back({f, c, outward > 0});
  }
  // 2. The walls: per coaxial pair of radii, the outer faces and the inner ones.
  std::vector<Wall> walls;
  const auto coaxial = [&](const gp_Ax1& a, const gp_Ax1& b) {
    if (!a.IsParallel(b, kAxisAngle)) return false;
    const gp_Vec d(a.Location(), b.Location());
    return (d - gp_Vec(a.Direction()) * d.Dot(a.Direction())).Magnitude() <= kAxisOffset * h;
  };
  const auto same = [&](double a, double b) { return std::abs(a - b) <= kAxisOffset * h; };
  std::map<int, gp_Cylinder> cylinder_of;  // per face
  for (const Cylinder& c : cylinders) cylinder_of.emplace(c.face, c.surface);
  for (const Cylinder& o : cylinders) {
    if (!o.outer) continue;
    const gp_Ax1 axis = o.surface.Axis();
    for (const Cylinder& i : cylinders) {
      if (i.outer || !coaxial(axis, i.surface.Axis())) continue;
      const double t = o.surface.Radius() - i.surface.Radius();
      if (!(t >= kThinnestWallCell * h && t <= kThickestWallCell * h)) continue;
      Wall* wall = nullptr;
      for (Wall& w : walls)
        if (coaxial(gp_Ax1(w.origin, w.axis), axis) && same(w.outer_radius, o.surface.Radius()) &&
            same(w.inner_radius, i.surface.Radius()))
          wall = &w;
      if (!wall) {
        walls.emplace_back();
        wall = &walls.back();
        wall->origin = axis.Location();
        wall->axis = axis.Direction();
        wall->x_dir = o.surface.Position().XDirection();
        wall->y_dir = wall->axis.Crossed(wall->x_dir);
        wall->outer_radius = o.surface.Radius(), wall->inner_radius = i.surface.Radius();
      }
      if (std::find(wall->outer_faces.begin(), wall->outer_faces.end(), o.face) ==
          wall->outer_faces.end())
        wall->outer_faces.push_back(o.face);
      if (std::find(wall->inner_faces.begin(), wall->inner_faces.end(), i.face) ==
          wall->inner_faces.end())
        wall->inner_faces.push_back(i.face);
    }
  }
  if (walls.empty()) return out;
  // The faces' lengths along the axis (from their nodes): the common one.
  const auto span = [&](const Wall& w, const std::vector<int>& faces) {
    double lo = 1e300, hi = -1e300;
    const Vec3 origin = of(w.origin), along = of(w.axis);
    for (const int f : faces)
      for (const int t : face_triangles[static_cast<std::size_t>(f)])
        for (const int n : surface.triangles[static_cast<std::size_t>(t)].node) {
          const double z = (surface.nodes[static_cast<std::size_t>(n)] - origin).dot(along);
          lo = std::min(lo, z), hi = std::max(hi, z);
        }
    return std::pair{lo, hi};
  };
  for (Wall& w : walls) {
    const auto [olo, ohi] = span(w, w.outer_faces);
    const auto [ilo, ihi] = span(w, w.inner_faces);
    w.z_lo = std::max(olo, ilo), w.z_hi = std::min(ohi, ihi);
  }

  // 3. Per wall, its grid; the cells whose corners place in one face's chart on each side.
  std::map<int, FaceChart> charts;
  const auto chart = [&](int face) -> const FaceChart* {
    auto it = charts.find(face);
    if (it == charts.end()) {
      std::optional<FaceChart> made =
          chart_of(shape, surface, face_triangles[static_cast<std::size_t>(face)], face);
      if (!made) return nullptr;
      it = charts.emplace(face, std::move(*made)).first;
    }
    return &it->second;
  };
  // A grid node: wall, layer (0 inner .. k outer), round (i, mod n), along (j).
  struct Node {
    std::size_t wall;
    int layer, i, j;
    bool operator<(const Node& o) const {
      return std::tie(wall, layer, i, j) < std::tie(o.wall, o.layer, o.i, o.j);
    }
  };
  struct Cell {
    std::size_t wall;
    int i, j;  // its least corner
    int outer_face, inner_face;
    std::array<Node, 8> corner;  // kKuhnPaths' order
  };
  std::vector<Cell> cells;
  std::map<Node, Vec3> world;                                // every corner's place
  std::map<std::pair<Node, int>, std::pair<P2, UV>> placed;  // per (node, face), in its chart
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    const Wall& w = walls[wi];
    const double middle = 0.5 * (w.outer_radius + w.inner_radius);
    const double length = w.z_hi - w.z_lo - h;  // rows h / 2 inside the ends
    if (!(length >= 0.5 * h)) continue;
    struct {
      int n, m, k;  // cells round, along, across
      double z0, dz;
    } g;
    // About h round the middle, and the outer face's chords within the chord deflection.
    const double chord_angle = 2 * std::acos(std::max(-1.0, 1 - deflection / w.outer_radius));
    g.n = std::max({8, static_cast<int>(std::lround(2 * M_PI * middle / h)),
                    static_cast<int>(std::ceil(2 * M_PI / chord_angle))});
    // Along the axis and across, cells at most kCellStretch times as long as round (where the
    // chord deflection makes them narrower than h: coarse sizes on small tubes).
    const double round_width = 2 * M_PI * middle / g.n;
    const double size = std::min(h, kCellStretch * round_width);
    g.m = std::max(1, static_cast<int>(std::lround(length / size)));
    g.k = std::max(1, static_cast<int>(std::lround((w.outer_radius - w.inner_radius) / size)));
    g.z0 = w.z_lo + 0.5 * h, g.dz = length / g.m;
    const auto at = [&](int layer, int i, int j) {
      const double theta = (i + 0.5) * 2 * M_PI / g.n;
      const double r = w.inner_radius + (w.outer_radius - w.inner_radius) * layer / g.k;
      const gp_Vec radial = gp_Vec(w.x_dir) * std::cos(theta) + gp_Vec(w.y_dir) * std::sin(theta);
      return w.origin.Translated(radial * r + gp_Vec(w.axis) * (g.z0 + j * g.dz));
    };
    // Grid node (layer, i, j), i round the axis taken modulo n.
    const auto node_at = [&](int layer, int i, int j) { return Node{wi, layer, i % g.n, j}; };
    // Where grid node (layer, i, j) on the wall's face places in that face's chart, clear of
    // its edges.
    const auto place = [&](int layer, int i, int j, int face) -> std::optional<P2> {
      const Node node = node_at(layer, i, j);
      const auto key = std::pair{node, face};
      if (const auto it = placed.find(key); it != placed.end()) return it->second.first;
      const FaceChart* c = chart(face);
      if (!c) return std::nullopt;
      const gp_Pnt p = at(layer, i, j);
      UV uv;
      ElSLib::Parameters(cylinder_of.at(face), p, uv.u, uv.v);
      const std::optional<P2> xy = place_clear(*c, uv, h);
      if (!xy) return std::nullopt;
      placed[key] = {*xy, uv};
      world[node] = of(p);
      return xy;
    };
    // The quad of cell (i, j) on the faces of layer `layer`, in one of `faces`: that face.
    const auto quad_face = [&](int layer, int i, int j, const std::vector<int>& faces) {
      for (const int face : faces) {
        std::array<P2, 4> xy;
        bool ok = true;
        const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
        for (int c = 0; c < 4 && ok; ++c) {
          const std::optional<P2> q = place(layer, i + di[c], j + dj[c], face);
          ok = q.has_value();
          if (ok) xy[static_cast<std::size_t>(c)] = *q;
        }
        if (!ok) continue;
        ok = quad_clear(*chart(face), xy, h);
        // Its sides in the chart as long as on the face (the chart's metric is the face's): not
        // the way round a periodic face's parameters from one side of its seam to the other.
        for (int e = 0; e < 4 && ok; ++e) {
          const double chord = (world.at(node_at(layer, i + di[e], j + dj[e])) -
                                world.at(node_at(layer, i + di[(e + 1) % 4], j + dj[(e + 1) % 4])))
                                   .norm();
          ok = std::hypot(xy[e][0] - xy[(e + 1) % 4][0], xy[e][1] - xy[(e + 1) % 4][1]) <=
               kChartStretch * chord;
        }
        if (ok) return face;
      }
      return -1;
    };
    for (int j = 0; j < g.m; ++j)
      for (int i = 0; i < g.n; ++i) {
        const int inner = quad_face(0, i, j, w.inner_faces);
        if (inner < 0) continue;
        const int outer = quad_face(g.k, i, j, w.outer_faces);
        if (outer < 0) continue;
        for (int layer = 0; layer < g.k; ++layer) {
          Cell cell{wi, i, j, layer == g.k - 1 ? outer : -1, layer == 0 ? inner : -1, {}};
          for (int b = 0; b < 8; ++b) {
            const Node node = node_at(layer + ((b >> 2) & 1), i + (b & 1), j + ((b >> 1) & 1));
            cell.corner[static_cast<std::size_t>(b)] = node;
            if (!world.count(node)) world[node] = of(at(node.layer, i + (b & 1), node.j));
          }
          cells.push_back(cell);
        }
      }
  }
  if (cells.empty()) return out;

  // 4. Per cell, its corners in the frame: its six tets at kTetFloor (turned positive), no point
  // of the core near it.
  const auto corners_of = [&](const Cell& c) {
    std::array<Vec3, 8> at;
    for (int b = 0; b < 8; ++b) at[b] = frame.to_frame(world.at(c.corner[b]));
    return at;
  };
  const auto column = [](const Cell& c) { return std::tuple{c.wall, c.i, c.j}; };
  const auto on_surface = [](const Cell& c) {
    return (c.inner_face >= 0 ? 1 : 0) | (c.outer_face >= 0 ? 2 : 0);
  };
  std::set<std::tuple<std::size_t, int, int>> dropped;
  for (Cell& c : cells) {
    std::array<Vec3, 8> at = corners_of(c);
    if (tet_quality(at[0], at[1], at[3], at[7]) < 0) {  // left-handed: bits u and v swapped
      for (const int b : {0, 4}) std::swap(c.corner[b + 1], c.corner[b + 2]);
      at = corners_of(c);
    }
    bool ok = true;
    for (const auto& q : kKuhnPaths)
      ok = ok && std::abs(tet_quality(at[0], at[q[0]], at[q[1]], at[7])) >= kTetFloor;
    Vec3 lo = at[0], hi = at[0];
    for (const Vec3& q : at) lo = vmin(lo, q), hi = vmax(hi, q);
    ok = ok && !obstacles.any_within((lo + hi) * 0.5, 0.5 * (hi - lo).norm() + 0.25 * h);
    if (!ok) dropped.insert(column(c));
  }
  // A wall where the core stands in most of it is the core's (and the buffer layer's): its
  // cells go where fewer than kLeastWallShare of its columns are left.
  {
    std::vector<std::set<std::pair<int, int>>> placed_columns(walls.size()), left(walls.size());
    for (const Cell& c : cells) {
      placed_columns[c.wall].insert({c.i, c.j});
      if (!dropped.count(column(c))) left[c.wall].insert({c.i, c.j});
    }
    for (const Cell& c : cells)
      if (left[c.wall].size() < kLeastWallShare * placed_columns[c.wall].size())
        dropped.insert(column(c));
  }

  // 5. Each face with quads triangulated again, until every face takes its quads and no cell
  // crosses the surface, holds a node or crosses another cell.
  const std::vector<char> node_elsewhere = nodes_on_several_faces(surface);
  const Surface original = surface;
  std::map<Node, int> node_of;  // the corners on the surface: their nodes
  for (bool again = true; again;) {
    again = false;
    surface = original;
    // The quads per face: corners by node, around with the split's diagonal first to third.
    std::map<int, std::vector<std::pair<std::array<Node, 4>, std::tuple<std::size_t, int, int>>>>
        quads_on;
    for (const Cell& c : cells) {
      if (dropped.count(column(c))) continue;
      if (c.inner_face >= 0)
        quads_on[c.inner_face].push_back(
            {{c.corner[0], c.corner[1], c.corner[3], c.corner[2]}, column(c)});
      if (c.outer_face >= 0)
        quads_on[c.outer_face].push_back(
            {{c.corner[4], c.corner[5], c.corner[7], c.corner[6]}, column(c)});
    }
    std::map<int, Retriangulated> remeshed;
    // The corners in the faces triangulated again (-1 - k in their triangles): node, world.
    std::vector<Node> top_node;
    std::vector<Vec3> top_world;
    std::map<Node, int> top_index;
    for (const auto& [face, quads] : quads_on) {
      std::map<Node, int> index;
      std::vector<Node> tops;
      std::vector<P2> xy;
      std::vector<UV> uv;
      std::vector<Vec3> at;
      std::vector<std::array<int, 4>> around;
      for (const auto& [corners, col] : quads) {
        std::array<int, 4> q{};
        for (int m = 0; m < 4; ++m) {
          const auto [it, fresh] = index.emplace(corners[m], static_cast<int>(tops.size()));
          if (fresh) {
            const auto& [p, u] = placed.at({corners[m], face});
            tops.push_back(corners[m]), xy.push_back(p), uv.push_back(u);
            at.push_back(world.at(corners[m]));
          }
          q[m] = it->second;
        }
        around.push_back(q);
      }
      std::vector<int> poor_tops;
      std::optional<Retriangulated> made =
          retriangulate(charts.at(face), surface, around, xy, uv, at, node_elsewhere, h,
                        {kNodeClearance, kQuadAreaChange, kQuadLeastAngle}, &poor_tops);
      if (!made)
        made = retriangulate(charts.at(face), surface, around, xy, uv, at, node_elsewhere, h,
                             {kWideNodeClearance, kQuadAreaChange, kQuadLeastAngle});
      if (!made) {
        std::set<Node> poor;
        for (const int k : poor_tops) poor.insert(tops[static_cast<std::size_t>(k)]);
        bool any = false;
        for (const auto& [corners, col] : quads)
          for (const Node& n : corners)
            if (poor.count(n)) {
              any = dropped.insert(col).second || any;
              break;
            }
        if (!any)
          for (const auto& [corners, col] : quads) dropped.insert(col);
        again = true;
        continue;
      }
      // This face's k-th corner is the node's among all faces' corners.
      for (auto& t : made->node)
        for (int& n : t)
          if (n < 0) {
            const Node& node = tops[static_cast<std::size_t>(-1 - n)];
            const auto [it, fresh] = top_index.emplace(node, static_cast<int>(top_node.size()));
            if (fresh) top_node.push_back(node), top_world.push_back(world.at(node));
            n = -1 - it->second;
          }
      remeshed.emplace(face, std::move(*made));
    }
    if (again) continue;
    if (remeshed.empty()) break;
    // The surface with the new triangles and the corners.
    const std::vector<int> put = put_in_surface(surface, remeshed, top_world, h);
    node_of.clear();
    for (std::size_t k = 0; k < put.size(); ++k)
      if (put[k] >= 0) node_of[top_node[k]] = put[k];
    // 6. The cells' faces inside the shape against the surface and each other; the surface's
    // nodes inside a cell.
    std::vector<Vec3> points(surface.nodes.size());
    for (std::size_t n = 0; n < points.size(); ++n) points[n] = frame.to_frame(surface.nodes[n]);
    std::map<Node, int> inside_point;
    const auto point_of = [&](const Node& node) {
      if (const auto it = node_of.find(node); it != node_of.end()) return it->second;
      const auto [it, fresh] = inside_point.emplace(node, static_cast<int>(points.size()));
      if (fresh) points.push_back(frame.to_frame(world.at(node)));
      return it->second;
    };
    // The surface's nodes, by place.
    Vec3 box_lo = points[0], box_hi = points[0];
    for (std::size_t n = 0; n < surface.nodes.size(); ++n)
      box_lo = vmin(box_lo, points[n]), box_hi = vmax(box_hi, points[n]);
    PointSet surface_nodes(box_lo, box_hi, h);
    for (std::size_t n = 0; n < surface.nodes.size(); ++n) surface_nodes.add(points[n]);
    std::vector<std::array<int, 3>> inner;
    std::vector<std::tuple<std::size_t, int, int>> owner;
    std::set<std::array<int, 3>> seen;
    for (const Cell& c : cells) {
      if (dropped.count(column(c))) continue;
      std::array<int, 8> id;
      for (int b = 0; b < 8; ++b) id[b] = point_of(c.corner[b]);
      for (const auto& [a, b, d] : cell_face_triangles(on_surface(c))) {
        std::array<int, 3> key{id[a], id[b], id[d]};
        std::sort(key.begin(), key.end());
        if (!seen.insert(key).second) continue;
        inner.push_back({id[a], id[b], id[d]});
        owner.push_back(column(c));
      }
      // A surface node inside it (on a face too; not at a corner).
      std::array<Vec3, 8> at;
      for (int b = 0; b < 8; ++b) at[b] = points[static_cast<std::size_t>(id[b])];
      Vec3 lo = at[0], hi = at[0];
      for (const Vec3& q : at) lo = vmin(lo, q), hi = vmax(hi, q);
      const bool holds =
          surface_nodes.any_within((lo + hi) * 0.5, 0.5 * (hi - lo).norm() + 1e-6 * h,
                                   [&](const Vec3& q) { return cell_holds(at, q, h); });
      if (holds && dropped.insert(column(c)).second) again = true;
    }
    std::vector<std::array<int, 3>> against;
    for (const SurfaceTriangle& t : surface.triangles) against.push_back(t.node);
    against.insert(against.end(), inner.begin(), inner.end());
    const std::vector<char> crossing = crosses_any(points, against, inner);
    for (std::size_t k = 0; k < inner.size(); ++k)
      if (crossing[k] && dropped.insert(owner[k]).second) again = true;
    if (!again) {
      report.nb_faces = remeshed.size();
      for (const auto& [face, made] : remeshed) report.faces.push_back(face);
    }
  }
  // 7. The cells.
  std::set<Node> inside;
  std::set<std::size_t> walls_with;
  for (const Cell& c : cells) {
    if (dropped.count(column(c)) || report.nb_faces == 0) continue;
    std::array<Vec3, 8> at;
    for (int b = 0; b < 8; ++b) {
      const Node& node = c.corner[b];
      at[b] = frame.to_frame(world.at(node));
      if (!node_of.count(node) && inside.insert(node).second) out.points.push_back(at[b]);
    }
    out.hexes.push_back(at);
    out.on_surface.push_back(static_cast<char>(on_surface(c)));
    walls_with.insert(c.wall);
  }
  if (report.nb_faces == 0) surface = original;
  report.nb_hexes = out.hexes.size();
  report.nb_walls = walls_with.size();
  return out;
}

void emit_wall_cells(const WallCells& cells, Surroundings& around, InsertedPoints& inserted) {
  for (const Vec3& q : cells.points) {
    inserted.points.push_back(q);
    inserted.face.push_back(-1);
  }
  std::set<std::array<double, 9>> seen;
  for (std::size_t hex = 0; hex < cells.hexes.size(); ++hex) {
    const std::array<Vec3, 8>& at = cells.hexes[hex];
    InsertedPoints::Split split;
    split.corners.assign(at.begin(), at.end());
    for (const auto& q : kKuhnPaths) {
      split.tets.push_back({0, q[0], q[1], 7});
      around.buffer_cells.add({at[0], at[q[0]], at[q[1]], at[7]});
    }
    // Its faces' triangles: constraints (those on the surface are its own).
    for (const auto& [a, b, d] : cell_face_triangles(cells.on_surface[hex])) {
      std::array<Vec3, 3> t{at[a], at[b], at[d]};
      std::array<double, 9> key;
      std::array<Vec3, 3> sorted = t;
      std::sort(sorted.begin(), sorted.end(), [](const Vec3& u, const Vec3& v) {
        return std::tie(u.x, u.y, u.z) < std::tie(v.x, v.y, v.z);
      });
      for (int k = 0; k < 3; ++k)
        key[3 * k] = sorted[k].x, key[3 * k + 1] = sorted[k].y, key[3 * k + 2] = sorted[k].z;
      if (seen.insert(key).second) inserted.constraints.push_back(t);
    }
    inserted.kept_cells.push_back(split.corners);
    inserted.splits.push_back(std::move(split));
  }
}

}  // namespace hexmerge::mesher
