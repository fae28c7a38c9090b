#include "hexmerge/occ/mesher/boundary_distance.h"

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <gp_Pnt2d.hxx>
#include <limits>
#include <memory>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/mesher/shape.h"

namespace hexmerge::mesher {

std::vector<int> point_faces(std::vector<int> given_face, std::size_t nb_points,
                             const std::vector<std::array<index_t, 3>>& boundary,
                             const std::vector<int>& boundary_marker) {
  const std::size_t given = given_face.size();
  given_face.resize(std::max(given, nb_points), -1);
  for (std::size_t i = 0; i < boundary.size(); ++i)
    for (const index_t v : boundary[i])
      if (v >= given && v < given_face.size() && given_face[v] < 0)
        given_face[v] = boundary_marker[i] - 1;
  return given_face;
}

double max_boundary_distance(const Shape& shape, const TetMesh& mesh,
                             const std::vector<int>& vertex_face, double tolerance) {
  const std::size_t made = mesh.points.size() / 3;
  // Face f of a tet is the one opposite its vertex f (TetTopology).
  const TetTopology topology(mesh);
  std::vector<char> boundary(made, 0);
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f))
        for (int k = 0; k < 4; ++k)
          if (k != f) boundary[mesh.tet(t)[k]] = 1;
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(shape.faces.Extent());
  std::vector<gp_Pnt2d> last(analysis.size());
  std::vector<char> has_last(analysis.size(), 0);
  double worst = 0;
  for (std::size_t v = 0; v < made; ++v) {
    if (!boundary[v]) continue;
    const int face = v < vertex_face.size() ? vertex_face[v] : -1;
    const gp_Pnt p(mesh.points[3 * v], mesh.points[3 * v + 1], mesh.points[3 * v + 2]);
    if (face < 0) {
      throw InputError("TetGen put node " + std::to_string(v) +
                           " on the boundary, which is on no face of the shape",
                       Entity::Node, static_cast<index_t>(v));
    }
    if (!analysis[face]) {
      const TopoDS_Face& f = TopoDS::Face(shape.faces(face + 1));
      analysis[face] = std::make_unique<ShapeAnalysis_Surface>(BRep_Tool::Surface(f));
    }
    // BRep_Tool::Surface(face) is the face's surface with its location applied. Newton's
    // method from the face's last node first: a point it finds within `tolerance` shows the
    // node on the face; else the global search (Extrema's grid, which took most of the time:
    // gmsh_917_fusee at its 50k size 1.39 -> 0.61 s), the nearer of the two taken.
    double gap = std::numeric_limits<double>::max();
    if (has_last[face]) {
      last[face] = analysis[face]->NextValueOfUV(last[face], p, tolerance, -1.0);
      gap = analysis[face]->Gap();
    }
    if (gap > tolerance) {
      last[face] = analysis[face]->ValueOfUV(p, tolerance);
      gap = std::min(gap, analysis[face]->Gap());
      has_last[face] = 1;
    }
    // Off the face's surface by more than 100 times the tolerance and the worst so far:
    // measured to the face with its edges too (BRepExtrema), the nearer taken. A node on a CAD
    // edge lies on that edge's curve, which a tolerant file puts off the face's surface by up to
    // the edge's tolerance (gmsh_SampleCrankshaft4A: Edge321 and Edge322 lie 0.218 mm off the
    // B-spline Face113, their tolerance; the node there is on the CAD, 1e-5 mm from that edge).
    if (gap > std::max(worst, 100 * tolerance)) {
      BRepExtrema_DistShapeShape to_face(BRepBuilderAPI_MakeVertex(p).Vertex(),
                                         shape.faces(face + 1));
      if (to_face.IsDone() && to_face.NbSolution() > 0) gap = std::min(gap, to_face.Value());
    }
    worst = std::max(worst, gap);
  }
  return worst;
}

}  // namespace hexmerge::mesher
