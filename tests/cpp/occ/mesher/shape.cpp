#include "hexmerge/occ/mesher/shape.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_BuilderAlgo.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_Copy.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepGProp.hxx>
#include <BRepLib.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Builder.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Line.hxx>
#include <Geom_CylindricalSurface.hxx>
#include <Poly_Triangle.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <array>
#include <cmath>
#include <gp_Ax1.hxx>
#include <gp_Ax2.hxx>
#include <gp_Ax3.hxx>
#include <gp_Circ.hxx>
#include <gp_Dir2d.hxx>
#include <gp_Pln.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Trsf.hxx>
#include <initializer_list>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/brep_text.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

TEST(load_shape, box_faces_edges_and_solids) {
  const mesher::Shape s = load(occ_box(0, 0, 0, 3, 2, 1));
  EXPECT_EQ(s.solids.Extent(), 1);
  EXPECT_EQ(s.faces.Extent(), 6);
  EXPECT_EQ(s.edges.Extent(), 12);
  for (int count : s.face_solid_count) EXPECT_EQ(count, 1);
  ASSERT_EQ(s.edge_faces.size(), 12u);
  for (const auto& faces : s.edge_faces) EXPECT_EQ(faces.size(), 2u);
}

TEST(load_shape, face_between_two_solids_counts_twice) {
  TopTools_ListOfShape arguments;
  arguments.Append(occ_box(0, 0, 0, 2, 2, 2));
  arguments.Append(occ_box(2, 0, 0, 4, 2, 2));
  BRepAlgoAPI_BuilderAlgo fuse;
  fuse.SetArguments(arguments);
  fuse.Build();
  const mesher::Shape s = load(fuse.Shape());
  EXPECT_EQ(s.solids.Extent(), 2);
  EXPECT_EQ(s.faces.Extent(), 11);
  int shared = 0;
  for (int count : s.face_solid_count) shared += count == 2;
  EXPECT_EQ(shared, 1);
}

TEST(load_shape, an_empty_solid_is_an_input_error_naming_it) {
  // A box, then a solid with no shell at all (its extent used to come out as -inf).
  TopoDS_Solid empty;
  BRep_Builder builder;
  builder.MakeSolid(empty);
  TopoDS_Compound both;
  builder.MakeCompound(both);
  builder.Add(both, occ_box(0, 0, 0, 1, 1, 1));
  builder.Add(both, empty);
  try {
    load(both);
    FAIL() << "an empty solid was loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Solid2 of the shape is empty"), std::string::npos)
        << e.what();
  }
}

TEST(load_shape, no_solid_and_open_shell_are_input_errors) {
  const TopoDS_Shape face = BRepBuilderAPI_MakeFace(gp_Pln(), 0, 1, 0, 1).Face();
  try {
    load(face);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no solid"), std::string::npos) << e.what();
  }
  // A solid on the box's shell less one face.
  const TopoDS_Shape box = occ_box(0, 0, 0, 1, 1, 1);
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(box, TopAbs_FACE, faces);
  BRep_Builder builder;
  TopoDS_Shell shell;
  builder.MakeShell(shell);
  for (int f = 1; f < faces.Extent(); ++f) builder.Add(shell, faces(f));
  TopoDS_Solid solid;
  builder.MakeSolid(solid);
  builder.Add(solid, shell);
  try {
    load(solid);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is not closed: Edge"), std::string::npos) << e.what();
  }
}

// A box's faces, each copied on its own (no edge shared, as an IGES file or a STEP file of
// surfaces gives them): sewn into one solid of the box's volume; one face fewer leaves the others
// open, and that is refused (they would be lost).
// A 10 x 10 x 4 box with a hole through it along z whose section is a circular segment (the
// arc of `degrees` of a circle of radius 3 round (5, 5) and its chord): its top and bottom faces
// have a hole of two edges between the same two vertices.
TopoDS_Shape box_with_segment_hole(double degrees) {
  const double half = degrees * M_PI / 360;
  const gp_Pnt a(5 + 3 * std::cos(-half), 5 + 3 * std::sin(-half), -1);
  const gp_Pnt b(5 + 3 * std::cos(half), 5 + 3 * std::sin(half), -1);
  const gp_Circ circle(gp_Ax2(gp_Pnt(5, 5, -1), gp_Dir(0, 0, 1)), 3);
  const TopoDS_Edge arc = BRepBuilderAPI_MakeEdge(circle, -half, half);
  const TopoDS_Edge chord = BRepBuilderAPI_MakeEdge(b, a);
  const TopoDS_Face section = BRepBuilderAPI_MakeFace(BRepBuilderAPI_MakeWire(arc, chord));
  const TopoDS_Shape prism = BRepPrimAPI_MakePrism(section, gp_Vec(0, 0, 6));
  return BRepAlgoAPI_Cut(occ_box(0, 0, 0, 10, 10, 4), prism).Shape();
}

