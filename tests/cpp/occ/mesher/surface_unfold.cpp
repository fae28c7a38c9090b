#include "hexmerge/occ/mesher/surface_unfold.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "hexmerge/occ/mesher/surface_check.h"

namespace hexmerge::test {
namespace {

using mesher::Surface;
using mesher::SurfaceTriangle;

// A disk in z = 0 (radius 2) as a sphere's pole comes out of BRepMesh near the face's outline:
// centre 0, inner ring 1-6 (radius 1), outer ring 7-18 (radius 2, every 30 degrees). The centre's
// fan covers the turn from node 1 to node 3 only; triangle 0-3-1 closes it the wrong way round
// (turned over, folding on all three sides), and a fan from node 3 over nodes 4, 5, 6, 1 covers
// the rest, across the centre. The outer strip is sound. Every node is on a side of the fold's
// triangles or the strip's.
Surface folded_disk() {
  Surface s;
  s.nodes.push_back({0, 0, 0});
  for (int k = 0; k < 6; ++k)
    s.nodes.push_back({std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0});
  for (int k = 0; k < 12; ++k)
    s.nodes.push_back({2 * std::cos(k * M_PI / 6), 2 * std::sin(k * M_PI / 6), 0});
  s.node_face.assign(s.nodes.size(), 0);
  const auto add = [&](int a, int b, int c) {
    SurfaceTriangle t{{a, b, c}, {}, 0};
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = s.nodes[static_cast<std::size_t>(t.node[k])];
      t.uv[k] = {p.x, p.y};
    }
    s.triangles.push_back(t);
  };
  const auto inner = [](int k) { return 1 + (k % 6); };
  const auto outer = [](int k) { return 7 + (k % 12); };
  add(0, 1, 2), add(0, 2, 3), add(0, 3, 1);  // the centre's fan, closed the wrong way
  add(3, 4, 5), add(3, 5, 6), add(3, 6, 1);  // the rest, across the centre
  for (int k = 0; k < 6; ++k) {              // the strip: two outer sides per inner one
    add(inner(k), outer(2 * k), outer(2 * k + 1));
    add(inner(k), outer(2 * k + 1), inner(k + 1));
    add(inner(k + 1), outer(2 * k + 1), outer(2 * k + 2));
  }
  return s;
}

// Whether a sorted side is used by one triangle (the outline) or two.
std::map<std::pair<int, int>, int> side_uses(const Surface& s) {
  std::map<std::pair<int, int>, int> uses;
  for (const SurfaceTriangle& t : s.triangles)
    for (int c = 0; c < 3; ++c) ++uses[std::minmax(t.node[c], t.node[(c + 1) % 3])];
  return uses;
}

TEST(unfold_faces, a_fan_closed_the_wrong_way_round_a_pole) {
  Surface s = folded_disk();
  const std::vector<Vec3> nodes = s.nodes;
  // The fold as the surface check sees it: crossings within the face.
  ASSERT_FALSE(mesher::find_crossings(s.nodes, s.triangles).empty());
  std::set<std::pair<int, int>> outline_before;
  for (const auto& [side, uses] : side_uses(s))
    if (uses == 1) outline_before.insert(side);
  const mesher::UnfoldReport report = mesher::unfold_faces(s);
  EXPECT_EQ(report.patches, 1u);
  EXPECT_EQ(report.failed, 0u);
  // Nothing crosses; every triangle faces up; the disk covered once: the areas add up to the
  // polygon's (the outer ring's 12-gon); the same outline; every node kept, in place, and used.
  EXPECT_TRUE(mesher::find_crossings(s.nodes, s.triangles).empty());
  ASSERT_EQ(s.nodes.size(), nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) EXPECT_EQ((s.nodes[n] - nodes[n]).norm(), 0.0);
  double area = 0;
  std::set<int> used;
  for (const SurfaceTriangle& t : s.triangles) {
    const Vec3 n = mesher::normal_of(s.nodes, t.node[0], t.node[1], t.node[2]);
    EXPECT_GT(n.z, 0.0);
    area += 0.5 * n.z;
    used.insert(t.node.begin(), t.node.end());
    EXPECT_EQ(t.face, 0);
  }
  EXPECT_NEAR(area, 12 * 0.5 * 4 * std::sin(M_PI / 6), 1e-12);
  EXPECT_EQ(used.size(), s.nodes.size());
  std::set<std::pair<int, int>> outline_after;
  for (const auto& [side, uses] : side_uses(s)) {
    EXPECT_LE(uses, 2);
    if (uses == 1) outline_after.insert(side);
  }
  EXPECT_EQ(outline_after, outline_before);
}

// A CAD edge's segments inside the patch (a sphere's seam from its pole: the centre to node 3,
// then out to node 11) stay sides; a sound surface is left as it is.
TEST(unfold_faces, keeps_a_seam_and_leaves_a_sound_surface) {
  Surface s = folded_disk();
  s.segments[mesher::pair_key(0, 3)] = {5, 0.0, 1.0};
  s.segments[mesher::pair_key(3, 11)] = {5, 1.0, 2.0};
  const mesher::UnfoldReport report = mesher::unfold_faces(s);
  EXPECT_EQ(report.patches, 1u);
  EXPECT_TRUE(mesher::find_crossings(s.nodes, s.triangles).empty());
  const auto uses = side_uses(s);
  ASSERT_TRUE(uses.count({0, 3}));
  EXPECT_EQ(uses.at({0, 3}), 2);
  EXPECT_EQ(uses.at({3, 11}), 2);
  for (const SurfaceTriangle& t : s.triangles)
    EXPECT_GT(mesher::normal_of(s.nodes, t.node[0], t.node[1], t.node[2]).z, 0.0);
  const std::vector<SurfaceTriangle> sound = s.triangles;
  EXPECT_EQ(mesher::unfold_faces(s).patches, 0u);
  ASSERT_EQ(s.triangles.size(), sound.size());
  for (std::size_t i = 0; i < sound.size(); ++i) EXPECT_EQ(s.triangles[i].node, sound[i].node);
}

}  // namespace
}  // namespace hexmerge::test
