#include "hexmerge/tetgen/triangulate_facets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace hexmerge::test {
namespace {

using tetgen::Facet;
using tetgen::triangulate_facets;

// A lattice face as the mesher hands it over: the square [0, 8 s]^2 on the plane z = 1.25
// (shifted by `origin`), its loop with a node every lattice step s (the nodes TetGen 1.5's own
// flips never ended on), an inner loop around the cell square [3 s, 5 s]^2 with its hole point,
// and every other lattice point inside as a single point.
struct LatticeFace {
  std::vector<Vec3> points;
  Facet facet{{}, {}, 7};
  double s = 0.5741599105922173;
  Vec3 origin{3.2171, -7.113, 1.25};

  int add(int i, int j) {
    points.push_back(origin + Vec3{i * s, j * s, 0});
    return static_cast<int>(points.size()) - 1;
  }
  std::vector<int> loop(int low, int high) {  // the square [low, high]^2, counterclockwise
    std::vector<int> out;
    for (int i = low; i < high; ++i) out.push_back(add(i, low));
    for (int j = low; j < high; ++j) out.push_back(add(high, j));
    for (int i = high; i > low; --i) out.push_back(add(i, high));
    for (int j = high; j > low; --j) out.push_back(add(low, j));
    return out;
  }
  LatticeFace() {
    facet.polygons.push_back(loop(0, 8));
    facet.polygons.push_back(loop(3, 5));
    facet.holes.push_back(origin + Vec3{4 * s, 4 * s, 0});
    for (int i = 1; i < 8; ++i)
      for (int j = 1; j < 8; ++j)
        if (i < 3 || i > 5 || j < 3 || j > 5) facet.polygons.push_back({add(i, j)});
  }
};

double area(const std::vector<Vec3>& p, const std::vector<int>& t) {
  return (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).norm() / 2;
}

TEST(TriangulateFacets, ALatticeFaceWithAHoleBecomesItsTriangles) {
  LatticeFace face;
  const std::vector<std::vector<int>> loops{face.facet.polygons[0], face.facet.polygons[1]};
  std::vector<Facet> facets{face.facet};
  ASSERT_EQ(triangulate_facets(facets, face.points, nullptr), 1u);
  double total = 0;
  std::map<std::pair<int, int>, int> sides;  // each side: how many triangles have it
  std::vector<int> used(face.points.size(), 0);
  for (const Facet& f : facets) {
    EXPECT_EQ(f.marker, 7);
    EXPECT_TRUE(f.holes.empty());
    ASSERT_EQ(f.polygons.size(), 1u);
    const std::vector<int>& t = f.polygons[0];
    ASSERT_EQ(t.size(), 3u);
    EXPECT_GT(area(face.points, t), 1e-3 * face.s * face.s) << "a flat triangle";
    total += area(face.points, t);
    const Vec3 centroid = (face.points[t[0]] + face.points[t[1]] + face.points[t[2]]) * (1.0 / 3);
    const double u = (centroid.x - face.origin.x) / face.s,
                 v = (centroid.y - face.origin.y) / face.s;
    EXPECT_FALSE(u > 3 && u < 5 && v > 3 && v < 5) << "a triangle in the hole";
    for (int k = 0; k < 3; ++k) {
      ++used[t[k]];
      ++sides[std::minmax(t[k], t[(k + 1) % 3])];
    }
  }
  EXPECT_NEAR(total, (64 - 4) * face.s * face.s, 1e-9);
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "a point in no triangle";
  for (const std::vector<int>& loop : loops)  // the loops' sides kept, on the face's side only
    for (std::size_t k = 0; k < loop.size(); ++k)
      EXPECT_EQ(sides[std::minmax(loop[k], loop[(k + 1) % loop.size()])], 1);
  // Inside, every side between two triangles: a triangulation with no crack.
  std::size_t boundary = 0;
  for (const auto& [side, count] : sides) {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_EQ(boundary, loops[0].size() + loops[1].size());
}

TEST(TriangulateFacets, CocircularPointsAreJoinedAsTheDelaunayTetsJoinThem) {
  // A square of side s (its corners cocircular) with a node in the middle of each side.
  const double s = 0.5741599105922173;
  const std::vector<Vec3> points{{0, 0, 2},     {s, 0, 2},         {2 * s, 0, 2},
                                 {2 * s, s, 2}, {2 * s, 2 * s, 2}, {s, 2 * s, 2},
                                 {0, 2 * s, 2}, {0, s, 2},         {s, s, 2}};  // and its centre
  for (const auto& [a, b] : {std::pair{0, 8}, std::pair{1, 7}}) {  // either diagonal of a cell
    std::vector<Facet> facets{Facet{{{0, 1, 2, 3, 4, 5, 6, 7}, {8}}, {}, 1}};
    const std::unordered_set<std::uint64_t> delaunay{tetgen::side_key(a, b)};
    ASSERT_EQ(triangulate_facets(facets, points, &delaunay), 1u);
    EXPECT_EQ(facets.size(), 8u);
    int with_side = 0;
    for (const Facet& f : facets) {
      const std::vector<int>& t = f.polygons[0];
      with_side += std::count(t.begin(), t.end(), a) && std::count(t.begin(), t.end(), b);
    }
    EXPECT_EQ(with_side, 2) << "the diagonal " << a << "-" << b;
  }
}

TEST(TriangulateFacets, TrianglesAndSinglePolygonsStayAsTheyAre) {
  const std::vector<Vec3> points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  std::vector<Facet> facets{Facet{{{0, 1, 2}}, {}, 1}, Facet{{{1, 3, 2}}, {}, 2}};
  EXPECT_EQ(triangulate_facets(facets, points, nullptr), 0u);
  ASSERT_EQ(facets.size(), 2u);
  EXPECT_EQ(facets[1].polygons[0], (std::vector<int>{1, 3, 2}));
}

TEST(TriangulateFacets, AFacetItCannotTakeIsLeftToTetGen) {
  const std::vector<Vec3> points{{0, 0, 0}, {1, 1, 0}, {1, 0, 0},   {0, 1, 0},  // a bow tie
                                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1.5}, {0, 1, 1},  // not planar
                                 {0, 0, 2}, {1, 0, 2}, {1, 1, 2},   {0, 1, 2}, {1, 1, 2}};
  std::vector<Facet> facets{Facet{{{0, 1, 2, 3}}, {}, 1}, Facet{{{4, 5, 6, 7}}, {}, 2},
                            Facet{{{8, 9, 10, 11}, {12}}, {}, 3}};  // 12 on 10's place
  const std::vector<Facet> before = facets;
  EXPECT_EQ(triangulate_facets(facets, points, nullptr), 0u);
  ASSERT_EQ(facets.size(), before.size());
  for (std::size_t f = 0; f < facets.size(); ++f) {
    EXPECT_EQ(facets[f].polygons, before[f].polygons) << "facet " << f;
    EXPECT_EQ(facets[f].marker, before[f].marker);
  }
}

// A 10 x 4 facet on z = 2 whose bottom side has a node every 0.25 and whose top side has its
// corners only: its triangulation fans from the top corners to the bottom's nodes (angles of a
// few degrees). refine_facet() adds points inside it, never where `accept` refuses (a disc
// around (8, 2)), and the triangulation with them has a larger smallest angle and fewer
// triangles under 20 degrees.
TEST(RefineFacet, PointsInsideRaiseTheSmallestAngle) {
  std::vector<Vec3> points;
  Facet facet{{{}}, {}, 4};
  for (int i = 0; i <= 40; ++i) {
    points.push_back({0.25 * i, 0, 2});
    facet.polygons[0].push_back(static_cast<int>(points.size()) - 1);
  }
  for (const Vec3& corner : {Vec3{10, 4, 2}, Vec3{0, 4, 2}}) {
    points.push_back(corner);
    facet.polygons[0].push_back(static_cast<int>(points.size()) - 1);
  }
  const auto smallest_angles = [](const std::vector<Vec3>& p, const std::vector<Facet>& facets,
                                  int& under_20) {
    double least = 180;
    under_20 = 0;
    for (const Facet& f : facets) {
      const std::vector<int>& t = f.polygons[0];
      double tri = 180;
      for (int k = 0; k < 3; ++k) {
        const Vec3 u = p[t[(k + 1) % 3]] - p[t[k]], w = p[t[(k + 2) % 3]] - p[t[k]];
        tri = std::min(tri, std::acos(u.dot(w) / (u.norm() * w.norm())) * 180 / M_PI);
      }
      least = std::min(least, tri);
      under_20 += tri < 20;
    }
    return least;
  };
  std::vector<Facet> before{facet};
  ASSERT_EQ(triangulate_facets(before, points, nullptr), 1u);
  int skinny_before = 0;
  const double least_before = smallest_angles(points, before, skinny_before);
  ASSERT_LT(least_before, 10);

  const Vec3 refused{8, 2, 2};
  const std::vector<Vec3> added = tetgen::refine_facet(
      facet, points, 20 * M_PI / 180, [](const Vec3&) { return 2.0; },
      [&](const Vec3& q) { return (q - refused).norm() > 1; }, 1000);
  ASSERT_FALSE(added.empty());
  Facet refined = facet;
  std::vector<Vec3> all = points;
  for (const Vec3& q : added) {
    EXPECT_GT(q.x, 0);
    EXPECT_LT(q.x, 10);
    EXPECT_GT(q.y, 0);
    EXPECT_LT(q.y, 4);
    EXPECT_EQ(q.z, 2.0);
    EXPECT_GT((q - refused).norm(), 1);
    refined.polygons.push_back({static_cast<int>(all.size())});
    all.push_back(q);
  }
  std::vector<Facet> after{refined};
  ASSERT_EQ(triangulate_facets(after, all, nullptr), 1u);
  int skinny_after = 0;
  const double least_after = smallest_angles(all, after, skinny_after);
  EXPECT_GT(least_after, least_before);
  EXPECT_LT(skinny_after, skinny_before);
  // Nothing more than asked for.
  EXPECT_LE(tetgen::refine_facet(
                facet, points, 20 * M_PI / 180, [](const Vec3&) { return 2.0; },
                [](const Vec3&) { return true; }, 3)
                .size(),
            3u);
}

}  // namespace
}  // namespace hexmerge::test
