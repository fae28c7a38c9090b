#pragma once
/// @file
/// Fixtures of the mesher's stage tests: OpenCASCADE solids loaded as the mesher loads them, and
/// the mesher's first steps (frame, triangulation, lattice) run on them.

#include <TopoDS_Shape.hxx>
#include <array>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/lattice.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::test {

/// The solid through BREP text, as mesh_shape() loads it.
mesher::Shape load(const TopoDS_Shape& solid);

/// A box [x0, x1] x [y0, y1] x [z0, z1].
TopoDS_Shape occ_box(double x0, double y0, double z0, double x1, double y1, double z1);
/// A cylinder of radius r from (0, 0, 0) to (0, 0, height).
TopoDS_Shape occ_cylinder(double r, double height);
/// An L: a 60 x 30 x 10 foot and a 10 x 30 x 40 flange at x in [0, 10], extruded along y, with
/// a hole of radius 4 along z through the foot at (40, 15). (No extrusion along any axis.)
TopoDS_Shape occ_bracket();
/// A step no one spacing fits: a 30 x 20 x 10 block and a 13 x 20 x 10 block on it at x in
/// [0, 13] (faces normal to x at 0, 13 and 30).
TopoDS_Shape occ_step();
/// Two boxes side by side (x in [0, 10] and [10, 23], 10 x 10), fused: the faces of y, z = 0 and
/// 10 come split in two along x = 10 (seams between coplanar faces).
TopoDS_Shape occ_split_box();
/// A 60 x 40 x 10 plate with a hole of radius 8 along z through its centre (30, 20).
TopoDS_Shape occ_plate_with_hole();
/// A 40 x 10 x 10 bar with a hole of radius 4.5 along z through (20, 5): 0.5 from both sides.
TopoDS_Shape occ_bar_with_hole_near_sides();

/// The mesher's steps up to the lattice, on a shape: load, frame, triangulation (chord
/// deflection 0.02 h), lattice.
struct Prepared {
  mesher::Shape shape;
  mesher::Surface surface;
  mesher::Lattice lattice;
  double h = 0;
};
Prepared prepare(const TopoDS_Shape& solid, double h, const std::string& frame = "global");

/// The surface repaired at p.h as mesh_shape() repairs a shape it does not sweep: refined, then
/// its short sides collapsed (chord deflection 0.02 h).
void repair_surface(Prepared& p);

/// The surface in frame coordinates (not swept), with its queries.
struct Placed {
  std::vector<Vec3> nodes;
  std::unique_ptr<mesher::Surroundings> around;
  std::unique_ptr<mesher::Parity> parity;
};
Placed place(const Prepared& p);

/// The hexahedral core laid and its points given to `inserted` (mesher::lay_core(), then
/// mesher::emit_core() with no buffer layer).
mesher::CoreCounts add_core(const mesher::Lattice& lattice, mesher::Surroundings& around,
                            const mesher::Parity& parity, const mesher::KeptPoints& kept,
                            int sweep_axis, double h, mesher::InsertedPoints& inserted,
                            bool pull = false);

/// Whether every directed side of the triangles is used once and its reverse once (a closed,
/// consistently oriented surface); `problem` says where not.
bool closed_and_oriented(const std::vector<mesher::SurfaceTriangle>& triangles,
                         std::string& problem);

/// The volume the triangles bound (positive when they face outward).
double enclosed_volume(const std::vector<Vec3>& nodes,
                       const std::vector<mesher::SurfaceTriangle>& triangles);

/// The surface's triangles by their corners' positions (rounded to `tolerance`), in any order.
class TriangleSet {
 public:
  TriangleSet(const mesher::Surface& surface, double tolerance);
  bool has(const Vec3& a, const Vec3& b, const Vec3& c) const;

 private:
  using Key = std::array<std::array<long long, 3>, 3>;
  Key key(const Vec3& a, const Vec3& b, const Vec3& c) const;
  double tolerance_;
  std::set<Key> triangles_;
};

/// Distance of point p (world coordinates) to face `face` of the shape (its surface, untrimmed).
double distance_to_face(const mesher::Shape& shape, int face, const Vec3& p);

/// Whether p (world coordinates) is inside the shape's solid(s), by OpenCASCADE's classifier
/// (BRepClass3d_SolidClassifier); `on` is set for points on the boundary (to 1e-7).
bool occ_inside(const mesher::Shape& shape, const Vec3& p, bool& on);

}  // namespace hexmerge::test
