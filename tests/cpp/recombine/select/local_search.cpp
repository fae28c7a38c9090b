// The local search (select/local_search.cpp, step 5 of select_candidates.h): swaps and exact
// re-selection in neighbourhoods.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/check/check_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/bound_selection.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/select/select_candidates.h"
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

/// The cells of a selection: tets minus the tets merged away.
std::size_t cells_of(const TetMesh& mesh, const Candidates& candidates,
                     const Selection& selection) {
  std::size_t cells = mesh.nb_tets();
  for (index_t c : selection.elements) cells -= candidates[c].nb_tets - 1u;
  return cells;
}

/// The candidates of one Kuhn cube with exactly the given tet sets, in that order; the first gets
/// the best quality, so that the greedy takes it first.
Candidates kuhn_cube_candidates(const TetMesh& cube, const std::vector<std::set<index_t>>& wanted) {
  const TetTopology topology(cube);
  const Candidates all = find_candidates(cube, topology, AcceptanceCriteria{}, 1);
  Candidates out;
  for (const std::set<index_t>& tets : wanted) {
    for (const Candidate& c : all) {
      const TetSpan ct = all.tets(c);
      if (std::set<index_t>(ct.begin(), ct.end()) != tets) continue;
      Candidate copy = c;
      if (out.empty()) copy.quality = 0.99f;
      out.push_back(copy, ct.data(), ct.size());
    }
  }
  EXPECT_EQ(out.size(), wanted.size());
  return out;
}

// A Kuhn cube is a ring of six tets around its diagonal, 1-0-2-3-5-4-1: every three consecutive
// tets make a prism, every two a pyramid. Offered only prism {0,1,2} (best quality), prism
// {0,2,3} and pyramid {1,4}, the greedy takes the first prism and nothing else fits: 6 - 2 = 4
// cells. The optimum is the other prism and the pyramid, 6 - 2 - 1 = 3 cells: one element for
// two, which the swap finds (the free tets 3 and 4 are next to the first prism).
TEST(local_search, a_swap_undoes_the_greedys_trap_one_element_for_two) {
  const TetMesh cube = kuhn_grid(1);
  const TetTopology topology(cube);
  const Candidates candidates = kuhn_cube_candidates(cube, {{0, 1, 2}, {0, 2, 3}, {1, 4}});
  ASSERT_EQ(candidates.size(), 3u);
  RecombineParameters p;
  p.conformity = Conformity::Allow;
  p.local_optimisation = false;  // the paper's move would find it too: leave it to the swap
  p.local_search = false;
  const Selection greedy = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, greedy), 4u);
  EXPECT_EQ(greedy.elements, (std::vector<index_t>{0}));
  p.local_search = true;
  const Selection swapped = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, swapped), 3u);
  EXPECT_EQ(swapped.elements, (std::vector<index_t>{1, 2}));
  EXPECT_EQ(swapped.swap_moves, 1u);
  EXPECT_EQ(swapped.reselection_moves, 0u);
  EXPECT_EQ(swapped.local_search_saved, 1u);
  if (selection_bound_available()) {  // and 3 is the optimum
    const SelectionBound bound = bound_selection(cube.nb_tets(), candidates, {}, 5.0);
    EXPECT_TRUE(bound.proved);
    EXPECT_EQ(bound.bound_elements, 3u);
  }
}

// Prism {0,1,2} (best), prism {2,3,5}, pyramid {0,1}: the greedy keeps the first prism (4 cells);
// the optimum, the second prism and the pyramid (3 cells), needs tet 5, which is not next to the
// first prism: swaps alone cannot reach it, a re-selection within one face hop of free tet 3 can.
TEST(local_search, a_reselection_reaches_what_a_swap_cannot) {
  const TetMesh cube = kuhn_grid(1);
  const TetTopology topology(cube);
  const Candidates candidates = kuhn_cube_candidates(cube, {{0, 1, 2}, {2, 3, 5}, {0, 1}});
  ASSERT_EQ(candidates.size(), 3u);
  RecombineParameters p;
  p.conformity = Conformity::Allow;
  p.local_optimisation = false;
  p.local_search_radius = 0;
  const Selection swaps_only = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, swaps_only), 4u);
  EXPECT_EQ(swaps_only.swap_moves, 0u);
  p.local_search_radius = 1;
  const Selection reselected = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, reselected), 3u);
  EXPECT_EQ(reselected.elements, (std::vector<index_t>{1, 2}));
  EXPECT_EQ(reselected.reselection_moves, 1u);
  EXPECT_EQ(reselected.local_search_saved, 1u);
}

