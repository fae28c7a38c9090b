#include "hexmerge/occ/mesher/corner_strips.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface_edit.h"

namespace hexmerge::mesher {

// The strips at the CAD's sharp corners: a face narrowing to a corner between two edges (a
// chamfer's cone meeting a flat tangentially, a fillet's end) is narrower than h over some
// distance, and every node on its edges there has a neighbour across the strip closer than h:
// the tets at such a pair of nodes have one short edge and are thin (hex_bolt at 250k: 51 of its
// 76 elements under scaled Jacobian 0.2 lay 1 to 4 h from its chamfer's corners). Taking those
// nodes out leaves one triangle from the corner to where the strip is wide enough, as thin as the
// corner itself makes it there and no thinner, and the tets at the corner's node alone thin.
std::size_t coarsen_sharp_corners(const Shape& s, Surface& surface,
                                  const std::vector<SharpCorner>& corners, double h,
                                  double deflection, const SizeField* deflection_field) {
  if (corners.empty()) return 0;
  FaceGaps gaps(s, deflection, h, deflection_field);
  std::vector<SurfaceTriangle>& tris = surface.triangles;
  const std::vector<Vec3>& nodes = surface.nodes;
  const int nb_nodes = static_cast<int>(nodes.size());
  // Per node, its segments: (the other node, the edge).
  std::vector<std::vector<std::pair<int, int>>> segments_at(nb_nodes);
  for (const auto& [key, segment] : surface.segments) {
    const int a = pair_lo(key), b = pair_hi(key);
    segments_at[a].push_back({b, segment.edge});
    segments_at[b].push_back({a, segment.edge});
  }
  std::vector<std::vector<int>> around(nb_nodes);
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
    for (int n : tris[ti].node) around[n].push_back(ti);
  std::vector<char> dead(tris.size(), 0), removed(nb_nodes, 0);
  const auto has = [](const SurfaceTriangle& t, int n) {
    return t.node[0] == n || t.node[1] == n || t.node[2] == n;
  };
  const auto distance_to_edge = [&](const Vec3& p, int edge) {
    const auto nearest = nearest_on_edge(s, edge, p, 1e-9 * h);
    return nearest ? nearest->first : std::numeric_limits<double>::infinity();
  };
  // Node r, on one CAD edge between two of its segments (to a and b) and on two faces, taken
  // out: on each face its triangles' polygon re-triangulated with the largest smallest angle (a
  // to b its new side, on the edge), where no triangle of the corner's face gets a smaller angle
  // than that face's triangles at r had, none of the other face one smaller than r's smallest,
  // none turns over and none moves away from its face further than the deflection allows; its
  // two segments joined.
  const auto remove_edge_node = [&](int r, int corner_face) {
    if (segments_at[r].size() != 2 || segments_at[r][0].second != segments_at[r][1].second)
      return false;
    const int a = segments_at[r][0].first, b = segments_at[r][1].first;
    std::map<int, std::vector<int>> by_face;
    for (int ti : around[r]) by_face[tris[ti].face].push_back(ti);
    if (by_face.size() != 2) return false;
    const auto connected = [&](int x, int y) {
      for (int ti : around[x])
        if (!has(tris[ti], r) && has(tris[ti], y)) return true;
      return false;
    };
    if (connected(a, b)) return false;
    // Per face, the smallest angle of its triangles at r; r's smallest over both.
    std::map<int, double> face_before;
    double before = M_PI, gap_before = 0;
    for (int ti : around[r]) {
      const double angle = smallest_angle(nodes, tris[ti].node);
      const auto [it, fresh] = face_before.emplace(tris[ti].face, angle);
      if (!fresh) it->second = std::min(it->second, angle);
      before = std::min(before, angle);
      gap_before = std::max(gap_before, gaps.of(nodes, tris[ti]));
    }
    std::vector<SurfaceTriangle> made;
    std::vector<int> slots;
    for (const auto& [face, fan] : by_face) {
      // The fan in its triangles' turn: (r, v[i], v[i + 1]) outward, from one of a and b to the
      // other.
      std::unordered_map<int, int> next;
      std::unordered_map<int, UV> uv;
      std::unordered_set<int> reached;
      Vec3 reference{0, 0, 0};
      for (int ti : fan) {
        const SurfaceTriangle& t = tris[ti];
        int c = 0;
        while (t.node[c] != r) ++c;
        if (!next.emplace(t.node[(c + 1) % 3], t.node[(c + 2) % 3]).second) return false;
        reached.insert(t.node[(c + 2) % 3]);
        for (int k = 0; k < 3; ++k) uv[t.node[k]] = t.uv[k];
        reference = reference + normal_of(nodes, t.node[0], t.node[1], t.node[2]);
      }
      std::vector<int> v;
      for (const int end : {a, b})
        if (next.count(end) && !reached.count(end)) v.push_back(end);
      if (v.size() != 1) return false;
      for (auto it = next.find(v.back()); it != next.end() && v.size() <= next.size();
           it = next.find(v.back()))
        v.push_back(it->second);
      if (v.size() != next.size() + 1 || v.back() != (v.front() == a ? b : a)) return false;
      const PolygonTriangulation polygon = best_triangulation(
          nodes, v, face, uv, reference, std::numeric_limits<double>::infinity(), connected);
      if (!(polygon.smallest >= (face == corner_face ? face_before.at(face) : before)))
        return false;
      made.insert(made.end(), polygon.triangles.begin(), polygon.triangles.end());
      slots.insert(slots.end(), fan.begin(), fan.end());
    }
    const auto made_gap = [&] {
      double worst = 0;
      for (const SurfaceTriangle& t : made) worst = std::max(worst, gaps.of(nodes, t));
      return worst;
    };
    if (!gaps.keeps_close(made_gap, [&] { return gap_before; })) return false;
    replace_triangles(tris, around, dead, slots, made);  // (one triangle fewer per face)
    join_segments(surface, r, a, b);
    for (auto& [other, e] : segments_at[a])
      if (other == r) other = b;
    for (auto& [other, e] : segments_at[b])
      if (other == r) other = a;
    segments_at[r].clear();
    around[r].clear();
    removed[r] = 1;
    return true;
  };
  std::size_t nb_removed = 0;
  const std::vector<int> corner_node = corner_nodes(corners, surface);
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const SharpCorner& corner = corners[k];
    const int c = corner_node[k];
    if (c < 0) continue;
    // Along each edge from the corner, the nodes within kCornerReach h of it that lie closer
    // than kCornerStripWidth h to the other edge; only when the strip is that wide within the
    // reach on both edges (else it stays thin: a long triangle there would be as thin).
    std::vector<std::pair<double, int>> strip;
    int nb_wide = 0;
    for (int side = 0; side < 2; ++side) {
      const int edge = corner.edges[side], other_edge = corner.edges[1 - side];
      int previous = c, current = -1;
      for (const auto& [other, e] : segments_at[c])
        if (e == edge) current = other;
      while (current >= 0 && current != c) {
        const double d = (nodes[current] - nodes[c]).norm();
        if (d > kCornerReach * h || segments_at[current].size() != 2) break;
        if (distance_to_edge(nodes[current], other_edge) >= kCornerStripWidth * h) {
          ++nb_wide;
          break;
        }
        strip.push_back({d, current});
        int following = -1;
        for (const auto& [other, e] : segments_at[current])
          if (other != previous && e == edge) following = other;
        previous = current, current = following;
      }
    }
    if (nb_wide < 2) continue;
    // Nearest the corner first.
    std::sort(strip.begin(), strip.end());
    for (const auto& [d, n] : strip)
      if (remove_edge_node(n, corner.face)) ++nb_removed;
  }
  if (nb_removed > 0) drop_removed(surface, removed, dead, true);
  return nb_removed;
}

}  // namespace hexmerge::mesher
