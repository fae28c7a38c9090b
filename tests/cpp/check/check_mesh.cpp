#include "hexmerge/check/check_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "fixtures.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge::test {
namespace {

struct Cell {
  CellType type;
  std::vector<index_t> vertices;
  std::vector<index_t> sources;
};

MixedMesh make_mixed(const TetMesh& input, const std::vector<Cell>& cells,
                     const std::vector<std::int32_t>& regions = {}) {
  MixedMesh mesh;
  mesh.points = input.points;
  mesh.offsets = {0};
  mesh.source_offsets = {0};
  for (const Cell& c : cells) {
    mesh.types.push_back(c.type);
    mesh.cell_vertices.insert(mesh.cell_vertices.end(), c.vertices.begin(), c.vertices.end());
    mesh.offsets.push_back(static_cast<index_t>(mesh.cell_vertices.size()));
    mesh.source_tets.insert(mesh.source_tets.end(), c.sources.begin(), c.sources.end());
    mesh.source_offsets.push_back(static_cast<index_t>(mesh.source_tets.size()));
  }
  mesh.regions = regions;
  return mesh;
}

/// Every tet of `input` as a cell of its own.
std::vector<Cell> tets_as_cells(const TetMesh& input) {
  std::vector<Cell> cells;
  for (index_t t = 0; t < input.nb_tets(); ++t) {
    cells.push_back({CellType::Tet, {input.tet(t), input.tet(t) + 4}, {t}});
  }
  return cells;
}

/// A unit cube (corner b at (b & 1, b >> 1 & 1, b >> 2 & 1)) split into Kuhn's 6 tets, a
/// pyramid of 2 tets on its top, a tet on one side of the pyramid: 9 tets, and the matching
/// mixed mesh hex (cell 0) + pyramid (cell 1) + tet (cell 2).
struct HandBuilt {
  TetMesh input;
  std::vector<Cell> cells;
};

HandBuilt hand_built() {
  HandBuilt h;
  h.input = kuhn_grid(1);  // grid_node(1, i, j, k) = i + 2j + 4k: the corner bits
  h.input.points.insert(h.input.points.end(), {0.5, 0.5, 1.5, 1.2, 0.5, 1.3});  // nodes 8, 9
  h.input.tets.insert(h.input.tets.end(), {4, 5, 7, 8, 4, 7, 6, 8, 5, 7, 8, 9});
  orient_positively(h.input);
  h.cells = {{CellType::Hex, {0, 1, 3, 2, 4, 5, 7, 6}, {0, 1, 2, 3, 4, 5}},
             {CellType::Pyramid, {4, 5, 7, 6, 8}, {6, 7}},
             {CellType::Tet, {h.input.tet(8), h.input.tet(8) + 4}, {8}}};
  return h;
}

bool mentions(const CheckReport& r, const std::string& text) {
  return std::any_of(r.problems.begin(), r.problems.end(),
                     [&](const std::string& line) { return line.find(text) != std::string::npos; });
}

std::string all_problems(const CheckReport& r) {
  std::string out;
  for (const auto& line : r.problems) out += line + "\n";
  return out;
}

TEST(check_mesh, passes_a_valid_mixed_mesh) {
  const HandBuilt h = hand_built();
  ASSERT_NO_THROW(validate_tet_mesh(h.input));
  const CheckReport r = check_mesh(make_mixed(h.input, h.cells), h.input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_TRUE(r.problems.empty()) << all_problems(r);
  EXPECT_EQ(r.nb_cells, 3u);
  EXPECT_EQ(r.counts, (std::array<std::size_t, NB_CELL_TYPES>{1, 1, 0, 1}));
  EXPECT_EQ(r.nonconforming_quads, 0u);
  EXPECT_EQ(r.cracks, 0u);
  EXPECT_GT(r.min_scaled_jacobian, 0.0);
  EXPECT_LT(r.worst_cell, 3u);
  EXPECT_NEAR(r.input_volume, total_volume(h.input), 1e-15);
  // Cube 1, pyramid 1/6, tet (5, 7, 8, 9) 1/24.
  EXPECT_NEAR(r.input_volume, 1.0 + 1.0 / 6.0 + 1.0 / 24.0, 1e-12);
  EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);
}

TEST(check_mesh, passes_tet_meshes_against_themselves_and_hex_grids) {
  for (const TetMesh& input : {kuhn_grid(3), five_tet_grid(3)}) {
    const CheckReport r = check_mesh(make_mixed(input, tets_as_cells(input)), input);
    EXPECT_TRUE(r.valid()) << all_problems(r);
    EXPECT_EQ(r.counts[0], input.nb_tets());
    EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);
  }
  // Every cube of the Kuhn grid as one hex (the grid builds tets cube by cube, 6 each).
  const int n = 3;
  const TetMesh input = kuhn_grid(n);
  std::vector<Cell> hexes;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const index_t cube = static_cast<index_t>(i + n * (j + n * k));
        std::vector<index_t> src;
        for (index_t t = 6 * cube; t < 6 * cube + 6; ++t) src.push_back(t);
        hexes.push_back(
            {CellType::Hex,
             {grid_node(n, i, j, k), grid_node(n, i + 1, j, k), grid_node(n, i + 1, j + 1, k),
              grid_node(n, i, j + 1, k), grid_node(n, i, j, k + 1), grid_node(n, i + 1, j, k + 1),
              grid_node(n, i + 1, j + 1, k + 1), grid_node(n, i, j + 1, k + 1)},
             src});
      }
    }
  }
  const CheckReport r = check_mesh(make_mixed(input, hexes), input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.counts[3], std::size_t(n * n * n));
  EXPECT_DOUBLE_EQ(r.min_scaled_jacobian, 1.0);
  EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);
}

