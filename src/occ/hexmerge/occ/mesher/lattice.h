#pragma once
/// @file
/// The cubic lattice in the frame and the points it gives TetGen (internal header of
/// mesh_shape(); no OpenCASCADE): the lattice laid through the shape's bounding box with as many
/// planar faces on its planes as can be ("lattice faces"), the surface's nodes in frame
/// coordinates, the queries of what lies near a point, inside/outside by ray parity, the lattice
/// points kept, and the hexahedral core with its closing pyramids' apexes.

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

/// Closing pyramids' apexes keep at least these fractions of h from every face and from the
/// surface's nodes (improve_tets() then nudges an apex whose tets fall under 0.2). At 0.1 and 0.25
/// (until 2026-12-03) they took core cells away beside curved faces: over the real parts at their
/// 50k sizes, median hex volume 48.9 -> 50.4 % (gmsh_Zylkopf 37.6 -> 43.0 %), 1,109 -> 1,115
/// elements under scaled Jacobian 0.2; smaller still (a quarter of these or less), more hexahedra
/// on no part and more elements under 0.2 (gmsh_as1-tu-203: 25 -> 48).
inline constexpr double kApexClearance = 0.02;
inline constexpr double kApexNodeClearance = 0.05;
/// A closing pyramid that is no longer Delaunay (pulled, or its apex in its cell's circumsphere)
/// keeps at least this scaled Jacobian, under which the recombination's default (0.3) and the
/// tets around its apex suffer.
inline constexpr double kCorePyramidFloor = 0.4;

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
/// planes than the uniform spacing does (a stepped part); add_core() then drops the cells whose
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
  /// Points of the core moved off the lattice (add_core()): where each is, and its lattice
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
  /// and closing pyramids (add_core() adds them): boundary-layer points placed after the core
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
  bool inside(const Vec3& q) const { return inside_given(crossings(q.y, q.z), q.x); }

 private:
  const std::vector<Vec3>& nodes_;
  double h_;
  std::vector<std::array<int, 3>> triangles_;
  BucketGrid yz_;
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

/// Counts of add_core().
struct CoreCounts {
  std::size_t nb_core_cells = 0;      ///< cells with all corners kept (the hexahedral core)
  std::size_t nb_lattice_points = 0;  ///< kept lattice points inserted
  std::size_t nb_apex_points = 0;     ///< closing pyramids' apexes inserted
  std::size_t nb_pulled_points = 0;   ///< of those, moved off the lattice towards the surface
  /// Closing pyramids kept although their apex lies in their cell's circumsphere (a narrow cell
  /// beside a wide one on a rectilinear axis): constrained, as the pulled ones.
  std::size_t nb_narrow_pyramids = 0;
  /// Closing pyramids' apexes placed inside, nearer their face, where the centre of the cell
  /// across is outside the shape (constrained, as the pulled ones).
  std::size_t nb_inner_apexes = 0;
};

/// A closing pyramid of the core: the core cell, its face's direction (0..5: -x, +x, -y, +y, -z,
/// +z) and the cell across, whose centre is the apex.
struct PyramidFace {
  int c[3], dir, n[3];
};

/// How pull_core() moves the core's points: per lattice point (Lattice::point_index) and per
/// apex (the index of its cell, i fastest).
struct PulledCore {
  std::unordered_map<std::size_t, Vec3> node, apex;
};

/// The hexahedral core as lay_core() lays it, before emit_core() gives its points to TetGen.
struct CoreLayout {
  std::vector<char> core;                  ///< per cell (i fastest): in the core
  std::vector<char> core_corner;           ///< per lattice point: a corner of a core cell
  std::vector<PyramidFace> pyramid_faces;  ///< the closing pyramids
  std::vector<char> apex_cell;             ///< per cell: its centre (or apex) closes a pyramid
  /// The cells whose apex lies in the circumsphere of a cell it closes (only with `pull`).
  std::vector<std::size_t> narrow_apexes;
  /// Per cell across a core face whose centre is outside: the apex inside that closes it.
  std::unordered_map<std::size_t, Vec3> inner_apex;
  PulledCore pulled;
  CoreCounts counts;  ///< the cells, narrow pyramids and inner apexes (the points: emit_core())
  /// Where lattice point p and the apex of the pyramids towards cell c are now.
  Vec3 point_at(const Lattice& lattice, std::size_t p) const;
  Vec3 apex_at(const Lattice& lattice, std::size_t c) const;
};

