#include "hexmerge/occ/mesher/thin_walls.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>

#include "hexmerge/occ/mesher/spatial.h"

namespace hexmerge::mesher {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Ray = Kernel::Ray_3;
using Segment = Kernel::Segment_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

using Hit = Tree::Intersection_and_primitive_id<Segment>::Type;

Point point(const Vec3& p) { return {p.x, p.y, p.z}; }

// How far from `from` a probe's intersection begins (a point, or the nearer end of a segment).
double distance_along(const Point& from, const decltype(Hit::first)& at) {
  if (const Point* p = boost::get<Point>(&at)) return std::sqrt(CGAL::squared_distance(from, *p));
  const Segment& s = boost::get<Segment>(at);
  return std::sqrt(
      std::min(CGAL::squared_distance(from, s.source()), CGAL::squared_distance(from, s.target())));
}

}  // namespace

std::vector<SizedTriangle> thin_wall_sizes(const Surface& surface, double h, double thinnest,
                                           UnsizedWalls* unsized) {
  // The patches and the triangle each comes from: each triangle cut into bands across from its
  // shortest side, each band into quads split in two, sides at most h (the diagonals 2 h):
  // a needle triangle along a channel 1,140 mm long (pyocc_11752) in as many patches as its
  // length holds, not their square (halving the longest side made 27 million from 39k). The
  // rays go against the patches: the boxes of such needles span the part.
  std::vector<Triangle> patches;
  std::vector<std::size_t> source;
  std::vector<Vec3> normals;  // per triangle
  for (std::size_t i = 0; i < surface.triangles.size(); ++i) {
    const SurfaceTriangle& t = surface.triangles[i];
    std::array<Vec3, 3> v;
    for (int k = 0; k < 3; ++k) v[k] = surface.nodes[static_cast<std::size_t>(t.node[k])];
    const Vec3 n = normal_of(surface.nodes, t.node[0], t.node[1], t.node[2]);
    const double length = n.norm();
    normals.push_back(length > 0 ? n * (1 / length) : Vec3{0, 0, 0});
    if (!(length > 0)) continue;
    // Apex c across the shortest side ab (the order kept: the patches turn as the triangle).
    int shortest = 0;
    for (int e = 1; e < 3; ++e)
      if ((v[(e + 1) % 3] - v[e]).norm() < (v[(shortest + 1) % 3] - v[shortest]).norm())
        shortest = e;
    const Vec3 &a = v[shortest], &b = v[(shortest + 1) % 3], &c = v[(shortest + 2) % 3];
    const int bands =
        std::max(1, static_cast<int>(std::ceil(std::max((a - c).norm(), (b - c).norm()) / h)));
    for (int band = 0; band < bands; ++band) {
      const double t0 = static_cast<double>(band) / bands,
                   t1 = static_cast<double>(band + 1) / bands;
      const Vec3 l0 = c + (a - c) * t0, r0 = c + (b - c) * t0, l1 = c + (a - c) * t1,
                 r1 = c + (b - c) * t1;
      const int pieces = std::max(1, static_cast<int>(std::ceil((r1 - l1).norm() / h)));
      for (int k = 0; k < pieces; ++k) {
        const double s0 = static_cast<double>(k) / pieces, s1 = static_cast<double>(k + 1) / pieces;
        const Vec3 p00 = l0 + (r0 - l0) * s0, p01 = l0 + (r0 - l0) * s1, p10 = l1 + (r1 - l1) * s0,
                   p11 = l1 + (r1 - l1) * s1;
        // (a, b, c) turns as p10, p11, p00: the two triangles of the quad, the first empty at
        // the apex.
        if (band > 0) {
          patches.emplace_back(point(p00), point(p11), point(p01));
          source.push_back(i);
        }
        patches.emplace_back(point(p10), point(p11), point(p00));
        source.push_back(i);
      }
    }
  }
  std::vector<SizedTriangle> out;
  if (patches.empty()) return out;
  const Tree tree(patches.begin(), patches.end());
  const double facing = -1 / std::sqrt(1 + kWallTaper * kWallTaper);  // -cos(atan(taper))
  std::vector<Hit> hits;
  // The wall's thickness under `from` on patch k (from triangle source[k]): along its inward
  // normal to the first patch of another triangle, when that one faces back nearly parallel
  // (kWallTaper); NaN for none within kThinWall h.
  const auto thickness_at = [&](const Point& from, std::size_t k) {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    const Vec3& n = normals[source[k]];
    // Only walls under kThinWall h count: the probe goes that far, not across the part (a ray
    // along pyocc_11752's needles, through boxes that span it, took 40 s at h 6.25).
    const Segment probe(from, from - (kThinWall * h) * Kernel::Vector_3(n.x, n.y, n.z));
    hits.clear();
    tree.all_intersections(probe, std::back_inserter(hits));
    // The first hit along the probe, not on the patch's own triangle (along another patch in its
    // plane: no thickness to measure).
    const Hit* first = nullptr;
    double nearest = std::numeric_limits<double>::infinity();
    for (const Hit& hit : hits) {
      if (source[static_cast<std::size_t>(hit.second - patches.begin())] == source[k]) continue;
      const double d = distance_along(from, hit.first);
      if (d < nearest) nearest = d, first = &hit;
    }
    if (!first) return kNone;
    const std::size_t j = source[static_cast<std::size_t>(first->second - patches.begin())];
    if (normals[j].dot(n) > facing) return kNone;         // a wedge, a face across a corner
    if (!boost::get<Point>(&first->first)) return kNone;  // along the patch: no thickness
    // The point where the ray along the probe meets that patch (to the last digit as a ray
    // query finds it).
    const auto meets =
        CGAL::intersection(Ray(from, from - Kernel::Vector_3(n.x, n.y, n.z)), *first->second);
    const Point* at = meets ? boost::get<Point>(&*meets) : nullptr;
    return at ? std::sqrt(CGAL::squared_distance(from, *at)) : kNone;
  };
  std::vector<double> thickness(patches.size());
  for (std::size_t k = 0; k < patches.size(); ++k)
    thickness[k] = thickness_at(CGAL::centroid(patches[k]), k);
  // The walls too thin to size (under `thinnest`): their patches' centroids.
  const auto vec = [](const Point& p) { return Vec3{p.x(), p.y(), p.z()}; };
  Vec3 lo = surface.nodes.front(), hi = lo;
  for (const Vec3& p : surface.nodes) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double reach = kTooThinReach * h;
  PointSet too_thin(lo, hi, reach);
  for (std::size_t k = 0; k < patches.size(); ++k)
    if (thickness[k] < thinnest) too_thin.add(vec(CGAL::centroid(patches[k])));
  // Whether the wall keeps its thickness t across patch k: probed again from near each corner (a
  // twentieth of the way in), within a factor kEvenWallRatio of the centre's.
  const auto even = [&](std::size_t k, const Point& centre, double t) {
    const Triangle& q = patches[k];
    for (int c = 0; c < 3; ++c) {
      const double there = thickness_at(q[c] + (centre - q[c]) * 0.05, k);
      if (!(there <= kEvenWallRatio * t && there * kEvenWallRatio >= t)) return false;
    }
    return true;
  };
  if (unsized) *unsized = UnsizedWalls{};
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const Triangle& q = patches[k];
    const Point centre = CGAL::centroid(q);
    const double t = thickness[k];
    if (unsized && t > 0 && t < thinnest && even(k, centre, t)) {
      unsized->thinnest = unsized->patches > 0 ? std::min(unsized->thinnest, t) : t;
      unsized->thickest = std::max(unsized->thickest, t);
      ++unsized->patches;
    }
    if (!(t < kThinWall * h && t >= thinnest)) continue;
    // Under kEvenWall h, a wall only kTooThinReach h from where it is thinner than sized, and
    // only where it keeps its thickness across the patch.
    if (t < kEvenWall * h && (too_thin.any_within(vec(centre), reach) || !even(k, centre, t)))
      continue;
    out.push_back({vec(q[0]), vec(q[1]), vec(q[2]), kThinWallSizeFactor * t});
  }
  return out;
}

}  // namespace hexmerge::mesher
