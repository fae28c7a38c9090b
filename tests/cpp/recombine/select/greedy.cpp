// The greedy stages (select/greedy.cpp): boundary tets, then the others, hexahedra before prisms
// before pyramids, then the closing of quad faces.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/prune_candidates.h"
#include "hexmerge/recombine/select/select_candidates.h"
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

// In allow mode the block does not run: the greedy stages alone turn every cube of a Kuhn grid
// into one hexahedron (hexahedra first, every cube's quality 1).
TEST(select_greedy, in_allow_mode_every_cube_of_a_kuhn_grid_is_one_hexahedron) {
  const int n = 3;
  const TetMesh mesh = kuhn_grid(n);
  const TetTopology topology(mesh);
  const Candidates all = find_candidates(mesh, topology, AcceptanceCriteria{}, 1);
  RecombineParameters p;
  p.conformity = Conformity::Allow;
  const Selection s = select_candidates(mesh, topology, all, p);
  EXPECT_EQ(s.block_hexahedra, 0u);
  ASSERT_EQ(s.elements.size(), std::size_t(n * n * n));
  for (index_t ci : s.elements) EXPECT_EQ(all[ci].type, CellType::Hex);
}

// Both orders of the boundary stage (best quality first; the paper's fewest remaining matches
// first) give a disjoint, conforming selection with fewer cells than tets on a
// jittered TetGen lattice (where the block takes few hexahedra and the greedy does the rest:
// 1,132 cells from 1,288 tets).
TEST(select_greedy, both_boundary_orders_give_a_disjoint_conforming_selection) {
  if (std::system("command -v tetgen > /dev/null 2>&1") != 0) GTEST_SKIP() << "no tetgen";
  const TetMesh mesh = tetgen_lattice(5, 0.15, 7);
  const TetTopology topology(mesh);
  Candidates all = find_candidates(mesh, topology, AcceptanceCriteria{}, 1);
  std::size_t removed = 0;
  all = prune_unclosable(mesh, topology, all, removed);
  for (BoundaryOrder order : {BoundaryOrder::Quality, BoundaryOrder::FewestMatches}) {
    SCOPED_TRACE(to_string(order));
    RecombineParameters p;
    p.boundary_order = order;
    const Selection s = select_candidates(mesh, topology, all, p);
    std::vector<int> owners;
    const std::size_t cells = selection_cells(mesh, all, s, owners);
    for (index_t t = 0; t < mesh.nb_tets(); ++t) EXPECT_LE(owners[t], 1) << "tet " << t;
    EXPECT_EQ(s.nonconforming_quads, 0u);
    EXPECT_LT(cells, std::size_t(mesh.nb_tets()));
  }
}

}  // namespace
}  // namespace hexmerge::test
