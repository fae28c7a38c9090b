#pragma once
/// @file
/// How far a tet mesh's boundary nodes are from the CAD faces they lie on (internal header of
/// mesh_shape(); no OpenCASCADE).

#include <vector>

#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge::mesher {

struct Shape;

/// The largest distance of a boundary node of `mesh` (a vertex of a face of one tet) to the
/// surface of its CAD face.
/// @param[in] vertex_face  per vertex, the index of the face it lies on, -1: none (vertices
///                         beyond its size: none)
/// @param[in] tolerance    precision of the projection onto the surface (a length)
/// @throws InputError naming the node when a boundary node lies on no face
double max_boundary_distance(const Shape& shape, const TetMesh& mesh,
                             const std::vector<int>& vertex_face, double tolerance);

}  // namespace hexmerge::mesher
