#pragma once
/// @file
/// Points on the axes of a shape's thin round parts (internal header of mesh_shape(); no
/// OpenCASCADE): wires, leads, pins and coils no thicker than about h, inside which the lattice
/// keeps no point and TetGen joins the tube's own surface nodes across it.

#include <cstddef>

#include "hexmerge/occ/mesher/lattice.h"

namespace hexmerge::mesher {

struct Shape;

/// Tubes thinner than this times h get points on their axes.
inline constexpr double kThinTube = 0.75;
/// Their points' spacing along the axis, times h.
inline constexpr double kAxisSpacing = 0.5;

/// Points on the axis of every cylinder, and the centre circle of every torus, of radius under
/// kThinTube h whose face turns through half a turn or more round the axis (a wire or pin, or
/// half of one: not a fillet; a torus bent by any angle, a wire's bend), kAxisSpacing h apart
/// along the face, where the axis is inside the shape (the tube is material, not a hole) and
/// the point is at least half the radius from every surface triangle of a face that is no
/// lattice face, half h from the core's and the layers' points, and kAxisSpacing h from
/// another such point. KiCad's axial inductor (leads of radius 0.4 mm at h 0.77, bent by
/// quarter tori): without them, the tets inside its leads joined four of the lead's surface
/// nodes each; with points h apart on the straight leads only, 451 tets under scaled Jacobian
/// 0.2; with these, 74.
/// @return the points appended to `inserted` (frame coordinates, on no lattice face)
std::size_t place_axis_points(const Shape& s, const Lattice& lattice, const Surroundings& around,
                              const Parity& parity, double h, InsertedPoints& inserted);

}  // namespace hexmerge::mesher
