#include "hexmerge/occ/mesher/second_order.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// The plate with a hole (radius 8 about (30, 20), along z) and one tet with a face on the bore:
// A and B at +-30 degrees on z = 0, C at 0 degrees on z = 3, D inside the plate at `d`.
struct BoreTet {
  mesher::Shape shape = load(occ_plate_with_hole());
  int bore = -1;
  TetMesh mesh;
  std::vector<int> vertex_face;
  explicit BoreTet(const Point& d) {
    for (int f = 0; f < shape.faces.Extent() && bore < 0; ++f)
      if (distance_to_face(shape, f, {38, 20, 5}) < 1e-9 &&
          distance_to_face(shape, f, {30, 28, 5}) < 1e-9)
        bore = f;
    const double c = 30 + 8 * std::cos(M_PI / 6), s = 8 * std::sin(M_PI / 6);
    mesh = make_tet_mesh({{c, 20 + s, 0}, {c, 20 - s, 0}, {38, 20, 3}, d}, {});
    add_tet(mesh, 0, 1, 2, 3);
    mesh.regions = {0};
    vertex_face = {bore, bore, bore, -1};
  }
  Tet10Mesh run(mesher::SecondOrderReport& report) const {
    return mesher::second_order_mesh(shape, mesh, vertex_face, {{0, 1, 2}}, {bore}, 1e-9, report);
  }
};

// The mid node of the edge between corners a and b of the one tet.
Vec3 mid_of(const Tet10Mesh& m, index_t a, index_t b) {
  static constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int k = 0; k < 6; ++k) {
    const index_t u = m.tets10[kEdge[k][0]], v = m.tets10[kEdge[k][1]];
    if ((u == a && v == b) || (u == b && v == a)) return Vec3::of(&m.points[3 * m.tets10[4 + k]]);
  }
  ADD_FAILURE() << "no edge " << a << "-" << b;
  return {};
}

double radius(const Vec3& p) { return std::hypot(p.x - 30, p.y - 20); }

TEST(SecondOrder, BoreMidNodesOnTheCylinderInnerOnesStraight) {
  const BoreTet t({44, 20, 1});
  ASSERT_GE(t.bore, 0);
  mesher::SecondOrderReport report;
  const Tet10Mesh m = t.run(report);
  ASSERT_EQ(m.tets10.size(), 10u);
  ASSERT_EQ(m.points.size(), 3u * 10);
  EXPECT_EQ(report.nb_projected, 3u);
  EXPECT_EQ(report.nb_straight, 0u);
  // The bore triangle's edges: on the cylinder; AB's midpoint projected to angle 0, z = 0.
  EXPECT_NEAR(radius(mid_of(m, 0, 1)), 8, 1e-9);
  EXPECT_NEAR(radius(mid_of(m, 1, 2)), 8, 1e-9);
  EXPECT_NEAR(radius(mid_of(m, 0, 2)), 8, 1e-9);
  EXPECT_NEAR((mid_of(m, 0, 1) - Vec3{38, 20, 0}).norm(), 0, 1e-9);
  // The edges to D (inside): their midpoints.
  const Vec3 d = Vec3::of(&m.points[9]);
  for (index_t a = 0; a < 3; ++a)
    EXPECT_NEAR((mid_of(m, a, 3) - (Vec3::of(&m.points[3 * a]) + d) * 0.5).norm(), 0, 1e-15);
  validate_tet10_mesh(m);
}

TEST(SecondOrderGuard, MidNodeThatWouldInvertTheTetStaysStraight) {
  // D just beyond the chord AB's midpoint (x 36.93) and short of the bore (x 38): the curved
  // edge AB would pass D, the tet's Jacobian at A and B turn negative.
  const BoreTet t({37.2, 20, 0.2});
  mesher::SecondOrderReport report;
  const Tet10Mesh m = t.run(report);
  EXPECT_GE(report.nb_straight, 1u);
  EXPECT_EQ(report.nb_projected + report.nb_straight, 3u);
  const Vec3 a = Vec3::of(&m.points[0]), b = Vec3::of(&m.points[3]);
  EXPECT_NEAR((mid_of(m, 0, 1) - (a + b) * 0.5).norm(), 0, 1e-15);
  validate_tet10_mesh(m);
}

}  // namespace
}  // namespace hexmerge::test
