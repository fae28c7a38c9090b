#include "hexmerge/occ/mesher/smooth_nodes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge {
namespace {

using test::add_tet;
using test::min_quality;

// An octahedron's six corners around node 6, which sits close to corner 0: the four tets at
// corner 0 are flat.
TetMesh star_with_an_offset_centre() {
  TetMesh m;
  m.points = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0.9, 0.05, 0.02};
  const index_t ring[4] = {2, 4, 3, 5};  // around the x axis
  for (int i = 0; i < 4; ++i) {
    add_tet(m, 6, 0, ring[i], ring[(i + 1) % 4]);
    add_tet(m, 6, 1, ring[i], ring[(i + 1) % 4]);
  }
  return m;
}

TEST(smooth_nodes, moving_the_centre_raises_the_minimum_and_nothing_else_moves) {
  TetMesh m = star_with_an_offset_centre();
  const std::vector<double> before = m.points;
  const double q0 = min_quality(m);
  std::vector<char> movable(m.nb_vertices(), 0);
  movable[6] = 1;
  SmoothNodesReport report;
  smooth_nodes(m, movable, SmoothNodesParameters{}, report);
  EXPECT_DOUBLE_EQ(report.min_before, q0);
  EXPECT_GT(report.min_after, 0.5);  // the centre of an octahedron gives 0.707
  EXPECT_GT(report.min_after, q0);
  EXPECT_DOUBLE_EQ(report.min_after, min_quality(m));
  EXPECT_GE(report.moves, 1u);
  for (std::size_t i = 0; i < 18; ++i) EXPECT_EQ(m.points[i], before[i]);  // corners stay
  EXPECT_EQ(m.tets.size(), 32u);                                           // tets stay
  validate_tet_mesh(m);
}

// `keeps` refuses positions: the centre takes none it refuses (here, with x under 0.5: an
// element relying on it would fail there), and none at all when it refuses every one.
TEST(smooth_nodes, a_node_takes_no_position_keeps_refuses) {
  TetMesh m = star_with_an_offset_centre();
  std::vector<char> movable(m.nb_vertices(), 0);
  movable[6] = 1;
  SmoothNodesReport report;
  smooth_nodes(m, movable, SmoothNodesParameters{}, report, nullptr, {}, nullptr,
               [&](index_t v) { return v != 6 || m.points[18] >= 0.5; });
  EXPECT_GE(m.points[18], 0.5);
  EXPECT_GT(report.min_after, report.min_before);
  EXPECT_LT(report.min_after, 0.5);  // the centre of the octahedron (0.707) is refused

  TetMesh still = star_with_an_offset_centre();
  smooth_nodes(still, movable, SmoothNodesParameters{}, report, nullptr, {}, nullptr,
               [](index_t) { return false; });
  EXPECT_EQ(still.points, star_with_an_offset_centre().points);
  EXPECT_EQ(report.moves, 0u);
}

// Random stars (an octahedron's corners moved by up to 0.45, the centre anywhere near the
// middle): the free centre's search raises its worst tet, but does not end with more of its tets
// below the floor than where it started unless its worst tet was under half the floor. Raising
// the worst tet alone pushed others below it.
TEST(smooth_nodes, a_free_node_never_ends_with_more_tets_below_the_floor) {
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> jitter(-0.45, 0.45);
  const SmoothNodesParameters parameters;
  std::size_t moved = 0;
  for (int trial = 0; trial < 400; ++trial) {
    TetMesh m = star_with_an_offset_centre();
    for (double& x : m.points) x += jitter(random);
    std::vector<char> movable(m.nb_vertices(), kFixed);
    movable[6] = kFree;
    auto below = [&] {
      std::size_t n = 0;
      for (index_t t = 0; t < m.nb_tets(); ++t)
        n += scaled_jacobian(CellType::Tet, m.points.data(), m.tet(t)) < parameters.floor;
      return n;
    };
    const std::size_t below_before = below();
    const double worst_before = min_quality(m);
    SmoothNodesReport report;
    smooth_nodes(m, movable, parameters, report);
    // More only where lifting a tet under half the floor needed it (the last position without
    // more had its worst tet there: the search starts from the node's own).
    if (worst_before >= 0.5 * parameters.floor)
      EXPECT_LE(below(), below_before) << "trial " << trial;
    EXPECT_GE(min_quality(m), worst_before) << "trial " << trial;
    moved += report.moves > 0;
  }
  EXPECT_GT(moved, 200u);  // most stars had a tet below the target to lift
}

