#include "hexmerge/occ/mesher/local_size.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/occ/mesher/surface_repair.h"
#include "hexmerge/occ/mesher/sweep.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// The size field: the item's size on it (within the slack), growing by `grading` per unit of
// distance beyond the slack, never above h; a segment is an item too; no item, h everywhere.
TEST(SizeField, grows_from_its_items_up_to_h) {
  const double h = 4, grading = 0.5, slack = 0.01;
  mesher::SizeField field(h, grading, slack);
  EXPECT_TRUE(field.empty());
  EXPECT_EQ(field.at(Vec3{0, 0, 0}), h);
  field.add(Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 2, 0}, 1.0);  // a triangle in z = 0
  field.add(Vec3{5, 5, 0}, Vec3{5, 5, 3}, Vec3{5, 5, 3}, 0.5);  // a segment along z
  EXPECT_FALSE(field.empty());
  EXPECT_EQ(field.smallest(), 0.5);
  EXPECT_DOUBLE_EQ(field.at(Vec3{0.5, 0.5, 0}), 1.0);
  EXPECT_DOUBLE_EQ(field.at(Vec3{0.5, 0.5, slack}), 1.0);  // within the slack
  EXPECT_DOUBLE_EQ(field.at(Vec3{0.5, 0.5, 2}), 1.0 + grading * (2 - slack));
  EXPECT_DOUBLE_EQ(field.at(Vec3{5, 6, 1}), 0.5 + grading * (1 - slack));
  EXPECT_DOUBLE_EQ(field.at(Vec3{5, 5, 4}), 0.5 + grading * (1 - slack));  // beyond its end
  EXPECT_EQ(field.at(Vec3{-9, -9, -9}), h);
  // The boxes below a size hold every point where the field is below it: the items finer than
  // the size, grown by what the field grows up to it.
  const std::vector<std::array<Vec3, 2>> below_2 = field.boxes_below(2.0);
  ASSERT_EQ(below_2.size(), 2u);
  EXPECT_DOUBLE_EQ(below_2[0][0].x, -((2.0 - 1.0) / grading + slack));
  EXPECT_DOUBLE_EQ(below_2[1][1].z, 3 + (2.0 - 0.5) / grading + slack);
  ASSERT_EQ(field.boxes_below(1.0).size(), 1u);  // the segment only
  EXPECT_TRUE(field.boxes_below(0.5).empty());
  for (double x = -6; x <= 10; x += 0.25)
    for (double z = -6; z <= 10; z += 0.25) {
      const Vec3 p{x, 0.5 * x, z};
      bool inside = false;
      for (const std::array<Vec3, 2>& box : below_2)
        inside = inside || (p.x >= box[0].x && p.y >= box[0].y && p.z >= box[0].z &&
                            p.x <= box[1].x && p.y <= box[1].y && p.z <= box[1].z);
      if (!inside) {
        EXPECT_GE(field.at(p), 2.0) << p.x << " " << p.y << " " << p.z;
      }
    }
}

// feature_size: an edge shorter than 2 fraction h gets its length, at least fraction h, unless
// it has a finer size already; degenerated edges (length 0) and longer ones get none.
TEST(add_short_edge_sizes, sizes_the_short_edges_only) {
  const double h = 10, fraction = 0.1;
  const std::vector<double> length = {0.0, 0.5, 1.5, 1.99, 2.0, 30.0, 0.3};
  std::vector<double> size = {h, h, h, h, h, h, 0.2};
  EXPECT_EQ(mesher::add_short_edge_sizes(length, h, fraction, size), 3u);
  EXPECT_EQ(size, (std::vector<double>{h, 1.0, 1.5, 1.99, h, h, 0.2}));
  std::vector<double> none = {h, h, h, h, h, h, h};
  EXPECT_EQ(mesher::add_short_edge_sizes(length, h, 0.0, none), 0u);  // 0: off
  EXPECT_EQ(none, std::vector<double>(7, h));
  // On the plate with a hole every edge is longer than 2 fraction h at h 5.
  const Prepared p = prepare(occ_plate_with_hole(), 5.0);
  ASSERT_EQ(p.shape.edge_length.size(), static_cast<std::size_t>(p.shape.edges.Extent()));
  double total = 0;
  for (const double l : p.shape.edge_length) total += l;
  std::vector<double> plate(p.shape.edge_length.size(), 5.0);
  EXPECT_EQ(mesher::add_short_edge_sizes(p.shape.edge_length, 5.0, fraction, plate), 0u);
  // Its lengths: the box's 12 edges (4 x 60, 4 x 40, 4 x 10), the hole's two circles and seam.
  EXPECT_NEAR(total, 450 + 32 * M_PI, 1e-6);
}

