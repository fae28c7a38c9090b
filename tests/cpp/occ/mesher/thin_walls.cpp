#include "hexmerge/occ/mesher/thin_walls.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// Walls from the chord deflection on are sized: mesh_shape()'s default, 0.02 h.
constexpr double kDeflection = 0.02;

double area(const mesher::SizedTriangle& p) { return 0.5 * (p.b - p.a).cross(p.c - p.a).norm(); }

// A slab 30 x 20 x t at h 6: across its thickness t (0.02 h to 0.2 h) both large faces are covered
// by patches of 3 t, each side at most 2 h; across its 20 and 30 (over 0.2 h) no
// patch.
TEST(thin_wall_sizes, covers_both_faces_of_a_thin_slab) {
  ASSERT_EQ(mesher::kThinWall, 0.2);
  ASSERT_EQ(mesher::kThinWallSizeFactor, 3.0);
  const double h = 6;
  for (const double t : {1.0, 0.6, 0.2}) {
    const Prepared p = prepare(occ_box(0, 0, 0, 30, 20, t), h);
    mesher::UnsizedWalls none;
    const std::vector<mesher::SizedTriangle> patches =
        mesher::thin_wall_sizes(p.surface, h, kDeflection * h, &none);
    ASSERT_FALSE(patches.empty());
    EXPECT_EQ(none.patches, 0u);
    double covered = 0;
    for (const mesher::SizedTriangle& q : patches) {
      for (const Vec3* c : {&q.a, &q.b, &q.c})  // on the top or the bottom
        EXPECT_TRUE(std::abs(c->z) < 1e-9 || std::abs(c->z - t) < 1e-9) << c->z;
      EXPECT_DOUBLE_EQ(q.size, 3 * t);
      EXPECT_LE(std::max({(q.b - q.a).norm(), (q.c - q.b).norm(), (q.a - q.c).norm()}),
                2 * h + 1e-9);
      covered += area(q);
    }
    EXPECT_NEAR(covered, 2 * 30 * 20, 1e-6);
  }
  // Thinner than the chord deflection, 0.02 h (0.12 at h 6): none, said (both faces, 0.1 apart).
  mesher::UnsizedWalls unsized;
  EXPECT_TRUE(mesher::thin_wall_sizes(prepare(occ_box(0, 0, 0, 30, 20, 0.1), h).surface, h,
                                      kDeflection * h, &unsized)
                  .empty());
  EXPECT_GE(unsized.patches, 2u);
  EXPECT_NEAR(unsized.thinnest, 0.1, 1e-9);
  EXPECT_NEAR(unsized.thickest, 0.1, 1e-9);
  // On a surface of a quarter of that deflection (0.005 h), walls from 0.03 on are sized.
  EXPECT_FALSE(mesher::thin_wall_sizes(prepare(occ_box(0, 0, 0, 30, 20, 0.1), h).surface, h,
                                       kDeflection / 4 * h)
                   .empty());
}

// A box 30 x 20 x 10 (triangulated at h 6): at h 6 thicker than 0.2 h everywhere, no patch; at
// h 60 its faces 10 apart (under 12) are a wall, those 20 and 30 apart are not.
TEST(thin_wall_sizes, leaves_walls_thicker_than_a_fifth_of_h) {
  const Prepared p = prepare(occ_box(0, 0, 0, 30, 20, 10), 6);
  EXPECT_TRUE(mesher::thin_wall_sizes(p.surface, 6, kDeflection * 6).empty());
  const std::vector<mesher::SizedTriangle> patches =
      mesher::thin_wall_sizes(p.surface, 60, kDeflection * 60);
  double covered = 0;
  for (const mesher::SizedTriangle& q : patches) {
    EXPECT_NEAR(std::abs(q.b.z - q.a.z) + std::abs(q.c.z - q.a.z), 0, 1e-9);  // top or bottom
    EXPECT_DOUBLE_EQ(q.size, 3 * 10.0);
    covered += area(q);
  }
  EXPECT_NEAR(covered, 2 * 30 * 20, 1e-6);
}

