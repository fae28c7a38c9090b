// FlipMesh: 2-3, 3-2 and 4-4 flips and contractions keep the union of the tets they replace, and
// undo restores.
#include "hexmerge/recombine/postmerge/flip_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "fixtures.h"
#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/geometry/quality.h"

namespace hexmerge {
namespace {

using test::add_tet;
using test::Point;

using Triangle = std::array<index_t, 3>;

std::vector<index_t> alive_tets(const FlipMesh& m) {
  std::vector<index_t> out;
  for (index_t t = 0; t < m.nb_slots(); ++t) {
    if (m.alive(t)) out.push_back(t);
  }
  return out;
}

// The triangles that bound the union of the alive tets (faces held by one tet), sorted.
std::vector<Triangle> boundary_triangles(const FlipMesh& m) {
  std::map<Triangle, int> count;
  for (index_t t : alive_tets(m)) {
    for (int f = 0; f < 4; ++f) {
      Triangle tri{};
      int n = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != f) tri[n++] = m.tet(t)[i];
      }
      std::sort(tri.begin(), tri.end());
      ++count[tri];
    }
  }
  std::vector<Triangle> out;
  for (const auto& [tri, n] : count) {
    EXPECT_LE(n, 2) << "a face held by three tets";
    if (n == 1) out.push_back(tri);
  }
  return out;
}

double volume(const FlipMesh& m, bool& all_positive) {
  double sum = 0.0;
  all_positive = true;
  for (index_t t : alive_tets(m)) {
    const index_t* q = m.tet(t);
    const double v = tet_volume(m.point(q[0]), m.point(q[1]), m.point(q[2]), m.point(q[3]));
    all_positive = all_positive && v > 0.0;
    sum += v;
  }
  return sum;
}

// Checks that the alive tets tile the same union as before: same boundary triangles, same volume,
// every tet positive.
void expect_same_union(const FlipMesh& m, const std::vector<Triangle>& boundary, double vol) {
  bool positive = false;
  EXPECT_NEAR(volume(m, positive), vol, 1e-12 * vol);
  EXPECT_TRUE(positive);
  EXPECT_EQ(boundary_triangles(m), boundary);
}

// Two tets on triangle (0, 1, 2) with apexes 3 above and 4 below: a convex bipyramid whose axis
// 3-4 crosses the triangle.
TetMesh bipyramid(const Point& below) {
  TetMesh mesh;
  const std::vector<Point> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3, 0.3, 1}, below};
  for (const Point& p : points) mesh.points.insert(mesh.points.end(), p.begin(), p.end());
  add_tet(mesh, 0, 1, 2, 3);
  add_tet(mesh, 0, 1, 2, 4);
  return mesh;
}