TEST(check_mesh, finds_a_crack_where_a_cell_was_removed) {
  const HandBuilt h = hand_built();
  std::vector<Cell> cells = h.cells;
  cells.erase(cells.begin() + 1);  // the pyramid
  const CheckReport r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.cracks, 2u) << all_problems(r);  // the hex's top quad, the tet's face
  EXPECT_TRUE(mentions(r, "hex 0")) << all_problems(r);
  EXPECT_TRUE(mentions(r, "crack")) << all_problems(r);
  EXPECT_LT(r.relative_volume_difference, -0.1);

  // In a tet mesh: one crack per face of the removed tet that is not on the boundary.
  const TetMesh grid = kuhn_grid(2);
  const TetTopology topo(grid);
  for (index_t removed : {index_t(0), index_t(17), index_t(47)}) {
    std::vector<Cell> tets = tets_as_cells(grid);
    tets.erase(tets.begin() + removed);
    std::size_t interior = 0;
    for (int f = 0; f < 4; ++f) interior += !topo.on_boundary(removed, f);
    const CheckReport g = check_mesh(make_mixed(grid, tets), grid);
    EXPECT_EQ(g.cracks, interior) << removed;
    EXPECT_EQ(g.source_errors, 1u) << "input tet " << removed << " belongs to no cell";
    EXPECT_FALSE(g.valid());
  }
}

TEST(check_mesh, finds_an_inverted_cell) {
  const HandBuilt h = hand_built();
  std::vector<Cell> cells = h.cells;
  cells[0].vertices = {4, 5, 7, 6, 0, 1, 3, 2};  // top and bottom swapped: mirrored
  const CheckReport r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.inverted_cells, 1u);
  EXPECT_EQ(r.worst_cell, 0u);
  EXPECT_LT(r.min_scaled_jacobian, 0.0);
  EXPECT_TRUE(mentions(r, "hex 0 is inverted")) << all_problems(r);
  // Its top now faces the same way as the pyramid's base.
  EXPECT_EQ(r.mismatched_faces, 1u);
}

