#pragma once
/// @file
/// A CAD face's triangles in the plane of its parameters (internal header of the buffer layer):
/// the chart, points placed in it, the outline's sides near a place, and the face triangulated
/// again with quads in it. Boxes and grids in that plane are spatial.h's BucketGrid with z = 0.
/// No OpenCASCADE here (CGAL's headers go before it in the source).

#include <array>
#include <initializer_list>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;

using P2 = std::array<double, 2>;

/// Twice the signed area of triangle abc (positive counter-clockwise).
double cross2(const P2& a, const P2& b, const P2& c);
/// Distance from p to segment ab.
double to_segment(const P2& p, const P2& a, const P2& b);
/// Whether segments ab and cd cross or touch.
bool segments_meet(const P2& a, const P2& b, const P2& c, const P2& d);

/// The box of points in the plane as BucketGrid's (z = 0), grown by `margin` (and a hair more, so
/// that a test at exactly the margin still finds what it holds).
std::pair<Vec3, Vec3> plane_box(std::initializer_list<P2> points, double margin);

/// A grid over the box of `xy` of cells about `cell` wide (at most about 1,000 across), holding
/// each item's box: items(add) calls add(item, box) for every item.
template <typename Items>
BucketGrid plane_grid(const std::vector<P2>& xy, double cell, const Items& items) {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
  for (std::size_t i = 0; i < xy.size(); ++i) {
    const Vec3 p{xy[i][0], xy[i][1], 0};
    lo = i == 0 ? p : vmin(lo, p), hi = i == 0 ? p : vmax(hi, p);
  }
  BucketGrid grid(lo, hi, std::max({cell, (hi.x - lo.x) / 1000, (hi.y - lo.y) / 1000, 1e-300}));
  items([&](int item, const std::pair<Vec3, Vec3>& box) { grid.add(item, box.first, box.second); });
  return grid;
}

/// One face's triangles in its parameters scaled by their mean metric (x = a u + b v, y = c v):
/// a vertex per node and parameters (a node on the seam is two), its sides used once (its edges
/// and seams), and whether its triangles go counter-clockwise.
struct FaceChart {
  int face = -1;
  double a = 1, b = 0, c = 1;
  double u_period = 0, v_period = 0;        // 0: not periodic
  std::vector<int> triangles;               // into the surface's
  std::vector<int> node;                    // per vertex
  std::vector<UV> uv;                       // per vertex
  std::vector<P2> xy;                       // per vertex
  std::vector<std::array<int, 3>> corners;  // per triangle, its vertices
  std::vector<std::array<int, 2>> outline;  // sides used once
  std::vector<char> on_outline;             // per vertex
  bool counter_clockwise = true;
  double area = 0;                          // of its triangles (3D)
  double smallest_angle = 0;                // of its triangles, degrees
  std::optional<BucketGrid> triangle_grid;  // its triangles by their boxes (place_in())
  std::optional<BucketGrid> outline_grid;   // its outline's sides by their boxes

  P2 scaled(const UV& p) const { return {a * p.u + b * p.v, c * p.v}; }
};

/// The chart of face `face` (its triangles: indices into surface.triangles), or none when its
/// metric cannot be fitted.
std::optional<FaceChart> chart_of(const Shape& shape, const Surface& surface,
                                  const std::vector<int>& triangles, int face);

/// The scaled parameters of uv inside the chart's triangles (shifted by whole periods where the
/// face is periodic, and uv with them), or none.
std::optional<P2> place_in(const FaceChart& chart, UV& uv);

/// Calls f(a, b) for the chart's outline sides ab whose boxes come within `margin` of the box of
/// `points`, until it returns true; whether it did.
template <typename F>
bool any_outline_side_near(const FaceChart& chart, std::initializer_list<P2> points, double margin,
                           const F& f) {
  const auto [lo, hi] = plane_box(points, margin);
  return chart.outline_grid->any_in(lo, hi, [&](int s) {
    const std::array<int, 2>& side = chart.outline[static_cast<std::size_t>(s)];
    return f(chart.xy[static_cast<std::size_t>(side[0])],
             chart.xy[static_cast<std::size_t>(side[1])]);
  });
}

/// Quads put into a face (the buffer layer's tops, the wall cells'): their corners at least
/// kQuadEdgeClearance h inside the face's edges, their sides crossing none and passing the edges'
/// nodes at half that; the face triangulated again keeps its area to kQuadAreaChange and no new
/// triangle's smallest angle falls under kQuadLeastAngle degrees (or the face's own smallest).
inline constexpr double kQuadEdgeClearance = 0.3;
inline constexpr double kQuadAreaChange = 0.02;
inline constexpr double kQuadLeastAngle = 15.0;

/// The scaled parameters of uv inside the chart (place_in(), uv shifted with them) at least
/// kQuadEdgeClearance h from its outline's sides, or none.
std::optional<P2> place_clear(const FaceChart& chart, UV& uv, double h);

/// Whether the quad `xy` (around) in the chart has its two triangles (on its diagonal from the
/// first corner) turning the same way and its sides crossing no side of the outline and passing
/// the outline's nodes at 0.5 kQuadEdgeClearance h or more.
bool quad_clear(const FaceChart& chart, const std::array<P2, 4>& xy, double h);

/// Per surface node, whether triangles of two faces or more use it (a face triangulated again
/// keeps it: retriangulate()'s `node_elsewhere`).
std::vector<char> nodes_on_several_faces(const Surface& surface);

/// A face triangulated again: its triangles (nodes: the surface's, or -1 - k for the k-th top)
/// and their parameters.
struct Retriangulated {
  std::vector<std::array<int, 3>> node;
  std::vector<std::array<UV, 3>> uv;
};

/// What a face triangulated again keeps: its inner nodes nearer than `node_clearance` h to a
/// quad go; its area to `area_change` of it; no new triangle's smallest angle under the smaller
/// of `least_angle` degrees and the face's own smallest.
struct RetriangulateLimits {
  double node_clearance;
  double area_change;
  double least_angle;
};

/// The chart's face triangulated again with the quads `quads` (tops by index into `top_xy`,
/// `top_uv` and `top_world`, around as the bases' corners, split on the diagonal from the first
/// to the third) in it, or none: where an inner node near a quad is also another face's
/// (`node_elsewhere`, per surface node), two points fall at one place, constraints cross, the
/// outline bounds no region, or a limit is broken. Where only the smallest angle is (the rest
/// held), `poor_tops` (when given) gets the tops to blame: the corners of each triangle under
/// it that are tops, or, for one with none, the tops of the quads whose clearance took the
/// face's nodes beside it; empty when no triangle can be blamed so.
std::optional<Retriangulated> retriangulate(
    const FaceChart& chart, const Surface& surface, const std::vector<std::array<int, 4>>& quads,
    const std::vector<P2>& top_xy, const std::vector<UV>& top_uv,
    const std::vector<Vec3>& top_world, const std::vector<char>& node_elsewhere, double h,
    const RetriangulateLimits& limits, std::vector<int>* poor_tops = nullptr);

/// The surface with each face of `remeshed` triangulated again: its triangles replaced by the new
/// ones, whose tops (-1 - k) are indices into `tops` (world coordinates; one node per top, on the
/// first face that has it), and the nodes no triangle uses any more dropped (the others
/// renumbered, as drop_unused_nodes()).
/// @return per top, its node (-1: in no triangle)
std::vector<int> put_in_surface(Surface& surface, const std::map<int, Retriangulated>& remeshed,
                                const std::vector<Vec3>& tops, double h);

}  // namespace hexmerge::mesher