// feature_size: a face from kNarrowestSizedFace h to kNarrowFaceWidth h wide (twice its area over
// its perimeter) gets kNarrowFaceSizeFactor times its width, unless it has a finer size already;
// wider and narrower faces and faces without a width (no perimeter: infinite) get none.
TEST(add_narrow_face_sizes, sizes_the_narrow_faces_only) {
  const double h = 10, inf = std::numeric_limits<double>::infinity();
  ASSERT_EQ(mesher::kNarrowFaceWidth, 0.1);
  ASSERT_EQ(mesher::kNarrowestSizedFace, 0.01);
  ASSERT_EQ(mesher::kNarrowFaceSizeFactor, 3.0);
  const std::vector<double> width = {inf, 0.5, 0.99, 1.0, 0.02, 30.0, 0.2, 0.1, 0.0};
  std::vector<double> size = {h, h, h, h, h, h, 0.3, h, h};
  std::vector<double> span(width.size(), 30.0);
  EXPECT_EQ(mesher::add_narrow_face_sizes(width, span, h, size), 3u);
  EXPECT_EQ(size[0], h);
  EXPECT_DOUBLE_EQ(size[1], 1.5);
  EXPECT_DOUBLE_EQ(size[2], 2.97);
  EXPECT_EQ(size[3], h);  // not narrower than 0.1 h
  EXPECT_EQ(size[4], h);  // narrower than 0.01 h
  EXPECT_EQ(size[5], h);
  EXPECT_EQ(size[6], 0.3);  // finer already
  EXPECT_DOUBLE_EQ(size[7], 0.3);
  EXPECT_EQ(size[8], h);
  // The plate with a hole (60 x 40 x 10, a hole of radius 8) at h 5: every face is wider than
  // 0.1 h.
  const Prepared p = prepare(occ_plate_with_hole(), 5.0);
  std::vector<double> plate(static_cast<std::size_t>(p.shape.faces.Extent()), 5.0);
  const std::vector<double>& plate_widths = p.shape.face_width;
  EXPECT_EQ(mesher::add_narrow_face_sizes(
                plate_widths, mesher::face_spans(p.shape, plate_widths, 1e9), 5.0, plate),
            0u);
  // A face 0.5 wide (0.05 h) that spans 0.09 across (a whole cylinder of radius 0.045): none.
  std::vector<double> one = {h};
  EXPECT_EQ(mesher::add_narrow_face_sizes({0.5}, {0.09}, h, one), 0u);
  EXPECT_EQ(one[0], h);
  EXPECT_EQ(mesher::add_narrow_face_sizes({0.5}, {0.1}, h, one), 1u);
  EXPECT_DOUBLE_EQ(one[0], 1.5);
}

