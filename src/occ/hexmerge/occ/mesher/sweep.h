#pragma once
/// @file
/// Swept shapes (internal header of mesh_shape(); no OpenCASCADE). A solid that is a profile
/// extruded along a lattice axis gets a mesh that is extruded too: its walls are triangulated in
/// strips between consecutive lattice planes, with the same nodes (stations) on every plane, so
/// that the layers, the lattice points and TetGen's tets repeat from one plane to the next. Every
/// tet then lies in a slab between two planes, the tets of a slab form prisms over the
/// cross-section's triangles, and two prisms over triangles that make a good quad form a
/// hexahedron: the transition between the lattice core and the boundary layers recombines too,
/// with no closing pyramids.

#include <array>
#include <optional>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::mesher {

struct Shape;

/// A swept shape's faces: caps (planar, normal to the axis, on a lattice plane) and walls
/// (parallel to the axis, between two lattice planes).
struct Sweep {
  int axis = -1;                          ///< frame axis
  std::vector<int> cap;                   ///< per face: its lattice plane if a cap, else -1
  std::vector<std::array<int, 2>> range;  ///< per wall: the lattice planes of its ends
};

/// The frame axis along which the shape is swept: every face is a cap on a lattice plane or a
/// wall (a plane, cylinder or surface of extrusion parallel to the axis, bounded by lines along
/// the axis and by curves in lattice planes), there are caps on the first and the last plane,
/// and at least one wall is not a lattice face (a box is a lattice already), and no edge lies
/// between caps only (a cap split into faces, its seams off the walls). The frame's third
/// axis is tried first. Whether the cross-section is the same on every plane is
/// sweep_surface()'s to see.
/// @param[in] face_plane    per face, its plane when planar and normal to a frame axis
/// @param[in] lattice_face  per face, whether it is a lattice face
/// @param[in] cells         lattice cells per axis
/// @param[in] spacing       lattice spacing per axis
/// @param[in] h             the target size (planes are matched to 1e-7 h)
std::optional<Sweep> find_sweep(const Shape& s, const Frame& frame,
                                const std::vector<std::optional<AxisPlane>>& face_plane,
                                const std::vector<bool>& lattice_face, const int (&cells)[3],
                                const std::array<double, 3>& spacing, double h);

/// What sweep_surface() made: per node, the node on the bottom plane it repeats (itself there);
/// the first plane's sides on walls, as a cap's triangles run, whether that wall lies between
/// two solids, whether it is a lattice face, and its wall face in each slab.
struct SweptSurface {
  std::vector<int> base;
  std::vector<std::array<int, 2>> sides;
  std::vector<char> shared, on_lattice_face;
  std::vector<std::vector<int>> wall;
};

/// Rebuilds the surface of a swept shape, when its cross-section is the same on every lattice
/// plane along the axis (else nothing changes and the result is empty): the caps on the first
/// plane as BRepMesh made them, their sides on walls split to at most `target` (on walls that
/// are not lattice faces: those keep their lattice points instead), every node on a wall
/// repeated on the `levels` planes above (`step` apart), the walls as two triangles per side and
/// slab (of the wall face there), and the caps on the planes above as copies of the first
/// plane's triangles, each in the cap face that holds its centroid there. The nodes come plane
/// by plane, in the same order on every plane. `wall_target` (null: none), per face, a smaller
/// target for the sides on that wall (local sizes on the caps' edges).
std::optional<SweptSurface> sweep_surface(const Shape& s, const Sweep& sweep, const Frame& frame,
                                          const Vec3& step, int levels, double target,
                                          double deflection, const std::vector<bool>& lattice_face,
                                          Surface& surface,
                                          const std::vector<double>* wall_target = nullptr);

/// Rebuilds a swept shape's tets as columns over one cross-section: the triangles TetGen made on
/// the first plane, each extruded through every slab as a prism of three tets (split by the
/// smallest point index, so that neighbours agree on every quad's diagonal), and the boundary
/// triangles (caps, walls, faces between solids) where TetGen's were, with their markers.
/// TetGen's own tets of a slab are the constrained Delaunay tets of its points, which form such
/// columns only where the caps' triangulation is Delaunay: on a plate with a grid of holes
/// (h 3.4) they did not, and a third of the volume recombined into pyramids.
/// The tets are left as they are (and 0 returned) when a point lies off the lattice planes, a
/// point has no repeat on some plane, TetGen added points, or the columns' volume differs from
/// the tets' (1e-9).
/// @param[in]     axis     the sweep's frame axis
/// @param[in]     spacing  the lattice spacing along it
/// @param[in,out] tets     TetGen's output, in frame coordinates
/// @param[in]     given    the number of points given to TetGen
/// @return the number of triangles extruded (0: left as they are)
std::size_t extrude_tets(int axis, double spacing, std::size_t given,
                         tetgen::TetrahedralizeOutput& tets);

/// A swept shape's tets without tetrahedralising its whole volume: TetGen runs on the first
/// slab only (the first plane's facets as they are, the same facets repeated on the second
/// plane, and the walls of the first plane's sides between them), and the first plane's
/// triangles it made are extruded through every slab as extrude_tets() does, the boundary
/// triangles marked by the walls' faces (`swept.wall`) and by the facets on each plane that hold
/// their centroids. On holed_plate at h 1.04 TetGen on the whole plate ran past 117 s.
/// Nothing is returned (and nothing run) when a point lies off the lattice planes or has no
/// repeat on some plane, or a wall side of the first plane is on no facet; nothing either when
/// TetGen failed on the slab, added or moved points on it, or the prisms' volume differs from
/// its tets' (1e-9): the caller then tetrahedralises the whole volume.
/// @param[in] input             the whole volume's input, in frame coordinates
/// @param[in] nb_surface_nodes  the surface's nodes (the first points; the rest were added)
/// @param[in] axis              the sweep's frame axis
/// @param[in] spacing           the lattice spacing along it
/// @param[out] extruded         the number of triangles extruded
std::optional<tetgen::TetrahedralizeOutput> tetrahedralize_swept(
    const tetgen::Tetrahedralizer& tetgen, const tetgen::TetrahedralizeInput& input,
    const SweptSurface& swept, std::size_t nb_surface_nodes, int axis, double spacing,
    std::size_t& extruded);

}  // namespace hexmerge::mesher
