#include "hexmerge/occ/mesher/surface_mend.h"

#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <cmath>
#include <limits>
#include <vector>

#include "hexmerge/geometry/triangle_distance.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/surface_check.h"

namespace hexmerge::mesher {

void insert_internal_vertices(const Shape& s, double deflection, NodeMerger& merger,
                              Surface& surface) {
  for (int fi = 1; fi <= s.faces.Extent(); ++fi) {
    const TopoDS_Face& face = TopoDS::Face(s.faces(fi));
    TopTools_IndexedMapOfShape on_edges;
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next())
      TopExp::MapShapes(ex.Current(), TopAbs_VERTEX, on_edges);
    for (TopExp_Explorer ex(face, TopAbs_VERTEX); ex.More(); ex.Next()) {
      const TopoDS_Vertex& vertex = TopoDS::Vertex(ex.Current());
      if (on_edges.Contains(vertex)) continue;
      const Vec3 p = of(BRep_Tool::Pnt(vertex));
      const int node = merger.id(p, fi - 1);
      int nearest = -1;
      bool used = false;
      double least = std::numeric_limits<double>::infinity();
      for (std::size_t ti = 0; ti < surface.triangles.size() && !used; ++ti) {
        const SurfaceTriangle& t = surface.triangles[ti];
        if (t.face != fi - 1) continue;
        used = t.node[0] == node || t.node[1] == node || t.node[2] == node;
        const double d = squared_distance_to_triangle(
            p, surface.nodes[t.node[0]], surface.nodes[t.node[1]], surface.nodes[t.node[2]]);
        if (d < least) least = d, nearest = static_cast<int>(ti);
      }
      // (Not one off the face's triangles by more than their deflection: no such face's.)
      if (used || nearest < 0 || std::sqrt(least) > 2 * deflection) continue;
      // Its parameters on the face (projected: such a vertex need not carry them).
      const gp_Pnt2d at = ShapeAnalysis_Surface(BRep_Tool::Surface(face))
                              .ValueOfUV(BRep_Tool::Pnt(vertex), BRep_Tool::Tolerance(vertex));
      const SurfaceTriangle t = surface.triangles[static_cast<std::size_t>(nearest)];
      for (int c = 0; c < 3; ++c) {
        SurfaceTriangle part = t;
        part.node[(c + 2) % 3] = node;
        part.uv[(c + 2) % 3] = UV{at.X(), at.Y()};
        if (c == 0)
          surface.triangles[static_cast<std::size_t>(nearest)] = part;
        else
          surface.triangles.push_back(part);
      }
      surface.internal_vertex_faces.push_back(fi - 1);
    }
  }
}

std::size_t part_shared_sides(const Shape& s, double tolerance, NodeMerger& merger,
                              Surface& surface) {
  std::size_t parted = 0;
  for (const OverusedSide& side : find_overused_sides(surface, s.face_solids, s.edge_faces)) {
    if (faces_meet_along(s, surface.nodes, side, tolerance)) continue;  // broken: refused later
    const Vec3 middle = (surface.nodes[static_cast<std::size_t>(side.a)] +
                         surface.nodes[static_cast<std::size_t>(side.b)]) *
                        0.5;
    for (const int face : side.faces) {
      std::vector<std::size_t> on_side;
      for (std::size_t ti = 0; ti < surface.triangles.size(); ++ti) {
        const SurfaceTriangle& t = surface.triangles[ti];
        int hits = 0;
        for (const int n : t.node) hits += n == side.a || n == side.b;
        if (t.face == face && hits == 2) on_side.push_back(ti);
      }
      if (on_side.size() != 2) continue;
      ShapeAnalysis_Surface projector(BRep_Tool::Surface(TopoDS::Face(s.faces(face + 1))));
      const gp_Pnt2d at = projector.ValueOfUV(gp_Pnt(middle.x, middle.y, middle.z), tolerance);
      const int m = merger.id(of(projector.Value(at)), face);
      for (const std::size_t ti : on_side) {
        const SurfaceTriangle t = surface.triangles[ti];
        int c = 0;  // the side from t.node[c] to t.node[c + 1]
        while (!((t.node[c] == side.a || t.node[c] == side.b) &&
                 (t.node[(c + 1) % 3] == side.a || t.node[(c + 1) % 3] == side.b)))
          ++c;
        SurfaceTriangle first = t, second = t;
        first.node[(c + 1) % 3] = m, first.uv[(c + 1) % 3] = UV{at.X(), at.Y()};
        second.node[c] = m, second.uv[c] = UV{at.X(), at.Y()};
        surface.triangles[ti] = first;
        surface.triangles.push_back(second);
      }
    }
    ++parted;
  }
  return parted;
}

}  // namespace hexmerge::mesher
