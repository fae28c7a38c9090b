#include "hexmerge/occ/mesher/remove_slivers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <vector>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge {
namespace {

using test::add_tet;
using test::min_quality;

std::set<std::array<index_t, 3>> boundary_faces(const TetMesh& m) {
  const TetTopology topology(m);
  std::set<std::array<index_t, 3>> out;
  for (index_t t = 0; t < m.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f)) {
        std::array<index_t, 3> k{m.tet(t)[(f + 1) % 4], m.tet(t)[(f + 2) % 4],
                                 m.tet(t)[(f + 3) % 4]};
        std::sort(k.begin(), k.end());
        out.insert(k);
      }
  return out;
}

// A square s0..s3 between apexes t (above) and u (below); s1 and s3 slightly raised. The top
// pyramid is cut along s1-s3, the bottom one along s0-s2: the sliver (s0, s1, s2, s3) fills the
// gap between the two diagonals.
TetMesh sliver_between_pyramids() {
  TetMesh m;
  m.points = {0, 0, 0, 1, 0, 0.02, 1, 1, 0, 0, 1, 0.02, 0.5, 0.5, 0.8, 0.5, 0.5, -0.8};
  add_tet(m, 1, 2, 3, 4);
  add_tet(m, 1, 3, 0, 4);
  add_tet(m, 0, 1, 2, 5);
  add_tet(m, 0, 2, 3, 5);
  add_tet(m, 0, 1, 2, 3);
  return m;
}

TEST(remove_slivers, an_edge_removal_takes_out_the_sliver) {
  TetMesh m = sliver_between_pyramids();
  const double before = min_quality(m);
  ASSERT_LT(before, 0.05);
  const auto boundary = boundary_faces(m);
  RemoveSliversReport report;
  remove_slivers(m, {}, {}, RemoveSliversParameters{}, report);
  validate_tet_mesh(m);
  EXPECT_EQ(m.nb_tets(), 4u);
  EXPECT_GT(min_quality(m), 0.5);
  EXPECT_DOUBLE_EQ(report.min_before, before);
  EXPECT_DOUBLE_EQ(report.min_after, min_quality(m));
  EXPECT_EQ(report.below_before, 1u);
  EXPECT_EQ(report.below_after, 0u);
  EXPECT_EQ(report.edge_removals + report.face_removals, 1u);
  EXPECT_EQ(boundary_faces(m), boundary);
}

TEST(remove_slivers, fixed_tets_and_region_boundaries_stay) {
  TetMesh m = sliver_between_pyramids();
  const std::vector<index_t> tets = m.tets;
  RemoveSliversReport report;
  remove_slivers(m, {0, 0, 0, 0, 1}, {}, RemoveSliversParameters{}, report);
  EXPECT_EQ(m.tets, tets);
  // The sliver in a region of its own: every flip would replace it with tets of another region.
  m.regions = {0, 0, 0, 0, 1};
  remove_slivers(m, {}, {}, RemoveSliversParameters{}, report);
  EXPECT_EQ(m.tets, tets);
  EXPECT_EQ(report.edge_removals + report.face_removals, 0u);
}

// A pyramid on a flat square base (the boundary), its apex over (0.2, 0.2): cut along s1-s3
// (worst scaled Jacobian 0.59) it is better than along s0-s2 (0.47), as given.
TetMesh pyramid_on_the_boundary() {
  TetMesh m;
  m.points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.2, 0.2, 0.6};
  add_tet(m, 0, 1, 2, 4);
  add_tet(m, 0, 2, 3, 4);
  return m;
}

