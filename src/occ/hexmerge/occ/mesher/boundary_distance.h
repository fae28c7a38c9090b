#pragma once
/// @file
/// How far a tet mesh's boundary nodes are from the CAD faces they lie on (internal header of
/// mesh_shape(); no OpenCASCADE).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge::mesher {

struct Shape;

/// Per point of a tet mesh of `nb_points` points, the index of the CAD face it lies on:
/// `given_face` for the points given to the tetrahedraliser (the first ones), -1 for the others
/// but those on the boundary, on a segment it split where it could not recover it otherwise
/// (TetGen, -Y notwithstanding), which take the face of a boundary triangle at them (its facet
/// marker less one).
std::vector<int> point_faces(std::vector<int> given_face, std::size_t nb_points,
                             const std::vector<std::array<index_t, 3>>& boundary,
                             const std::vector<int>& boundary_marker);

/// Per vertex of a mesh of `nb_vertices`, the CAD faces it lies on: its own (`vertex_face`, when
/// >= 0; beyond its size: none), then those of the boundary triangles at it (`boundary_face`,
/// when >= 0), each once, in that order.
std::vector<std::vector<int>> vertex_faces(std::size_t nb_vertices,
                                           const std::vector<int>& vertex_face,
                                           const std::vector<std::array<index_t, 3>>& boundary,
                                           const std::vector<std::int32_t>& boundary_face);

/// The largest distance of a boundary node of `mesh` (a vertex of a face of one tet) to the
/// surface of its CAD face, or where it is further from that than 100 tolerances, to the
/// nearest of that face and `other_faces`.
/// @param[in] vertex_face  per vertex, the index of the face it lies on, -1: none (vertices
///                         beyond its size: none)
/// @param[in] tolerance    precision of the projection onto the surface (a length)
/// @param[in] other_faces  per vertex (or empty), other faces it may lie on: vertex_faces() (a
///                         swept profile's node inside a fillet's arc took the face of the plane
///                         beside it, 0.129 mm off, where it lies on the fillet)
/// @throws InputError naming the node when a boundary node lies on no face
double max_boundary_distance(const Shape& shape, const TetMesh& mesh,
                             const std::vector<int>& vertex_face, double tolerance,
                             const std::vector<std::vector<int>>& other_faces = {});

}  // namespace hexmerge::mesher
