#include "hexmerge/occ/mesher/sharp_features.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepLProp_SLProps.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {
namespace {

constexpr double kDegrees = 180.0 / M_PI;
// Points sampled along each edge for its dihedral angle (inside it: its ends are corners).
constexpr int kEdgeSamples = 9;

// The face's outward normal at (u, v) of its surface (`reversed`: the face's orientation is
// reversed), or nothing where the surface has none (a cone's apex, a sphere's pole).
std::optional<Vec3> normal_at(const BRepAdaptor_Surface& surface, bool reversed, double u,
                              double v) {
  BRepLProp_SLProps props(surface, u, v, 1, 1e-9);
  if (!props.IsNormalDefined()) return std::nullopt;
  const Vec3 n = of(props.Normal());
  return reversed ? n * -1.0 : n;
}

// The unit tangent of a curve at parameter t, along its parameter; where the derivative
// vanishes, the chord to a point a thousandth of its range on.
std::optional<Vec3> tangent_at(const BRepAdaptor_Curve& curve, double t) {
  gp_Pnt p;
  gp_Vec d;
  curve.D1(t, p, d);
  Vec3 tangent{d.X(), d.Y(), d.Z()};
  const double range = curve.LastParameter() - curve.FirstParameter();
  if (tangent.norm() <= 1e-12 * std::max(1.0, range)) {
    const double step = 1e-3 * range * (t < curve.FirstParameter() + 0.5 * range ? 1 : -1);
    tangent = (of(curve.Value(t + step)) - of(p)) * (step > 0 ? 1.0 : -1.0);
  }
  const double length = tangent.norm();
  if (!(length > 0)) return std::nullopt;
  return tangent * (1 / length);
}

// The direction in which an edge leaves one of its ends, `first` or last by its own parameter:
// its unit tangent there, and the unit chord to the point a thousandth of its range inside
// (which parts two edges tangent at the vertex, a line and a circle touching it, by their
// curvature, as their faces part).
struct EndDirection {
  Vec3 tangent, chord;
};
std::optional<EndDirection> direction_from_end(const TopoDS_Edge& edge, bool first) {
  const BRepAdaptor_Curve curve(edge);
  const double a = curve.FirstParameter(), b = curve.LastParameter();
  const double from = first ? a : b, to = from + (first ? 1e-3 : -1e-3) * (b - a);
  gp_Pnt p;
  gp_Vec d;
  curve.D1(from, p, d);
  Vec3 chord = of(curve.Value(to)) - of(p),
       tangent = Vec3{d.X(), d.Y(), d.Z()} * (first ? 1.0 : -1.0);
  if (!(chord.norm() > 0)) return std::nullopt;
  chord = chord * (1 / chord.norm());
  // Where the derivative vanishes (a singular parameterisation), the chord.
  tangent = tangent.norm() > 1e-12 * std::max(1.0, b - a) ? tangent * (1 / tangent.norm()) : chord;
  return EndDirection{tangent, chord};
}

// The angle in [0, 360) degrees from `from` to `to` turning about `axis`.
double turn(const Vec3& from, const Vec3& to, const Vec3& axis) {
  double a = std::atan2(from.cross(to).dot(axis), from.dot(to)) * kDegrees;
  return a < 0 ? a + 360 : a;
}

// The corners of `face` under `limit`. At each vertex, the directions of the face's edges
// leaving it (a wire's edge leaving the vertex, or the reverse of one arriving), in turn about
// the outward normal: the face lies on the left of its oriented edges, so its sectors there run
// from a leaving edge to the next direction (the reverse of an arriving one). A vertex where two
// wires meet (a hole touching the outer boundary: gmsh_as1-tu-203's circle tangent to a line)
// has a sector per wire's pass.
void face_corners(const Shape& shape, int face_index, double limit, std::vector<SharpCorner>& out) {
  const TopoDS_Face& face = TopoDS::Face(shape.faces(face_index + 1));
  const BRepAdaptor_Surface surface(face);
  struct Direction {
    EndDirection u;
    bool leaving;
    int edge;
    double turn = 0;  // of its chord about the normal, from the vertex's first chord
  };
  TopTools_IndexedMapOfShape vertices;
  std::vector<std::vector<Direction>> at;  // per vertex of `vertices`
  // The vertices at a degenerated edge, where the surface's parameters collapse: the normal is
  // taken beside them.
  TopTools_IndexedMapOfShape at_pole;
  // Per vertex at a degenerated edge, points of the face's parameters a thousandth of the
  // range of the edges before and after it from it.
  std::vector<std::vector<gp_Pnt2d>> beside;
  for (TopExp_Explorer wires(face, TopAbs_WIRE); wires.More(); wires.Next()) {
    // The wire's edges in order, each with the vertex it leaves from.
    std::vector<std::pair<TopoDS_Edge, TopoDS_Vertex>> loop;
    for (BRepTools_WireExplorer e(TopoDS::Wire(wires.Current()), face); e.More(); e.Next())
      loop.emplace_back(e.Current(), e.CurrentVertex());
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const auto& [leaving, vertex] = loop[i];
      if (BRep_Tool::Degenerated(leaving)) continue;
      // The edge arriving at the vertex: the one before, or before the degenerated edges there
      // (a point: a B-spline face's collapsed side, where two edges meet at a cusp).
      std::size_t before = (i + loop.size() - 1) % loop.size();
      for (std::size_t k = 0; k < loop.size() && BRep_Tool::Degenerated(loop[before].first); ++k)
        before = (before + loop.size() - 1) % loop.size();
      const TopoDS_Edge& arriving = loop[before].first;
      if (BRep_Tool::Degenerated(arriving) || arriving.IsSame(leaving)) continue;
      const bool pole = before != (i + loop.size() - 1) % loop.size();
      if (pole) at_pole.Add(vertex);
      // The arriving edge ends at the vertex, the leaving one starts there (in the wire's
      // direction, against or along the edges' own).
      const std::optional<EndDirection> u_in =
          direction_from_end(arriving, arriving.Orientation() == TopAbs_REVERSED);
      const std::optional<EndDirection> u_out =
          direction_from_end(leaving, leaving.Orientation() != TopAbs_REVERSED);
      if (!u_in || !u_out) continue;
      const int v = vertices.Add(vertex);
      if (v > static_cast<int>(at.size()))
        at.resize(static_cast<std::size_t>(v)), beside.resize(static_cast<std::size_t>(v));
      if (pole)
        for (const bool from_start : {true, false}) {
          const TopoDS_Edge& edge = from_start ? leaving : arriving;
          double first = 0, last = 0;
          const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, first, last);
          // Where the edge leaves the vertex (the leaving edge's start in the wire's direction,
          // the arriving edge's end).
          const bool at_first = (edge.Orientation() != TopAbs_REVERSED) == from_start;
          if (!pcurve.IsNull())
            beside[v - 1].push_back(pcurve->Value(at_first ? first + 1e-3 * (last - first)
                                                           : last - 1e-3 * (last - first)));
        }
      // A seam is no boundary of the face in space: its two passes go.
      if (!BRep_Tool::IsClosed(leaving, face))
        at[v - 1].push_back({*u_out, true, shape.edges.FindIndex(leaving) - 1});
      if (!BRep_Tool::IsClosed(arriving, face))
        at[v - 1].push_back({*u_in, false, shape.edges.FindIndex(arriving) - 1});
    }
  }
  for (int v = 1; v <= vertices.Extent(); ++v) {
    const TopoDS_Vertex& vertex = TopoDS::Vertex(vertices(v));
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    std::optional<Vec3> n;
    if (at_pole.Contains(vertex)) {  // the mean of the normals beside it
      Vec3 sum{0, 0, 0};
      for (const gp_Pnt2d& uv : beside[v - 1])
        if (const std::optional<Vec3> there = normal_at(surface, reversed, uv.X(), uv.Y()))
          sum = sum + *there;
      if (sum.norm() > 0) n = sum * (1 / sum.norm());
    } else {
      const gp_Pnt2d uv = BRep_Tool::Parameters(vertex, face);
      n = normal_at(surface, reversed, uv.X(), uv.Y());
    }
    if (!n) continue;
    std::vector<Direction>& directions = at[v - 1];
    if (directions.empty()) continue;  // only seams there (a torus's one vertex)
    // In turn about the normal by their chords (tangent edges part by them), leaving first at
    // equal turns; a sector's angle is the turn between the chords corrected to the tangents'.
    const Vec3 first = directions.front().u.chord;
    for (Direction& d : directions) d.turn = turn(first, d.u.chord, *n);
    std::stable_sort(directions.begin(), directions.end(),
                     [](const Direction& a, const Direction& b) {
                       return a.turn < b.turn || (a.turn == b.turn && a.leaving && !b.leaving);
                     });
    // The signed turn from a direction's tangent to its chord.
    const auto bend = [&](const Direction& d) {
      const double t = turn(d.u.tangent, d.u.chord, *n);
      return t > 180 ? t - 360 : t;
    };
    for (std::size_t k = 0; k < directions.size(); ++k) {
      const Direction& from = directions[k];
      if (!from.leaving) continue;
      // The next direction in turn that is an arriving one's (the sector ends there).
      std::size_t next = (k + 1) % directions.size();
      while (next != k && directions[next].leaving) next = (next + 1) % directions.size();
      if (next == k) continue;
      const double chords = directions[next].turn - from.turn + (next > k ? 0 : 360);
      const double angle = std::clamp(chords + bend(from) - bend(directions[next]), 0.0, 360.0);
      if (angle >= limit) continue;
      SharpCorner corner;
      corner.face = face_index;
      corner.edges[0] = directions[next].edge;
      corner.edges[1] = from.edge;
      corner.angle = angle;
      corner.point = of(BRep_Tool::Pnt(vertex));
      out.push_back(corner);
    }
  }
}

}  // namespace

