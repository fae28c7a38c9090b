#pragma once
/// @file
/// The cubic lattice in the frame and the points it gives TetGen (internal header of
/// mesh_shape(); no OpenCASCADE): the lattice laid through the shape's bounding box with as many
/// planar faces on its planes as can be ("lattice faces"), the surface's nodes in frame
/// coordinates, the queries of what lies near a point, inside/outside by ray parity, the lattice
/// points kept (the hexahedral core on them: core.h).

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

/// A closing pyramid's apex lies at least this fraction of the cell's circumradius outside the
/// circumsphere of the core cell beside it (lay_lattice(), lay_core()).
inline constexpr double kCellSphereClearance = 1e-3;

struct Shape;
struct SweptSurface;

/// The lattice: cells[a] cells along frame axis a, its planes through the lower corner of the
/// surface's bounding box in the frame (the frame's origin). Along an axis the planes are either
/// uniform (i * spacing[a]; ticks[a] empty) or rectilinear: at ticks[a][i], placed on the planar
/// faces normal to the axis at least h wide, each cell within a factor 1.25 of the uniform
/// spacing the axis would have (spacing[a] is then their mean).
struct Lattice {
  Frame frame;
  std::array<double, 3> extent{};  ///< the bounding box's size along each axis
  double largest = 0;              ///< the largest of extent
  int cells[3] = {0, 0, 0};
  std::array<double, 3> spacing{};
  std::array<std::vector<double>, 3> ticks;  ///< rectilinear axes: the planes' offsets
  /// Per face, its plane when planar and normal to a frame axis.
  std::vector<std::optional<AxisPlane>> face_plane;
  std::vector<bool> lattice_face;  ///< per face: planar and on a lattice plane
  std::vector<bool> lattice_edge;  ///< per edge: every face it bounds is a lattice face
  std::size_t nb_lattice_faces = 0;

  bool uniform(int a) const { return ticks[a].empty(); }
  /// Frame coordinate along axis a of lattice coordinate t (t = i: plane i; i + 0.5: the middle
  /// of cell i; linear within a cell).
  double at(int a, double t) const { return lattice_coordinate(ticks[a], spacing[a], t); }
  /// Lattice coordinate of frame coordinate x along axis a (the inverse of at()).
  double cells_at(int a, double x) const { return cells_coordinate(ticks[a], spacing[a], x); }
  /// Width of cell i along axis a.
  double width(int a, int i) const {
    return uniform(a) ? spacing[a] : ticks[a][i + 1] - ticks[a][i];
  }
  /// The widest cell along axis a.
  double widest(int a) const;
  /// Whether frame coordinate x along axis a lies on a lattice plane (within `tolerance`).
  bool on_plane(int a, double x, double tolerance) const;

  /// The index of lattice point (i, j, k) in per-point arrays (i fastest, then j, then k).
  std::size_t point_index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * (cells[1] + 1) + j) * (cells[0] + 1) + i;
  }
  /// The (i, j, k) of the lattice point at `index` (point_index()'s inverse).
  std::array<int, 3> point_ijk(std::size_t index) const {
    const std::size_t n0 = cells[0] + 1, n1 = cells[1] + 1;
    return {static_cast<int>(index % n0), static_cast<int>(index / n0 % n1),
            static_cast<int>(index / (n0 * n1))};
  }
  /// The (i, j, k) of cell `index` (i fastest, then j, then k).
  std::array<int, 3> cell_ijk(std::size_t index) const {
    const std::size_t c0 = cells[0], c1 = cells[1];
    return {static_cast<int>(index % c0), static_cast<int>(index / c0 % c1),
            static_cast<int>(index / (c0 * c1))};
  }
  /// Lattice point (i, j, k) and the centre of cell (i, j, k), in frame coordinates.
  Vec3 point(int i, int j, int k) const { return Vec3{at(0, i), at(1, j), at(2, k)}; }
  Vec3 point(const std::array<int, 3>& ijk) const { return point(ijk[0], ijk[1], ijk[2]); }
  Vec3 cell_centre(int i, int j, int k) const {
    return Vec3{at(0, i + 0.5), at(1, j + 0.5), at(2, k + 0.5)};
  }
  Vec3 cell_centre(const std::array<int, 3>& ijk) const {
    return cell_centre(ijk[0], ijk[1], ijk[2]);
  }
};

