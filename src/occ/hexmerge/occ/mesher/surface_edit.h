#pragma once
/// @file
/// Edits of the surface triangulation shared by the surface repairs (surface_repair.h) and the
/// sharp corners' strips (corner_strips.h) (internal header of mesh_shape(); no OpenCASCADE):
/// how far triangles are from their CAD faces, the best triangulation of a polygon, and the
/// bookkeeping of a node taken out.

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/surface.h"

class ShapeAnalysis_Surface;

namespace hexmerge::mesher {

struct Shape;
class SizeField;

/// How far the triangles are from the CAD faces they stand for: the distance from a triangle's
/// centroid to its face's surface (projected from the middle of the triangle's parameters). The
/// repairs (flips, node moves, collapses, the corners' node removals) make no triangle further than
/// the chord deflection, unless none of the triangles it replaces was nearer: on a face far
/// narrower than the target, a flip or a collapse otherwise joins nodes across the face, and the
/// triangle cuts through the solid (pyocc_11752 at h 13: tubes of radius 1.1 and 1.6, triangles of
/// each wall through the other, 1.8 million intersecting pairs, TetGen never ending). Where a
/// deflection field is finer than the target, the deflection shrinks with it, as BRepMesh's would:
/// the crossing rounds' places keep the nodes that part two faces closer than the deflection (a
/// KiCad connector's channel 0.03 mm wide between a fillet and a chamfer on one edge: collapsed
/// onto the chamfer, the fillet's triangles crossed it at every size of those places).
class FaceGaps {
 public:
  FaceGaps(const Shape& s, double deflection, double target, const SizeField* field);
  ~FaceGaps();
  /// The centroid's distance to `face`, for a triangle of corners p at parameters uv.
  double of(int face, const std::array<Vec3, 3>& p, const std::array<UV, 3>& uv);
  double of(const std::vector<Vec3>& nodes, const SurfaceTriangle& t) {
    return of(t.face, {nodes[t.node[0]], nodes[t.node[1]], nodes[t.node[2]]}, t.uv);
  }
  /// Whether any bound applies (the deflection is finite).
  bool bounded() const { return !std::isinf(deflection_); }
  /// Whether triangles at gaps `made` may replace triangles at gaps `replaced` (evaluated only
  /// when one of `made` is beyond the deflection).
  template <class Made, class Replaced>
  bool keeps_close(Made made, Replaced replaced) const {
    if (!bounded()) return true;
    const double worst = made();
    return worst <= deflection_ || worst <= replaced();
  }

 private:
  const Shape& s_;
  double deflection_;
  double target_;
  const SizeField* field_;
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> surfaces_;
};

/// The triangulation of the polygon v[0], ..., v[m - 1] of a face (closed by its side from
/// v[m - 1] to v[0]) with the largest smallest angle, by dynamic programming over its chords: no
/// triangle turned over from `reference`, no chord longer than `limit` or one `connected` says
/// exists already (the closing side is not asked about). The triangles keep the polygon's turn
/// (v[i], v[k], v[j] for i < k < j); none (smallest -1) when no triangulation qualifies.
struct PolygonTriangulation {
  std::vector<SurfaceTriangle> triangles;
  double smallest = -1.0;
};
template <class Connected>
PolygonTriangulation best_triangulation(const std::vector<Vec3>& nodes, const std::vector<int>& v,
                                        int face, const std::unordered_map<int, UV>& uv,
                                        const Vec3& reference, double limit, Connected connected) {
  const int m = static_cast<int>(v.size());
  // best[i][j]: the largest smallest angle of a triangulation of v[i..j] (-1: none).
  std::vector<double> best(static_cast<std::size_t>(m * m), -1.0);
  std::vector<int> split(static_cast<std::size_t>(m * m), -1);
  auto at = [&](int i, int j) -> double& { return best[static_cast<std::size_t>(i * m + j)]; };
  for (int i = 0; i + 1 < m; ++i) at(i, i + 1) = M_PI;
  for (int span = 2; span < m; ++span)
    for (int i = 0; i + span < m; ++i) {
      const int j = i + span;
      if (!(i == 0 && j == m - 1) &&
          ((nodes[v[i]] - nodes[v[j]]).norm() > limit || connected(v[i], v[j])))
        continue;
      for (int k = i + 1; k < j; ++k) {
        if (at(i, k) < 0 || at(k, j) < 0) continue;
        const std::array<int, 3> t{v[i], v[k], v[j]};
        if (turned_over(normal_of(nodes, t[0], t[1], t[2]), reference)) continue;
        const double q = std::min({at(i, k), at(k, j), smallest_angle(nodes, t)});
        if (q > at(i, j)) at(i, j) = q, split[static_cast<std::size_t>(i * m + j)] = k;
      }
    }
  PolygonTriangulation out;
  if (m < 3 || at(0, m - 1) < 0) return out;
  out.smallest = at(0, m - 1);
  std::vector<std::pair<int, int>> stack{{0, m - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[static_cast<std::size_t>(i * m + j)];
    out.triangles.push_back({{v[i], v[k], v[j]}, {uv.at(v[i]), uv.at(v[k]), uv.at(v[j])}, face});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return out;
}

/// Node r's segments to a and b (both on one CAD edge) become the one segment from a to b, with
/// the edge's parameters at a and b.
void join_segments(Surface& surface, int r, int a, int b);

/// The triangles in `slots` (a node's, taken out) replaced by `made` (as many or fewer: the
/// slots left over die), the nodes' lists of their triangles (`around`) kept up to date.
void replace_triangles(std::vector<SurfaceTriangle>& tris, std::vector<std::vector<int>>& around,
                       std::vector<char>& dead, const std::vector<int>& slots,
                       const std::vector<SurfaceTriangle>& made);

/// The surface without its `removed` nodes and `dead` triangles, the rest renumbered in their
/// order, with their segments; Surface::seed gives each node's index in `surface` or, with
/// `keep_seeds`, the seed it had there.
void drop_removed(Surface& surface, const std::vector<char>& removed, const std::vector<char>& dead,
                  bool keep_seeds);

}  // namespace hexmerge::mesher
