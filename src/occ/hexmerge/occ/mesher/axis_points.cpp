#include "hexmerge/occ/mesher/axis_points.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <cmath>
#include <functional>
#include <gp_Cylinder.hxx>
#include <gp_Torus.hxx>
#include <vector>

#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"

namespace hexmerge::mesher {

std::size_t place_axis_points(const Shape& s, const Lattice& lattice, const Surroundings& around,
                              const Parity& parity, double h, InsertedPoints& inserted) {
  const Frame& frame = lattice.frame;
  PointSet placed(around.box_lo, around.box_hi, h);
  std::size_t count = 0;
  for (int f = 1; f <= s.faces.Extent(); ++f) {
    const TopoDS_Face& face = TopoDS::Face(s.faces(f));
    const BRepAdaptor_Surface surface(face, false);
    double u0, u1, v0, v1;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    // The axis (a torus: its centre circle) as a curve of the face's other parameter.
    double radius = 0, lo = 0, hi = 0, run = 0;  // run: the axis's length over [lo, hi]
    std::function<Vec3(double)> axis;
    // Under half a turn round the axis (a cylinder's u, a torus's v): a fillet, not a tube.
    if (surface.GetType() == GeomAbs_Cylinder) {
      if (u1 - u0 < M_PI - 1e-9) continue;
      const gp_Cylinder cylinder = surface.Cylinder();
      radius = cylinder.Radius();
      const Vec3 origin = of(cylinder.Location()), along = of(cylinder.Axis().Direction());
      axis = [origin, along](double v) { return origin + along * v; };
      lo = v0, hi = v1, run = v1 - v0;
    } else if (surface.GetType() == GeomAbs_Torus) {
      if (v1 - v0 < M_PI - 1e-9) continue;
      const gp_Torus torus = surface.Torus();
      radius = torus.MinorRadius();
      const gp_Ax3 position = torus.Position();
      const Vec3 centre = of(position.Location()), x = of(position.XDirection()),
                 y = of(position.YDirection());
      const double major = torus.MajorRadius();
      axis = [centre, x, y, major](double u) {
        return centre + (x * std::cos(u) + y * std::sin(u)) * major;
      };
      lo = u0, hi = u1, run = major * (u1 - u0);
    } else {
      continue;
    }
    if (!(radius < kThinTube * h)) continue;
    const int pieces = std::max(1, static_cast<int>(std::round(run / (kAxisSpacing * h))));
    for (int k = 0; k < pieces; ++k) {
      const double t = lo + (hi - lo) * (k + 0.5) / pieces;
      const Vec3 q = frame.to_frame(axis(t));
      if (around.curved.any_within(q, 0.5 * radius) ||
          around.surface_points.any_within(q, 0.5 * radius) ||
          around.core_points.any_within(q, 0.5 * h) || around.layer_points.any_within(q, 0.5 * h) ||
          placed.any_within(q, 0.5 * kAxisSpacing * h) || !parity.inside(q))
        continue;
      placed.add(q);
      inserted.points.push_back(q);
      inserted.face.push_back(-1);
      ++count;
    }
  }
  return count;
}

}  // namespace hexmerge::mesher
