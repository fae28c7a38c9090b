// The selection's optimality bound: the integer program against hand-made conflicts whose optimum
// is known, and against the engine's selection on grids.
#include "hexmerge/recombine/bound_selection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/recombine.h"
#include "hexmerge/recombine/select/select_candidates.h"

namespace hexmerge::test {
namespace {

struct Group {
  std::vector<index_t> tets;
  CellType type = CellType::Hex;
};

/// Candidates made of the given tets only (the program looks at nothing else).
Candidates groups(std::vector<Group> list) {
  Candidates out;
  for (Group& g : list) {
    Candidate c{};
    c.vertices.fill(NO_VERTEX);
    c.type = g.type;
    c.quality = 1.0f;
    std::sort(g.tets.begin(), g.tets.end());
    out.push_back(c, g.tets.data(), static_cast<int>(g.tets.size()));
  }
  return out;
}

#define SKIP_WITHOUT_GLPK() \
  if (!selection_bound_available()) GTEST_SKIP() << "built without GLPK"

TEST(bound_selection, two_disjoint_hexes_beat_the_one_that_overlaps_both) {
  SKIP_WITHOUT_GLPK();
  // A takes tets 0-5; B and C each share three of them with A and are disjoint from each other.
  const Candidates candidates =
      groups({{{0, 1, 2, 3, 4, 5}}, {{0, 1, 2, 10, 11, 12}}, {{3, 4, 5, 13, 14, 15}}});
  // Started from the greedy-looking choice {A}: the solver must still find {B, C}.
  for (const std::vector<index_t>& initial : {std::vector<index_t>{}, std::vector<index_t>{0}}) {
    const SelectionBound bound = bound_selection(16, candidates, initial, 10.0);
    EXPECT_TRUE(bound.proved);
    EXPECT_EQ(bound.bound_elements, 6u);  // 16 tets - 2 x 5 saved
    EXPECT_EQ(bound.best_elements, 6u);
    EXPECT_EQ(std::set<index_t>(bound.best.begin(), bound.best.end()), (std::set<index_t>{1, 2}));
  }
}

TEST(bound_selection, an_odd_cycle_of_conflicts_is_solved_past_its_fractional_relaxation) {
  SKIP_WITHOUT_GLPK();
  // Three pyramids pairwise sharing one tet: the LP relaxation saves 1.5, any selection 1.
  const Candidates candidates = groups(
      {{{0, 1}, CellType::Pyramid}, {{1, 2}, CellType::Pyramid}, {{0, 2}, CellType::Pyramid}});
  const SelectionBound bound = bound_selection(3, candidates, {}, 10.0);
  EXPECT_TRUE(bound.proved);
  EXPECT_EQ(bound.bound_elements, 2u);
  EXPECT_EQ(bound.best_elements, 2u);
  EXPECT_EQ(bound.best.size(), 1u);
}

TEST(bound_selection, a_conformity_row_forbids_a_quad_face_left_open) {
  SKIP_WITHOUT_GLPK();
  // Hexes A and C, and pyramid B that closes A's quad face but overlaps C.
  const Candidates candidates =
      groups({{{0, 1, 2, 3, 4, 5}}, {{6, 7}, CellType::Pyramid}, {{7, 8, 9, 10, 11, 12}}});
  const SelectionBound packing = bound_selection(13, candidates, {}, 10.0);
  EXPECT_EQ(packing.bound_elements, 3u);  // A and C
  const std::vector<ConformityRow> rows = {{0, {1}}};
  const SelectionBound conforming = bound_selection(13, candidates, {}, 10.0, rows);
  EXPECT_TRUE(conforming.proved);
  EXPECT_EQ(conforming.conformity_rows, 1u);
  EXPECT_EQ(conforming.bound_elements, 7u);  // A and B
  EXPECT_EQ(std::set<index_t>(conforming.best.begin(), conforming.best.end()),
            (std::set<index_t>{0, 1}));
  // An initial selection breaking the row keeps its place: the row is left out.
  const SelectionBound from_broken = bound_selection(13, candidates, {0}, 10.0, rows);
  EXPECT_EQ(from_broken.dropped_rows, 1u);
  EXPECT_EQ(from_broken.bound_elements, 3u);
}

TEST(bound_selection, conforming_selections_keep_every_conformity_row) {
  SKIP_WITHOUT_GLPK();
  std::mt19937 rng(11);
  for (bool five : {false, true}) {
    SCOPED_TRACE(five ? "five-tet grid" : "Kuhn grid");
    TetMesh mesh = five ? five_tet_grid(3) : kuhn_grid(3);
    random_perturbation(mesh, rng, 0.12);
    const TetTopology topology(mesh);
    const RecombineParameters p;  // conforming
    AcceptanceCriteria criteria;
    const Candidates candidates = find_candidates(mesh, topology, criteria, 1);
    const Selection selection = select_candidates(mesh, topology, candidates, p);
    const std::vector<ConformityRow> rows = conformity_rows(mesh, topology, candidates);
    EXPECT_FALSE(rows.empty());
    const SelectionBound packing =
        bound_selection(mesh.nb_tets(), candidates, selection.elements, 2.0);
    const SelectionBound conforming =
        bound_selection(mesh.nb_tets(), candidates, selection.elements, 2.0, rows);
    EXPECT_EQ(conforming.dropped_rows, 0u);
    EXPECT_EQ(conforming.conformity_rows, rows.size());
    EXPECT_GE(conforming.bound_elements, packing.bound_elements);
    std::size_t ours = mesh.nb_tets();
    for (index_t c : selection.elements) ours -= candidates[c].nb_tets - 1u;
    EXPECT_LE(conforming.best_elements, ours);
    EXPECT_LE(conforming.bound_elements, conforming.best_elements);
  }
}

TEST(bound_selection, no_candidates_bound_is_the_tets) {
  SKIP_WITHOUT_GLPK();
  const SelectionBound bound = bound_selection(7, {}, {}, 1.0);
  EXPECT_TRUE(bound.proved);
  EXPECT_EQ(bound.bound_elements, 7u);
  EXPECT_EQ(bound.best_elements, 7u);
}

TEST(bound_selection, kuhn_grid_bound_is_one_element_per_cube_and_the_gap_is_zero) {
  SKIP_WITHOUT_GLPK();
  for (int n : {2, 3}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    RecombineParameters p;
    p.optimality_bound = true;
    RecombineReport report;
    recombine(kuhn_grid(n), p, report);
    const std::size_t cubes = std::size_t(n) * n * n;
    ASSERT_TRUE(report.bound_computed);
    EXPECT_TRUE(report.bound_conforming);
    EXPECT_TRUE(report.bound_proved);
    EXPECT_EQ(report.bound_elements, cubes);
    EXPECT_EQ(report.bound_best_elements, cubes);
    EXPECT_EQ(report.output_cells, cubes);
    EXPECT_DOUBLE_EQ(report.gap_percent, 0.0);
  }
}

TEST(bound_selection, gap_is_never_negative_on_jittered_grids) {
  SKIP_WITHOUT_GLPK();
  std::mt19937 rng(5);
  for (bool five : {false, true}) {
    for (const char* conformity : {"conforming", "allow"}) {
      SCOPED_TRACE(std::string(five ? "five-tet" : "Kuhn") + " grid, " + conformity);
      TetMesh mesh = five ? five_tet_grid(3) : kuhn_grid(3);
      random_perturbation(mesh, rng, 0.12);
      RecombineParameters p;
      set_parameter(p, "conformity", conformity);
      p.optimality_bound = true;
      p.bound_time_limit = 2.0;  // a bound that stops early must hold as well
      RecombineReport report;
      recombine(mesh, p, report);
      ASSERT_TRUE(report.bound_computed);
      EXPECT_EQ(report.bound_conforming, std::string(conformity) == "conforming");
      EXPECT_LE(report.bound_elements, report.bound_best_elements);
      EXPECT_LE(report.bound_best_elements, report.output_cells);  // ours is its first incumbent
      EXPECT_GE(report.gap_percent, 0.0);
      if (report.bound_proved) {
        EXPECT_EQ(report.bound_elements, report.bound_best_elements);
      }
    }
  }
}

TEST(bound_selection, without_glpk_the_parameter_is_refused_by_name) {
  if (selection_bound_available()) GTEST_SKIP() << "built with GLPK";
  RecombineParameters p;
  p.optimality_bound = true;
  RecombineReport report;
  try {
    recombine(kuhn_grid(1), p, report);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Parameter);
    EXPECT_NE(std::string(e.what()).find("optimality_bound"), std::string::npos);
  }
}

TEST(bound_selection, parameters_are_in_the_table_with_their_ranges) {
  RecombineParameters p;
  EXPECT_FALSE(p.optimality_bound);
  EXPECT_DOUBLE_EQ(p.bound_time_limit, 30.0);
  set_parameter(p, "optimality_bound", "true");
  set_parameter(p, "bound_time_limit", "5");
  EXPECT_TRUE(p.optimality_bound);
  EXPECT_DOUBLE_EQ(p.bound_time_limit, 5.0);
  EXPECT_THROW(set_parameter(p, "bound_time_limit", "0.5"), InputError);
  EXPECT_THROW(set_parameter(p, "bound_time_limit", "4000"), InputError);
}

}  // namespace
}  // namespace hexmerge::test
