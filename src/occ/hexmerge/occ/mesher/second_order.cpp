#include "hexmerge/occ/mesher/second_order.h"

#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <gp_Pnt2d.hxx>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <unordered_map>

#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/mesher/boundary_distance.h"
#include "hexmerge/occ/mesher/shape.h"

namespace hexmerge::mesher {
namespace {

// The six edges of a tet in VTK's Tet10 order (mid node k is on edge k).
constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
// The mid node of edge (i, j) of a tet: its index among the six.
int edge_index(int i, int j) {
  for (int k = 0; k < 6; ++k)
    if ((kEdge[k][0] == i && kEdge[k][1] == j) || (kEdge[k][0] == j && kEdge[k][1] == i)) return k;
  return -1;
}

std::uint64_t edge_key(index_t a, index_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

Vec3 point(const std::vector<double>& p, std::size_t v) { return Vec3::of(&p[3 * v]); }

// The Jacobian of a Tet10 at corner i: the determinant of the tangents of its three edges there
// (x'(0) = 4 m - 3 a - b along the edge from a through m to b), in the order that gives the
// linear tet's determinant for straight edges.
double corner_jacobian(const std::vector<double>& points, const index_t* q, int i) {
  static constexpr int kOthers[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  const Vec3 a = point(points, q[i]);
  Vec3 d[3];
  for (int c = 0; c < 3; ++c) {
    const int j = kOthers[i][c];
    d[c] = point(points, q[4 + edge_index(i, j)]) * 4.0 - a * 3.0 - point(points, q[j]);
  }
  return det3(d[0], d[1], d[2]);
}

bool corners_positive(const std::vector<double>& points, const index_t* q) {
  for (int i = 0; i < 4; ++i)
    if (!(corner_jacobian(points, q, i) > 0)) return false;
  return true;
}

// Within the middle half of edge ab along it and within half its length of its midpoint
// (validate_tet10_mesh's rules), with a margin: at most 0.2 of its length along it from the
// midpoint and 0.45 of its length away from the midpoint.
bool near_middle(const Vec3& a, const Vec3& b, const Vec3& m) {
  const Vec3 d = m - (a + b) * 0.5;
  const Vec3 e = b - a;
  const double length = e.dot(e);
  return d.dot(d) <= 0.2 * length && std::fabs(d.dot(e)) <= 0.2 * length;
}

}  // namespace

Tet10Mesh second_order_mesh(const Shape& shape, const TetMesh& mesh,
                            const std::vector<int>& vertex_face,
                            const std::vector<std::array<index_t, 3>>& boundary,
                            const std::vector<std::int32_t>& boundary_face, double tolerance,
                            SecondOrderReport& report) {
  report = SecondOrderReport{};
  const std::size_t nv = mesh.points.size() / 3;
  const index_t nt = mesh.nb_tets();

  // The edges, numbered in increasing order of (smaller node, larger node).
  std::vector<std::uint64_t> keys;
  keys.reserve(6 * static_cast<std::size_t>(nt));
  for (index_t t = 0; t < nt; ++t)
    for (const auto& e : kEdge) keys.push_back(edge_key(mesh.tet(t)[e[0]], mesh.tet(t)[e[1]]));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  auto edge_of = [&](index_t a, index_t b) {
    return static_cast<std::size_t>(std::lower_bound(keys.begin(), keys.end(), edge_key(a, b)) -
                                    keys.begin());
  };

  Tet10Mesh out;
  out.regions = mesh.regions;
  out.points = mesh.points;
  out.points.resize(3 * (nv + keys.size()));
  auto midpoint = [&](std::size_t e) {
    return (point(mesh.points, keys[e] >> 32) + point(mesh.points, keys[e] & 0xffffffffu)) * 0.5;
  };
  auto set_mid = [&](std::size_t e, const Vec3& m) {
    double* q = &out.points[3 * (nv + e)];
    q[0] = m.x, q[1] = m.y, q[2] = m.z;
  };
  for (std::size_t e = 0; e < keys.size(); ++e) set_mid(e, midpoint(e));
  out.tets10.resize(10 * static_cast<std::size_t>(nt));
  for (index_t t = 0; t < nt; ++t) {
    const index_t* v = mesh.tet(t);
    index_t* q = &out.tets10[10 * static_cast<std::size_t>(t)];
    for (int i = 0; i < 4; ++i) q[i] = v[i];
    for (int k = 0; k < 6; ++k)
      q[4 + k] = static_cast<index_t>(nv + edge_of(v[kEdge[k][0]], v[kEdge[k][1]]));
  }

  // The faces each vertex lies on: its own and those of TetGen's boundary triangles around it
  // (sorted, for the searches below).
  std::vector<std::vector<int>> faces_of = vertex_faces(nv, vertex_face, boundary, boundary_face);
  for (auto& f : faces_of) std::sort(f.begin(), f.end());
  std::map<std::array<index_t, 3>, int> triangle_face;
  for (std::size_t i = 0; i < boundary.size() && i < boundary_face.size(); ++i) {
    if (boundary_face[i] < 0) continue;
    std::array<index_t, 3> key = boundary[i];
    std::sort(key.begin(), key.end());
    triangle_face[key] = boundary_face[i];
  }

  // Per boundary edge, the CAD faces of the boundary triangles around it.
  std::map<std::size_t, std::vector<int>> edge_faces;
  const TetTopology topology(mesh);
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      if (!topology.on_boundary(t, f)) continue;
      std::array<index_t, 3> tri;
      int n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != f) tri[n++] = mesh.tet(t)[k];
      std::array<index_t, 3> key = tri;
      std::sort(key.begin(), key.end());
      int face = -1;
      const auto found = triangle_face.find(key);
      if (found != triangle_face.end()) {
        face = found->second;
      } else {  // swapped inside one face: the face its three vertices share
        for (const int c : faces_of[tri[0]])
          if (std::binary_search(faces_of[tri[1]].begin(), faces_of[tri[1]].end(), c) &&
              std::binary_search(faces_of[tri[2]].begin(), faces_of[tri[2]].end(), c)) {
            face = c;
            break;
          }
      }
      if (face < 0) continue;  // on no known face: its edges are placed by their other side
      for (int c = 0; c < 3; ++c) {
        std::vector<int>& faces = edge_faces[edge_of(tri[c], tri[(c + 1) % 3])];
        if (std::find(faces.begin(), faces.end(), face) == faces.end()) faces.push_back(face);
      }
    }
  }

