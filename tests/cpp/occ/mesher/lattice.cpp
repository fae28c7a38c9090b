#include "hexmerge/occ/mesher/lattice.h"

#include <gtest/gtest.h>

#include <BRepAdaptor_Curve.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <algorithm>
#include <cmath>
#include <random>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/surface_repair.h"
#include "hexmerge/occ/mesher/sweep.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

TEST(lay_lattice, box_faces_are_lattice_faces) {
  const double h = 7;
  const Prepared p = prepare(occ_box(0, 0, 0, 100, 40, 30), h);
  const auto& l = p.lattice;
  const double extent[3] = {100, 40, 30};
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(l.extent[a], extent[a], 1e-9);
    EXPECT_NEAR(l.cells[a] * l.spacing[a], extent[a], 1e-9);
    EXPECT_EQ(l.cells[a], std::lround(extent[a] / h));  // no other face to fit
  }
  EXPECT_EQ(l.nb_lattice_faces, 6u);
  for (bool e : l.lattice_edge) EXPECT_TRUE(e);
  const Vec3 origin = l.frame.origin;
  EXPECT_NEAR(origin.norm(), 0, 1e-9);
}

TEST(lay_lattice, spacing_puts_planes_on_the_steps) {
  // The flange's side at x = 10 of a 60-long foot and the foot's top at z = 10 of a 50-high
  // flange: the spacings put lattice planes on them (60 / 18 and 50 / 15, nearest h = 3).
  const Prepared p = prepare(occ_bracket(), 3.0);
  const auto& l = p.lattice;
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(l.spacing[a], 0.75 * p.h * (1 - 1e-9));
    EXPECT_LE(l.spacing[a], 1.2 * p.h * (1 + 1e-9));
  }
  EXPECT_EQ(l.cells[0], 18);
  EXPECT_EQ(l.cells[2], 15);
  for (int f = 0; f < p.shape.faces.Extent(); ++f)
    if (l.face_plane[f]) {
      EXPECT_TRUE(l.lattice_face[f]) << f;
    }
}

// 27.5 x 15 x 18 at h 6: the counts nearest L / h per axis (5, 2, 3: spacings 5.5, 7.5, 6)
// put the centre of the cell across an x face 5.5 from a cell's centre, inside its circumsphere
// (radius 5.53), and Delaunay would join it to the cell's corners. 3 cells along y (5.0) keep
// every apex outside.
TEST(lay_lattice, every_spacing_exceeds_half_the_cells_diagonal) {
  const Prepared p = prepare(occ_box(0, 0, 0, 27.5, 15, 18), 6.0);
  const auto& l = p.lattice;
  EXPECT_EQ(l.cells[0], 5);
  EXPECT_EQ(l.cells[1], 3);
  EXPECT_EQ(l.cells[2], 3);
  const double half_diagonal =
      0.5 * std::sqrt(l.spacing[0] * l.spacing[0] + l.spacing[1] * l.spacing[1] +
                      l.spacing[2] * l.spacing[2]);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(l.spacing[a], half_diagonal) << "axis " << a;
    EXPECT_NEAR(l.cells[a] * l.spacing[a], l.extent[a], 1e-9);
  }
  EXPECT_EQ(l.nb_lattice_faces, 6u);
  // Near-cubic cells keep the counts nearest L / h.
  const Prepared q = prepare(occ_box(0, 0, 0, 30, 15, 18), 6.0);
  EXPECT_EQ(q.lattice.cells[0], 5);
  EXPECT_EQ(q.lattice.cells[1], 2);
  EXPECT_EQ(q.lattice.cells[2], 3);
}

