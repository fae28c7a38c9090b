// Conforming groups (select/groups.cpp): hexahedra whose quad faces close each other, taken
// together or not at all.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/prune_candidates.h"
#include "hexmerge/recombine/select/select_candidates.h"
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

// Two by two by two cubes of five tets each (five_tet_grid): the two tets behind a face of a
// cube are corner tets with different fourth vertices, so no pyramid closes any quad face; the
// inner node moved off the lattice and the grid sheared, so that no cube is near-perfect
// (scaled Jacobian 0.9; the block takes a hexahedron beside a near-perfect one whose face no
// pyramid closes) or has planar quads (the block takes none). Every cube's three inner faces can
// only be shared with its neighbours.
TetMesh skewed_five_tet_grid() {
  TetMesh mesh = five_tet_grid(2);
  double* inner = &mesh.points[3 * std::size_t(grid_node(2, 1, 1, 1))];
  inner[0] += 0.2;
  inner[1] += 0.15;
  inner[2] += 0.1;
  // Sheared (x += z / 2): no corner of a cube is then square (scaled Jacobian at most 0.894).
  for (std::size_t p = 0; p < mesh.points.size(); p += 3)
    mesh.points[p] += 0.5 * mesh.points[p + 2];
  return mesh;
}

std::size_t count(const Outcome& run, CellType type) {
  return run.check.counts[static_cast<int>(type)];
}

TEST(select_groups, hexahedra_sharing_faces_no_pyramid_closes_are_taken_together) {
  const TetMesh mesh = skewed_five_tet_grid();
  RecombineParameters one_at_a_time;
  one_at_a_time.group_size = 0;
  const Outcome before = recombine_and_check(mesh, one_at_a_time, false);
  EXPECT_EQ(hexes(before), 0u) << "no hexahedron alone has every face closed";
  EXPECT_EQ(before.report.group_seeds, 0u);

  const Outcome run = recombine_and_check(mesh, {}, false);
  EXPECT_EQ(hexes(run), 8u);
  EXPECT_EQ(run.mesh.nb_cells(), 8u);
  EXPECT_EQ(count(run, CellType::Pyramid), 0u);
  EXPECT_EQ(run.report.block_hexahedra, 0u);
  EXPECT_EQ(run.report.groups, 1u);
  EXPECT_EQ(run.report.group_hexahedra, 8u);
  EXPECT_EQ(run.report.groups_failed + run.report.groups_capped, 0u);
  EXPECT_EQ(run.check.nonconforming_quads, 0u);
  EXPECT_EQ(run.check.cracks, 0u);
  EXPECT_NEAR(run.report.volume_fraction[static_cast<int>(CellType::Hex)], 1.0, 1e-12);
  EXPECT_LT(run.mesh.nb_cells(), before.mesh.nb_cells());
}

// A group that needs more members than group_size is rolled back: the selection is exactly the
// one made without groups, and the report counts the groups given up.
TEST(select_groups, a_group_given_up_leaves_the_selection_unchanged) {
  const TetMesh mesh = skewed_five_tet_grid();
  const TetTopology topology(mesh);
  Candidates all = find_candidates(mesh, topology, AcceptanceCriteria{}, 1);
  std::size_t removed = 0;
  all = prune_unclosable(mesh, topology, all, removed);
  RecombineParameters off;
  off.group_size = 0;
  RecombineParameters small;
  small.group_size = 7;
  RecombineParameters enough;
  enough.group_size = 8;
  const Selection without = select_candidates(mesh, topology, all, off);
  const Selection capped = select_candidates(mesh, topology, all, small);
  const Selection whole = select_candidates(mesh, topology, all, enough);
  EXPECT_EQ(capped.elements, without.elements);
  EXPECT_EQ(capped.groups, 0u);
  EXPECT_GT(capped.groups_capped, 0u);
  EXPECT_EQ(capped.group_seeds, capped.groups_capped + capped.groups_failed);
  EXPECT_EQ(whole.groups, 1u);
  EXPECT_EQ(whole.group_hexahedra, 8u);
  EXPECT_EQ(whole.elements.size(), 8u);
  for (index_t ci : whole.elements) EXPECT_EQ(all[ci].type, CellType::Hex);
  EXPECT_EQ(whole.nonconforming_quads, 0u);
}

