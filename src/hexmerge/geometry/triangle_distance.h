#pragma once
/// @file
/// The distance from a point to a triangle.

#include "hexmerge/geometry/vec3.h"

namespace hexmerge {

/// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
double squared_distance_to_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace hexmerge
