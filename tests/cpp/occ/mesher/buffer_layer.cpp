#include "hexmerge/occ/mesher/buffer_layer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/face_chart.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

double scaled_jacobian_of(CellType type, const std::vector<Vec3>& corners, const index_t* order) {
  std::vector<double> xyz;
  for (const Vec3& c : corners) xyz.insert(xyz.end(), {c.x, c.y, c.z});
  return scaled_jacobian(type, xyz.data(), order);
}

// A cylinder (r 10, 20 long) at h 2.5, not swept, its core pulled: the bases facing its curved
// face get hexahedra to it; the face is triangulated again with their tops in it, the surface
// still closed, outward and on the CAD, enclosing the same volume to 1 %; each top is two of its
// triangles; every hexahedron keeps scaled Jacobian 0.3, every side pyramid 0.4.
TEST(buffer_layer, a_cylinders_core_reaches_its_curved_face) {
  const double h = 2.5;
  Prepared p = prepare(occ_cylinder(10, 20), h);
  repair_surface(p);
  const Placed at = place(p);
  const std::vector<Vec3>& nodes = at.nodes;
  const mesher::Surroundings& around = *at.around;
  const mesher::Parity& parity = *at.parity;
  const mesher::KeptPoints kept =
      mesher::keep_lattice_points(p.lattice, around, parity, 0.3 * h, 0.3 * h, -1);
  const mesher::CoreLayout layout =
      mesher::lay_core(p.lattice, around, parity, kept, -1, h, /*pull=*/true);
  std::vector<char> eligible(static_cast<std::size_t>(p.shape.faces.Extent()));
  int curved = -1;
  for (std::size_t f = 0; f < eligible.size(); ++f) {
    eligible[f] = !p.lattice.lattice_face[f];
    if (eligible[f]) curved = static_cast<int>(f);
  }
  ASSERT_GE(curved, 0);
  const double volume_before = enclosed_volume(p.surface.nodes, p.surface.triangles);
  double smallest_before = 180;
  for (const mesher::SurfaceTriangle& t : p.surface.triangles)
    if (t.face == curved)
      smallest_before =
          std::min(smallest_before, mesher::smallest_angle(p.surface.nodes, t.node) * 180 / M_PI);
  mesher::BufferReport report;
  const mesher::BufferCells buffer = mesher::buffer_layer(p.shape, p.lattice, layout, nodes, around,
                                                          eligible, h, p.surface, report);
  EXPECT_EQ(report.nb_faces, 1u);
  EXPECT_GT(report.nb_hexes, 24u);
  EXPECT_EQ(buffer.hexes.size(), report.nb_hexes);
  EXPECT_EQ(buffer.pyramids.size(), report.nb_pyramids);

  std::string problem;
  EXPECT_TRUE(closed_and_oriented(p.surface.triangles, problem)) << problem;
  // (The tops' quads, h wide, are chords of the face: 0.03 h off it at their middle here.)
  EXPECT_NEAR(enclosed_volume(p.surface.nodes, p.surface.triangles), volume_before,
              1e-2 * volume_before);
  double smallest_after = 180;
  for (const mesher::SurfaceTriangle& t : p.surface.triangles)
    if (t.face == curved)
      smallest_after =
          std::min(smallest_after, mesher::smallest_angle(p.surface.nodes, t.node) * 180 / M_PI);
  EXPECT_GE(smallest_after, std::min(15.0, smallest_before));

  const TriangleSet triangles(p.surface, 1e-9 * h);
  static const index_t kUp[8] = {0, 1, 2, 3, 4, 5, 6, 7}, kDown[8] = {0, 3, 2, 1, 4, 7, 6, 5};
  for (const mesher::BufferCells::Hex& hex : buffer.hexes) {
    const mesher::PyramidFace& f = layout.pyramid_faces[hex.face];
    const std::array<std::size_t, 4> base = mesher::base_corners(p.lattice, f);
    std::vector<Vec3> corners;
    for (const std::size_t c : base) corners.push_back(layout.point_at(p.lattice, c));
    std::array<Vec3, 4> top_world{};
    for (int m = 0; m < 4; ++m) {
      corners.push_back(hex.top[m]);
      top_world[m] = p.lattice.frame.to_world(hex.top[m]);
      EXPECT_LT(distance_to_face(p.shape, curved, top_world[m]), 1e-6 * h);
    }
    EXPECT_GE(scaled_jacobian_of(CellType::Hex, corners, f.dir % 2 ? kUp : kDown), 0.3);
    EXPECT_TRUE(triangles.has(top_world[0], top_world[1], top_world[2]));
    EXPECT_TRUE(triangles.has(top_world[0], top_world[2], top_world[3]));
  }
  static const index_t kAround[5] = {0, 1, 2, 3, 4}, kOther[5] = {0, 3, 2, 1, 4};
  for (const mesher::BufferCells::SidePyramid& pyramid : buffer.pyramids) {
    const std::vector<Vec3> corners{layout.point_at(p.lattice, pyramid.lo),
                                    layout.point_at(p.lattice, pyramid.hi),
                                    buffer.top_of.at(pyramid.hi), buffer.top_of.at(pyramid.lo),
                                    layout.apex_at(p.lattice, pyramid.apex_cell)};
    EXPECT_GE(std::max(scaled_jacobian_of(CellType::Pyramid, corners, kAround),
                       scaled_jacobian_of(CellType::Pyramid, corners, kOther)),
              0.4);
  }
}