// The step's side at x = 13 of 30: no count of equal cells about h = 3 wide puts a plane on
// it (13 / 30 has no denominator from 7 to 13), so the planes along x are placed: 0 to 13 and 13
// to 30 each cut into equal cells, all within the band around the uniform spacing, and every
// planar face is a lattice face. The cells across the step keep their apexes outside their
// circumspheres (add_core() checks it cell by cell): the block is all core, less the cells whose
// closing pyramids would stick out.
TEST(lay_lattice, planes_placed_on_faces_no_spacing_fits) {
  const double h = 3.0;
  const Prepared p = prepare(occ_step(), h);
  const auto& l = p.lattice;
  ASSERT_FALSE(l.uniform(0));
  EXPECT_TRUE(l.uniform(1));
  EXPECT_TRUE(l.uniform(2));
  ASSERT_EQ(l.ticks[0].size(), static_cast<std::size_t>(l.cells[0]) + 1);
  EXPECT_EQ(l.ticks[0].front(), 0.0);
  EXPECT_NEAR(l.ticks[0].back(), 30.0, 1e-9);
  EXPECT_TRUE(std::any_of(l.ticks[0].begin(), l.ticks[0].end(),
                          [](double t) { return std::abs(t - 13.0) < 1e-9; }));
  for (int i = 0; i < l.cells[0]; ++i) {
    EXPECT_GE(l.width(0, i), 0.75 * h) << i;
    EXPECT_LE(l.width(0, i), 1.5 * h) << i;
    // The lattice coordinates of a plane and of a cell's middle, and back.
    EXPECT_DOUBLE_EQ(l.at(0, i), l.ticks[0][i]);
    EXPECT_NEAR(l.at(0, i + 0.5), 0.5 * (l.ticks[0][i] + l.ticks[0][i + 1]), 1e-12);
    EXPECT_NEAR(l.cells_at(0, l.at(0, i + 0.25)), i + 0.25, 1e-12);
  }
  std::size_t planar = 0;
  for (int f = 0; f < p.shape.faces.Extent(); ++f)
    if (l.face_plane[f]) {
      EXPECT_TRUE(l.lattice_face[f]) << f;
      ++planar;
    }
  EXPECT_EQ(p.shape.faces.Extent(), static_cast<int>(planar));  // every face is planar
  EXPECT_EQ(l.nb_lattice_faces, planar);

  const Placed placed = place(p);
  const mesher::KeptPoints kept =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, 0.3 * h, 0.3 * h, true);
  mesher::InsertedPoints inserted;
  const mesher::CoreCounts core =
      add_core(l, *placed.around, *placed.parity, kept, -1, h, inserted);
  // Every cell of the shape is a core cell: the step's cells fill it exactly.
  std::size_t inside = 0;
  for (int k = 0; k < l.cells[2]; ++k)
    for (int j = 0; j < l.cells[1]; ++j)
      for (int i = 0; i < l.cells[0]; ++i) {
        bool on = false;
        inside += occ_inside(p.shape, l.frame.to_world(l.cell_centre(i, j, k)), on);
      }
  EXPECT_EQ(core.nb_core_cells, inside);
  EXPECT_EQ(core.nb_apex_points, 0u);
}

// The split box's seams (x = 10 on its four long faces) lie between coplanar lattice faces, on no
// lattice line (x = 10 is on no plane of 8 cells of 2.875): no lattice edges, and refine() splits
// them to h (no lattice point comes onto them, no other face's triangle splits them). The box's
// own edges are lattice edges and keep their ends only.
TEST(lay_lattice, seams_between_coplanar_faces_are_no_lattice_edges) {
  const double h = 3.0;
  Prepared p = prepare(occ_split_box(), h);
  const auto& l = p.lattice;
  ASSERT_EQ(l.nb_lattice_faces, static_cast<std::size_t>(p.shape.faces.Extent()));
  EXPECT_FALSE(l.on_plane(0, 10.0, 1e-7 * h));
  int seams = 0;
  for (int e = 0; e < p.shape.edges.Extent(); ++e) {
    const TopoDS_Edge& edge = TopoDS::Edge(p.shape.edges(e + 1));
    BRepAdaptor_Curve curve(edge);
    const gp_Pnt a = curve.Value(curve.FirstParameter()), b = curve.Value(curve.LastParameter());
    const bool seam = std::abs(a.X() - 10) < 1e-9 && std::abs(b.X() - 10) < 1e-9;
    seams += seam;
    EXPECT_EQ(l.lattice_edge[e], !seam) << "edge " << e;
  }
  EXPECT_EQ(seams, 4);
  mesher::refine(p.shape, p.surface, h, 0.02 * h, l.lattice_face, l.lattice_edge);
  int on_seams = 0;
  for (const auto& [key, segment] : p.surface.segments) {
    const Vec3 &a = p.surface.nodes[key >> 32], &b = p.surface.nodes[key & 0xffffffffu];
    if (std::abs(a.x - 10) > 1e-9 || std::abs(b.x - 10) > 1e-9) continue;
    ++on_seams;
    EXPECT_LE((a - b).norm(), h * (1 + 1e-9));
  }
  EXPECT_GE(on_seams, 4 * 4);  // each 10 long seam in at least 4 sides
}