TEST(check_mesh, finds_moved_nodes_and_missing_points) {
  const HandBuilt h = hand_built();
  MixedMesh mesh = make_mixed(h.input, h.cells);
  mesh.points[3 * 5 + 1] += 1e-12;
  CheckReport r = check_mesh(mesh, h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.moved_nodes, 1u);
  EXPECT_TRUE(mentions(r, "node 5 ")) << all_problems(r);

  mesh = make_mixed(h.input, h.cells);
  mesh.points[0] = -0.0;  // equal as numbers, not bitwise
  EXPECT_EQ(check_mesh(mesh, h.input).moved_nodes, 1u);

  mesh = make_mixed(h.input, h.cells);
  mesh.points.insert(mesh.points.end(), {9, 9, 9});
  r = check_mesh(mesh, h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_TRUE(mentions(r, "11 nodes")) << all_problems(r);
}

// --- Declared node changes (MixedMesh::changed_nodes) -------------------------------------------

/// The mesh of `input`'s tets as cells, with no source tets (as a post-merge output has).
MixedMesh unsourced(const TetMesh& tets, const std::vector<double>& points) {
  MixedMesh mesh = make_mixed(tets, tets_as_cells(tets));
  mesh.points = points;
  mesh.source_offsets.clear();
  mesh.source_tets.clear();
  return mesh;
}

/// The unit cube (kuhn_grid(1)) coned from a node 8 at (0.5, 0.5, z) over its boundary
/// triangles: all twelve (`bottom` true; node 8 inside), or all but the two of its face z = 0
/// (node 8 at z = 0: that face is then four triangles at node 8).
TetMesh coned_cube(double z, bool bottom) {
  const TetMesh cube = kuhn_grid(1);
  const TetTopology topology(cube);
  TetMesh coned;
  coned.points = cube.points;
  coned.points.insert(coned.points.end(), {0.5, 0.5, z});
  const auto at_bottom = [&](index_t v) { return cube.points[3 * v + 2] == 0.0; };
  for (index_t t = 0; t < cube.nb_tets(); ++t) {
    for (int f = 0; f < 4; ++f) {
      if (!topology.on_boundary(t, f)) continue;
      std::array<index_t, 3> tri{};
      int n = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != f) tri[n++] = cube.tet(t)[i];
      }
      if (!bottom && at_bottom(tri[0]) && at_bottom(tri[1]) && at_bottom(tri[2])) continue;
      add_tet(coned, tri[0], tri[1], tri[2], 8);
    }
  }
  return coned;
}

TEST(check_mesh, accepts_a_declared_inner_node_move_and_refuses_an_undeclared_one) {
  const TetMesh input = kuhn_grid(2);
  const index_t centre = grid_node(2, 1, 1, 1);
  std::vector<double> points = input.points;
  points[3 * centre] += 0.1;
  points[3 * centre + 2] -= 0.05;
  MixedMesh mesh = unsourced(input, points);
  CheckReport r = check_mesh(mesh, input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.moved_nodes, 1u);
  mesh.changed_nodes = {centre};
  r = check_mesh(mesh, input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.moved_nodes, 0u);
  EXPECT_EQ(r.declared_changed_nodes, 1u);
  EXPECT_EQ(r.volume_not_kept, 0u);
  EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);
}

TEST(check_mesh, a_declared_boundary_node_must_stay_on_the_input_boundary_surface) {
  const TetMesh input = kuhn_grid(2);
  const index_t side = grid_node(2, 1, 1, 0);  // centre of the face z = 0
  // Slid along its face: valid.
  std::vector<double> points = input.points;
  points[3 * side] += 0.2;
  points[3 * side + 1] -= 0.1;
  MixedMesh mesh = unsourced(input, points);
  mesh.changed_nodes = {side};
  CheckReport r = check_mesh(mesh, input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.off_boundary_nodes, 0u);
  // Pushed out of the face: off the surface, and the volume grows.
  points = input.points;
  points[3 * side + 2] -= 0.1;
  mesh = unsourced(input, points);
  mesh.changed_nodes = {side};
  r = check_mesh(mesh, input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.off_boundary_nodes, 1u);
  EXPECT_EQ(r.volume_not_kept, 1u);
  EXPECT_TRUE(mentions(r, "changed node " + std::to_string(side))) << all_problems(r);
  // Pulled inside, by less than the tolerance of its edges (1e-6 of 1): still on the surface.
  points = input.points;
  points[3 * side + 2] += 1e-9;
  mesh = unsourced(input, points);
  mesh.changed_nodes = {side};
  r = check_mesh(mesh, input);
  EXPECT_EQ(r.off_boundary_nodes, 0u) << all_problems(r);
}

TEST(check_mesh, accepts_a_declared_removed_node_and_a_declared_added_node) {
  const TetMesh coned = coned_cube(0.5, true);
  const TetMesh cube = kuhn_grid(1);
  // Removed: the coned cube's centre contracted away, the cube's own 6 tets left.
  MixedMesh mesh = unsourced(cube, coned.points);
  CheckReport r = check_mesh(mesh, coned);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.unused_input_nodes, 1u);
  mesh.changed_nodes = {8};
  r = check_mesh(mesh, coned);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.unused_input_nodes, 0u);
  // Added: the cube's tets coned from a new node 8.
  mesh = unsourced(coned, coned.points);
  r = check_mesh(mesh, cube);
  EXPECT_FALSE(r.valid());
  EXPECT_TRUE(mentions(r, "9 nodes")) << all_problems(r);
  mesh.changed_nodes = {8};
  r = check_mesh(mesh, cube);
  EXPECT_TRUE(r.valid()) << all_problems(r);
}

