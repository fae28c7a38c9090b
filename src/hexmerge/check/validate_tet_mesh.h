#pragma once
/// @file
/// The input check of a tet mesh: everything the engine cannot process, named.

#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// Smallest scaled Jacobian of an input tet (scale-free): below it a tet is flat to round-off,
/// its orientation noise.
constexpr double kMinInputScaledJacobian = 1e-12;

/// Checks a TetMesh for everything the engine cannot process and throws InputError naming the
/// first node or element at fault: an empty mesh, array sizes that do not match, NaN or infinite
/// coordinates, vertex ids out of range, a tet with a repeated vertex, an inverted or zero-volume
/// tet, a tet flat to round-off (scaled Jacobian <= kMinInputScaledJacobian), two tets on the
/// same four vertices. (Faces shared by three or more tets and folded tets, two on the same side
/// of their shared face, are found by TetTopology.) The mesh is never modified.
void validate_tet_mesh(const TetMesh& mesh);

}  // namespace hexmerge