TEST(lay_lattice, size_larger_than_the_shape_is_refused) {
  EXPECT_THROW(prepare(occ_box(0, 0, 0, 10, 10, 10), 11.0), InputError);
}

// Inside/outside by ray parity agrees with OpenCASCADE's classifier, away from the surface
// (within the chord deflection the triangulation and the CAD may disagree).
TEST(Parity, agrees_with_the_solid_classifier) {
  for (const auto& [name, solid, h] :
       {std::tuple{"bracket", occ_bracket(), 3.0}, std::tuple{"plate", occ_plate_with_hole(), 2.0},
        std::tuple{"cylinder", occ_cylinder(10, 30), 3.0}}) {
    SCOPED_TRACE(name);
    const Prepared p = prepare(solid, h);
    const Placed placed = place(p);
    // Every triangle, for "near the surface".
    mesher::TriangleSet all(placed.nodes, placed.around->box_lo, placed.around->box_hi, h);
    for (const auto& t : p.surface.triangles) all.add(t.node);
    std::mt19937 random(7);
    std::uniform_real_distribution<double> u(-0.1, 1.1);
    int inside = 0, outside = 0;
    for (int i = 0; i < 3000; ++i) {
      const Vec3 q{u(random) * p.lattice.extent[0], u(random) * p.lattice.extent[1],
                   u(random) * p.lattice.extent[2]};
      if (all.any_within(q, 0.1 * h)) continue;
      bool on = false;
      const bool expected = occ_inside(p.shape, p.lattice.frame.to_world(q), on);
      ASSERT_FALSE(on);
      EXPECT_EQ(placed.parity->inside(q), expected) << q.x << " " << q.y << " " << q.z;
      (expected ? inside : outside)++;
    }
    EXPECT_GT(inside, 300);
    EXPECT_GT(outside, 300);
  }
}

// Swept along z, a lattice point on a wall (the sides y = 0 and 10) beside the hole, 0.5 from
// both, stays on every plane: the sweep repeats its first plane, where the wall is a side that
// only its lattice points split (dropped, the side ran past the hole, its prisms flat: FreeCAD's
// PathTests/test_holes00). Not swept, the points between the caps go (on a lattice face within
// keep_distance of the hole), those on the caps' edges stay.
TEST(keep_lattice_points, a_sweep_keeps_its_walls_points_on_every_plane) {
  const double h = 2.0, keep = 0.6 * h;
  const Prepared p = prepare(occ_bar_with_hole_near_sides(), h);
  Placed placed = place(p);
  const auto& l = p.lattice;
  ASSERT_DOUBLE_EQ(l.at(1, l.cells[1]), 10.0);
  const mesher::KeptPoints swept =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, keep, 0.3 * h, 2);
  const mesher::KeptPoints unswept =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, keep, 0.3 * h, -1);
  int beside = 0;
  for (int j = 0; j <= l.cells[1]; ++j)
    for (int i = 0; i <= l.cells[0]; ++i) {
      // Every column is kept or dropped whole.
      const char bottom = swept.kept[l.point_index(i, j, 0)];
      for (int k = 1; k <= l.cells[2]; ++k)
        EXPECT_EQ(swept.kept[l.point_index(i, j, k)], bottom) << i << " " << j << " " << k;
      const Vec3 q = l.point(i, j, 0);
      if ((j != 0 && j != l.cells[1]) || std::hypot(q.x - 20, q.y - 5) >= 4.5 + keep) continue;
      ++beside;
      EXPECT_TRUE(bottom) << i << " " << j;
      EXPECT_TRUE(unswept.kept[l.point_index(i, j, 0)]) << i << " " << j;  // the caps' edges
      for (int k = 1; k < l.cells[2]; ++k)
        EXPECT_FALSE(unswept.kept[l.point_index(i, j, k)]) << i << " " << j << " " << k;
    }
  EXPECT_GE(beside, 6);
}

