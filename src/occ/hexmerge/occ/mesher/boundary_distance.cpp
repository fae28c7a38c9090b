#include "hexmerge/occ/mesher/boundary_distance.h"

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
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

std::vector<std::vector<int>> vertex_faces(std::size_t nb_vertices,
                                           const std::vector<int>& vertex_face,
                                           const std::vector<std::array<index_t, 3>>& boundary,
                                           const std::vector<std::int32_t>& boundary_face) {
  std::vector<std::vector<int>> faces(nb_vertices);
  for (std::size_t v = 0; v < nb_vertices && v < vertex_face.size(); ++v)
    if (vertex_face[v] >= 0) faces[v].push_back(vertex_face[v]);
  for (std::size_t i = 0; i < boundary.size() && i < boundary_face.size(); ++i) {
    if (boundary_face[i] < 0) continue;
    for (const index_t v : boundary[i])
      if (v < nb_vertices &&
          std::find(faces[v].begin(), faces[v].end(), boundary_face[i]) == faces[v].end())
        faces[v].push_back(boundary_face[i]);
  }
  return faces;
}

double max_boundary_distance(const Shape& shape, const TetMesh& mesh,
                             const std::vector<int>& vertex_face, double tolerance,
                             const std::vector<std::vector<int>>& other_faces) {
  const std::size_t made = mesh.points.size() / 3;
  // The boundary nodes and, per node, the boundary nodes across a side of a boundary triangle
  // (face f of a tet is the one opposite its vertex f, TetTopology).
  const TetTopology topology(mesh);
  std::vector<char> boundary(made, 0);
  std::vector<std::vector<index_t>> beside(made);
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f))
        for (int k = 0; k < 4; ++k) {
          if (k == f) continue;
          const index_t v = mesh.tet(t)[k];
          boundary[v] = 1;
          for (int j = 0; j < 4; ++j)
            if (j != f && j != k) beside[v].push_back(mesh.tet(t)[j]);
        }
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(shape.faces.Extent());
  std::vector<gp_Pnt2d> uv(made);
  std::vector<char> projected(made, 0);
  double worst = 0;
  // The nodes breadth first along the boundary triangles, so that each but the first of a patch
  // has a projected neighbour on its face: Newton's method from that neighbour's parameters
  // finds the node on the face when it is there (the neighbour lies within a side of it); else
  // the global search (Extrema's grid: on a helical spring's B-spline face, whose cache is
  // rebuilt at every evaluation, most of the run when started from the face's last node), the
  // nearer of the two taken.
  const auto measure = [&](std::size_t v) {
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
    // BRep_Tool::Surface(face) is the face's surface with its location applied.
    double gap = std::numeric_limits<double>::max();
    for (const index_t w : beside[v])
      if (projected[w] && w < vertex_face.size() && vertex_face[w] == face) {
        uv[v] = analysis[face]->NextValueOfUV(uv[w], p, tolerance, -1.0);
        gap = analysis[face]->Gap();
        break;
      }
    if (gap > tolerance) {
      const gp_Pnt2d found = analysis[face]->ValueOfUV(p, tolerance);
      if (analysis[face]->Gap() < gap) gap = analysis[face]->Gap(), uv[v] = found;
    }
    projected[v] = 1;
    // Off the face's surface by more than 100 times the tolerance and the worst so far:
    // measured to the face with its edges too (BRepExtrema), the nearer taken. A node on a CAD
    // edge lies on that edge's curve, which a tolerant file puts off the face's surface by up to
    // the edge's tolerance (gmsh_SampleCrankshaft4A: Edge321 and Edge322 lie 0.218 mm off the
    // B-spline Face113, their tolerance; the node there is on the CAD, 1e-5 mm from that edge).
    // Still that far: measured to the other faces it may lie on, the nearest taken.
    if (gap > std::max(worst, 100 * tolerance)) {
      const TopoDS_Vertex node = BRepBuilderAPI_MakeVertex(p).Vertex();
      const auto to = [&](int f) {
        BRepExtrema_DistShapeShape to_face(node, shape.faces(f + 1));
        if (to_face.IsDone() && to_face.NbSolution() > 0) gap = std::min(gap, to_face.Value());
      };
      to(face);
      if (v < other_faces.size())
        for (const int f : other_faces[v])
          if (f >= 0 && f != face && gap > 100 * tolerance) to(f);
    }
    worst = std::max(worst, gap);
  };
  std::vector<char> queued(made, 0);
  std::vector<std::size_t> queue;
  for (std::size_t seed = 0; seed < made; ++seed) {
    if (!boundary[seed] || queued[seed]) continue;
    queue.assign(1, seed);
    queued[seed] = 1;
    for (std::size_t i = 0; i < queue.size(); ++i) {
      measure(queue[i]);
      for (const index_t w : beside[queue[i]])
        if (!queued[w]) queued[w] = 1, queue.push_back(w);
    }
  }
  return worst;
}

}  // namespace hexmerge::mesher