// A star (found among random ones) whose worst tet, 0.175, the search lifts furthest by pushing
// a third tet below the floor: the node stops where no more than two are, its worst tet still
// raised.
TEST(smooth_nodes, lifting_the_worst_tet_pushes_no_other_below_the_floor) {
  TetMesh m = star_with_an_offset_centre();
  m.points = {1.4295226223066553,    -0.013608800206461324, -0.14499095201668155,
              -1.0845225936840048,   0.098046690294850247,  0.12219436462563327,
              0.0058815198943410474, 1.3639127351463345,    -0.35258710137555405,
              -0.044224041111324552, -0.62593737040199326,  -0.42715511120845773,
              -0.33007981813676324,  -0.31824790098218114,  0.57178843128827961,
              -0.3552451093861399,   -0.30002290336815729,  -0.88295754502919055,
              0.57907075196079438,   0.12616090510311823,   -0.16919835122341628};
  const SmoothNodesParameters parameters;
  auto below = [&] {
    std::size_t n = 0;
    for (index_t t = 0; t < m.nb_tets(); ++t)
      n += scaled_jacobian(CellType::Tet, m.points.data(), m.tet(t)) < parameters.floor;
    return n;
  };
  const double worst_before = min_quality(m);
  ASSERT_EQ(below(), 2u);
  ASSERT_GT(worst_before, 0.5 * parameters.floor);
  std::vector<char> movable(m.nb_vertices(), kFixed);
  movable[6] = kFree;
  SmoothNodesReport report;
  smooth_nodes(m, movable, parameters, report);
  EXPECT_EQ(report.moves, 1u);
  EXPECT_LE(below(), 2u);  // lifting the worst tet furthest left three below 0.2
  EXPECT_GT(min_quality(m), worst_before);
  validate_tet_mesh(m);
}

TEST(smooth_nodes, a_nudged_node_moves_only_until_its_tets_reach_the_nudge_target) {
  TetMesh free_run = star_with_an_offset_centre(), nudged_run = free_run;
  const Vec3 start{0.9, 0.05, 0.02};
  std::vector<char> movable(free_run.nb_vertices(), kFixed);
  movable[6] = kFree;
  SmoothNodesReport report;
  smooth_nodes(free_run, movable, SmoothNodesParameters{}, report);
  movable[6] = kNudged;
  SmoothNodesParameters parameters;
  parameters.nudge_target = 0.2;
  smooth_nodes(nudged_run, movable, parameters, report);
  EXPECT_GE(report.min_after, 0.2);
  EXPECT_LT(report.min_after, 0.5);  // not as far as the free node goes (0.707 at the centre)
  EXPECT_DOUBLE_EQ(report.min_after, min_quality(nudged_run));
  EXPECT_GE(report.moves, 1u);
  const double free_move = (Vec3::of(free_run.point(6)) - start).norm();
  const double nudge = (Vec3::of(nudged_run.point(6)) - start).norm();
  EXPECT_GT(nudge, 0);
  EXPECT_LT(nudge, 0.5 * free_move);
  validate_tet_mesh(nudged_run);
  // At the nudge target already: it stays, though below the free nodes' target.
  const std::vector<double> before = nudged_run.points;
  smooth_nodes(nudged_run, movable, parameters, report);
  EXPECT_EQ(nudged_run.points, before);
  EXPECT_EQ(report.moves, 0u);
}

// Node 6 of the star is also the apex of a pyramid over the square 2-4-3-5 (x = 0): moved to
// the star's centre it would flatten it. Kept, the pyramid stays at pyramid_floor while the tets
// still improve.
TEST(smooth_nodes, a_kept_pyramid_stays_at_its_floor) {
  TetMesh free_run = star_with_an_offset_centre(), kept_run = free_run;
  std::array<index_t, 5> pyramid{2, 4, 3, 5, 6};
  if (scaled_jacobian(CellType::Pyramid, kept_run.points.data(), pyramid.data()) < 0)
    std::swap(pyramid[1], pyramid[3]);
  const auto pyramid_quality = [&](const TetMesh& m) {
    return scaled_jacobian(CellType::Pyramid, m.points.data(), pyramid.data());
  };
  ASSERT_GT(pyramid_quality(kept_run), 0.5);
  std::vector<char> movable(free_run.nb_vertices(), kFixed);
  movable[6] = kFree;
  SmoothNodesParameters parameters;
  parameters.pyramid_floor = 0.3;
  SmoothNodesReport free_report, kept_report;
  smooth_nodes(free_run, movable, parameters, free_report);
  EXPECT_LT(pyramid_quality(free_run), 0.3);  // unguarded, the apex goes near the base
  smooth_nodes(kept_run, movable, parameters, kept_report, nullptr, {pyramid});
  EXPECT_GE(pyramid_quality(kept_run), 0.3);
  EXPECT_GT(kept_report.min_after, kept_report.min_before);
  EXPECT_LT(kept_report.min_after, free_report.min_after);
  validate_tet_mesh(kept_run);
  // A pyramid already below the floor may not get worse.
  TetMesh low_run = star_with_an_offset_centre();
  parameters.pyramid_floor = 1.0;
  const double low_before = pyramid_quality(low_run);
  smooth_nodes(low_run, movable, parameters, kept_report, nullptr, {pyramid});
  EXPECT_GE(pyramid_quality(low_run), low_before);
  EXPECT_THROW(smooth_nodes(low_run, movable, parameters, kept_report, nullptr, {{0, 1, 2, 3, 99}}),
               InputError);
}

