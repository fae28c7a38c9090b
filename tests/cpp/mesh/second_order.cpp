#include "hexmerge/mesh/second_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge::test {
namespace {

/// A Tet10 mesh on a linear tet mesh: one new node at the midpoint of every edge.
Tet10Mesh add_mid_nodes(const TetMesh& linear) {
  Tet10Mesh out;
  out.points = linear.points;
  out.regions = linear.regions;
  std::map<std::pair<index_t, index_t>, index_t> mid;
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (index_t t = 0; t < linear.nb_tets(); ++t) {
    const index_t* q = linear.tet(t);
    out.tets10.insert(out.tets10.end(), q, q + 4);
    for (const auto& e : edges) {
      const std::pair<index_t, index_t> key = std::minmax(q[e[0]], q[e[1]]);
      auto it = mid.find(key);
      if (it == mid.end()) {
        const index_t id = static_cast<index_t>(out.points.size() / 3);
        for (int c = 0; c < 3; ++c) {
          out.points.push_back(0.5 *
                               (linear.points[3 * q[e[0]] + c] + linear.points[3 * q[e[1]] + c]));
        }
        it = mid.emplace(key, id).first;
      }
      out.tets10.push_back(it->second);
    }
  }
  return out;
}

MixedMesh one_cell(const std::vector<double>& points, CellType type, std::vector<index_t> verts) {
  MixedMesh mesh;
  mesh.points = points;
  mesh.types = {type};
  mesh.offsets = {0, static_cast<index_t>(verts.size())};
  mesh.cell_vertices = std::move(verts);
  return mesh;
}

/// Every mid node of every quadratic cell sits at the middle of its edge, corners first.
void expect_mid_nodes_on_edges(const MixedMesh& linear, const QuadraticCells& quad,
                               const std::vector<double>& points) {
  ASSERT_EQ(quad.offsets.size(), std::size_t(linear.nb_cells()) + 1);
  for (index_t c = 0; c < linear.nb_cells(); ++c) {
    const CellDescriptor& d = descriptor(linear.types[c]);
    ASSERT_EQ(quad.offsets[c + 1] - quad.offsets[c], index_t(d.nb_vertices + d.nb_edges));
    const index_t* nodes = &quad.nodes[quad.offsets[c]];
    for (int i = 0; i < d.nb_vertices; ++i) EXPECT_EQ(nodes[i], linear.cell(c)[i]);
    for (int e = 0; e < d.nb_edges; ++e) {
      const index_t a = nodes[d.edge[e][0]], b = nodes[d.edge[e][1]], m = nodes[d.nb_vertices + e];
      for (int k = 0; k < 3; ++k) {
        EXPECT_DOUBLE_EQ(points[3 * m + k], 0.5 * (points[3 * a + k] + points[3 * b + k]))
            << d.name << " " << c << " edge " << e;
      }
    }
  }
}

TEST(corner_mesh, keeps_corners_points_and_regions) {
  TetMesh linear = five_tet_grid(2);
  linear.regions.assign(linear.nb_tets(), 4);
  linear.regions[3] = 7;
  const Tet10Mesh tet10 = add_mid_nodes(linear);
  const TetMesh corners = corner_mesh(tet10);
  EXPECT_EQ(corners.tets, linear.tets);
  EXPECT_EQ(corners.points, tet10.points);
  EXPECT_EQ(corners.regions, linear.regions);
  EXPECT_NO_THROW(validate_tet_mesh(corners));
  Tet10Mesh bad = tet10;
  bad.tets10.pop_back();
  EXPECT_THROW(corner_mesh(bad), InputError);
}

TEST(quadratic_cells, tets_give_back_the_tet10_input) {
  const TetMesh linear = kuhn_grid(2);
  const Tet10Mesh tet10 = add_mid_nodes(linear);
  MixedMesh mixed;
  mixed.points = tet10.points;
  mixed.offsets = {0};
  for (index_t t = 0; t < linear.nb_tets(); ++t) {
    mixed.types.push_back(CellType::Tet);
    mixed.cell_vertices.insert(mixed.cell_vertices.end(), linear.tet(t), linear.tet(t) + 4);
    mixed.offsets.push_back(static_cast<index_t>(mixed.cell_vertices.size()));
  }
  const QuadraticCells quad = quadratic_cells(mixed, tet10);
  EXPECT_EQ(quad.nodes, tet10.tets10);
  expect_mid_nodes_on_edges(mixed, quad, tet10.points);
}

TEST(quadratic_cells, merged_cells_reuse_the_mid_nodes) {
  // Hex20 from every triangulation of the cube: each cube edge is an edge of some tet.
  const Polytope cube = unit_cube();
  for (const auto& tets : enumerate_triangulations(cube)) {
    const Tet10Mesh tet10 = add_mid_nodes(polytope_mesh(cube, tets));
    const MixedMesh hex = one_cell(tet10.points, CellType::Hex, {0, 1, 3, 2, 4, 5, 7, 6});
    const QuadraticCells quad = quadratic_cells(hex, tet10);
    expect_mid_nodes_on_edges(hex, quad, tet10.points);
  }
  for (const auto& tets : enumerate_triangulations(unit_prism())) {
    const Tet10Mesh tet10 = add_mid_nodes(polytope_mesh(unit_prism(), tets));
    const MixedMesh prism = one_cell(tet10.points, CellType::Prism, {0, 1, 2, 3, 4, 5});
    expect_mid_nodes_on_edges(prism, quadratic_cells(prism, tet10), tet10.points);
  }
  for (const auto& tets : enumerate_triangulations(square_pyramid())) {
    const Tet10Mesh tet10 = add_mid_nodes(polytope_mesh(square_pyramid(), tets));
    const MixedMesh pyramid = one_cell(tet10.points, CellType::Pyramid, {0, 1, 2, 3, 4});
    expect_mid_nodes_on_edges(pyramid, quadratic_cells(pyramid, tet10), tet10.points);
  }
}

TEST(quadratic_cells, one_edge_with_two_mid_nodes_is_an_input_error) {
  const TetMesh linear = kuhn_grid(1);
  Tet10Mesh tet10 = add_mid_nodes(linear);
  // Tets 0 and 1 share the diagonal 0-7; give tet 1 its own mid node there.
  const index_t extra = static_cast<index_t>(tet10.points.size() / 3);
  tet10.points.insert(tet10.points.end(), {0.5, 0.5, 0.5});
  bool replaced = false;
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int k = 0; k < 6 && !replaced; ++k) {
    const std::pair<index_t, index_t> e =
        std::minmax(tet10.tets10[10 + edges[k][0]], tet10.tets10[10 + edges[k][1]]);
    if (e == std::pair<index_t, index_t>(0, 7)) {
      tet10.tets10[10 + 4 + k] = extra;
      replaced = true;
    }
  }
  ASSERT_TRUE(replaced);
  const MixedMesh hex = one_cell(tet10.points, CellType::Hex, {0, 1, 3, 2, 4, 5, 7, 6});
  try {
    quadratic_cells(hex, tet10);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_LT(e.id(), linear.nb_tets());
    EXPECT_NE(std::string(e.what()).find("two different mid nodes"), std::string::npos) << e.what();
  }
}

