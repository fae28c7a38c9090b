#pragma once
/// @file
/// The shape's surface triangulation (internal header of mesh_shape(); no OpenCASCADE): nodes
/// merged across faces, triangles oriented outward with their nodes' parameters on their face,
/// the sides on CAD edges with their parameters; and the geometry of surface triangles.

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {

struct Shape;

/// A point's parameters (u, v) on a face's surface.
struct UV {
  double u = 0, v = 0;
};

/// A triangle of the surface on CAD face `face` (0-based), oriented outward (as the face is in
/// its solid).
struct SurfaceTriangle {
  std::array<int, 3> node;
  std::array<UV, 3> uv;  ///< the nodes' parameters on the triangle's face (sweeps: unset)
  int face;
};

/// The key of side c of a triangle (from node c to node c + 1).
inline std::uint64_t side_key(const SurfaceTriangle& t, int c) {
  return pair_key(t.node[c], t.node[(c + 1) % 3]);
}
/// The side of t with a given key (t must have it).
inline int side_with_key(const SurfaceTriangle& t, std::uint64_t key) {
  int c = 0;
  while (side_key(t, c) != key) ++c;
  return c;
}

/// A segment of the surface triangulation on a CAD edge: the edge and its parameters at the
/// segment's smaller and larger node id.
struct EdgeSegment {
  int edge;
  double t_lo, t_hi;
};

/// A triangulated surface.
struct Surface {
  std::vector<Vec3> nodes;                 ///< world coordinates
  std::vector<int> node_face;              ///< a face the node lies on
  std::vector<SurfaceTriangle> triangles;  ///< oriented outward (as the face is in its solid)
  std::unordered_map<std::uint64_t, EdgeSegment> segments;  ///< by pair_key of their nodes
  /// Per node, its index before collapse_sides() (seeds the layers' depths, so that a
  /// collapse does not change them everywhere).
  std::vector<int> seed;
  /// Faces whose refinement to the target size did not converge and was given up (refine()).
  std::vector<int> unrefined_faces;
  /// BRepMesh's triangles whose three nodes lie on one line, taken out by triangulate() (the
  /// triangle across each one's longest side split at its third node).
  std::size_t nb_flat_triangles = 0;
  /// Faces triangulated as surfaces of revolution (triangulate(): BRepMesh failed on a face of
  /// the shape as it is); 0 when the shape meshed as it is.
  std::size_t nb_revolution_faces = 0;
  /// Faces BRepMesh left without triangles between two edges with the same ends, narrower than
  /// the chord deflection, closed by joining the faces across them (triangulate()).
  std::size_t nb_zipped_faces = 0;
  /// Patches of faces whose triangles folded over each other, triangulated anew (triangulate():
  /// unfold_faces()).
  std::size_t nb_unfolded_patches = 0;
  /// Per vertex inside a face (on none of its edges) made a node of its triangles, that face
  /// (triangulate(): BRepMesh leaves them out). Such a face is no lattice face: a lattice face's
  /// triangles go to the tetrahedraliser as its loops only.
  std::vector<int> internal_vertex_faces;
  /// Sides BRepMesh gave two faces that only come close there, split apart (triangulate()).
  std::size_t nb_parted_sides = 0;
};

/// BRepMesh's angular deflection in triangulate() (radians). Its CAD edges' segments turn by at
/// most half of it, 45 degrees: at least 8 segments on a circle (Gmsh puts at least 7 points),
/// more where the chord deflection asks (a radius of r takes segments of 0.4 sqrt(r h) at the
/// default 0.02 h). At 0.35 a 4 mm hole had 36 nodes at h 3.4 (0.1 h apart) and every small
/// fillet's arc 9 segments: the tets between them and the lattice h away were needles
/// (holed_plate at h 3.4: prisms below scaled Jacobian 0.2 1,840 -> 0).
constexpr double kSurfaceAngle = 1.57;

/// BRepMesh left faces without triangles at this chord deflection (triangulate()): another may
/// not (a random part's sphere cut by a plane and a cylinder, the hole in its face bounded by two
/// arcs of one segment each at h 40.64, meshes on a finer surface).
class FacesNotTriangulated : public InputError {
 public:
  using InputError::InputError;
};

/// The shape's faces triangulated by OpenCASCADE (BRepMesh, chord deflection `deflection`,
/// angular deflection kSurfaceAngle), nodes closer than `tolerance` merged into one. Where
/// BRepMesh leaves a face without triangles, the whole shape is triangulated again with its
/// cylinders, cones, spheres and tori as surfaces of revolution (ShapeCustom's; the same
/// geometry), the nodes' parameters taken back onto each face's own surface.
/// @param face_names  per face of `s`, its name for messages (as the user numbers it: "Face12")
/// @throws FacesNotTriangulated when a face cannot be triangulated either way (naming it and its
///         kind)
Surface triangulate(const Shape& s, double deflection, double tolerance,
                    const std::vector<std::string>& face_names);

/// Merges nodes within `tolerance` of an earlier node into it (the triangles that lose a side go),
/// takes out pairs of triangles on the same three nodes facing opposite ways (a fold: it bounds
/// no volume; of triangles facing the same way one stays), then the nodes no triangle uses (the
/// rest renumbered, with their segments and seeds). The repairs can leave nodes at one point
/// where a side was split again and again there (gmsh_Kurbelwelle at h 0.57: ten nodes at one
/// point of face 5, in folds), and TetGen stops on coincident nodes.
void remove_folds(Surface& surface, double tolerance);

/// Drops the nodes no triangle uses and renumbers the rest, with their segments and seeds: TetGen
/// leaves such a node out (gmsh_U_Joint_2's 0.35 mm faces: every node of theirs coincident with
/// another), which failed every way of placing the points.
void drop_unused_nodes(Surface& surface);

/// Per face of `s` narrower than `below` (`face_width`: Shape::face_width), how far it spans
/// across: the middle side of its oriented bounding box (from its geometry, OpenCASCADE's). Below
/// its width where the face closes round: a whole cylinder of radius r spans 2 r, its width is
/// about 2 pi r. Infinite for the wider faces (not measured: as long as the widths, 0.47 s on a
/// KiCad connector's 3,094 faces) and where OpenCASCADE finds no box.
std::vector<double> face_spans(const Shape& s, const std::vector<double>& face_width, double below);

/// Faces narrower than `width` (`face_width`: Shape::face_width) are no faces: every node of theirs
/// and every node within `width` of one become one node (remove_folds() then takes out their
/// triangles), unless the surface would then touch itself or have a gap (it is left as it
/// was). Returns how many such faces had triangles and went (0: none went).
std::size_t merge_narrow_faces(Surface& surface, const Shape& s,
                               const std::vector<double>& face_width, double width);

/// The angle at node v between the sides to a and b.
double angle_at(const std::vector<Vec3>& nodes, int v, int a, int b);
/// The (area-weighted: twice the area long) normal of triangle abc.
Vec3 normal_of(const std::vector<Vec3>& nodes, int a, int b, int c);
/// The smallest angle of triangle v.
double smallest_angle(const std::vector<Vec3>& nodes, const std::array<int, 3>& v);
/// The smallest angle of triangle abc.
double smallest_angle(const Vec3& a, const Vec3& b, const Vec3& c);

/// The volume the triangles of faces that bound one solid enclose (`face_solid_count`: per face,
/// how many solids it bounds): the union of the solids', the triangles oriented outward.
double enclosed_volume(const std::vector<Vec3>& nodes,
                       const std::vector<SurfaceTriangle>& triangles,
                       const std::vector<int>& face_solid_count);

/// Surface smoothing and collapses keep every triangle within 20 degrees of the surface's normal
/// at the node they move or remove: true when `now` turned further from `reference`.
bool turned_over(const Vec3& now, const Vec3& reference);

/// Per node, whether it lies on a CAD edge (an end of a segment).
std::vector<char> nodes_on_edges(const Surface& surface);

/// The coordinates (s, r) of q in triangle p0 p1 p2, q = p0 + s (p1 - p0) + r (p2 - p0), all
/// seen along frame axis `axis` (nodes in frame coordinates); false when the triangle is edge-on.
bool coordinates_across(const Vec3& q, const Vec3& p0, const Vec3& p1, const Vec3& p2, int axis,
                        double& s, double& r);

/// The face of the first of `triangles` (on a plane normal to frame axis `axis`, nodes in frame
/// coordinates) that holds q, to 1e-9 of its coordinates; -1 for none.
int face_holding(const Vec3& q, const std::vector<const SurfaceTriangle*>& triangles,
                 const std::vector<Vec3>& nodes, int axis);

}  // namespace hexmerge::mesher
