#pragma once
/// @file
/// The surface triangulation checked before it goes to the tetrahedraliser (internal header of
/// mesh_shape(); no OpenCASCADE): triangles that cross one another, and whether the CAD itself
/// makes them (faces that meet where they share no edge).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;

/// Two triangles of a surface that cross: they share no side, and they meet other than at the
/// node they share (if one).
struct Crossing {
  int first, second;  ///< the triangles (indices into the surface's)
};

/// Of each pair of faces (or face with itself) whose triangles cross (exact predicates), the
/// first two triangles found crossing. A tetrahedraliser cannot keep such a surface (TetGen 1.5
/// recovers its boundary for ever).
std::vector<Crossing> find_crossings(const std::vector<Vec3>& nodes,
                                     const std::vector<SurfaceTriangle>& triangles);

/// Per triangle of `inner` (corners by index into `nodes`), whether it crosses a triangle of
/// `surface` (corners into the same `nodes`; `surface` may be `inner` itself) by the exact test
/// of find_crossings(): triangles sharing a corner cross only where they meet beyond it, a common
/// side or the same triangle is no crossing. Inner facets a tetrahedraliser is asked to keep must
/// cut neither the surface nor each other (TetGen stops: "a segment and a subface intersect").
std::vector<char> crosses_any(const std::vector<Vec3>& nodes,
                              const std::vector<std::array<int, 3>>& surface,
                              const std::vector<std::array<int, 3>>& inner);

/// A side of the surface's triangles where a solid's boundary passes more than once: more than
/// two of its triangles on the faces of one solid (the faces of touching solids glued together
/// bound both).
struct OverusedSide {
  int a, b;                ///< its nodes
  std::vector<int> faces;  ///< the faces of its triangles (each once, in order)
};

/// The sides where a solid's boundary touches itself (`face_solids`: per face, the solids it
/// bounds) though no one CAD edge bounds all their faces there (`edge_faces`: per edge, the
/// faces it bounds): two CAD edges at one place, their nodes merged, and TetGen 1.5 never ends
/// on such a surface. (An edge of a non-manifold solid, shared by four faces, is not one.) One
/// per set of faces.
std::vector<OverusedSide> find_overused_sides(const Surface& surface,
                                              const std::vector<std::vector<int>>& face_solids,
                                              const std::vector<std::vector<int>>& edge_faces);

/// Whether the CAD's faces of an overused side meet along it: at a quarter, half and three
/// quarters of the side, two of its faces come within `tolerance` of each other, not on an edge
/// they share (two of the solid's edges at one place: broken CAD; a sphere and a torus whose
/// curve of intersection runs 0.18 mm from a side they share with a plane meet as the CAD means
/// them to). Not where they lie apart there: faces that only come
/// close share such a side when BRepMesh gives both the same chord between two of their common
/// edges (a random part's cylinder and cone, 0.27 mm apart between their two curves of
/// intersection: every size from 9 to 25 mm but 17 refused as broken), which a finer surface
/// parts.
bool faces_meet_along(const Shape& s, const std::vector<Vec3>& nodes, const OverusedSide& side,
                      double tolerance);

/// The faces (0-based, sorted) with a side that only one triangle of the surface has: a gap
/// (BRepMesh covered a random part's boss cylinder only in part at h 58.8, and TetGen carved the
/// whole solid away).
std::vector<int> faces_with_open_sides(const Surface& surface);

/// The faces by `face_names`, for the user: "Face11, Face12 and Face14".
std::string face_list(const std::vector<int>& faces, const std::vector<std::string>& face_names);

/// The places find_overused_sides() found, for the user: up to three, each its faces (by
/// `face_names`) and a point ("Face810, Face876, Face1013 and Face1014 meet near (x, y, z)"),
/// and how many more there are.
std::string describe_overused_sides(const std::vector<Vec3>& nodes,
                                    const std::vector<OverusedSide>& overused,
                                    const std::vector<std::string>& face_names);

/// How the mesher's errors on a broken shape end: where the user finds such faces.
inline constexpr const char* kRepairTheShape =
    ". Repair the shape (FreeCAD's Part > Check geometry, with its BOP check, lists such faces)";

/// Whether the CAD's faces of any crossing meet where they share no edge (as describe_crossings()
/// tells them), stopping at the first that does.
bool any_faces_meet(const Shape& s, const std::vector<SurfaceTriangle>& triangles,
                    const std::vector<Crossing>& crossings, double tolerance);

/// What the crossings say, for the user: per pair of faces whose triangles cross (up to three,
/// those whose CAD faces meet first), the faces (by `face_names`) and a point, and whether the
/// CAD's own faces meet: an
/// edge of one lies on the other (within `tolerance`) without being one of its edges (faces
/// not sewn together, or overlapping), which no size repairs ("(meeting there)").
/// @param[out] cad_at_fault  whether any pair's CAD faces meet so
std::string describe_crossings(const Shape& s, const std::vector<Vec3>& nodes,
                               const std::vector<SurfaceTriangle>& triangles,
                               const std::vector<Crossing>& crossings, double tolerance,
                               const std::vector<std::string>& face_names, bool& cad_at_fault);

}  // namespace hexmerge::mesher