TEST(load_shape, a_hole_of_two_nearly_straight_edges_gets_a_vertex) {
  // An arc of 60 degrees (under BRepMesh's angular deflection, kSurfaceAngle: one segment at a
  // coarse chord deflection, as its chord): the longer edge of each of the two holes, the arc,
  // is split at its middle, and the edges as given lead to the split ones.
  const TopoDS_Shape shape = box_with_segment_hole(60);
  TopTools_IndexedMapOfShape given_faces, given_edges;
  TopExp::MapShapes(shape, TopAbs_FACE, given_faces);
  TopExp::MapShapes(shape, TopAbs_EDGE, given_edges);
  mesher::GlueSolidsReport glue;
  const mesher::Shape s = mesher::load_shape(write_brep(shape), 1e-7, glue);
  EXPECT_EQ(glue.nb_split_lens_edges, 2u);
  EXPECT_EQ(s.faces.Extent(), given_faces.Extent());
  EXPECT_EQ(s.edges.Extent(), given_edges.Extent() + 2);
  ASSERT_EQ(glue.face_images.size(), static_cast<std::size_t>(given_faces.Extent()));
  ASSERT_EQ(glue.edge_images.size(), static_cast<std::size_t>(given_edges.Extent()));
  for (const auto& images : glue.face_images) EXPECT_EQ(images.size(), 1u);
  int split = 0;
  double length = 0;
  for (int e = 1; e <= given_edges.Extent(); ++e) {
    const std::vector<int>& images = glue.edge_images[static_cast<std::size_t>(e - 1)];
    ASSERT_FALSE(images.empty());
    if (images.size() == 1) continue;
    ++split;
    // The two pieces make the edge given: an arc of 60 degrees of radius 3.
    ASSERT_EQ(images.size(), 2u);
    for (const int piece : images) length += s.edge_length[static_cast<std::size_t>(piece)];
  }
  EXPECT_EQ(split, 2);
  EXPECT_NEAR(length, 2 * M_PI, 1e-6);
  // The solid is as it was.
  GProp_GProps before, after;
  BRepGProp::VolumeProperties(shape, before);
  BRepGProp::VolumeProperties(s.shape, after);
  EXPECT_NEAR(after.Mass(), before.Mass(), 1e-9 * before.Mass());

  // A half circle turns by more than kSurfaceAngle: BRepMesh divides it, nothing is split.
  mesher::GlueSolidsReport half;
  const mesher::Shape whole =
      mesher::load_shape(write_brep(box_with_segment_hole(180)), 1e-7, half);
  EXPECT_EQ(half.nb_split_lens_edges, 0u);
  EXPECT_TRUE(half.edge_images.empty());
  EXPECT_EQ(whole.edges.Extent(), given_edges.Extent());

  // Glued to a box beside it, the same: two solids sharing one face, the images composed (each
  // given face one face, the arcs two edges each).
  TopTools_ListOfShape arguments;
  arguments.Append(shape);
  arguments.Append(occ_box(10, 0, 0, 20, 10, 4));
  BRepAlgoAPI_BuilderAlgo fuse;
  fuse.SetArguments(arguments);
  fuse.Build();
  TopTools_IndexedMapOfShape pair_faces, pair_edges;
  TopExp::MapShapes(fuse.Shape(), TopAbs_FACE, pair_faces);
  TopExp::MapShapes(fuse.Shape(), TopAbs_EDGE, pair_edges);
  mesher::GlueSolidsReport pair;
  const mesher::Shape glued = mesher::load_shape(write_brep(fuse.Shape()), 1e-7, pair);
  EXPECT_TRUE(pair.glued);
  EXPECT_EQ(pair.nb_shared_faces, 1u);
  EXPECT_EQ(pair.nb_split_lens_edges, 2u);
  EXPECT_EQ(glued.solids.Extent(), 2);
  ASSERT_EQ(pair.face_images.size(), static_cast<std::size_t>(pair_faces.Extent()));
  std::size_t in_two = 0;
  for (const auto& images : pair.face_images) EXPECT_EQ(images.size(), 1u);
  for (const auto& images : pair.edge_images) in_two += images.size() == 2;
  EXPECT_EQ(in_two, 2u);
  EXPECT_EQ(glued.edges.Extent(), pair_edges.Extent() + 2);
  GProp_GProps both;
  BRepGProp::VolumeProperties(glued.shape, both);
  EXPECT_NEAR(both.Mass(), before.Mass() + 400, 1e-9 * both.Mass());
}

