#include "hexmerge/occ/mesher/spatial.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
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

// The buckets a box overlaps, as BucketGrid files it (points outside go to the nearest bucket).
std::array<std::array<int, 2>, 3> bucket_range(const Vec3& a, const Vec3& b, const Vec3& lo,
                                               double cell, int n) {
  const double from[3] = {a.x, a.y, a.z}, to[3] = {b.x, b.y, b.z}, origin[3] = {lo.x, lo.y, lo.z};
  std::array<std::array<int, 2>, 3> range{};
  for (int k = 0; k < 3; ++k)
    for (int end = 0; end < 2; ++end)
      range[k][end] = std::clamp(
          static_cast<int>(std::floor(((end == 0 ? from : to)[k] - origin[k]) / cell)), 0, n - 1);
  return range;
}

// Every item filed under a bucket the query box overlaps comes, once per such bucket, and the
// items of one bucket come in the order they were added (the mesher's outputs depend on it);
// items in no such bucket never come. Most of the grid's buckets stay empty.
TEST(BucketGrid, any_in_visits_the_items_of_the_overlapping_buckets_in_order) {
  std::mt19937 random(13);
  std::uniform_real_distribution<double> u(-1, 21), size(0, 2.5);
  const Vec3 lo{0, 0, 0};
  const double cell = 1.0;
  const int n = 21;  // buckets per axis over [0, 20]: ceil(20 / 1) + 1
  mesher::BucketGrid grid(lo, Vec3{20, 20, 20}, cell);
  std::vector<std::array<Vec3, 2>> boxes;
  for (int i = 0; i < 200; ++i) {
    const Vec3 a{u(random), u(random), u(random)};
    boxes.push_back({a, a + Vec3{size(random), size(random), size(random)}});
    grid.add(i, boxes.back()[0], boxes.back()[1]);
  }
  const auto overlap = [](const auto& r, const auto& s) {
    for (int k = 0; k < 3; ++k)
      if (r[k][1] < s[k][0] || s[k][1] < r[k][0]) return 0;
    int shared = 1;
    for (int k = 0; k < 3; ++k)
      shared *= std::min(r[k][1], s[k][1]) - std::max(r[k][0], s[k][0]) + 1;
    return shared;
  };
  int visited_in_all = 0;
  for (int q = 0; q < 500; ++q) {
    const Vec3 a{u(random), u(random), u(random)};
    const Vec3 b = a + Vec3{size(random), size(random), size(random)};
    const auto query = bucket_range(a, b, lo, cell, n);
    std::vector<int> visited;
    EXPECT_FALSE(grid.any_in(a, b, [&](int item) {
      visited.push_back(item);
      return false;
    }));
    for (int i = 0; i < static_cast<int>(boxes.size()); ++i) {
      const int expected = overlap(query, bucket_range(boxes[i][0], boxes[i][1], lo, cell, n));
      EXPECT_EQ(std::count(visited.begin(), visited.end(), i), expected) << "item " << i;
    }
    visited_in_all += static_cast<int>(visited.size());
    // Within one bucket, the order added: a query of one bucket sees increasing items.
    const Vec3 centre = (a + b) * 0.5;
    std::vector<int> one;
    grid.any_in(centre, centre, [&](int item) {
      one.push_back(item);
      return false;
    });
    EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
    // any_in stops at the first item f takes.
    if (!visited.empty()) {
      int seen = 0;
      EXPECT_TRUE(grid.any_in(a, b, [&](int) { return ++seen == 1; }));
      EXPECT_EQ(seen, 1);
    }
  }
  EXPECT_GT(visited_in_all, 500);
}

}  // namespace
}  // namespace hexmerge::test
