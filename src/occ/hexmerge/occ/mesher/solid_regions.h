#pragma once
/// @file
/// The solid of each tet of a mesh made from a shape's faces (internal header: includes
/// OpenCASCADE through shape.h).

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::mesher {

struct Surface;

/// The tets' volume (each counted positive; `tets` 4 indices per tet into `points`, x, y, z).
double tets_volume(const std::vector<double>& points, const std::vector<index_t>& tets);

/// Per tet, the index of its solid in shape.solids, from the triangles the tetrahedraliser kept
/// on the shape's faces: the tets connected through faces that are no such triangle are one
/// solid's, and that solid is the one every face they touch bounds (a shared face bounds two).
/// No geometry is evaluated. Nothing when the triangles do not separate the solids (a component
/// touching faces of no single common solid): the caller then classifies by geometry.
/// @param[in] shape      the shape meshed (its solids and faces, glued where they touch)
/// @param[in] mesh       the tets, positively oriented
/// @param[in] triangles  the triangles on the shape's faces (interior ones, between two solids,
///                       included), each with its face's index into shape.faces + 1
std::optional<std::vector<std::int32_t>> solid_regions(
    const Shape& shape, const TetMesh& mesh, const std::vector<std::array<index_t, 3>>& triangles,
    const std::vector<int>& markers);

/// Removes the tets outside the shape: the tets connected through faces that are none of
/// `triangles` (the triangles on the shape's faces) form components, and a component whose
/// largest tet's centroid is not `inside` goes whole. The tetrahedraliser carves the outside
/// away from the convex hull only, so it fills a void the solids enclose (FreeCAD's
/// electrostatics example: a ball less two balls inside it). Points stay (one only removed tets
/// used is left in no tet). Returns the number of tets removed.
std::size_t remove_outside_components(TetMesh& mesh,
                                      const std::vector<std::array<index_t, 3>>& triangles,
                                      const std::function<bool(const Vec3&)>& inside);

/// The tet mesh from the tetrahedraliser's output (frame coordinates): tets oriented positive,
/// points in the world, the surface's nodes at their exact CAD positions, regions by solid
/// (solid_regions(), by geometry where the triangles do not separate the solids: `brep`, the
/// shape as given to regions_by_solid()).
TetMesh world_mesh(const std::string& brep, const Shape& shape, const Surface& surface,
                   const Frame& frame, const tetgen::TetrahedralizeOutput& tets);

}  // namespace hexmerge::mesher
