#include "hexmerge/occ/mesher/sharp_features.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Ax2.hxx>
#include <vector>

#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/surface.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// A sector of `degrees` of a cone of base radius 10 and height 30 (its apex a degenerated
// edge of the curved face, between the two lines from the base).
TopoDS_Shape cone_sector(double degrees) {
  return BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10, 0, 30,
                              degrees * M_PI / 180)
      .Shape();
}

// A prism of height 10 over a polygon in z = 0.
TopoDS_Shape prism(const std::vector<gp_Pnt>& corners) {
  BRepBuilderAPI_MakePolygon polygon;
  for (const gp_Pnt& p : corners) polygon.Add(p);
  polygon.Close();
  const TopoDS_Face base = BRepBuilderAPI_MakeFace(polygon.Wire()).Face();
  return BRepPrimAPI_MakePrism(base, gp_Vec(0, 0, 10)).Shape();
}

// The prism over a triangle whose corner at the origin is `degrees` wide (sides of 50 along x
// and along the direction at that angle).
TopoDS_Shape wedge(double degrees) {
  const double a = degrees * M_PI / 180;
  return prism({gp_Pnt(0, 0, 0), gp_Pnt(50, 0, 0), gp_Pnt(50 * std::cos(a), 50 * std::sin(a), 0)});
}

// The curved face of a 20-degree sector of a cone meets itself at the apex through a
// degenerated edge: the two lines from the base part there by 2 asin(sin(10 degrees) sin(half
// angle)), 6.29 degrees (half angle atan(1/3)), a corner of the face; the whole cone has none.
TEST(sharp_features, a_corner_through_a_degenerated_edge) {
  const mesher::Shape shape = load(cone_sector(20));
  const mesher::SharpFeatures sharp = mesher::sharp_features(shape, mesher::kSharpAngle);
  const double expected =
      2 * std::asin(std::sin(10 * M_PI / 180) * std::sin(std::atan(1.0 / 3))) * 180 / M_PI;
  std::size_t at_apex = 0;
  for (const mesher::SharpCorner& c : sharp.corners)
    if (std::abs(c.point.z - 30) < 1e-9) {
      ++at_apex;
      EXPECT_NEAR(c.angle, expected, 1e-3);
      EXPECT_NE(c.edges[0], c.edges[1]);
    }
  EXPECT_EQ(at_apex, 1u);
  for (const mesher::SharpCorner& c :
       mesher::sharp_features(load(cone_sector(360)), mesher::kSharpAngle).corners)
    EXPECT_GT(std::abs(c.point.z - 30), 1e-9);
}

// A 5-degree wedge: its two triangles' corners at the origin's edge, and that edge, are 5
// degrees inside the solid; nothing else is under 45.
TEST(sharp_features, a_thin_wedge_has_its_corners_and_edge) {
  const mesher::Shape shape = load(wedge(5));
  const mesher::SharpFeatures sharp = mesher::sharp_features(shape, 45);
  ASSERT_EQ(sharp.corners.size(), 2u);
  for (const mesher::SharpCorner& c : sharp.corners) {
    EXPECT_NEAR(c.angle, 5, 1e-6);
    EXPECT_NEAR(c.point.x, 0, 1e-9);
    EXPECT_NEAR(c.point.y, 0, 1e-9);
    EXPECT_NE(c.edges[0], c.edges[1]);
  }
  ASSERT_EQ(sharp.edges.size(), 1u);
  EXPECT_NEAR(sharp.edges[0].angle, 5, 1e-6);
  EXPECT_NEAR(sharp.edges[0].point.x, 0, 1e-9);
  EXPECT_NEAR(sharp.edges[0].point.y, 0, 1e-9);
  EXPECT_NE(sharp.edges[0].faces[0], sharp.edges[0].faces[1]);
  // Under the limit of a scaled Jacobian of 0.2 (8.13 degrees) too; a 10-degree wedge is not.
  EXPECT_EQ(mesher::sharp_features(shape, mesher::kSharpAngle).edges.size(), 1u);
  const mesher::SharpFeatures wider = mesher::sharp_features(load(wedge(10)), mesher::kSharpAngle);
  EXPECT_TRUE(wider.corners.empty() && wider.edges.empty());
}