SharpFeatures sharp_features(const Shape& shape, double limit) {
  SharpFeatures features;
  for (int f = 0; f < shape.faces.Extent(); ++f) face_corners(shape, f, limit, features.corners);
  // Per solid, each edge's faces as the solid holds them (orientations composed), the edge as
  // each face holds it.
  for (int s = 1; s <= shape.solids.Extent(); ++s) {
    std::vector<std::vector<std::pair<TopoDS_Face, TopoDS_Edge>>> at_edge(
        static_cast<std::size_t>(shape.edges.Extent()));
    for (TopExp_Explorer faces(shape.solids(s), TopAbs_FACE); faces.More(); faces.Next()) {
      const TopoDS_Face& face = TopoDS::Face(faces.Current());
      for (TopExp_Explorer edges(face, TopAbs_EDGE); edges.More(); edges.Next()) {
        const int e = shape.edges.FindIndex(edges.Current()) - 1;
        if (e >= 0) at_edge[e].emplace_back(face, TopoDS::Edge(edges.Current()));
      }
    }
    for (int e = 0; e < shape.edges.Extent(); ++e) {
      const auto& sides = at_edge[e];
      if (sides.size() != 2 || sides[0].first.IsSame(sides[1].first)) continue;
      const TopoDS_Edge& edge = TopoDS::Edge(shape.edges(e + 1));
      if (BRep_Tool::Degenerated(edge)) continue;
      const BRepAdaptor_Curve curve(edge);
      // Per side: its surface, the edge's curve on it, and the edge's direction as the face
      // holds it.
      struct Side {
        BRepAdaptor_Surface surface;
        Handle(Geom2d_Curve) pcurve;
        bool reversed_face, reversed_edge;
      };
      std::vector<Side> side;
      for (const auto& [face, oriented] : sides) {
        double first = 0, last = 0;
        side.push_back(
            {BRepAdaptor_Surface(face), BRep_Tool::CurveOnSurface(oriented, face, first, last),
             face.Orientation() == TopAbs_REVERSED, oriented.Orientation() == TopAbs_REVERSED});
      }
      if (side[0].pcurve.IsNull() || side[1].pcurve.IsNull()) continue;
      SharpEdge sharp;
      sharp.angle = 360;
      for (int k = 0; k < kEdgeSamples; ++k) {
        const double t =
            curve.FirstParameter() +
            (k + 0.5) / kEdgeSamples * (curve.LastParameter() - curve.FirstParameter());
        const Vec3 p = of(curve.Value(t));
        const std::optional<Vec3> tangent = tangent_at(curve, t);
        if (!tangent) continue;
        // Per side: the direction into the face, normal to the edge (left of the edge as the
        // face holds it), and the face's outward normal.
        Vec3 into[2], normal[2];
        bool defined = true;
        for (int i = 0; i < 2 && defined; ++i) {
          const gp_Pnt2d uv = side[i].pcurve->Value(t);
          const std::optional<Vec3> n =
              normal_at(side[i].surface, side[i].reversed_face, uv.X(), uv.Y());
          defined = n.has_value();
          if (!defined) break;
          normal[i] = *n;
          into[i] = n->cross(side[i].reversed_edge ? *tangent * -1.0 : *tangent);
        }
        if (!defined || into[0].norm() == 0 || into[1].norm() == 0) continue;
        // Convex (the solid inside the wedge between the faces) where face 0 runs against
        // face 1's outward normal.
        const double between =
            std::acos(
                std::clamp(into[0].dot(into[1]) / (into[0].norm() * into[1].norm()), -1.0, 1.0)) *
            kDegrees;
        const double angle = into[0].dot(normal[1]) < 0 ? between : 360 - between;
        if (angle < sharp.angle) sharp.angle = angle, sharp.point = p;
      }
      if (sharp.angle >= limit) continue;
      sharp.edge = e;
      sharp.faces[0] = shape.faces.FindIndex(sides[0].first) - 1;
      sharp.faces[1] = shape.faces.FindIndex(sides[1].first) - 1;
      features.edges.push_back(sharp);
    }
  }
  return features;
}