// Four tets around the axis 4-5 of an octahedron on the square 0-1-2-3.
TetMesh octahedron() {
  TetMesh mesh;
  const std::vector<Point> points = {{1, 0, 0},  {0, 1, 0}, {-1, 0, 0},
                                     {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Point& p : points) mesh.points.insert(mesh.points.end(), p.begin(), p.end());
  for (index_t i = 0; i < 4; ++i) add_tet(mesh, 4, 5, i, (i + 1) % 4);
  return mesh;
}

TEST(flip_mesh, a_2_3_flip_keeps_the_union_and_its_3_2_flip_gives_back_the_two_tets) {
  const TetMesh mesh = bipyramid({0.3, 0.3, -1});
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  bool positive = false;
  const double vol = volume(m, positive);
  ASSERT_TRUE(positive);
  ASSERT_TRUE(m.flip_23(0, 1, 0.0));
  EXPECT_EQ(alive_tets(m).size(), 3u);
  EXPECT_EQ(m.counts().flips_23, 1u);
  expect_same_union(m, boundary, vol);
  std::vector<index_t> around;
  m.tets_with_edge(3, 4, around);
  EXPECT_EQ(around.size(), 3u);  // the new edge joins the two apexes
  // The 3-2 flip of that edge: two tets on triangle (0, 1, 2) again.
  ASSERT_TRUE(m.remove_edge(3, 4, 0, 0.0));
  EXPECT_EQ(alive_tets(m).size(), 2u);
  EXPECT_EQ(m.counts().flips_32, 1u);
  expect_same_union(m, boundary, vol);
  EXPECT_NE(m.tet_with_face(0, 1, 2, NO_CELL), NO_CELL);
}

TEST(flip_mesh, a_2_3_flip_whose_new_edge_misses_the_face_changes_nothing) {
  // The lower apex is far to the side: the segment between the apexes passes outside triangle
  // (0, 1, 2), so the three new tets would not tile the union.
  const TetMesh mesh = bipyramid({2.0, 2.0, -0.2});
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  EXPECT_FALSE(m.flip_23(0, 1, 0.0));
  EXPECT_EQ(alive_tets(m), (std::vector<index_t>{0, 1}));
  EXPECT_EQ(m.counts().flips_23, 0u);
  EXPECT_EQ(boundary_triangles(m), boundary);
}

TEST(flip_mesh, the_quality_floor_locks_and_regions_refuse_a_flip) {
  TetMesh mesh = bipyramid({0.3, 0.3, -1});
  {
    FlipMesh m(mesh);
    EXPECT_FALSE(m.flip_23(0, 1, 0.99));  // no tet of the three is near regular
    m.set_locked(1, true);
    EXPECT_FALSE(m.flip_23(0, 1, 0.0));
    EXPECT_EQ(alive_tets(m).size(), 2u);
  }
  mesh.regions = {1, 2};
  FlipMesh m(mesh);
  EXPECT_FALSE(m.flip_23(0, 1, 0.0));
}

TEST(flip_mesh, a_4_4_flip_turns_the_octahedron_axis_into_either_diagonal) {
  const TetMesh mesh = octahedron();
  std::vector<int> made;  // per diagonal choice: 0 for the new edge 0-2, 1 for 1-3
  for (int diagonal = 0; diagonal < 2; ++diagonal) {
    FlipMesh m(mesh);
    const auto boundary = boundary_triangles(m);
    bool positive = false;
    const double vol = volume(m, positive);
    ASSERT_TRUE(m.remove_edge(4, 5, diagonal, 0.0));
    EXPECT_EQ(m.counts().flips_44, 1u);
    expect_same_union(m, boundary, vol);
    std::vector<index_t> around, across;
    m.tets_with_edge(4, 5, around);
    EXPECT_TRUE(around.empty());
    // The new edge joins opposite square corners: 0-2 or 1-3, held by all four tets.
    m.tets_with_edge(0, 2, around);
    m.tets_with_edge(1, 3, across);
    EXPECT_EQ(around.size() + across.size(), 4u);
    EXPECT_TRUE(around.size() == 4u || across.size() == 4u);
    made.push_back(around.size() == 4u ? 0 : 1);
  }
  EXPECT_NE(made[0], made[1]);  // the two choices give the two diagonals
}

TEST(flip_mesh, a_boundary_edge_is_not_removed) {
  // Three of the octahedron's four tets: the ring around 4-5 is open.
  TetMesh mesh = octahedron();
  mesh.tets.resize(12);
  FlipMesh m(mesh);
  EXPECT_FALSE(m.remove_edge(4, 5, 0, 0.0));
  EXPECT_EQ(alive_tets(m).size(), 3u);
}

TEST(flip_mesh, undo_restores_the_tets_and_the_counts_after_several_flips) {
  const TetMesh mesh = octahedron();
  FlipMesh m(mesh);
  const std::size_t start = m.mark();
  ASSERT_TRUE(m.remove_edge(4, 5, 0, 0.0));
  std::vector<index_t> around;
  m.tets_with_edge(0, 2, around);
  const index_t u = around.size() == 4u ? 0 : 1;
  m.tets_with_edge(u, u + 2, around);
  ASSERT_EQ(around.size(), 4u);
  ASSERT_TRUE(m.remove_edge(u, u + 2, 0, 0.0) || m.remove_edge(u, u + 2, 1, 0.0));
  EXPECT_EQ(m.counts().flips_44, 2u);
  m.undo(start);
  EXPECT_EQ(m.counts().flips_44, 0u);
  const TetMesh back = m.compact();
  EXPECT_EQ(back.tets, mesh.tets);
  m.tets_with_edge(4, 5, around);
  EXPECT_EQ(around.size(), 4u);
}

// The unit cube's corners (nodes 0-7) and two inner nodes 8 and 9 near its centre, Delaunay
// tetrahedralised: the nearest pair of points, 8-9 is an edge.
TetMesh cube_with_two_inner_nodes() {
  std::vector<Point> points;
  for (int b = 0; b < 8; ++b) points.push_back({double(b & 1), double(b >> 1 & 1), double(b >> 2)});
  points.push_back({0.45, 0.5, 0.52});
  points.push_back({0.6, 0.53, 0.47});
  return test::tetgen_mesh(points);
}

bool uses(const FlipMesh& m, index_t v) {
  for (index_t t : alive_tets(m)) {
    if (std::count(m.tet(t), m.tet(t) + 4, v)) return true;
  }
  return false;
}

TEST(flip_mesh, a_contraction_takes_an_inner_node_out_and_keeps_the_union) {
  const TetMesh mesh = cube_with_two_inner_nodes();
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "no tetgen";
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  bool positive = false;
  const double vol = volume(m, positive);
  ASSERT_TRUE(positive);
  std::vector<index_t> joined;
  m.tets_with_edge(8, 9, joined);
  ASSERT_FALSE(joined.empty());
  const std::size_t before = alive_tets(m).size();
  const std::size_t start = m.mark();
  ASSERT_TRUE(m.contract(9, 8, 0.0));
  EXPECT_EQ(m.counts().contractions, 1u);
  EXPECT_FALSE(uses(m, 9));
  EXPECT_TRUE(uses(m, 8));
  EXPECT_EQ(alive_tets(m).size(), before - joined.size());  // the tets around 8-9 are gone
  expect_same_union(m, boundary, vol);
  // The compact mesh keeps every point (node 9 unused) and passes the tet mesh checks.
  const TetMesh out = m.compact();
  EXPECT_EQ(out.points, mesh.points);
  EXPECT_NO_THROW(validate_tet_mesh(out));
  m.undo(start);
  EXPECT_EQ(m.counts().contractions, 0u);
  EXPECT_EQ(m.compact().tets, mesh.tets);
}

TEST(flip_mesh, a_contraction_refuses_boundary_nodes_locks_regions_and_the_floor) {
  const TetMesh mesh = cube_with_two_inner_nodes();
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "no tetgen";
  {
    FlipMesh m(mesh);
    // A corner is on the boundary: never contracted, whatever its neighbour.
    std::vector<index_t> star;
    m.tets_with_edge(0, 0, star);
    for (int i = 0; i < 4; ++i) {
      const index_t other = m.tet(star[0])[i];
      if (other != 0) {
        EXPECT_FALSE(m.contract(0, other, 0.0));
      }
    }
    EXPECT_FALSE(m.contract(9, 9, 0.0));   // no edge
    EXPECT_FALSE(m.contract(9, 8, 0.99));  // no cone tet is near regular
    m.tets_with_edge(9, 9, star);
    m.set_locked(star.back(), true);
    EXPECT_FALSE(m.contract(9, 8, 0.0));
    EXPECT_EQ(m.counts().contractions, 0u);
    EXPECT_EQ(m.compact().tets, mesh.tets);
  }
  // One of node 9's tets in another region: an interface node stays.
  TetMesh two = mesh;
  two.regions.assign(two.nb_tets(), 1);
  for (index_t t = 0; t < two.nb_tets(); ++t) {
    if (std::count(two.tet(t), two.tet(t) + 4, 9)) {
      two.regions[t] = 2;
      break;
    }
  }
  FlipMesh m(two);
  EXPECT_FALSE(m.contract(9, 8, 0.0));
  two.regions.assign(two.nb_tets(), 1);
  FlipMesh same(two);
  EXPECT_TRUE(same.contract(9, 8, 0.0));
}

TEST(flip_mesh, a_contraction_on_a_flat_face_keeps_the_face) {
  // Nodes 8 and 9 inside the cube's face z = 0, node 10 inside the cube.
  std::vector<Point> points;
  for (int b = 0; b < 8; ++b) points.push_back({double(b & 1), double(b >> 1 & 1), double(b >> 2)});
  points.push_back({0.55, 0.5, 0.0});
  points.push_back({0.35, 0.45, 0.0});
  points.push_back({0.5, 0.5, 0.6});
  const TetMesh mesh = test::tetgen_mesh(points);
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "no tetgen";
  FlipMesh m(mesh);
  bool positive = false;
  const double vol = volume(m, positive);
  std::vector<index_t> joined;
  m.tets_with_edge(9, 10, joined);
  // Onto a node off the face: the face would not be kept.
  if (!joined.empty()) {
    EXPECT_FALSE(m.contract(9, 10, 0.0));
  }
  m.tets_with_edge(8, 9, joined);
  ASSERT_FALSE(joined.empty());
  ASSERT_TRUE(m.contract(9, 8, 0.0));
  EXPECT_FALSE(uses(m, 9));
  bool still_positive = false;
  EXPECT_NEAR(volume(m, still_positive), vol, 1e-12 * vol);
  EXPECT_TRUE(still_positive);
  // The boundary: the cube's faces, z = 0 now without node 9; every boundary triangle on a face
  // of the cube, and the ones on z = 0 cover it (area 1).
  double bottom_area = 0.0;
  for (const Triangle& tri : boundary_triangles(m)) {
    std::array<Point, 3> p{};
    for (int i = 0; i < 3; ++i) p[i] = {m.point(tri[i])[0], m.point(tri[i])[1], m.point(tri[i])[2]};
    bool on_a_face = false;
    for (int axis = 0; axis < 3; ++axis) {
      for (double side : {0.0, 1.0}) {
        on_a_face = on_a_face || (p[0][axis] == side && p[1][axis] == side && p[2][axis] == side);
      }
    }
    EXPECT_TRUE(on_a_face);
    if (p[0][2] == 0.0 && p[1][2] == 0.0 && p[2][2] == 0.0) {
      bottom_area += 0.5 * std::fabs((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) -
                                     (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]));
    }
  }
  EXPECT_NEAR(bottom_area, 1.0, 1e-12);
}

