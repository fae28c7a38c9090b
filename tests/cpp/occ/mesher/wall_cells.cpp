#include "hexmerge/occ/mesher/wall_cells.h"

#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/core.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// A tube along z: radii 10 and 7, 40 long.
TopoDS_Shape tube() {
  const TopoDS_Shape outer =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10, 40).Shape();
  const TopoDS_Shape bore =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp_Dir(0, 0, 1)), 7, 42).Shape();
  return BRepAlgoAPI_Cut(outer, bore).Shape();
}

// A tube (radii 10 and 7, 40 long) at h 3: its wall, one cell thick, gets a ring of cells along
// it (29 round, the outer face's chords within the chord deflection 0.06, 12 along, the column
// across the outer face's seam and the one across the inner face's lost, the rows h / 2 inside
// its ends). Both cylinders are
// triangulated again with the cells' quads in them, the surface still closed, outward and
// enclosing the same volume to 1 %; each cell is a hexahedron of scaled Jacobian 0.9 or more
// (its faces planar: chords and radial planes), its corners on the cylinders' CAD, its outer and
// inner quads two surface triangles each on the diagonal of its split, its six tets positive at
// 0.2 or more. emit_wall_cells() gives each cell's split and corners, and its faces inside the
// tube as constraints (none of them a surface triangle).
TEST(wall_cells, a_tubes_wall_gets_a_ring_of_cells) {
  const double h = 3;
  Prepared p = prepare(tube(), h);
  repair_surface(p);
  const double volume_before = enclosed_volume(p.surface.nodes, p.surface.triangles);
  std::vector<char> eligible(static_cast<std::size_t>(p.shape.faces.Extent()), 1);
  const mesher::PointSet none(Vec3{-20, -20, -20}, Vec3{60, 60, 60}, h);
  mesher::WallReport report;
  const mesher::WallCells cells =
      mesher::wall_cells(p.shape, p.lattice.frame, eligible, none, h, 0.02 * h, p.surface, report);
  EXPECT_EQ(report.nb_walls, 1u);
  EXPECT_EQ(report.nb_faces, 2u);
  EXPECT_GE(report.nb_hexes, 27u * 12u * 3 / 4);
  EXPECT_EQ(cells.hexes.size(), report.nb_hexes);
  EXPECT_TRUE(cells.points.empty());  // one cell across

  std::string problem;
  EXPECT_TRUE(closed_and_oriented(p.surface.triangles, problem)) << problem;
  EXPECT_NEAR(enclosed_volume(p.surface.nodes, p.surface.triangles), volume_before,
              1e-2 * volume_before);

  const TriangleSet triangles(p.surface, 1e-9 * h);
  // Cell-type order (cell_type.h) from kKuhnPaths' bits: 0 1 3 2 on the inner face, 4 5 7 6.
  static const index_t kHex[8] = {0, 1, 3, 2, 4, 5, 7, 6};
  static const index_t kTet[4] = {0, 1, 2, 3};
  for (std::size_t c = 0; c < cells.hexes.size(); ++c) {
    const std::array<Vec3, 8>& at = cells.hexes[c];
    EXPECT_EQ(cells.on_surface[c], 3);
    std::vector<double> xyz;
    for (const Vec3& q : at) xyz.insert(xyz.end(), {q.x, q.y, q.z});
    EXPECT_GE(scaled_jacobian(CellType::Hex, xyz.data(), kHex), 0.9);
    for (const auto& path : mesher::kKuhnPaths) {
      const Vec3 t[4] = {at[0], at[static_cast<std::size_t>(path[0])],
                         at[static_cast<std::size_t>(path[1])], at[7]};
      double txyz[12];
      for (int k = 0; k < 4; ++k)
        txyz[3 * k] = t[k].x, txyz[3 * k + 1] = t[k].y, txyz[3 * k + 2] = t[k].z;
      EXPECT_GE(std::abs(scaled_jacobian(CellType::Tet, txyz, kTet)), 0.2);
    }
    std::array<Vec3, 8> w;
    for (int b = 0; b < 8; ++b) {
      w[b] = p.lattice.frame.to_world(at[b]);
      const double r = std::hypot(w[b].x, w[b].y);
      EXPECT_NEAR(r, b & 4 ? 10.0 : 7.0, 1e-9 * h);
    }
    EXPECT_TRUE(triangles.has(w[4], w[5], w[7]) && triangles.has(w[4], w[7], w[6]));
    EXPECT_TRUE(triangles.has(w[0], w[1], w[3]) && triangles.has(w[0], w[3], w[2]));
  }

  const Placed placed = place(p);
  mesher::Surroundings& around = *placed.around;
  mesher::InsertedPoints inserted;
  mesher::emit_wall_cells(cells, around, inserted);
  EXPECT_EQ(inserted.splits.size(), cells.hexes.size());
  EXPECT_EQ(inserted.kept_cells.size(), cells.hexes.size());
  EXPECT_TRUE(inserted.points.empty());
  // Four side faces of two triangles per cell, each shared by two cells but at the ends of the
  // ring's runs.
  EXPECT_GE(inserted.constraints.size(), 4 * cells.hexes.size());
  EXPECT_LE(inserted.constraints.size(), 8 * cells.hexes.size());
  for (const std::array<Vec3, 3>& t : inserted.constraints)
    EXPECT_FALSE(triangles.has(p.lattice.frame.to_world(t[0]), p.lattice.frame.to_world(t[1]),
                               p.lattice.frame.to_world(t[2])));
  EXPECT_TRUE(around.buffer_cells.near(cells.hexes[0][0], 1e-9));
}

