#include "hexmerge/occ/mesher/sweep.h"

#include <gtest/gtest.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <ShapeUpgrade_UnifySameDomain.hxx>
#include <cmath>
#include <string>

#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

std::optional<mesher::Sweep> find(const Prepared& p) {
  const auto& l = p.lattice;
  return mesher::find_sweep(p.shape, l.frame, l.face_plane, l.lattice_face, l.cells, l.spacing,
                            p.h);
}

std::optional<mesher::SweptSurface> sweep(Prepared& p, const mesher::Sweep& s) {
  const auto& l = p.lattice;
  return mesher::sweep_surface(p.shape, s, l.frame, l.frame.axis[s.axis] * l.spacing[s.axis],
                               l.cells[s.axis], p.h, 0.02 * p.h, l.lattice_face, p.surface);
}

// A swept surface: closed and outward, every node on a lattice plane along the axis and exactly
// over the node of the first plane it repeats, every node on the CAD face it is said to be on.
void expect_swept(Prepared& p, double volume, double relative_volume_tolerance) {
  const auto s = find(p);
  ASSERT_TRUE(s);
  const int a = s->axis;
  const auto made = sweep(p, *s);
  ASSERT_TRUE(made);
  const auto& surface = p.surface;
  std::string problem;
  EXPECT_TRUE(closed_and_oriented(surface.triangles, problem)) << problem;
  EXPECT_NEAR(enclosed_volume(surface.nodes, surface.triangles), volume,
              relative_volume_tolerance * volume);
  ASSERT_EQ(made->base.size(), surface.nodes.size());
  const auto& frame = p.lattice.frame;
  const double spacing = p.lattice.spacing[a];
  std::vector<int> per_plane(p.lattice.cells[a] + 1, 0);
  for (std::size_t n = 0; n < surface.nodes.size(); ++n) {
    const Vec3 q = frame.to_frame(surface.nodes[n]);
    const double level = mesher::coord(q, a) / spacing;
    EXPECT_NEAR(level, std::round(level), 1e-9) << "node " << n;
    ++per_plane[static_cast<int>(std::lround(level))];
    const Vec3 b = frame.to_frame(surface.nodes[made->base[n]]);
    EXPECT_NEAR(mesher::coord(b, a), 0, 1e-9 * p.h) << "base of node " << n;
    for (int c = 0; c < 3; ++c)
      if (c != a) {
        EXPECT_NEAR(mesher::coord(q, c), mesher::coord(b, c), 1e-9 * p.h);
      }
    EXPECT_LT(distance_to_face(p.shape, surface.node_face[n], surface.nodes[n]), 1e-7 * p.h)
        << "node " << n;
  }
  // The same stations on every plane between the caps.
  for (std::size_t k = 1; k + 1 < per_plane.size(); ++k) EXPECT_EQ(per_plane[k], per_plane[1]);
  EXPECT_FALSE(made->sides.empty());
}

TEST(find_sweep, cylinder_along_its_axis) {
  Prepared p = prepare(occ_cylinder(10, 30), 3.0);
  const auto s = find(p);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->axis, 2);
  int caps = 0;
  for (int f = 0; f < p.shape.faces.Extent(); ++f)
    if (s->cap[f] >= 0) {
      ++caps;
      EXPECT_TRUE(s->cap[f] == 0 || s->cap[f] == p.lattice.cells[2]);
    } else {
      EXPECT_EQ(s->range[f][0], 0);
      EXPECT_EQ(s->range[f][1], p.lattice.cells[2]);
    }
  EXPECT_EQ(caps, 2);
  expect_swept(p, M_PI * 10 * 10 * 30, 0.02);
}

TEST(find_sweep, hexagonal_prism_along_its_axis) {
  BRepBuilderAPI_MakePolygon hexagon;
  for (int i = 0; i < 6; ++i)
    hexagon.Add(gp_Pnt(20 * std::cos(i * M_PI / 3), 20 * std::sin(i * M_PI / 3), 0));
  hexagon.Close();
  const TopoDS_Shape prism =
      BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(hexagon.Wire()).Face(), gp_Vec(0, 0, 30))
          .Shape();
  Prepared p = prepare(prism, 2.5);
  expect_swept(p, 1.5 * std::sqrt(3.0) * 20 * 20 * 30, 1e-9);
}

TEST(find_sweep, plate_with_a_hole_along_the_hole) {
  Prepared p = prepare(occ_plate_with_hole(), 2.0);
  expect_swept(p, 60 * 40 * 10 - M_PI * 8 * 8 * 10, 0.02);
}

// The L as the fuse leaves it: its bottom is two faces, with an edge between them that no wall
// has (nothing would split it): not swept.
TEST(find_sweep, caps_split_into_faces_are_not_swept) {
  const Prepared p = prepare(occ_bracket(), 2.5);
  EXPECT_FALSE(find(p));
}

TEST(find_sweep, box_is_a_lattice_already) {
  const Prepared p = prepare(occ_box(0, 0, 0, 20, 10, 5), 2.0);
  EXPECT_FALSE(find(p));
}

// An L with a hole across its foot, its faces merged where the fuse left them split: along y and
// x the hole's wall is not parallel; along z the caps are on lattice planes but the
// cross-section changes (the flange above the foot), which sweep_surface() sees, leaving the
// surface as it was.
TEST(find_sweep, l_with_a_hole_across_is_not_swept) {
  ShapeUpgrade_UnifySameDomain unify(occ_bracket());
  unify.Build();
  Prepared p = prepare(unify.Shape(), 2.5);
  const auto s = find(p);
  ASSERT_TRUE(s);  // caps on lattice planes, walls parallel to z (the hole's too)
  EXPECT_EQ(s->axis, 2);
  const auto triangles = p.surface.triangles.size();
  const auto nodes = p.surface.nodes;
  EXPECT_FALSE(sweep(p, *s));
  EXPECT_EQ(p.surface.triangles.size(), triangles);
  ASSERT_EQ(p.surface.nodes.size(), nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n)
    EXPECT_EQ((p.surface.nodes[n] - nodes[n]).norm(), 0.0);
}

}  // namespace
}  // namespace hexmerge::test
