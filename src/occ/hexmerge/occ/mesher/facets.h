#pragma once
/// @file
/// The shape's surface as the facets of a piecewise linear complex for the tetrahedraliser
/// (internal header of mesh_shape(); no OpenCASCADE).

#include <cstddef>
#include <optional>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::mesher {

using tetgen::Facet;

/// The facets: every triangle of the faces that are not lattice faces as it is (kept by the
/// tetrahedraliser); a lattice face as its boundary loops only (with a hole point inside each
/// inner loop), so that nothing but the inserted lattice points decides how it is cut into
/// triangles. A face whose boundary touches itself keeps its triangles. Markers: face index + 1.
/// @param[in] nodes       the surface's nodes in frame coordinates
/// @param[in] face_plane  per face, its plane when normal to a frame axis (every lattice face's)
std::vector<Facet> make_facets(const Surface& surface, const std::vector<Vec3>& nodes,
                               const std::vector<bool>& lattice_face,
                               const std::vector<std::optional<AxisPlane>>& face_plane);

/// The surface's triangles as the tetrahedraliser's boundary will have them, to check them for
/// crossings before it runs: a lattice face's own triangles are placeholders (only its boundary
/// loops go to it), so each lattice face is the constrained Delaunay triangulation of its loops
/// (tetgen::triangulate_facets(), before its lattice points are added); the other faces' triangles
/// as they are. A lattice face that triangulation leaves as it is keeps its triangles. Splitting
/// a lattice face's boundary to a local size bulges it past the placeholders' needles (a half
/// cylinder's foot on gmsh_SampleCrankshaft4A's Face112), which crossed where its loop does not.
/// @param[in] frame  the lattice's frame (the loops are triangulated in its coordinates)
std::vector<SurfaceTriangle> facet_triangles(
    const Surface& surface, const Frame& frame, const std::vector<bool>& lattice_face,
    const std::vector<std::optional<AxisPlane>>& face_plane);

/// Puts the lattice points lying on lattice faces, points[first..], into the facets of those
/// faces: into a boundary loop where they lie on one of its sides (to `tolerance`), else as a
/// polygon of one point where they lie inside.
void add_face_points(std::vector<Facet>& facets, const std::vector<Vec3>& points, std::size_t first,
                     const std::vector<bool>& lattice_face,
                     const std::vector<std::optional<AxisPlane>>& face_plane, double tolerance);

}  // namespace hexmerge::mesher
