#pragma once
/// @file
/// The engine's input: a linear tetrahedral mesh as flat arrays (structure of arrays). Its
/// validation, which needs geometry, is check/validate_tet_mesh.h.

#include <cstdint>
#include <vector>

#include "hexmerge/core/index.h"

namespace hexmerge {

/// A tetrahedral mesh. Tet t has vertices tets[4t .. 4t+3] in VTK order (positive volume:
/// det(p1-p0, p2-p0, p3-p0) > 0). Coordinates of vertex v: points[3v .. 3v+2].
struct TetMesh {
  std::vector<double> points;         ///< #V by 3, row-major
  std::vector<index_t> tets;          ///< #T by 4, row-major
  std::vector<std::int32_t> regions;  ///< #T region ids (material / solid), or empty: one region

  index_t nb_vertices() const { return static_cast<index_t>(points.size() / 3); }
  index_t nb_tets() const { return static_cast<index_t>(tets.size() / 4); }
  std::int32_t region(index_t t) const { return regions.empty() ? 0 : regions[t]; }
  const double* point(index_t v) const { return &points[3 * static_cast<std::size_t>(v)]; }
  const index_t* tet(index_t t) const { return &tets[4 * static_cast<std::size_t>(t)]; }
};

/// The exponent k of the power of two that brings the largest absolute finite coordinate of
/// `points` (x, y, z per point) into [1, 2) when it lies outside [2^-32, 2^32]; 0 inside that
/// range (the points are used as given). Scaling by 2^k is exact, so geometric tests on the
/// scaled points give the answers they give at a moderate scale, where no product of
/// coordinates under- or overflows.
int normalising_exponent(const std::vector<double>& points);

}  // namespace hexmerge