// How far each face spans across: a rod of radius 0.5 and height 30 (its wall, a whole cylinder,
// spans 1, its width is about 2 pi 0.5; its caps 1); a box 60 x 40 x 10: its faces span their
// shorter side.
TEST(face_spans, are_the_middle_sides_of_the_faces_boxes) {
  const mesher::Shape rod = load(occ_cylinder(0.5, 30));
  const std::vector<double>& widths = rod.face_width;
  const std::vector<double> spans = mesher::face_spans(rod, widths, 1e9);
  ASSERT_EQ(spans.size(), 3u);
  for (std::size_t f = 0; f < spans.size(); ++f) {
    EXPECT_NEAR(spans[f], 1.0, 0.05) << f;
    if (widths[f] > 2) {  // the wall: twice its area over its circles and its seam, twice
      EXPECT_NEAR(widths[f], 2 * (2 * M_PI * 0.5 * 30) / (2 * (2 * M_PI * 0.5) + 2 * 30), 1e-3);
    }
  }
  const mesher::Shape block = load(occ_box(0, 0, 0, 60, 40, 10));
  std::vector<double> box = mesher::face_spans(block, block.face_width, 1e9);
  std::sort(box.begin(), box.end());
  EXPECT_EQ(box.size(), 6u);
  for (std::size_t f = 0; f < 4; ++f) EXPECT_NEAR(box[f], 10, 1e-6) << f;
  for (std::size_t f = 4; f < 6; ++f) EXPECT_NEAR(box[f], 40, 1e-6) << f;
  // Only the faces narrower than `below` are measured: of widths 8 (40 x 10), 8.57 (60 x 10) and
  // 24 (60 x 40), below 8.5 the two 40 x 10 faces, spanning 10.
  const std::vector<double>& widths_of_block = block.face_width;
  const std::vector<double> narrow = mesher::face_spans(block, widths_of_block, 8.5);
  int measured = 0;
  for (std::size_t f = 0; f < narrow.size(); ++f) {
    if (widths_of_block[f] < 8.5) {
      EXPECT_NEAR(narrow[f], 10, 1e-6) << f;
      ++measured;
    } else {
      EXPECT_EQ(narrow[f], std::numeric_limits<double>::infinity()) << f;
    }
  }
  EXPECT_EQ(measured, 2);
}

// The hole's wall (face of radius 8 about (30, 20)) at a local size: refine() brings its sides to
// that size and every other side to the size the field gives at its ends (at most h);
// collapse_sides() keeps them so.
TEST(refine, to_the_local_sizes) {
  const double h = 2.0, fine = 0.5;
  Prepared p = prepare(occ_plate_with_hole(), h);
  int hole = -1;
  for (const mesher::SurfaceTriangle& t : p.surface.triangles) {
    bool on = true;
    for (int n : t.node)
      on = on &&
           std::abs(std::hypot(p.surface.nodes[n].x - 30, p.surface.nodes[n].y - 20) - 8) < 1e-6;
    if (on) hole = t.face;
  }
  ASSERT_GE(hole, 0);
  ASSERT_FALSE(p.lattice.lattice_face[hole]);
  mesher::LocalSizeItems items;
  items.face_size.assign(static_cast<std::size_t>(p.shape.faces.Extent()), h);
  items.edge_size.assign(static_cast<std::size_t>(p.shape.edges.Extent()), h);
  items.face_size[hole] = fine;
  const mesher::SizeField field = mesher::make_size_field(p.surface, items, h, 0.5, 0.02 * h);
  mesher::refine(p.shape, p.surface, h, 0.02 * h, p.lattice.lattice_face, p.lattice.lattice_edge,
                 &field);
  mesher::collapse_sides(p.shape, p.surface, h, h, 0.02 * h, p.lattice.lattice_face, &field);
  ASSERT_TRUE(p.surface.unrefined_faces.empty());
  std::string problem;
  EXPECT_TRUE(closed_and_oriented(p.surface.triangles, problem)) << problem;
  EXPECT_NEAR(enclosed_volume(p.surface.nodes, p.surface.triangles), 60 * 40 * 10 - M_PI * 64 * 10,
              0.01 * M_PI * 64 * 10);
  std::size_t on_hole = 0;
  for (const mesher::SurfaceTriangle& t : p.surface.triangles) {
    if (p.lattice.lattice_face[t.face]) continue;
    for (int c = 0; c < 3; ++c) {
      const int a = t.node[c], b = t.node[(c + 1) % 3];
      const double side = (p.surface.nodes[a] - p.surface.nodes[b]).norm();
      const double wanted = std::min(field.at(p.surface.nodes[a]), field.at(p.surface.nodes[b]));
      EXPECT_LE(side, wanted * (1 + 1e-9)) << "face " << t.face;
      if (t.face == hole) {
        EXPECT_LE(side, fine * (1 + 1e-9));
      }
    }
    on_hole += t.face == hole;
  }
  // The wall is 2 pi 8 x 10: about 500 / (0.5^2 sqrt(3) / 4) triangles of side 0.5.
  EXPECT_GT(on_hole, 1500u);
}