// A 2 x 2 x 2 Kuhn grid with its one inner node pushed off its place.
TetMesh displaced_grid(const Point& offset) {
  TetMesh mesh = test::kuhn_grid(2);
  const index_t v = test::grid_node(2, 1, 1, 1);
  for (int k = 0; k < 3; ++k) mesh.points[3 * v + k] += offset[k];
  return mesh;
}

double worst_at(const FlipMesh& m, index_t v) {
  double worst = 1.0;
  for (index_t t : alive_tets(m)) {
    const index_t* q = m.tet(t);
    if (std::count(q, q + 4, v) == 0) continue;
    const std::array<index_t, 4> tet{{q[0], q[1], q[2], q[3]}};
    worst = std::min(worst, scaled_jacobian(CellType::Tet, m.point(0), tet.data()));
  }
  return worst;
}

TEST(flip_mesh, a_move_meets_its_goal_keeps_the_union_and_undo_puts_the_node_back) {
  const TetMesh mesh = displaced_grid({0.3, 0.2, 0.25});
  const index_t v = test::grid_node(2, 1, 1, 1);
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  bool positive = false;
  const double vol = volume(m, positive);
  ASSERT_TRUE(positive);
  const double before = worst_at(m, v);
  // Goal: the worst tet at the node at least 0.1 better than now.
  const std::vector<FlipMesh::Goal> goals = {{[&]() { return worst_at(m, v); }, before + 0.1}};
  const std::size_t start = m.mark();
  ASSERT_TRUE(m.movable(v));
  ASSERT_TRUE(m.smooth(v, goals, {}, 0.3));
  EXPECT_EQ(m.counts().moves, 1u);
  EXPECT_GE(worst_at(m, v), before + 0.1);
  EXPECT_NE(m.compact().points, mesh.points);  // the node moved
  expect_same_union(m, boundary, vol);         // same tets, same surface, same volume
  m.undo(start);
  EXPECT_EQ(m.counts().moves, 0u);
  EXPECT_EQ(m.compact().points, mesh.points);
}