void expect_tet10_error(const Tet10Mesh& tet10, const std::string& words) {
  try {
    validate_tet10_mesh(tet10);
    FAIL() << "no InputError for " << words;
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(validate_tet10_mesh, mid_nodes_must_be_distinct_near_their_edges_and_no_corners) {
  const Tet10Mesh good = add_mid_nodes(kuhn_grid(2));
  EXPECT_NO_THROW(validate_tet10_mesh(good));
  {  // every mid node of tet 0 the same node (in every tet, so each edge keeps one mid node)
    Tet10Mesh tet10 = good;
    const std::vector<index_t> mids(tet10.tets10.begin() + 4, tet10.tets10.begin() + 10);
    for (index_t& v : tet10.tets10) {
      if (std::find(mids.begin(), mids.end(), v) != mids.end()) v = mids[0];
    }
    expect_tet10_error(tet10, "is the mid node of two edges");
  }
  {  // one node the mid node of two edges of two tets
    Tet10Mesh tet10 = good;
    index_t other = NO_INDEX;
    for (std::size_t i = 10; i < tet10.tets10.size() && other == NO_INDEX; ++i) {
      const bool in_tet0 = std::find(tet10.tets10.begin() + 4, tet10.tets10.begin() + 10,
                                     tet10.tets10[i]) != tet10.tets10.begin() + 10;
      if (i % 10 >= 4 && !in_tet0) other = tet10.tets10[i];
    }
    const index_t mid = tet10.tets10[4];
    for (index_t& v : tet10.tets10) {
      if (v == mid) v = other;
    }
    expect_tet10_error(tet10, "is the mid node of two edges");
  }
  {  // a mid node 1e6 off its edge
    Tet10Mesh tet10 = good;
    tet10.points[3 * tet10.tets10[7] + 1] += 1e6;
    expect_tet10_error(tet10, "from the edge's midpoint");
  }
  {  // a mid node at the position of an end of its edge (the reader fuzzer's case: -0 for 0)
    Tet10Mesh tet10 = good;
    const index_t end = tet10.tets10[0];  // edge 0 runs from corner 0 to corner 1
    for (int c = 0; c < 3; ++c) tet10.points[3 * tet10.tets10[4] + c] = tet10.points[3 * end + c];
    expect_tet10_error(tet10, "middle half of its edge");
  }
  {  // a mid node that is a corner of another tet
    Tet10Mesh tet10 = good;
    const index_t mid = tet10.tets10[4];
    const index_t corner = tet10.tets10[10 * (tet10.nb_tets() - 1)];
    for (index_t& v : tet10.tets10) {
      if (v == mid) v = corner;
    }
    EXPECT_THROW(validate_tet10_mesh(tet10), InputError);
  }
  {  // a curved edge (the mid node off the chord by a quarter of the edge) passes
    Tet10Mesh tet10 = good;
    tet10.points[3 * tet10.tets10[4] + 2] += 0.25;
    EXPECT_NO_THROW(validate_tet10_mesh(tet10));
  }
}

TEST(quadratic_cells, a_missing_mid_node_is_an_input_error) {
  Tet10Mesh tet10 = add_mid_nodes(kuhn_grid(1));
  tet10.tets10[10 * 2 + 6] = NO_VERTEX;
  const MixedMesh hex = one_cell(tet10.points, CellType::Hex, {0, 1, 3, 2, 4, 5, 7, 6});
  try {
    quadratic_cells(hex, tet10);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_EQ(e.id(), 2u);
  }
}

TEST(quadratic_cells, a_cell_edge_that_no_tet_has_is_an_input_error) {
  const Tet10Mesh tet10 = add_mid_nodes(kuhn_grid(1));
  // Tet (1, 2, 4, 7): edge 1-2 is a face diagonal the Kuhn split does not use.
  MixedMesh mixed = one_cell(tet10.points, CellType::Tet, {1, 2, 4, 7});
  mixed.types.push_back(CellType::Tet);
  mixed.cell_vertices = {0, 1, 3, 7, 1, 2, 4, 7};
  mixed.offsets = {0, 4, 8};
  try {
    quadratic_cells(mixed, tet10);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_EQ(e.id(), 1u);
  }
}

}  // namespace
}  // namespace hexmerge::test