TEST(remove_slivers, boundary_sides_swap_only_within_one_patch) {
  TetMesh m = pyramid_on_the_boundary();
  const double before = min_quality(m);
  // Patches per tet face (opposite vertex f): the base triangles are the faces opposite the apex.
  auto patches = [&](std::int32_t first, std::int32_t second) {
    std::vector<std::int32_t> p(8, 7);
    for (index_t t = 0; t < 2; ++t)
      for (int f = 0; f < 4; ++f)
        if (m.tet(t)[f] == 4) p[4 * t + f] = t == 0 ? first : second;
    return p;
  };
  RemoveSliversParameters every_tet;
  every_tet.target = 1;
  TetMesh other = m;
  RemoveSliversReport report;
  remove_slivers(other, {}, patches(3, 4), every_tet, report);
  EXPECT_EQ(other.tets, m.tets);  // two CAD faces: their shared side stays
  remove_slivers(m, {}, {}, every_tet, report);
  EXPECT_EQ(report.boundary_swaps, 0u);  // no patches given: the boundary stays
  remove_slivers(m, {}, patches(3, 3), every_tet, report);
  validate_tet_mesh(m);
  EXPECT_EQ(report.boundary_swaps, 1u);
  EXPECT_GT(min_quality(m), before);
  const auto boundary = boundary_faces(m);
  EXPECT_TRUE(boundary.count({1, 3, 4}) == 0 && boundary.count({0, 1, 3}) == 1 &&
              boundary.count({1, 2, 3}) == 1);
}

// The sliver between the pyramids with the lower pyramid gone: its two lower faces, bent along
// s0-s2 (s1 and s3 are 0.02 up), are on the boundary, and s0-s2 is in no other tet. The upper
// pyramid is fixed: only the boundary swap of s0-s2 to s1-s3 can take the sliver out.
TEST(remove_slivers, a_bent_boundary_side_swaps_within_the_shift_allowed) {
  TetMesh m = sliver_between_pyramids();
  m.points.resize(15);
  m.tets = {1, 2, 3, 4, 1, 3, 0, 4, 0, 1, 2, 3};
  std::vector<std::int32_t> patches(12, 0);  // one patch for every boundary face
  const std::vector<char> fixed{1, 1, 0};
  RemoveSliversParameters p;
  p.target = 1;
  RemoveSliversReport report;
  TetMesh other = m;
  remove_slivers(other, fixed, patches, p, report);
  EXPECT_EQ(other.tets, m.tets);  // not in one plane: the boundary stays
  p.max_boundary_shift = 0.019;   // the lines s0-s2 and s1-s3 are 0.02 apart
  remove_slivers(other, fixed, patches, p, report);
  EXPECT_EQ(other.tets, m.tets);
  p.max_boundary_shift = 0.021;
  remove_slivers(m, fixed, patches, p, report);
  validate_tet_mesh(m);
  EXPECT_EQ(report.boundary_swaps, 1u);
  EXPECT_EQ(m.nb_tets(), 2u);  // the sliver is gone, the boundary is s0 s1 s3 and s1 s2 s3
  const auto boundary = boundary_faces(m);
  EXPECT_TRUE(boundary.count({0, 1, 3}) == 1 && boundary.count({1, 2, 3}) == 1 &&
              boundary.count({0, 1, 2}) == 0);
  p.max_boundary_shift = -1;
  EXPECT_THROW(remove_slivers(m, {}, {}, p, report), InputError);
}