TEST(flip_mesh, a_move_refuses_boundary_nodes_locked_tets_and_goals_out_of_reach) {
  const TetMesh mesh = displaced_grid({0.3, 0.2, 0.25});
  const index_t v = test::grid_node(2, 1, 1, 1);
  FlipMesh m(mesh);
  const std::vector<FlipMesh::Goal> unreachable = {{[&]() { return worst_at(m, v); }, 2.0}};
  EXPECT_FALSE(m.smooth(v, unreachable, {}, 0.3));
  EXPECT_EQ(m.compact().points, mesh.points);
  // A node on a face of the grid is not moved, whatever the goal.
  const index_t face_node = test::grid_node(2, 0, 1, 1);
  EXPECT_FALSE(m.movable(face_node));
  const std::vector<FlipMesh::Goal> lift = {
      {[&]() { return worst_at(m, face_node); }, worst_at(m, face_node) + 0.1}};
  EXPECT_FALSE(m.smooth(face_node, lift, {}, 0.0));
  // A locked tet at the node (a kept element's) keeps it where it is.
  for (index_t t : alive_tets(m)) {
    if (std::count(m.tet(t), m.tet(t) + 4, v) != 0) {
      m.set_locked(t, true);
      break;
    }
  }
  EXPECT_FALSE(m.movable(v));
  const std::vector<FlipMesh::Goal> better = {{[&]() { return worst_at(m, v); }, 0.5}};
  EXPECT_FALSE(m.smooth(v, better, {}, 0.3));
  EXPECT_EQ(m.compact().points, mesh.points);
  EXPECT_EQ(m.counts().moves, 0u);
}