// A triangle facing down (z = 0) under one 1 above it: facing back, a wall 1 thick. Tilted
// about the line x = 0 at z = 1, by 8 degrees (within atan(kWallTaper), 9.46) it still is one; by
// 12 degrees (a wedge: the thickness grows by a fifth of the distance, over a size of 3 t by more
// than half of t) and by 50 (a face across a corner) it is none. Triangles as given (outward).
TEST(thin_wall_sizes, a_wedge_or_a_face_across_a_corner_is_no_wall) {
  ASSERT_EQ(mesher::kWallTaper, 1.0 / 6);
  const double h = 6;
  const auto patches_under = [&](double degrees) {
    const double slope = std::tan(degrees * M_PI / 180);  // z = 1 - slope x
    mesher::Surface surface;
    surface.nodes = {{0, 0, 0},
                     {0, 10, 0},
                     {10, 0, 0},
                     {-5, -5, 1 + 5 * slope},
                     {5, -5, 1 - 5 * slope},
                     {-5, 20, 1 + 5 * slope}};
    if (degrees == 0) surface.nodes[4] = {20, -5, 1};
    mesher::SurfaceTriangle down, up;
    down.node = {0, 1, 2}, down.face = 0;
    up.node = {3, 4, 5}, up.face = 1;
    surface.triangles = {down, up};
    return mesher::thin_wall_sizes(surface, h, kDeflection * h);
  };
  double lower = 0, upper = 0;  // the patches' area on each
  for (const mesher::SizedTriangle& q : patches_under(0)) {
    EXPECT_DOUBLE_EQ(q.size, 3.0);
    (q.a.z == 0 ? lower : upper) += area(q);
  }
  EXPECT_NEAR(lower, 50, 1e-9);  // all of it
  EXPECT_GT(upper, 0);           // where it lies over the lower one
  EXPECT_LT(upper, 2 * 50);      // (its patches, up to h across, straddle the lower one's outline)
  // Tilted by 8 degrees: the lower triangle's patches whose centroids lie h / 12 to 0.2 h under
  // the upper one (x up to 1.2 tan 82 = 8.5 from where it is 0.5 above) are still a wall.
  const std::vector<mesher::SizedTriangle> tapered = patches_under(8);
  EXPECT_FALSE(tapered.empty());
  for (const mesher::SizedTriangle& q : tapered) EXPECT_LE(q.size, 3 * 0.2 * h + 1e-9);
  EXPECT_TRUE(patches_under(12).empty());
  EXPECT_TRUE(patches_under(50).empty());
}

// A triangle facing down (z = 0, 60 x 30) under a plane that rises from 0.06 at x = 0 by 1.5
// degrees (the gap 0.12, 0.02 h at h 6, at x = 2.3; h / 12 = 0.5 at x = 16.8): the gap is a wall
// from x = 2.3 on, but under h / 12 only 2 h (kTooThinReach) from where it is thinner than 0.02 h
// (a wall tapering to nothing, as a boss nearly tangent to a side: sized down to 0.06 h beside
// triangles of h, a random part's elements under 0.2 went from 570 to 2,282). Under a parallel
// plane 0.3 above (0.05 h, nowhere thinner), the lower triangle is sized all over, at 0.9.
TEST(thin_wall_sizes, walls_under_h_over_12_only_even_and_away_from_thinner_ones) {
  ASSERT_EQ(mesher::kEvenWall, 0.25 / 3);
  ASSERT_EQ(mesher::kTooThinReach, 2.0);
  const double h = 6;
  const auto patches_under = [&](double start, double degrees) {
    const double slope = std::tan(degrees * M_PI / 180);  // z = start + slope x
    mesher::Surface surface;
    surface.nodes = {{0, 0, 0},
                     {0, 30, 0},
                     {60, 0, 0},
                     {-5, -5, start - 5 * slope},
                     {70, -5, start + 70 * slope},
                     {-5, 40, start - 5 * slope}};
    mesher::SurfaceTriangle down, up;
    down.node = {0, 1, 2}, down.face = 0;
    up.node = {3, 4, 5}, up.face = 1;
    surface.triangles = {down, up};
    std::vector<mesher::SizedTriangle> lower;
    for (const mesher::SizedTriangle& q : mesher::thin_wall_sizes(surface, h, kDeflection * h))
      if (q.a.z == 0 && q.b.z == 0 && q.c.z == 0) lower.push_back(q);
    return lower;
  };
  double covered = 0;
  for (const mesher::SizedTriangle& q : patches_under(0.3, 0)) {
    EXPECT_NEAR(q.size, 0.9, 1e-9);
    covered += area(q);
  }
  EXPECT_NEAR(covered, 60 * 30 / 2, 1e-6);
  std::size_t under = 0, over = 0;
  for (const mesher::SizedTriangle& q : patches_under(0.06, 1.5)) {
    const Vec3 centre = (q.a + q.b + q.c) * (1.0 / 3);
    const double t = q.size / 3;
    EXPECT_NEAR(t, 0.06 + centre.x * std::tan(1.5 * M_PI / 180), 1e-9);
    EXPECT_GE(t, 0.02 * h);
    if (t < h / 12) {
      EXPECT_GT(centre.x, 10) << "a patch " << t << " thick within 2 h of the gap under 0.12";
      ++under;
    } else {
      ++over;
    }
  }
  EXPECT_GT(over, 0);
  EXPECT_GT(under, 0);  // 2 h on, the wall is sized under h / 12 too
  // Rising by 4 degrees from 0.13 (nowhere under 0.02 h), the wall's thickness more than doubles
  // across a patch (up to h along x) where it is under h / 12 (x under 5.3): none sized there.
  ASSERT_EQ(mesher::kEvenWallRatio, 1.5);
  std::size_t steep = 0;
  for (const mesher::SizedTriangle& q : patches_under(0.13, 4)) {
    EXPECT_GE(q.size / 3, h / 12);
    ++steep;
  }
  EXPECT_GT(steep, 0);
}

}  // namespace
}  // namespace hexmerge::test
