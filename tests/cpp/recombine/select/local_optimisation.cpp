// The paper's local optimisation (select/local_optimisation.cpp, Meshkat & Talmor 4.2): moves
// around the boundary tets the greedy stages left unmatched.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/select/select_candidates.h"
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

// On TetGen's Delaunay tets of random points in a cube (allow mode, the permissive acceptance
// criteria of the fixtures, so that boundary tets have candidates to move to: 4 moves on seed
// 1), the local optimisation makes moves, never more cells, and the selection stays disjoint.
TEST(select_local_optimisation, moves_never_add_cells_and_keep_the_selection_disjoint) {
  if (std::system("command -v tetgen > /dev/null 2>&1") != 0) GTEST_SKIP() << "no tetgen";
  std::size_t moves = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<Point> points;
    for (int i = 0; i < 600; ++i) points.push_back({u(rng), u(rng), u(rng)});
    const TetMesh mesh = tetgen_mesh(points);
    const TetTopology topology(mesh);
    const Candidates all = find_candidates(mesh, topology, permissive_criteria(), 1);
    std::size_t cells[2] = {0, 0};
    for (bool on : {false, true}) {
      RecombineParameters p;
      p.conformity = Conformity::Allow;
      p.local_optimisation = on;
      p.local_search = false;
      const Selection s = select_candidates(mesh, topology, all, p);
      std::vector<int> owners;
      cells[on] = selection_cells(mesh, all, s, owners);
      for (index_t t = 0; t < mesh.nb_tets(); ++t) EXPECT_LE(owners[t], 1) << "tet " << t;
      if (on) moves += s.local_moves;
      if (!on) {
        EXPECT_EQ(s.local_moves, 0u);
      }
    }
    EXPECT_LE(cells[1], cells[0]);
  }
  EXPECT_GT(moves, 0u);
}

}  // namespace
}  // namespace hexmerge::test