// A guard refuses every position: nothing moves.
TEST(flip_mesh, the_move_guard_rules_positions_out) {
  const TetMesh mesh = displaced_grid({0.3, 0.2, 0.25});
  const index_t v = test::grid_node(2, 1, 1, 1);
  FlipMesh m(mesh);
  int asked = 0;
  m.set_move_guard([&](index_t node, const std::vector<index_t>&) {
    EXPECT_EQ(node, v);
    ++asked;
    return false;
  });
  const std::vector<FlipMesh::Goal> goals = {{[&]() { return worst_at(m, v); }, 0.5}};
  EXPECT_FALSE(m.smooth(v, goals, {}, 0.3));
  EXPECT_GT(asked, 0);
  EXPECT_EQ(m.compact().points, mesh.points);
}

// With sliding on, a node inside a flat face of the grid moves in the face's plane: the
// boundary triangles and the volume are kept; a node on an edge of the grid never moves.
TEST(flip_mesh, a_node_inside_a_flat_face_slides_in_its_plane_and_an_edge_node_stays) {
  TetMesh mesh = test::kuhn_grid(2);
  const index_t face_node = test::grid_node(2, 0, 1, 1);  // on the face x = 0
  mesh.points[3 * face_node + 1] += 0.3;
  mesh.points[3 * face_node + 2] -= 0.25;
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  bool positive = false;
  const double vol = volume(m, positive);
  ASSERT_TRUE(positive);
  EXPECT_FALSE(m.movable(face_node));  // sliding off
  m.set_slide_on_faces(true);
  ASSERT_TRUE(m.movable(face_node));
  EXPECT_FALSE(m.movable(test::grid_node(2, 0, 0, 1)));  // on an edge of the grid
  EXPECT_FALSE(m.movable(test::grid_node(2, 0, 0, 0)));  // a corner
  const double before = worst_at(m, face_node);
  const std::vector<FlipMesh::Goal> goals = {
      {[&]() { return worst_at(m, face_node); }, before + 0.1}};
  ASSERT_TRUE(m.smooth(face_node, goals, {}, 0.3));
  EXPECT_GE(worst_at(m, face_node), before + 0.1);
  EXPECT_EQ(m.point(face_node)[0], 0.0);  // still on the face x = 0, exactly
  EXPECT_NE(m.compact().points, mesh.points);
  expect_same_union(m, boundary, vol);
}

