#include "hexmerge/occ/mesher/shape.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <GProp_PrincipalProps.hxx>
#include <Geom2d_Curve.hxx>
#include <GeomLib_IsPlanarSurface.hxx>
#include <Geom_Curve.hxx>
#include <ShapeAnalysis_Curve.hxx>
#include <ShapeFix_Solid.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shell.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <gp_Pln.hxx>
#include <gp_Pnt2d.hxx>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/brep_text.h"
#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {

namespace {

// A shape of faces or shells only (an IGES file, a STEP file of surfaces): its faces sewn within
// 1e-6 of its bounding box's diagonal, and each closed shell made a solid (oriented so that it
// bounds a finite volume). FreeCAD's SOT23.stp (73 faces, each its own shell) is one closed
// shell so. A face left in an open shell would be lost: refused instead.
TopoDS_Shape solids_of_faces(const TopoDS_Shape& shape, std::size_t& nb_solids) {
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  if (faces.IsEmpty())
    throw InputError(
        "the shape holds no solid and no face (a wire or points cannot be meshed into tets): "
        "give a closed solid");
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  BRepBuilderAPI_Sewing sewing(box.IsVoid() ? 1e-7 : 1e-6 * std::sqrt(box.SquareExtent()));
  for (int f = 1; f <= faces.Extent(); ++f) sewing.Add(faces(f));
  sewing.Perform();
  const TopoDS_Shape sewn = sewing.SewedShape();
  TopoDS_Compound solids;
  BRep_Builder builder;
  builder.MakeCompound(solids);
  std::size_t closed = 0, open = 0, open_faces = 0;
  for (TopExp_Explorer ex(sewn, TopAbs_SHELL); ex.More(); ex.Next()) {
    const TopoDS_Shell& shell = TopoDS::Shell(ex.Current());
    if (!BRep_Tool::IsClosed(shell)) {
      ++open;
      for (TopExp_Explorer f(shell, TopAbs_FACE); f.More(); f.Next()) ++open_faces;
      continue;
    }
    ShapeFix_Solid fix;
    builder.Add(solids, fix.SolidFromShell(shell));
    ++closed;
  }
  for (TopExp_Explorer f(sewn, TopAbs_FACE, TopAbs_SHELL); f.More(); f.Next()) ++open_faces, ++open;
  if (open_faces > 0 || closed == 0)
    throw InputError("the shape holds no solid, and its " + std::to_string(faces.Extent()) +
                     " face(s) do not all close a volume: sewn together, they make " +
                     std::to_string(closed) + " closed shell(s) and leave " +
                     std::to_string(open_faces) + " face(s) in " + std::to_string(open) +
                     " open one(s), which would be lost; give closed solids (FreeCAD: Part > "
                     "Shape builder, solid from shell)");
  nb_solids = closed;
  return solids;
}

// The first edge of a solid (1-based: solid, then edge in `edges`) that bounds a single face of
// it but as a seam: the solid's boundary is open there. None: every solid is closed.
std::optional<std::pair<int, int>> open_edge(const TopTools_IndexedMapOfShape& solids,
                                             const TopTools_IndexedMapOfShape& edges) {
  for (int i = 1; i <= solids.Extent(); ++i) {
    TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
    TopExp::MapShapesAndAncestors(solids(i), TopAbs_EDGE, TopAbs_FACE, edge_faces);
    for (int e = 1; e <= edge_faces.Extent(); ++e) {
      const TopoDS_Edge& edge = TopoDS::Edge(edge_faces.FindKey(e));
      if (BRep_Tool::Degenerated(edge)) continue;
      const TopTools_ListOfShape& around = edge_faces.FindFromIndex(e);
      if (around.Extent() >= 2) continue;
      if (around.Extent() == 1 && BRep_Tool::IsClosed(edge, TopoDS::Face(around.First()))) continue;
      // An edge inside a face (INTERNAL: a random part's circle on a sphere where a boolean cut
      // it, valid by FreeCAD's BOP check) bounds nothing.
      bool bounds = false;
      for (const TopoDS_Shape& face : around)
        for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More() && !bounds; ex.Next())
          bounds = ex.Current().IsSame(edge) && (ex.Current().Orientation() == TopAbs_FORWARD ||
                                                 ex.Current().Orientation() == TopAbs_REVERSED);
      if (!bounds) continue;
      return std::make_pair(i, edges.FindIndex(edge));
    }
  }
  return std::nullopt;
}

}  // namespace