/// Hexahedra between closing pyramids' bases and the surface (buffer_layer()), each taking its
/// base's pyramid's place, and the pyramids that close their side faces where no other such
/// hexahedron does. Frame coordinates.
struct BufferCells {
  struct Hex {
    std::size_t face;         ///< its base: CoreLayout::pyramid_faces[face]
    std::array<Vec3, 4> top;  ///< the base's corners (base_corners() order) on the surface
  };
  /// A pyramid on a hexahedron's side face, the one over the base's side from lattice point lo
  /// to lattice point hi (lo < hi), whose apex (that of the pyramids towards cell apex_cell)
  /// closes a pyramid of the core too. The face splits on its diagonal from lo's corner to hi's
  /// top, as the hexahedron's split has it.
  struct SidePyramid {
    std::size_t lo, hi, apex_cell;
  };
  std::vector<Hex> hexes;
  std::vector<SidePyramid> pyramids;
  /// Per lattice point (by index), its projection onto the surface where a hexahedron uses it.
  std::unordered_map<std::size_t, Vec3> top_of;
};

/// The six tets of a cell around its diagonal from corner 0 to corner 7 (corner bits x, y, z, or
/// any right-handed bits): {0, q[0], q[1], 7} for each q.
/// No point of the core but a buffer cell's own corners lies nearer to the cell than this
/// fraction of h: the tets in the gap between would be flat (gmsh_Angled at its 50k size: a
/// lattice point 0.09 h beside a hexahedron's side face made 36 tets under 0.2).
inline constexpr double kBufferClearance = 0.25;

inline constexpr int kKuhnPaths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};

/// A buffer hexahedron's corners in kKuhnPaths' order: bits u, v across its base (corners in
/// base_corners() order, the base facing +axis when `up`), w to its tops; u and v swapped on a
/// base facing down its axis, so that the bits are right-handed.
std::array<Vec3, 8> buffer_hex_corners(const std::array<Vec3, 4>& base,
                                       const std::array<Vec3, 4>& top, bool up);

/// The hexahedral core: cells with 8 kept corners whose circumsphere holds nothing else; every
/// quad face between the core and another cell inside needs a closing pyramid whose apex is
/// that cell's centre and whose circumsphere holds nothing else, or the core cell goes (swept,
/// sweep_axis >= 0: only across the axis).
///
/// With `pull` (not swept), the core is pulled towards the surface: its nodes on closing
/// pyramids' bases move out along the bases' normals, the apexes with them, until the apexes
/// come near the faces (as far as the cells and pyramids stay good); see pull_core(). With
/// `pull` too, a core face whose closing pyramid's apex lies in its cell's circumsphere (a
/// narrow cell beside a wide one on a rectilinear axis), which Delaunay would join to the cell's
/// corners, keeps its cell (where the pyramid keeps kCorePyramidFloor): that cell, its pyramid
/// and the cells and pyramids whose circumspheres hold the apex are constrained as the moved.
CoreLayout lay_core(const Lattice& lattice, const Surroundings& around, const Parity& parity,
                    const KeptPoints& kept, int sweep_axis, double h, bool pull = false);

/// The core's points for TetGen: appends the kept lattice points that are no surface node, then
/// the apexes (but those of pyramids a buffer hexahedron replaces), to `inserted`; the points to
/// around.core_points, the circumspheres of the core's cells and closing pyramids to
/// around.core_balls, and the buffer's cells to around.buffer_cells. The cells and pyramids moved
/// (pulled, a narrow or inner apex, a moved point or a buffer cell's corner in their circumsphere,
/// a buffer hexahedron on them, an apex a buffer's pyramid shares) are no longer Delaunay: their
/// faces go to `inserted.constraints`, their splits to `inserted.splits`, the moved points to
/// `inserted.pulled`; so do the buffer's cells, whose splits also go to `inserted.kept_cells`.
/// Returns the layout's counts with the points'.
CoreCounts emit_core(const Lattice& lattice, const CoreLayout& layout, const BufferCells& buffer,
                     const KeptPoints& kept, double h, Surroundings& around,
                     InsertedPoints& inserted);

/// Reorders `inserted` so that the points on lattice faces come first (stable); returns their
/// number.
std::size_t face_points_first(InsertedPoints& inserted);

}  // namespace hexmerge::mesher
