#pragma once
/// @file
/// Quality of the tets after TetGen (internal header of mesh_shape(); no OpenCASCADE): flips
/// (remove_slivers) alternating with moves of the free nodes (smooth_nodes), neither ever
/// lowering the smallest scaled Jacobian, the lattice's own tets kept for the hexahedra.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/occ/mesher/smooth_nodes.h"

namespace hexmerge::mesher {

/// What improve_tets() did.
struct ImproveReport {
  double min_quality_before = 0.0;      ///< smallest scaled Jacobian before the first flips
  std::size_t face_flips = 0;           ///< 2-3 flips
  std::size_t edge_flips = 0;           ///< edge removals (3-2, 4-4, ...)
  std::size_t boundary_swaps = 0;       ///< of which on the boundary, inside one CAD face
  std::size_t node_moves = 0;           ///< moves of free nodes
  std::size_t boundary_node_moves = 0;  ///< of those, of boundary nodes along a CAD face or edge
  std::size_t inserted_vertices = 0;    ///< vertices inserted into tets no flip improved
  std::size_t released_cells = 0;       ///< kept cells released (ImproveParameters::kept_cells)
  /// lattice points inside a lattice face, corners of no core cell, released with the cells to
  /// move along the face's plane (ImproveParameters::surface)
  std::size_t released_face_points = 0;
  /// cells (lattice cells, buffer hexahedra) with a face nothing closes, split into six pyramids
  /// to their centre (split_open_cells())
  std::size_t split_open_cells = 0;
};

/// How improve_tets() works.
struct ImproveParameters {
  std::array<double, 3> spacing{};           ///< the lattice's spacing per frame axis
  std::array<std::vector<double>, 3> ticks;  ///< its planes on rectilinear axes (Lattice::ticks)
  int sweep_axis = -1;  ///< swept: the tets within one slab stay; -1: not swept
  /// Vertices below this index (the surface's nodes) move only along `surface`.
  std::size_t nb_surface_nodes = 0;
  /// Boundary triangles of one CAD face may swap their side where the boundary moves by no more
  /// than this (the surface's chord deflection).
  double max_boundary_shift = 0.0;
  /// The boundary nodes that may move along their CAD face or edge, and where (null: none; swept:
  /// none move); with it, the lattice points inside a lattice face that are corners of no core
  /// cell move along the face's plane once released (at a tet under insert_below after the fourth
  /// or the last round). They move while a tet at them is below 0.2, no more of their tets below
  /// it and their boundary triangles' smallest angle kept (or above 10 degrees).
  SurfacePath* surface = nullptr;
  /// A tet below this scaled Jacobian that no flip improves gets a vertex inside
  /// (RemoveSliversParameters::insert_below); 0: never.
  double insert_below = 0.0;
  /// The cell centres' closing pyramids (all of whose tets are the lattice's) keep this scaled
  /// Jacobian when their apex is nudged (SmoothNodesParameters::pyramid_floor): the
  /// recombination's min_scaled_jacobian, so that they and the core cells' hexahedra they close
  /// stay. In (0, 1].
  double pyramid_floor = 0.3;
  /// Cells whose tets stay as they are and whose vertices do not move, by their vertices (the
  /// buffer layer's hexahedra and pyramids: buffer_layer()), until a tet under insert_below
  /// outside them touches one after a round's flips: then it is released.
  std::vector<std::vector<index_t>> kept_cells;
};

/// The closing pyramids at some cell centres: at each vertex v with `apex_of[v]` (a lattice cell's
/// centre), the faces of its cell split into two tets of the mesh that join v to three of the
/// face's four corners. Base in cell_type.h's order (around the face), apex v, positively
/// oriented.
/// @param[in] mesh     the tets
/// @param[in] cell_of  their vertices' frame coordinates in cells (lattice points whole), at
///                     least the first apex_of.size()
/// @param[in] apex_of  per vertex (the first ones, the others not): whether it may be an apex
std::vector<std::array<index_t, 5>> closing_pyramids(
    const TetMesh& mesh, const std::vector<std::array<double, 3>>& cell_of,
    const std::vector<char>& apex_of);

/// Flips take out slivers, then the free nodes (not on the surface, not on the half lattice,
/// not in a swept mesh; the boundary nodes along their CAD face or edge, `surface`) move to raise
/// the worst tet around them, then flips again, for 8 rounds of flips (a ninth where kept cells
/// or lattice faces' points were released beside tets under insert_below after the eighth, the
/// points after the fourth too: ImproveParameters::kept_cells, surface). Tets within one lattice
/// cell or closing pyramid (all corners on the half lattice, within one cell's width), or swept
/// within one slab, stay as they are.
/// @param[in,out] mesh           the tets (coordinates in the world)
/// @param[in]     frame_points   #vertices by 3: the vertices in frame coordinates (lattice at
///                               multiples of the spacing)
/// @param[in]     boundary       the boundary triangles and, per triangle, its CAD face
///                (boundary_face); their vertices move along `surface` only
void improve_tets(TetMesh& mesh, const std::vector<double>& frame_points,
                  const std::vector<std::array<index_t, 3>>& boundary,
                  const std::vector<std::int32_t>& boundary_face,
                  const ImproveParameters& parameters, ImproveReport& report);

}  // namespace hexmerge::mesher