// A hole touching a side (gmsh_as1-tu-203 has such): the top and bottom faces narrow to nothing
// on both sides of the point of contact, and so does the solid along the line of contact.
TEST(sharp_features, a_hole_tangent_to_a_side_makes_cusps) {
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 10, -1), gp_Dir(0, 0, 1)), 5, 7).Shape();
  const mesher::Shape shape = load(BRepAlgoAPI_Cut(occ_box(0, 0, 0, 20, 20, 5), hole).Shape());
  const mesher::SharpFeatures sharp = mesher::sharp_features(shape, mesher::kSharpAngle);
  ASSERT_EQ(sharp.corners.size(), 4u);
  for (const mesher::SharpCorner& c : sharp.corners) {
    EXPECT_NEAR(c.angle, 0, 1e-6);
    EXPECT_NEAR(c.point.x, 0, 1e-9);
    EXPECT_NEAR(c.point.y, 10, 1e-9);
  }
  for (const mesher::SharpEdge& e : sharp.edges) EXPECT_LT(e.angle, mesher::kSharpAngle);
}

// The surface's nodes at them: every node of a sharp edge's segments, also where the edge bounds
// a sharp corner too, and the node at the corner's vertex.
TEST(sharp_features, nodes_at_take_the_sharp_edges_and_the_corners) {
  mesher::Surface surface;
  surface.nodes = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 1, 0}, {4, 2, 0}};
  surface.segments[mesher::pair_key(0, 1)] = {7, 0.0, 0.5};
  surface.segments[mesher::pair_key(1, 2)] = {7, 0.5, 1.0};
  surface.segments[mesher::pair_key(2, 3)] = {8, 0.0, 0.5};
  surface.segments[mesher::pair_key(3, 4)] = {8, 0.5, 1.0};
  mesher::SharpFeatures sharp;
  mesher::SharpEdge edge;
  edge.edge = 7;
  sharp.edges.push_back(edge);
  mesher::SharpCorner corner;
  corner.edges[0] = 7, corner.edges[1] = 8, corner.point = {2, 0, 0};
  sharp.corners.push_back(corner);
  EXPECT_EQ(mesher::nodes_at(sharp, surface), (std::vector<int>{0, 1, 2}));
  sharp.edges.clear();
  EXPECT_EQ(mesher::nodes_at(sharp, surface), (std::vector<int>{2}));
}

// Right angles, concave edges and a hole's round edges (the bracket), a cylinder: nothing is
// under 90; at 90.001 the box's 12 edges and 24 face corners.
TEST(sharp_features, right_and_reflex_angles_are_not_sharp) {
  const mesher::SharpFeatures bracket = mesher::sharp_features(load(occ_bracket()), 89.999);
  EXPECT_TRUE(bracket.corners.empty() && bracket.edges.empty());
  // All of them, on a prism over an L: its two caps have a corner of 270 degrees, its inner
  // edge is 270.
  const mesher::SharpFeatures all =
      mesher::sharp_features(load(prism({gp_Pnt(0, 0, 0), gp_Pnt(30, 0, 0), gp_Pnt(30, 10, 0),
                                         gp_Pnt(10, 10, 0), gp_Pnt(10, 30, 0), gp_Pnt(0, 30, 0)})),
                             360);
  EXPECT_EQ(all.corners.size(), 2u * 6 + 6u * 4);
  EXPECT_EQ(
      std::count_if(all.corners.begin(), all.corners.end(),
                    [](const mesher::SharpCorner& c) { return std::abs(c.angle - 270) < 1e-9; }),
      2);
  EXPECT_EQ(all.edges.size(), 18u);
  EXPECT_EQ(
      std::count_if(all.edges.begin(), all.edges.end(),
                    [](const mesher::SharpEdge& e) { return std::abs(e.angle - 270) < 1e-9; }),
      1);
  const mesher::SharpFeatures cylinder = mesher::sharp_features(load(occ_cylinder(5, 10)), 89.999);
  EXPECT_TRUE(cylinder.corners.empty() && cylinder.edges.empty());
  // A torus: one face, its one vertex on seams only (it crashed the corners' sort once).
  const mesher::SharpFeatures torus =
      mesher::sharp_features(load(BRepPrimAPI_MakeTorus(20, 5).Shape()), 360);
  EXPECT_TRUE(torus.corners.empty() && torus.edges.empty());
  const mesher::SharpFeatures box = mesher::sharp_features(load(occ_box(0, 0, 0, 1, 2, 3)), 90.001);
  EXPECT_EQ(box.edges.size(), 12u);
  EXPECT_EQ(box.corners.size(), 24u);
  for (const mesher::SharpEdge& e : box.edges) EXPECT_NEAR(e.angle, 90, 1e-9);
  for (const mesher::SharpCorner& c : box.corners) EXPECT_NEAR(c.angle, 90, 1e-9);
}

}  // namespace
}  // namespace hexmerge::test