TEST(check_mesh, new_boundary_triangles_at_an_added_node_must_lie_on_the_input_boundary) {
  // Node 8 added at the centre of the cube's face z = 0: face z = 0 is four triangles at node 8,
  // none of them the input's.
  const TetMesh cube = kuhn_grid(1);
  TetMesh on_face = coned_cube(0.0, false);
  MixedMesh mesh = unsourced(on_face, on_face.points);
  mesh.changed_nodes = {8};
  CheckReport r = check_mesh(mesh, cube);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.cracks, 0u);
  mesh.changed_nodes.clear();  // undeclared: the node count differs and face z = 0 is open
  r = check_mesh(mesh, cube);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.cracks, 4u);
  // The added node lifted into the cube: its four bottom triangles are off the surface.
  TetMesh lifted = coned_cube(0.05, false);
  mesh = unsourced(lifted, lifted.points);
  mesh.changed_nodes = {8};
  r = check_mesh(mesh, cube);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.cracks, 4u);
  EXPECT_EQ(r.volume_not_kept, 1u);
}

TEST(check_mesh, new_boundary_triangles_next_to_a_removed_boundary_node_must_lie_on_the_surface) {
  // The input has node 8 at the centre of face z = 0; the output is the cube's 6 Kuhn tets, node
  // 8 contracted away: its two bottom triangles are new and have no declared node, but nodes
  // next to one.
  const TetMesh input = coned_cube(0.0, false);
  const TetMesh cube = kuhn_grid(1);
  MixedMesh mesh = unsourced(cube, input.points);
  mesh.changed_nodes = {8};
  CheckReport r = check_mesh(mesh, input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.cracks, 0u);
  mesh.changed_nodes.clear();
  r = check_mesh(mesh, input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.unused_input_nodes, 1u);
  EXPECT_EQ(r.cracks, 2u);
}

TEST(check_mesh, refuses_a_faulty_changed_node_list) {
  const TetMesh coned = coned_cube(0.5, true);
  MixedMesh mesh = unsourced(coned, coned.points);
  mesh.changed_nodes = {0};  // declared, not changed: nothing to find
  EXPECT_TRUE(check_mesh(mesh, coned).valid());
  mesh.changed_nodes = {3, 1};
  CheckReport bad = check_mesh(mesh, coned);
  EXPECT_FALSE(bad.valid());
  EXPECT_TRUE(mentions(bad, "out of order")) << all_problems(bad);
  mesh.changed_nodes = {99};
  bad = check_mesh(mesh, coned);
  EXPECT_FALSE(bad.valid());
  EXPECT_TRUE(mentions(bad, "past the nodes")) << all_problems(bad);
}

TEST(check_mesh, counts_a_hex_next_to_tets_as_non_conforming) {
  // Cube (0,0,0) of a 2x2x2 Kuhn grid as a hex, the other seven cubes left as tets: its three
  // inner quads each meet two triangles.
  const TetMesh input = kuhn_grid(2);
  std::vector<Cell> cells = {
      {CellType::Hex,
       {grid_node(2, 0, 0, 0), grid_node(2, 1, 0, 0), grid_node(2, 1, 1, 0), grid_node(2, 0, 1, 0),
        grid_node(2, 0, 0, 1), grid_node(2, 1, 0, 1), grid_node(2, 1, 1, 1), grid_node(2, 0, 1, 1)},
       {0, 1, 2, 3, 4, 5}}};
  const std::vector<Cell> tets = tets_as_cells(input);
  cells.insert(cells.end(), tets.begin() + 6, tets.end());
  const CheckReport r = check_mesh(make_mixed(input, cells), input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.nonconforming_quads, 3u);
  EXPECT_EQ(r.cracks, 0u);
  EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);

  // Either diagonal of the quad will do: in the five-tet grid the neighbours' diagonals
  // alternate.
  const TetMesh five = five_tet_grid(2);
  std::vector<Cell> mixed = {cells[0]};
  mixed[0].sources = {0, 1, 2, 3, 4};
  const std::vector<Cell> five_tets = tets_as_cells(five);
  mixed.insert(mixed.end(), five_tets.begin() + 5, five_tets.end());
  const CheckReport f = check_mesh(make_mixed(five, mixed), five);
  EXPECT_EQ(f.nonconforming_quads, 3u) << all_problems(f);
  EXPECT_TRUE(f.valid()) << all_problems(f);
}

