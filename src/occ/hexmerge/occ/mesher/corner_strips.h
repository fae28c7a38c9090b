#pragma once
/// @file
/// The strips at the CAD's sharp face corners, their nodes taken out (internal header of
/// mesh_shape(); no OpenCASCADE): run after the surface repairs (surface_repair.h).

#include <cstddef>
#include <vector>

#include "hexmerge/occ/mesher/sharp_features.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;
class SizeField;

/// How far from a sharp corner (kCornerReach h) coarsen_sharp_corners() takes nodes out, and
/// how wide the strip between its edges must have become there (kCornerStripWidth h). Chosen on
/// six real parts with tangent corners (docs/benchmarks-real-parts.md): 0.3 and 4 gave fewer
/// elements under scaled Jacobian 0.2 than 0.5 and 4, 0.3 and 6, 0.2 and 3.
constexpr double kCornerStripWidth = 0.3;
constexpr double kCornerReach = 4.0;

/// At each sharp corner (a face narrowing between two edges at a vertex), the nodes on its two
/// edges within kCornerReach h of the vertex that lie closer than kCornerStripWidth h to the
/// other edge are taken out, nearest the corner first, when the strip gets that wide within the
/// reach on both edges: the two faces at each node re-triangulated over its fan (largest
/// smallest angle), the node's two segments joined. A node stays where a triangle would turn
/// over or leave its face further than `deflection` allows (as in collapse_sides()), where the
/// corner's face would get a smaller angle than its triangles at the node had (gmsh_as1-tu-203 at
/// 50k: a hole touching a side, its corner triangle 5.7 -> 3.3 degrees, tets 0.095 -> 0.058), or
/// the other face one smaller than the node's smallest; on a lattice face only the loops count
/// (its triangles are made again from them, facets.h). The rest are renumbered; Surface::seed
/// keeps each node's index from before collapse_sides().
/// @return the nodes taken out
std::size_t coarsen_sharp_corners(const Shape& s, Surface& surface,
                                  const std::vector<SharpCorner>& corners, double h,
                                  double deflection, const SizeField* deflection_field = nullptr);

}  // namespace hexmerge::mesher
