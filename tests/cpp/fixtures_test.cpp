// Tests of the shared fixtures themselves: the enumerations the engine tests rely on must be
// complete and right before they can judge the engine.
#include "fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge::test {
namespace {

TEST(fixtures, cube_has_58_candidate_tets_and_74_triangulations) {
  const Polytope cube = unit_cube();
  EXPECT_EQ(candidate_tets(cube).size(), 58u);
  const auto triangulations = enumerate_triangulations(cube);
  ASSERT_EQ(triangulations.size(), 74u);
  std::set<std::vector<Tet>> distinct(triangulations.begin(), triangulations.end());
  EXPECT_EQ(distinct.size(), 74u);
  for (const auto& tets : triangulations) {
    const TetMesh mesh = polytope_mesh(cube, tets);
    EXPECT_NO_THROW(validate_tet_mesh(mesh));
    EXPECT_DOUBLE_EQ(total_volume(mesh), 1.0);
    EXPECT_TRUE(tets.size() == 5 || tets.size() == 6);
    // Twelve boundary triangles: two per cube face.
    EXPECT_EQ(TetTopology(mesh).nb_boundary_faces(), 12u);
  }
}

TEST(fixtures, cube_triangulations_fall_into_the_papers_six_rf_graphs) {
  const Polytope cube = unit_cube();
  const auto triangulations = enumerate_triangulations(cube);
  std::vector<std::string> keys;
  for (const auto& tets : triangulations) keys.push_back(canonical_form(rf_graph(cube, tets)));
  std::vector<int> sizes;
  const std::vector<int> cls = classes_of(keys, sizes);
  std::vector<int> sorted_sizes = sizes;
  std::sort(sorted_sizes.begin(), sorted_sizes.end());
  EXPECT_EQ(sorted_sizes, (std::vector<int>{2, 4, 8, 12, 24, 24}));
  // Within a class: the same number of tets and the same cycle; the 5-tet class is a tree (the
  // paper's Figure 4); the 6-tet classes have cycles of 6, 5, 4, 4, 3 (Figures 5 to 9).
  std::vector<std::set<std::pair<std::size_t, int>>> shape(sizes.size());
  for (std::size_t i = 0; i < triangulations.size(); ++i) {
    const RFGraph g = rf_graph(cube, triangulations[i]);
    shape[cls[i]].insert({triangulations[i].size(), solid_cycle_length(g)});
    int dashed = 0;
    for (int a = 0; a < g.nb_nodes; ++a) {
      for (int b = a + 1; b < g.nb_nodes; ++b) dashed += (g.adjacency[a][b] & 2) ? 1 : 0;
    }
    EXPECT_EQ(dashed, 6) << "one quad pair per cube face";
  }
  std::multiset<std::pair<std::size_t, int>> all;
  for (const auto& s : shape) {
    ASSERT_EQ(s.size(), 1u);
    all.insert(*s.begin());
  }
  EXPECT_EQ(all, (std::multiset<std::pair<std::size_t, int>>{
                     {5, 0}, {6, 6}, {6, 5}, {6, 4}, {6, 4}, {6, 3}}));
  for (std::size_t i = 0; i < triangulations.size(); ++i) {
    if (triangulations[i].size() == 5) {
      EXPECT_EQ(sizes[cls[i]], 2);
    }
  }
}

TEST(fixtures, prism_has_6_triangulations_and_pyramid_2) {
  const auto prisms = enumerate_triangulations(unit_prism());
  EXPECT_EQ(prisms.size(), 6u);
  for (const auto& tets : prisms) {
    EXPECT_EQ(tets.size(), 3u);
    const TetMesh mesh = polytope_mesh(unit_prism(), tets);
    EXPECT_NO_THROW(validate_tet_mesh(mesh));
    EXPECT_DOUBLE_EQ(total_volume(mesh), 0.5);
  }
  const auto pyramids = enumerate_triangulations(square_pyramid());
  EXPECT_EQ(pyramids.size(), 2u);
  for (const auto& tets : pyramids) {
    EXPECT_EQ(tets.size(), 2u);
    EXPECT_DOUBLE_EQ(total_volume(polytope_mesh(square_pyramid(), tets)), 4.0 / 3.0);
  }
}

TEST(fixtures, grids_are_valid_conforming_tet_meshes) {
  for (int n : {1, 2, 3}) {
    for (const TetMesh& mesh : {kuhn_grid(n), five_tet_grid(n)}) {
      EXPECT_NO_THROW(validate_tet_mesh(mesh));
      EXPECT_NEAR(total_volume(mesh), double(n * n * n), 1e-12);
      // Conforming: only the 2 triangles per boundary square are unpaired.
      EXPECT_EQ(TetTopology(mesh).nb_boundary_faces(), std::size_t(12 * n * n));
    }
    EXPECT_EQ(kuhn_grid(n).nb_tets(), index_t(6 * n * n * n));
    EXPECT_EQ(five_tet_grid(n).nb_tets(), index_t(5 * n * n * n));
  }
}

TEST(fixtures, affine_maps_and_perturbations_keep_tets_valid) {
  std::mt19937 rng(7);
  for (int k = 0; k < 20; ++k) {
    TetMesh mesh = five_tet_grid(2);
    random_affine_map(mesh, rng);
    EXPECT_NO_THROW(validate_tet_mesh(mesh));
    const std::vector<double> before = mesh.points;
    random_perturbation(mesh, rng, 0.02);
    EXPECT_NO_THROW(validate_tet_mesh(mesh));
    EXPECT_NE(before, mesh.points);
  }
}

}  // namespace
}  // namespace hexmerge::test