TEST(check_mesh, counts_a_quad_against_a_triangle_and_half_a_quad_as_non_conforming) {
  // In the plane z = 0: above, a pyramid on the square 0-1-2-3 and a tet on 2-4-3; below, a
  // pyramid on the parallelogram 0-2-4-3 and a tet on 0-1-2. The square's halves on diagonal
  // 0-2 are the lower tet's triangle and half of the parallelogram, and vice versa.
  TetMesh input = make_tet_mesh(
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 2, 0}, {0.5, 0.5, 1}, {0.5, 1, -1}},
      {{0, 1, 2, 5}, {0, 2, 3, 5}, {2, 4, 3, 5}, {0, 2, 3, 6}, {2, 4, 3, 6}, {0, 1, 2, 6}});
  orient_positively(input);
  ASSERT_NO_THROW(validate_tet_mesh(input));
  const std::vector<Cell> cells = {{CellType::Pyramid, {0, 1, 2, 3, 5}, {0, 1}},
                                   {CellType::Tet, {input.tet(2), input.tet(2) + 4}, {2}},
                                   {CellType::Pyramid, {0, 3, 4, 2, 6}, {3, 4}},
                                   {CellType::Tet, {input.tet(5), input.tet(5) + 4}, {5}}};
  const CheckReport r = check_mesh(make_mixed(input, cells), input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.inverted_cells, 0u);
  EXPECT_EQ(r.nonconforming_quads, 2u) << all_problems(r);
  EXPECT_EQ(r.cracks, 0u) << all_problems(r);
  EXPECT_LT(std::abs(r.relative_volume_difference), 1e-14);
  // Without the upper tet, half of the parallelogram is open (a crack), as is the upper
  // pyramid's face that met the tet; the square is still covered.
  std::vector<Cell> holed = cells;
  holed.erase(holed.begin() + 1);
  const CheckReport h = check_mesh(make_mixed(input, holed), input);
  EXPECT_EQ(h.nonconforming_quads, 1u) << all_problems(h);
  EXPECT_EQ(h.cracks, 2u) << all_problems(h);
  EXPECT_TRUE(mentions(h, "quad (0 2 4 3) of pyramid 1")) << all_problems(h);
}

TEST(check_mesh, finds_faces_shared_by_three_cells) {
  const HandBuilt h = hand_built();
  std::vector<Cell> cells = h.cells;
  cells.push_back(cells[2]);  // the tet twice
  const CheckReport r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.overshared_faces, 1u) << all_problems(r);  // its face on the pyramid
  EXPECT_EQ(r.mismatched_faces, 3u) << all_problems(r);  // its boundary faces, doubled
  EXPECT_TRUE(mentions(r, "tet 2")) << all_problems(r);
  EXPECT_TRUE(mentions(r, "tet 3")) << all_problems(r);
}

TEST(check_mesh, finds_region_mismatches) {
  HandBuilt h = hand_built();
  h.input.regions = {1, 1, 1, 1, 1, 1, 2, 2, 2};
  EXPECT_TRUE(check_mesh(make_mixed(h.input, h.cells, {1, 2, 2}), h.input).valid());
  const CheckReport r = check_mesh(make_mixed(h.input, h.cells, {1, 2, 1}), h.input);
  EXPECT_FALSE(r.valid());
  EXPECT_EQ(r.region_mismatches, 1u);
  EXPECT_TRUE(mentions(r, "cell 2")) << all_problems(r);
  // A cell spanning two regions cannot match both.
  std::vector<Cell> cells = h.cells;
  cells[1].sources = {6, 8};
  cells[2].sources = {7};
  EXPECT_EQ(check_mesh(make_mixed(h.input, cells, {1, 2, 2}), h.input).region_mismatches, 0u);
  h.input.regions[8] = 3;
  EXPECT_GE(check_mesh(make_mixed(h.input, cells, {1, 2, 3}), h.input).region_mismatches, 1u);
}

