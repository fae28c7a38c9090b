#pragma once
/// @file
/// Solids that touch, made to share their common faces (internal header: includes OpenCASCADE).
///
/// FreeCAD's compounds, BooleanFragments and assemblies read from STEP bring solids that touch
/// each other as separate closed shells: two coincident faces where one is wanted. A tet mesher
/// given both fails or makes a mesh that is not conforming across the contact. glue_solids()
/// imprints every solid on the others with OpenCASCADE's General Fuse, so that the area two
/// solids share becomes one face bounding both; solids that overlap in volume are refused.

#include <TopoDS_Edge.hxx>
#include <TopoDS_Shape.hxx>
#include <cstddef>
#include <vector>

namespace hexmerge::mesher {

/// What glue_solids() did.
struct GlueSolidsReport {
  std::size_t nb_solids = 0;        ///< solids of the shape
  std::size_t nb_shared_faces = 0;  ///< faces bounding two solids after gluing
  bool glued = false;               ///< General Fuse ran (more than one solid)
  double fuzzy = 0.0;               ///< its fuzzy value (the tolerance given)
  /// Solids load_shape() made of a shape that held faces or shells only (sewn, each closed shell a
  /// solid); 0 when the shape held solids.
  std::size_t nb_sewn_solids = 0;
  /// Glued: per face of the shape as given (0-based, in TopExp::MapShapes(shape, TopAbs_FACE)
  /// order: FreeCAD's FaceN is face N - 1), the faces of the glued shape it became (0-based, in
  /// the same order over the glued shape): itself, its pieces, or the one face it shares with
  /// another solid's face. Empty when not glued.
  std::vector<std::vector<int>> face_images;
  /// Likewise per edge (FreeCAD's EdgeN).
  std::vector<std::vector<int>> edge_images;
  /// Edges split at their middle by split_lens_edges() (then face_images and edge_images lead
  /// from the shape as given to the shape split, glued or not).
  std::size_t nb_split_lens_edges = 0;
};

/// The shape's solids, in the order TopExp::MapShapes(shape, TopAbs_SOLID) gives them, glued:
/// a compound of as many solids, each bounded by its own faces, where the faces two solids share
/// (touching solids) are one face of both. A single solid is returned as it is.
/// @param[in]  shape      a shape holding at least one solid
/// @param[in]  tolerance  distance under which two faces count as touching (the shape's own
///                        tolerances are added), in the shape's units
/// @param[out] report     counts
/// @throws InputError naming the two solids (0-based, in the order above) when solids overlap
///         in volume, or when OpenCASCADE cannot intersect the solids' faces
TopoDS_Shape glue_solids(const TopoDS_Shape& shape, double tolerance, GlueSolidsReport& report);

/// An edge's length (OpenCASCADE's linear properties; load_shape()'s Shape::edge_length too).
double edge_length(const TopoDS_Edge& edge);

/// Whether `a` and `b` bound a lens: two distinct edges, neither degenerated nor closed, between
/// the same two vertices (a hole split_lens_edges() splits, a face triangulate() zips shut).
bool lens_edges(const TopoDS_Edge& a, const TopoDS_Edge& b);

/// The shape with one edge of each lens wire split at its middle (a vertex added there): a wire
/// of two edges between the same two vertices, each turning by less than BRepMesh's angular
/// deflection (kSurfaceAngle), which BRepMesh divides into one segment each at a coarse enough
/// chord deflection: the hole they bound then has no area, and BRepMesh fails on the face without
/// a word (a random part's torus, whose hole of two 0.94 mm edges where a plane and a cylinder
/// meet it had triangles up to 9 mm off it at every deflection). The longer edge of the two is
/// split (the hole then has three segments at least). Only holes (wires other than the face's
/// outer one): a face whose outline is such a lens is zipped shut after BRepMesh, and a sphere
/// whose one wire is one goes to a finer surface (surface.cpp). The faces keep their numbers;
/// `report`'s face_images and edge_images lead from the shape as given (before `glued`, when
/// report.glued) to the one returned.
/// @param[in]     shape   the shape as glue_solids() returned it
/// @param[in,out] report  its images, composed; nb_split_lens_edges
TopoDS_Shape split_lens_edges(const TopoDS_Shape& shape, GlueSolidsReport& report);

}  // namespace hexmerge::mesher