// Where no partner exists (one cube made a poor hexahedron by moving its outer corner), the
// group that reaches that cube is rolled back and the selection is the one made without groups.
// The candidates are not pruned here: pruning would remove every hexahedron (each needs the
// missing one), and the group must find that out itself.
TEST(select_groups, a_group_with_a_face_nothing_closes_is_rolled_back) {
  TetMesh mesh = skewed_five_tet_grid();
  double* corner = &mesh.points[3 * std::size_t(grid_node(2, 0, 0, 0))];
  corner[0] += 0.55;
  corner[1] += 0.55;
  corner[2] += 0.55;
  const TetTopology topology(mesh);
  const Candidates all = find_candidates(mesh, topology, AcceptanceCriteria{}, 1);
  std::size_t hex_candidates = 0;
  for (const Candidate& c : all) hex_candidates += c.type == CellType::Hex;
  ASSERT_EQ(hex_candidates, 7u) << "the moved corner's cube is no hexahedron candidate";
  RecombineParameters off;
  off.group_size = 0;
  const Selection without = select_candidates(mesh, topology, all, off);
  const Selection with = select_candidates(mesh, topology, all, RecombineParameters{});
  EXPECT_GT(with.groups_failed, 0u);
  EXPECT_EQ(with.groups, 0u);
  EXPECT_EQ(with.group_seeds, with.groups_failed);
  EXPECT_EQ(with.elements, without.elements);
  EXPECT_EQ(with.nonconforming_quads, 0u);
}

// Three by three by three skewed cubes (every inner node moved): one group of 27 hexahedra,
// given up when group_size is 26.
TEST(select_groups, a_larger_group_is_taken_whole_or_given_up_at_group_size) {
  TetMesh mesh = five_tet_grid(3);
  const double offsets[8][3] = {{0.12, -0.08, 0.05},  {-0.1, 0.07, 0.11},  {0.06, 0.12, -0.09},
                                {-0.07, -0.11, 0.08}, {0.1, 0.05, -0.12},  {-0.12, 0.09, -0.06},
                                {0.08, -0.1, -0.07},  {-0.05, -0.06, 0.12}};
  int m = 0;
  for (int k = 1; k < 3; ++k) {
    for (int j = 1; j < 3; ++j) {
      for (int i = 1; i < 3; ++i, ++m) {
        double* p = &mesh.points[3 * std::size_t(grid_node(3, i, j, k))];
        for (int a = 0; a < 3; ++a) p[a] += offsets[m][a];
      }
    }
  }
  RecombineParameters off;
  off.group_size = 0;
  const Outcome before = recombine_and_check(mesh, off, false);
  EXPECT_EQ(hexes(before), 0u);
  const Outcome run = recombine_and_check(mesh, {}, false);
  EXPECT_EQ(hexes(run), 27u);
  EXPECT_EQ(run.mesh.nb_cells(), 27u);
  EXPECT_EQ(run.report.groups, 1u);
  EXPECT_EQ(run.check.nonconforming_quads, 0u);
  EXPECT_EQ(run.check.cracks, 0u);
  RecombineParameters small;
  small.group_size = 26;
  const Outcome capped = recombine_and_check(mesh, small, false);
  EXPECT_EQ(hexes(capped), 0u);
  EXPECT_GT(capped.report.groups_capped, 0u);
  EXPECT_EQ(capped.mesh.cell_vertices, before.mesh.cell_vertices);
}

TEST(select_groups, group_size_is_in_the_table_with_its_range) {
  RecombineParameters p;
  EXPECT_EQ(p.group_size, 64);
  set_parameter(p, "group_size", "0");
  EXPECT_EQ(p.group_size, 0);
  set_parameter(p, "group_size", "500");
  EXPECT_EQ(p.group_size, 500);
  EXPECT_THROW(set_parameter(p, "group_size", "-1"), InputError);
  EXPECT_THROW(set_parameter(p, "group_size", "10001"), InputError);
  EXPECT_THROW(set_parameter(p, "group_size", "2.5"), InputError);
  std::set<std::string> names;
  for (const ParameterInfo& row : parameter_table()) names.insert(row.name);
  EXPECT_TRUE(names.count("group_size"));
}

}  // namespace
}  // namespace hexmerge::test