// The lattice points kept are inside the solid (or on a lattice face) and at least
// keep_distance from the faces off the lattice; the core cells have their 8 corners kept.
TEST(keep_lattice_points, inside_and_clear_of_the_curved_faces) {
  const double h = 2.0, keep = 0.6 * h;
  const Prepared p = prepare(occ_plate_with_hole(), h);
  Placed placed = place(p);
  const auto& l = p.lattice;
  const mesher::KeptPoints kept =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, keep, 0.3 * h, -1);
  std::size_t nb_kept = 0;
  for (int k = 0; k <= l.cells[2]; ++k)
    for (int j = 0; j <= l.cells[1]; ++j)
      for (int i = 0; i <= l.cells[0]; ++i) {
        const std::size_t index = l.point_index(i, j, k);
        if (!kept.kept[index]) continue;
        ++nb_kept;
        const Vec3 q = l.point(i, j, k);
        bool on = false;
        const bool in = occ_inside(p.shape, l.frame.to_world(q), on);
        EXPECT_TRUE(in || (on && kept.face[index] >= 0)) << i << " " << j << " " << k;
        // The hole's axis is at (30, 20): kept points are at least r + keep from it.
        EXPECT_GE(std::hypot(q.x - 30, q.y - 20), 8 + keep - 0.02 * h - 1e-9);
      }
  EXPECT_GT(nb_kept, 1000u);

  mesher::InsertedPoints inserted;
  const mesher::CoreCounts core =
      add_core(l, *placed.around, *placed.parity, kept, -1, h, inserted);
  EXPECT_GT(core.nb_core_cells, 0u);
  EXPECT_EQ(inserted.points.size(), core.nb_lattice_points + core.nb_apex_points);
  EXPECT_LE(core.nb_lattice_points, nb_kept);
  // The apexes are cell centres inside the solid.
  for (std::size_t i = core.nb_lattice_points; i < inserted.points.size(); ++i) {
    const Vec3 q = inserted.points[i];
    for (int a = 0; a < 3; ++a) {
      const double c = mesher::coord(q, a) / l.spacing[a] - 0.5;
      EXPECT_NEAR(c, std::round(c), 1e-9);
    }
    bool on = false;
    EXPECT_TRUE(occ_inside(p.shape, l.frame.to_world(q), on));
    EXPECT_EQ(inserted.face[i], -1);
  }
  const std::size_t on_faces = mesher::face_points_first(inserted);
  for (std::size_t i = 0; i < inserted.face.size(); ++i)
    EXPECT_EQ(inserted.face[i] >= 0, i < on_faces);
}

// A box: every lattice point kept, every cell in the core, no pyramid needed; the points given
// are the lattice points less the box's corners (the surface's nodes).
TEST(add_core, box_is_all_core) {
  const double h = 2.5;
  const Prepared p = prepare(occ_box(0, 0, 0, 20, 10, 5), h);
  Placed placed = place(p);
  const auto& l = p.lattice;
  const mesher::KeptPoints kept =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, 0.6 * h, 0.3 * h, true);
  for (char k : kept.kept) EXPECT_TRUE(k);
  mesher::InsertedPoints inserted;
  const mesher::CoreCounts core =
      add_core(l, *placed.around, *placed.parity, kept, -1, h, inserted);
  const std::size_t cells = static_cast<std::size_t>(l.cells[0]) * l.cells[1] * l.cells[2];
  const std::size_t points =
      static_cast<std::size_t>(l.cells[0] + 1) * (l.cells[1] + 1) * (l.cells[2] + 1);
  EXPECT_EQ(core.nb_core_cells, cells);
  EXPECT_EQ(core.nb_apex_points, 0u);
  EXPECT_EQ(core.nb_lattice_points, points - placed.nodes.size());
}

