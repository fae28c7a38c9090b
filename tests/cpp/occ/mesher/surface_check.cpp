#include "hexmerge/occ/mesher/surface_check.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRep_Builder.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Compound.hxx>
#include <array>
#include <limits>
#include <vector>

#include "hexmerge/occ/mesher/surface_repair.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

using mesher::SurfaceTriangle;

SurfaceTriangle triangle(int a, int b, int c, int face = 0) { return {{a, b, c}, {}, face}; }

// A triangle in z = 0 and others through it, beside it, sharing a node with it.
const std::vector<Vec3> kNodes = {
    {0, 0, 0},      {2, 0, 0},     {0, 2, 0},  // 0-2: a triangle in z = 0
    {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0},  // 3-5: through it at (0.5, 0.5)
    {5, 0, 0},      {6, 0, 0},     {5, 1, 0},  // 6-8: beside it
    {1, 1, 1},      {1, 1, -1},                // 9, 10: with node 0, through (1, 1, 0)
    {0, -1, 0},     {-1, 0, 0}};               // 11, 12: with node 0, outside it

// Two triangles crossing through each other, side by side, sharing a node (meeting beyond it or
// not), sharing a side.
TEST(find_crossings, by_exact_predicates) {
  const std::vector<Vec3>& nodes = kNodes;
  const auto find = [&](const std::vector<SurfaceTriangle>& triangles) {
    return mesher::find_crossings(nodes, triangles);
  };
  const std::vector<mesher::Crossing> crossing = find({triangle(0, 1, 2), triangle(3, 4, 5)});
  ASSERT_EQ(crossing.size(), 1u);
  EXPECT_EQ(crossing[0].first, 0);
  EXPECT_EQ(crossing[0].second, 1);
  EXPECT_TRUE(find({triangle(0, 1, 2), triangle(6, 7, 8)}).empty());
  // Node 0 shared; the side 9-10 passes through (1, 1, 0), on the first's side 1-2: they meet
  // beyond the node.
  EXPECT_EQ(find({triangle(0, 1, 2), triangle(0, 9, 10)}).size(), 1u);
  EXPECT_TRUE(find({triangle(0, 1, 2), triangle(0, 11, 12)}).empty());
  EXPECT_TRUE(find({triangle(0, 1, 2), triangle(1, 0, 11)}).empty());
  // One crossing per pair of faces: faces 0 and 1 cross twice, 0 and 2 once.
  EXPECT_EQ(find({triangle(0, 1, 2), triangle(3, 4, 5, 1), triangle(3, 5, 4, 1)}).size(), 1u);
  EXPECT_EQ(find({triangle(0, 1, 2), triangle(3, 4, 5, 1), triangle(3, 5, 4, 2)}).size(), 2u);
}

// crosses_any: per triangle of a list, whether it crosses one of another list (or of itself), by
// the same test: through it, beyond a shared node; not beside it, not at the shared node only,
// not along a shared side, not itself.
TEST(crosses_any, each_triangle_against_a_list) {
  const std::vector<Vec3>& nodes = kNodes;
  const std::vector<std::array<int, 3>> surface = {{0, 1, 2}};
  const std::vector<std::array<int, 3>> inner = {{3, 4, 5},   {6, 7, 8},  {0, 9, 10},
                                                 {0, 11, 12}, {1, 0, 11}, {0, 1, 2}};
  const std::vector<char> crosses = mesher::crosses_any(nodes, surface, inner);
  EXPECT_EQ(crosses, (std::vector<char>{1, 0, 1, 0, 0, 0}));
  // Against itself: 0-9-10 passes through 0-1-2 beyond their common node, so both cross; the
  // others cross nothing.
  const std::vector<std::array<int, 3>> all = {{0, 1, 2}, {6, 7, 8}, {0, 11, 12}, {0, 9, 10}};
  EXPECT_EQ(mesher::crosses_any(nodes, all, all), (std::vector<char>{1, 0, 0, 1}));
  EXPECT_EQ(mesher::crosses_any(nodes, {}, inner), std::vector<char>(inner.size(), 0));
}

