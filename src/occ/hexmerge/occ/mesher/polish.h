#pragma once
/// @file
/// The tets the recombination will leave, improved after the sliver stage (internal header of
/// mesh_shape(); no OpenCASCADE): the recombination is run once to see which tets its
/// hexahedra, prisms and pyramids take; those stay, and the others get flips and node moves
/// that keep every element that relies on their nodes acceptable.

#include <cstddef>
#include <vector>

#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/occ/mesher/smooth_nodes.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge::mesher {

/// What polish_leftover_tets() did.
struct PolishReport {
  std::size_t elements = 0;             ///< hexahedra, prisms and pyramids the recombination made
  std::size_t below_before = 0;         ///< tets it left under the floor, before
  std::size_t below_after = 0;          ///< and after (the same elements kept)
  std::size_t flips = 0;                ///< flips among the tets it left (2-3, 3-2, 4-4, ...)
  std::size_t inserted_vertices = 0;    ///< vertices inserted into such tets
  std::size_t node_moves = 0;           ///< node moves
  std::size_t boundary_node_moves = 0;  ///< of which along a CAD face or edge
};

/// The recombination's leftover tets raised: recombine() with `recombination` tells which tets
/// make its hexahedra, prisms and pyramids; those tets stay as they are. The others below
/// `floor` get, for a few rounds, flips and vertex insertions (remove_slivers(), among the tets
/// left only, the boundary as it is) and moves of their nodes (smooth_nodes()), a move taken
/// only where every element at the node stays acceptable: its scaled Jacobian at least the
/// recombination's min_scaled_jacobian and down by no more than kPolishDrop, its quad faces
/// folding and their corners opening no further than the recombination accepts (or than they
/// do). The nodes of a near-perfect hexahedron (kBlockHexQuality) or of an element whose quads
/// are planar stay: the recombination's block takes those first. Called again, the
/// recombination has every element it made (its tets as they were, its corners moved only so)
/// and the better tets between them to choose from; where the moves made other candidates
/// better it may choose those. A mesh with no tet under `floor` is left as it is, not
/// recombined. The whole mesh is recombined: recombining the tets within three rings of those
/// under the floor only (a tenth of the time), the selection there differed from the whole
/// mesh's near the cut, and moves broke elements the whole mesh's takes (gmsh_U_Joint_2 at its
/// 250k size: 49.4 -> 43.4 % hex volume).
/// @param[in,out] mesh           the tets (a valid mesh); points may be appended
/// @param[in]     movable        #V NodeMobility values: the nodes that may move and how
///                               (kOnSurface: along `surface`)
/// @param[in,out] surface        the boundary nodes' path (null: they stay)
/// @param[in]     recombination  the parameters recombine() will be called with
/// @param[in]     floor          the scaled Jacobian the leftover tets are raised towards
/// @param[out]    report         see PolishReport
/// @param[in]     progress       the recombination's progress, its phases (empty: none);
///                               false from it cancels (Cancelled)
void polish_leftover_tets(TetMesh& mesh, std::vector<char> movable, SurfacePath* surface,
                          const RecombineParameters& recombination, double floor,
                          PolishReport& report, const ProgressCallback& progress = {});

}  // namespace hexmerge::mesher
