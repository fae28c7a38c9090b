#include "hexmerge/occ/mesher/surface_path.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <gp_Pnt2d.hxx>
#include <memory>
#include <optional>

#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {
namespace {

class BoundaryPath final : public SurfacePath {
 public:
  BoundaryPath(const Shape& shape, const Surface& surface, const std::vector<bool>& kept_face,
               const std::vector<bool>& kept_edge, double tolerance)
      : face_(surface.nodes.size(), -1), uv_(surface.nodes.size()) {
    // A node inside one face: on no CAD edge, every triangle at it on one face.
    const std::vector<char> on_edge = nodes_on_edges(surface);
    std::vector<char> mixed(surface.nodes.size(), 0);
    for (const SurfaceTriangle& t : surface.triangles)
      for (int c = 0; c < 3; ++c) {
        const auto n = static_cast<std::size_t>(t.node[c]);
        if (face_[n] >= 0 && face_[n] != t.face) mixed[n] = 1;
        if (face_[n] < 0) face_[n] = t.face, uv_[n] = t.uv[c];
      }
    surfaces_.resize(static_cast<std::size_t>(shape.faces.Extent()));
    std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analyses(surfaces_.size());
    for (std::size_t n = 0; n < face_.size(); ++n) {
      const int f = face_[n];
      if (f < 0) continue;
      if (on_edge[n] || mixed[n] || kept_face[static_cast<std::size_t>(f)]) {
        face_[n] = -1;
        continue;
      }
      std::optional<BRepAdaptor_Surface>& s = surfaces_[static_cast<std::size_t>(f)];
      if (!s) s.emplace(TopoDS::Face(shape.faces(f + 1)), false);
      // The parameters a triangle carries are where the node was made; a repair may have moved
      // it since (needle smoothing): found again from there, else the node stays.
      const Vec3& q = surface.nodes[n];
      const gp_Pnt at_uv = s->Value(uv_[n].u, uv_[n].v);
      if (gp_Pnt(q.x, q.y, q.z).Distance(at_uv) <= tolerance) continue;
      std::unique_ptr<ShapeAnalysis_Surface>& analysis = analyses[static_cast<std::size_t>(f)];
      if (!analysis)
        analysis = std::make_unique<ShapeAnalysis_Surface>(
            BRep_Tool::Surface(TopoDS::Face(shape.faces(f + 1))));
      const gp_Pnt2d found =
          analysis->NextValueOfUV(gp_Pnt2d(uv_[n].u, uv_[n].v), gp_Pnt(q.x, q.y, q.z), tolerance);
      if (analysis->Gap() <= tolerance &&
          gp_Pnt(q.x, q.y, q.z).Distance(s->Value(found.X(), found.Y())) <= tolerance)
        uv_[n] = UV{found.X(), found.Y()};
      else
        face_[n] = -1;
    }
    // A node inside one CAD edge: on the sides of that edge only, at one parameter, strictly
    // between the curve's ends (a closed edge's vertex has two), the edge not kept and bounding
    // no kept face.
    edge_.assign(surface.nodes.size(), -1);
    t_.assign(surface.nodes.size(), 0.0);
    std::vector<char> edge_mixed(surface.nodes.size(), 0);
    std::vector<int> sides(surface.nodes.size(), 0);
    for (const auto& [key, segment] : surface.segments) {
      const auto lo = static_cast<std::size_t>(pair_lo(key)),
                 hi = static_cast<std::size_t>(pair_hi(key));
      for (const auto& [n, t] : {std::pair{lo, segment.t_lo}, std::pair{hi, segment.t_hi}}) {
        ++sides[n];
        if (edge_[n] >= 0 &&
            (edge_[n] != segment.edge || std::abs(t_[n] - t) > 1e-9 * (1 + std::abs(t))))
          edge_mixed[n] = 1;
        edge_[n] = segment.edge, t_[n] = t;
      }
    }
    curves_.resize(static_cast<std::size_t>(shape.edges.Extent()));
    for (std::size_t n = 0; n < edge_.size(); ++n) {
      const int e = edge_[n];
      if (e < 0) continue;
      bool kept = kept_edge[static_cast<std::size_t>(e)];
      for (const int f : shape.edge_faces[static_cast<std::size_t>(e)])
        kept = kept || kept_face[static_cast<std::size_t>(f)];
      std::optional<BRepAdaptor_Curve>& c = curves_[static_cast<std::size_t>(e)];
      if (!edge_mixed[n] && sides[n] == 2 && !kept && !c)
        c.emplace(TopoDS::Edge(shape.edges(e + 1)));
      if (edge_mixed[n] || sides[n] != 2 || kept || !(t_[n] > c->FirstParameter()) ||
          !(t_[n] < c->LastParameter()))
        edge_[n] = -1;
    }
  }

