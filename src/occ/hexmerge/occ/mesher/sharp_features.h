#pragma once
/// @file
/// The CAD's sharp corners and edges: where the shape itself forces thin elements (internal
/// header of mesh_shape()). A tet with a corner in a face angle theta, or along a dihedral
/// angle theta, has a scaled Jacobian of at most sqrt(2) sin(theta) there, and a boundary
/// triangle in a face corner of theta an angle of at most theta.

#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/mesher/local_size.h"

namespace hexmerge::mesher {

struct Shape;
struct Surface;

/// A corner of a face: the face's angle between its two edges at a CAD vertex.
struct SharpCorner {
  int face = -1;        ///< 0-based, as Shape::faces
  int edges[2]{};       ///< the two edges meeting there, 0-based, as Shape::edges
  double angle = 0.0;   ///< degrees, in the face
  Vec3 point{0, 0, 0};  ///< the vertex
};

/// A CAD edge along which a solid's dihedral angle is sharp.
struct SharpEdge {
  int edge = -1;        ///< 0-based, as Shape::edges
  int faces[2]{};       ///< its two faces in the solid, 0-based
  double angle = 0.0;   ///< degrees, the smallest of the solid's angle at the points sampled
  Vec3 point{0, 0, 0};  ///< where it is smallest
};

/// The face corners and edges of the shape's solids with an angle, inside the solid, below
/// `limit` degrees. Face corners: at each vertex of each wire, the angle from the leaving
/// edge's tangent to the arriving edge's, turning about the face's outward normal (the face
/// lies on the left of its oriented edges); a degenerated edge between two edges is a point
/// (a cone sector's apex, a B-spline face's collapsed side where two edges meet at a cusp), the
/// normal there taken beside it; seams are no boundary (a whole cone's apex, a sphere's pole
/// have no corner). Edges: the solid's dihedral angle
/// at nine points along each edge between two distinct faces of the solid (seams are smooth).
struct SharpFeatures {
  std::vector<SharpCorner> corners;
  std::vector<SharpEdge> edges;
};
SharpFeatures sharp_features(const Shape& shape, double limit);

/// Per corner, the surface's node at its vertex: of its edges' segments' ends, the nearest to
/// it (-1: its edges have none).
std::vector<int> corner_nodes(const std::vector<SharpCorner>& corners, const Surface& surface);

/// The surface's nodes at the features, sorted: both ends of every segment on a sharp edge,
/// and per corner the node at its vertex (of its edges' segments' ends, the nearest to it).
std::vector<int> nodes_at(const SharpFeatures& features, const Surface& surface);

/// The features for the report (MeshShapeReport::sharp_features), faces and edges numbered as in
/// the shape as given (`faces`, `edges`).
std::vector<SharpFeatureReport> sharp_feature_reports(const SharpFeatures& features,
                                                      const ItemNumbering& faces,
                                                      const ItemNumbering& edges);

/// The angle, in degrees, under which a face corner or a dihedral edge keeps every tet at it
/// below a scaled Jacobian of 0.2: asin(0.2 / sqrt(2)).
constexpr double kSharpAngle = 8.13;

}  // namespace hexmerge::mesher
