#pragma once
/// @file
/// Small helpers the mesher's stages share (internal header of mesh_shape(); no OpenCASCADE):
/// component-wise minimum and maximum, a coordinate by axis, the keys of an unordered node pair
/// and of a triangle.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "hexmerge/core/index.h"
#include "hexmerge/geometry/vec3.h"

namespace hexmerge::mesher {

/// The key of the unordered pair {a, b} (the smaller in the high 32 bits).
inline std::uint64_t pair_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

/// The smaller and the larger of the pair whose pair_key() is `key`.
inline int pair_lo(std::uint64_t key) { return static_cast<int>(key >> 32); }
inline int pair_hi(std::uint64_t key) { return static_cast<int>(key & 0xffffffffu); }

/// A triangle (a tet's face) by its sorted vertices, and its hash.
using FaceKey = std::array<index_t, 3>;
inline FaceKey face_key(index_t a, index_t b, index_t c) {
  FaceKey k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}
struct FaceKeyHash {
  std::size_t operator()(const FaceKey& k) const {
    return (static_cast<std::size_t>(k[0]) * 73856093u) ^
           (static_cast<std::size_t>(k[1]) * 19349663u) ^
           (static_cast<std::size_t>(k[2]) * 83492791u);
  }
};

/// Component-wise minimum and maximum.
inline Vec3 vmin(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 vmax(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
/// Coordinate `axis` (0, 1, 2: x, y, z) of v, read and written.
inline double coord(const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }
inline void set_coord(Vec3& v, int axis, double value) {
  (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = value;
}
/// v scaled to length 1 (v must not be zero).
inline Vec3 unit(const Vec3& v) { return v * (1.0 / v.norm()); }

}  // namespace hexmerge::mesher