  int dimension(index_t v) const override {
    return v >= face_.size() ? 0 : face_[v] >= 0 ? 2 : edge_[v] >= 0 ? 1 : 0;
  }

  void tangents(index_t v, Vec3& along_u, Vec3& along_v) const override {
    gp_Pnt p;
    if (face_[v] < 0) {
      gp_Vec d;
      curve(v).D1(t_[v], p, d);
      along_u = unit_or_zero(d);
      along_v = Vec3{0, 0, 0};
      return;
    }
    gp_Vec du, dv;
    surface(v).D1(uv_[v].u, uv_[v].v, p, du, dv);
    along_u = unit_or_zero(du);
    along_v = unit_or_zero(dv);
  }

  bool at(index_t v, double a, double b, Vec3& point) const override {
    if (face_[v] < 0) {
      double t = 0;
      if (b != 0 || !along_curve(v, a, t)) return false;
      const gp_Pnt p = curve(v).Value(t);
      point = Vec3{p.X(), p.Y(), p.Z()};
      return true;
    }
    UV uv;
    if (!offset(v, a, b, uv)) return false;
    const gp_Pnt p = surface(v).Value(uv.u, uv.v);
    point = Vec3{p.X(), p.Y(), p.Z()};
    return true;
  }

  void moved(index_t v, double a, double b) override {
    if (face_[v] < 0) {
      double t = 0;
      if (along_curve(v, a, t)) t_[v] = t;
      return;
    }
    UV uv;
    if (offset(v, a, b, uv)) uv_[v] = uv;
  }

 private:
  const BRepAdaptor_Surface& surface(index_t v) const {
    return *surfaces_[static_cast<std::size_t>(face_[v])];
  }

  const BRepAdaptor_Curve& curve(index_t v) const {
    return *curves_[static_cast<std::size_t>(edge_[v])];
  }

  // Node v's parameter on its edge offset by length a; false where the curve is degenerate
  // there or the result leaves it.
  bool along_curve(index_t v, double a, double& t) const {
    const BRepAdaptor_Curve& c = curve(v);
    gp_Pnt p;
    gp_Vec d;
    c.D1(t_[v], p, d);
    const double l = d.Magnitude();
    if (!(l > 0)) return false;
    t = t_[v] + a / l;
    return t > c.FirstParameter() && t < c.LastParameter();
  }

  static Vec3 unit_or_zero(const gp_Vec& d) {
    const double n = d.Magnitude();
    return n > 0 ? Vec3{d.X() / n, d.Y() / n, d.Z() / n} : Vec3{0, 0, 0};
  }

  // Node v's parameters offset by lengths (a, b) along its two parameter directions; false
  // where a direction is degenerate there (a pole) or the result leaves the surface's domain
  // (across a periodic parameter's seam is in it).
  bool offset(index_t v, double a, double b, UV& uv) const {
    const BRepAdaptor_Surface& s = surface(v);
    gp_Pnt p;
    gp_Vec du, dv;
    s.D1(uv_[v].u, uv_[v].v, p, du, dv);
    const double lu = du.Magnitude(), lv = dv.Magnitude();
    if (!(lu > 0) || !(lv > 0)) return false;
    uv.u = uv_[v].u + a / lu;
    uv.v = uv_[v].v + b / lv;
    const auto within = [](double x, double lo, double hi, bool periodic) {
      return periodic || (x >= lo && x <= hi);
    };
    return within(uv.u, s.FirstUParameter(), s.LastUParameter(), s.IsUPeriodic()) &&
           within(uv.v, s.FirstVParameter(), s.LastVParameter(), s.IsVPeriodic());
  }

  std::vector<int> face_;  // per node, the face it lies inside (-1: none)
  std::vector<UV> uv_;     // and its parameters there
  std::vector<std::optional<BRepAdaptor_Surface>> surfaces_;  // per face, when a node needs it
  std::vector<int> edge_;  // per node, the CAD edge it lies inside (-1: none)
  std::vector<double> t_;  // and its parameter there
  std::vector<std::optional<BRepAdaptor_Curve>> curves_;  // per edge, when a node needs it
};

}  // namespace

std::unique_ptr<SurfacePath> boundary_path(const Shape& shape, const Surface& surface,
                                           const std::vector<bool>& kept_face,
                                           const std::vector<bool>& kept_edge, double tolerance) {
  return std::make_unique<BoundaryPath>(shape, surface, kept_face, kept_edge, tolerance);
}

}  // namespace hexmerge::mesher
