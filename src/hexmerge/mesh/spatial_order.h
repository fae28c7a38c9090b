#pragma once
/// @file
/// Tets renumbered along a space-filling curve, so that tets close in space get close ids.
///
/// Mesh generators may number tets with little locality (Gmsh's Delaunay meshes put face
/// neighbours about 10^4 ids apart): a search that walks the adjacency then misses the cache at
/// nearly every step. Running it on a renumbered copy, and mapping its results back, keeps the
/// walk in cache.

#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// The tets in Morton (Z-curve) order of their centroids in the mesh's bounding box, on a grid
/// of about #T / 4 cells; tets in one cell in id order. Deterministic.
/// @return #T ids: position i holds the tet that goes to position i
std::vector<index_t> spatial_order(const TetMesh& mesh);

/// The mesh with its tets (and their regions) permuted: tet i of the result is tet order[i] of
/// `mesh`, with the same vertices in the same local order. Points are copied unchanged.
/// @param[in] order  a permutation of the tet ids (spatial_order)
TetMesh reorder_tets(const TetMesh& mesh, const std::vector<index_t>& order);

}  // namespace hexmerge
