#include "hexmerge/occ/mesher/surface.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Common.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <algorithm>
#include <cmath>
#include <string>

#include "hexmerge/occ/mesher/corner_strips.h"
#include "hexmerge/occ/mesher/sharp_features.h"
#include "hexmerge/occ/mesher/surface_repair.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

using mesher::Surface;

// The triangulation is closed and outward, and every node lies on the CAD face it is said to be
// on, as are the three nodes of every triangle on the triangle's face.
void expect_sound_surface(const Prepared& p, const Surface& surface, double volume,
                          double relative_volume_tolerance, double on_face_tolerance) {
  std::string problem;
  EXPECT_TRUE(closed_and_oriented(surface.triangles, problem)) << problem;
  EXPECT_NEAR(enclosed_volume(surface.nodes, surface.triangles), volume,
              relative_volume_tolerance * volume);
  ASSERT_EQ(surface.node_face.size(), surface.nodes.size());
  for (std::size_t n = 0; n < surface.nodes.size(); ++n)
    EXPECT_LT(distance_to_face(p.shape, surface.node_face[n], surface.nodes[n]), on_face_tolerance)
        << "node " << n;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    for (int n : surface.triangles[t].node)
      EXPECT_LT(distance_to_face(p.shape, surface.triangles[t].face, surface.nodes[n]),
                on_face_tolerance)
          << "triangle " << t << " node " << n;
}

TEST(triangulate, box_is_closed_outward_and_on_its_faces) {
  const Prepared p = prepare(occ_box(0, 0, 0, 20, 10, 5), 2.0);
  EXPECT_EQ(p.shape.faces.Extent(), 6);
  expect_sound_surface(p, p.surface, 1000.0, 1e-12, 1e-9);
}

TEST(triangulate, cylinder_is_closed_outward_and_on_its_faces) {
  const double r = 10, height = 30, h = 3;
  const Prepared p = prepare(occ_cylinder(r, height), h);
  // Chords inside the circle: the polyhedron is a little smaller, by at most the deflection.
  const double volume = M_PI * r * r * height;
  expect_sound_surface(p, p.surface, volume, 2 * 0.02 * h / r, 1e-7);
  EXPECT_LT(enclosed_volume(p.surface.nodes, p.surface.triangles), volume);
}

TEST(triangulate, nodes_shared_across_faces_are_merged) {
  // A box's 8 corners and nothing twice: every node is on at least one triangle, and no two
  // nodes coincide.
  const Prepared p = prepare(occ_box(0, 0, 0, 20, 10, 5), 2.0);
  for (std::size_t a = 0; a < p.surface.nodes.size(); ++a)
    for (std::size_t b = a + 1; b < p.surface.nodes.size(); ++b)
      EXPECT_GT((p.surface.nodes[a] - p.surface.nodes[b]).norm(), 1e-6) << a << " " << b;
}

// Refinement brings every side of the faces off the lattice to at most h (sides on edges
// between lattice faces excepted), keeps the surface closed and its nodes on the CAD, and the
// collapses after it keep that too.
TEST(refine, sides_at_most_h_on_the_cad) {
  const double h = 3;
  Prepared p = prepare(occ_plate_with_hole(), h);
  const auto& lattice = p.lattice;
  mesher::refine(p.shape, p.surface, h, 0.02 * h, lattice.lattice_face, lattice.lattice_edge);
  const double volume = 60 * 40 * 10 - M_PI * 8 * 8 * 10;
  expect_sound_surface(p, p.surface, volume, 0.01, 1e-6 * h);
  std::size_t checked = 0;
  for (const auto& t : p.surface.triangles) {
    if (lattice.lattice_face[t.face]) continue;
    for (int c = 0; c < 3; ++c) {
      const int a = t.node[c], b = t.node[(c + 1) % 3];
      const auto segment = p.surface.segments.find(mesher::pair_key(a, b));
      if (segment != p.surface.segments.end() && lattice.lattice_edge[segment->second.edge])
        continue;
      EXPECT_LE((p.surface.nodes[a] - p.surface.nodes[b]).norm(), h * (1 + 1e-9));
      ++checked;
    }
  }
  EXPECT_GT(checked, 100u);  // the hole's wall

  const std::size_t before = p.surface.nodes.size();
  mesher::collapse_sides(p.shape, p.surface, h, h, 0.02 * h, lattice.lattice_face);
  expect_sound_surface(p, p.surface, volume, 0.01, 1e-6 * h);
  ASSERT_EQ(p.surface.seed.size(), p.surface.nodes.size());
  for (std::size_t n = 1; n < p.surface.seed.size(); ++n)
    EXPECT_LT(p.surface.seed[n - 1], p.surface.seed[n]);  // the kept nodes, in their old order
  EXPECT_LE(p.surface.nodes.size(), before);
}

