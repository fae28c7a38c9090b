#pragma once
/// @file
/// Second-order tets on the CAD: a mid node on every edge, the boundary ones on the CAD face or
/// edge the edge lies on (internal header of mesh_shape(); no OpenCASCADE).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hexmerge/mesh/second_order.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge::mesher {

struct Shape;

/// What second_order_mesh() did.
struct SecondOrderReport {
  /// boundary mid nodes projected onto their CAD face or edge (on a plane: the midpoint itself)
  std::size_t nb_projected = 0;
  /// Boundary mid nodes kept at their edge's midpoint: on the CAD they would have made a Tet10's
  /// Jacobian at a corner non-positive or left the middle half of their edge
  std::size_t nb_straight = 0;
};

/// The Tet10 mesh of `mesh` (VTK order, see Tet10Mesh), its mid nodes numbered after the
/// corners by edge (smaller node id first, in increasing order). Mid nodes of edges inside the
/// mesh are the edges' midpoints; those of boundary edges are the midpoints projected on the CAD
/// face of the boundary triangles around the edge, or, where these lie on two faces, on the CAD
/// edge between them, unless that would make the Jacobian of a tet around the edge at one of its
/// corners non-positive or put the node outside the middle half of its edge (or further than
/// half the edge's length off it): such nodes stay at the midpoint and are counted.
/// @param[in] vertex_face    per vertex, a face it lies on, -1: none (beyond its size: none)
/// @param[in] boundary       TetGen's boundary triangles, with boundary_face: per triangle, its
///                           CAD face (the final boundary differs only by swaps inside a face)
/// @param[in] tolerance      precision of the projections (a length)
Tet10Mesh second_order_mesh(const Shape& shape, const TetMesh& mesh,
                            const std::vector<int>& vertex_face,
                            const std::vector<std::array<index_t, 3>>& boundary,
                            const std::vector<std::int32_t>& boundary_face, double tolerance,
                            SecondOrderReport& report);

}  // namespace hexmerge::mesher