// A planar face, the square [0, 4]^2 as a grid of unit squares split in two (its nodes the
// surface's, world = (x, y, 0)), triangulated again with two quads: A inside, which takes the
// nodes near it, and B beside the outline, 0.1 from it, whose sides leave triangles of about 11
// degrees against it. With both the face fails (the face's own smallest angle is 45, the limit
// 15) and only B's tops are blamed; with A alone it takes A's two triangles and keeps its area.
TEST(retriangulate, blames_the_tops_of_the_thin_triangles_only) {
  mesher::Surface surface;
  mesher::FaceChart chart;
  chart.face = 0;
  const auto id = [](int i, int j) { return 5 * j + i; };
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) {
      surface.nodes.push_back(Vec3{double(i), double(j), 0});
      chart.node.push_back(id(i, j));
      chart.uv.push_back(mesher::UV{double(i), double(j)});
      chart.xy.push_back(mesher::P2{double(i), double(j)});
      chart.on_outline.push_back(i == 0 || j == 0 || i == 4 || j == 4);
    }
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      chart.corners.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      chart.corners.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  for (int k = 0; k < 4; ++k) {
    chart.outline.push_back({id(k, 0), id(k + 1, 0)});
    chart.outline.push_back({id(4, k), id(4, k + 1)});
    chart.outline.push_back({id(k + 1, 4), id(k, 4)});
    chart.outline.push_back({id(0, k + 1), id(0, k)});
  }
  chart.area = 16;
  chart.smallest_angle = 45;
  // Tops 0-3: quad A, around (1.5, 1.5); tops 4-7: quad B, x from 0.1 to 0.9, y from 2.5 to 3.5.
  const std::vector<mesher::P2> xy{{1.2, 1.2}, {1.8, 1.2}, {1.8, 1.8}, {1.2, 1.8},
                                   {0.1, 2.5}, {0.9, 2.5}, {0.9, 3.5}, {0.1, 3.5}};
  std::vector<mesher::UV> uv;
  std::vector<Vec3> world;
  for (const mesher::P2& q : xy) uv.push_back({q[0], q[1]}), world.push_back(Vec3{q[0], q[1], 0});
  const std::vector<char> elsewhere(surface.nodes.size(), 0);
  const mesher::RetriangulateLimits limits{0.35, 0.02, 15.0};
  const std::array<int, 4> a{0, 1, 2, 3}, b{4, 5, 6, 7};

  std::vector<int> blamed;
  EXPECT_FALSE(mesher::retriangulate(chart, surface, {a, b}, xy, uv, world, elsewhere, 1.0, limits,
                                     &blamed));
  ASSERT_FALSE(blamed.empty());
  for (const int top : blamed) EXPECT_GE(top, 4) << "a top of quad A blamed";
  // The thin triangles' corners at x = 0.1, against the outline.
  EXPECT_TRUE(std::count(blamed.begin(), blamed.end(), 4) &&
              std::count(blamed.begin(), blamed.end(), 7));

  blamed = {99};
  const std::optional<mesher::Retriangulated> made =
      mesher::retriangulate(chart, surface, {a}, xy, uv, world, elsewhere, 1.0, limits, &blamed);
  ASSERT_TRUE(made);
  EXPECT_EQ(blamed, std::vector<int>{99});  // untouched when it succeeds
  double area = 0;
  std::set<std::array<int, 3>> triangles;
  for (const std::array<int, 3>& t : made->node) {
    const auto at = [&](int n) {
      return n >= 0 ? surface.nodes[std::size_t(n)] : world[std::size_t(-1 - n)];
    };
    area += 0.5 * (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0])).norm();
    std::array<int, 3> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    triangles.insert(sorted);
  }
  EXPECT_NEAR(area, 16.0, 1e-9);
  EXPECT_TRUE(triangles.count({-3, -2, -1}));  // tops 0, 1, 2
  EXPECT_TRUE(triangles.count({-4, -3, -1}));  // tops 0, 2, 3
}

}  // namespace
}  // namespace hexmerge::test