// A cylinder's core cut by a gap across y (the cells of one or two layers out of the core, the
// lattice points inside it not kept), closing pyramids on the faces towards the gap: across a
// gap of two cells, the faces are pulled into it; across a gap of one, by 0.1 h at most.
// Pulled from both sides, the apexes in such a gap passed each other's bases and left flat tets
// between them (gmsh_Kurbelwelle).
TEST(pull_core, faces_across_a_gap_of_one_cell_are_pulled_little) {
  const double h = 2.5;
  const Prepared p = prepare(occ_cylinder(10, 20), h);
  Placed placed = place(p);
  const auto& l = p.lattice;
  const mesher::KeptPoints all =
      mesher::keep_lattice_points(l, *placed.around, *placed.parity, 0.6 * h, 0.3 * h, true);
  const mesher::CoreLayout laid =
      mesher::lay_core(l, *placed.around, *placed.parity, all, -1, h, false);
  const auto cell_index = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * l.cells[1] + j) * l.cells[0] + i;
  };
  const int gj = l.cells[1] / 2;
  // How far the base corners of the faces towards the gap move across it (along y), at most.
  const auto moved_towards_gap = [&](int width) {
    // (The lattice points inside the gap not kept: a node beside one stays.)
    mesher::KeptPoints kept = all;
    for (int k = 0; k <= l.cells[2]; ++k)
      for (int i = 0; i <= l.cells[0]; ++i)
        for (int j = gj + 1; j < gj + width; ++j) kept.kept[l.point_index(i, j, k)] = 0;
    std::vector<char> core = laid.core;
    for (int k = 0; k < l.cells[2]; ++k)
      for (int i = 0; i < l.cells[0]; ++i)
        for (int j = gj; j < gj + width; ++j) core[cell_index(i, j, k)] = 0;
    std::vector<char> core_corner(kept.kept.size(), 0);
    std::vector<mesher::PyramidFace> faces;
    for (int k = 0; k < l.cells[2]; ++k)
      for (int i = 0; i < l.cells[0]; ++i) {
        if (!core[cell_index(i, gj - 1, k)] || !core[cell_index(i, gj + width, k)]) continue;
        faces.push_back({{i, gj - 1, k}, 3, {i, gj, k}});
        faces.push_back({{i, gj + width, k}, 2, {i, gj + width - 1, k}});
      }
    for (int k = 0; k < l.cells[2]; ++k)
      for (int j = 0; j < l.cells[1]; ++j)
        for (int i = 0; i < l.cells[0]; ++i)
          if (core[cell_index(i, j, k)])
            for (int c = 0; c < 8; ++c)
              core_corner[l.point_index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] = 1;
    EXPECT_GT(faces.size(), 8u);
    const mesher::PulledCore pulled =
        mesher::pull_core(l, *placed.around, *placed.parity, kept, core, core_corner, faces, {}, h);
    double most = 0;
    for (const mesher::PyramidFace& f : faces)
      for (const std::size_t q : mesher::base_corners(l, f))
        if (const auto it = pulled.node.find(q); it != pulled.node.end())
          most = std::max(most, std::abs(it->second.y));
    return most;
  };
  EXPECT_GT(moved_towards_gap(2), 0.2 * h);
  EXPECT_LE(moved_towards_gap(1), 0.1 * h + 1e-9);
}

// A closing pyramid's scaled Jacobian (Verdict's): positive with the apex on the side `up`
// names, the same for the pyramid mirrored, falling as the apex comes down to its base (0.82 at
// half the base's side, kCorePyramidFloor 0.4 at about 0.21).
TEST(closing_pyramid_quality, sign_and_height) {
  const std::array<Vec3, 4> base{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{1, 1, 0}, Vec3{0, 1, 0}};
  const double half = mesher::closing_pyramid_quality(base, Vec3{0.5, 0.5, 0.5}, true);
  EXPECT_NEAR(half, std::sqrt(2.0 / 3.0), 1e-9);
  EXPECT_NEAR(mesher::closing_pyramid_quality(base, Vec3{0.5, 0.5, -0.5}, false), half, 1e-12);
  EXPECT_LT(mesher::closing_pyramid_quality(base, Vec3{0.5, 0.5, -0.5}, true), 0);
  EXPECT_GT(mesher::closing_pyramid_quality(base, Vec3{0.5, 0.5, 0.25}, true),
            mesher::kCorePyramidFloor);
  EXPECT_LT(mesher::closing_pyramid_quality(base, Vec3{0.5, 0.5, 0.18}, true),
            mesher::kCorePyramidFloor);
}

