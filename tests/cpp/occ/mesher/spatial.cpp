#include "hexmerge/occ/mesher/spatial.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace hexmerge::test {
namespace {

TEST(PointSet, any_within_agrees_with_brute_force) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> u(-1, 11);  // some outside the grid's box
  mesher::PointSet set(Vec3{0, 0, 0}, Vec3{10, 10, 10}, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 300; ++i) {
    points.push_back({u(random), u(random), u(random)});
    set.add(points.back());
  }
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 q{u(random), u(random), u(random)};
    const double r = 0.2 + 0.8 * (i % 5) / 4.0;
    const bool expected = std::any_of(points.begin(), points.end(),
                                      [&](const Vec3& p) { return (p - q).norm() < r; });
    EXPECT_EQ(set.any_within(q, r), expected);
    hits += expected;
  }
  EXPECT_GT(hits, 200);
  EXPECT_LT(hits, 1800);
}

TEST(TriangleSet, any_within_agrees_with_brute_force) {
  std::mt19937 random(9);
  std::uniform_real_distribution<double> u(0, 10), d(-1, 1);
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 3>> triangles;
  for (int i = 0; i < 100; ++i) {
    const Vec3 centre{u(random), u(random), u(random)};
    const int first = static_cast<int>(nodes.size());
    for (int k = 0; k < 3; ++k) nodes.push_back(centre + Vec3{d(random), d(random), d(random)});
    triangles.push_back({first, first + 1, first + 2});
  }
  mesher::TriangleSet set(nodes, Vec3{0, 0, 0}, Vec3{10, 10, 10}, 1.5);
  for (const auto& t : triangles) set.add(t);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 q{u(random), u(random), u(random)};
    const double r = 0.3 + 0.2 * (i % 4);
    const bool expected = std::any_of(triangles.begin(), triangles.end(), [&](const auto& t) {
      return squared_distance_to_triangle(q, nodes[t[0]], nodes[t[1]], nodes[t[2]]) < r * r;
    });
    EXPECT_EQ(set.any_within(q, r), expected);
    hits += expected;
  }
  EXPECT_GT(hits, 100);
}

}  // namespace
}  // namespace hexmerge::test
