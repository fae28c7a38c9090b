#include "hexmerge/occ/mesher/facets.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <utility>

#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/tetgen/triangulate_facets.h"

namespace hexmerge::mesher {

// The facets for TetGen: every triangle of the other faces as it is (TetGen keeps them, -Y);
// a lattice face as its boundary loops only, so that nothing but the inserted lattice points
// decides how it is cut into triangles (a triangle's edges would be segments TetGen must keep).
std::vector<Facet> make_facets(const Surface& surface, const std::vector<Vec3>& nodes,
                               const std::vector<bool>& lattice_face,
                               const std::vector<std::optional<AxisPlane>>& face_plane) {
  std::vector<Facet> facets;
  std::map<int, std::vector<const SurfaceTriangle*>> by_face;
  for (const SurfaceTriangle& t : surface.triangles) {
    if (lattice_face[t.face])
      by_face[t.face].push_back(&t);
    else
      facets.push_back(Facet{{{t.node[0], t.node[1], t.node[2]}}, {}, t.face + 1});
  }
  for (const auto& [face, triangles] : by_face) {
    std::unordered_map<std::uint64_t, int> uses;
    for (const SurfaceTriangle* t : triangles)
      for (int c = 0; c < 3; ++c) ++uses[pair_key(t->node[c], t->node[(c + 1) % 3])];
    // Directed boundary edges, as the triangles run; a node where loops touch (a glued face's
    // footprint meeting its outline) has two.
    std::unordered_map<int, std::vector<int>> next;
    for (const SurfaceTriangle* t : triangles)
      for (int c = 0; c < 3; ++c) {
        const int a = t->node[c], b = t->node[(c + 1) % 3];
        if (uses[pair_key(a, b)] == 1) next[a].push_back(b);
      }
    // The loops: walk the edges, and cut a loop off wherever the walk comes back to a node it
    // holds, so that every loop is simple (two loops touching at a node share it). Kept as
    // triangles, such a face took its lattice points as points inside single triangles, a hair
    // from their sides: gmsh_as1-tu-203 at h 2.239 ran TetGen's boundary recovery to its time
    // limit in every way with lattice faces.
    std::vector<std::vector<int>> loops;
    bool closed = true;
    while (!next.empty() && closed) {
      std::vector<int> path;
      std::unordered_map<int, std::size_t> at;  // node -> its place in path
      int a = next.begin()->first;
      for (;;) {
        if (const auto seen = at.find(a); seen != at.end()) {
          const std::size_t start = seen->second;
          loops.emplace_back(path.begin() + static_cast<std::ptrdiff_t>(start), path.end());
          for (std::size_t i = start; i < path.size(); ++i) at.erase(path[i]);
          path.resize(start);
        }
        const auto out = next.find(a);
        if (out == next.end()) break;
        at[a] = path.size();
        path.push_back(a);
        a = out->second.back();
        out->second.pop_back();
        if (out->second.empty()) next.erase(out);
      }
      closed = path.empty();
    }
    if (!closed) {  // the sides do not close into loops: keep the triangles
      for (const SurfaceTriangle* t : triangles)
        facets.push_back(Facet{{{t->node[0], t->node[1], t->node[2]}}, {}, face + 1});
      continue;
    }
    const int axis = face_plane[face]->axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
    // The face's side from all its triangles (one folded over, its sign turned, weighs less).
    Vec3 normal{0, 0, 0};
    for (const SurfaceTriangle* t : triangles)
      normal = normal +
               (nodes[t->node[1]] - nodes[t->node[0]]).cross(nodes[t->node[2]] - nodes[t->node[0]]);
    const double side = coord(normal, axis) > 0 ? 1 : -1;
    Facet facet{{}, {}, face + 1};
    for (std::vector<int>& loop : loops) {
      double area = 0;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Vec3 &p = nodes[loop[i]], &q = nodes[loop[(i + 1) % loop.size()]];
        area += coord(p, u) * coord(q, v) - coord(q, u) * coord(p, v);
      }
      if (area * side < 0) {
        // An inner loop: a point just beside its first edge, away from the face's triangles.
        const Vec3 &p = nodes[loop[0]], &q = nodes[loop[1]];
        Vec3 axis_normal{0, 0, 0};
        set_coord(axis_normal, axis, side);
        const Vec3 left = axis_normal.cross(q - p);
        facet.holes.push_back((p + q) * 0.5 - left * 1e-3);
      }
      facet.polygons.push_back(std::move(loop));
    }
    // The CAD edges inside the face (both sides on it: where another solid touches it along a
    // curve only, the General Fuse puts that curve into the face as a slit): each segment a
    // polygon of two points, so that the nodes the other solid's faces have there are the
    // facet's too (a cylinder lying on a box: without them, every way with lattice faces failed,
    // the cylinder's triangles crossing the box's top at those nodes).
    std::vector<std::uint64_t> inside;
    for (const auto& [key, count] : uses)
      if (count == 2 && surface.segments.count(key)) inside.push_back(key);
    std::sort(inside.begin(), inside.end());
    for (const std::uint64_t key : inside) facet.polygons.push_back({pair_lo(key), pair_hi(key)});
    facets.push_back(std::move(facet));
  }
  return facets;
}