  // The boundary mid nodes on the CAD. Each projected onto its face by Newton's method from the
  // parameters found for a mid node of an edge at one of its ends (the edges come by their ends'
  // numbers: most have one), the global search only for the others and where Newton's method
  // fails (NextValueOfUV falls back to it). The global search alone, which rebuilds a B-spline
  // face's cache at every evaluation: a helical spring at h 0.8, 72 s for 26,724 mid nodes.
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> surfaces(shape.faces.Extent());
  std::unordered_map<std::uint64_t, gp_Pnt2d> near_node;  // node * faces + face -> parameters
  const auto node_on_face = [&](std::uint64_t v, int face) {
    return v * static_cast<std::uint64_t>(shape.faces.Extent()) + static_cast<std::uint64_t>(face);
  };
  std::vector<std::size_t> moved;
  for (const auto& [e, faces] : edge_faces) {
    const Vec3 a = point(mesh.points, keys[e] >> 32), b = point(mesh.points, keys[e] & 0xffffffffu);
    const Vec3 mid = midpoint(e);
    const gp_Pnt p(mid.x, mid.y, mid.z);
    std::optional<Vec3> on;
    if (faces.size() == 1) {
      const int face = faces[0];
      if (!surfaces[face]) {
        const TopoDS_Face& f = TopoDS::Face(shape.faces(face + 1));
        surfaces[face] = std::make_unique<ShapeAnalysis_Surface>(BRep_Tool::Surface(f));
      }
      const std::uint64_t ends[2] = {node_on_face(keys[e] >> 32, face),
                                     node_on_face(keys[e] & 0xffffffffu, face)};
      auto start = near_node.find(ends[0]);
      if (start == near_node.end()) start = near_node.find(ends[1]);
      const gp_Pnt2d uv = start != near_node.end()
                              ? surfaces[face]->NextValueOfUV(start->second, p, tolerance, -1.0)
                              : surfaces[face]->ValueOfUV(p, tolerance);
      near_node[ends[0]] = near_node[ends[1]] = uv;
      on = of(surfaces[face]->Value(uv));
    } else if (faces.size() == 2) {
      // On the CAD edge between the two faces, the nearest when they share several.
      double best = std::numeric_limits<double>::infinity();
      for (int c = 0; c < static_cast<int>(shape.edge_faces.size()); ++c) {
        const std::vector<int>& ef = shape.edge_faces[c];
        if (std::find(ef.begin(), ef.end(), faces[0]) == ef.end() ||
            std::find(ef.begin(), ef.end(), faces[1]) == ef.end())
          continue;
        const auto nearest = nearest_on_edge(shape, c, of(p), tolerance);
        if (nearest && nearest->first < best) best = nearest->first, on = nearest->second;
      }
    }
    if (!on || !near_middle(a, b, *on)) {
      if (on) ++report.nb_straight;
      continue;
    }
    set_mid(e, *on);
    moved.push_back(e);
  }

  // A moved node whose tets' Jacobian at a corner is not positive goes back to its midpoint,
  // until every tet is positive (straight tets are: mesh is valid).
  std::vector<char> is_moved(keys.size(), 0);
  for (const std::size_t e : moved) is_moved[e] = 1;
  for (bool changed = true; changed;) {
    changed = false;
    for (index_t t = 0; t < nt; ++t) {
      const index_t* q = &out.tets10[10 * static_cast<std::size_t>(t)];
      if (corners_positive(out.points, q)) continue;
      for (int k = 0; k < 6; ++k) {
        const std::size_t e = q[4 + k] - nv;
        if (!is_moved[e]) continue;
        set_mid(e, midpoint(e));
        is_moved[e] = 0;
        ++report.nb_straight;
        changed = true;
      }
    }
  }
  report.nb_projected = static_cast<std::size_t>(std::count(is_moved.begin(), is_moved.end(), 1));
  return out;
}

}  // namespace hexmerge::mesher
