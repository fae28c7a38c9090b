#include "hexmerge/occ/mesher/polish.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/recombine.h"

namespace hexmerge {
namespace {

using mesher::polish_leftover_tets;
using mesher::PolishReport;
using test::grid_node;
using test::kuhn_grid;
using test::min_quality;
using test::total_volume;

constexpr int kCells = 6;

// A Kuhn grid of kCells^3 cubes whose inner nodes with i >= 3 are moved at random by up to 0.3:
// the cubes there recombine into some hexahedra, prisms and pyramids and leave tets under 0.2
// between them; the others stay perfect hexahedra.
TetMesh half_shaken_grid() {
  TetMesh m = kuhn_grid(kCells);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> offset(-0.3, 0.3);
  for (int k = 1; k < kCells; ++k)
    for (int j = 1; j < kCells; ++j)
      for (int i = 3; i < kCells; ++i) {
        const index_t v = grid_node(kCells, i, j, k);
        for (int c = 0; c < 3; ++c) m.points[3 * v + c] += offset(random);
      }
  validate_tet_mesh(m);
  return m;
}

std::vector<char> inner_nodes_free(const TetMesh& m) {
  const TetTopology topology(m);
  std::vector<char> movable(m.nb_vertices(), kFree);
  for (index_t t = 0; t < m.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f))
        for (int k = 1; k < 4; ++k) movable[m.tet(t)[(f + k) % 4]] = kFixed;
  return movable;
}

std::size_t tets_below(const MixedMesh& mixed, double floor) {
  std::size_t below = 0;
  for (index_t c = 0; c < mixed.nb_cells(); ++c)
    below += mixed.types[c] == CellType::Tet &&
             scaled_jacobian(CellType::Tet, mixed.points.data(), mixed.cell(c)) < floor;
  return below;
}

TEST(polish_leftover_tets, raises_the_tets_left_and_keeps_every_element) {
  TetMesh m = half_shaken_grid();
  const TetMesh before = m;
  RecombineReport first_report;
  const MixedMesh first = recombine(before, RecombineParameters{}, first_report);
  const std::size_t below_first = tets_below(first, 0.2);
  ASSERT_GT(below_first, 0u);

  PolishReport report;
  polish_leftover_tets(m, inner_nodes_free(m), nullptr, RecombineParameters{}, 0.2, report);
  validate_tet_mesh(m);
  EXPECT_EQ(report.elements, first.nb_cells() - first_report.output_counts[0]);
  EXPECT_EQ(report.below_before, below_first);
  EXPECT_LT(report.below_after, report.below_before);
  EXPECT_GT(report.node_moves, 0u);
  EXPECT_GE(min_quality(m), min_quality(before));
  EXPECT_NEAR(total_volume(m), total_volume(before), 1e-9 * total_volume(before));

  // Recombined again: every element of the first still acceptable (the selection, on the moved
  // nodes, chooses among more: here more hexahedra, fewer cells), no tet under 0.2 left.
  RecombineReport second_report;
  const MixedMesh second = recombine(m, RecombineParameters{}, second_report);
  for (index_t c = 0; c < first.nb_cells(); ++c)
    if (first.types[c] != CellType::Tet)
      EXPECT_GE(scaled_jacobian(first.types[c], m.points.data(), first.cell(c)),
                RecombineParameters{}.min_scaled_jacobian);
  EXPECT_EQ(tets_below(second, 0.2), 0u);
  EXPECT_GT(second_report.output_counts[3], first_report.output_counts[3]);
  EXPECT_LT(second_report.output_cells, first_report.output_cells);

  // The boundary's nodes and the perfect hexahedra's (i <= 2) stay where they were.
  const std::vector<char> movable = inner_nodes_free(before);
  for (int k = 0; k <= kCells; ++k)
    for (int j = 0; j <= kCells; ++j)
      for (int i = 0; i <= kCells; ++i) {
        const index_t v = grid_node(kCells, i, j, k);
        if (i > 2 && movable[v] == kFree) continue;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(m.points[3 * v + c], before.points[3 * v + c]);
      }
}

// The recombination's phases go to the progress callback; false from it cancels, the mesh as
// it was.
TEST(polish_leftover_tets, shows_the_recombinations_progress_and_can_be_cancelled) {
  TetMesh m = half_shaken_grid();
  std::vector<std::string> phases;
  PolishReport report;
  polish_leftover_tets(m, inner_nodes_free(m), nullptr, RecombineParameters{}, 0.2, report,
                       [&](const std::string& phase, double) {
                         phases.push_back(phase);
                         return true;
                       });
  ASSERT_FALSE(phases.empty());
  EXPECT_EQ(phases.front(), "topology");
  EXPECT_EQ(phases.back(), "done");
  TetMesh cancelled = half_shaken_grid();
  EXPECT_THROW(
      polish_leftover_tets(cancelled, inner_nodes_free(cancelled), nullptr, RecombineParameters{},
                           0.2, report, [](const std::string&, double) { return false; }),
      Cancelled);
  EXPECT_EQ(cancelled.points, half_shaken_grid().points);
  EXPECT_EQ(cancelled.tets, half_shaken_grid().tets);
}

TEST(polish_leftover_tets, does_nothing_where_no_tet_is_under_the_floor) {
  TetMesh m = kuhn_grid(3);
  const TetMesh before = m;
  PolishReport report;
  polish_leftover_tets(m, inner_nodes_free(m), nullptr, RecombineParameters{}, 0.2, report);
  EXPECT_EQ(report.elements, 0u);  // not even recombined
  EXPECT_EQ(report.below_before, 0u);
  EXPECT_EQ(report.node_moves + report.flips + report.inserted_vertices, 0u);
  EXPECT_EQ(m.points, before.points);
  EXPECT_EQ(m.tets, before.tets);
}

}  // namespace
}  // namespace hexmerge