// A core point beside the wall keeps the cells near it away; a wall thinner than
// kThinnestWallCell h gets none.
TEST(wall_cells, keeps_clear_of_the_core_and_of_walls_too_thin) {
  const double h = 3;
  Prepared p = prepare(tube(), h);
  repair_surface(p);
  std::vector<char> eligible(static_cast<std::size_t>(p.shape.faces.Extent()), 1);
  const mesher::PointSet none(Vec3{-20, -20, -20}, Vec3{60, 60, 60}, h);
  mesher::WallReport all;
  mesher::Surface surface = p.surface;
  const std::size_t everywhere =
      mesher::wall_cells(p.shape, p.lattice.frame, eligible, none, h, 0.02 * h, surface, all)
          .hexes.size();
  mesher::PointSet core(Vec3{-20, -20, -20}, Vec3{60, 60, 60}, h);
  core.add(p.lattice.frame.to_frame(Vec3{-8.5, 0.5, 20}));
  mesher::WallReport beside;
  surface = p.surface;
  const mesher::WallCells kept =
      mesher::wall_cells(p.shape, p.lattice.frame, eligible, core, h, 0.02 * h, surface, beside);
  EXPECT_LT(kept.hexes.size(), everywhere);
  EXPECT_GT(kept.hexes.size(), everywhere - 12);
  for (const std::array<Vec3, 8>& at : kept.hexes)
    for (const Vec3& q : at)
      EXPECT_GE((p.lattice.frame.to_world(q) - Vec3{-8.5, 0.5, 20}).norm(), 0.25 * h);

  const double thin_h = 3 / (0.9 * mesher::kThinnestWallCell);  // the wall 0.9 of the least
  Prepared thin = prepare(tube(), thin_h);
  repair_surface(thin);
  mesher::WallReport none_made;
  const mesher::WallCells no_cells =
      mesher::wall_cells(thin.shape, thin.lattice.frame, eligible, none, thin_h, 0.02 * thin_h,
                         thin.surface, none_made);
  EXPECT_TRUE(no_cells.hexes.empty());
  EXPECT_EQ(none_made.nb_walls, 0u);
}

// At a coarse size the chord deflection makes the cells narrower than h round the axis: along
// it they are at most twice as long as wide (a tube of radii 10 and 6 at h 7: 19 round, 2.6 wide
// at the middle radius, 5.5 along, not 6.6).
TEST(wall_cells, are_no_longer_than_twice_their_width) {
  const double h = 7;
  const TopoDS_Shape outer =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10, 40).Shape();
  const TopoDS_Shape bore =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp_Dir(0, 0, 1)), 6, 42).Shape();
  Prepared p = prepare(BRepAlgoAPI_Cut(outer, bore).Shape(), h);
  repair_surface(p);
  std::vector<char> eligible(static_cast<std::size_t>(p.shape.faces.Extent()), 1);
  const mesher::PointSet none(Vec3{-20, -20, -20}, Vec3{60, 60, 60}, h);
  mesher::WallReport report;
  const mesher::WallCells cells =
      mesher::wall_cells(p.shape, p.lattice.frame, eligible, none, h, 0.02 * h, p.surface, report);
  ASSERT_GT(cells.hexes.size(), 0u);
  for (const std::array<Vec3, 8>& at : cells.hexes) {
    const Vec3 middle_0 = (at[0] + at[4]) * 0.5, middle_1 = (at[1] + at[5]) * 0.5,
               middle_2 = (at[2] + at[6]) * 0.5;
    const double round = (middle_1 - middle_0).norm(), along = (middle_2 - middle_0).norm();
    EXPECT_LT(round, 0.5 * h);
    EXPECT_LE(along, 2 * round * 1.05);
  }
}

}  // namespace
}  // namespace hexmerge::test
