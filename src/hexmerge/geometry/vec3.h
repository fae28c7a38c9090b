#pragma once
/// @file
/// Minimal 3-vector arithmetic on double[3] coordinates.

#include <cmath>

namespace hexmerge {

struct Vec3 {
  double x, y, z;
  static Vec3 of(const double* p) { return {p[0], p[1], p[2]}; }
  Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
  double dot(const Vec3& o) const { return x * o.x + y * o.y + z * o.z; }
  Vec3 cross(const Vec3& o) const {
    return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x};
  }
  double norm() const { return std::sqrt(dot(*this)); }
};

inline double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return a.cross(b).dot(c); }

}  // namespace hexmerge