TEST(load_shape, faces_only_are_sewn_into_solids) {
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(occ_box(0, 0, 0, 3, 2, 1), TopAbs_FACE, faces);
  for (const int count : {6, 5}) {
    TopoDS_Compound loose;
    BRep_Builder builder;
    builder.MakeCompound(loose);
    for (int f = 1; f <= count; ++f) builder.Add(loose, BRepBuilderAPI_Copy(faces(f)).Shape());
    mesher::GlueSolidsReport glue;
    if (count == 6) {
      const mesher::Shape s = mesher::load_shape(write_brep(loose), 1e-9, glue);
      EXPECT_EQ(glue.nb_sewn_solids, 1u);
      EXPECT_EQ(s.solids.Extent(), 1);
      EXPECT_EQ(s.faces.Extent(), 6);
      EXPECT_EQ(s.edges.Extent(), 12);  // sewn: each edge shared by two faces
      GProp_GProps volume;
      BRepGProp::VolumeProperties(s.shape, volume);
      EXPECT_NEAR(volume.Mass(), 6.0, 1e-9);  // positive: oriented outward
      continue;
    }
    try {
      mesher::load_shape(write_brep(loose), 1e-9, glue);
      FAIL() << "five faces of a box were loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("5 face(s) in 1 open one(s)"), std::string::npos)
          << e.what();
    }
  }
}

void expect_orthonormal_right_handed(const mesher::Frame& f) {
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(f.axis[a].norm(), 1, 1e-12);
    EXPECT_NEAR(f.axis[a].dot(f.axis[(a + 1) % 3]), 0, 1e-12);
  }
  EXPECT_NEAR(det3(f.axis[0], f.axis[1], f.axis[2]), 1, 1e-12);
}

// A 100 x 40 x 30 box turned 30 degrees about z: "auto" takes the normal of the largest faces
// (z) as the third axis and that of the next largest (the turned y) as the first.
// A face on a cylinder bounded by the straight lines in its parameters (u, v) between four
// corners (OpenCASCADE's MakeFace from a parameter range would bring the range within one
// period; a STEP file's curves on the face need not).
TopoDS_Face cylinder_face(const std::array<gp_Pnt2d, 4>& corners) {
  const Handle(Geom_CylindricalSurface) cylinder = new Geom_CylindricalSurface(gp_Ax3(), 2.0);
  BRepBuilderAPI_MakeWire wire;
  for (int i = 0; i < 4; ++i) {
    const gp_Pnt2d a = corners[i], b = corners[(i + 1) % 4];
    const Handle(Geom2d_Line) line = new Geom2d_Line(a, gp_Dir2d(b.X() - a.X(), b.Y() - a.Y()));
    wire.Add(BRepBuilderAPI_MakeEdge(line, cylinder, 0, a.Distance(b)).Edge());
  }
  TopoDS_Face face = BRepBuilderAPI_MakeFace(cylinder, wire.Wire()).Face();
  BRepLib::BuildCurves3d(face);
  return face;
}

TopoDS_Face cylinder_face(double sweep) {
  return cylinder_face({gp_Pnt2d(0, 0), gp_Pnt2d(sweep, 0), gp_Pnt2d(sweep, 1), gp_Pnt2d(0, 1)});
}

// A face whose parameters go 450 degrees round a cylinder covers a quarter of it twice (KiCad's
// NXP MPL115A1 has such a surface of revolution); 360 or 286 degrees, a helical strip whose
// parameters span 450 degrees but 270 at each height (as a random part's boss cylinder cut by a
// cone), a plane, a sphere do not.
TEST(face_over_itself, a_face_round_its_surface_more_than_once) {
  const auto faces_of = [](std::initializer_list<TopoDS_Shape> shapes) {
    TopTools_IndexedMapOfShape faces;
    for (const TopoDS_Shape& s : shapes) faces.Add(s);
    return faces;
  };
  const TopoDS_Face over = cylinder_face(2.5 * M_PI), round = cylinder_face(2 * M_PI),
                    part = cylinder_face(5.0);
  const TopoDS_Face helical = cylinder_face(
      {gp_Pnt2d(0, 0), gp_Pnt2d(1.5 * M_PI, 0), gp_Pnt2d(2.5 * M_PI, 1), gp_Pnt2d(M_PI, 1)});
  const TopoDS_Face plane = BRepBuilderAPI_MakeFace(gp_Pln(), 0, 1, 0, 1).Face();
  const TopoDS_Face sphere = BRepPrimAPI_MakeSphere(3.0).Face();
  EXPECT_FALSE(mesher::face_over_itself(faces_of({round, part, helical, plane, sphere})));
  const auto found = mesher::face_over_itself(faces_of({plane, round, helical, over, part}));
  ASSERT_TRUE(found);
  EXPECT_EQ(found->first, 4);
  EXPECT_NEAR(found->second, 450.0, 1e-6);
}

