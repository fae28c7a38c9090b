#include "mesher_fixtures.h"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Ax2.hxx>
#include <map>
#include <sstream>
#include <utility>

#include "hexmerge/occ/brep_text.h"
#include "hexmerge/occ/mesher/surface_repair.h"
#include "hexmerge/occ/mesher/sweep.h"

namespace hexmerge::test {

mesher::Shape load(const TopoDS_Shape& solid) {
  mesher::GlueSolidsReport glue;
  return mesher::load_shape(write_brep(solid), 1e-9, glue);
}

TopoDS_Shape occ_box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return BRepPrimAPI_MakeBox(gp_Pnt(x0, y0, z0), gp_Pnt(x1, y1, z1)).Shape();
}

TopoDS_Shape occ_cylinder(double r, double height) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), r, height).Shape();
}

TopoDS_Shape occ_bracket() {
  const TopoDS_Shape l =
      BRepAlgoAPI_Fuse(occ_box(0, 0, 0, 60, 30, 10), occ_box(0, 0, 0, 10, 30, 50)).Shape();
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(40, 15, -1), gp_Dir(0, 0, 1)), 4, 12).Shape();
  return BRepAlgoAPI_Cut(l, hole).Shape();
}

TopoDS_Shape occ_step() {
  return BRepAlgoAPI_Fuse(occ_box(0, 0, 0, 30, 20, 10), occ_box(0, 0, 10, 13, 20, 20)).Shape();
}

TopoDS_Shape occ_split_box() {
  return BRepAlgoAPI_Fuse(occ_box(0, 0, 0, 10, 10, 10), occ_box(10, 0, 0, 23, 10, 10)).Shape();
}

TopoDS_Shape occ_plate_with_hole() {
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 20, -1), gp_Dir(0, 0, 1)), 8, 12).Shape();
  return BRepAlgoAPI_Cut(occ_box(0, 0, 0, 60, 40, 10), hole).Shape();
}

TopoDS_Shape occ_bar_with_hole_near_sides() {
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 5, -1), gp_Dir(0, 0, 1)), 4.5, 12).Shape();
  return BRepAlgoAPI_Cut(occ_box(0, 0, 0, 40, 10, 10), hole).Shape();
}

Prepared prepare(const TopoDS_Shape& solid, double h, const std::string& frame) {
  Prepared p;
  p.h = h;
  p.shape = load(solid);
  std::vector<std::string> face_names;
  for (int f = 1; f <= p.shape.faces.Extent(); ++f)
    face_names.push_back("Face" + std::to_string(f));
  p.surface = mesher::triangulate(p.shape, 0.02 * h, 1e-9 * h + 1e-12, face_names);
  p.lattice =
      mesher::lay_lattice(p.shape, mesher::choose_frame(p.shape, frame), p.surface.nodes, h);
  return p;
}

bool closed_and_oriented(const std::vector<mesher::SurfaceTriangle>& triangles,
                         std::string& problem) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& t : triangles)
    for (int c = 0; c < 3; ++c) ++uses[{t.node[c], t.node[(c + 1) % 3]}];
  for (const auto& [side, n] : uses) {
    const auto back = uses.find({side.second, side.first});
    if (n != 1 || back == uses.end() || back->second != 1) {
      std::ostringstream out;
      out << "side " << side.first << " -> " << side.second << " used " << n
          << " times, its reverse " << (back == uses.end() ? 0 : back->second);
      problem = out.str();
      return false;
    }
  }
  return true;
}

TriangleSet::TriangleSet(const mesher::Surface& surface, double tolerance) : tolerance_(tolerance) {
  for (const mesher::SurfaceTriangle& t : surface.triangles)
    triangles_.insert(
        key(surface.nodes[t.node[0]], surface.nodes[t.node[1]], surface.nodes[t.node[2]]));
}

TriangleSet::Key TriangleSet::key(const Vec3& a, const Vec3& b, const Vec3& c) const {
  const auto round = [&](const Vec3& q) {
    return std::array<long long, 3>{std::llround(q.x / tolerance_), std::llround(q.y / tolerance_),
                                    std::llround(q.z / tolerance_)};
  };
  Key corners{round(a), round(b), round(c)};
  std::sort(corners.begin(), corners.end());
  return corners;
}

bool TriangleSet::has(const Vec3& a, const Vec3& b, const Vec3& c) const {
  return triangles_.count(key(a, b, c)) > 0;
}

double enclosed_volume(const std::vector<Vec3>& nodes,
                       const std::vector<mesher::SurfaceTriangle>& triangles) {
  double v = 0;
  for (const auto& t : triangles)
    v += det3(nodes[t.node[0]], nodes[t.node[1]], nodes[t.node[2]]) / 6;
  return v;
}

double distance_to_face(const mesher::Shape& shape, int face, const Vec3& p) {
  ShapeAnalysis_Surface surface(BRep_Tool::Surface(TopoDS::Face(shape.faces(face + 1))));
  surface.ValueOfUV(gp_Pnt(p.x, p.y, p.z), 1e-9);
  return surface.Gap();
}

bool occ_inside(const mesher::Shape& shape, const Vec3& p, bool& on) {
  on = false;
  for (int s = 1; s <= shape.solids.Extent(); ++s) {
    BRepClass3d_SolidClassifier classifier(shape.solids(s), gp_Pnt(p.x, p.y, p.z), 1e-7);
    if (classifier.State() == TopAbs_ON) on = true;
    if (classifier.State() == TopAbs_IN) return true;
  }
  return false;
}

void repair_surface(Prepared& p) {
  mesher::refine(p.shape, p.surface, p.h, 0.02 * p.h, p.lattice.lattice_face,
                 p.lattice.lattice_edge);
  mesher::collapse_sides(p.shape, p.surface, p.h, p.h, 0.02 * p.h, p.lattice.lattice_face);
}

Placed place(const Prepared& p) {
  Placed out;
  out.nodes = mesher::frame_nodes(p.shape, p.surface, p.lattice, -1, mesher::SweptSurface{});
  out.around = std::make_unique<mesher::Surroundings>(out.nodes, p.surface, p.lattice, p.h);
  out.parity = std::make_unique<mesher::Parity>(out.nodes, p.surface, p.shape.face_solid_count,
                                                *out.around, p.h);
  return out;
}

mesher::CoreCounts add_core(const mesher::Lattice& lattice, mesher::Surroundings& around,
                            const mesher::Parity& parity, const mesher::KeptPoints& kept,
                            int sweep_axis, double h, mesher::InsertedPoints& inserted, bool pull) {
  const mesher::CoreLayout layout =
      mesher::lay_core(lattice, around, parity, kept, sweep_axis, h, pull);
  return mesher::emit_core(lattice, layout, mesher::BufferCells{}, kept, h, around, inserted);
}

}  // namespace hexmerge::test
