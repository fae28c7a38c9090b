#pragma once
/// @file
/// The lattice frame: three orthonormal axes and an origin (internal header of mesh_shape(); no
/// OpenCASCADE). Everything from the lattice on works in frame coordinates.

#include <algorithm>
#include <cmath>
#include <vector>

#include "hexmerge/geometry/vec3.h"

namespace hexmerge::mesher {

/// A right-handed orthonormal frame (axis[0..2], unit vectors, rows) and an origin.
struct Frame {
  Vec3 axis[3];
  Vec3 origin{0, 0, 0};
  /// World coordinates -> frame coordinates.
  Vec3 to_frame(const Vec3& p) const {
    const Vec3 d = p - origin;
    return {d.dot(axis[0]), d.dot(axis[1]), d.dot(axis[2])};
  }
  /// Frame coordinates -> world coordinates.
  Vec3 to_world(const Vec3& q) const {
    return origin + axis[0] * q.x + axis[1] * q.y + axis[2] * q.z;
  }
};

/// Completes e3 (and e1 when given) into a right-handed orthonormal frame at the origin.
/// @param[in] e3        the third axis (any length > 0)
/// @param[in] e1_hint   the first axis, projected normal to e3; null or shorter than 0.5: the
///                      axis of `fallback` least aligned with e3 instead
/// @param[in] fallback  three candidate first axes
Frame make_frame(const Vec3& e3, const Vec3* e1_hint, const Vec3 (&fallback)[3]);

/// A planar face normal to a frame axis: the axis and the face's offset along it (frame
/// coordinates).
struct AxisPlane {
  int axis;
  double offset;
  double width = 0;  ///< twice its area over its perimeter (a strip's width)
};

/// Lattice coordinates along one frame axis: planes at i * spacing (`ticks` empty), or at
/// ticks[i] (increasing, from 0). The frame coordinate of lattice coordinate t: plane t where t
/// is whole, linear within a cell (beyond the ends, along the end cells).
inline double lattice_coordinate(const std::vector<double>& ticks, double spacing, double t) {
  if (ticks.empty()) return t * spacing;
  const long last = static_cast<long>(ticks.size()) - 2;
  const long i = std::clamp(static_cast<long>(std::floor(t)), 0L, last);
  const double f = t - static_cast<double>(i);
  if (f == 0) return ticks[i];
  if (f == 1) return ticks[i + 1];
  return ticks[i] + f * (ticks[i + 1] - ticks[i]);
}

/// The lattice coordinate of frame coordinate x (the inverse of lattice_coordinate()): whole on
/// a plane.
inline double cells_coordinate(const std::vector<double>& ticks, double spacing, double x) {
  if (ticks.empty()) return x / spacing;
  const long above = std::upper_bound(ticks.begin(), ticks.end(), x) - ticks.begin();
  const long i = std::clamp(above - 1, 0L, static_cast<long>(ticks.size()) - 2);
  return static_cast<double>(i) + (x - ticks[i]) / (ticks[i + 1] - ticks[i]);
}

/// Whether frame coordinate x lies on a lattice plane (to `tolerance`) of the axis
/// lattice_coordinate() describes.
inline bool on_lattice_plane(const std::vector<double>& ticks, double spacing, double x,
                             double tolerance) {
  if (ticks.empty()) {
    const double k = x / spacing;
    return std::abs(k - std::round(k)) * spacing < tolerance;
  }
  return std::abs(x - lattice_coordinate(ticks, spacing,
                                         std::round(cells_coordinate(ticks, spacing, x)))) <
         tolerance;
}

}  // namespace hexmerge::mesher
