#include "hexmerge/occ/mesher/buffer_layer.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>
#include <string>

#include "hexmerge/geometry/quality.h"
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

  // The surface's triangles by their corners' positions (world, rounded to 1e-9 h).
  const auto key = [&](const Vec3& q) {
    return std::array<long long, 3>{std::llround(q.x / (1e-9 * h)), std::llround(q.y / (1e-9 * h)),
                                    std::llround(q.z / (1e-9 * h))};
  };
  std::set<std::array<std::array<long long, 3>, 3>> triangles;
  for (const mesher::SurfaceTriangle& t : p.surface.triangles) {
    std::array<std::array<long long, 3>, 3> corners{};
    for (int c = 0; c < 3; ++c) corners[c] = key(p.surface.nodes[t.node[c]]);
    std::sort(corners.begin(), corners.end());
    triangles.insert(corners);
  }
  const auto has_triangle = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    std::array<std::array<long long, 3>, 3> corners{key(a), key(b), key(c)};
    std::sort(corners.begin(), corners.end());
    return triangles.count(corners) > 0;
  };
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
    EXPECT_TRUE(has_triangle(top_world[0], top_world[1], top_world[2]));
    EXPECT_TRUE(has_triangle(top_world[0], top_world[2], top_world[3]));
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

}  // namespace
}  // namespace hexmerge::test
