#pragma once
/// @file
/// Second-order (quadratic) meshes: split a Tet10 mesh into its corner mesh, and rebuild
/// quadratic cells on a linear mixed mesh from the input's mid-edge nodes.

#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/mixed_mesh.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// A Tet10 mesh: tet t has nodes tets10[10t .. 10t+9] in VTK order: corners 0-3, then the
/// mid-edge nodes of edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3).
struct Tet10Mesh {
  std::vector<double> points;
  std::vector<index_t> tets10;
  std::vector<std::int32_t> regions;
  index_t nb_tets() const { return static_cast<index_t>(tets10.size() / 10); }
};

/// The linear mesh on the corner nodes of a Tet10 mesh (same points, same ids, same regions;
/// the mid-edge nodes stay in `points`, unused). Throws InputError when the array sizes do not
/// match (points not by 3, tets10 not by 10, regions not one per tet).
TetMesh corner_mesh(const Tet10Mesh& mesh);

/// Throws InputError (Entity::Element, naming the tet and the node) when the mid-edge nodes of a
/// Tet10 mesh disagree with themselves: an id out of range, an edge with two mid nodes, a node
/// that is the mid node of two edges or also a corner, or a mid node outside the middle half of
/// its edge (along it) or further from its midpoint than half the edge's length (curved edges up
/// to a half circle pass).
void validate_tet10_mesh(const Tet10Mesh& mesh);

/// Quadratic cells of a mixed mesh: cell c has nodes nodes[offsets[c] .. offsets[c+1]): its
/// corners in linear order, then one mid-edge node per edge in the order of cell_type.h
/// (VTK's quadratic order: Tet10, Pyramid13, Wedge15, Hexahedron20).
struct QuadraticCells {
  std::vector<index_t> offsets;
  std::vector<index_t> nodes;
};

/// Rebuilds quadratic cells from the input's mid-edge nodes: every edge of a merged cell is an
/// edge of one of its tets, so its mid-edge node exists. Throws InputError (Entity::Element)
/// when the Tet10 mesh disagrees with itself (one edge with two different mid nodes; names a
/// tet), when a tet's node is missing (id out of range or NO_VERTEX) or a corner doubles as a
/// mid node (names the tet), or when a cell of `linear` has an edge that no tet has (names the
/// cell). Runs in O(#T log #T).
/// @param[in] linear  mixed mesh on the corner nodes of `input` (e.g. from recombine)
/// @param[in] input   the Tet10 mesh whose corner mesh `linear` was made from
QuadraticCells quadratic_cells(const MixedMesh& linear, const Tet10Mesh& input);

}  // namespace hexmerge