// The octahedron on +-x, +-y, +-z (nodes 0 to 5) with node 6 at its centre: eight tets, one
// per octant; node 6 is inner.
TetMesh centred_octahedron() {
  TetMesh mesh;
  const std::vector<Point> points = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0},
                                     {0, 0, 1}, {0, 0, -1}, {0, 0, 0}};
  for (const Point& p : points) mesh.points.insert(mesh.points.end(), p.begin(), p.end());
  for (index_t x : {0, 1}) {
    for (index_t y : {2, 3}) {
      for (index_t z : {4, 5}) add_tet(mesh, 6, x, y, z);
    }
  }
  return mesh;
}

// The tets of node 6 on the +x side (holding node 0): they take the new node.
std::vector<index_t> plus_x_tets(const FlipMesh& m) {
  std::vector<index_t> out;
  for (index_t t : alive_tets(m)) {
    if (std::count(m.tet(t), m.tet(t) + 4, 6) && std::count(m.tet(t), m.tet(t) + 4, 0)) {
      out.push_back(t);
    }
  }
  return out;
}

TEST(flip_mesh, a_vertex_split_adds_a_node_and_a_ring_of_tets_and_keeps_the_union) {
  const TetMesh mesh = centred_octahedron();
  FlipMesh m(mesh);
  const auto boundary = boundary_triangles(m);
  bool positive = false;
  const double vol = volume(m, positive);
  ASSERT_TRUE(positive);
  const std::size_t start = m.mark();
  const index_t n = m.split(6, plus_x_tets(m), {-0.2, 0, 0}, {0.2, 0, 0}, 0.1);
  ASSERT_EQ(n, 7u);  // past the existing nodes
  EXPECT_EQ(m.nb_nodes(), 8u);
  EXPECT_EQ(m.counts().splits, 1u);
  // Eight tets, one at each node of the new edge per octant, and a ring of four around the
  // edge (one per face between the two sides: (6, +-y, +-z)).
  EXPECT_EQ(alive_tets(m).size(), 12u);
  std::vector<index_t> ring;
  m.tets_with_edge(6, 7, ring);
  EXPECT_EQ(ring.size(), 4u);
  expect_same_union(m, boundary, vol);
  for (index_t t : alive_tets(m)) {
    EXPECT_GE(scaled_jacobian(CellType::Tet, m.point(0), m.tet(t)), 0.1);
  }
  EXPECT_EQ(m.point(6)[0], -0.2);
  EXPECT_EQ(m.point(7)[0], 0.2);
  const TetMesh out = m.compact();
  EXPECT_EQ(out.nb_vertices(), 8u);
  EXPECT_NO_THROW(validate_tet_mesh(out));
  // A split node can be split again, and undo takes both back exactly.
  const std::vector<index_t> again = {ring[0]};
  EXPECT_NE(m.split(7, again, {0.2, 0, 0}, {0.15, 0.02, 0.01}, 0.0), NO_VERTEX);
  m.undo(start);
  EXPECT_EQ(m.counts().splits, 0u);
  EXPECT_EQ(m.nb_nodes(), 7u);
  EXPECT_EQ(m.compact().tets, mesh.tets);
  EXPECT_EQ(m.compact().points, mesh.points);
}