std::vector<SurfaceTriangle> facet_triangles(
    const Surface& surface, const Frame& frame, const std::vector<bool>& lattice_face,
    const std::vector<std::optional<AxisPlane>>& face_plane) {
  if (std::none_of(surface.triangles.begin(), surface.triangles.end(),
                   [&](const SurfaceTriangle& t) { return lattice_face[t.face]; }))
    return surface.triangles;
  std::vector<Vec3> nodes(surface.nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) nodes[i] = frame.to_frame(surface.nodes[i]);
  std::vector<Facet> facets = make_facets(surface, nodes, lattice_face, face_plane);
  tetgen::triangulate_facets(facets, nodes, nullptr);
  std::vector<SurfaceTriangle> out;
  std::vector<char> as_given(lattice_face.size(), 0);
  for (const Facet& facet : facets) {
    if (facet.polygons.size() == 1 && facet.polygons[0].size() == 3)
      out.push_back(
          SurfaceTriangle{{facet.polygons[0][0], facet.polygons[0][1], facet.polygons[0][2]},
                          {},
                          facet.marker - 1});
    else
      as_given[static_cast<std::size_t>(facet.marker - 1)] = 1;  // left as it is
  }
  for (const SurfaceTriangle& t : surface.triangles)
    if (as_given[static_cast<std::size_t>(t.face)]) out.push_back(t);
  return out;
}

// Puts the lattice points lying on lattice faces, points[first..], into the facets of those
// faces: into a boundary loop where they lie on one of its sides, else as a polygon of one point
// where they lie inside. TetGen then triangulates each lattice face with its lattice points from
// the start; left to -i, they came into two large triangles per face, which left long and flat
// tets along the face.
void add_face_points(std::vector<Facet>& facets, const std::vector<Vec3>& points, std::size_t first,
                     const std::vector<bool>& lattice_face,
                     const std::vector<std::optional<AxisPlane>>& face_plane, double tolerance) {
  // Per axis, the points by their coordinate along it.
  std::vector<std::pair<double, int>> by_axis[3];
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = first; i < points.size(); ++i)
      by_axis[a].emplace_back(coord(points[i], a), static_cast<int>(i));
    std::sort(by_axis[a].begin(), by_axis[a].end());
  }
  for (Facet& facet : facets) {
    if (!lattice_face[facet.marker - 1]) continue;
    const int axis = face_plane[facet.marker - 1]->axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double offset = coord(points[facet.polygons[0][0]], axis);
    const auto& list = by_axis[axis];
    auto it = std::lower_bound(list.begin(), list.end(), std::make_pair(offset - tolerance, -1));
    // Points on each side of each polygon, by their parameter along it.
    std::map<std::pair<std::size_t, std::size_t>, std::vector<std::pair<double, int>>> on_side;
    std::vector<std::vector<int>> singles;
    for (; it != list.end() && it->first <= offset + tolerance; ++it) {
      const Vec3& q = points[it->second];
      const double qu = coord(q, u), qv = coord(q, v);
      bool on_boundary = false, inside = false;
      for (std::size_t p = 0; p < facet.polygons.size() && !on_boundary; ++p) {
        const auto& polygon = facet.polygons[p];
        if (polygon.size() < 3) continue;  // a segment inside the face (make_facets()) or a point
        for (std::size_t k = 0; k < polygon.size() && !on_boundary; ++k) {
          const Vec3 &a = points[polygon[k]], &b = points[polygon[(k + 1) % polygon.size()]];
          const double du = coord(b, u) - coord(a, u), dv = coord(b, v) - coord(a, v);
          const double wu = qu - coord(a, u), wv = qv - coord(a, v);
          const double length2 = du * du + dv * dv, t = (wu * du + wv * dv) / length2;
          if (std::abs(wu * dv - wv * du) <= tolerance * std::sqrt(length2) && t > 0 && t < 1) {
            on_side[{p, k}].emplace_back(t, it->second);
            on_boundary = true;
          }
          // Even-odd rule along +u.
          if ((coord(a, v) > qv) != (coord(b, v) > qv) &&
              qu < coord(a, u) + (qv - coord(a, v)) * du / dv)
            inside = !inside;
        }
      }
      if (!on_boundary && inside) singles.push_back({it->second});
    }
    // From the last side back, so that the sides' indices hold.
    for (auto entry = on_side.rbegin(); entry != on_side.rend(); ++entry) {
      auto& polygon = facet.polygons[entry->first.first];
      std::sort(entry->second.begin(), entry->second.end());
      std::vector<int> between;
      for (const auto& along : entry->second) between.push_back(along.second);
      polygon.insert(polygon.begin() + static_cast<std::ptrdiff_t>(entry->first.second) + 1,
                     between.begin(), between.end());
    }
    facet.polygons.insert(facet.polygons.end(), singles.begin(), singles.end());
  }
}

}  // namespace hexmerge::mesher