// The finer lattices' points around the fine hole: inside, below h where they are, half the
// size wanted there clear of the surface's nodes, on a lattice of spacing h / 2^l.
TEST(place_graded_points, fill_the_graded_zone_inside) {
  const double h = 2.0, fine = 0.5;
  Prepared p = prepare(occ_plate_with_hole(), h);
  mesher::LocalSizeItems items;
  items.face_size.assign(static_cast<std::size_t>(p.shape.faces.Extent()), h);
  items.edge_size.assign(static_cast<std::size_t>(p.shape.edges.Extent()), h);
  for (const mesher::SurfaceTriangle& t : p.surface.triangles)
    if (!p.lattice.lattice_face[t.face]) items.face_size[t.face] = fine;  // the hole's wall
  const mesher::SizeField field = mesher::make_size_field(p.surface, items, h, 0.5, 0.02 * h);
  mesher::refine(p.shape, p.surface, h, 0.02 * h, p.lattice.lattice_face, p.lattice.lattice_edge,
                 &field);
  mesher::collapse_sides(p.shape, p.surface, h, h, 0.02 * h, p.lattice.lattice_face, &field);
  const std::vector<Vec3> nodes =
      mesher::frame_nodes(p.shape, p.surface, p.lattice, -1, mesher::SweptSurface{});
  mesher::Surroundings around(nodes, p.surface, p.lattice, h);
  const mesher::Parity parity(nodes, p.surface, p.shape.face_solid_count, around, h);
  mesher::InsertedPoints inserted;
  const std::size_t placed =
      mesher::place_graded_points(field, p.lattice, parity, around, 0.5, inserted);
  ASSERT_EQ(inserted.points.size(), placed);
  EXPECT_GT(placed, 100u);
  std::size_t on_faces = 0;
  for (std::size_t i = 0; i < placed; ++i) {
    const Vec3 q = inserted.points[i];
    const Vec3 world = p.lattice.frame.to_world(q);
    const double size = field.at(world);
    EXPECT_LT(size, h) << i;
    bool on = false;
    const bool inside = occ_inside(p.shape, world, on);
    if (inserted.face[i] >= 0) {
      EXPECT_TRUE(on) << i;  // on the lattice face it was given to
      ++on_faces;
    } else {
      EXPECT_TRUE(inside && !on) << i;
    }
    for (const Vec3& n : nodes) ASSERT_GE((n - q).norm(), 0.5 * size * (1 - 1e-9)) << i;
    // On a finer lattice: each coordinate a multiple of spacing / 2^l, l <= 2 (h / fine = 4).
    for (int a = 0; a < 3; ++a) {
      const double steps = mesher::coord(q, a) / (p.lattice.spacing[a] / 4);
      EXPECT_NEAR(steps, std::round(steps), 1e-9) << i;
    }
  }
  EXPECT_GT(on_faces, 0u);  // the plate's faces around the hole get points of their own
}

}  // namespace
}  // namespace hexmerge::test