// A thin cylinder (radius 0.2 h, 2 h tall): BRepMesh divides its circles into eight segments of
// 0.15 h and joins them by strips along the axis; a tet on such a strip is no better than its
// 9-degree angle. refine() splits the strips' long sides until no triangle with a side on a
// circle has a side over three times as long.
TEST(refine, strips_along_a_cad_edge_are_split) {
  const double h = 5;
  Prepared p = prepare(occ_cylinder(0.2 * h, 2 * h), h);
  const auto& lattice = p.lattice;
  // The strips BRepMesh made, before.
  const auto worst_strip = [&] {
    double ratio = 0;
    for (const auto& t : p.surface.triangles) {
      if (lattice.lattice_face[t.face]) continue;
      double shortest = 1e300, longest = 0;
      bool short_on_edge = false;
      for (int c = 0; c < 3; ++c) {
        const int a = t.node[c], b = t.node[(c + 1) % 3];
        const double l = (p.surface.nodes[a] - p.surface.nodes[b]).norm();
        if (l < shortest)
          shortest = l, short_on_edge = p.surface.segments.count(mesher::pair_key(a, b));
        longest = std::max(longest, l);
      }
      if (short_on_edge) ratio = std::max(ratio, longest / shortest);
    }
    return ratio;
  };
  ASSERT_GT(worst_strip(), 5);
  mesher::refine(p.shape, p.surface, h, 0.02 * h, lattice.lattice_face, lattice.lattice_edge);
  // Closed, outward, on the CAD; its volume between the inscribed octagon's and the cylinder's.
  expect_sound_surface(p, p.surface, M_PI * h * h * 0.04 * 2 * h, 0.1, 1e-6 * h);
  EXPECT_LE(worst_strip(), 3 * (1 + 1e-9));
}

// A cap of three nodes of one CAD edge (BRepMesh's node inside a short curved edge): its middle
// node goes onto one of the others, with the cap and the other face's triangle on that side; the
// chord becomes the edge's segment, and the other face's triangles keep their own parameters.
TEST(collapse_sides, a_cap_on_a_cad_edge_loses_its_middle_node) {
  Surface surface;
  // The edge a r b (edge 0, parameters 0, 0.5, 1) between face z0 (the plane z = 0, here y > 0)
  // and face y0 (the plane y = 0, here z < 0) of a box; r bulges 0.005 off the chord.
  const Prepared box = prepare(occ_box(-1, 0, 0, 2, 2, 2), 1.0);
  int z0 = -1, y0 = -1;
  for (int f = 0; f < box.shape.faces.Extent(); ++f) {
    if (distance_to_face(box.shape, f, {0.5, 1, 0}) < 1e-12) z0 = f;
    if (distance_to_face(box.shape, f, {0.5, 0, -1}) < 1e-12) y0 = f;
  }
  ASSERT_GE(z0, 0);
  ASSERT_GE(y0, 0);
  const int a = 0, r = 1, b = 2, c = 3, d = 4;
  surface.nodes = {{0, 0, 0}, {0.5, -0.005, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, -1}};
  surface.node_face = {z0, z0, z0, z0, y0};
  const mesher::UV on0{3, 3}, on1{7, 7};
  surface.triangles = {{{a, r, b}, {on0, on0, on0}, z0},  // the cap
                       {{a, b, c}, {on0, on0, on0}, z0},
                       {{r, a, d}, {on1, on1, on1}, y0},
                       {{b, r, d}, {on1, on1, on1}, y0}};
  surface.segments[mesher::pair_key(a, r)] = {0, 0.0, 0.5};
  surface.segments[mesher::pair_key(r, b)] = {0, 0.5, 1.0};
  mesher::collapse_sides(box.shape, surface, 1.0, 10.0, 0.02,
                         std::vector<bool>(box.shape.faces.Extent(), false));

  ASSERT_EQ(surface.nodes.size(), 4u);  // r gone, the others in their order
  EXPECT_EQ(surface.seed, (std::vector<int>{a, b, c, d}));
  ASSERT_EQ(surface.triangles.size(), 2u);
  for (const mesher::SurfaceTriangle& t : surface.triangles) {
    EXPECT_GT(mesher::smallest_angle(surface.nodes, t.node), 0.5) << "face " << t.face;
    for (const mesher::UV& uv : t.uv) EXPECT_EQ(uv.u, t.face == z0 ? 3 : 7) << "face " << t.face;
  }
  ASSERT_EQ(surface.segments.size(), 1u);
  const auto& [key, segment] = *surface.segments.begin();
  EXPECT_EQ(key, mesher::pair_key(0, 1));  // a and b, renumbered
  EXPECT_EQ(segment.edge, 0);
  EXPECT_EQ(segment.t_lo, 0.0);
  EXPECT_EQ(segment.t_hi, 1.0);
}