/// The lattice in `frame` through the bounding box of the surface's nodes (world coordinates):
/// cells about h wide per axis, chosen so that as many axis-normal planar faces as possible lie
/// on lattice planes (the box's own faces always do), and every spacing exceeds half the cell's
/// diagonal where the best few counts per axis allow (else a closing pyramid's apex, the centre
/// of the cell across a face, lies in the cell's circumsphere and Delaunay breaks the cell).
/// An axis is rectilinear where placed planes put more planar faces at least h wide on lattice
/// planes than the uniform spacing does (a stepped part); lay_core() then drops the cells whose
/// apexes fall in their circumspheres. Without `lattice_faces`, no face is a lattice face (its
/// planar faces are treated like the others) and every axis is uniform.
/// @throws InputError when h is larger than the shape's largest extent
Lattice lay_lattice(const Shape& shape, const Frame& frame, const std::vector<Vec3>& surface_nodes,
                    double h, bool lattice_faces = true);

/// The surface's nodes in frame coordinates: the nodes of lattice faces exactly on their planes,
/// straight edges across the lattice on one line (align_straight_edges); swept (sweep_axis >= 0),
/// every node exactly on its lattice plane and across the axis exactly where the node on the
/// bottom plane it repeats is.
std::vector<Vec3> frame_nodes(const Shape& shape, const Surface& surface, const Lattice& lattice,
                              int sweep_axis, const SweptSurface& swept);

/// Points TetGen gets besides the surface's nodes (frame coordinates), with the lattice face
/// each lies on (-1: inside).
struct InsertedPoints {
  std::vector<Vec3> points;
  std::vector<int> face;
  /// Points of the core moved off the lattice (emit_core()): where each is, and its lattice
  /// position (a lattice point or a cell's centre).
  std::vector<std::pair<Vec3, Vec3>> pulled;
  /// Triangles TetGen must keep (the faces of the core's cells and pyramids that are no longer
  /// cospherical), by their corners' positions (points inserted or the surface's nodes).
  std::vector<std::array<Vec3, 3>> constraints;
  /// The pulled cells and pyramids, each to be split as the lattice's (the six tets around a
  /// cell's diagonal from its least corner; a pyramid's base on its diagonal from its least
  /// corner): corners by position and the tets by corner.
  struct Split {
    std::vector<Vec3> corners;
    std::vector<std::array<int, 4>> tets;
  };
  std::vector<Split> splits;
  /// The buffer's cells (emit_core()), by their corners' positions: the tets inside each stay as
  /// they are after TetGen (improve_tets()).
  std::vector<std::vector<Vec3>> kept_cells;
};

/// Balls (centre, radius), with "does one hold q" queries, over the box [lo, hi].
class BallSet {
 public:
  BallSet(const Vec3& lo, const Vec3& hi, double cell) : grid_(lo, hi, cell) {}
  void add(const Vec3& centre, double r) {
    grid_.add(static_cast<int>(balls_.size()), centre - Vec3{r, r, r}, centre + Vec3{r, r, r});
    balls_.emplace_back(centre, r);
  }
  /// Whether q lies in a ball grown by `slack` (a length).
  bool holds(const Vec3& q, double slack) const {
    return grid_.any_in(
        q, q, [&](int i) { return (balls_[i].first - q).norm() < balls_[i].second + slack; });
  }
  std::size_t size() const { return balls_.size(); }

 private:
  BucketGrid grid_;
  std::vector<std::pair<Vec3, double>> balls_;
};

/// What lies near a point (frame coordinates, within 2 h of the lattice's box): the triangles of
/// the faces that are not lattice faces, the surface's nodes, the boundary-layer points placed so
/// far; and which lattice face holds a point on a lattice plane. Keeps references to `nodes` and
/// `surface`.
class Surroundings {
 public:
  Surroundings(const std::vector<Vec3>& nodes, const Surface& surface, const Lattice& lattice,
               double h);
  /// The lattice face holding q, on the lattice planes index[a] (a = 0..2; -1: none), or -1.
  int on_lattice_face(const Vec3& q, const int (&index)[3]) const;
  /// The planes through lattice point q (its index) on which a lattice face holds it: bit a
  /// for the plane across axis a. Two bits: q lies on the CAD edge between two lattice faces;
  /// three: at a corner.
  int lattice_planes(const Vec3& q, const int (&index)[3]) const;
  /// Whether the ball (centre, r) holds no surface triangle, surface node or layer point (to
  /// 1e-9 of r).
  bool ball_is_empty(const Vec3& centre, double r) const;

