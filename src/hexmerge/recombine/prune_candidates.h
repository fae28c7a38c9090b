#pragma once
/// @file
/// Conformity as a property of the candidates: the elements with quad faces that no conforming
/// selection can hold.

#include <cstddef>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"

namespace hexmerge {

/// The candidates without the hexahedra, prisms and pyramids that cannot be part of any
/// conforming selection, and how many were removed.
///
/// In a conforming mesh every quad face of an element lies on the domain boundary (both of its
/// triangles), or is the quad face of another element on its other side: a pyramid on it as base,
/// or a hexahedron, prism or pyramid that can itself be part of a conforming mesh. The removed set
/// is the greatest fixpoint of that condition: a candidate goes when one of its quad faces has
/// neither, and the elements that counted on it are looked at again. It is a necessary condition
/// only (two closers may still need the same tet), so the selection keeps its own checks; what it
/// saves the selection is choosing elements, like hexes that chain into a structured region from
/// an unstructured one, that can only end up released.
/// The candidates are taken by value and the kept ones returned in their storage (pass them with
/// std::move when the caller no longer needs them: no second array is made).
/// @param[in] threads  worker threads (>= 1); the result does not depend on them
Candidates prune_unclosable(const TetMesh& mesh, const TetTopology& topology, Candidates candidates,
                            std::size_t& removed, int threads = 1);

}  // namespace hexmerge
