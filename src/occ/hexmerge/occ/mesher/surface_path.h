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
/// them on that face) whose nodes are not kept: its surface, from the node's parameters on it
/// (nodes numbered as `surface`'s; the mesh's other vertices are held by none). Nodes inside one
/// CAD edge (on its sides only, between its ends) that is not kept and bounds no kept face: its
/// curve.
/// @param[in] kept_face  per face, whether its nodes stay (lattice faces: on the lattice; faces
///                       with a local size: their sides at most the size; face layers: their
///                       points along the nodes' normals; faces between two solids)
/// @param[in] kept_edge  per edge, whether its nodes stay (a local size on it)
/// @param[in] tolerance  a face node whose parameters are further than this from it (a repair
///                       moved it) gets them again by projection, or stays
std::unique_ptr<SurfacePath> boundary_path(const Shape& shape, const Surface& surface,
                                           const std::vector<bool>& kept_face,
                                           const std::vector<bool>& kept_edge, double tolerance);

}  // namespace hexmerge::mesher
