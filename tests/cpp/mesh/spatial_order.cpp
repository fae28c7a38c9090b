#include "hexmerge/mesh/spatial_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "fixtures.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge::test {
namespace {

// A grid with its tets shuffled, regions set: the order has something to undo.
TetMesh shuffled_grid() {
  TetMesh mesh = five_tet_grid(4);
  std::mt19937 rng(7);
  random_perturbation(mesh, rng, 0.05);
  std::vector<index_t> shuffle(mesh.nb_tets());
  std::iota(shuffle.begin(), shuffle.end(), 0);
  std::shuffle(shuffle.begin(), shuffle.end(), rng);
  mesh = reorder_tets(mesh, shuffle);
  mesh.regions.resize(mesh.nb_tets());
  for (index_t t = 0; t < mesh.nb_tets(); ++t) mesh.regions[t] = static_cast<std::int32_t>(t % 3);
  return mesh;
}

TEST(spatial_order, is_a_permutation_and_deterministic) {
  const TetMesh mesh = shuffled_grid();
  const std::vector<index_t> order = spatial_order(mesh);
  std::vector<index_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<index_t> identity(mesh.nb_tets());
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(sorted, identity);
  EXPECT_EQ(spatial_order(mesh), order);
}

TEST(spatial_order, brings_face_neighbours_closer) {
  const TetMesh mesh = shuffled_grid();
  auto mean_gap = [](const TetMesh& m) {
    const TetTopology topology(m);
    double sum = 0.0;
    int n = 0;
    for (index_t t = 0; t < m.nb_tets(); ++t) {
      for (int f = 0; f < 4; ++f) {
        const index_t u = topology.neighbor(t, f);
        if (u == NO_CELL) continue;
        sum += std::abs(static_cast<double>(u) - static_cast<double>(t));
        ++n;
      }
    }
    return sum / n;
  };
  EXPECT_LT(mean_gap(reorder_tets(mesh, spatial_order(mesh))), 0.5 * mean_gap(mesh));
}

TEST(reorder_tets, moves_tets_with_their_regions) {
  const TetMesh mesh = shuffled_grid();
  const std::vector<index_t> order = spatial_order(mesh);
  const TetMesh moved = reorder_tets(mesh, order);
  EXPECT_EQ(moved.points, mesh.points);
  ASSERT_EQ(moved.nb_tets(), mesh.nb_tets());
  for (index_t i = 0; i < moved.nb_tets(); ++i) {
    EXPECT_TRUE(std::equal(moved.tet(i), moved.tet(i) + 4, mesh.tet(order[i])));
    EXPECT_EQ(moved.region(i), mesh.region(order[i]));
  }
}

TEST(TetTopology, reordered_is_the_topology_of_the_reordered_mesh) {
  const TetMesh mesh = shuffled_grid();
  const std::vector<index_t> order = spatial_order(mesh);
  const TetTopology expected(reorder_tets(mesh, order));
  const TetTopology reordered = TetTopology(mesh).reordered(order);
  ASSERT_EQ(reordered.nb_tets(), expected.nb_tets());
  EXPECT_EQ(reordered.nb_boundary_faces(), expected.nb_boundary_faces());
  for (index_t t = 0; t < expected.nb_tets(); ++t) {
    for (int f = 0; f < 4; ++f) {
      ASSERT_EQ(reordered.neighbor(t, f), expected.neighbor(t, f));
      if (expected.neighbor(t, f) != NO_CELL) {
        EXPECT_EQ(reordered.neighbor_face(t, f), expected.neighbor_face(t, f));
      }
    }
  }
}

}  // namespace
}  // namespace hexmerge::test
