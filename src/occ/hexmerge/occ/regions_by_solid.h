#pragma once
/// @file
/// Material regions of a tetrahedral mesh from the solids of a CAD shape (OpenCASCADE).
///
/// The header needs no OpenCASCADE include: the shape comes in as BREP text (what FreeCAD's
/// `Shape.exportBrepToString()` and OCCT's `BRepTools::Write` produce).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hexmerge/core/phase_timer.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// The region of a tet that lies in no solid of the shape.
constexpr std::int32_t NO_SOLID = -1;

/// How regions_by_solid() works.
struct RegionsBySolidParameters {
  /// Distance under which a mesh node lies on a face shared by two solids, in fractions of the
  /// shape's bounding-box diagonal (the BREP's own face tolerances are added). Range (0, 0.01].
  double tolerance = 1e-6;
  /// Tets classified per piece (see regions_by_solid); a piece whose samples disagree is
  /// classified tet by tet. Range [1, 1000].
  int samples_per_piece = 5;
  /// Classify the centroid of every tet instead of one sample set per piece (slow; a reference
  /// for tests and benchmarks).
  bool classify_every_tet = false;
  /// Worker threads; 0 means one per hardware thread.
  int nb_threads = 0;
};

/// What regions_by_solid() did.
struct RegionsBySolidReport {
  std::size_t nb_solids = 0;
  std::size_t nb_shared_faces = 0;       ///< faces of the shape between two solids
  std::size_t nb_interface_nodes = 0;    ///< mesh nodes found on a shared face
  std::size_t nb_pieces = 0;             ///< connected pieces of tets, cut at shared faces
  std::size_t nb_split_pieces = 0;       ///< pieces whose samples disagreed (classified per tet)
  std::size_t nb_classified_points = 0;  ///< point-in-solid queries made
  std::size_t nb_unassigned_tets = 0;    ///< tets in no solid (NO_SOLID)
  PhaseSeconds phase_seconds;            ///< wall time per phase, in order
};

/// The solid of a shape that holds each tet of a mesh.
///
/// The tets are split into connected pieces through their faces, cut wherever all three nodes
/// of a face lie on a face the shape's solids share (or on two coincident faces of different
/// solids); a few tets per piece are classified by their centroid (bounding boxes first, then
/// OpenCASCADE's point-in-solid test), in parallel. A mesh made from the shape thus costs one
/// handful of queries per solid plus work linear in its size.
///
/// @param[in]  brep        the shape as BREP text; its solids are numbered as
///                         TopExp::MapShapes(shape, TopAbs_SOLID) numbers them, from 0 (the
///                         order of FreeCAD's `Shape.Solids`)
/// @param[in]  mesh        #V points and #T by 4 tets (regions are ignored)
/// @param[in]  parameters  see RegionsBySolidParameters
/// @param[out] report      counts and timings
/// @return #T solid indices, NO_SOLID for a tet in no solid
/// @throws InputError when the BREP text cannot be read, holds no solid, or the mesh is not a
///         valid tet mesh (see validate_tet_mesh and TetTopology)
std::vector<std::int32_t> regions_by_solid(const std::string& brep, const TetMesh& mesh,
                                           const RegionsBySolidParameters& parameters,
                                           RegionsBySolidReport& report);

/// Overload without a report.
std::vector<std::int32_t> regions_by_solid(const std::string& brep, const TetMesh& mesh,
                                           const RegionsBySolidParameters& parameters = {});

}  // namespace hexmerge