// BRepMesh's triangles of a face, each with two corners within the tolerance, collapse when
// triangulate() merges those corners: a failure on a face 1 wide (a KiCad pin's cone got such
// triangles at its apex), not on a face narrower than the tolerance, which is meant to collapse;
// one triangle with its corners apart is a triangulation.
TEST(triangulation_collapsed, every_triangle_with_two_corners_at_one_place) {
  const auto triangulation = [](std::initializer_list<gp_Pnt> nodes,
                                std::initializer_list<Poly_Triangle> triangles) {
    Poly_Triangulation made(static_cast<int>(nodes.size()), static_cast<int>(triangles.size()),
                            false);
    int i = 1;
    for (const gp_Pnt& p : nodes) made.SetNode(i++, p);
    i = 1;
    for (const Poly_Triangle& t : triangles) made.SetTriangle(i++, t);
    return made;
  };
  const TopoDS_Face wide = BRepBuilderAPI_MakeFace(gp_Pln(), 0, 1, 0, 1).Face();
  const TopoDS_Face narrow = BRepBuilderAPI_MakeFace(gp_Pln(), 0, 1, 0, 1e-7).Face();
  const double tolerance = 1e-5;
  const Poly_Triangulation collapsed = triangulation(
      {gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0), gp_Pnt(1, 0, 1e-6), gp_Pnt(0, 1, 0), gp_Pnt(0, 1, 1e-7)},
      {Poly_Triangle(1, 2, 3), Poly_Triangle(1, 4, 5)});
  EXPECT_TRUE(mesher::triangulation_collapsed(wide, collapsed, tolerance));
  EXPECT_FALSE(mesher::triangulation_collapsed(narrow, collapsed, tolerance));
  const Poly_Triangulation sound =
      triangulation({gp_Pnt(0, 0, 0), gp_Pnt(1, 0, 0), gp_Pnt(1, 0, 1e-6), gp_Pnt(0, 1, 0)},
                    {Poly_Triangle(1, 2, 3), Poly_Triangle(1, 2, 4)});
  EXPECT_FALSE(mesher::triangulation_collapsed(wide, sound, tolerance));
}

TEST(choose_frame, auto_follows_the_largest_planar_faces) {
  gp_Trsf turn;
  turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), M_PI / 6);
  const TopoDS_Shape box =
      BRepBuilderAPI_Transform(occ_box(0, 0, 0, 100, 40, 30), turn, true).Shape();
  const mesher::Shape s = load(box);
  const mesher::Frame f = mesher::choose_frame(s, "auto");
  expect_orthonormal_right_handed(f);
  EXPECT_NEAR(std::abs(f.axis[2].z), 1, 1e-9);
  const Vec3 turned_y{-std::sin(M_PI / 6), std::cos(M_PI / 6), 0};
  EXPECT_NEAR(std::abs(f.axis[0].dot(turned_y)), 1, 1e-9);

  const mesher::Frame global = mesher::choose_frame(s, "global");
  EXPECT_EQ(global.axis[0].x, 1);
  EXPECT_EQ(global.axis[1].y, 1);
  EXPECT_EQ(global.axis[2].z, 1);
  const mesher::Frame principal = mesher::choose_frame(s, "principal");
  expect_orthonormal_right_handed(principal);
  // The box's principal axes are its edges' directions.
  for (int a = 0; a < 3; ++a) {
    const double along =
        std::max({std::abs(principal.axis[a].z), std::abs(principal.axis[a].dot(turned_y)),
                  std::abs(principal.axis[a].dot(Vec3{turned_y.y, -turned_y.x, 0}))});
    EXPECT_NEAR(along, 1, 1e-9);
  }
}

TEST(face_planes, planar_faces_normal_to_an_axis) {
  const mesher::Shape s = load(occ_plate_with_hole());
  mesher::Frame frame = mesher::choose_frame(s, "global");
  frame.origin = Vec3{1, 2, 3};
  const auto planes = mesher::face_planes(s, frame);
  int planar = 0;
  for (const auto& plane : planes) {
    if (!plane) continue;
    ++planar;
    const double expected[3][2] = {{-1, 59}, {-2, 38}, {-3, 7}};  // offsets in the frame
    EXPECT_TRUE(std::abs(plane->offset - expected[plane->axis][0]) < 1e-9 ||
                std::abs(plane->offset - expected[plane->axis][1]) < 1e-9)
        << plane->axis << " " << plane->offset;
  }
  EXPECT_EQ(planar, 6);  // the hole's wall is not planar
}

}  // namespace
}  // namespace hexmerge::test