// A hexagonal head 20 across its flats and 10 tall, chamfered by a cone (45 degrees) that meets
// the top in a circle touching the six flats (hex_bolt's head, whose elements under scaled
// Jacobian 0.2 were most of them 1 to 4 h from those points): the cone's face narrows to nothing
// at each, between the circle and the flat's hyperbola, which part by about 0.07 d^2 at d from
// it. At h 1 the nodes across that neck closer than 0.3 h to the other side go (the closest
// two across then four times as far apart at least); the surface
// stays closed, outward, on the CAD and encloses the same volume, and the angles of the
// triangles at the corners get no smaller.
TEST(coarsen_sharp_corners, nodes_across_a_narrow_neck_go) {
  const double h = 1;
  BRepBuilderAPI_MakePolygon hexagon;
  for (int k = 0; k < 6; ++k) {
    const double t = (30 + 60 * k) * M_PI / 180, r = 10 / std::cos(M_PI / 6);
    hexagon.Add(gp_Pnt(r * std::cos(t), r * std::sin(t), 0));
  }
  hexagon.Close();
  const TopoDS_Shape prism =
      BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(hexagon.Wire()).Face(), gp_Vec(0, 0, 10))
          .Shape();
  const TopoDS_Shape cone =
      BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 20, 10, 10).Shape();
  Prepared p = prepare(BRepAlgoAPI_Common(prism, cone).Shape(), h);
  repair_surface(p);
  const mesher::SharpFeatures sharp = mesher::sharp_features(p.shape, mesher::kSharpAngle);
  ASSERT_GE(sharp.corners.size(), 6u);
  // The closest two nodes across a neck, one on each of a corner's edges within the reach of
  // it (neither the corner's own), over h; and the smallest angle at the corners' nodes.
  double angle_before = 0, angle_after = 0;
  const auto across = [&](const mesher::Surface& surface, double& angle) {
    std::vector<std::vector<int>> on_edge(static_cast<std::size_t>(p.shape.edges.Extent()));
    for (const auto& [key, segment] : surface.segments)
      for (const int n : {static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu)})
        on_edge[static_cast<std::size_t>(segment.edge)].push_back(n);
    double closest = 1e300;
    angle = M_PI;
    for (const mesher::SharpCorner& c : sharp.corners) {
      const auto near = [&](int n) {
        const double d = (surface.nodes[n] - c.point).norm();
        return d > 1e-9 && d < mesher::kCornerReach * h;
      };
      for (const int u : on_edge[c.edges[0]])
        for (const int v : on_edge[c.edges[1]])
          if (near(u) && near(v))
            closest = std::min(closest, (surface.nodes[u] - surface.nodes[v]).norm());
      for (const mesher::SurfaceTriangle& t : surface.triangles)
        for (const int n : t.node)
          if ((surface.nodes[n] - c.point).norm() < 1e-9)
            angle = std::min(angle, mesher::smallest_angle(surface.nodes, t.node));
    }
    return closest / h;
  };
  const double across_before = across(p.surface, angle_before);
  ASSERT_LT(across_before, mesher::kCornerStripWidth);
  const double volume = enclosed_volume(p.surface.nodes, p.surface.triangles);
  const std::size_t nb_nodes = p.surface.nodes.size();
  const std::size_t removed =
      mesher::coarsen_sharp_corners(p.shape, p.surface, sharp.corners, h, 0.02 * h);
  EXPECT_GE(removed, 12u);  // at least one on each side of each corner
  EXPECT_EQ(p.surface.nodes.size(), nb_nodes - removed);
  // (0.06 h before, 0.29 h after: a node next to where the neck reaches 0.3 h stays when its
  // removal would make a triangle of the cone's face thinner.)
  EXPECT_GT(across(p.surface, angle_after), 4 * across_before);
  EXPECT_GE(angle_after, angle_before);
  expect_sound_surface(p, p.surface, volume, 1e-4, 1e-6 * h);
}

