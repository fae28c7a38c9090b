// prune_unclosable: the candidates no conforming selection can hold.
#include "hexmerge/recombine/prune_candidates.h"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "fixtures.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/recombine/recombine.h"

namespace hexmerge {
namespace {

using test::kuhn_grid;
using test::orient_positively;

std::size_t count_type(const std::vector<Candidate>& candidates, CellType type) {
  std::size_t n = 0;
  for (const Candidate& c : candidates) n += c.type == type;
  return n;
}

// A Kuhn cube with one tet on each triangle of its top face (z = 1), whose apexes are `apex0`
// and `apex1`: the cube's top quad is closed by a pyramid when they are one point, by nothing
// when they are two.
TetMesh cube_with_cap(const std::array<double, 3>& apex0, const std::array<double, 3>& apex1) {
  TetMesh mesh = kuhn_grid(1);
  std::vector<std::array<index_t, 3>> top;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* v = mesh.tet(t);
    for (int f = 0; f < 4; ++f) {
      std::array<index_t, 3> tri{};
      int k = 0;
      for (int i = 0; i < 4; ++i)
        if (i != f) tri[k++] = v[i];
      if (mesh.point(tri[0])[2] == 1 && mesh.point(tri[1])[2] == 1 && mesh.point(tri[2])[2] == 1)
        top.push_back(tri);
    }
  }
  EXPECT_EQ(top.size(), 2u);
  const index_t a0 = mesh.nb_vertices();
  mesh.points.insert(mesh.points.end(), apex0.begin(), apex0.end());
  index_t a1 = a0;
  if (apex1 != apex0) {
    a1 = a0 + 1;
    mesh.points.insert(mesh.points.end(), apex1.begin(), apex1.end());
  }
  mesh.tets.insert(mesh.tets.end(), {top[0][0], top[0][1], top[0][2], a0});
  mesh.tets.insert(mesh.tets.end(), {top[1][0], top[1][1], top[1][2], a1});
  orient_positively(mesh);
  validate_tet_mesh(mesh);
  return mesh;
}

std::vector<Candidate> candidates_of(const TetMesh& mesh) {
  const TetTopology topology(mesh);
  AcceptanceCriteria criteria;
  criteria.min_scaled_jacobian = 0.05;
  return find_candidates(mesh, topology, criteria, 1);
}

TEST(PruneUnclosable, KeepsEveryCellOfAGrid) {
  // Every quad face of a grid cell is on the boundary or shared with the next cell.
  const TetMesh mesh = kuhn_grid(3);
  const TetTopology topology(mesh);
  const std::vector<Candidate> all = candidates_of(mesh);
  std::size_t removed = 0;
  const std::vector<Candidate> kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(kept.size() + removed, all.size());
  std::size_t cubes = 0;
  for (const Candidate& c : kept) cubes += c.type == CellType::Hex && c.quality > 0.999f;
  EXPECT_EQ(cubes, 27u);
}

TEST(PruneUnclosable, KeepsAHexWhoseQuadAPyramidCloses) {
  const TetMesh mesh = cube_with_cap({0.5, 0.5, 1.5}, {0.5, 0.5, 1.5});
  const TetTopology topology(mesh);
  const std::vector<Candidate> all = candidates_of(mesh);
  ASSERT_EQ(count_type(all, CellType::Hex), 1u);
  ASSERT_GE(count_type(all, CellType::Pyramid), 1u);
  std::size_t removed = 0;
  const std::vector<Candidate> kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(count_type(kept, CellType::Hex), 1u);
  // And the selection makes the pair: one hex, one pyramid, conforming.
  RecombineReport report;
  RecombineParameters parameters;
  parameters.min_scaled_jacobian = 0.05;
  const MixedMesh out = recombine(mesh, parameters, report);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Hex)], 1u);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Pyramid)], 1u);
  EXPECT_EQ(report.nonconforming_quads, 0u);
}

TEST(PruneUnclosable, RemovesAHexWhoseQuadNothingCloses) {
  // Two tets with different apexes on the top quad: no pyramid, no hex across.
  const TetMesh mesh = cube_with_cap({0.3, 0.6, 1.4}, {0.7, 0.4, 1.4});
  const TetTopology topology(mesh);
  const std::vector<Candidate> all = candidates_of(mesh);
  ASSERT_EQ(count_type(all, CellType::Hex), 1u);
  std::size_t removed = 0;
  const std::vector<Candidate> kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(count_type(kept, CellType::Hex), 0u);
  // So do the pyramids and prisms of the cube that have the top quad as a face.
  EXPECT_GT(removed, 1u);
  EXPECT_EQ(kept.size() + removed, all.size());
  // The selection then leaves the cube's top quad to no element: conforming.
  RecombineReport report;
  RecombineParameters parameters;
  parameters.min_scaled_jacobian = 0.05;
  recombine(mesh, parameters, report);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Hex)], 0u);
  EXPECT_EQ(report.nonconforming_quads, 0u);
  EXPECT_EQ(report.candidates_unclosable, removed);
}

}  // namespace
}  // namespace hexmerge