TEST(flip_mesh, a_vertex_split_refuses_boundary_nodes_locks_regions_the_floor_and_bad_sides) {
  const TetMesh mesh = centred_octahedron();
  const auto unchanged = [&mesh](const FlipMesh& m) {
    EXPECT_EQ(m.counts().splits, 0u);
    EXPECT_EQ(m.nb_nodes(), 7u);
    EXPECT_EQ(m.compact().tets, mesh.tets);
    EXPECT_EQ(m.compact().points, mesh.points);
  };
  {
    FlipMesh m(mesh);
    const std::vector<index_t> side = plus_x_tets(m);
    // Node 0 is a corner of the domain.
    std::vector<index_t> star;
    m.tets_with_edge(0, 0, star);
    EXPECT_EQ(m.split(0, {star[0]}, {1, 0, 0}, {0.9, 0, 0}, 0.0), NO_VERTEX);
    // The floor: no tet of this split is near regular.
    EXPECT_EQ(m.split(6, side, {-0.2, 0, 0}, {0.2, 0, 0}, 0.99), NO_VERTEX);
    // The new node out of the star: tets inverted.
    EXPECT_EQ(m.split(6, side, {0, 0, 0}, {1.5, 0, 0}, 0.0), NO_VERTEX);
    // The new edge across the cut (the +x side's node on the -x side): ring tets inverted.
    EXPECT_EQ(m.split(6, side, {0.2, 0, 0}, {-0.2, 0, 0}, 0.0), NO_VERTEX);
    // No tet, every tet, or a tet not at the node.
    EXPECT_EQ(m.split(6, {}, {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), NO_VERTEX);
    EXPECT_EQ(m.split(6, alive_tets(m), {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), NO_VERTEX);
    EXPECT_EQ(m.split(6, {m.nb_slots()}, {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), NO_VERTEX);
    unchanged(m);
  }
  {
    FlipMesh m(mesh);
    m.set_locked(alive_tets(m).back(), true);  // a tet of the star locked
    EXPECT_EQ(m.split(6, plus_x_tets(m), {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), NO_VERTEX);
    unchanged(m);
  }
  // One tet in another region: node 6 is on an interface and stays.
  TetMesh two = mesh;
  two.regions.assign(two.nb_tets(), 1);
  two.regions[0] = 2;
  FlipMesh mixed(two);
  EXPECT_EQ(mixed.split(6, plus_x_tets(mixed), {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), NO_VERTEX);
  two.regions.assign(two.nb_tets(), 1);
  FlipMesh same(two);
  EXPECT_EQ(same.split(6, plus_x_tets(same), {-0.2, 0, 0}, {0.2, 0, 0}, 0.0), 7u);
}

// tet_with_face() answers from the input's neighbours where it can: the same tet as a search of
// every live tet, after flips, a flip undone and flips again.
TEST(flip_mesh, the_tet_across_a_face_is_the_one_a_search_finds) {
  const TetMesh mesh = bipyramid({0.3, 0.3, -1});
  FlipMesh m(mesh);
  const auto expect_as_searched = [&] {
    for (index_t t : alive_tets(m)) {
      for (int f = 0; f < 4; ++f) {
        std::array<index_t, 3> face{};
        int n = 0;
        for (int i = 0; i < 4; ++i) {
          if (i != f) face[n++] = m.tet(t)[i];
        }
        index_t searched = NO_CELL;
        for (index_t u : alive_tets(m)) {
          const index_t* q = m.tet(u);
          if (u != t && std::count(q, q + 4, face[0]) && std::count(q, q + 4, face[1]) &&
              std::count(q, q + 4, face[2])) {
            searched = u;
          }
        }
        EXPECT_EQ(m.tet_with_face(face[0], face[1], face[2], t), searched) << t << " " << f;
      }
    }
  };
  expect_as_searched();
  const std::size_t start = m.mark();
  ASSERT_TRUE(m.flip_23(0, 1, 0.0));  // the input's two tets die: a search answers
  expect_as_searched();
  m.undo(start);  // alive again: their neighbours answer
  expect_as_searched();
  ASSERT_TRUE(m.flip_23(0, 1, 0.0));
  ASSERT_TRUE(m.remove_edge(3, 4, 0, 0.0));
  expect_as_searched();
}

}  // namespace
}  // namespace hexmerge