std::vector<int> corner_nodes(const std::vector<SharpCorner>& corners, const Surface& surface) {
  std::vector<char> wanted;  // per edge: at a corner
  for (const SharpCorner& c : corners)
    for (const int e : c.edges) {
      if (e >= static_cast<int>(wanted.size())) wanted.resize(static_cast<std::size_t>(e) + 1, 0);
      wanted[e] = 1;
    }
  std::vector<std::vector<int>> ends(wanted.size());  // per edge at a corner: its nodes
  for (const auto& [key, segment] : surface.segments)
    if (segment.edge >= 0 && segment.edge < static_cast<int>(wanted.size()) && wanted[segment.edge])
      for (const int n : {pair_lo(key), pair_hi(key)}) ends[segment.edge].push_back(n);
  std::vector<int> out;
  for (const SharpCorner& c : corners) {
    int nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    for (const int e : c.edges)
      for (const int n : ends[e])
        if (const double d = (surface.nodes[n] - c.point).norm(); d < best) best = d, nearest = n;
    out.push_back(nearest);
  }
  return out;
}

std::vector<int> nodes_at(const SharpFeatures& features, const Surface& surface) {
  std::vector<char> sharp;  // per edge: whether it is a sharp edge
  for (const SharpEdge& e : features.edges) {
    if (e.edge >= static_cast<int>(sharp.size()))
      sharp.resize(static_cast<std::size_t>(e.edge) + 1, 0);
    sharp[e.edge] = 1;
  }
  std::vector<int> out;
  for (const auto& [key, segment] : surface.segments)
    if (segment.edge >= 0 && segment.edge < static_cast<int>(sharp.size()) && sharp[segment.edge])
      for (const int n : {pair_lo(key), pair_hi(key)}) out.push_back(n);
  for (const int nearest : corner_nodes(features.corners, surface))
    if (nearest >= 0) out.push_back(nearest);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<SharpFeatureReport> sharp_feature_reports(const SharpFeatures& features,
                                                      const ItemNumbering& faces,
                                                      const ItemNumbering& edges) {
  std::vector<SharpFeatureReport> out;
  for (const SharpCorner& c : features.corners)
    out.push_back({"corner",
                   {faces.number_of(c.face)},
                   {edges.number_of(c.edges[0]), edges.number_of(c.edges[1])},
                   c.angle,
                   {c.point.x, c.point.y, c.point.z}});
  for (const SharpEdge& e : features.edges)
    out.push_back({"edge",
                   {faces.number_of(e.faces[0]), faces.number_of(e.faces[1])},
                   {edges.number_of(e.edge)},
                   e.angle,
                   {e.point.x, e.point.y, e.point.z}});
  return out;
}

}  // namespace hexmerge::mesher