Shape load_shape(const std::string& brep, double glue_tolerance, GlueSolidsReport& glue) {
  Shape s;
  s.shape = read_brep(brep);
  TopExp::MapShapes(s.shape, TopAbs_SOLID, s.solids);
  std::size_t nb_sewn = 0;
  if (s.solids.IsEmpty()) {
    s.shape = solids_of_faces(s.shape, nb_sewn);
    TopExp::MapShapes(s.shape, TopAbs_SOLID, s.solids);
  }
  const TopoDS_Shape given = s.shape;  // its edges numbered as the user numbers them
  for (int i = 1; i <= s.solids.Extent(); ++i)
    if (!TopExp_Explorer(s.solids(i), TopAbs_FACE).More())
      throw InputError("Solid" + std::to_string(i) +
                       " of the shape is empty (it has no faces): give closed solids");
  // Faces or edges beside the solids bound no volume: only the solids are meshed (points beside
  // them, as pyocc_face_recognition_sample_part's 30, change nothing and stay).
  // (Gmsh's STEP export of hex_bolt.geo holds the profile face the body was revolved from; its
  // edge across the tip's disc crossed the disc's triangles, and TetGen refused every input.)
  {
    TopoDS_Compound solids;
    BRep_Builder builder;
    builder.MakeCompound(solids);
    for (int i = 1; i <= s.solids.Extent(); ++i) builder.Add(solids, s.solids(i));
    TopTools_IndexedMapOfShape in_shape, in_solids;
    TopExp::MapShapes(s.shape, TopAbs_EDGE, in_shape);
    TopExp::MapShapes(solids, TopAbs_EDGE, in_solids);
    if (in_shape.Extent() != in_solids.Extent()) s.shape = solids;
  }
  {
    // A closed shell: every edge of a solid bounds two of its faces, or one face twice (a seam).
    TopTools_IndexedMapOfShape given_edges;
    TopExp::MapShapes(given, TopAbs_EDGE, given_edges);
    if (const auto open = open_edge(s.solids, given_edges))
      throw InputError("Solid" + std::to_string(open->first) + " is not closed: Edge" +
                       std::to_string(open->second) +
                       " bounds a single face (an open shell); give a closed solid");
  }
  {
    TopTools_IndexedMapOfShape given_faces;
    TopExp::MapShapes(given, TopAbs_FACE, given_faces);
    if (const auto over = face_over_itself(given_faces)) {
      std::ostringstream degrees;
      degrees.precision(4);
      degrees << over->second;
      throw InputError("the shape is broken: Face" + std::to_string(over->first) +
                       " covers part of its surface twice (its parameters go " + degrees.str() +
                       " degrees round a surface that closes after 360), so no mesh can follow "
                       "it. Repair the shape (FreeCAD's Part > Check geometry, with its BOP "
                       "check, lists such faces)");
    }
  }
  // OpenCASCADE's General Fuse can leave a glued solid open where others touch it, at a fuzzy
  // value near round-off (KiCad's Ethernet transformer HALO TG111, its twelve pins on its body:
  // twelve edges of the body bound one face each at 1.1e-7, none at 1e-5): glued again with a
  // larger fuzzy value, 1e-5 and then 1e-4 of the shape's diagonal.
  Bnd_Box given_box;
  BRepBndLib::Add(s.shape, given_box);
  const double given_diagonal = given_box.IsVoid() ? 0.0 : std::sqrt(given_box.SquareExtent());
  std::optional<std::pair<int, int>> open;
  for (const double fuzzy : {glue_tolerance, 1e-5 * given_diagonal, 1e-4 * given_diagonal}) {
    if (fuzzy < glue_tolerance) continue;
    const TopoDS_Shape glued = glue_solids(s.shape, fuzzy, glue);
    TopTools_IndexedMapOfShape glued_solids, glued_edges;
    TopExp::MapShapes(glued, TopAbs_SOLID, glued_solids);
    TopExp::MapShapes(glued, TopAbs_EDGE, glued_edges);
    open = open_edge(glued_solids, glued_edges);
    if (!open) {
      s.shape = glued;
      break;
    }
  }
  if (open)
    throw InputError("OpenCASCADE's General Fuse, gluing the shape's " +
                     std::to_string(s.solids.Extent()) + " solids where they touch, left Solid" +
                     std::to_string(open->first) +
                     " open (an edge of it bounds a single face) at every fuzzy value tried, up "
                     "to " +
                     std::to_string(1e-4 * given_diagonal) +
                     ": glue the solids in FreeCAD (Part BooleanFragments) and mesh the result");
  s.shape = split_lens_edges(s.shape, glue);
  glue.nb_sewn_solids = nb_sewn;
  s.solids.Clear();
  TopExp::MapShapes(s.shape, TopAbs_SOLID, s.solids);
  Bnd_Box box;
  BRepBndLib::Add(s.shape, box);
  if (!box.IsVoid()) s.diagonal = std::sqrt(box.SquareExtent());
  TopExp::MapShapes(s.shape, TopAbs_FACE, s.faces);
  TopExp::MapShapes(s.shape, TopAbs_EDGE, s.edges);
  s.face_solids.assign(static_cast<std::size_t>(s.faces.Extent()), {});
  s.face_solid_count.assign(static_cast<std::size_t>(s.faces.Extent()), 0);
  for (int i = 1; i <= s.solids.Extent(); ++i) {
    TopTools_IndexedMapOfShape solid_faces;
    TopExp::MapShapes(s.solids(i), TopAbs_FACE, solid_faces);
    for (int f = 1; f <= solid_faces.Extent(); ++f) {
      const int index = s.faces.FindIndex(solid_faces(f));
      if (index <= 0) continue;
      s.face_solids[static_cast<std::size_t>(index - 1)].push_back(i - 1);
      ++s.face_solid_count[static_cast<std::size_t>(index - 1)];
    }
  }
  s.edge_faces.resize(static_cast<std::size_t>(s.edges.Extent()));
  s.edge_length.assign(static_cast<std::size_t>(s.edges.Extent()), 0.0);
  for (int e = 1; e <= s.edges.Extent(); ++e) {
    const TopoDS_Edge& edge = TopoDS::Edge(s.edges(e));
    if (!BRep_Tool::Degenerated(edge))
      s.edge_length[static_cast<std::size_t>(e - 1)] = edge_length(edge);
  }
  s.face_area.assign(static_cast<std::size_t>(s.faces.Extent()), 0.0);
  s.face_width.assign(s.face_area.size(), std::numeric_limits<double>::infinity());
  for (int f = 1; f <= s.faces.Extent(); ++f) {
    GProp_GProps area;
    BRepGProp::SurfaceProperties(s.faces(f), area);
    const auto i = static_cast<std::size_t>(f - 1);
    s.face_area[i] = area.Mass();
    double perimeter = 0;
    for (TopExp_Explorer e(s.faces(f), TopAbs_EDGE); e.More(); e.Next())
      perimeter += s.edge_length[static_cast<std::size_t>(s.edges.FindIndex(e.Current()) - 1)];
    if (perimeter > 0) s.face_width[i] = 2 * s.face_area[i] / perimeter;
  }
  BRepGProp::VolumeProperties(s.shape, s.volume);
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(s.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  for (int e = 1; e <= edge_faces.Extent(); ++e) {
    const int edge = s.edges.FindIndex(edge_faces.FindKey(e)) - 1;
    for (const TopoDS_Shape& f : edge_faces.FindFromIndex(e)) {
      const int face = s.faces.FindIndex(f) - 1;
      auto& list = s.edge_faces[edge];
      if (std::find(list.begin(), list.end(), face) == list.end()) list.push_back(face);
    }
  }
  return s;
}

// (KiCad's NXP MPL115A1: a pad's corner, a surface of revolution trimmed to 450 degrees where
// its edges turn 90.)
std::optional<std::pair<int, double>> face_over_itself(const TopTools_IndexedMapOfShape& faces) {
  constexpr int kSamples = 32;      // per parameter, inside the face's parameter box
  constexpr int kEdgeSamples = 64;  // points per edge's curve in the face's parameters
  for (int i = 1; i <= faces.Extent(); ++i) {
    const TopoDS_Face& face = TopoDS::Face(faces(i));
    const BRepAdaptor_Surface surface(face, false);
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    // The face's boundary in its parameters as they are (OpenCASCADE's classifiers take them
    // modulo the periods): each edge's curve on it, as a polyline.
    std::vector<std::array<gp_Pnt2d, 2>> sides;
    const auto boundary = [&]() {
      if (!sides.empty()) return;
      for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
        double first = 0, last = 0;
        const Handle(Geom2d_Curve) curve =
            BRep_Tool::CurveOnSurface(TopoDS::Edge(ex.Current()), face, first, last);
        if (curve.IsNull()) continue;
        gp_Pnt2d previous = curve->Value(first);
        for (int k = 1; k <= kEdgeSamples; ++k) {
          const gp_Pnt2d next = curve->Value(first + (last - first) * k / kEdgeSamples);
          sides.push_back({previous, next});
          previous = next;
        }
      }
    };
    // Even-odd: whether a ray from p along +u crosses the boundary an odd number of times.
    const auto inside = [&](double u, double v) {
      bool in = false;
      for (const auto& [a, b] : sides)
        if ((a.Y() > v) != (b.Y() > v) &&
            u < a.X() + (v - a.Y()) * (b.X() - a.X()) / (b.Y() - a.Y()))
          in = !in;
      return in;
    };
    for (const bool along_u : {true, false}) {
      if (along_u ? !surface.IsUPeriodic() : !surface.IsVPeriodic()) continue;
      const double period = along_u ? surface.UPeriod() : surface.VPeriod();
      const double span = along_u ? u1 - u0 : v1 - v0;
      if (span <= period * (1 + 1e-9)) continue;
      boundary();
      for (int a = 1; a < kSamples; ++a)
        for (int b = 1; b < kSamples; ++b) {
          const double u = u0 + (u1 - u0) * a / kSamples, v = v0 + (v1 - v0) * b / kSamples;
          const double qu = along_u ? u + period : u, qv = along_u ? v : v + period;
          if ((along_u ? qu < u1 : qv < v1) && inside(u, v) && inside(qu, qv))
            return std::make_pair(i, span * 360 / period);
        }
    }
  }
  return std::nullopt;
}

