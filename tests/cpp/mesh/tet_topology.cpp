#include "hexmerge/mesh/tet_topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge::test {
namespace {

std::vector<TetMesh> topology_fixtures() {
  std::vector<TetMesh> meshes = {kuhn_grid(1), kuhn_grid(3), five_tet_grid(1), five_tet_grid(4)};
  for (const auto& tets : enumerate_triangulations(unit_cube())) {
    meshes.push_back(polytope_mesh(unit_cube(), tets));
  }
  std::mt19937 rng(3);
  TetMesh skewed = five_tet_grid(3);
  random_affine_map(skewed, rng);
  random_perturbation(skewed, rng, 0.05);
  meshes.push_back(skewed);
  return meshes;
}

std::array<index_t, 3> sorted_face(const TetMesh& mesh, index_t t, int f) {
  const auto& face = descriptor(CellType::Tet).face[f];
  std::array<index_t, 3> v = {mesh.tet(t)[face[0]], mesh.tet(t)[face[1]], mesh.tet(t)[face[2]]};
  std::sort(v.begin(), v.end());
  return v;
}

TEST(TetTopology, adjacency_is_symmetric_in_range_and_through_the_same_face) {
  for (const TetMesh& mesh : topology_fixtures()) {
    const TetTopology topo(mesh);
    ASSERT_EQ(topo.nb_tets(), mesh.nb_tets());
    std::size_t boundary = 0;
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      bool any_boundary = false;
      for (int f = 0; f < 4; ++f) {
        const index_t u = topo.neighbor(t, f);
        if (u == NO_CELL) {
          EXPECT_TRUE(topo.on_boundary(t, f));
          any_boundary = true;
          ++boundary;
          continue;
        }
        ASSERT_LT(u, mesh.nb_tets());
        EXPECT_NE(u, t);
        const int g = topo.neighbor_face(t, f);
        ASSERT_TRUE(g >= 0 && g < 4);
        EXPECT_EQ(topo.neighbor(u, g), t);
        EXPECT_EQ(topo.neighbor_face(u, g), f);
        EXPECT_EQ(sorted_face(mesh, t, f), sorted_face(mesh, u, g));
      }
      EXPECT_EQ(topo.is_boundary_tet(t), any_boundary);
    }
    EXPECT_EQ(topo.nb_boundary_faces(), boundary);
  }
}

TEST(TetTopology, boundary_faces_of_structured_grids) {
  for (int n : {1, 2, 5}) {
    // Two triangles per boundary square, six sides of n x n squares.
    EXPECT_EQ(TetTopology(kuhn_grid(n)).nb_boundary_faces(), std::size_t(12 * n * n));
    EXPECT_EQ(TetTopology(five_tet_grid(n)).nb_boundary_faces(), std::size_t(12 * n * n));
  }
  // The central tet of a five-tet cube touches no boundary.
  const TetTopology one(five_tet_grid(1));
  EXPECT_FALSE(one.is_boundary_tet(4));
  for (index_t t = 0; t < 4; ++t) EXPECT_TRUE(one.is_boundary_tet(t));
}

TEST(TetTopology, three_tets_on_one_face_is_an_input_error) {
  // Face (0,1,2) in the plane z = 0 carries a tet below it and two above it.
  TetMesh mesh =
      make_tet_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, 1}, {0, 0, -1}},
                    {{0, 1, 2, 3}, {0, 1, 2, 4}, {0, 2, 1, 5}});
  try {
    TetTopology topo(mesh);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_LT(e.id(), 3u);
    EXPECT_NE(std::string(e.what()).find("3 tetrahedra"), std::string::npos) << e.what();
  }
  // One above and one below are fine.
  mesh.tets.erase(mesh.tets.begin() + 4, mesh.tets.begin() + 8);
  EXPECT_EQ(TetTopology(mesh).nb_boundary_faces(), 6u);
}

TEST(TetTopology, two_tets_on_the_same_side_of_their_face_are_an_input_error) {
  // Both positively oriented, both above face (0,1,2): they overlap (a fold), and validation,
  // which looks at one tet at a time, passes them.
  const TetMesh mesh = make_tet_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.2, 1}},
                                     {{0, 1, 2, 3}, {0, 1, 2, 4}});
  validate_tet_mesh(mesh);
  try {
    TetTopology topo(mesh);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_EQ(e.id(), 1u);
    EXPECT_NE(std::string(e.what()).find("same side of their shared face (nodes 0, 1, 2)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hexmerge::test