// Triangles that touch exactly (a corner on another's side, two corners at one place in one
// plane) cross; those 1e-9 apart or clearly apart do not: the quick separation test that runs
// before the exact one never hides a touch.
TEST(crosses_any, touching_exactly_is_crossing) {
  const std::vector<Vec3> nodes = {
      {0, 0, 0},     {2, 0, 0},  {0, 2, 0},    // 0-2: in z = 0
      {1, 0, 0},     {1, -1, 1}, {1, -1, -1},  // 3-5: a corner on the side 0-1
      {1, -1e-9, 0},                           // 6: with 4, 5: 1e-9 off it
      {2, 0, 0},     {3, 0, 0},  {2, 1, 0},    // 7-9: in the plane, at node 1's place
      {3, 0, 0},     {4, 0, 0},  {3, 1, 0}};   // 10-12: in the plane, apart
  const std::vector<std::array<int, 3>> surface = {{0, 1, 2}};
  const std::vector<std::array<int, 3>> inner = {{3, 4, 5}, {6, 4, 5}, {7, 8, 9}, {10, 11, 12}};
  EXPECT_EQ(mesher::crosses_any(nodes, surface, inner), (std::vector<char>{1, 0, 1, 0}));
  // Moved far from the origin (by whole numbers: the same configuration).
  std::vector<Vec3> far = nodes;
  for (Vec3& p : far) p = p + Vec3{1e5, -2e5, 3e5};
  far[6] = Vec3{1, 0, 0} + Vec3{1e5, -2e5, 3e5};  // (the 1e-9 is below the rounding there)
  EXPECT_EQ(mesher::crosses_any(far, surface, inner), (std::vector<char>{1, 1, 1, 0}));
}

// Four triangles on the side 0-1, of faces 0 to 3: one solid's boundary passing there twice (two
// CAD edges at one place) is found, unless one CAD edge bounds the four faces (a non-manifold
// solid's edge); faces of touching solids glued (face 2 bounding both) pass it once each.
TEST(find_overused_sides, a_solid_touching_itself_along_a_side) {
  mesher::Surface surface;
  surface.nodes = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  surface.triangles = {triangle(0, 1, 2, 0), triangle(1, 0, 4, 1), triangle(0, 1, 3, 2),
                       triangle(1, 0, 5, 3)};
  const std::vector<std::vector<int>> one_solid = {{0}, {0}, {0}, {0}};
  const std::vector<std::vector<int>> edge_faces = {{0, 1}, {2, 3}, {0, 1, 2, 3}};
  std::vector<mesher::OverusedSide> found =
      mesher::find_overused_sides(surface, one_solid, edge_faces);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(std::min(found[0].a, found[0].b), 0);
  EXPECT_EQ(std::max(found[0].a, found[0].b), 1);
  EXPECT_EQ(found[0].faces, (std::vector<int>{0, 1, 2, 3}));
  surface.segments[mesher::pair_key(0, 1)] = {0, 0.0, 1.0};  // edge 0 bounds faces 0 and 1 only
  EXPECT_EQ(mesher::find_overused_sides(surface, one_solid, edge_faces).size(), 1u);
  surface.segments[mesher::pair_key(0, 1)] = {2, 0.0, 1.0};  // edge 2 bounds all four
  EXPECT_TRUE(mesher::find_overused_sides(surface, one_solid, edge_faces).empty());
  surface.segments.clear();
  // Two solids: faces 0, 1 bound solid 0, faces 2, 3 solid 1 (boxes touching along an edge
  // glued are one edge; here even without one, each solid passes twice).
  EXPECT_TRUE(mesher::find_overused_sides(surface, {{0}, {0}, {1}, {1}}, edge_faces).empty());
  // A glued interface: three triangles, face 2 bounding both solids.
  surface.triangles.pop_back();
  EXPECT_TRUE(mesher::find_overused_sides(surface, {{0}, {1}, {0, 1}}, edge_faces).empty());
}