// Jittered lattice points through TetGen: tets no flip improves remain under 0.2; vertices
// inserted into them (insert_below) leave fewer, never a lower minimum, the same boundary and
// volume, the given points where they were, a valid mesh.
TEST(remove_slivers, inserted_vertices_take_out_tets_no_flip_improves) {
  const TetMesh given = test::tetgen_lattice(6, 0.45, 11);
  if (given.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  RemoveSliversParameters p;
  RemoveSliversReport flipped, inserted;
  TetMesh flips_only = given;
  remove_slivers(flips_only, {}, {}, p, flipped);
  EXPECT_EQ(flipped.insertions, 0u);
  EXPECT_EQ(flips_only.points, given.points);
  p.insert_below = 0.2;
  TetMesh m = given;
  remove_slivers(m, {}, {}, p, inserted);
  validate_tet_mesh(m);
  ASSERT_GT(inserted.insertions, 0u);
  EXPECT_EQ(m.nb_vertices(), given.nb_vertices() + inserted.insertions);
  EXPECT_TRUE(std::equal(given.points.begin(), given.points.end(), m.points.begin()));
  EXPECT_LT(test::count_below(m, 0.2), test::count_below(flips_only, 0.2));
  EXPECT_EQ(inserted.below_after, test::count_below(m, p.target));
  EXPECT_GE(min_quality(m), flipped.min_after);
  EXPECT_EQ(boundary_faces(m), boundary_faces(given));
  EXPECT_NEAR(test::total_volume(m), test::total_volume(given), 1e-9 * test::total_volume(given));
  p.insert_below = 1.5;
  EXPECT_THROW(remove_slivers(m, {}, {}, p, inserted), InputError);
}

// The tets at each vertex, as sorted vertex lists.
std::vector<std::set<std::array<index_t, 4>>> tets_at_vertices(const TetMesh& m) {
  std::vector<std::set<std::array<index_t, 4>>> out(m.nb_vertices());
  for (index_t t = 0; t < m.nb_tets(); ++t) {
    std::array<index_t, 4> key{m.tet(t)[0], m.tet(t)[1], m.tet(t)[2], m.tet(t)[3]};
    std::sort(key.begin(), key.end());
    for (const index_t v : key) out[v].insert(key);
  }
  return out;
}

// The state a call leaves (the tets no flip improves, the vertices whose tets changed) makes
// the next call skip those tets, not flip otherwise: with it or without, the same tets. Between
// the calls some tets are flipped by a call with fewer passes, so that the state is partial.
TEST(remove_slivers, the_state_left_for_the_next_call_changes_no_flip) {
  const TetMesh given = test::tetgen_lattice(6, 0.45, 11);
  if (given.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  RemoveSliversParameters first;
  first.max_passes = 1;
  RemoveSliversState state;
  RemoveSliversReport report;
  TetMesh m = given;
  remove_slivers(m, {}, {}, first, report, &state);
  ASSERT_GT(report.edge_removals + report.face_removals, 0u);
  ASSERT_EQ(state.settled.size(), m.nb_tets());
  ASSERT_EQ(state.touched.size(), m.nb_vertices());
  // Every vertex whose tets changed is marked touched; some tets below the target are settled.
  const auto before = tets_at_vertices(given), after = tets_at_vertices(m);
  std::size_t touched = 0, settled_below = 0;
  for (index_t v = 0; v < m.nb_vertices(); ++v) {
    if (before[v] != after[v]) EXPECT_TRUE(state.touched[v]) << "vertex " << v;
    touched += state.touched[v] != 0;
  }
  for (index_t t = 0; t < m.nb_tets(); ++t)
    settled_below += state.settled[t] &&
                     scaled_jacobian(CellType::Tet, m.points.data(), m.tet(t)) < first.target;
  EXPECT_GT(touched, 0u);
  EXPECT_LT(touched, m.nb_vertices());
  EXPECT_GT(settled_below, 0u);
  RemoveSliversParameters next;
  next.insert_below = 0.2;
  TetMesh with_state = m, without = m;
  RemoveSliversReport with_report, without_report;
  remove_slivers(with_state, {}, {}, next, with_report, &state);
  remove_slivers(without, {}, {}, next, without_report);
  validate_tet_mesh(with_state);
  EXPECT_EQ(with_state.tets, without.tets);
  EXPECT_EQ(with_state.points, without.points);
  EXPECT_EQ(with_report.edge_removals, without_report.edge_removals);
  EXPECT_EQ(with_report.face_removals, without_report.face_removals);
  EXPECT_EQ(with_report.insertions, without_report.insertions);
  // A state of another mesh is refused.
  state.settled.push_back(1);
  EXPECT_THROW(remove_slivers(with_state, {}, {}, next, with_report, &state), InputError);
}

TEST(remove_slivers, bad_parameters_are_reported) {
  TetMesh m = sliver_between_pyramids();
  RemoveSliversReport report;
  RemoveSliversParameters p;
  p.target = 0;
  EXPECT_THROW(remove_slivers(m, {}, {}, p, report), InputError);
  EXPECT_THROW(remove_slivers(m, {1}, {}, RemoveSliversParameters{}, report), InputError);
}

}  // namespace
}  // namespace hexmerge
