#pragma once
/// @file
/// A face's triangles that fold over each other, triangulated anew (internal header of
/// mesh_shape(); no OpenCASCADE).
///
/// BRepMesh triangulates a face in its parameters. Where they collapse to a point (a sphere's
/// pole, a cone's apex) near the face's outline, its triangles there can overlap in space: a
/// random part's fused sphere (radius 1.74 h), its pole 0.3 h from a rib's edge, had the fan
/// round the pole cover a third of the turn and two triangles from the outline cover the rest,
/// one of them across the fan; the repairs could not part them, and every way of placing the
/// points failed at sizes from 0.92 h to 1.07 h of the one asked.

#include <cstddef>

#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

/// Passes over the face's triangles (about a ring each) that unfold_faces() grows a fold by at
/// most.
inline constexpr int kUnfoldRings = 4;

/// What unfold_faces() did.
struct UnfoldReport {
  std::size_t patches = 0;  ///< patches triangulated anew
  std::size_t failed = 0;   ///< folds left as they were (no patch up to kUnfoldRings passes did)
};

/// Per face whose triangles cross each other (find_crossings()' exact test) or fold on a common
/// side (normals more than 150 degrees apart), each fold (its folded triangles joined by their
/// nodes) is grown by passes over the face's triangles (each takes in those touching the patch,
/// about a ring), up to kUnfoldRings, until it can be
/// triangulated anew in the plane across its other triangles' mean normal: the constrained
/// Delaunay triangulation of its nodes, its outline (a single loop, simple and turning
/// counter-clockwise in that plane) and the CAD edges' segments inside it (a seam) kept. Taken
/// when no new triangle turns from that normal by 80 degrees or more, none is flat, none folds on
/// a side with its neighbours and none crosses a triangle of the surface outside the patch; every
/// node stays. Where no patch qualifies the fold stays (the surface check after the repairs names
/// it).
UnfoldReport unfold_faces(Surface& surface);

}  // namespace hexmerge::mesher