  const Vec3 box_lo, box_hi;  ///< the box the queries cover
  TriangleSet curved;         ///< triangles of the faces that are not lattice faces
  TriangleSet every_face;     ///< triangles of every face (in the order of surface.triangles)
  PointSet surface_points;    ///< the surface's nodes
  PointSet layer_points;      ///< boundary-layer points (place_layers() adds them)
  /// The hexahedral core's points (lattice points and apexes) and the circumspheres of its cells
  /// and closing pyramids (emit_core() adds them): boundary-layer points placed after the core
  /// keep out of them, so that TetGen's Delaunay tets keep the core's cells and pyramids.
  PointSet core_points;
  BallSet core_balls;
  /// The buffer layer's hexahedra and pyramids, as their tets (emit_core() adds them): no point
  /// goes inside them or near them (kBufferClearance h for the lattice points).
  TetSet buffer_cells;

 private:
  // The lattice face holding q on the lattice plane index[axis] across `axis`, or -1.
  int face_on_plane(const Vec3& q, const int (&index)[3], int axis) const;

  const std::vector<Vec3>& nodes_;
  // Lattice faces' triangles per lattice plane (axis, index).
  std::map<std::pair<int, long>, std::vector<const SurfaceTriangle*>> plane_triangles_;
};

/// Inside/outside by ray parity along frame x lines through the surface's triangles, faces
/// between two solids left out. Keeps references to `nodes`.
class Parity {
 public:
  Parity(const std::vector<Vec3>& nodes, const Surface& surface,
         const std::vector<int>& face_solid_count, const Surroundings& around, double h);
  /// Crossings of the line {y, z} along x (nudged off lattice lines) with the surface, sorted.
  std::vector<double> crossings(double y, double z) const;
  /// Whether x is inside, given the crossings of its line.
  static bool inside_given(const std::vector<double>& xs, double x);
  /// Whether q is inside: inside_given(crossings(q.y, q.z), q.x), the crossings before q.x
  /// counted as they come.
  bool inside(const Vec3& q) const;

 private:
  /// Calls f(x) for each crossing of the line {y, z} (nudged as crossings() does), unsorted,
  /// up to the triangles that start beyond `before` along x.
  template <typename F>
  void for_each_crossing(double y, double z, double before, F&& f) const;

  const std::vector<Vec3>& nodes_;
  double h_;
  std::vector<std::array<int, 3>> triangles_;  // by their smallest x
  std::vector<double> least_x_;                // per triangle
  BucketGrid yz_;                              // each bucket's in the order of triangles_
};

/// Per lattice point (i fastest, then j, then k), whether it is kept and the lattice face it
/// lies on (-1: inside).
struct KeptPoints {
  std::vector<char> kept;
  std::vector<int> face;
};

/// The lattice points inside (or on a lattice face), not within `keep_distance` of a face that
/// is not a lattice face, nor within `margin` of a boundary-layer point; on a lattice face, not
/// within `margin` of a surface node that is not at the point. A point on an edge between
/// lattice faces (whose sides only its lattice points split) stays within `keep_distance` of
/// other faces, and within `margin` of surface nodes off the edge's lines (those sharing two of
/// the coordinates of its planes). Swept along `sweep_axis` (-1: not swept), every point on a
/// wall (a lattice face across another axis) is such a point, its planes the wall's and the one
/// across the sweep axis: the sweep repeats the first plane, where the wall is a side; but not
/// within `keep_distance` of a node on its line (where the side meets another face: the layers
/// carried onto the wall go there).
KeptPoints keep_lattice_points(const Lattice& lattice, const Surroundings& around,
                               const Parity& parity, double keep_distance, double margin,
                               int sweep_axis);

/// Whether q, on a lattice plane across `axis`, lies in a square of four kept lattice points of
/// that plane (a lattice cell's face, which TetGen keeps whole, core or not).
bool in_kept_square(const Lattice& lattice, const KeptPoints& kept, const Vec3& q, int axis);

/// Reorders `inserted` so that the points on lattice faces come first (stable); returns their
/// number.
std::size_t face_points_first(InsertedPoints& inserted);

}  // namespace hexmerge::mesher
