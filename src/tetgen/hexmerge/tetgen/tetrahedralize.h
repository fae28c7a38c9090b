#pragma once
/// @file
/// TetGen behind one interface (no OpenCASCADE, no TetGen types), used by the mesher from CAD
/// (mesh_shape()), the C++ test fixtures and, through the Python module, the benchmarks' mesh
/// generator: a piecewise linear complex (points, facets with markers) in, tets and the
/// boundary faces with their markers out, the surface kept as it is (no point added on it); or,
/// with no facets, the Delaunay tetrahedralisation of the points.
///
/// Today's implementation runs the `tetgen` program (TetGen 1.5, `-pYz`) through its files,
/// under a time limit, the facets with loops triangulated first (triangulate_facets.h; one it
/// cannot take is restarted with its loops started at other vertices when a run does not finish
/// or loses the surface), and nudging isolated points it leaves out. A
/// version on TetGen as a library (libtet1.5-dev: tetgenio and tetrahedralize()) fits the same
/// declarations: only Tetrahedralizer's constructor and run() would change.

#include <array>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/geometry/vec3.h"

namespace hexmerge::tetgen {

/// A facet of the complex: polygons (closed loops of point indices: a face's outer and inner
/// boundary loops, or one triangle; a polygon of one point is a single point inside the facet),
/// a point inside each of its holes, and its boundary marker (> 0).
struct Facet {
  std::vector<std::vector<int>> polygons;
  std::vector<Vec3> holes;
  int marker;
};

/// What to tetrahedralise. Points are in any consistent coordinates; the facets must bound a
/// closed volume (or several touching ones, faces between them included). With no facets, the
/// points' Delaunay tetrahedralisation (of their convex hull) is made, every point kept.
struct TetrahedralizeInput {
  std::vector<Vec3> points;   ///< the facets' vertices, then the isolated points
  std::vector<Facet> facets;  ///< the boundary, kept as it is
  /// Points from this index on are isolated vertices of the complex (inside the volume): one
  /// the tetrahedraliser leaves out is moved by `nudge` and the run made once more. A point
  /// before it left out is an error.
  std::size_t first_isolated = 0;
  /// World position of a point, for messages that name points (identity when empty).
  std::function<Vec3(const Vec3&)> to_world;
};

/// The tetrahedraliser could not tetrahedralise the input: it crashed, refused the input, left
/// points out or did not finish. The message says which, in our words (the program's own crash
/// text is left out; the reason it gives is quoted).
class TetrahedralizeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How to tetrahedralise.
struct TetrahedralizeParameters {
  /// The TetGen program: a name looked up on PATH, or a path.
  std::string program = "tetgen";
  /// A directory for the program's files, kept afterwards; empty: a temporary one, removed.
  std::string work_directory;
  /// Time limit of one run, in seconds; 0: 30 s plus 1 ms per point.
  double time_limit = 0.0;
  /// Runs made again after one that does not finish or leaves no tet, before failing, when a
  /// facet is still given as loops (none else: the same input fails the same way).
  int restarts = 5;
  /// Length an isolated point left out moves (along (1, 0.7, 0.3)) before the one rerun.
  double nudge = 0.0;
  /// Distance within which an output point is the input point of the same rank.
  double tolerance = 0.0;
  /// Let the tetrahedraliser add points inside for quality (radius-edge ratio at most 1.5), for
  /// an input with no isolated points.
  bool quality = false;
};

/// The tets.
struct TetrahedralizeOutput {
  /// #points by 3: the input points (nudged ones moved) in order, then the points the
  /// tetrahedraliser added (Steiner points).
  std::vector<double> points;
  std::vector<index_t> tets;  ///< #tets by 4, indices into points, orientation as made
  /// The boundary triangles and, per triangle, the marker of the facet it lies in.
  std::vector<std::array<index_t, 3>> boundary;
  std::vector<int> boundary_marker;
  std::size_t nb_restarts = 0;  ///< runs made again after one that failed
  std::size_t nb_nudged = 0;    ///< isolated points moved by `nudge` after being left out
  std::string command;          ///< what was run (the command line)
};

/// A tetrahedraliser, checked usable when made.
class Tetrahedralizer {
 public:
  /// @throws InputError when it cannot run (the TetGen program is not found)
  explicit Tetrahedralizer(const TetrahedralizeParameters& parameters);

  /// The tets of the complex.
  /// @throws InputError when the complex cannot be tetrahedralised: a run past the time limit
  ///         or losing the surface (`restarts` + 1 times with loops), the program failing (with its
  ///         output), points left out (naming them), or unreadable output
  TetrahedralizeOutput run(TetrahedralizeInput input) const;

 private:
  TetrahedralizeParameters parameters_;
  std::string program_;  // the program's path
};

}  // namespace hexmerge::tetgen