// A corner of 3 degrees between straight sides 50 long: 0.3 h apart only 5.7 h from it, past
// the reach (4 h), so a long triangle there would be as thin: no node goes.
TEST(coarsen_sharp_corners, a_strip_thin_past_the_reach_keeps_its_nodes) {
  const double a = 3 * M_PI / 180, h = 2;
  BRepBuilderAPI_MakePolygon polygon;
  for (const gp_Pnt& q :
       {gp_Pnt(0, 0, 0), gp_Pnt(50, 0, 0), gp_Pnt(50 * std::cos(a), 50 * std::sin(a), 0)})
    polygon.Add(q);
  polygon.Close();
  const TopoDS_Shape wedge =
      BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(polygon.Wire()).Face(), gp_Vec(0, 0, 10))
          .Shape();
  Prepared p = prepare(wedge, h);
  repair_surface(p);
  const mesher::SharpFeatures sharp = mesher::sharp_features(p.shape, mesher::kSharpAngle);
  ASSERT_FALSE(sharp.corners.empty());
  const std::size_t nb_nodes = p.surface.nodes.size();
  EXPECT_EQ(mesher::coarsen_sharp_corners(p.shape, p.surface, sharp.corners, h, 0.02 * h), 0u);
  EXPECT_EQ(p.surface.nodes.size(), nb_nodes);
}

TEST(coordinates_across, seen_along_each_axis) {
  // The triangle (0,0,0) (2,0,0) (0,2,0) seen along z; q = p0 + s (p1 - p0) + r (p2 - p0).
  const Vec3 p0{0, 0, 0}, p1{2, 0, 0}, p2{0, 2, 0};
  double s = -1, r = -1;
  ASSERT_TRUE(mesher::coordinates_across(Vec3{0.5, 1.0, 7.0}, p0, p1, p2, 2, s, r));
  EXPECT_DOUBLE_EQ(s, 0.25);
  EXPECT_DOUBLE_EQ(r, 0.5);
  // Seen along x the triangle is edge-on.
  EXPECT_FALSE(mesher::coordinates_across(Vec3{0, 0.5, 0.5}, p0, p1, p2, 0, s, r));
}

TEST(face_holding, first_triangle_holding_the_point) {
  const std::vector<Vec3> nodes{{0, 0, 5}, {4, 0, 5}, {0, 4, 5}, {4, 4, 5}};
  const mesher::SurfaceTriangle a{{0, 1, 2}, {}, 7}, b{{1, 3, 2}, {}, 8};
  const std::vector<const mesher::SurfaceTriangle*> triangles{&a, &b};
  EXPECT_EQ(mesher::face_holding(Vec3{1, 1, 5}, triangles, nodes, 2), 7);
  EXPECT_EQ(mesher::face_holding(Vec3{3, 3, 5}, triangles, nodes, 2), 8);
  EXPECT_EQ(mesher::face_holding(Vec3{2, 2, 5}, triangles, nodes, 2), 7);  // on both: the first
  EXPECT_EQ(mesher::face_holding(Vec3{5, 1, 5}, triangles, nodes, 2), -1);
}

}  // namespace
}  // namespace hexmerge::test

namespace hexmerge::test {
namespace {

TEST(remove_folds, coincident_nodes_merged_and_folds_taken_out) {
  // A closed tetrahedron's surface (nodes 0-3), plus node 4 at node 3's place used by a fold on
  // nodes 0, 1, 4 (one triangle each way), plus node 5 at node 2's place standing in for it in
  // one of the tetrahedron's triangles.
  mesher::Surface s;
  s.nodes = {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0},
             Vec3{0, 0, 1}, Vec3{0, 0, 1}, Vec3{0, 1, 1e-12}};
  s.node_face = {0, 0, 0, 1, 1, 2};
  s.seed = {10, 11, 12, 13, 14, 15};
  auto triangle = [](int a, int b, int c, int face) {
    mesher::SurfaceTriangle t;
    t.node = {a, b, c};
    t.face = face;
    return t;
  };
  s.triangles = {triangle(0, 2, 1, 0), triangle(0, 1, 3, 1), triangle(1, 5, 3, 2),
                 triangle(0, 3, 2, 3), triangle(0, 1, 4, 1), triangle(1, 0, 4, 1)};
  s.segments[mesher::pair_key(1, 5)] = mesher::EdgeSegment{7, 0.0, 1.0};
  mesher::remove_folds(s, 1e-9);
  ASSERT_EQ(s.nodes.size(), 4u);  // 4 merged into 3, 5 into 2
  ASSERT_EQ(s.triangles.size(), 4u);
  std::string problem;
  EXPECT_TRUE(closed_and_oriented(s.triangles, problem)) << problem;
  EXPECT_EQ(s.seed, (std::vector<int>{10, 11, 12, 13}));
  ASSERT_EQ(s.segments.size(), 1u);
  EXPECT_EQ(s.segments.begin()->first, mesher::pair_key(1, 2));
  // Nothing to do: nothing changes.
  const auto before = s.triangles;
  mesher::remove_folds(s, 1e-9);
  ASSERT_EQ(s.triangles.size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(s.triangles[i].node, before[i].node);
}

}  // namespace
}  // namespace hexmerge::test