// A pulled pyramid whose base no longer lies flat (corner 1 raised): its facets are kept, but the
// region inside them holds a sliver of the base's four corners and two tets on the other
// diagonal. resplit_core() gives it the lattice's split (the base on its diagonal from corner
// 0) and leaves the tet beyond the base alone; a split whose corners are not a region's, a
// region whose outer faces are not the split's, or a region holding another point, stays.
TEST(resplit_core, a_pyramid_with_a_sliver_gets_the_lattices_split) {
  const std::vector<Vec3> at = {{0, 0, 0}, {1, 0, 0.1},     {1, 1, 0},
                                {0, 1, 0}, {0.5, 0.5, 0.8}, {0.4, 0.6, -1}};
  std::vector<double> coordinates;
  for (const Vec3& p : at) coordinates.insert(coordinates.end(), {p.x, p.y, p.z});
  const auto volume = [&](const index_t* t) {
    return det3(at[t[1]] - at[t[0]], at[t[2]] - at[t[0]], at[t[3]] - at[t[0]]) / 6;
  };
  // Positive tets: the sliver, the two on diagonal 1-3, and one below the base.
  std::vector<index_t> tets = {0, 1, 3, 2, 0, 1, 3, 4, 1, 2, 3, 4, 0, 3, 2, 5};
  for (std::size_t t = 0; t < tets.size() / 4; ++t) {
    if (volume(&tets[4 * t]) < 0) std::swap(tets[4 * t + 1], tets[4 * t + 2]);
    ASSERT_GT(volume(&tets[4 * t]), 0);
  }
  double before = 0;
  for (std::size_t t = 0; t < tets.size() / 4; ++t) before += volume(&tets[4 * t]);
  const std::vector<std::array<int, 3>> constraints = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4},
                                                       {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  mesher::InsertedPoints::Split split;
  split.corners = {at[0], at[1], at[2], at[3], at[4]};
  split.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}};

  // Corners that are no region's (the apex elsewhere): nothing changes.
  mesher::InsertedPoints::Split elsewhere = split;
  elsewhere.corners[4] = Vec3{0.5, 0.5, 0.7};
  std::vector<index_t> same = tets;
  EXPECT_EQ(mesher::resplit_core(coordinates, same, constraints, {elsewhere}, 1e-9), 0u);
  EXPECT_EQ(same, tets);

  EXPECT_EQ(mesher::resplit_core(coordinates, tets, constraints, {split}, 1e-9), 1u);
  ASSERT_EQ(tets.size(), 12u);
  std::vector<std::array<index_t, 4>> sorted;
  double after = 0;
  for (std::size_t t = 0; t < 3; ++t) {
    EXPECT_GT(volume(&tets[4 * t]), 0);
    after += volume(&tets[4 * t]);
    std::array<index_t, 4> k{tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3]};
    std::sort(k.begin(), k.end());
    sorted.push_back(k);
  }
  std::sort(sorted.begin(), sorted.end());
  const std::vector<std::array<index_t, 4>> expected = {{0, 1, 2, 4}, {0, 2, 3, 4}, {0, 2, 3, 5}};
  EXPECT_EQ(sorted, expected);
  EXPECT_NEAR(after, before, 1e-12);

  // A region on the surface, its base split on the other diagonal (the surface's triangles,
  // which the tets must keep): its outer faces are not the split's, and it stays.
  std::vector<index_t> on_surface = {0, 1, 3, 4, 1, 2, 3, 4};
  for (std::size_t t = 0; t < 2; ++t)
    if (volume(&on_surface[4 * t]) < 0) std::swap(on_surface[4 * t + 1], on_surface[4 * t + 2]);
  const std::vector<std::array<int, 3>> sides(constraints.begin() + 2, constraints.end());
  std::vector<index_t> kept = on_surface;
  EXPECT_EQ(mesher::resplit_core(coordinates, kept, sides, {split}, 1e-9), 0u);
  EXPECT_EQ(kept, on_surface);

  // A region holding a point besides the split's corners (a Steiner point TetGen added) stays.
  std::vector<double> more = coordinates;
  more.insert(more.end(), {0.5, 0.45, 0.3});
  std::vector<index_t> with_point = {0, 1, 2, 6, 0, 2, 3, 6, 0, 1, 6, 4,
                                     1, 2, 6, 4, 2, 3, 6, 4, 3, 0, 6, 4};
  EXPECT_EQ(mesher::resplit_core(more, with_point, constraints, {split}, 1e-9), 0u);
}

}  // namespace
}  // namespace hexmerge::test
