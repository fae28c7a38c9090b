#include "hexmerge/occ/regions_by_solid.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_BuilderAlgo.hxx>
#include <BRepBndLib.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax2.hxx>
#include <set>
#include <sstream>

#include "fixtures.h"
#include "hexmerge/core/error.h"

namespace hexmerge::test {
namespace {

std::string brep_text(const TopoDS_Shape& shape) {
  std::ostringstream out;
  BRepTools::Write(shape, out);
  return out.str();
}

// The general fuse of the shapes: solids that share the faces where they touch, as FreeCAD's
// BooleanFragments makes them.
TopoDS_Shape fragments(const std::vector<TopoDS_Shape>& shapes) {
  TopTools_ListOfShape arguments;
  for (const auto& s : shapes) arguments.Append(s);
  BRepAlgoAPI_BuilderAlgo fuse;
  fuse.SetArguments(arguments);
  fuse.Build();
  EXPECT_TRUE(fuse.IsDone());
  return fuse.Shape();
}

// A compound of shapes that touch without sharing faces.
TopoDS_Shape compound(const std::vector<TopoDS_Shape>& shapes) {
  TopoDS_Compound c;
  BRep_Builder builder;
  builder.MakeCompound(c);
  for (const auto& s : shapes) builder.Add(c, s);
  return c;
}

TopoDS_Shape box(double x0, double x1, double size) {
  return BRepPrimAPI_MakeBox(gp_Pnt(x0, 0, 0), gp_Pnt(x1, size, size)).Shape();
}

// The index (TopExp::MapShapes order) of the solid whose bounding box starts at x = xmin.
int solid_starting_at(const TopoDS_Shape& shape, double xmin) {
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  for (int s = 1; s <= solids.Extent(); ++s) {
    Bnd_Box b;
    BRepBndLib::Add(solids(s), b, false);
    double x0, y0, z0, x1, y1, z1;
    b.Get(x0, y0, z0, x1, y1, z1);
    if (std::abs(x0 - xmin) < 1e-6) return s - 1;
  }
  return -2;
}

double centroid_x(const TetMesh& mesh, index_t t) {
  double x = 0;
  for (int k = 0; k < 4; ++k) x += 0.25 * mesh.point(mesh.tet(t)[k])[0];
  return x;
}

// Two 2 x 4 x 4 boxes side by side over a 4 x 4 x 4 Kuhn grid: the interface is x = 2.
void expect_split_at_x2(const TopoDS_Shape& shape, const char* what) {
  SCOPED_TRACE(what);
  const TetMesh mesh = kuhn_grid(4);
  RegionsBySolidReport report;
  const auto region = regions_by_solid(brep_text(shape), mesh, {}, report);
  ASSERT_EQ(region.size(), mesh.nb_tets());
  const int left = solid_starting_at(shape, 0.0), right = solid_starting_at(shape, 2.0);
  ASSERT_NE(left, right);
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    EXPECT_EQ(region[t], centroid_x(mesh, t) < 2 ? left : right) << "tet " << t;
  }
  EXPECT_EQ(report.nb_solids, 2u);
  EXPECT_EQ(report.nb_interface_nodes, 25u);  // the 5 x 5 grid nodes at x = 2
  EXPECT_EQ(report.nb_pieces, 2u);
  EXPECT_EQ(report.nb_split_pieces, 0u);
  EXPECT_EQ(report.nb_unassigned_tets, 0u);
  EXPECT_EQ(report.nb_classified_points, 2u * RegionsBySolidParameters{}.samples_per_piece);

  RegionsBySolidParameters every;
  every.classify_every_tet = true;
  EXPECT_EQ(regions_by_solid(brep_text(shape), mesh, every), region);
}

TEST(regions_by_solid, two_boxes_sharing_a_face) {
  expect_split_at_x2(fragments({box(0, 2, 4), box(2, 4, 4)}), "fragments");
}

TEST(regions_by_solid, two_touching_boxes_in_a_plain_compound) {
  expect_split_at_x2(compound({box(0, 2, 4), box(2, 4, 4)}), "compound");
}

TEST(regions_by_solid, one_thread_and_many_agree) {
  const TopoDS_Shape shape = fragments({box(0, 2, 4), box(2, 4, 4)});
  const TetMesh mesh = kuhn_grid(4);
  RegionsBySolidParameters one, four;
  one.nb_threads = 1;
  four.nb_threads = 4;
  one.classify_every_tet = four.classify_every_tet = true;
  EXPECT_EQ(regions_by_solid(brep_text(shape), mesh, one),
            regions_by_solid(brep_text(shape), mesh, four));
}

TEST(regions_by_solid, single_solid_is_one_piece) {
  const TetMesh mesh = kuhn_grid(3);
  RegionsBySolidReport report;
  const auto region = regions_by_solid(brep_text(box(0, 3, 3)), mesh, {}, report);
  EXPECT_EQ(std::set<std::int32_t>(region.begin(), region.end()), std::set<std::int32_t>{0});
  EXPECT_EQ(report.nb_pieces, 1u);
  EXPECT_EQ(report.nb_shared_faces, 0u);
}

// A cylinder through the middle of a box: the grid does not follow the curved interface, so the
// pieces' samples disagree and every tet is classified on its own, as in classify_every_tet.
TEST(regions_by_solid, interface_the_mesh_does_not_follow) {
  const TopoDS_Shape cylinder =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(2, 2, -1), gp_Dir(0, 0, 1)), 1.2, 6).Shape();
  const TopoDS_Shape shape = fragments({box(0, 4, 4), cylinder});
  const TetMesh mesh = kuhn_grid(4);
  RegionsBySolidReport report;
  const auto region = regions_by_solid(brep_text(shape), mesh, {}, report);
  EXPECT_GE(report.nb_split_pieces, 1u);
  RegionsBySolidParameters every;
  every.classify_every_tet = true;
  EXPECT_EQ(region, regions_by_solid(brep_text(shape), mesh, every));
  // Four solids (the box minus the cylinder, the cylinder inside the box, the cylinder's two
  // ends outside it); the mesh fills the box, so tets lie in the first two only.
  const std::set<std::int32_t> used(region.begin(), region.end());
  EXPECT_EQ(used.size(), 2u);
  EXPECT_EQ(used.count(NO_SOLID), 0u);
}

TEST(regions_by_solid, tets_outside_every_solid) {
  TetMesh mesh = kuhn_grid(2);
  const auto region = regions_by_solid(brep_text(box(10, 12, 2)), mesh);
  for (const auto r : region) EXPECT_EQ(r, NO_SOLID);
}

TEST(regions_by_solid, bad_input) {
  const TetMesh mesh = kuhn_grid(1);
  EXPECT_THROW(regions_by_solid("this is no BREP", mesh), InputError);
  // A shape without solids: one face of a box.
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(box(0, 1, 1), TopAbs_FACE, faces);
  EXPECT_THROW(regions_by_solid(brep_text(faces(1)), mesh), InputError);
  TetMesh broken = mesh;
  broken.tets[5] = 1000;
  EXPECT_THROW(regions_by_solid(brep_text(box(0, 1, 1)), broken), InputError);
  RegionsBySolidParameters bad;
  bad.tolerance = 0;
  EXPECT_THROW(regions_by_solid(brep_text(box(0, 1, 1)), mesh, bad), InputError);
}

}  // namespace
}  // namespace hexmerge::test