// A side between two faces of a 1 x 1 x 1 box: along their common edge they meet as the CAD
// means them to, across the box (opposite faces, 1 apart) they do not come close (faces that
// only come close, sharing BRepMesh's chord): neither is touching. Two boxes touching along a
// line, not glued (each edge there its own, as in a broken file: load_shape() would glue them):
// their faces there meet where they share no edge, the refusal's case (two of a solid's edges at
// one place).
TEST(faces_meet_along, only_where_faces_touch_along_the_side_beside_their_common_edges) {
  const auto face_at = [](const mesher::Shape& shape, const Vec3& p) {
    for (int f = 0; f < shape.faces.Extent(); ++f)
      if (distance_to_face(shape, f, p) < 1e-9) return f;
    return -1;
  };
  const mesher::Shape box = load(occ_box(0, 0, 0, 1, 1, 1));
  const int x0 = face_at(box, {0, 0.5, 0.5}), x1 = face_at(box, {1, 0.5, 0.5}),
            y0 = face_at(box, {0.5, 0, 0.5});
  ASSERT_GE(x0, 0);
  ASSERT_GE(x1, 0);
  ASSERT_GE(y0, 0);
  const std::vector<Vec3> nodes = {{0, 0, 0.2}, {0, 0, 0.8}, {0, 0.5, 0.5}, {1, 0.5, 0.5}};
  EXPECT_FALSE(mesher::faces_meet_along(box, nodes, {0, 1, {x0, y0}}, 1e-6));
  EXPECT_FALSE(mesher::faces_meet_along(box, nodes, {2, 3, {x0, x1}}, 1e-6));
  EXPECT_FALSE(mesher::faces_meet_along(box, nodes, {0, 1, {x0, x1, y0}}, 1e-6));

  TopoDS_Compound pair;
  BRep_Builder builder;
  builder.MakeCompound(pair);
  builder.Add(pair, occ_box(0, 0, 0, 1, 1, 1));
  builder.Add(pair, occ_box(1, 1, 0, 2, 2, 1));
  mesher::Shape two;
  two.shape = pair;
  TopExp::MapShapes(pair, TopAbs_FACE, two.faces);
  TopExp::MapShapes(pair, TopAbs_EDGE, two.edges);
  two.edge_faces.resize(static_cast<std::size_t>(two.edges.Extent()));
  for (int f = 1; f <= two.faces.Extent(); ++f)
    for (TopExp_Explorer ex(two.faces(f), TopAbs_EDGE); ex.More(); ex.Next())
      two.edge_faces[static_cast<std::size_t>(two.edges.FindIndex(ex.Current()) - 1)].push_back(f -
                                                                                                1);
  // Box 1's face on x = 1 and box 2's on y = 1 (its faces come after box 1's; face_at() takes
  // the first face whose surface holds the point, and box 1's y = 1 face lies on that plane too).
  const int a = face_at(two, {1, 0.5, 0.5});
  int b = -1;
  for (int f = two.faces.Extent() - 1; f >= 0 && b < 0; --f)
    if (distance_to_face(two, f, {1.5, 1, 0.5}) < 1e-9) b = f;
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 6);
  const std::vector<Vec3> line = {{1, 1, 0.2}, {1, 1, 0.8}};
  EXPECT_TRUE(mesher::faces_meet_along(two, line, {0, 1, {a, b}}, 1e-6));
}

// A tube 1140 long with walls of radius 1.0795 and 1.5875 (0.508 thick, as pyocc_11752's 178)
// at h 13, its faces about eight strips around: the refinement's flips and node moves and the
// collapses kept every triangle within the chord deflection of its face (split sides aside);
// they joined nodes across the wall before (triangles 1.5 off the outer wall, through the
// inner one, TetGen's boundary recovery never ending).
TEST(find_crossings, none_on_a_thin_tube_at_a_coarse_size) {
  const double h = 13, deflection = 0.02 * h;
  const TopoDS_Shape tube =
      BRepAlgoAPI_Cut(occ_cylinder(1.5875, 1140), occ_cylinder(1.0795, 1140)).Shape();
  Prepared p = prepare(tube, h);
  mesher::collapse_sides(p.shape, p.surface, h, std::numeric_limits<double>::infinity(), deflection,
                         p.lattice.lattice_face);
  mesher::refine(p.shape, p.surface, h, deflection, p.lattice.lattice_face, p.lattice.lattice_edge);
  mesher::collapse_sides(p.shape, p.surface, h, h, deflection, p.lattice.lattice_face);
  std::string problem;
  EXPECT_TRUE(closed_and_oriented(p.surface.triangles, problem)) << problem;
  EXPECT_GT(p.surface.triangles.size(), 1000u);
  EXPECT_TRUE(mesher::find_crossings(p.surface.nodes, p.surface.triangles).empty());
  double worst = 0;
  for (const SurfaceTriangle& t : p.surface.triangles) {
    const Vec3 c =
        (p.surface.nodes[t.node[0]] + p.surface.nodes[t.node[1]] + p.surface.nodes[t.node[2]]) *
        (1.0 / 3);
    worst = std::max(worst, distance_to_face(p.shape, t.face, c));
  }
  EXPECT_LT(worst, 1.25 * deflection);  // half the wall
}

}  // namespace
}  // namespace hexmerge::test
