#pragma once
/// @file
/// Thin walls (internal header of mesh_shape(); no OpenCASCADE): where the solid is from the
/// chord deflection to 0.2 h thick, its surface gets a size of its own, so that the tets across the
/// wall are not flat (a wall 0.175 h thick between triangles of side h holds no tet much better
/// than scaled Jacobian 0.2: gmsh_1385_Laufrad_1000's blades at its 50k size, 112 elements under
/// 0.2; at 0.2 h, a third of the side, about 0.25).

#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

/// A patch of the surface (world coordinates) with a size of its own.
struct SizedTriangle {
  Vec3 a, b, c;
  double size;
};

/// Across a wall from the chord deflection to kThinWall h thick, the surface gets
/// kThinWallSizeFactor times the wall's thickness: a tet of three nodes on one side and one on
/// the other then has a height of a third of its base's sides. (Walls up to h / 3 sized too:
/// gmsh_Zylkopf's tets under 0.2 at its 50k size the same, 13.) Walls thinner than kEvenWall h are
/// sized only kTooThinReach h away from where the wall is thinner than the deflection, and only
/// where the wall keeps its thickness across the patch (to within kEvenWallRatio at its corners):
/// a wall that tapers to nothing (a boss nearly tangent to a side), sized down to 0.06 h where its
/// sizes end beside triangles of h, made its tets worse, not better (a random part's elements
/// under 0.2 570 -> 2,282), and so did a fin 1 mm wide whose thickness doubles across it (306 ->
/// 1,420). Walls thinner than the deflection get none: there the two sides' triangles may cross
/// (a hollow box's walls 1.2 thick at h 80, 0.015 h, sized at the default deflection, 0.02 h,
/// took 255 s and left 12,029 tets under 0.2; unsized, 1,891: their tets are flat, as before walls
/// that thin were sized). Sized from the deflection, thin shells mesh at sizes of 12 to 50 times
/// their walls with every element at 0.2 or more (the CAX-IF s1 housings' shells at h 18 to 33:
/// 2,255 elements under 0.2, or no mesh at all, when walls were sized from h / 12 only; at h 77,
/// 0.02 h, on the surface at a quarter of the deflection), where they had no element above 0.2
/// across their walls.
inline constexpr double kThinWall = 0.2;
inline constexpr double kThinWallSizeFactor = 3;
inline constexpr double kEvenWall = 0.25 / kThinWallSizeFactor;
inline constexpr double kTooThinReach = 2;
inline constexpr double kEvenWallRatio = 1.5;
/// The far side of a wall runs nearly parallel to the near one: its normal within atan(kWallTaper)
/// (9.46 degrees) of the opposite of the near side's. Over a patch's new size, 3 t, the thickness
/// then changes by at most half of it. Faces that meet at a larger angle are a wedge, no wall:
/// there the thickness grows with the distance from their edge, and sizes of 3 t make the same
/// tets, only smaller and more of them (a random part's edge of 11.5 degrees, sized while faces
/// up to 45 degrees counted: 84 elements under 0.2 became 233; and a face across a concave corner
/// is none either).
inline constexpr double kWallTaper = 1.0 / 6;

/// The patches of the surface across thin walls: each triangle cut into patches of sides at
/// most h along and across bands (a quad's diagonal up to 2 h); from each patch's centroid along
/// the inward normal to the first triangle hit (the triangles oriented outward); where that one
/// runs nearly parallel (kWallTaper) and lies from `thinnest` to kThinWall h away, the patch
/// with the size, under kEvenWall h only farther than kTooThinReach h from every patch whose wall
/// is thinner than `thinnest` and where the wall is as thick under the patch's corners (a face
/// between two solids: into the solid its triangles leave; the faces of the other solid that face
/// back across it are probed from there).
/// Walls left unsized for being thinner than the deflection, where they keep their thickness
/// across a patch (a shell meshed at a size over 50 times its wall; not where two faces come
/// together at a tangent): their patches and their thinnest and thickest.
struct UnsizedWalls {
  std::size_t patches = 0;
  double thinnest = 0, thickest = 0;
};

/// @param[in]  surface   the surface (world coordinates), triangles oriented outward
/// @param[in]  thinnest  the thinnest wall sized: the surface's chord deflection
/// @param[out] unsized   null, or the even walls thinner than `thinnest` (none: 0 patches)
std::vector<SizedTriangle> thin_wall_sizes(const Surface& surface, double h, double thinnest,
                                           UnsizedWalls* unsized = nullptr);

}  // namespace hexmerge::mesher
