#pragma once
/// @file
/// The facets with loops triangulated before TetGen sees them (internal to the TetGen layer).
/// TetGen 1.5 triangulates such a facet itself, by Lawson flips whose in-circle test is computed
/// in floating point: on a loop whose nodes lie evenly along straight sides (a lattice face's
/// boundary, nodes every lattice step) four nodes are cocircular, the test answers both ways,
/// and the flips never end (thin_bracket at h 0.574: four runs of TetGen past its time limit,
/// 15 GB; the face's outer loop alone does it, 440 of its 452 nodes collinear in runs). The
/// triangulation here is CGAL's constrained Delaunay one with exact predicates.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_set>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::tetgen {

/// Replaces each facet that has a polygon of more than three points by one facet per triangle
/// of its constrained Delaunay triangulation (same marker): the facet's points (its polygons'
/// and its single points), its polygons' sides kept, the triangles outside its outer loops and
/// inside its holes (the regions around its hole points, up to the sides) left out, as TetGen
/// does. No point is added. A facet is left as it is when it is not planar to 1e-6 of its size,
/// two of its points fall at one place in its plane or two of its sides cross (TetGen then says
/// what is wrong with it).
/// Where four points of a facet are cocircular (a lattice face's cells), its triangulation takes
/// the diagonal `delaunay_edges` has and not the other: TetGen's Delaunay tetrahedralisation of
/// the points (side_key()), which it starts from. With other diagonals it recovered them by flips
/// through the lattice cells behind (gmsh_part at h 6.99 / 7: hex volume 41.0 / 39.0 % -> 28.7 /
/// 34.0 %).
/// @param[in,out] facets          the complex's facets
/// @param[in]     points          the complex's points
/// @param[in]     delaunay_edges  the sides of the points' Delaunay tets, or null
/// @return the number of facets triangulated
std::size_t triangulate_facets(std::vector<Facet>& facets, const std::vector<Vec3>& points,
                               const std::unordered_set<std::uint64_t>* delaunay_edges);

/// Points inside an axis-normal facet that raise the smallest angle of its constrained Delaunay
/// triangulation (its polygons' points and sides, its single points): in rounds, the
/// circumcentres of the triangles with an angle under `min_angle` (radians), worst first, then of
/// those whose circumradius exceeds `max_radius` at their circumcentre, largest over it first,
/// where the centre lies inside the facet, outside the diametral circle of every side near it
/// (the sides are not split) and at least half the triangle's circumradius from every point and
/// every other centre of the round, and where `accept` takes it; until no triangle gets one or
/// `max_points` are added. The facet is not changed. Nothing for a facet triangulate_facets()
/// would leave to TetGen.
/// @return the points, in the facet's plane, in the points' coordinates
std::vector<Vec3> refine_facet(const Facet& facet, const std::vector<Vec3>& points,
                               double min_angle,
                               const std::function<double(const Vec3&)>& max_radius,
                               const std::function<bool(const Vec3&)>& accept,
                               std::size_t max_points);

/// Whether the facet has a loop (a polygon of more than three points) for TetGen to triangulate.
bool has_loop(const Facet& facet);

/// The key of the side between points a and b, either way round.
std::uint64_t side_key(int a, int b);

}  // namespace hexmerge::tetgen
