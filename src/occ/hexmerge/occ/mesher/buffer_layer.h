#pragma once
/// @file
/// The buffer layer (internal header of mesh_shape(); no OpenCASCADE): hexahedra between the
/// core's closing pyramids' bases and the surface. Each base's corners are projected onto the
/// nearest CAD face, and that face is triangulated again with the projected quads in it, so
/// that the hexahedron's top is two of its boundary triangles (Schneiders, "A grid-based
/// algorithm for the generation of hexahedral element meshes", Engineering with Computers 12,
/// 1996: the core's boundary quads projected onto the surface).

#include <cstddef>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;

/// What buffer_layer() made.
struct BufferReport {
  std::size_t nb_hexes = 0;     ///< hexahedra between the core and the surface
  std::size_t nb_pyramids = 0;  ///< pyramids closing their side faces
  std::size_t nb_faces = 0;     ///< CAD faces triangulated again with the hexahedra's tops
  std::vector<int> faces;       ///< those faces (0-based)
  BufferBaseCounts bases;       ///< why each base got a hexahedron or not
};

/// The hexahedra between the core's closing pyramids' bases and the surface, and the surface
/// with their tops. A base gets one where its pyramid's apex closes no other base; its four
/// corners project onto one face (`eligible`: per face, whether it may take tops: no lattice
/// face, no face with a local size or face layers, none between two solids), each at least
/// 0.15 h and at most 1.5 h away, within 35 degrees of the base's normal, at least 0.3 h inside
/// the face's edges; the hexahedron keeps scaled Jacobian 0.3. A side face that no other
/// hexahedron shares is closed by a pyramid to the apex of the core's pyramid across that side of
/// the base (scaled Jacobian 0.4), or the hexahedron goes. Each face with tops is triangulated
/// again, constrained Delaunay in its parameters scaled by their mean metric: its nodes on its
/// edges and those clear of the tops kept, the tops' quads split on their diagonal from the top
/// of the base's least corner. A face where that fails (a quad across its seam or edges, a
/// triangle flatter than the face had, the area changed) keeps its triangles and gets no tops.
/// Last, a hexahedron or side pyramid whose faces cross the surface, each other or the core's
/// pyramids beside them, or that holds a surface node or a point of the core, goes (and with it
/// the side pyramids it needs), and the faces are triangulated again without it.
/// @param[in]     nodes    the surface's nodes in frame coordinates (those `around` holds)
/// @param[in,out] surface  the faces with tops triangulated again (world coordinates)
/// @return the cells (frame coordinates); none where the layer found no room
BufferCells buffer_layer(const Shape& shape, const Lattice& lattice, const CoreLayout& layout,
                         const std::vector<Vec3>& nodes, const Surroundings& around,
                         const std::vector<char>& eligible, double h, Surface& surface,
                         BufferReport& report);

}  // namespace hexmerge::mesher
