#pragma once
/// @file
/// The shape to mesh: its solids, faces and edges, checked closed; the lattice frame chosen from
/// it; its planar faces normal to a frame axis. Internal header of mesh_shape(), and the one
/// mesher header that includes OpenCASCADE: the other stages take `const Shape&` declared only.

#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Dir.hxx>
#include <gp_Pnt.hxx>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/glue_solids.h"

namespace hexmerge::mesher {

/// A shape of closed solids. Faces, edges and solids are numbered from 0 in the order of
/// TopExp::MapShapes (index i is map(i + 1)).
struct Shape {
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape solids, faces, edges;
  std::vector<std::vector<int>> face_solids;  ///< per face, the solids it bounds (0-based)
  std::vector<int> face_solid_count;          ///< per face, how many (2: shared by two)
  std::vector<std::vector<int>> edge_faces;   ///< per edge, the faces it bounds
  std::vector<double> edge_length;            ///< per edge, its length (0: degenerated, a pole)
  std::vector<double> face_area;              ///< per face, its area
  /// per face, its width: twice its area over its perimeter (infinite without a perimeter)
  std::vector<double> face_width;
  GProp_GProps volume;  ///< the shape's volume properties (mass: its volume; principal axes)
  double diagonal = 0;  ///< the diagonal of the shape's bounding box
};

/// The shape in BREP text, its solids glued where they touch (glue_solids(), within
/// `glue_tolerance`), its maps filled.
/// @throws InputError when the text cannot be read, holds no solid, a solid is not closed
///         (naming the edge that bounds a single face), a face covers part of its surface
///         twice (face_over_itself()), or two solids overlap
Shape load_shape(const std::string& brep, double glue_tolerance, GlueSolidsReport& glue);

/// The first face (1-based, in `faces`) that covers part of its surface twice: a face on a
/// periodic surface with points (u, v) and (u + period, v) (or (u, v + period)) both inside it,
/// and how many degrees its parameters sweep round the surface; none when no face does.
std::optional<std::pair<int, double>> face_over_itself(const TopTools_IndexedMapOfShape& faces);

/// The lattice frame (origin at 0): "global" (x, y, z), "principal" (principal axes of
/// inertia), "auto" (the normals of the largest planar faces by area, else "principal").
Frame choose_frame(const Shape& s, const std::string& kind);

/// Per face, its plane when it is planar and normal to an axis of `frame` (offset in frame
/// coordinates), else nothing.
std::vector<std::optional<AxisPlane>> face_planes(const Shape& s, const Frame& frame);

/// OpenCASCADE's directions and points as Vec3.
inline Vec3 of(const gp_Dir& d) { return {d.X(), d.Y(), d.Z()}; }
inline Vec3 of(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

/// The point of CAD edge `edge` (numbered from 0: Shape::edges(edge + 1)) nearest to p and its
/// distance (ShapeAnalysis_Curve's projection onto the edge's curve within its range, to
/// `tolerance`); nothing for an edge without a 3D curve.
std::optional<std::pair<double, Vec3>> nearest_on_edge(const Shape& s, int edge, const Vec3& p,
                                                       double tolerance);

/// Whether every triangle of a face's triangulation has two corners within `tolerance`
/// (triangulate() merges them: the face would get no triangle) though the face is wider than 10
/// `tolerance` (2 area / perimeter): BRepMesh failed on it. A KiCad connector's cone 0.45 mm long,
/// its base circle cut into nine arcs, got five triangles each with two corners at its apex, at
/// h 4 to 9; its pin then had a hole, and TetGen carved the pin away. (A face narrower than that
/// collapses as triangulate() means it to.)
bool triangulation_collapsed(const TopoDS_Face& face, const Poly_Triangulation& triangulation,
                             double tolerance);

}  // namespace hexmerge::mesher
