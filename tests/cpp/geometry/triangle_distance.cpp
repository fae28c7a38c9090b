// squared_distance_to_triangle: the nearest point's region of the plane, against brute force.
#include "hexmerge/geometry/triangle_distance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace hexmerge {
namespace {

// Squared distance from p to triangle abc by brute force: the plane's foot when inside, else
// the nearest point of the three sides, each sampled finely and then refined.
double brute_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  double best = 1e300;
  auto side = [&](const Vec3& u, const Vec3& v) {
    const Vec3 d = v - u;
    const double t = std::clamp((p - u).dot(d) / d.dot(d), 0.0, 1.0);
    const Vec3 q = u + d * t - p;
    best = std::min(best, q.dot(q));
  };
  side(a, b), side(b, c), side(c, a);
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 foot = p - n * ((p - a).dot(n) / n.dot(n));
  // foot inside abc: same side of every edge.
  const double s0 = (b - a).cross(foot - a).dot(n), s1 = (c - b).cross(foot - b).dot(n),
               s2 = (a - c).cross(foot - c).dot(n);
  if (s0 >= 0 && s1 >= 0 && s2 >= 0) best = std::min(best, (foot - p).dot(foot - p));
  return best;
}

TEST(squared_distance_to_triangle, regions_of_the_plane) {
  const Vec3 a{0, 0, 0}, b{4, 0, 0}, c{0, 4, 0};
  EXPECT_DOUBLE_EQ(squared_distance_to_triangle({1, 1, 3}, a, b, c), 9);    // above the face
  EXPECT_DOUBLE_EQ(squared_distance_to_triangle({-1, -2, 0}, a, b, c), 5);  // beyond vertex a
  EXPECT_DOUBLE_EQ(squared_distance_to_triangle({2, -3, 4}, a, b, c), 25);  // beyond side ab
  EXPECT_DOUBLE_EQ(squared_distance_to_triangle({3, 3, 0}, a, b, c), 2);    // beyond side bc
  EXPECT_DOUBLE_EQ(squared_distance_to_triangle({0, 4, 0}, a, b, c), 0);    // on vertex c
}

TEST(squared_distance_to_triangle, agrees_with_brute_force) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 a{u(random), u(random), u(random)}, b{u(random), u(random), u(random)},
        c{u(random), u(random), u(random)}, p{u(random), u(random), u(random)};
    const double expected = brute_distance2(p, a, b, c);
    EXPECT_NEAR(squared_distance_to_triangle(p, a, b, c), expected, 1e-9 * (1 + expected));
  }
}

}  // namespace
}  // namespace hexmerge
