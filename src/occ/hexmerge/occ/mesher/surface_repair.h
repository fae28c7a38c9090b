#pragma once
/// @file
/// The surface triangulation brought to the target size and cleaned (internal header of
/// mesh_shape(); no OpenCASCADE): refinement by longest-side bisection with Delaunay flips and
/// needle smoothing, collapse of short sides.

#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;
class SizeField;

/// Splits the triangles of the faces that are not lattice faces until no side is longer than
/// `target` (sides on edges between lattice faces excepted) and no triangle whose shortest side
/// lies on a CAD edge has a side over three times longer (down to a fifth of the size wanted:
/// BRepMesh's strips between finely divided edges, whose small angles no tet on them gets
/// over); lattice-face triangles are split
/// only where a neighbour's side must be, and on a seam between lattice faces on one plane
/// (no lattice point comes onto it). New nodes lie on the CAD edge (sides on an edge) or on
/// the face's surface. Then needles are smoothed on their face and the Delaunay flips redone.
/// @param[in] lattice_face  per face, whether it is a lattice face (planar, on a lattice plane)
/// @param[in] lattice_edge  per edge, whether every face it bounds is a lattice face
/// @param[in] field  local sizes (null: none): a side is split to the smaller of the sizes the
///                   field gives at its ends, lattice faces' sides on CAD edges too
/// A face whose refinement adds far more nodes than its area needs (it is not converging) is
/// left as it is then, and listed in Surface::unrefined_faces.
/// @param[in] deflection  no flip or node move takes a triangle's centroid further than this
///                        from its face (or further than the triangles it replaces were);
///                        infinity: no bound
/// @param[in] deflection_field  where it is finer than `target`, the deflection shrinks with it
///                              (null: the deflection everywhere)
void refine(const Shape& s, Surface& surface, double target, double deflection,
            const std::vector<bool>& lattice_face, const std::vector<bool>& lattice_edge,
            const SizeField* field = nullptr, const SizeField* deflection_field = nullptr);

/// Collapses the sides of needles and caps (an angle under 5 degrees) and the short sides (under
/// target / 4) inside a face (not on a CAD edge, not on a lattice face) where no triangle gets
/// worse and no side gets longer than `max_side`; the removed nodes are dropped, the rest
/// renumbered, and Surface::seed gives each node's index before. With local sizes (`field`),
/// `target` and `max_side` shrink with the size the field gives at the side's nodes. No
/// collapse takes a triangle's centroid further than `deflection` from its face of `s` (or
/// further than the triangles it replaces were; infinity: no bound), less where
/// `deflection_field` is finer than `target` (as in refine()).
void collapse_sides(const Shape& s, Surface& surface, double target, double max_side,
                    double deflection, const std::vector<bool>& lattice_face,
                    const SizeField* field = nullptr, const SizeField* deflection_field = nullptr);

}  // namespace hexmerge::mesher
