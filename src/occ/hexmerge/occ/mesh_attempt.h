#pragma once
/// @file
/// One way of placing the points (internal header of mesh_shape()): mesh_shape.cpp loads the
/// shape, refuses a size too large and tries the ways in turn (steps 1 to 3 of its entry);
/// mesh_attempt.cpp runs one way, steps 4 to 14 (surface, lattice, core, layers, TetGen,
/// regions, slivers, check, second order), and throws SurfaceTooCoarse or another
/// TetrahedralizeFailure for the next way to be tried.

#include <string>
#include <vector>

#include "hexmerge/core/progress.h"
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/sharp_features.h"
#include "hexmerge/occ/mesher/strategy.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::mesher {

/// Around a local size, the size wanted grows by this fraction of the distance, up to h.
constexpr double kLocalGrading = 0.5;
/// Faces narrower than this times h are merged away (merge_narrow_faces): under the boundary's
/// tolerance to the CAD, 1e-3 h.
constexpr double kNarrowFace = 9e-4;

/// A way's surface too coarse for the shape's thin parts: its triangles cross (faces closer than
/// the chord deflection, or folds), or the boundary swaps against slivers, each within the chord
/// deflection, moved a wall past its thickness.
class SurfaceTooCoarse : public tetgen::TetrahedralizeFailure {
 public:
  using tetgen::TetrahedralizeFailure::TetrahedralizeFailure;
};

/// The faces and edges as the user numbers them (the shape as given), and the shape's they name.
struct GivenItems {
  ItemNumbering faces, edges;
};

/// One attempt: steps 3 to 14 of mesh_shape() with one strategy; the Tet10 mesh too when
/// `tet10` is given. `sharp`: the shape's sharp features (the report has them), whose surface
/// nodes the attempt reports. `widths`, `spans`: the faces' widths (Shape::face_width) and spans
/// (face_spans()); with `merge_narrow`, faces narrower than kNarrowFace h are merged away.
TetMesh mesh_attempt(const Shape& shape, const GivenItems& given_items, const Frame& frame,
                     const SharpFeatures& sharp, const std::string& regions_brep,
                     const MeshShapeParameters& parameters, const Strategy& strategy,
                     const std::vector<double>& widths, const std::vector<double>& spans,
                     bool merge_narrow, MeshShapeReport& report, Tet10Mesh* tet10,
                     const ProgressCallback& progress);

}  // namespace hexmerge::mesher