// A square pyramid (apex 4 over the ring 0-3 on z = 0) cut at node 5, which lies on the base
// close to corner 0: the tets at corner 0 are flat, the base's triangles needles.
TetMesh pyramid_with_an_offset_base_node() {
  TetMesh m;
  m.points = {1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0, 0, 0, 1, 0.9, 0.05, 0};
  for (index_t i = 0; i < 4; ++i) add_tet(m, 5, i, (i + 1) % 4, 4);
  return m;
}

// The plane z = 0 (dimension 2) or the line y = 0.05, z = 0 (dimension 1) through node 5, by
// lengths along x and y from where the node stands.
class FlatPath final : public SurfacePath {
 public:
  explicit FlatPath(int dimension) : dimension_(dimension) {}
  int dimension(index_t v) const override { return v == 5 ? dimension_ : 0; }
  void tangents(index_t, Vec3& along_u, Vec3& along_v) const override {
    along_u = {1, 0, 0};
    along_v = dimension_ == 2 ? Vec3{0, 1, 0} : Vec3{0, 0, 0};
  }
  bool at(index_t, double a, double b, Vec3& point) const override {
    if (dimension_ == 1 && b != 0) return false;
    point = stood_ + Vec3{a, b, 0};
    return true;
  }
  void moved(index_t, double a, double b) override {
    stood_ = stood_ + Vec3{a, b, 0};
    ++moves_;
  }
  Vec3 stood() const { return stood_; }
  int moves() const { return moves_; }

 private:
  int dimension_;
  Vec3 stood_{0.9, 0.05, 0};
  int moves_ = 0;
};

TEST(smooth_nodes, a_node_on_a_surface_moves_along_it_and_stays_on_it) {
  TetMesh m = pyramid_with_an_offset_base_node();
  const double q0 = min_quality(m);
  std::vector<char> movable(m.nb_vertices(), kFixed);
  movable[5] = kOnSurface;
  FlatPath plane(2);
  SmoothNodesReport report;
  smooth_nodes(m, movable, SmoothNodesParameters{}, report, &plane);
  EXPECT_LT(q0, 0.1);
  EXPECT_GE(report.min_after, 0.2);  // the nudge target (the base's centre gives 1)
  EXPECT_DOUBLE_EQ(report.min_after, min_quality(m));
  EXPECT_EQ(report.surface_moves, report.moves);
  EXPECT_GE(report.moves, 1u);
  EXPECT_EQ(m.point(5)[2], 0.0);  // on the plane
  const Vec3 stood = plane.stood();
  EXPECT_EQ(Vec3::of(m.point(5)).x, stood.x);  // where the path was told it went
  EXPECT_EQ(Vec3::of(m.point(5)).y, stood.y);
  EXPECT_LT(stood.x, 0.9);
  validate_tet_mesh(m);
}

TEST(smooth_nodes, a_node_on_a_curve_moves_along_it_only) {
  TetMesh m = pyramid_with_an_offset_base_node();
  std::vector<char> movable(m.nb_vertices(), kFixed);
  movable[5] = kOnSurface;
  FlatPath line(1);
  SmoothNodesReport report;
  smooth_nodes(m, movable, SmoothNodesParameters{}, report, &line);
  EXPECT_GT(report.min_after, report.min_before);
  EXPECT_EQ(m.point(5)[1], 0.05);
  EXPECT_EQ(m.point(5)[2], 0.0);
  EXPECT_LT(m.point(5)[0], 0.9);
  validate_tet_mesh(m);
}

