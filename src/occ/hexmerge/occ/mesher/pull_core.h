#pragma once
/// @file
/// The hexahedral core pulled towards the surface (internal header of mesh_shape(); no
/// OpenCASCADE): lay_core() moves the core's boundary nodes and its closing pyramids' apexes
/// off the lattice (pull_core()), and the cells and pyramids so moved, which TetGen keeps as
/// constraints, get the lattice's split back after it (resplit_core()).

#include <array>
#include <cstddef>
#include <optional>
#include <unordered_map>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/core.h"

namespace hexmerge::mesher {

/// The lattice point indices of the corners of the lattice square across frame axis `axis` at
/// plane index `plane` whose least corner is (p, q) along the two other axes (u = axis + 1,
/// v = axis + 2), around it: (p, q), (p + 1, q), (p + 1, q + 1), (p, q + 1). The core's faces go
/// to TetGen split on the diagonal from the first.
std::array<std::size_t, 4> face_corners(const Lattice& lattice, int axis, int plane, int p, int q);

/// The lattice point indices of the corners of face `f`'s base, around it (face_corners()).
std::array<std::size_t, 4> base_corners(const Lattice& lattice, const PyramidFace& f);

/// The lattice points `points` (indices) where the lattice has them.
std::array<Vec3, 4> lattice_points(const Lattice& lattice,
                                   const std::array<std::size_t, 4>& points);

/// Where the apex of the closing pyramids towards cell `cell` (its index, i fastest) lies before
/// the pull: the inner apex placed for it (place_inner_apex()), else the cell's centre.
Vec3 apex_home(const Lattice& lattice, const std::unordered_map<std::size_t, Vec3>& inner_apex,
               std::size_t cell);

/// The scaled Jacobian of a closing pyramid: its base's corners in base_corners()' order, its
/// apex towards +axis (`up`) or -axis.
double closing_pyramid_quality(const std::array<Vec3, 4>& base, const Vec3& apex, bool up);

/// An apex that closes face `f` where the centre of the cell across (f.n) is outside the shape:
/// on the way from the face's centre to that centre, 0.9 down to 0.5 of it, the first that is
/// inside, 0.15 h from every face and 0.25 h from every surface node (0.25 h from layer points),
/// makes a pyramid of scaled Jacobian kCorePyramidFloor, whose way from its base crosses no face
/// and which holds no surface node; `at` (an apex the cell across has already): that one, if it
/// is so for f. None: no such apex.
std::optional<Vec3> place_inner_apex(const Lattice& lattice, const Surroundings& around,
                                     const Parity& parity, const PyramidFace& f,
                                     const std::optional<Vec3>& at, double h);

/// The core's nodes on closing pyramids' bases moved out along the bases' normals (at an edge or
/// corner of the core, along each base's), each apex by the mean of its bases' corners' moves,
/// so that each apex comes 0.15 h from the faces; the moves halved where a moved cell would fall
/// below scaled Jacobian 0.9 or fold a quad face by more than 15 degrees, a pyramid below 0.4, a
/// moved node come within 0.25 h of a face or a surface node, an apex within kApexClearance h of
/// a face (kApexNodeClearance h of a node), or either leave the solid; dropped after five
/// halvings. Nodes on lattice faces, on the surface, or beside a kept point that is no core
/// corner (`core_corner`, per lattice point) or lies on a lattice face stay, and a face whose
/// apex cell has the core one cell on along its normal (that cell, or one beside it whose cell
/// beside the apex cell is out of the core: a gap in the core, which a pull from both sides
/// would close) moves at most 0.1 h. A moved pyramid's sides keep 0.02 h from the faces beyond
/// 0.25 h of their base corners.
/// @param[in] core        per cell (i fastest): in the core
/// @param[in] faces       the core's closing pyramids
/// @param[in] inner_apex  per cell across a face whose centre is outside: the apex inside that
///                        closes the face instead (else the apex is the cell's centre)
PulledCore pull_core(const Lattice& lattice, const Surroundings& around, const Parity& parity,
                     const KeptPoints& kept, const std::vector<char>& core,
                     const std::vector<char>& core_corner, const std::vector<PyramidFace>& faces,
                     const std::unordered_map<std::size_t, Vec3>& inner_apex, double h);

/// The pulled cells and pyramids split as the lattice's after the tetrahedraliser: it keeps their
/// faces (`constraints`, triangles by point index) but may fill one with a sliver on a face that
/// is no longer flat and the two tets beside it. Each region of the tets (joined across faces
/// that are no constraint) whose corners are a split's corners (`splits`, by position, found
/// within `tolerance` among `coordinates`, #points by 3) is replaced by the split's tets, when
/// these are positive, fill the same volume and have the region's outer faces (a region on the
/// surface keeps the surface's triangles). Returns how many regions were replaced.
/// @param[in,out] tets  #tets by 4
std::size_t resplit_core(const std::vector<double>& coordinates, std::vector<index_t>& tets,
                         const std::vector<std::array<int, 3>>& constraints,
                         const std::vector<InsertedPoints::Split>& splits, double tolerance);

}  // namespace hexmerge::mesher