// On jittered grids (many skewed candidates, so the greedy is far from optimal) in every
// conformity mode: never more cells than without the local search (in allow and last_resort
// mode, where the elements that would leave a crack are released after the search, when
// neither run released one); every cell positive, no face shared by three cells, every node
// kept, the volume kept up to what non-planar quads explain; every mode valid (no crack);
// conforming mode with no non-conforming quad; last_resort no more non-conforming quads than
// without.
TEST(local_search, keeps_validity_and_conformity_and_never_adds_cells) {
  std::mt19937 rng(7);
  std::size_t moves = 0, saved = 0;
  for (int grid = 0; grid < 4; ++grid) {
    TetMesh mesh = grid % 2 ? five_tet_grid(4) : kuhn_grid(4);
    random_perturbation(mesh, rng, 0.15);
    for (Conformity mode : {Conformity::Conforming, Conformity::LastResort, Conformity::Allow}) {
      for (bool hexes_on : {true, false}) {
        SCOPED_TRACE("grid " + std::to_string(grid) + ", " + to_string(mode) +
                     (hexes_on ? "" : ", no hexahedra"));
        RecombineParameters p = permissive_parameters();
        p.conformity = mode;
        p.make_hexahedra = hexes_on;
        p.local_search = false;
        RecombineReport off_report, on_report;
        const MixedMesh off = recombine(mesh, p, off_report);
        p.local_search = true;
        p.local_search_radius = 2;
        p.local_search_seeds = LocalSearchSeeds::All;
        const MixedMesh on = recombine(mesh, p, on_report);
        const CheckReport off_check = check_mesh(off, mesh), on_check = check_mesh(on, mesh);
        const bool released = off_report.released_elements + on_report.released_elements > 0;
        if (mode == Conformity::Conforming || !released) {
          EXPECT_LE(on.nb_cells(), off.nb_cells());
        }
        if (mode != Conformity::Conforming && !released) {
          // One selection, so the saving is all the search's.
          EXPECT_EQ(off.nb_cells() - on.nb_cells(), on_report.local_search_saved);
        }
        EXPECT_TRUE(on_check.valid()) << describe(on_check);
        EXPECT_TRUE(off_check.valid()) << describe(off_check);
        EXPECT_EQ(on_check.inverted_cells, 0u) << describe(on_check);
        EXPECT_GT(on_check.min_scaled_jacobian, 0.0);
        EXPECT_EQ(on_check.overshared_faces, 0u);
        EXPECT_EQ(on_check.unused_input_nodes, 0u);
        EXPECT_EQ(on_check.region_mismatches, 0u);
        EXPECT_LE(std::abs(on_check.output_volume - on_check.input_volume),
                  quad_volume_bound(on) + 1e-12);
        for (int t = 0; t < NB_CELL_TYPES; ++t) {
          EXPECT_EQ(on_report.output_counts[t], on_check.counts[t]);
        }
        if (mode == Conformity::Conforming) {
          EXPECT_TRUE(on_check.valid()) << describe(on_check);
          EXPECT_EQ(on_check.nonconforming_quads, 0u);
          EXPECT_EQ(on_report.nonconforming_quads, 0u);
        } else if (mode == Conformity::LastResort && !released) {
          EXPECT_LE(on_check.nonconforming_quads, off_check.nonconforming_quads);
          EXPECT_LE(on_report.nonconforming_quads, off_report.nonconforming_quads);
        }
        moves += on_report.swap_moves + on_report.reselection_moves;
        saved += on_report.local_search_saved;
      }
    }
  }
  EXPECT_GT(moves, 0u);  // the meshes do exercise the moves
  EXPECT_GE(saved, moves);
}

TEST(local_search, is_deterministic) {
  std::mt19937 rng(3);
  TetMesh mesh = kuhn_grid(4);
  random_perturbation(mesh, rng, 0.15);
  RecombineParameters p = permissive_parameters();
  p.local_search_radius = 2;
  p.local_search_seeds = LocalSearchSeeds::All;
  RecombineReport r1, r2;
  const MixedMesh a = recombine(mesh, p, r1);
  const MixedMesh b = recombine(mesh, p, r2);
  EXPECT_EQ(a.types, b.types);
  EXPECT_EQ(a.cell_vertices, b.cell_vertices);
  EXPECT_EQ(r1.swap_moves, r2.swap_moves);
  EXPECT_EQ(r1.reselection_moves, r2.reselection_moves);
}

TEST(local_search, parameters_are_in_the_table_with_their_ranges) {
  RecombineParameters p;
  EXPECT_TRUE(p.local_search);
  EXPECT_EQ(p.local_search_radius, 0);
  EXPECT_EQ(p.local_search_nodes, 2000);
  EXPECT_EQ(p.local_search_seeds, LocalSearchSeeds::Unmatched);
  set_parameter(p, "local_search", "false");
  set_parameter(p, "local_search_radius", "3");
  set_parameter(p, "local_search_nodes", "50000");
  set_parameter(p, "local_search_seeds", "all");
  EXPECT_FALSE(p.local_search);
  EXPECT_EQ(p.local_search_radius, 3);
  EXPECT_EQ(p.local_search_nodes, 50000);
  EXPECT_EQ(p.local_search_seeds, LocalSearchSeeds::All);
  EXPECT_THROW(set_parameter(p, "local_search_radius", "5"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_radius", "1.5"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_nodes", "0"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_seeds", "some"), InputError);
  RecombineParameters bad;
  bad.local_search_nodes = -1;
  EXPECT_THROW(validate_parameters(bad), InputError);
  std::set<std::string> names;
  for (const ParameterInfo& row : parameter_table()) names.insert(row.name);
  for (const char* name :
       {"local_search", "local_search_radius", "local_search_nodes", "local_search_seeds"}) {
    EXPECT_TRUE(names.count(name)) << name;
  }
}

}  // namespace
}  // namespace hexmerge::test