TEST(smooth_nodes, a_node_on_a_surface_stays_without_its_path) {
  TetMesh m = pyramid_with_an_offset_base_node();
  const std::vector<double> before = m.points;
  std::vector<char> movable(m.nb_vertices(), kFixed);
  movable[5] = kOnSurface;
  SmoothNodesReport report;
  smooth_nodes(m, movable, SmoothNodesParameters{}, report);
  EXPECT_EQ(m.points, before);
  FlatPath elsewhere(0);  // holds no node
  smooth_nodes(m, movable, SmoothNodesParameters{}, report, &elsewhere);
  EXPECT_EQ(m.points, before);
  EXPECT_EQ(elsewhere.moves(), 0);
}

TEST(smooth_nodes, fixed_nodes_and_good_tets_stay) {
  TetMesh m = star_with_an_offset_centre();
  const std::vector<double> before = m.points;
  SmoothNodesReport report;
  smooth_nodes(m, std::vector<char>(m.nb_vertices(), 0), SmoothNodesParameters{}, report);
  EXPECT_EQ(m.points, before);
  EXPECT_EQ(report.moves, 0u);
  // Above the target: nothing to do.
  std::vector<char> movable(m.nb_vertices(), 1);
  SmoothNodesParameters low;
  low.target = 1e-3;
  smooth_nodes(m, movable, low, report);
  EXPECT_EQ(m.points, before);
}

// The nodes a call leaves settled (their search moved them nowhere, and no node of a tet at
// them moved after) are skipped by the next call, which moves the others as it would without:
// the same points. The first call makes two passes only, so that some nodes are not settled;
// with a lower target, fewer nodes are searched and some stay settled.
TEST(smooth_nodes, the_settled_nodes_a_call_leaves_change_no_move) {
  const TetMesh given = test::tetgen_lattice(6, 0.45, 11);
  if (given.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  // The nodes inside are free (a node on the lattice's box is in a boundary face).
  std::vector<char> movable(given.nb_vertices(), kFree);
  const TetTopology topology(given);
  for (index_t t = 0; t < given.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f))
        for (int k = 0; k < 4; ++k)
          if (k != f) movable[given.tet(t)[k]] = kFixed;
  SmoothNodesParameters lower, two_passes;
  lower.target = lower.nudge_target = 0.15;  // fewer nodes searched: some stay settled
  two_passes = lower;
  two_passes.max_passes = 2;
  std::vector<char> settled(given.nb_vertices(), 0);
  TetMesh m = given;
  SmoothNodesReport report;
  smooth_nodes(m, movable, two_passes, report, nullptr, {}, &settled);
  ASSERT_GT(report.moves, 0u);
  ASSERT_EQ(settled.size(), m.nb_vertices());
  const auto count = std::count(settled.begin(), settled.end(), 1);
  EXPECT_GT(count, 0);
  EXPECT_LT(static_cast<std::size_t>(count), m.nb_vertices());
  TetMesh with_state = m, without = m;
  SmoothNodesReport with_report, without_report;
  smooth_nodes(with_state, movable, lower, with_report, nullptr, {}, &settled);
  smooth_nodes(without, movable, lower, without_report);
  ASSERT_GT(without_report.moves, 0u);
  EXPECT_EQ(with_state.points, without.points);
  EXPECT_EQ(with_report.moves, without_report.moves);
  EXPECT_DOUBLE_EQ(with_report.min_after, without_report.min_after);
  // Settled flags of another mesh are refused.
  settled.pop_back();
  EXPECT_THROW(smooth_nodes(with_state, movable, SmoothNodesParameters{}, with_report, nullptr, {},
                            &settled),
               InputError);
}

TEST(smooth_nodes, bad_arguments_name_what_is_wrong) {
  TetMesh m = star_with_an_offset_centre();
  SmoothNodesReport report;
  EXPECT_THROW(smooth_nodes(m, std::vector<char>(3, 1), SmoothNodesParameters{}, report),
               InputError);
  SmoothNodesParameters bad;
  bad.target = 0;
  EXPECT_THROW(smooth_nodes(m, std::vector<char>(m.nb_vertices(), 1), bad, report), InputError);
  bad.target = 0.3;
  bad.nudge_target = 1.5;
  EXPECT_THROW(smooth_nodes(m, std::vector<char>(m.nb_vertices(), 1), bad, report), InputError);
  bad.nudge_target = 0.2;
  bad.floor = -1;
  EXPECT_THROW(smooth_nodes(m, std::vector<char>(m.nb_vertices(), 1), bad, report), InputError);
}

}  // namespace
}  // namespace hexmerge
