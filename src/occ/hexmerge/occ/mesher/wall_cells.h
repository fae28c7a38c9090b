#pragma once
/// @file
/// Hexahedra across tube walls (internal header of mesh_shape()): where two coaxial cylindrical
/// faces of one solid bound a wall between them (a pipe, a bore in a boss, a bushing) too thin
/// for the lattice's core, a grid of cells along the wall, each cell's outer and inner quads put
/// into the two faces' triangles (face_chart's retriangulate()), so that the tets between are a
/// hexahedron's six and the recombination takes it.

#include <array>
#include <cstddef>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/lattice.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;

/// Walls from kThinnestWallCell h to kThickestWallCell h thick get cells (thicker ones are the
/// core's: two cells of it fit across).
inline constexpr double kThinnestWallCell = 0.5;
inline constexpr double kThickestWallCell = 2.5;

/// What wall_cells() made.
struct WallReport {
  std::size_t nb_walls = 0;  ///< coaxial pairs of cylinders with at least one cell
  std::size_t nb_hexes = 0;  ///< cells
  std::size_t nb_faces = 0;  ///< CAD faces triangulated again with the cells' quads
  std::vector<int> faces;    ///< those faces (0-based)
};

/// The cells, frame coordinates, corners in kKuhnPaths' order (bits: round the axis, along it,
/// outward), and the points between their faces' nodes (walls more than one cell thick).
struct WallCells {
  std::vector<std::array<Vec3, 8>> hexes;
  /// Per cell, whether its inner face (1) and its outer one (2) are the surface's.
  std::vector<char> on_surface;
  std::vector<Vec3> points;
};

/// The cells of the walls between two cylindrical faces of one solid, coaxial, the outer one's
/// material inside its radius and the inner one's outside, kThinnestWallCell h to
/// kThickestWallCell h apart (faces `eligible` only: no lattice face, no local size, not between
/// two solids). Along each wall a grid of about h round its middle radius, finer where the outer
/// face's chords would leave it by more than the chord deflection `deflection`, and h along its
/// axis (round(thickness / h) cells across, rows h / 2 inside the faces' common length; along and
/// across at most twice as long as round), half a cell off the outer face's seam; a cell is kept
/// where its corners lie at least 0.3 h inside a face's edges on both sides, its six tets keep a
/// scaled Jacobian of 0.2, no point of `obstacles` (the core's, frame coordinates) comes within
/// h / 4 of it, no surface node lies in it and its faces cross neither the surface nor each
/// other; a wall keeps none where under half its columns are clear of `obstacles` (the core's
/// wall). The faces with quads are triangulated again (a face where that fails keeps its
/// triangles and gets no cells).
/// @param[in]     frame      the lattice's frame (the cells are given in it)
/// @param[in,out] surface    the faces with quads triangulated again (world coordinates)
WallCells wall_cells(const Shape& shape, const Frame& frame, const std::vector<char>& eligible,
                     const PointSet& obstacles, double h, double deflection, Surface& surface,
                     WallReport& report);

/// The cells' splits (the six tets around the diagonal from corner 0 to corner 7) and corners
/// to `inserted` (splits, kept cells), their faces inside the shape as constraints, the points
/// between their faces' nodes as points inside, and their tets to around.buffer_cells (no point
/// placed later comes near them).
void emit_wall_cells(const WallCells& cells, Surroundings& around, InsertedPoints& inserted);

}  // namespace hexmerge::mesher
