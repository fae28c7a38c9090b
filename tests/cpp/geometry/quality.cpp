#include "hexmerge/geometry/quality.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "fixtures.h"
#include "hexmerge/geometry/vec3.h"

namespace hexmerge {
namespace {

constexpr double kPi = 3.141592653589793;

TEST(tet_volume, sign_and_value) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {0, 0, 1};
  EXPECT_DOUBLE_EQ(tet_volume(a, b, c, d), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(tet_volume(a, c, b, d), -1.0 / 6.0);
  const double e[3] = {0.3, 0.2, 0.0};
  EXPECT_DOUBLE_EQ(tet_volume(a, b, c, e), 0.0);
}

TEST(quad_dihedral_angle, folding_along_the_diagonal) {
  // Diagonal a-c on the x axis; b below it in z = 0, d rotated by theta about the x axis.
  const double a[3] = {0, 0, 0}, b[3] = {1, -1, 0}, c[3] = {2, 0, 0};
  for (double theta : {0.0, 10.0, 30.0, 90.0, 135.0}) {
    const double r = theta * kPi / 180.0;
    const double d[3] = {1, std::cos(r), std::sin(r)};
    EXPECT_NEAR(quad_dihedral_angle(a, b, c, d), 180.0 - theta, 1e-9) << theta;
  }
  // Flat but not square: still 180.
  const double p[3] = {0, 0, 0}, q[3] = {3, 0, 0}, s[3] = {4, 2, 0}, t[3] = {-1, 1, 0};
  EXPECT_NEAR(quad_dihedral_angle(p, q, s, t), 180.0, 1e-9);
}

TEST(quad_is_planar, to_round_off_only) {
  // A square moved off the axes (its corners' coordinates not exact): planar.
  const double a[3] = {0.1, 0.2, 0.3}, b[3] = {1.1, 0.2 + 1.0 / 3, 0.3},
               c[3] = {1.1, 1.2 + 1.0 / 3, 0.3 + 1.0 / 7}, d[3] = {0.1, 1.2, 0.3 + 1.0 / 7};
  EXPECT_TRUE(quad_is_planar(a, b, c, d));
  // One corner lifted by 1e-6 of the sides: not planar (a fold of about 1e-4 degrees).
  const double lifted[3] = {0.1, 1.2, 0.3 + 1.0 / 7 + 1e-6};
  EXPECT_FALSE(quad_is_planar(a, b, c, lifted));
  EXPECT_GT(quad_dihedral_angle(a, b, c, lifted), 179.99);
}

TEST(quad_max_corner_angle, known_quads) {
  const double a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {2, 1, 0}, d[3] = {0, 1, 0};
  EXPECT_NEAR(quad_max_corner_angle(a, b, c, d), 90.0, 1e-9);  // rectangle
  const double h = std::sqrt(3.0) / 2.0;
  const double r1[3] = {0, 0, 0}, r2[3] = {1, 0, 0}, r3[3] = {1.5, h, 0}, r4[3] = {0.5, h, 0};
  EXPECT_NEAR(quad_max_corner_angle(r1, r2, r3, r4), 120.0, 1e-9);  // 60/120 rhombus
  const double t1[3] = {0, 0, 0}, t2[3] = {4, 0, 0}, t3[3] = {3, 1, 0}, t4[3] = {1, 1, 0};
  EXPECT_NEAR(quad_max_corner_angle(t1, t2, t3, t4), 135.0, 1e-9);  // trapezoid 45/135
  // Measured in 3D: with d lifted to (0.5, 1, 1) the corners are 70.5, 90, 90 and 63.4 degrees
  // (a projection onto z = 0 would see 116.6 at d).
  const double f1[3] = {0, 0, 0}, f2[3] = {1, 0, 0}, f3[3] = {1, 1, 0}, f4[3] = {0.5, 1, 1};
  EXPECT_NEAR(quad_max_corner_angle(f1, f2, f3, f4), 90.0, 1e-9);
}

TEST(cell_volume, non_planar_hex_is_the_trilinear_volume) {
  // Unit cube with corner 6 (1,1,1) lifted by h: the trilinear map z = w + h u v w has
  // det J = 1 + h u v, so the volume is 1 + h / 4. Its bilinear faces enclose exactly that.
  for (double h : {0.0, 0.2, 0.4, -0.3}) {
    std::vector<double> p = {0, 0, 0, 1, 0, 0, 1, 1, 0,     0, 1, 0,
                             0, 0, 1, 1, 0, 1, 1, 1, 1 + h, 0, 1, 1};
    const index_t ids[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    EXPECT_NEAR(cell_volume(CellType::Hex, p.data(), ids), 1.0 + h / 4.0, 1e-14) << h;
  }
}

TEST(cell_volume, matches_tet_sums_for_flat_faces) {
  // Any cube triangulation sums to the hex's volume; affine images too.
  std::mt19937 rng(11);
  for (int k = 0; k < 10; ++k) {
    TetMesh mesh = test::kuhn_grid(1);
    test::random_affine_map(mesh, rng);
    const index_t hex[8] = {test::grid_node(1, 0, 0, 0), test::grid_node(1, 1, 0, 0),
                            test::grid_node(1, 1, 1, 0), test::grid_node(1, 0, 1, 0),
                            test::grid_node(1, 0, 0, 1), test::grid_node(1, 1, 0, 1),
                            test::grid_node(1, 1, 1, 1), test::grid_node(1, 0, 1, 1)};
    EXPECT_NEAR(cell_volume(CellType::Hex, mesh.points.data(), hex), test::total_volume(mesh),
                1e-12);
  }
  // Pyramid and prism against their tets.
  const std::vector<double> pyr = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0, 1, 1, 1};
  const index_t py[5] = {0, 1, 2, 3, 4};
  EXPECT_NEAR(cell_volume(CellType::Pyramid, pyr.data(), py), 4.0 / 3.0, 1e-14);
  const std::vector<double> pri = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  const index_t pr[6] = {0, 1, 2, 3, 4, 5};
  EXPECT_NEAR(cell_volume(CellType::Prism, pri.data(), pr), 0.5, 1e-14);
  const index_t tet[4] = {0, 1, 3, 4};
  EXPECT_NEAR(cell_volume(CellType::Tet, pyr.data(), tet),
              tet_volume(&pyr[0], &pyr[3], &pyr[9], &pyr[12]), 1e-15);
}

TEST(scaled_jacobian, known_cells) {
  // A parallelepiped with edges (1,0,0), (0,1,0), (1,1,1): every corner 1/sqrt(3).
  std::vector<double> p = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 1, 1, 2, 1, 1, 2, 2, 1, 1, 2, 1};
  const index_t ids[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  EXPECT_NEAR(scaled_jacobian(CellType::Hex, p.data(), ids), 1.0 / std::sqrt(3.0), 1e-12);
  // Push corner 6 through the opposite faces: that corner inverts.
  std::vector<double> bad = {0, 0, 0, 1, 0, 0, 1,    1,    0,    0, 1, 0,
                             0, 0, 1, 1, 0, 1, -0.5, -0.5, -0.5, 0, 1, 1};
  EXPECT_LT(scaled_jacobian(CellType::Hex, bad.data(), ids), 0.0);
  // Right-triangle prism: the 45 degree corners score sin(45) * 2 / sqrt(3).
  const std::vector<double> pri = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  EXPECT_NEAR(scaled_jacobian(CellType::Prism, pri.data(), ids),
              std::sqrt(0.5) * 2 / std::sqrt(3.0), 1e-12);
  // Flattened tet: zero.
  const std::vector<double> flat = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  EXPECT_NEAR(scaled_jacobian(CellType::Tet, flat.data(), ids), 0.0, 1e-15);
}

// The tet's scaled Jacobian is computed on its own path (two corners per SSE2 register); it must
// be the general corner loop's double, bit for bit: the mesher's flips and moves compare them.
TEST(scaled_jacobian, a_tet_is_the_general_loops_double_bit_for_bit) {
  const CellDescriptor& d = descriptor(CellType::Tet);
  auto general = [&](const std::vector<double>& p, const index_t* v) {
    double worst = 1e300;
    for (int k = 0; k < d.nb_corners; ++k) {
      const auto& c = d.corner[k];
      const Vec3 q = Vec3::of(&p[3 * v[c[0]]]);
      const Vec3 e1 = Vec3::of(&p[3 * v[c[1]]]) - q, e2 = Vec3::of(&p[3 * v[c[2]]]) - q,
                 e3 = Vec3::of(&p[3 * v[c[3]]]) - q;
      const double l = e1.norm() * e2.norm() * e3.norm();
      worst = std::min(worst, l > 0.0 ? det3(e1, e2, e3) / l : 0.0);
    }
    return std::min(1.0, worst * d.jacobian_scale);
  };
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  std::vector<double> p(3 * 4);
  const index_t ids[4] = {0, 1, 2, 3};
  std::size_t tested = 0, negative = 0, flat = 0;
  for (int i = 0; i < 200000; ++i) {
    for (double& x : p) x = coordinate(random);
    const int kind = i % 5;
    if (kind == 1)  // vertex 3 on the line through 0 and 1: flat, with rounding
      for (int a = 0; a < 3; ++a) p[9 + a] = p[a] + 0.37 * (p[3 + a] - p[a]);
    if (kind == 2)  // two vertices at one place: an edge of length 0
      for (int a = 0; a < 3; ++a) p[6 + a] = p[a];
    if (kind == 3)  // a sliver: vertex 3 near the plane of the others
      for (int a = 0; a < 3; ++a)
        p[9 + a] = 0.3 * p[a] + 0.3 * p[3 + a] + 0.4 * p[6 + a] + 1e-9 * coordinate(random);
    if (kind == 4)  // far from the origin, small: cancellation in the differences
      for (double& x : p) x = 1e6 + 1e-3 * x;
    const double fast = scaled_jacobian(CellType::Tet, p.data(), ids);
    const double loop = general(p, ids);
    ASSERT_EQ(std::memcmp(&fast, &loop, sizeof fast), 0)
        << "tet " << i << ": " << fast << " against " << loop;
    ++tested, negative += fast < 0, flat += fast == 0;
  }
  EXPECT_EQ(tested, 200000u);
  EXPECT_GT(negative, 1000u);  // both orientations met
  EXPECT_GT(flat, 1000u);      // the zero-length edges' corners
}

TEST(AngleBound, predicates_answer_as_the_angles_do) {
  // Random quads, from flat to folded, against bounds far from, near and at their angles.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const double fold = k % 4 == 0 ? 1e-3 : 0.5;
    const double a[3] = {0, 0, 0}, c[3] = {2, u(rng) * 0.1, 0};
    const double b[3] = {1 + u(rng) * 0.5, -1 + u(rng) * 0.5, u(rng) * fold};
    const double d[3] = {1 + u(rng) * 0.5, 1 + u(rng) * 0.5, u(rng) * fold};
    const double dihedral = quad_dihedral_angle(a, b, c, d);
    const double corner = quad_max_corner_angle(a, b, c, d);
    for (const double delta : {0.0, 1e-13, -1e-13, 1e-6, -1e-6, 5.0, -5.0}) {
      const AngleBound on_dihedral(dihedral + delta), on_corner(corner + delta);
      EXPECT_EQ(quad_dihedral_angle_below(a, b, c, d, on_dihedral), dihedral < on_dihedral.degrees);
      EXPECT_EQ(quad_max_corner_angle_above(a, b, c, d, on_corner), corner > on_corner.degrees);
      for (const double bound : {150.0, 179.0, 170.0, 120.0}) {
        EXPECT_EQ(quad_dihedral_angle_below(a, b, c, d, AngleBound(bound)), dihedral < bound);
        EXPECT_EQ(quad_max_corner_angle_above(a, b, c, d, AngleBound(bound)), corner > bound);
      }
      ++checked;
    }
  }
  // A degenerate quad (b on the diagonal): dihedral 0, corner 180.
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, d[3] = {1, 1, 0};
  EXPECT_TRUE(quad_dihedral_angle_below(a, b, c, d, AngleBound(10.0)));
  EXPECT_TRUE(quad_max_corner_angle_above(a, a, c, d, AngleBound(170.0)));
  EXPECT_EQ(checked, 14000);
}

}  // namespace
}  // namespace hexmerge
