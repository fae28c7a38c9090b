#pragma once
/// @file
/// The distance from a point to a triangle.

#include "hexmerge/geometry/vec3.h"

namespace hexmerge {

/// The point of triangle abc nearest to p, which is a + s (b - a) + t (c - a) (Ericson,
/// Real-Time Collision Detection, 5.1.5).
Vec3 nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double& s,
                         double& t);

/// Squared distance from p to triangle abc.
double squared_distance_to_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace hexmerge
