#pragma once
/// @file
/// How many tets a shape meshes into at a size, and the memory that takes, before any work
/// (internal header: includes OpenCASCADE).

#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Shape.hxx>
#include <cstdint>
#include <string>
#include <vector>

#include "hexmerge/occ/mesher/thin_walls.h"

namespace hexmerge::mesher {

/// The estimate of estimate_size().
struct SizeEstimate {
  double tets = 0;   ///< tets mesh_shape() makes (fitted on 45 runs over 14 real parts: the
                     ///< count was between 0.4 and 1.5 times this; shapes of large planar
                     ///< lattice faces make fewer, the bracket 0.3 times)
  double bytes = 0;  ///< peak memory of meshing and recombining them
};

/// Tets ≈ 11 V / h³ + 10 A / h² (V the shape's volume, A its area: the lattice inside, the
/// refined surface and its layers at the boundary), at kBytesPerTet each; a cylinder, sphere or
/// torus face of radius r (a torus: its minor one) whose strips BRepMesh makes at most
/// kSurfaceAngle (surface.h) or the chord of sagitta `deflection` wide, a radians, are finer than h
/// counts f = 0.866 h / (r a) times its 10 A / h² (f > 1; pyocc_11752's 178 channels of radius 1.1
/// and 1.6 mm, 1140 mm long, at h 13.08: f 18 to 26, 2.8k triangles each, not 150).
/// `volume`: the shape's (Shape::volume's mass).
SizeEstimate estimate_size(const TopoDS_Shape& shape, double volume, double size,
                           double deflection);

/// The smallest size from `size` up whose estimate_size() (deflection `deflection_ratio` times
/// the size) needs at most `bytes`, to 1 %, rounded up to three significant digits: pyocc_11752
/// under 8.45 GB, 11.8 where the cube root of the excess at its 250k size 7.56 said 8.81 (its
/// channels' strips grow with 1 / h only).
double size_that_fits(const TopoDS_Shape& shape, double volume, double size,
                      double deflection_ratio, double bytes);

/// Tets that local sizes add to estimate_size()'s: per face of local size s < h, its area A times
/// 10 / s² (its surface) + 11 / (2 g) (1 / s² - 1 / h²) (the zone graded by g inside), less its
/// 10 A / h²; per edge of length L, 11 π L / (g² s) (the graded zone around it). Faces and edges
/// as in the maps (`face_size`, `edge_size` per index from 0; h: none).
double estimate_local_tets(const TopTools_IndexedMapOfShape& faces,
                           const TopTools_IndexedMapOfShape& edges,
                           const std::vector<double>& face_size,
                           const std::vector<double>& edge_size, double h, double grading);

/// Tets that patches with sizes of their own (thin_wall_sizes()) add to estimate_size()'s: per
/// patch of size s < h, as a face of that size (estimate_local_tets()).
double estimate_patch_tets(const std::vector<SizedTriangle>& patches, double h, double grading);

/// Refuses a mesh that would not fit in memory: `memory_limit` GB, or the memory available
/// (available_memory()) when 0.
/// @throws InputError (Entity::Parameter) when `estimate` needs more, giving the tets, the
///         memory and the smallest size (from `size` up, size_that_fits()) whose estimate fits;
///         `why` (may be empty) says what the estimate counts beyond the shape's volume and area
void refuse_if_too_large(const SizeEstimate& estimate, const TopoDS_Shape& shape, double volume,
                         double size, double deflection_ratio, double memory_limit,
                         const std::string& why);

/// Peak bytes per tet of meshing a shape and recombining the tets (TetGen's process, the
/// engine's candidates and selection on lattice tets, the arrays handed to Python).
constexpr double kBytesPerTet = 3000;

/// The memory the system can give without swapping (Linux: MemAvailable), or less when the
/// process's address space is limited (what the limit leaves above the space it holds), in
/// bytes; 0 when unknown.
std::uint64_t available_memory();

}  // namespace hexmerge::mesher
