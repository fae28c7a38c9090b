#pragma once
/// @file
/// The hexahedral core on the kept lattice points (internal header of mesh_shape(); no
/// OpenCASCADE): its cells and closing pyramids laid (lay_core(), pulled towards the surface by
/// pull_core()), then their points, constraints and splits given to TetGen with the buffer
/// layer's cells (emit_core()).

#include <array>
#include <cstddef>
#include <unordered_map>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/lattice.h"

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

/// Counts of lay_core() and emit_core().
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

/// No point of the core but a buffer cell's own corners lies nearer to the cell than this
/// fraction of h: the tets in the gap between would be flat (gmsh_Angled at its 50k size: a
/// lattice point 0.09 h beside a hexahedron's side face made 36 tets under 0.2).
inline constexpr double kBufferClearance = 0.25;

/// The six tets of a cell around its diagonal from corner 0 to corner 7 (corner bits x, y, z, or
/// any right-handed bits): {0, q[0], q[1], 7} for each q.
inline constexpr int kKuhnPaths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};

/// The scaled Jacobian of tet (a, b, c, d) (negative when det(b - a, c - a, d - a) is).
double tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Whether q lies in the cell of `corner` (kKuhnPaths' order: in one of its six tets, on its faces
/// too, to 1e-6 of them), but not at a corner (within 1e-6 h): a point TetGen would put there.
bool cell_holds(const std::array<Vec3, 8>& corner, const Vec3& q, double h);

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

}  // namespace hexmerge::mesher