namespace {

// The face's plane: its surface's when that is a plane, else where its surface (a B-spline or
// Bezier patch, as STEP files from some systems store every face) is flat to 1e-7 of the shape's
// diagonal (gmsh_917_fusee: 130 of its 249 B-spline faces, 64 % of its area; gmsh_t20_data 7 of
// 21, 57 %; gmsh_wrenchnut 24 of 36, 38 %: measured with FreeCAD's findPlane).
std::optional<gp_Pln> plane_of(const TopoDS_Face& face, double diagonal) {
  BRepAdaptor_Surface surface(face, false);
  if (surface.GetType() == GeomAbs_Plane) return surface.Plane();
  if (surface.GetType() != GeomAbs_BSplineSurface && surface.GetType() != GeomAbs_BezierSurface)
    return std::nullopt;
  const GeomLib_IsPlanarSurface planar(BRep_Tool::Surface(face), 1e-7 * diagonal);
  if (!planar.IsPlanar()) return std::nullopt;
  return planar.Plan();
}

}  // namespace

Frame choose_frame(const Shape& s, const std::string& kind) {
  const Vec3 global[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (kind == "global") return make_frame(global[2], &global[0], global);
  const GProp_PrincipalProps principal = s.volume.PrincipalProperties();
  const Vec3 principal_axes[3] = {of(gp_Dir(principal.FirstAxisOfInertia())),
                                  of(gp_Dir(principal.SecondAxisOfInertia())),
                                  of(gp_Dir(principal.ThirdAxisOfInertia()))};
  if (kind == "principal") return make_frame(principal_axes[2], &principal_axes[0], principal_axes);
  // "auto": planar face normals, grouped by direction (up to sign), weighted by area.
  std::vector<std::pair<Vec3, double>> directions;
  for (int i = 1; i <= s.faces.Extent(); ++i) {
    const TopoDS_Face& face = TopoDS::Face(s.faces(i));
    const std::optional<gp_Pln> plane = plane_of(face, s.diagonal);
    if (!plane) continue;
    const double area = s.face_area[static_cast<std::size_t>(i - 1)];
    const Vec3 n = of(plane->Axis().Direction());
    bool merged = false;
    for (auto& [d, a] : directions)
      if (std::abs(std::abs(d.dot(n)) - 1) < 1e-9) a += area, merged = true;
    if (!merged) directions.emplace_back(n, area);
  }
  if (directions.empty()) return make_frame(principal_axes[2], &principal_axes[0], principal_axes);
  std::stable_sort(directions.begin(), directions.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  const Vec3 e3 = directions[0].first;
  for (std::size_t i = 1; i < directions.size(); ++i)
    if (std::abs(directions[i].first.dot(e3)) < 1e-9)
      return make_frame(e3, &directions[i].first, principal_axes);
  return make_frame(e3, nullptr, principal_axes);
}

std::vector<std::optional<AxisPlane>> face_planes(const Shape& shape, const Frame& frame) {
  std::vector<std::optional<AxisPlane>> face_plane(shape.faces.Extent());
  for (int fi = 1; fi <= shape.faces.Extent(); ++fi) {
    const std::optional<gp_Pln> plane = plane_of(TopoDS::Face(shape.faces(fi)), shape.diagonal);
    if (!plane) continue;
    const Vec3 n = of(plane->Axis().Direction());
    for (int a = 0; a < 3; ++a) {
      if (std::abs(std::abs(n.dot(frame.axis[a])) - 1) > 1e-9) continue;
      const double offset = coord(frame.to_frame(of(plane->Location())), a);
      const double width = shape.face_width[static_cast<std::size_t>(fi - 1)];
      face_plane[fi - 1] = AxisPlane{a, offset, std::isinf(width) ? 0 : width};
    }
  }
  return face_plane;
}

bool triangulation_collapsed(const TopoDS_Face& face, const Poly_Triangulation& triangulation,
                             double tolerance) {
  for (int k = 1; k <= triangulation.NbTriangles(); ++k) {
    int n[3];
    triangulation.Triangle(k).Get(n[0], n[1], n[2]);
    bool collapses = false;
    for (int c = 0; c < 3; ++c)
      collapses = collapses || triangulation.Node(n[c]).Distance(
                                   triangulation.Node(n[(c + 1) % 3])) <= tolerance;
    if (!collapses) return false;
  }
  GProp_GProps area, perimeter;
  BRepGProp::SurfaceProperties(face, area);
  BRepGProp::LinearProperties(face, perimeter);
  return 2 * area.Mass() > 10 * tolerance * perimeter.Mass();
}

std::optional<std::pair<double, Vec3>> nearest_on_edge(const Shape& s, int edge, const Vec3& p,
                                                       double tolerance) {
  double first = 0, last = 0;
  const Handle(Geom_Curve) curve = BRep_Tool::Curve(TopoDS::Edge(s.edges(edge + 1)), first, last);
  if (curve.IsNull()) return std::nullopt;
  gp_Pnt projected;
  double parameter = 0;
  const double distance = ShapeAnalysis_Curve().Project(curve, gp_Pnt(p.x, p.y, p.z), tolerance,
                                                        projected, parameter, first, last);
  return std::pair<double, Vec3>{distance, of(projected)};
}

}  // namespace hexmerge::mesher
