#pragma once
/// @file
/// The CAD faces as the path of the boundary nodes that smooth_nodes() moves along them
/// (internal header of mesh_shape(); no OpenCASCADE).

#include <memory>
#include <vector>

#include "hexmerge/occ/mesher/smooth_nodes.h"

namespace hexmerge::mesher {

struct Shape;
struct Surface;

/// The path of the surface's nodes that lie inside one face (on no CAD edge, every triangle at
/// them on that face) that is not a lattice face: its surface, from the node's parameters on it
/// (nodes numbered as `surface`'s; the mesh's other vertices are held by none).
/// Nodes inside one CAD edge (on its sides only, between its ends), where the edge bounds no
/// lattice face: its curve.
/// @param[in] lattice_face  per face, whether it is a lattice face (its nodes stay on the lattice)
/// @param[in] tolerance     a face node whose parameters are further than this from it (a repair
///                          moved it) gets them again by projection, or stays
std::unique_ptr<SurfacePath> boundary_path(const Shape& shape, const Surface& surface,
                                           const std::vector<bool>& lattice_face, double tolerance);

}  // namespace hexmerge::mesher