TEST(check_mesh, a_bent_quad_between_two_regions_is_split_as_the_input_splits_it) {
  // Two layers of cubes, five tets each (the split alternating, so half the quads between the
  // layers are split off their least corner), one region per layer, the node in the middle of
  // the interface raised: its four quads are bent. As hexahedra, with a declared (unmoved) node,
  // each region keeps its volume only where the checker splits those quads as the tets do.
  const int n = 2;
  TetMesh input = five_tet_grid(n);
  const index_t middle = grid_node(n, 1, 1, 1);
  input.points[3 * middle + 2] += 0.15;
  ASSERT_NO_THROW(validate_tet_mesh(input));
  for (index_t t = 0; t < input.nb_tets(); ++t) {
    double z = 0;
    for (int i = 0; i < 4; ++i) z += input.point(input.tet(t)[i])[2] / 4;
    input.regions.push_back(z < 1 ? 1 : 2);
  }
  std::vector<Cell> hexes;
  std::vector<std::int32_t> regions;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        hexes.push_back(
            {CellType::Hex,
             {grid_node(n, i, j, k), grid_node(n, i + 1, j, k), grid_node(n, i + 1, j + 1, k),
              grid_node(n, i, j + 1, k), grid_node(n, i, j, k + 1), grid_node(n, i + 1, j, k + 1),
              grid_node(n, i + 1, j + 1, k + 1), grid_node(n, i, j + 1, k + 1)},
             {}});
        regions.push_back(k + 1);
      }
    }
  }
  MixedMesh mesh = make_mixed(input, hexes, regions);
  mesh.source_offsets.clear();
  mesh.changed_nodes = {middle};
  const CheckReport r = check_mesh(mesh, input);
  EXPECT_TRUE(r.valid()) << all_problems(r);
  EXPECT_EQ(r.volume_not_kept, 0u);
  EXPECT_LT(r.linear_volume_difference, 1e-12);
}

TEST(check_mesh, finds_unused_nodes_and_foreign_corners) {
  const HandBuilt h = hand_built();
  std::vector<Cell> cells = h.cells;
  cells.pop_back();  // node 9 was used by this tet only
  CheckReport r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_EQ(r.unused_input_nodes, 1u);
  EXPECT_TRUE(mentions(r, "input node 9")) << all_problems(r);
  EXPECT_EQ(r.cracks, 1u) << all_problems(r);  // the pyramid's face that met the tet
  EXPECT_FALSE(r.valid());

  // A cell whose corners are not its source tets' corners.
  cells = h.cells;
  std::swap(cells[1].sources, cells[2].sources);
  r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_EQ(r.source_errors, 2u) << all_problems(r);
  EXPECT_FALSE(r.valid());
}

TEST(check_mesh, survives_malformed_cells) {
  const HandBuilt h = hand_built();
  std::vector<Cell> cells = h.cells;
  cells[2].vertices[1] = 99;
  CheckReport r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_EQ(r.malformed_cells, 1u);
  EXPECT_FALSE(r.valid());
  EXPECT_TRUE(mentions(r, "99")) << all_problems(r);
  cells = h.cells;
  cells[0].vertices.pop_back();
  r = check_mesh(make_mixed(h.input, cells), h.input);
  EXPECT_EQ(r.malformed_cells, 1u);
  EXPECT_FALSE(r.valid());
  MixedMesh broken = make_mixed(h.input, h.cells);
  broken.offsets.pop_back();
  EXPECT_FALSE(check_mesh(broken, h.input).valid());
}

TEST(check_mesh, keeps_problem_lists_short) {
  const TetMesh grid = kuhn_grid(4);
  std::vector<Cell> tets = tets_as_cells(grid);
  std::vector<Cell> half(tets.begin(), tets.begin() + tets.size() / 2);
  const CheckReport r = check_mesh(make_mixed(grid, half), grid);
  EXPECT_GT(r.cracks, kMaxProblemsPerKind);
  std::size_t crack_lines = 0;
  for (const auto& line : r.problems) crack_lines += line.find("crack") != std::string::npos;
  EXPECT_EQ(crack_lines, kMaxProblemsPerKind);
  EXPECT_TRUE(mentions(r, "more of the same kind"));
}

}  // namespace
}  // namespace hexmerge::test
