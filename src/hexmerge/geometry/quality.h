#pragma once
/// @file
/// Volumes and shape measures of linear cells and quadrilateral faces.

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

/// Signed volume of tet (a, b, c, d): positive when det(b-a, c-a, d-a) > 0.
double tet_volume(const double* a, const double* b, const double* c, const double* d);

/// Signed volume of a cell whose quad faces are bilinear patches (divergence theorem; the flux
/// through a bilinear quad is the mean of its two triangulations). Positive for a valid cell.
/// @param[in] points    #V by 3 coordinates
/// @param[in] vertices  the cell's vertex ids in the local order of cell_type.h
double cell_volume(CellType type, const double* points, const index_t* vertices);

/// Verdict's scaled Jacobian: the minimum over the cell's corners (cell_type.h, `corner`) of the
/// determinant of the three normalised edge vectors, times the type's scale, so that the ideal
/// cell scores 1. Negative for an inverted corner. Capped at 1 (pyramids can exceed it); never
/// clamped below, so the sign tells validity.
double scaled_jacobian(CellType type, const double* points, const index_t* vertices);

/// Dihedral angle, in degrees, between triangles (a, b, c) and (a, c, d) across their shared
/// diagonal a-c: 180 when the quad a-b-c-d is flat, smaller the more it folds.
double quad_dihedral_angle(const double* a, const double* b, const double* c, const double* d);

/// The largest interior corner angle, in degrees, of the quad a-b-c-d (each measured in 3D
/// between the two edges meeting at the corner). 90 for a rectangle.
double quad_max_corner_angle(const double* a, const double* b, const double* c, const double* d);

/// Whether the quad a-b-c-d lies in one plane to round-off: d off the plane of a, b and c by a
/// volume |((b - a) x (c - a)) . (d - a)| of at most 1e-9 |b - a| |c - a| |d - a| (the
/// hexahedra and prisms of swept meshes and lattices, a cross-section repeated from plane to
/// plane).
bool quad_is_planar(const double* a, const double* b, const double* c, const double* d);

/// A bound on an angle, in degrees, with its cosine: the predicates below compare cosines and
/// take an arccosine only when the angle is within about 1e-7 degrees of the bound (or the bound
/// is outside [0, 180]).
struct AngleBound {
  explicit AngleBound(double bound);
  double degrees;
  double cosine;
};

/// quad_dihedral_angle(a, b, c, d) < min_angle.degrees: the same answer, faster.
bool quad_dihedral_angle_below(const double* a, const double* b, const double* c, const double* d,
                               const AngleBound& min_angle);

/// quad_max_corner_angle(a, b, c, d) > max_angle.degrees: the same answer, faster.
bool quad_max_corner_angle_above(const double* a, const double* b, const double* c, const double* d,
                                 const AngleBound& max_angle);

}  // namespace hexmerge
