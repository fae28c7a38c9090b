#include "hexmerge/occ/mesh_shape.h"

#include <sys/wait.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <GProp_PrincipalProps.hxx>
#include <Geom2d_Curve.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <Poly_Triangulation.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gp_Pln.hxx>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/remove_slivers.h"
#include "hexmerge/geometry/smooth_nodes.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/brep_text.h"
#include "hexmerge/occ/regions_by_solid.h"

namespace hexmerge {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Wall time of consecutive phases, written into the report.
class PhaseClock {
 public:
  explicit PhaseClock(std::map<std::string, double>& out) : out_(out), start_(Clock::now()) {}
  void lap(const char* phase) {
    const auto now = Clock::now();
    out_[phase] = std::chrono::duration<double>(now - start_).count();
    start_ = now;
  }

 private:
  std::map<std::string, double>& out_;
  Clock::time_point start_;
};

std::uint64_t pair_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

// ---------------------------------------------------------------------------------------------
// Spatial queries: points and triangles in a uniform grid of cubic buckets.

class BucketGrid {
 public:
  BucketGrid(const Vec3& lo, const Vec3& hi, double cell) : lo_(lo), cell_(cell) {
    for (int a = 0; a < 3; ++a) {
      const double extent = (a == 0 ? hi.x - lo.x : a == 1 ? hi.y - lo.y : hi.z - lo.z);
      n_[a] = std::max(1, static_cast<int>(std::ceil(extent / cell)) + 1);
    }
    buckets_.resize(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2]);
  }
  // Adds item to every bucket the box [a, b] overlaps.
  void add(int item, const Vec3& a, const Vec3& b) {
    std::array<int, 3> i0 = coords(a), i1 = coords(b);
    for (int i = i0[0]; i <= i1[0]; ++i)
      for (int j = i0[1]; j <= i1[1]; ++j)
        for (int k = i0[2]; k <= i1[2]; ++k) buckets_[index(i, j, k)].push_back(item);
  }
  // Calls f(item) for the items of the buckets the box [a, b] overlaps (an item may come twice);
  // stops when f returns true, and returns whether it did.
  template <typename F>
  bool any_in(const Vec3& a, const Vec3& b, F&& f) const {
    std::array<int, 3> i0 = coords(a), i1 = coords(b);
    for (int i = i0[0]; i <= i1[0]; ++i)
      for (int j = i0[1]; j <= i1[1]; ++j)
        for (int k = i0[2]; k <= i1[2]; ++k)
          for (int item : buckets_[index(i, j, k)])
            if (f(item)) return true;
    return false;
  }

 private:
  std::array<int, 3> coords(const Vec3& p) const {
    const double c[3] = {(p.x - lo_.x) / cell_, (p.y - lo_.y) / cell_, (p.z - lo_.z) / cell_};
    std::array<int, 3> out{};
    for (int a = 0; a < 3; ++a)
      out[a] = std::clamp(static_cast<int>(std::floor(c[a])), 0, n_[a] - 1);
    return out;
  }
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(i) * n_[1] + j) * n_[2] + k;
  }
  Vec3 lo_;
  double cell_;
  std::array<int, 3> n_{};
  std::vector<std::vector<int>> buckets_;
};

// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
double squared_distance_to_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  auto sq = [](const Vec3& v) { return v.dot(v); };
  if (d1 <= 0 && d2 <= 0) return sq(ap);
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return sq(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return sq(p - (a + ab * (d1 / (d1 - d3))));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return sq(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return sq(p - (a + ac * (d2 / (d2 - d6))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return sq(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  const double denom = 1.0 / (va + vb + vc);
  return sq(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

Vec3 vmin(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
Vec3 vmax(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
double coord(const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; }
void set_coord(Vec3& v, int axis, double value) {
  (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = value;
}

// Points, with "is there one within r of q" queries.
class PointSet {
 public:
  PointSet(const Vec3& lo, const Vec3& hi, double cell) : grid_(lo, hi, cell) {}
  void add(const Vec3& p) {
    grid_.add(static_cast<int>(points_.size()), p, p);
    points_.push_back(p);
  }
  bool any_within(const Vec3& q, double r) const {
    const Vec3 d{r, r, r};
    return grid_.any_in(q - d, q + d, [&](int i) { return (points_[i] - q).norm() < r; });
  }

 private:
  BucketGrid grid_;
  std::vector<Vec3> points_;
};

// Triangles, with "is one nearer than r to q" queries.
class TriangleSet {
 public:
  TriangleSet(const std::vector<Vec3>& nodes, const Vec3& lo, const Vec3& hi, double cell)
      : nodes_(nodes), grid_(lo, hi, cell) {}
  void add(const std::array<int, 3>& t) {
    const Vec3 &a = nodes_[t[0]], &b = nodes_[t[1]], &c = nodes_[t[2]];
    grid_.add(static_cast<int>(tris_.size()), vmin(a, vmin(b, c)), vmax(a, vmax(b, c)));
    tris_.push_back(t);
  }
  bool any_within(const Vec3& q, double r) const {
    const Vec3 d{r, r, r};
    return grid_.any_in(q - d, q + d, [&](int i) {
      const auto& t = tris_[i];
      return squared_distance_to_triangle(q, nodes_[t[0]], nodes_[t[1]], nodes_[t[2]]) < r * r;
    });
  }

 private:
  const std::vector<Vec3>& nodes_;
  BucketGrid grid_;
  std::vector<std::array<int, 3>> tris_;
};

// ---------------------------------------------------------------------------------------------
// The shape: its solids, faces, edges, checked.

struct Shape {
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape solids, faces, edges;
  std::vector<int> face_solid_count;  // solids each face bounds (2: shared by two solids)
  std::vector<std::vector<int>> edge_faces;
};

Shape load_shape(const std::string& brep) {
  Shape s;
  s.shape = read_brep(brep);
  TopExp::MapShapes(s.shape, TopAbs_SOLID, s.solids);
  if (s.solids.IsEmpty())
    throw InputError(
        "the shape holds no solid (a face, a shell or a wire cannot be meshed "
        "into tets): give a closed solid");
  TopExp::MapShapes(s.shape, TopAbs_FACE, s.faces);
  TopExp::MapShapes(s.shape, TopAbs_EDGE, s.edges);
  s.face_solid_count.assign(static_cast<std::size_t>(s.faces.Extent()), 0);
  for (int i = 1; i <= s.solids.Extent(); ++i) {
    TopTools_IndexedMapOfShape solid_faces;
    TopExp::MapShapes(s.solids(i), TopAbs_FACE, solid_faces);
    for (int f = 1; f <= solid_faces.Extent(); ++f) {
      const int index = s.faces.FindIndex(solid_faces(f));
      if (index > 0) ++s.face_solid_count[index - 1];
    }
    // A closed shell: every edge of the solid bounds two faces, or one face twice (a seam).
    TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
    TopExp::MapShapesAndAncestors(s.solids(i), TopAbs_EDGE, TopAbs_FACE, edge_faces);
    for (int e = 1; e <= edge_faces.Extent(); ++e) {
      const TopoDS_Edge& edge = TopoDS::Edge(edge_faces.FindKey(e));
      if (BRep_Tool::Degenerated(edge)) continue;
      const TopTools_ListOfShape& around = edge_faces.FindFromIndex(e);
      if (around.Extent() >= 2) continue;
      if (around.Extent() == 1 && BRep_Tool::IsClosed(edge, TopoDS::Face(around.First()))) continue;
      throw InputError("solid " + std::to_string(i - 1) + " is not closed: edge " +
                       std::to_string(s.edges.FindIndex(edge) - 1) +
                       " bounds a single face (an open shell); give a closed solid");
    }
  }
  s.edge_faces.resize(static_cast<std::size_t>(s.edges.Extent()));
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(s.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  for (int e = 1; e <= edge_faces.Extent(); ++e) {
    const int edge = s.edges.FindIndex(edge_faces.FindKey(e)) - 1;
    for (const TopoDS_Shape& f : edge_faces.FindFromIndex(e)) {
      const int face = s.faces.FindIndex(f) - 1;
      auto& list = s.edge_faces[edge];
      if (std::find(list.begin(), list.end(), face) == list.end()) list.push_back(face);
    }
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// The lattice frame.

struct Frame {
  Vec3 axis[3];
  Vec3 origin{0, 0, 0};
  Vec3 to_frame(const Vec3& p) const {
    const Vec3 d = p - origin;
    return {d.dot(axis[0]), d.dot(axis[1]), d.dot(axis[2])};
  }
  Vec3 to_world(const Vec3& q) const {
    return origin + axis[0] * q.x + axis[1] * q.y + axis[2] * q.z;
  }
};

Vec3 unit(const Vec3& v) { return v * (1.0 / v.norm()); }
Vec3 of(const gp_Dir& d) { return {d.X(), d.Y(), d.Z()}; }
Vec3 of(const gp_Pnt& p) { return {p.X(), p.Y(), p.Z()}; }

// Completes e3 (and e1 when given) into a right-handed orthonormal frame.
Frame make_frame(const Vec3& e3, const Vec3* e1_hint, const Vec3 (&fallback)[3]) {
  Frame f;
  f.axis[2] = unit(e3);
  Vec3 e1{0, 0, 0};
  if (e1_hint) e1 = *e1_hint;
  if (e1.norm() < 0.5) {
    // The fallback axis least aligned with e3.
    double best = 2;
    for (const Vec3& a : fallback)
      if (std::abs(a.dot(f.axis[2])) < best) best = std::abs(a.dot(f.axis[2])), e1 = a;
  }
  e1 = e1 - f.axis[2] * e1.dot(f.axis[2]);
  f.axis[0] = unit(e1);
  f.axis[1] = f.axis[2].cross(f.axis[0]);
  return f;
}

Frame choose_frame(const Shape& s, const std::string& kind) {
  const Vec3 global[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (kind == "global") return make_frame(global[2], &global[0], global);
  GProp_GProps volume;
  BRepGProp::VolumeProperties(s.shape, volume);
  const GProp_PrincipalProps principal = volume.PrincipalProperties();
  const Vec3 principal_axes[3] = {of(gp_Dir(principal.FirstAxisOfInertia())),
                                  of(gp_Dir(principal.SecondAxisOfInertia())),
                                  of(gp_Dir(principal.ThirdAxisOfInertia()))};
  if (kind == "principal") return make_frame(principal_axes[2], &principal_axes[0], principal_axes);
  // "auto": planar face normals, grouped by direction (up to sign), weighted by area.
  std::vector<std::pair<Vec3, double>> directions;
  for (int i = 1; i <= s.faces.Extent(); ++i) {
    const TopoDS_Face& face = TopoDS::Face(s.faces(i));
    BRepAdaptor_Surface surface(face, false);
    if (surface.GetType() != GeomAbs_Plane) continue;
    GProp_GProps area;
    BRepGProp::SurfaceProperties(face, area);
    const Vec3 n = of(surface.Plane().Axis().Direction());
    bool merged = false;
    for (auto& [d, a] : directions)
      if (std::abs(std::abs(d.dot(n)) - 1) < 1e-9) a += area.Mass(), merged = true;
    if (!merged) directions.emplace_back(n, area.Mass());
  }
  if (directions.empty()) return make_frame(principal_axes[2], &principal_axes[0], principal_axes);
  std::stable_sort(directions.begin(), directions.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  const Vec3 e3 = directions[0].first;
  for (std::size_t i = 1; i < directions.size(); ++i)
    if (std::abs(directions[i].first.dot(e3)) < 1e-9)
      return make_frame(e3, &directions[i].first, principal_axes);
  return make_frame(e3, nullptr, principal_axes);
}

// ---------------------------------------------------------------------------------------------
// The surface: BRepMesh's triangulation, nodes merged across faces, refined by bisection with
// every new node on the CAD surface or edge.

struct SurfaceTriangle {
  std::array<int, 3> node;
  std::array<gp_Pnt2d, 3> uv;  // the nodes' parameters on the triangle's face
  int face;
};

// The key of side c of a triangle (from node c to node c + 1), and the side with a given key.
std::uint64_t side_key(const SurfaceTriangle& t, int c) {
  return pair_key(t.node[c], t.node[(c + 1) % 3]);
}
int side_with_key(const SurfaceTriangle& t, std::uint64_t key) {
  int c = 0;
  while (side_key(t, c) != key) ++c;
  return c;
}

// A segment of the surface triangulation on a CAD edge: the edge and its parameters at the
// segment's smaller and larger node id.
struct EdgeSegment {
  int edge;
  double t_lo, t_hi;
};

struct Surface {
  std::vector<Vec3> nodes;                 // world coordinates
  std::vector<int> node_face;              // a face the node lies on
  std::vector<SurfaceTriangle> triangles;  // oriented outward (as the face is in its solid)
  std::unordered_map<std::uint64_t, EdgeSegment> segments;
  // Per node, its index before collapse_short_sides() (seeds the layers' depths, so that a
  // collapse does not change them everywhere).
  std::vector<int> seed;
};

// Geometry of surface triangles on `nodes`: the angle at v between the sides to a and b, the
// (area-weighted) normal of triangle abc, its smallest angle.
double angle_at(const std::vector<Vec3>& nodes, int v, int a, int b) {
  const Vec3 x = nodes[a] - nodes[v], y = nodes[b] - nodes[v];
  return std::atan2(x.cross(y).norm(), x.dot(y));
}
Vec3 normal_of(const std::vector<Vec3>& nodes, int a, int b, int c) {
  return (nodes[b] - nodes[a]).cross(nodes[c] - nodes[a]);
}
double smallest_angle(const std::vector<Vec3>& nodes, const std::array<int, 3>& v) {
  double worst = M_PI;
  for (int c = 0; c < 3; ++c)
    worst = std::min(worst, angle_at(nodes, v[c], v[(c + 1) % 3], v[(c + 2) % 3]));
  return worst;
}

// Surface smoothing and collapses keep every triangle within this angle (20 degrees) of the
// surface's normal at the node they move or remove: true when `now` turned further from it.
bool turned_over(const Vec3& now, const Vec3& reference) {
  return now.dot(reference) <= std::cos(20.0 * M_PI / 180) * now.norm() * reference.norm();
}

// Per node, whether it lies on a CAD edge (an end of a segment).
std::vector<char> nodes_on_edges(const Surface& surface) {
  std::vector<char> on_edge(surface.nodes.size(), 0);
  for (const auto& [key, segment] : surface.segments) {
    (void)segment;
    on_edge[key >> 32] = on_edge[key & 0xffffffffu] = 1;
  }
  return on_edge;
}

// The coordinates (s, r) of q in triangle p0 p1 p2, q = p0 + s (p1 - p0) + r (p2 - p0), all seen
// along frame axis `axis` (nodes in frame coordinates); false when the triangle is edge-on.
bool coordinates_across(const Vec3& q, const Vec3& p0, const Vec3& p1, const Vec3& p2, int axis,
                        double& s, double& r) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double x0 = coord(p0, u), y0 = coord(p0, v);
  const double d =
      (coord(p1, u) - x0) * (coord(p2, v) - y0) - (coord(p2, u) - x0) * (coord(p1, v) - y0);
  if (d == 0) return false;
  s = ((coord(q, u) - x0) * (coord(p2, v) - y0) - (coord(p2, u) - x0) * (coord(q, v) - y0)) / d;
  r = ((coord(p1, u) - x0) * (coord(q, v) - y0) - (coord(q, u) - x0) * (coord(p1, v) - y0)) / d;
  return true;
}

// The face of the first of `triangles` (on a plane normal to frame axis `axis`, nodes in frame
// coordinates) that holds q, to 1e-9 of its coordinates; -1 for none.
int face_holding(const Vec3& q, const std::vector<const SurfaceTriangle*>& triangles,
                 const std::vector<Vec3>& nodes, int axis) {
  for (const SurfaceTriangle* t : triangles) {
    double s, r;
    if (!coordinates_across(q, nodes[t->node[0]], nodes[t->node[1]], nodes[t->node[2]], axis, s, r))
      continue;
    const double eps = 1e-9;
    if (s >= -eps && r >= -eps && s + r <= 1 + eps) return t->face;
  }
  return -1;
}

// Merges points closer than a tolerance into one node.
class NodeMerger {
 public:
  NodeMerger(Surface& s, double tolerance) : s_(s), tol_(tolerance) {}
  int id(const Vec3& p, int face) {
    const std::array<long long, 3> c = cell(p);
    for (long long i = c[0] - 1; i <= c[0] + 1; ++i)
      for (long long j = c[1] - 1; j <= c[1] + 1; ++j)
        for (long long k = c[2] - 1; k <= c[2] + 1; ++k) {
          auto it = cells_.find(hash(i, j, k));
          if (it == cells_.end()) continue;
          for (int n : it->second)
            if ((s_.nodes[n] - p).norm() <= tol_) return n;
        }
    const int n = static_cast<int>(s_.nodes.size());
    s_.nodes.push_back(p);
    s_.node_face.push_back(face);
    cells_[hash(c[0], c[1], c[2])].push_back(n);
    return n;
  }

 private:
  std::array<long long, 3> cell(const Vec3& p) const {
    const double w = 4 * tol_;
    return {static_cast<long long>(std::floor(p.x / w)),
            static_cast<long long>(std::floor(p.y / w)),
            static_cast<long long>(std::floor(p.z / w))};
  }
  static std::uint64_t hash(long long i, long long j, long long k) {
    return static_cast<std::uint64_t>(i) * 73856093ULL ^
           static_cast<std::uint64_t>(j) * 19349663ULL ^
           static_cast<std::uint64_t>(k) * 83492791ULL;
  }
  Surface& s_;
  double tol_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

Surface triangulate(const Shape& s, double deflection, double tolerance) {
  try {
    BRepMesh_IncrementalMesh mesher(s.shape, deflection, false, 0.35, true);
    if (!mesher.IsDone()) throw InputError("OpenCASCADE could not triangulate the shape's faces");
  } catch (const Standard_Failure& e) {
    throw InputError(std::string("OpenCASCADE could not triangulate the shape's faces: ") +
                     e.GetMessageString());
  }
  Surface surface;
  NodeMerger merger(surface, tolerance);
  for (int fi = 1; fi <= s.faces.Extent(); ++fi) {
    const int face_index = fi - 1;
    const TopoDS_Face& face = TopoDS::Face(s.faces(fi));
    TopLoc_Location loc;
    const Handle(Poly_Triangulation)& tri = BRep_Tool::Triangulation(face, loc);
    if (tri.IsNull() || tri->NbTriangles() == 0)
      throw InputError(
          "OpenCASCADE could not triangulate face " + std::to_string(face_index) + " of the shape",
          Entity::None);
    const gp_Trsf trsf = loc.Transformation();
    std::vector<int> global(static_cast<std::size_t>(tri->NbNodes()) + 1);
    for (int i = 1; i <= tri->NbNodes(); ++i)
      global[i] = merger.id(of(tri->Node(i).Transformed(trsf)), face_index);
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (int k = 1; k <= tri->NbTriangles(); ++k) {
      int n[3];
      tri->Triangle(k).Get(n[0], n[1], n[2]);
      if (reversed) std::swap(n[1], n[2]);
      SurfaceTriangle t;
      t.face = face_index;
      for (int c = 0; c < 3; ++c) {
        t.node[c] = global[n[c]];
        t.uv[c] = tri->HasUVNodes() ? tri->UVNode(n[c]) : gp_Pnt2d(0, 0);
      }
      if (t.node[0] == t.node[1] || t.node[1] == t.node[2] || t.node[0] == t.node[2]) continue;
      surface.triangles.push_back(t);
    }
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
      if (BRep_Tool::Degenerated(edge)) continue;
      const Handle(Poly_PolygonOnTriangulation)& poly =
          BRep_Tool::PolygonOnTriangulation(edge, tri, loc);
      if (poly.IsNull()) continue;
      const int edge_index = s.edges.FindIndex(edge) - 1;
      BRepAdaptor_Curve curve(edge);
      for (int k = 1; k < poly->NbNodes(); ++k) {
        const int a = global[poly->Node(k)], b = global[poly->Node(k + 1)];
        if (a == b) continue;
        double ta, tb;
        if (poly->HasParameters()) {
          ta = poly->Parameter(k), tb = poly->Parameter(k + 1);
        } else {  // spread evenly over the edge's range
          const double f = curve.FirstParameter(), l = curve.LastParameter();
          ta = f + (l - f) * (k - 1) / (poly->NbNodes() - 1);
          tb = f + (l - f) * k / (poly->NbNodes() - 1);
        }
        surface.segments[pair_key(a, b)] =
            a < b ? EdgeSegment{edge_index, ta, tb} : EdgeSegment{edge_index, tb, ta};
      }
    }
  }
  return surface;
}

// Rounds of smoothing and flips after the surface refinement.
constexpr int kSmoothingRounds = 5;
// Surface nodes with a smaller angle than this (radians, 20 degrees) in their triangles are
// smoothed.
constexpr double kNeedleAngle = 20.0 * M_PI / 180;
// A needle's node moves no nearer than this fraction of h to its neighbours.
constexpr double kNeedleNearest = 0.125;
// Largest relative change of a boundary layer's depth from one node to the next.
constexpr double kLayerJitter = 0.1;
// Times TetGen is run again, its lattice faces' loops started elsewhere, when it does not finish.
constexpr int kTetgenRestarts = 5;
// Rounds of flips (remove_slivers) and node moves (smooth_nodes) after TetGen; the last is flips.
constexpr int kQualityRounds = 4;

// Splits the triangles of the faces that are not lattice faces until no side is longer than
// `target` (sides on edges between lattice faces excepted); lattice-face triangles are split
// only where a neighbour's side must be. New nodes lie on the CAD edge (sides on an edge) or on
// the face's surface.
void refine(const Shape& s, Surface& surface, double target, const std::vector<bool>& lattice_face,
            const std::vector<bool>& lattice_edge) {
  std::vector<std::unique_ptr<BRepAdaptor_Surface>> surfaces(s.faces.Extent());
  std::vector<std::unique_ptr<BRepAdaptor_Curve>> curves(s.edges.Extent());
  // Per face, the pcurves of its edges (a seam has two: one per orientation).
  struct PCurve {
    int edge;
    Handle(Geom2d_Curve) curve;
  };
  std::vector<std::vector<PCurve>> pcurves(s.faces.Extent());
  for (int fi = 1; fi <= s.faces.Extent(); ++fi) {
    const TopoDS_Face& face = TopoDS::Face(s.faces(fi));
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
      if (BRep_Tool::Degenerated(edge)) continue;
      double f, l;
      Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, f, l);
      if (!pc.IsNull()) pcurves[fi - 1].push_back({s.edges.FindIndex(edge) - 1, pc});
    }
  }
  auto face_surface = [&](int f) -> const BRepAdaptor_Surface& {
    if (!surfaces[f])
      surfaces[f] = std::make_unique<BRepAdaptor_Surface>(TopoDS::Face(s.faces(f + 1)));
    return *surfaces[f];
  };
  auto edge_curve = [&](int e) -> const BRepAdaptor_Curve& {
    if (!curves[e]) curves[e] = std::make_unique<BRepAdaptor_Curve>(TopoDS::Edge(s.edges(e + 1)));
    return *curves[e];
  };

  // Longest-side bisection with Delaunay flips after each insertion: the triangles across a
  // split side are split along (the triangulation stays conforming) and the flips take back the
  // poor shapes that this and BRepMesh's own needles make.
  std::vector<SurfaceTriangle>& tris = surface.triangles;
  std::unordered_map<std::uint64_t, std::vector<int>> at_edge;  // triangles per side
  auto link = [&](int ti) {
    for (int c = 0; c < 3; ++c) at_edge[side_key(tris[ti], c)].push_back(ti);
  };
  auto unlink = [&](int ti) {
    for (int c = 0; c < 3; ++c) {
      auto& v = at_edge[side_key(tris[ti], c)];
      v.erase(std::remove(v.begin(), v.end(), ti), v.end());
    }
  };
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti) link(ti);
  auto length = [&](int a, int b) { return (surface.nodes[a] - surface.nodes[b]).norm(); };
  // The longest side of triangle ti.
  auto longest = [&](int ti) {
    const SurfaceTriangle& t = tris[ti];
    int best = 0;
    for (int c = 1; c < 3; ++c)
      if (length(t.node[c], t.node[(c + 1) % 3]) > length(t.node[best], t.node[(best + 1) % 3]))
        best = c;
    return best;
  };
  // The midpoint of side c of triangle ti: its parameters on the triangle's face, and its node,
  // made when `node` is -1 (on the CAD edge for a side on one, else on the face's surface).
  auto midpoint = [&](int ti, int c, int node, gp_Pnt2d& uv) {
    const SurfaceTriangle& t = tris[ti];
    const int a = t.node[c], b = t.node[(c + 1) % 3];
    uv = gp_Pnt2d(0.5 * (t.uv[c].X() + t.uv[(c + 1) % 3].X()),
                  0.5 * (t.uv[c].Y() + t.uv[(c + 1) % 3].Y()));
    auto seg = surface.segments.find(pair_key(a, b));
    const bool on_edge = seg != surface.segments.end();
    const double tm = on_edge ? 0.5 * (seg->second.t_lo + seg->second.t_hi) : 0.0;
    if (on_edge) {
      const EdgeSegment& e = seg->second;
      const double ta = a < b ? e.t_lo : e.t_hi;
      double best = std::numeric_limits<double>::max();
      for (const PCurve& pc : pcurves[t.face]) {  // the pcurve through node a (seams have two)
        if (pc.edge != e.edge) continue;
        const double d = pc.curve->Value(ta).Distance(t.uv[c]);
        if (d < best) best = d, uv = pc.curve->Value(tm);
      }
    }
    if (node >= 0) return node;
    surface.nodes.push_back(on_edge ? of(edge_curve(seg->second.edge).Value(tm))
                                    : of(face_surface(t.face).Value(uv.X(), uv.Y())));
    surface.node_face.push_back(t.face);
    return static_cast<int>(surface.nodes.size()) - 1;
  };
  // Splits side (a, b) in every triangle that has it; the halves of an edge segment stay one.
  auto split_side = [&](int a, int b) {
    const std::uint64_t key = pair_key(a, b);
    const std::vector<int> around = at_edge[key];
    int m = -1;
    for (int ti : around) {
      const SurfaceTriangle t = tris[ti];
      const int c = side_with_key(t, key);
      gp_Pnt2d uv;
      m = midpoint(ti, c, m, uv);
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      unlink(ti);
      tris[ti] = SurfaceTriangle{{t.node[c], m, t.node[c2]}, {t.uv[c], uv, t.uv[c2]}, t.face};
      link(ti);
      tris.push_back(
          SurfaceTriangle{{m, t.node[c1], t.node[c2]}, {uv, t.uv[c1], t.uv[c2]}, t.face});
      link(static_cast<int>(tris.size()) - 1);
    }
    auto seg = surface.segments.find(key);
    if (seg != surface.segments.end()) {
      const EdgeSegment e = seg->second;
      const double tm = 0.5 * (e.t_lo + e.t_hi);
      const int lo = std::min(a, b), hi = std::max(a, b);
      surface.segments.erase(seg);
      surface.segments[pair_key(lo, m)] =
          lo < m ? EdgeSegment{e.edge, e.t_lo, tm} : EdgeSegment{e.edge, tm, e.t_lo};
      surface.segments[pair_key(m, hi)] =
          m < hi ? EdgeSegment{e.edge, tm, e.t_hi} : EdgeSegment{e.edge, e.t_hi, tm};
    }
    at_edge.erase(key);
    std::vector<std::uint64_t> stack;  // the sides of the triangles around the new node
    for (int end : {a, b})
      for (int ti : at_edge[pair_key(m, end)])
        for (int c = 0; c < 3; ++c) stack.push_back(side_key(tris[ti], c));
    return stack;
  };
  // Lawson's flips after an insertion: sides that fail the Delaunay test (opposite angles
  // summing past pi, in 3D) between two triangles of one face, off the CAD edges, are flipped
  // unless that folds the surface. Bisection alone keeps the needles BRepMesh makes on ruled
  // faces (a cylinder is strips from cap to cap); the flips give them up.
  auto angle_at = [&](int v, int a, int b) { return hexmerge::angle_at(surface.nodes, v, a, b); };
  auto normal_of = [&](int a, int b, int c) { return hexmerge::normal_of(surface.nodes, a, b, c); };
  auto restore_delaunay = [&](std::vector<std::uint64_t> stack) {
    std::size_t flips = 0;
    while (!stack.empty() && flips < 10000) {
      const std::uint64_t key = stack.back();
      stack.pop_back();
      auto it = at_edge.find(key);
      if (it == at_edge.end() || it->second.size() != 2 || surface.segments.count(key)) continue;
      const int t1 = it->second[0], t2 = it->second[1];
      if (tris[t1].face != tris[t2].face || lattice_face[tris[t1].face]) continue;
      // t1 = (p, q, m), t2 = (q, p, x).
      const int c1 = side_with_key(tris[t1], key), c2 = side_with_key(tris[t2], key);
      const SurfaceTriangle a = tris[t1], b = tris[t2];
      const int p = a.node[c1], q = a.node[(c1 + 1) % 3], m = a.node[(c1 + 2) % 3];
      const int x = b.node[(c2 + 2) % 3];
      if (b.node[c2] != q || m == x) continue;
      // Off the plane the test can fail both ways: flip only to a strictly better pair.
      const double now = angle_at(m, p, q) + angle_at(x, q, p);
      if (now <= M_PI * (1 + 1e-9) || angle_at(p, x, m) + angle_at(q, m, x) >= now - 1e-9) continue;
      const Vec3 before = normal_of(p, q, m) + normal_of(q, p, x);
      // Nor across the surface's curvature: both new triangles within 20 degrees of the old.
      const Vec3 n1 = normal_of(m, p, x), n2 = normal_of(x, q, m);
      const double c20 = std::cos(20.0 * M_PI / 180);
      if (n1.dot(before) <= c20 * n1.norm() * before.norm() ||
          n2.dot(before) <= c20 * n2.norm() * before.norm())
        continue;
      const gp_Pnt2d up = a.uv[c1], uq = a.uv[(c1 + 1) % 3], um = a.uv[(c1 + 2) % 3];
      const gp_Pnt2d ux = b.uv[(c2 + 2) % 3];
      unlink(t1);
      unlink(t2);
      at_edge.erase(key);
      tris[t1] = SurfaceTriangle{{m, p, x}, {um, up, ux}, a.face};
      tris[t2] = SurfaceTriangle{{x, q, m}, {ux, uq, um}, a.face};
      link(t1);
      link(t2);
      ++flips;
      for (std::uint64_t k : {pair_key(m, p), pair_key(p, x), pair_key(x, q), pair_key(q, m)})
        stack.push_back(k);
    }
  };
  auto needs_split = [&](int ti) {
    if (lattice_face[tris[ti].face]) return false;
    const int c = longest(ti);
    const int a = tris[ti].node[c], b = tris[ti].node[(c + 1) % 3];
    auto seg = surface.segments.find(pair_key(a, b));
    if (seg != surface.segments.end() && lattice_edge[seg->second.edge]) return false;
    return length(a, b) > target;
  };
  // Splits the longest side of triangle ti (in every triangle that has it), then restores the
  // Delaunay property around the new node.
  auto split_longest = [&](int ti) {
    const int c = longest(ti);
    restore_delaunay(split_side(tris[ti].node[c], tris[ti].node[(c + 1) % 3]));
  };
  // Sides end at about target / 2 or more: more nodes than ten times the surface's area over
  // such triangles' area (plus BRepMesh's own) means the refinement is not converging, which is
  // reported rather than run without end.
  double area = 0;
  for (const SurfaceTriangle& t : tris)
    area += 0.5 * normal_of(t.node[0], t.node[1], t.node[2]).norm();
  const std::size_t node_budget =
      surface.nodes.size() + static_cast<std::size_t>(10 * area / (0.1 * target * target)) + 1000;
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
    while (needs_split(ti)) {
      if (surface.nodes.size() > node_budget)
        throw InputError("the surface triangulation of face " + std::to_string(tris[ti].face) +
                             " does not converge to size " + std::to_string(target) + " (over " +
                             std::to_string(node_budget) + " nodes); try another size",
                         Entity::Parameter);
      split_longest(ti);
    }

  // Bisection leaves nodes very near a seam or an edge (needles, and a tet on a needle is no
  // better than its smallest angle). Each node inside a face that is not a lattice face moves to
  // the centroid of its neighbours, put back on the face's surface, where that raises the
  // smallest angle of its triangles without turning one over; then the flips again.
  const std::vector<char> on_edge = nodes_on_edges(surface);
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(s.faces.Extent());
  std::vector<std::vector<int>> around;
  auto shortest_side = [&](int n) {
    double shortest = std::numeric_limits<double>::max();
    for (int ti : around[n])
      for (int m : tris[ti].node)
        if (m != n) shortest = std::min(shortest, length(n, m));
    return shortest;
  };
  auto smallest_angle = [&](int n) {
    double worst = M_PI;
    for (int ti : around[n])
      worst = std::min(worst, hexmerge::smallest_angle(surface.nodes, tris[ti].node));
    return worst;
  };
  for (int round = 0; round < kSmoothingRounds; ++round) {
    around.assign(surface.nodes.size(), {});
    for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
      for (int n : tris[ti].node) around[n].push_back(ti);
    for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) {
      if (on_edge[n] || around[n].empty()) continue;
      const int face = tris[around[n].front()].face;
      // Only nodes of needles: the others stay where the refinement put them (smoothing them
      // all changed TetGen's lattice enough for the bracket to lose two thirds of its hexes at
      // some sizes).
      if (lattice_face[face] || smallest_angle(n) >= kNeedleAngle) continue;
      Vec3 centroid{0, 0, 0};
      int count = 0;
      for (int ti : around[n])
        for (int m : tris[ti].node)
          if (m != n) centroid = centroid + surface.nodes[m], ++count;
      if (!analysis[face]) {
        const TopoDS_Face& f = TopoDS::Face(s.faces(face + 1));
        analysis[face] = std::make_unique<ShapeAnalysis_Surface>(BRep_Tool::Surface(f));
      }
      centroid = centroid * (1.0 / count);
      const Vec3 old = surface.nodes[n];
      // The surface's normal at the node: its triangles' normals weighted by area (a needle's
      // own normal is noise: compared with it, moves off the seam were refused as folds).
      Vec3 reference{0, 0, 0};
      for (int ti : around[n])
        reference = reference + normal_of(tris[ti].node[0], tris[ti].node[1], tris[ti].node[2]);
      const double before = smallest_angle(n), shortest = shortest_side(n);
      // To the centroid, else half or a quarter of the way, put back on the surface: better
      // angles, no triangle turned more than 20 degrees from the reference, and no nearer than
      // h / 8 to a neighbour (unless it was already): nodes must not gather (TetGen drops points
      // too close together). With only the whole way and h / 4, needles whose node sat within
      // h / 4 of the seam's nodes stayed (cylinder: tets of scaled Jacobian 0.006 on triangles
      // of 179.4 degrees at the seam).
      bool keep = false;
      for (double fraction : {1.0, 0.5, 0.25}) {
        const Vec3 goal = old + (centroid - old) * fraction;
        const gp_Pnt2d uv =
            analysis[face]->ValueOfUV(gp_Pnt(goal.x, goal.y, goal.z), 1e-9 * target);
        surface.nodes[n] = of(analysis[face]->Value(uv));
        keep = smallest_angle(n) > before &&
               shortest_side(n) >= std::min(shortest, kNeedleNearest * target);
        for (std::size_t k = 0; k < around[n].size() && keep; ++k) {
          const auto& v = tris[around[n][k]].node;
          keep = !turned_over(normal_of(v[0], v[1], v[2]), reference);
        }
        if (keep) break;
      }
      if (!keep) surface.nodes[n] = old;
    }
    std::vector<std::uint64_t> all_sides;
    for (const SurfaceTriangle& t : tris)
      for (int c = 0; c < 3; ++c) all_sides.push_back(side_key(t, c));
    restore_delaunay(all_sides);
  }
}

// Sides shorter than this fraction of h inside one face are collapsed after the refinement.
constexpr double kCollapseSide = 0.25;

// Collapses the short sides that bisection and smoothing leave inside a face (not on a CAD edge,
// not on a lattice face): one end goes to the other, which stays where it is (so on its face),
// where the link condition holds, no triangle turns more than 20 degrees from the surface's
// normal at the removed node, no side gets longer than `target`, and the smallest angle of the
// triangles around both ends does not get worse. Runs of nodes 0.1 to 0.3 h apart (cylinder at
// h 2.7: twenty in a line on the side face) otherwise make triangles of 179 degrees, and tets on
// them of scaled Jacobian 0.003. The removed nodes are dropped and the rest renumbered.
void collapse_short_sides(Surface& surface, double target, const std::vector<bool>& lattice_face) {
  std::vector<SurfaceTriangle>& tris = surface.triangles;
  const std::vector<Vec3>& nodes = surface.nodes;
  const int nb_nodes = static_cast<int>(nodes.size());
  const std::vector<char> on_edge = nodes_on_edges(surface);
  std::vector<std::vector<int>> around(nb_nodes);
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
    for (int n : tris[ti].node) around[n].push_back(ti);
  std::vector<char> dead(tris.size(), 0), removed(nb_nodes, 0);
  auto normal_of = [&](const std::array<int, 3>& v) {
    return hexmerge::normal_of(nodes, v[0], v[1], v[2]);
  };
  auto smallest_angle = [&](const std::array<int, 3>& v) {
    return hexmerge::smallest_angle(nodes, v);
  };
  auto has = [](const SurfaceTriangle& t, int n) {
    return t.node[0] == n || t.node[1] == n || t.node[2] == n;
  };
  // The smallest angle after moving node r onto node k, or -1 when that is not allowed.
  auto try_collapse = [&](int r, int k) {
    if (on_edge[r] || around[r].empty()) return -1.0;
    const int face = tris[around[r].front()].face;
    if (lattice_face[face]) return -1.0;
    std::vector<int> shared;
    Vec3 reference{0, 0, 0};
    for (int ti : around[r]) {
      if (tris[ti].face != face) return -1.0;
      if (has(tris[ti], k)) shared.push_back(ti);
      reference = reference + normal_of(tris[ti].node);
    }
    if (shared.size() != 2) return -1.0;
    // Link condition: the ends' common neighbours are the shared triangles' third nodes.
    std::unordered_set<int> near_r, common;
    for (int ti : around[r])
      for (int n : tris[ti].node) near_r.insert(n);
    for (int ti : around[k])
      for (int n : tris[ti].node)
        if (n != r && n != k && near_r.count(n)) common.insert(n);
    if (common.size() != 2) return -1.0;
    double before = M_PI, after = M_PI;
    for (int ti : around[k]) before = std::min(before, smallest_angle(tris[ti].node));
    for (int ti : around[k])
      if (!has(tris[ti], r)) after = std::min(after, smallest_angle(tris[ti].node));
    for (int ti : around[r]) {
      before = std::min(before, smallest_angle(tris[ti].node));
      if (has(tris[ti], k)) continue;
      std::array<int, 3> v = tris[ti].node;
      for (int& n : v)
        if (n == r) n = k;
      for (int n : v)
        if ((nodes[n] - nodes[k]).norm() > target) return -1.0;
      const Vec3 now = normal_of(v);
      if (turned_over(now, reference)) return -1.0;
      after = std::min(after, smallest_angle(v));
    }
    return after >= before ? after : -1.0;
  };
  auto collapse = [&](int r, int k) {
    gp_Pnt2d uv_k;
    for (int ti : around[r])
      if (has(tris[ti], k)) {
        dead[ti] = 1;
        for (int c = 0; c < 3; ++c)
          if (tris[ti].node[c] == k) uv_k = tris[ti].uv[c];
      }
    for (int ti : around[r]) {
      if (dead[ti]) {
        for (int n : tris[ti].node)
          if (n != r)
            around[n].erase(std::remove(around[n].begin(), around[n].end(), ti), around[n].end());
        continue;
      }
      for (int c = 0; c < 3; ++c)
        if (tris[ti].node[c] == r) tris[ti].node[c] = k, tris[ti].uv[c] = uv_k;
      around[k].push_back(ti);
    }
    around[r].clear();
    removed[r] = 1;
  };
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<std::pair<double, std::uint64_t>> sides;
    for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti) {
      if (dead[ti] || lattice_face[tris[ti].face]) continue;
      for (int c = 0; c < 3; ++c) {
        const int a = tris[ti].node[c], b = tris[ti].node[(c + 1) % 3];
        const double l = (nodes[a] - nodes[b]).norm();
        if (a < b && l < kCollapseSide * target && !surface.segments.count(pair_key(a, b)))
          sides.push_back({l, pair_key(a, b)});
      }
    }
    std::sort(sides.begin(), sides.end());
    for (const auto& [l, key] : sides) {
      (void)l;
      const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
      if (removed[a] || removed[b]) continue;
      const double ab = try_collapse(a, b), ba = try_collapse(b, a);
      if (ab < 0 && ba < 0) continue;
      if (ab >= ba)
        collapse(a, b);
      else
        collapse(b, a);
      changed = true;
    }
  }
  std::vector<int> renumber(nb_nodes, -1);
  Surface out;
  for (int n = 0; n < nb_nodes; ++n)
    if (!removed[n]) {
      renumber[n] = static_cast<int>(out.nodes.size());
      out.nodes.push_back(nodes[n]);
      out.node_face.push_back(surface.node_face[n]);
      out.seed.push_back(n);
    }
  for (std::size_t ti = 0; ti < tris.size(); ++ti) {
    if (dead[ti]) continue;
    SurfaceTriangle t = tris[ti];
    for (int& n : t.node) n = renumber[n];
    out.triangles.push_back(t);
  }
  for (const auto& [key, segment] : surface.segments)
    out.segments[pair_key(renumber[key >> 32], renumber[key & 0xffffffffu])] = segment;
  surface = std::move(out);
}

// Puts the nodes of each straight CAD edge that bounds a lattice face and runs across two frame
// axes exactly on one line (nodes in frame coordinates). TetGen 1.5 never ended, or lost the
// face, on lattice faces whose loop had a nearly collinear run (a hexagonal prism's caps, a
// trapezoid's). The edge's ends go to a grid of 2^-40 of the shape's size along those two axes,
// and every node between to their exact binary interpolation at its parameter, rounded to 2^-20
// of the edge (bisection and the sweep's power-of-two pieces give such parameters).
void align_straight_edges(const Shape& s, const Surface& surface,
                          const std::vector<bool>& lattice_face, double largest,
                          std::vector<Vec3>& nodes) {
  std::map<int, std::vector<std::pair<double, int>>> on_edge;  // edge -> (parameter, node)
  for (const auto& [key, segment] : surface.segments) {
    const auto& faces = s.edge_faces[segment.edge];
    if (std::none_of(faces.begin(), faces.end(), [&](int f) { return lattice_face[f]; })) continue;
    auto& list = on_edge[segment.edge];
    list.emplace_back(segment.t_lo, static_cast<int>(key >> 32));  // the smaller id
    list.emplace_back(segment.t_hi, static_cast<int>(key & 0xffffffffu));
  }
  const int exponent = std::ilogb(largest) - 40;
  // x rounded to a multiple of 2^e.
  auto round_to = [](double x, int e) { return std::ldexp(std::round(std::ldexp(x, -e)), e); };
  for (auto& [edge, list] : on_edge) {
    if (BRepAdaptor_Curve(TopoDS::Edge(s.edges(edge + 1))).GetType() != GeomAbs_Line) continue;
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    const double t0 = list.front().first, t1 = list.back().first;
    Vec3& a = nodes[list.front().second];
    Vec3& b = nodes[list.back().second];
    std::vector<int> across;  // the axes the edge runs across
    for (int c = 0; c < 3; ++c)
      if (coord(a, c) != coord(b, c)) across.push_back(c);
    if (across.size() < 2 || t1 <= t0) continue;
    for (int c : across)
      set_coord(a, c, round_to(coord(a, c), exponent)),
          set_coord(b, c, round_to(coord(b, c), exponent));
    for (std::size_t k = 1; k + 1 < list.size(); ++k) {
      const double f = round_to((list[k].first - t0) / (t1 - t0), -20);
      for (int c : across)
        set_coord(nodes[list[k].second], c, coord(a, c) + (coord(b, c) - coord(a, c)) * f);
    }
  }
}

// A planar face normal to a frame axis: the axis and the face's offset along it.
struct AxisPlane {
  int axis;
  double offset;
};

// ---------------------------------------------------------------------------------------------
// Swept shapes. A solid that is a profile extruded along a lattice axis gets a mesh that is
// extruded too: its walls are triangulated in strips between consecutive lattice planes, with
// the same nodes (stations) on every plane, so that the layers, the lattice points and TetGen's
// tets repeat from one plane to the next. Every tet then lies in a slab between two planes, the
// tets of a slab form prisms over the cross-section's triangles, and two prisms over triangles
// that make a good quad form a hexahedron: the transition between the lattice core and the
// boundary layers recombines too, with no closing pyramids.

// A swept shape's faces: caps (planar, normal to the axis, on a lattice plane) and walls
// (parallel to the axis, between two lattice planes).
struct Sweep {
  int axis = -1;                          // frame axis
  std::vector<int> cap;                   // per face: its lattice plane if a cap, else -1
  std::vector<std::array<int, 2>> range;  // per wall: the lattice planes of its ends
};

// The frame axis along which the shape is swept: every face is a cap on a lattice plane or a wall
// (a plane, cylinder or surface of extrusion parallel to the axis, bounded by lines along the
// axis and by curves in lattice planes), there are caps on the first and the last plane, and at
// least one wall is not a lattice face (a box is a lattice already). The frame's third axis is
// tried first. Whether the cross-section is the same on every plane is sweep_surface()'s to see.
std::optional<Sweep> find_sweep(const Shape& s, const Frame& frame,
                                const std::vector<std::optional<AxisPlane>>& face_plane,
                                const std::vector<bool>& lattice_face, const int (&cells)[3],
                                const std::array<double, 3>& spacing, double h) {
  const double tolerance = 1e-7 * h;
  for (int a = 2; a >= 0; --a) {
    const Vec3& axis = frame.axis[a];
    // The lattice plane at offset z along the axis, or -1.
    auto plane_at = [&](double z) {
      const long k = std::lround(z / spacing[a]);
      return std::abs(z - k * spacing[a]) < tolerance && k >= 0 && k <= cells[a]
                 ? static_cast<int>(k)
                 : -1;
    };
    const int nb_faces = s.faces.Extent();
    Sweep sweep{a, std::vector<int>(nb_faces, -1), std::vector<std::array<int, 2>>(nb_faces)};
    bool ok = true, bottom = false, top = false, unaligned_wall = false;
    for (int f = 0; f < nb_faces && ok; ++f) {
      if (face_plane[f] && face_plane[f]->axis == a) {
        sweep.cap[f] = plane_at(face_plane[f]->offset);
        ok = sweep.cap[f] >= 0 && lattice_face[f];
        bottom = bottom || sweep.cap[f] == 0;
        top = top || sweep.cap[f] == cells[a];
        continue;
      }
      const TopoDS_Face& face = TopoDS::Face(s.faces(f + 1));
      BRepAdaptor_Surface surface(face, false);
      const double parallel = 1 - 1e-12;
      switch (surface.GetType()) {
        case GeomAbs_Plane:
          ok = std::abs(of(surface.Plane().Axis().Direction()).dot(axis)) < 1e-9;
          break;
        case GeomAbs_Cylinder:
          ok = std::abs(of(surface.Cylinder().Axis().Direction()).dot(axis)) > parallel;
          break;
        case GeomAbs_SurfaceOfExtrusion:
          ok = std::abs(of(surface.Direction()).dot(axis)) > parallel;
          break;
        default:
          ok = false;
      }
      unaligned_wall = unaligned_wall || !lattice_face[f];
      int lo = cells[a] + 1, hi = -1;  // the planes of its edges across the axis
      for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More() && ok; ex.Next()) {
        const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
        if (BRep_Tool::Degenerated(edge)) {
          ok = false;
          break;
        }
        BRepAdaptor_Curve curve(edge);
        if (curve.GetType() == GeomAbs_Line &&
            std::abs(of(curve.Line().Direction()).dot(axis)) > parallel)
          continue;
        int level = -2;  // the lattice plane the edge lies in
        for (int i = 0; i <= 8 && ok; ++i) {
          const double t =
              curve.FirstParameter() + (curve.LastParameter() - curve.FirstParameter()) * i / 8;
          const int here = plane_at(coord(frame.to_frame(of(curve.Value(t))), a));
          ok = here >= 0 && (level == -2 || here == level);
          level = here;
        }
        lo = std::min(lo, level), hi = std::max(hi, level);
      }
      ok = ok && lo < hi;
      sweep.range[f] = {lo, hi};
    }
    if (ok && bottom && top && unaligned_wall) return sweep;
  }
  return std::nullopt;
}

// What sweep_surface() made: per node, the node on the bottom plane it repeats (itself there);
// the first plane's sides on walls, as a cap's triangles run, whether that wall lies between two
// solids, and whether it is a lattice face.
struct SweptSurface {
  std::vector<int> base;
  std::vector<std::array<int, 2>> sides;
  std::vector<char> shared, on_lattice_face;
};

// Rebuilds the surface of a swept shape, when its cross-section is the same on every lattice
// plane along the axis (else nothing changes and the result is empty): the caps on the first
// plane as BRepMesh made them, their sides on walls split to at most `target` (on walls that
// are not lattice faces: those keep their lattice points instead), every node on a wall repeated
// on the `levels` planes above (`step` apart), the walls as two triangles per side and slab (of
// the wall face there), and the caps on the planes above as copies of the first plane's
// triangles, each in the cap face that holds its centroid there. The nodes come plane by plane,
// in the same order on every plane.
std::optional<SweptSurface> sweep_surface(const Shape& s, const Sweep& sweep, const Frame& frame,
                                          const Vec3& step, int levels, double target,
                                          double deflection, const std::vector<bool>& lattice_face,
                                          Surface& surface) {
  const int axis = sweep.axis;
  auto directed = [](int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
           static_cast<std::uint32_t>(b);
  };
  std::vector<Vec3> framed(surface.nodes.size());  // of the nodes BRepMesh made
  for (std::size_t n = 0; n < framed.size(); ++n) framed[n] = frame.to_frame(surface.nodes[n]);
  // The first plane's caps, the caps' triangles per plane, and the wall face behind each
  // directed side of a wall triangle.
  std::vector<SurfaceTriangle> bottom;
  std::map<int, std::vector<const SurfaceTriangle*>> caps_on;  // plane -> cap triangles
  std::unordered_map<std::uint64_t, int> wall_at;
  for (const SurfaceTriangle& t : surface.triangles) {
    if (sweep.cap[t.face] == 0)
      bottom.push_back(t);
    else if (sweep.cap[t.face] > 0)
      caps_on[sweep.cap[t.face]].push_back(&t);
    else
      for (int c = 0; c < 3; ++c) wall_at[directed(t.node[c], t.node[(c + 1) % 3])] = t.face;
  }
  // Each wall's profile: the sides of its triangles on its lowest plane, across the axis.
  std::vector<std::vector<std::array<Vec3, 2>>> profile(s.faces.Extent());
  for (const SurfaceTriangle& t : surface.triangles) {
    if (sweep.cap[t.face] >= 0) continue;
    for (int c = 0; c < 3; ++c) {
      Vec3 p = framed[t.node[c]], q = framed[t.node[(c + 1) % 3]];
      const double z = sweep.range[t.face][0] * (step.norm());
      if (std::abs(coord(p, axis) - z) > 1e-7 * target ||
          std::abs(coord(q, axis) - z) > 1e-7 * target)
        continue;
      set_coord(p, axis, 0), set_coord(q, axis, 0);
      profile[t.face].push_back({p, q});
    }
  }
  // The wall face with a strip over the side from p to q (across the axis) in slab k: its range
  // holds k and its profile passes by the side's midpoint (two chords of one curve are at most
  // twice the deflection apart).
  auto wall_over = [&](const Vec3& p, const Vec3& q, int k) {
    Vec3 m = (p + q) * 0.5;
    set_coord(m, axis, 0);
    for (int f = 0; f < s.faces.Extent(); ++f) {
      if (sweep.cap[f] >= 0 || sweep.range[f][0] > k || sweep.range[f][1] <= k) continue;
      for (const auto& side : profile[f]) {
        const Vec3 d = side[1] - side[0];
        const double t = std::clamp((m - side[0]).dot(d) / d.dot(d), 0.0, 1.0);
        if ((side[0] + d * t - m).norm() <= 2 * deflection + 1e-7 * target) return f;
      }
    }
    return -1;
  };
  std::unordered_map<std::uint64_t, int> triangle_at;  // directed side -> bottom triangle
  for (int ti = 0; ti < static_cast<int>(bottom.size()); ++ti)
    for (int c = 0; c < 3; ++c)
      triangle_at[directed(bottom[ti].node[c], bottom[ti].node[(c + 1) % 3])] = ti;
  // The first plane's sides on walls (once, directed as the wall's triangles run the other way),
  // and the wall of each slab over them; every wall must be over some side.
  struct Side {
    int from, to;
    std::vector<int> wall;  // per slab
  };
  std::vector<Side> boundary;
  std::vector<char> used(s.faces.Extent(), 0);
  std::unordered_set<std::uint64_t> seen;
  for (const SurfaceTriangle& t : bottom)
    for (int c = 0; c < 3; ++c) {
      int a = t.node[c], b = t.node[(c + 1) % 3];
      if (!seen.insert(pair_key(a, b)).second) continue;
      if (!wall_at.count(directed(b, a))) std::swap(a, b);
      if (!wall_at.count(directed(b, a))) {
        if (!triangle_at.count(directed(b, a)) || !triangle_at.count(directed(a, b)))
          return std::nullopt;  // an outer side with no wall behind
        continue;               // inside the first plane's caps
      }
      Side side{a, b, std::vector<int>(levels, -1)};
      for (int k = 0; k < levels; ++k) {
        side.wall[k] = k > 0 && sweep.range[side.wall[k - 1]][1] > k
                           ? side.wall[k - 1]
                           : wall_over(framed[a], framed[b], k);
        if (side.wall[k] < 0) return std::nullopt;  // the cross-section changes
        used[side.wall[k]] = 1;
      }
      boundary.push_back(std::move(side));
    }
  for (int f = 0; f < s.faces.Extent(); ++f)
    if (sweep.cap[f] < 0 && !used[f]) return std::nullopt;  // a wall the first plane lacks

  // Long sides on walls that are not lattice faces: split evenly along their CAD edge, the
  // first plane's triangles on them cut into fans.
  std::vector<Side> sides;
  std::unordered_map<std::uint64_t, EdgeSegment> segments;  // of the sides, old numbering
  for (const Side& side : boundary) {
    const auto segment = surface.segments.find(pair_key(side.from, side.to));
    const double length = (surface.nodes[side.to] - surface.nodes[side.from]).norm();
    int pieces = static_cast<int>(std::ceil(length / target - 1e-9));
    if (lattice_face[side.wall[0]] || segment == surface.segments.end() || pieces <= 1) {
      if (segment != surface.segments.end()) segments.insert(*segment);
      sides.push_back(side);
      continue;
    }
    const EdgeSegment e = segment->second;
    const double t_from = side.from < side.to ? e.t_lo : e.t_hi;
    const double t_to = side.from < side.to ? e.t_hi : e.t_lo;
    const BRepAdaptor_Curve curve(TopoDS::Edge(s.edges(e.edge + 1)));
    // A straight side is split into a power of two of pieces, so that align_straight_edges()
    // can put its nodes exactly on one line.
    if (curve.GetType() == GeomAbs_Line)
      pieces = 1 << static_cast<int>(std::ceil(std::log2(pieces) - 1e-9));
    std::vector<int> chain{side.from};
    for (int i = 1; i < pieces; ++i) {
      chain.push_back(static_cast<int>(surface.nodes.size()));
      surface.nodes.push_back(of(curve.Value(t_from + (t_to - t_from) * i / pieces)));
      surface.node_face.push_back(side.wall[0]);  // on its bottom edge
    }
    chain.push_back(side.to);
    for (int i = 1; i <= pieces; ++i) {
      // The piece's segment of the CAD edge, at its parameters.
      const double ta = t_from + (t_to - t_from) * (i - 1) / pieces;
      const double tb = i == pieces ? t_to : t_from + (t_to - t_from) * i / pieces;
      const int previous = chain[i - 1], next = chain[i];
      segments[pair_key(previous, next)] =
          previous < next ? EdgeSegment{e.edge, ta, tb} : EdgeSegment{e.edge, tb, ta};
      sides.push_back({previous, next, side.wall});
    }
    // The triangles on the side (one, or two on a wall between two caps): fans.
    for (const auto& [x, y] : {std::pair{side.from, side.to}, std::pair{side.to, side.from}}) {
      const auto at = triangle_at.find(directed(x, y));
      if (at == triangle_at.end()) continue;
      const int ti = at->second;
      const SurfaceTriangle t = bottom[ti];
      const int apex = t.node[(side_with_key(t, pair_key(x, y)) + 2) % 3];
      for (int i = 1; i <= pieces; ++i) {
        const int p = x == side.from ? chain[i - 1] : chain[pieces - i + 1];
        const int q = x == side.from ? chain[i] : chain[pieces - i];
        const SurfaceTriangle piece{{p, q, apex}, {}, t.face};
        const int index = i == 1 ? ti : static_cast<int>(bottom.size());
        if (i == 1)
          bottom[ti] = piece;
        else
          bottom.push_back(piece);
        for (int k = 0; k < 3; ++k)
          triangle_at[directed(piece.node[k], piece.node[(k + 1) % 3])] = index;
      }
    }
  }

  // The new surface: the first plane's caps' nodes (renumbered in their order), then plane by
  // plane the nodes on walls repeated, and on planes with caps the caps' inner nodes they use.
  std::vector<int> renumber(surface.nodes.size(), -1);
  std::vector<int> order;
  for (const SurfaceTriangle& t : bottom)
    for (int n : t.node) renumber[n] = 1;
  for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n)
    if (renumber[n] >= 0) renumber[n] = static_cast<int>(order.size()), order.push_back(n);
  std::vector<int> wall_of(order.size(), -1);  // per node of the first plane: a wall there
  for (const Side& side : sides)
    for (int n : {side.from, side.to}) wall_of[renumber[n]] = side.wall[0];
  // The cap face on plane k holding point p (BRepMesh's triangles of the caps there), or -1.
  auto cap_face = [&](int k, const Vec3& p) {
    const auto it = caps_on.find(k);
    return it == caps_on.end() ? -1 : face_holding(frame.to_frame(p), it->second, framed, axis);
  };
  // The caps on the planes above: the first plane's triangles that fall in one, per plane.
  std::vector<std::vector<std::pair<int, int>>> capped(levels + 1);  // (bottom triangle, face)
  std::vector<std::vector<char>> needed(levels + 1, std::vector<char>(order.size(), 0));
  for (int k = 1; k <= levels; ++k) {
    if (!caps_on.count(k)) continue;
    for (int ti = 0; ti < static_cast<int>(bottom.size()); ++ti) {
      const SurfaceTriangle& t = bottom[ti];
      const Vec3 centroid =
          (surface.nodes[t.node[0]] + surface.nodes[t.node[1]] + surface.nodes[t.node[2]]) *
              (1.0 / 3) +
          step * k;
      const int face = cap_face(k, centroid);
      if (face < 0) continue;
      capped[k].emplace_back(ti, face);
      for (int n : t.node) needed[k][renumber[n]] = 1;
    }
  }
  Surface swept;
  SweptSurface result;
  std::vector<std::vector<int>> copy(levels + 1, std::vector<int>(order.size(), -1));
  for (int k = 0; k <= levels; ++k)
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (k > 0 && wall_of[i] < 0 && !needed[k][i]) continue;
      copy[k][i] = static_cast<int>(swept.nodes.size());
      swept.nodes.push_back(surface.nodes[order[i]] + step * k);
      swept.node_face.push_back(k == 0            ? surface.node_face[order[i]]
                                : wall_of[i] >= 0 ? wall_of[i]
                                                  : cap_face(k, swept.nodes.back()));
      result.base.push_back(static_cast<int>(i));
    }
  swept.seed = result.base;
  // The first plane's segments (the planes above repeat its nodes, see mesh_shape).
  for (const auto& [key, segment] : segments)
    swept.segments[pair_key(renumber[key >> 32], renumber[key & 0xffffffffu])] = segment;
  for (const SurfaceTriangle& t : bottom)
    swept.triangles.push_back(
        {{renumber[t.node[0]], renumber[t.node[1]], renumber[t.node[2]]}, {}, t.face});
  for (const Side& side : sides) {
    const int a = renumber[side.from], b = renumber[side.to];
    result.sides.push_back({a, b});
    result.shared.push_back(s.face_solid_count[side.wall[0]] > 1);
    result.on_lattice_face.push_back(lattice_face[side.wall[0]]);
    for (int k = 0; k < levels; ++k) {
      swept.triangles.push_back({{copy[k][b], copy[k][a], copy[k + 1][a]}, {}, side.wall[k]});
      swept.triangles.push_back({{copy[k][b], copy[k + 1][a], copy[k + 1][b]}, {}, side.wall[k]});
    }
  }
  for (int k = 1; k <= levels; ++k)
    for (const auto& [ti, face] : capped[k]) {
      const SurfaceTriangle& t = bottom[ti];
      const int a = renumber[t.node[0]], b = renumber[t.node[1]], c = renumber[t.node[2]];
      swept.triangles.push_back({{copy[k][a], copy[k][c], copy[k][b]}, {}, face});
    }
  surface = std::move(swept);
  return result;
}

// ---------------------------------------------------------------------------------------------
// TetGen through its files.

// A TetGen facet: polygons (a face's outer and inner boundary loops, or one triangle, and single
// points inside it), points inside its holes, its boundary marker (face index + 1).
struct Facet {
  std::vector<std::vector<int>> polygons;
  std::vector<Vec3> holes;
  int marker;
};

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
    std::unordered_map<int, int> next;  // directed boundary edges, as the triangles run
    bool simple = true;
    for (const SurfaceTriangle* t : triangles)
      for (int c = 0; c < 3; ++c) {
        const int a = t->node[c], b = t->node[(c + 1) % 3];
        if (uses[pair_key(a, b)] == 1) simple &= next.emplace(a, b).second;
      }
    if (!simple) {  // a loop touching itself: keep the triangles
      for (const SurfaceTriangle* t : triangles)
        facets.push_back(Facet{{{t->node[0], t->node[1], t->node[2]}}, {}, face + 1});
      continue;
    }
    const int axis = face_plane[face]->axis, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const SurfaceTriangle* t0 = triangles.front();
    const Vec3 normal =
        (nodes[t0->node[1]] - nodes[t0->node[0]]).cross(nodes[t0->node[2]] - nodes[t0->node[0]]);
    const double side = coord(normal, axis) > 0 ? 1 : -1;
    Facet facet{{}, {}, face + 1};
    while (!next.empty()) {
      std::vector<int> loop;
      int a = next.begin()->first;
      while (next.count(a)) {
        loop.push_back(a);
        const int b = next[a];
        next.erase(a);
        a = b;
      }
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
    facets.push_back(std::move(facet));
  }
  return facets;
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

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) return fs::exists(name) ? name : std::string();
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  return std::string();
}

std::string tail_of_file(const fs::path& path, std::size_t max_chars) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  return s.size() > max_chars ? "..." + s.substr(s.size() - max_chars) : s;
}

// Reads a TetGen output table (.node, .ele or .face, 0-based with -z): a header "count header
// ...", then per line an id and `columns` values; '#' starts a comment. The header's second
// number is `header`: the values per row of .node (3) and .ele (4), the marker flag of .face
// (1: three vertices and a marker per row). Returns count * columns values.
template <typename T>
std::vector<T> read_tetgen_table(const fs::path& path, int header, int columns) {
  std::ifstream in(path);
  const std::string name = path.filename().string();
  if (!in) throw InputError("TetGen wrote no " + name);
  std::string line;
  long long n = -1, width = 0;
  std::vector<T> values;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    if (n < 0) {
      if (!(ls >> n >> width)) continue;
      if (width != header)
        throw InputError("TetGen's " + name + " has " + std::to_string(width) +
                         " in its header, not " + std::to_string(header));
      values.reserve(static_cast<std::size_t>(n) * columns);
      continue;
    }
    long long id;
    if (!(ls >> id)) continue;
    for (int k = 0; k < columns; ++k) {
      T x;
      if (!(ls >> x)) throw InputError("TetGen's " + name + " has a short row: " + line);
      values.push_back(x);
    }
  }
  if (n < 0 || static_cast<long long>(values.size()) != columns * n)
    throw InputError("TetGen's " + name + " is truncated");
  return values;
}

// A temporary directory removed on destruction (unless kept).
class WorkDirectory {
 public:
  explicit WorkDirectory(const std::string& requested) {
    if (!requested.empty()) {
      path_ = requested;
      fs::create_directories(path_);
      keep_ = true;
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "hexmerge-mesh-XXXXXX").string();
    if (!mkdtemp(pattern.data()))
      throw InputError("cannot create a temporary directory for TetGen");
    path_ = pattern;
  }
  ~WorkDirectory() {
    std::error_code ec;
    if (!keep_) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool keep_ = false;
};

void check_parameters(const MeshShapeParameters& p) {
  auto bad = [](const std::string& what) {
    throw InputError("mesh_shape: " + what, Entity::Parameter);
  };
  if (!(p.size > 0) || !std::isfinite(p.size)) bad("size must be a positive length");
  if (p.boundary_layers < 0 || p.boundary_layers > 3) bad("boundary_layers must be in [0, 3]");
  if (!(p.layer_thickness >= 0.1 && p.layer_thickness <= 1))
    bad("layer_thickness must be in [0.1, 1]");
  if (!(p.lattice_margin >= 0.1 && p.lattice_margin <= 2))
    bad("lattice_margin must be in [0.1, 2]");
  if (!(p.surface_deflection > 0 && p.surface_deflection <= 0.5))
    bad("surface_deflection must be in (0, 0.5]");
  if (p.frame != "auto" && p.frame != "principal" && p.frame != "global")
    bad("frame must be \"auto\", \"principal\" or \"global\"");
  if (p.tetgen.empty()) bad("tetgen must name the TetGen program");
  if (!(p.tetgen_time_limit >= 0 && p.tetgen_time_limit <= 86400))
    bad("tetgen_time_limit must be in [0, 86400] seconds");
}

}  // namespace

TetMesh mesh_shape(const std::string& brep, const MeshShapeParameters& parameters,
                   MeshShapeReport& report) {
  check_parameters(parameters);
  report = MeshShapeReport{};
  PhaseClock clock(report.phase_seconds);
  const double h = parameters.size;
  const std::string tetgen = find_program(parameters.tetgen);
  if (tetgen.empty())
    throw InputError("mesh_shape needs TetGen: \"" + parameters.tetgen +
                         "\" is not found (Debian: apt install tetgen)",
                     Entity::Parameter);

  // The shape and its frame.
  const Shape shape = load_shape(brep);
  report.nb_solids = static_cast<std::size_t>(shape.solids.Extent());
  report.nb_faces = static_cast<std::size_t>(shape.faces.Extent());
  Frame frame = choose_frame(shape, parameters.frame);
  clock.lap("shape");

  // The lattice through the bounding box in the frame, from the triangulation's nodes (on the CAD).
  const double deflection = parameters.surface_deflection * h;
  Surface surface = triangulate(shape, deflection, 1e-9 * h + 1e-12);
  Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
          std::numeric_limits<double>::max()};
  Vec3 hi = lo * -1.0;
  for (const Vec3& p : surface.nodes) {
    const Vec3 q = frame.to_frame(p);
    lo = vmin(lo, q), hi = vmax(hi, q);
  }
  const double extent[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
  const double largest = std::max({extent[0], extent[1], extent[2]});
  if (h > largest)
    throw InputError("mesh_shape: size " + std::to_string(h) + " is larger than the shape (" +
                         std::to_string(largest) + " across)",
                     Entity::Parameter);
  frame.origin = frame.to_world(lo);  // lattice planes through the box's lower corner
  // Whether an offset along an axis falls on a lattice plane of the given spacing.
  const auto on_lattice_plane = [plane_tolerance = 1e-7 * h](double offset, double spacing) {
    const double k = offset / spacing;
    return std::abs(k - std::round(k)) * spacing < plane_tolerance;
  };

  // Planar faces normal to a frame axis, and their offsets along it.
  std::vector<std::optional<AxisPlane>> face_plane(shape.faces.Extent());
  std::vector<double> offsets[3];
  for (int fi = 1; fi <= shape.faces.Extent(); ++fi) {
    BRepAdaptor_Surface s(TopoDS::Face(shape.faces(fi)), false);
    if (s.GetType() != GeomAbs_Plane) continue;
    const Vec3 n = of(s.Plane().Axis().Direction());
    for (int a = 0; a < 3; ++a) {
      if (std::abs(std::abs(n.dot(frame.axis[a])) - 1) > 1e-9) continue;
      const double offset = coord(frame.to_frame(of(s.Plane().Location())), a);
      face_plane[fi - 1] = AxisPlane{a, offset};
      offsets[a].push_back(offset);
    }
  }
  // Cells per axis: about h wide, chosen so that as many axis-normal planar faces as possible
  // lie on lattice planes (the box's own faces always do).
  int cells[3];
  for (int a = 0; a < 3; ++a) {
    const double L = extent[a];
    const int guess = std::max(1, static_cast<int>(std::lround(L / h)));
    int best = guess, best_hits = -1;
    const int lo_n = std::max(1, static_cast<int>(std::floor(L / (1.5 * h))));
    const int hi_n = std::max(lo_n, static_cast<int>(std::ceil(L / (0.75 * h))));
    for (int n = lo_n; n <= hi_n; ++n) {
      const double spacing = L / n;
      int hits = 0;
      for (double o : offsets[a]) hits += on_lattice_plane(o, spacing);
      if (hits > best_hits || (hits == best_hits && std::abs(n - L / h) < std::abs(best - L / h)))
        best = n, best_hits = hits;
    }
    cells[a] = best;
    report.spacing[a] = L / best;
  }
  for (int a = 0; a < 3; ++a) report.frame[a] = {frame.axis[a].x, frame.axis[a].y, frame.axis[a].z};

  std::vector<bool> lattice_face(shape.faces.Extent(), false);
  for (int f = 0; f < shape.faces.Extent(); ++f) {
    if (!face_plane[f]) continue;
    lattice_face[f] = on_lattice_plane(face_plane[f]->offset, report.spacing[face_plane[f]->axis]);
    report.nb_lattice_faces += lattice_face[f];
  }
  std::vector<bool> lattice_edge(shape.edges.Extent(), false);
  for (int e = 0; e < shape.edges.Extent(); ++e) {
    const auto& around = shape.edge_faces[e];
    lattice_edge[e] = !around.empty() && std::all_of(around.begin(), around.end(),
                                                     [&](int f) { return lattice_face[f]; });
  }
  std::optional<Sweep> sweep;
  if (parameters.sweep)
    sweep = find_sweep(shape, frame, face_plane, lattice_face, cells, report.spacing, h);
  SweptSurface swept;
  if (sweep) {
    const int a = sweep->axis;
    const std::optional<SweptSurface> made =
        sweep_surface(shape, *sweep, frame, frame.axis[a] * report.spacing[a], cells[a], h,
                      deflection, lattice_face, surface);
    if (made)
      swept = *made;
    else
      sweep.reset();  // the cross-section changes along the axis
  }
  if (sweep) {
    report.sweep_axis = sweep->axis;
  } else {
    refine(shape, surface, h, lattice_face, lattice_edge);
    collapse_short_sides(surface, h, lattice_face);
  }
  clock.lap("surface");

  // Everything below in frame coordinates; nodes of lattice faces exactly on their planes.
  std::vector<Vec3> nodes(surface.nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) nodes[i] = frame.to_frame(surface.nodes[i]);
  for (const SurfaceTriangle& t : surface.triangles)
    if (lattice_face[t.face])
      for (int n : t.node) {
        const AxisPlane& plane = *face_plane[t.face];
        const double k = std::round(coord(nodes[n], plane.axis) / report.spacing[plane.axis]);
        set_coord(nodes[n], plane.axis, k * report.spacing[plane.axis]);
      }
  align_straight_edges(shape, surface, lattice_face, largest, nodes);
  if (sweep) {
    const int a = sweep->axis;
    // Every node exactly on its lattice plane, and across the axis exactly where the node on the
    // bottom plane it repeats is: the slabs are then equal to the last bit.
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const double level = std::round(coord(nodes[i], a) / report.spacing[a]);
      Vec3 p = nodes[swept.base[i]];
      set_coord(p, a, level * report.spacing[a]);
      nodes[i] = p;
    }
  }
  report.nb_surface_nodes = nodes.size();
  report.nb_surface_triangles = surface.triangles.size();

  const Vec3 box_lo = Vec3{0, 0, 0} - Vec3{2 * h, 2 * h, 2 * h};
  const Vec3 box_hi = Vec3{extent[0], extent[1], extent[2]} + Vec3{2 * h, 2 * h, 2 * h};
  TriangleSet curved(nodes, box_lo, box_hi, h);  // faces that are not lattice faces
  PointSet surface_points(box_lo, box_hi, h);
  for (const SurfaceTriangle& t : surface.triangles)
    if (!lattice_face[t.face]) curved.add(t.node);
  for (const Vec3& p : nodes) surface_points.add(p);

  // Lattice faces' triangles per lattice plane, for "does this lattice point lie on a face".
  std::map<std::pair<int, long>, std::vector<const SurfaceTriangle*>> plane_triangles;
  for (const SurfaceTriangle& t : surface.triangles)
    if (lattice_face[t.face]) {
      const AxisPlane& plane = *face_plane[t.face];
      plane_triangles[{plane.axis, std::lround(plane.offset / report.spacing[plane.axis])}]
          .push_back(&t);
    }
  auto on_lattice_face = [&](const Vec3& q, const int(&index)[3]) -> int {
    for (int a = 0; a < 3; ++a) {
      auto it = plane_triangles.find({a, index[a]});
      if (it == plane_triangles.end()) continue;
      const int face = face_holding(q, it->second, nodes, a);
      if (face >= 0) return face;
    }
    return -1;
  };

  // Boundary layers: surface nodes of the other faces where the surface is smooth, moved along
  // the inward normal, where there is room.
  std::vector<Vec3> normal(nodes.size(), Vec3{0, 0, 0});
  std::vector<bool> smooth(nodes.size(), true);
  auto triangle_normal = [&](const SurfaceTriangle& t) {
    return (nodes[t.node[1]] - nodes[t.node[0]]).cross(nodes[t.node[2]] - nodes[t.node[0]]);
  };
  for (const SurfaceTriangle& t : surface.triangles) {
    const Vec3 n = triangle_normal(t);
    for (int c : t.node) {
      normal[c] = normal[c] + n;
      if (lattice_face[t.face] || shape.face_solid_count[t.face] > 1) smooth[c] = false;
    }
  }
  for (auto& n : normal)
    if (n.norm() > 0) n = unit(n);
  for (const SurfaceTriangle& t : surface.triangles) {
    const Vec3 n = triangle_normal(t);
    if (n.norm() == 0) continue;
    for (int c : t.node)
      if (unit(n).dot(normal[c]) < std::cos(25.0 * M_PI / 180)) smooth[c] = false;
  }
  // Swept: the nodes repeating a node of the bottom caps' boundary take its normal across the
  // walls (its sides' normals weighted by length), on the caps' planes too, and are smooth where
  // the walls are; the depths, the room and the caps' faces are found on the bottom plane, so
  // that every plane gets the same layer points. A wall between two solids gets layers on both
  // sides (without them, a cylinder through boxes had triangles of 14 degrees between its fine
  // stations and the lattice, prisms below the quality floor, and the block unravelled).
  std::vector<std::vector<int>> column;  // swept: per bottom node, its repeats plane by plane
  std::vector<char> two_sided(nodes.size(), 0);
  if (sweep) {
    const int a = sweep->axis;
    Vec3 along{0, 0, 0};
    set_coord(along, a, 1.0);
    std::vector<Vec3> side_normal(swept.sides.size()), sum(nodes.size(), Vec3{0, 0, 0});
    for (std::size_t k = 0; k < swept.sides.size(); ++k) {
      const auto& side = swept.sides[k];
      side_normal[k] = (nodes[side[0]] - nodes[side[1]]).cross(along);  // the wall's, outward
      for (int end : side) sum[end] = sum[end] + side_normal[k];
    }
    std::vector<char> station(nodes.size(), 0), bent(nodes.size(), 0), outer(nodes.size(), 0);
    for (std::size_t k = 0; k < swept.sides.size(); ++k) {
      const auto& side = swept.sides[k];
      const Vec3 n = unit(side_normal[k]);
      for (int end : side) {
        station[end] = 1;
        if (n.dot(unit(sum[end])) < std::cos(25.0 * M_PI / 180)) bent[end] = 1;
        if (swept.shared[k])
          two_sided[end] = 1;
        else
          outer[end] = 1;
        // Lattice faces have no layers: one ending at a station beside one (where a fillet meets
        // a lattice face) left triangles of 11 degrees there, prisms below the quality floor.
        if (swept.on_lattice_face[k]) bent[end] = 1;
      }
    }
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (two_sided[i] && outer[i]) bent[i] = 1, two_sided[i] = 0;  // where solids meet a wall
    column.resize(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const int b = swept.base[i];
      column[b].push_back(static_cast<int>(i));
      two_sided[i] = two_sided[b];
      smooth[i] = station[b] && !bent[b];
      normal[i] = station[b] ? unit(sum[b]) : Vec3{0, 0, 0};
    }
  }
  const double layer = parameters.layer_thickness * h;
  std::vector<Vec3> inserted;      // points TetGen gets besides the surface, in frame coords
  std::vector<int> inserted_face;  // the lattice face an inserted point lies on, or -1
  PointSet layer_points(box_lo, box_hi, h);
  for (int k = 1; k <= parameters.boundary_layers; ++k)
    for (std::size_t i = 0; i < nodes.size(); ++i)
      for (const double sign : {1.0, -1.0}) {
        if (sign < 0 && !two_sided[i]) continue;
        if (!smooth[i] || normal[i].norm() == 0) continue;
        if (sweep && swept.base[i] != static_cast<int>(i)) continue;  // placed with its base
        // Depths vary by up to kLayerJitter (a fixed pseudo-random fraction per node): the sides
        // of equally deep layers are cocircular quads (rectangles, isosceles trapezoids), which
        // TetGen cuts with flat tets where the prisms on either side disagree on the diagonal.
        const double spread =
            static_cast<double>((static_cast<std::size_t>(surface.seed[i]) * 2654435761u) % 1000) /
                500.0 -
            1;
        const double depth = k * layer * (1 + kLayerJitter * spread);
        const Vec3 q = nodes[i] - normal[i] * (sign * depth);
        // Room: no other part of the surface nearer than the depth, no other point too near.
        if (curved.any_within(q, 0.9 * depth)) continue;
        if (layer_points.any_within(q, 0.3 * layer) || surface_points.any_within(q, 0.5 * depth))
          continue;
        if (sweep) {
          const int a = sweep->axis;
          std::vector<std::pair<Vec3, int>> repeats;  // the point on every plane, and its cap face
          for (int j : column[i]) {
            Vec3 r = q;
            set_coord(r, a, coord(nodes[j], a));
            const int level = static_cast<int>(std::lround(coord(r, a) / report.spacing[a]));
            int index[3] = {-1, -1, -1};
            index[a] = level;
            const int face = on_lattice_face(r, index);  // a cap it lies in, on any plane
            if (face < 0 && (level == 0 || level == cells[a])) break;  // outside: none anywhere
            repeats.emplace_back(r, face);
          }
          if (repeats.size() != column[i].size()) continue;
          for (const auto& [r, face] : repeats) {
            layer_points.add(r);
            inserted.push_back(r);
            inserted_face.push_back(face);
            ++report.nb_layer_points;
          }
          continue;
        }
        layer_points.add(q);
        inserted.push_back(q);
        inserted_face.push_back(-1);
        ++report.nb_layer_points;
      }
  clock.lap("layers");

  // Inside/outside by ray parity along frame x lines (faces between two solids do not count).
  std::vector<std::array<int, 3>> parity_tris;
  for (const SurfaceTriangle& t : surface.triangles)
    if (shape.face_solid_count[t.face] <= 1) parity_tris.push_back(t.node);
  BucketGrid yz(Vec3{box_lo.y, box_lo.z, 0}, Vec3{box_hi.y, box_hi.z, 0}, h);
  for (std::size_t i = 0; i < parity_tris.size(); ++i) {
    const auto& t = parity_tris[i];
    Vec3 a{nodes[t[0]].y, nodes[t[0]].z, 0}, b{nodes[t[1]].y, nodes[t[1]].z, 0},
        c{nodes[t[2]].y, nodes[t[2]].z, 0};
    yz.add(static_cast<int>(i), vmin(a, vmin(b, c)), vmax(a, vmax(b, c)));
  }
  // Crossings of the line {y, z} (nudged off lattice lines) with the surface, sorted by x.
  auto crossings = [&](double y, double z) {
    y += 1.234567e-7 * h, z += 2.345678e-7 * h;
    std::vector<double> xs;
    std::unordered_set<int> seen;
    yz.any_in(Vec3{y, z, 0}, Vec3{y, z, 0}, [&](int i) {
      if (!seen.insert(i).second) return false;
      const auto& t = parity_tris[i];
      const Vec3 &p0 = nodes[t[0]], &p1 = nodes[t[1]], &p2 = nodes[t[2]];
      double u, v;
      if (!coordinates_across(Vec3{0, y, z}, p0, p1, p2, 0, u, v)) return false;
      if (u < 0 || v < 0 || u + v > 1) return false;
      xs.push_back(p0.x + u * (p1.x - p0.x) + v * (p2.x - p0.x));
      return false;
    });
    std::sort(xs.begin(), xs.end());
    return xs;
  };
  auto inside_given = [](const std::vector<double>& xs, double x) {
    return (std::lower_bound(xs.begin(), xs.end(), x) - xs.begin()) % 2 == 1;
  };
  auto inside = [&](const Vec3& q) { return inside_given(crossings(q.y, q.z), q.x); };

  // Lattice points: kept when inside (or on a lattice face) and far enough from the other faces.
  const int n0 = cells[0] + 1, n1 = cells[1] + 1, n2 = cells[2] + 1;
  auto point_index = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * n1 + j) * n0 + i;
  };
  auto lattice_point = [&](int i, int j, int k) {
    return Vec3{i * report.spacing[0], j * report.spacing[1], k * report.spacing[2]};
  };
  const double keep_distance =
      (parameters.boundary_layers * parameters.layer_thickness + parameters.lattice_margin) * h;
  std::vector<char> kept(static_cast<std::size_t>(n0) * n1 * n2, 0);
  std::vector<int> kept_face(kept.size(), -1);
  for (int k = 0; k < n2; ++k)
    for (int j = 0; j < n1; ++j) {
      const std::vector<double> xs = crossings(j * report.spacing[1], k * report.spacing[2]);
      for (int i = 0; i < n0; ++i) {
        const Vec3 q = lattice_point(i, j, k);
        const int index[3] = {i, j, k};
        const int face = on_lattice_face(q, index);
        if (face < 0 && !inside_given(xs, q.x)) continue;
        if (curved.any_within(q, keep_distance)) continue;
        if (layer_points.any_within(q, parameters.lattice_margin * h)) continue;
        kept[point_index(i, j, k)] = 1;
        kept_face[point_index(i, j, k)] = face;
      }
    }
  clock.lap("lattice");

  // The hexahedral core: cells with 8 kept corners whose circumsphere holds nothing else; then
  // every quad face between the core and another cell inside needs a closing pyramid whose apex
  // is that cell's centre and whose circumsphere holds nothing else, or the core cell goes.
  const int c0 = cells[0], c1 = cells[1], c2 = cells[2];
  auto cell_index = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * c1 + j) * c0 + i;
  };
  // The cell across face dir (0..5: -x, +x, -y, +y, -z, +z) of cell (i, j, k), in n; whether it
  // is in the lattice.
  auto across = [&](int i, int j, int k, int dir, int(&n)[3]) {
    n[0] = i, n[1] = j, n[2] = k;
    n[dir / 2] += dir % 2 ? 1 : -1;
    return n[0] >= 0 && n[0] < c0 && n[1] >= 0 && n[1] < c1 && n[2] >= 0 && n[2] < c2;
  };
  auto cell_centre = [&](int i, int j, int k) {
    return Vec3{(i + 0.5) * report.spacing[0], (j + 0.5) * report.spacing[1],
                (k + 0.5) * report.spacing[2]};
  };
  const double half_diagonal = 0.5 * std::sqrt(report.spacing[0] * report.spacing[0] +
                                               report.spacing[1] * report.spacing[1] +
                                               report.spacing[2] * report.spacing[2]);
  auto ball_is_empty = [&](const Vec3& centre, double r) {
    const double inner = r * (1 - 1e-9);
    return !curved.any_within(centre, inner) && !surface_points.any_within(centre, inner) &&
           !layer_points.any_within(centre, inner);
  };
  std::vector<char> core(static_cast<std::size_t>(c0) * c1 * c2, 0);
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        bool all = true;
        for (int corner = 0; corner < 8 && all; ++corner)
          all =
              kept[point_index(i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1))];
        if (!all) continue;
        const Vec3 centre = cell_centre(i, j, k);
        if (!inside(centre) || !ball_is_empty(centre, half_diagonal)) continue;
        core[cell_index(i, j, k)] = 1;
      }
  // Per directed face (cell, direction 0..5): 0 unknown, 1 boundary (no pyramid needed),
  // 2 pyramid possible, 3 impossible.
  std::vector<std::uint8_t> face_state(core.size() * 6, 0);
  auto face_kind = [&](int i, int j, int k, int dir) -> std::uint8_t {
    std::uint8_t& state = face_state[cell_index(i, j, k) * 6 + dir];
    if (state) return state;
    const int axis = dir / 2, side = dir % 2 ? 1 : -1;
    // Swept: the prisms and hexahedra of the slab close the core's sides.
    if (sweep && axis != sweep->axis) return state = 1;
    int n[3];
    const bool in_range = across(i, j, k, dir, n);
    const Vec3 face_centre =
        cell_centre(i, j, k) + Vec3{axis == 0 ? side * 0.5 * report.spacing[0] : 0,
                                    axis == 1 ? side * 0.5 * report.spacing[1] : 0,
                                    axis == 2 ? side * 0.5 * report.spacing[2] : 0};
    const Vec3 apex = in_range ? cell_centre(n[0], n[1], n[2]) : face_centre;
    if (!in_range || !inside(apex)) return state = 1;
    // The sphere through the face's corners and the apex.
    const double a = 0.5 * report.spacing[axis];
    double rho2 = 0;
    for (int b = 0; b < 3; ++b)
      if (b != axis) rho2 += 0.25 * report.spacing[b] * report.spacing[b];
    const double c = (a * a - rho2) / (2 * a);
    const Vec3 towards = apex - face_centre;
    const Vec3 centre = face_centre + towards * (c / a);
    const double r = a - c;
    const bool ok = ball_is_empty(centre, r) && !surface_points.any_within(apex, 0.25 * h) &&
                    !layer_points.any_within(apex, 0.25 * h);
    return state = ok ? 2 : 3;
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (int k = 0; k < c2; ++k)
      for (int j = 0; j < c1; ++j)
        for (int i = 0; i < c0; ++i) {
          if (!core[cell_index(i, j, k)]) continue;
          for (int dir = 0; dir < 6; ++dir) {
            int n[3];
            if (across(i, j, k, dir, n) && core[cell_index(n[0], n[1], n[2])]) continue;
            if (face_kind(i, j, k, dir) == 3) {
              core[cell_index(i, j, k)] = 0;
              changed = true;
              break;
            }
          }
        }
  }
  std::vector<char> apex_cell(core.size(), 0);
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        if (!core[cell_index(i, j, k)]) continue;
        ++report.nb_core_cells;
        for (int dir = 0; dir < 6; ++dir) {
          int n[3];
          if (!across(i, j, k, dir, n) || core[cell_index(n[0], n[1], n[2])]) continue;
          if (face_kind(i, j, k, dir) == 2) apex_cell[cell_index(n[0], n[1], n[2])] = 1;
        }
      }
  for (int k = 0; k < n2; ++k)
    for (int j = 0; j < n1; ++j)
      for (int i = 0; i < n0; ++i) {
        if (!kept[point_index(i, j, k)]) continue;
        const Vec3 q = lattice_point(i, j, k);
        if (surface_points.any_within(q, 1e-6 * h)) continue;  // already a surface node
        inserted.push_back(q);
        inserted_face.push_back(kept_face[point_index(i, j, k)]);
        ++report.nb_lattice_points;
      }
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i)
        if (apex_cell[cell_index(i, j, k)]) {
          inserted.push_back(cell_centre(i, j, k));
          inserted_face.push_back(-1);
          ++report.nb_apex_points;
        }
  // The points on lattice faces first: they go to TetGen with the surface, in its facets.
  {
    std::vector<std::size_t> order(inserted.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_partition(order.begin(), order.end(),
                          [&](std::size_t i) { return inserted_face[i] >= 0; });
    std::vector<Vec3> points(order.size());
    std::vector<int> faces(order.size());
    for (std::size_t i = 0; i < order.size(); ++i)
      points[i] = inserted[order[i]], faces[i] = inserted_face[order[i]];
    inserted.swap(points);
    inserted_face.swap(faces);
  }
  const auto nb_on_faces = static_cast<std::size_t>(
      std::count_if(inserted_face.begin(), inserted_face.end(), [](int f) { return f >= 0; }));
  clock.lap("core");

  // TetGen: the surface kept as it is (-pY), the lattice faces with their lattice points, the
  // other points as isolated vertices of the PLC, 0-based (-z), quiet (-Q). Given to -i instead,
  // TetGen 1.5 inserted them after the boundary recovery and left non-Delaunay tets in the
  // degenerate (cospherical) lattice: a closing pyramid's apex joined to the far corner of the
  // core cell behind it (bracket h 1.40: two core faces without closer, 89.5 % hex volume).
  WorkDirectory work(parameters.work_directory);
  const fs::path poly = work.path() / "shape.poly";
  std::vector<Facet> facets = make_facets(surface, nodes, lattice_face, face_plane);
  {
    std::vector<Vec3> face_points = nodes;
    face_points.insert(face_points.end(), inserted.begin(), inserted.begin() + nb_on_faces);
    add_face_points(facets, face_points, nodes.size(), lattice_face, face_plane, 1e-7 * h);
  }
  auto write_poly = [&] {
    std::ofstream out(poly);
    out.precision(17);
    out << nodes.size() + inserted.size() << " 3 0 0\n";
    for (std::size_t i = 0; i < nodes.size() + inserted.size(); ++i) {
      const Vec3& p = i < nodes.size() ? nodes[i] : inserted[i - nodes.size()];
      out << i << ' ' << p.x << ' ' << p.y << ' ' << p.z << '\n';
    }
    out << facets.size() << " 1\n";
    for (const Facet& f : facets) {
      out << f.polygons.size() << ' ' << f.holes.size() << ' ' << f.marker << '\n';
      for (const auto& polygon : f.polygons) {
        out << polygon.size();
        for (int v : polygon) out << ' ' << v;
        out << '\n';
      }
      for (std::size_t i = 0; i < f.holes.size(); ++i)
        out << i + 1 << ' ' << f.holes[i].x << ' ' << f.holes[i].y << ' ' << f.holes[i].z << '\n';
    }
    out << "0\n0\n";
    if (!out) throw InputError("cannot write TetGen's input in " + work.path().string());
  };
  write_poly();
  const fs::path log = work.path() / "tetgen.log";
  report.tetgen_command = shell_quote(tetgen) + " -pYzQ " + shell_quote(poly.string());
  const std::size_t given = nodes.size() + inserted.size();
  std::vector<double> frame_points;
  // TetGen 1.5 can fail to triangulate a lattice face from its loops: it never ends, or leaves
  // the face with a gap and every tet counted as outside. Nearly collinear loop nodes did it
  // (align_straight_edges() now prevents that), and whether it happened depended on the vertex
  // the loop started at. So TetGen runs under a time limit, far above its own time (about 1 s
  // per 20k points), and after a failure the loops start elsewhere.
  const double time_limit = parameters.tetgen_time_limit > 0
                                ? parameters.tetgen_time_limit
                                : 30 + 1e-3 * static_cast<double>(nodes.size() + inserted.size());
  std::ostringstream limit_text;
  limit_text << time_limit;
  const std::string limited = "timeout -k 5 " + limit_text.str() + " ";
  int restarts = 0;
  for (bool nudged = false;;) {
    const int status = std::system(
        (limited + report.tetgen_command + " > " + shell_quote(log.string()) + " 2>&1").c_str());
    const bool timed_out = WIFEXITED(status) && WEXITSTATUS(status) == 124;
    if (timed_out || (status == 0 && !fs::exists(work.path() / "shape.1.ele"))) {
      if (++restarts > kTetgenRestarts)
        throw InputError(std::string("TetGen ") +
                         (timed_out ? "did not finish within " + limit_text.str() + " s"
                                    : "lost the shape's surface (no tets inside)") +
                         ", " + std::to_string(restarts) +
                         " times with the lattice faces' loops started at other vertices; try "
                         "another size\n(command: " +
                         report.tetgen_command + ")");
      for (Facet& facet : facets)
        for (auto& polygon : facet.polygons)
          if (polygon.size() > 3)
            std::rotate(
                polygon.begin(),
                polygon.begin() + static_cast<std::ptrdiff_t>(
                                      (7919u * static_cast<unsigned>(restarts)) % polygon.size()),
                polygon.end());
      ++report.nb_tetgen_restarts;
      write_poly();
      continue;
    }
    if (status != 0 || !fs::exists(work.path() / "shape.1.ele"))
      throw InputError("TetGen failed (exit status " + std::to_string(status) +
                       ") on the shape's surface "
                       "and points; its output:\n" +
                       tail_of_file(log, 2000) + "\n(command: " + report.tetgen_command + ")");
    frame_points = read_tetgen_table<double>(work.path() / "shape.1.node", 3, 3);
    // TetGen now and then leaves a point of the regular lattice out (degenerate: all
    // cospherical): missing from its .node (which breaks the numbering) or in no tet. The points
    // left out move by 1e-7 h (they stay on the lattice for everything below) and TetGen runs
    // once more.
    std::vector<std::size_t> dropped;
    if (frame_points.size() / 3 >= given) {
      std::vector<char> used(given, 0);
      for (long long v : read_tetgen_table<long long>(work.path() / "shape.1.ele", 4, 4))
        if (v >= 0 && v < static_cast<long long>(given)) used[v] = 1;
      for (std::size_t i = 0; i < given; ++i)
        if (!used[i]) dropped.push_back(i);
      if (dropped.empty()) break;
    } else {
      // Found by their coordinates: TetGen keeps the others in order.
      for (std::size_t i = 0, j = 0; i < given; ++i) {
        const Vec3 p = i < nodes.size() ? nodes[i] : inserted[i - nodes.size()];
        if (j < frame_points.size() / 3 && (Vec3::of(&frame_points[3 * j]) - p).norm() <= 1e-9 * h)
          ++j;
        else
          dropped.push_back(i);
      }
    }
    std::string which;
    for (std::size_t i : dropped) {
      const Vec3 p = frame.to_world(i < nodes.size() ? nodes[i] : inserted[i - nodes.size()]);
      which += " " + std::to_string(i) + " at (" + std::to_string(p.x) + ", " +
               std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
    }
    if (nudged || dropped.empty() || dropped.front() < nodes.size() + nb_on_faces)
      throw InputError("TetGen dropped " + std::to_string(dropped.size()) +
                       " of the points given (points too close together or not insertable):" +
                       which + "; try another size\n(command: " + report.tetgen_command + ")");
    for (std::size_t i : dropped)
      inserted[i - nodes.size()] = inserted[i - nodes.size()] + Vec3{1.0, 0.7, 0.3} * (1e-7 * h);
    report.nb_nudged_points += dropped.size();
    nudged = true;
    write_poly();
  }
  clock.lap("tetgen");

  TetMesh mesh;
  for (long long v : read_tetgen_table<long long>(work.path() / "shape.1.ele", 4, 4)) {
    if (v < 0 || v >= static_cast<long long>(frame_points.size() / 3))
      throw InputError("TetGen's shape.1.ele refers to a missing node");
    mesh.tets.push_back(static_cast<index_t>(v));
  }
  const std::size_t made = frame_points.size() / 3;
  report.nb_steiner_points = made > given ? made - given : 0;
  // Orientation: positive volume in frame coordinates is positive in the world (proper frame).
  for (std::size_t t = 0; t < mesh.tets.size() / 4; ++t) {
    index_t* v = &mesh.tets[4 * t];
    const Vec3 p0 = Vec3::of(&frame_points[3 * v[0]]);
    const double d =
        det3(Vec3::of(&frame_points[3 * v[1]]) - p0, Vec3::of(&frame_points[3 * v[2]]) - p0,
             Vec3::of(&frame_points[3 * v[3]]) - p0);
    if (d < 0) std::swap(v[1], v[2]);
  }
  mesh.points.resize(frame_points.size());
  for (std::size_t i = 0; i < made; ++i) {
    const Vec3 p = frame.to_world(Vec3::of(&frame_points[3 * i]));
    mesh.points[3 * i] = p.x, mesh.points[3 * i + 1] = p.y, mesh.points[3 * i + 2] = p.z;
  }
  // The surface nodes keep their exact CAD positions.
  for (std::size_t i = 0; i < nodes.size() && i < made; ++i) {
    mesh.points[3 * i] = surface.nodes[i].x, mesh.points[3 * i + 1] = surface.nodes[i].y,
                    mesh.points[3 * i + 2] = surface.nodes[i].z;
  }
  if (shape.solids.Extent() > 1)
    mesh.regions = regions_by_solid(brep, mesh);
  else
    mesh.regions.assign(mesh.tets.size() / 4, 0);
  clock.lap("regions");

  // TetGen leaves slivers where the lattice meets the boundary layers and the surface (four
  // nearly cocircular points, as the sides of the layers' prisms are): flips take them out, then
  // the free nodes (boundary-layer and Steiner points, inside) move to raise the worst tet around
  // them, then flips again, for kQualityRounds rounds. The lattice's own tets, in one cell or one
  // closing pyramid, stay for the hexahedra, and lattice points and cell centres do not move.
  {
    // Per vertex: whether it is a lattice point or a cell centre, and its coordinates in cells.
    std::vector<char> half_lattice(made, 1);
    std::vector<std::array<double, 3>> cell_of(made);
    for (std::size_t v = 0; v < made; ++v)
      for (int a = 0; a < 3; ++a) {
        cell_of[v][a] = frame_points[3 * v + a] / report.spacing[a];
        if (std::abs(2 * cell_of[v][a] - std::round(2 * cell_of[v][a])) > 1e-6) half_lattice[v] = 0;
      }
    // Whether tet t lies in one lattice cell or one closing pyramid (all its corners on the half
    // lattice, within one cell's width along each axis).
    auto in_one_cell = [&](index_t t) {
      double least[3] = {1e300, 1e300, 1e300}, most[3] = {-1e300, -1e300, -1e300};
      for (int k = 0; k < 4; ++k) {
        const index_t v = mesh.tet(t)[k];
        if (!half_lattice[v]) return false;
        for (int a = 0; a < 3; ++a) {
          least[a] = std::min(least[a], cell_of[v][a]), most[a] = std::max(most[a], cell_of[v][a]);
          if (most[a] - least[a] >= 1 + 1e-6) return false;
        }
      }
      return true;
    };
    // Swept: whether tet t lies between two consecutive lattice planes (its prism or hexahedron
    // stays as TetGen made it).
    auto in_one_slab = [&](index_t t) {
      if (!sweep) return false;
      double least = 1e300, most = -1e300;
      for (int k = 0; k < 4; ++k) {
        const double level = cell_of[mesh.tet(t)[k]][sweep->axis];
        least = std::min(least, level), most = std::max(most, level);
      }
      return most - least <= 1 + 1e-6;
    };
    // The CAD face of each boundary face, from TetGen's markers (face index + 1), so that
    // triangles of one planar face may swap their shared sides.
    std::map<std::array<index_t, 3>, std::int32_t> face_marker;
    const std::vector<long long> faces =
        read_tetgen_table<long long>(work.path() / "shape.1.face", 1, 4);
    std::vector<char> movable(made, 0);
    for (std::size_t v = nodes.size(); v < made; ++v) movable[v] = !sweep && !half_lattice[v];
    for (std::size_t i = 0; i + 3 < faces.size(); i += 4) {
      std::array<index_t, 3> key{static_cast<index_t>(faces[i]), static_cast<index_t>(faces[i + 1]),
                                 static_cast<index_t>(faces[i + 2])};
      for (index_t v : key) movable[v] = 0;
      std::sort(key.begin(), key.end());
      face_marker[key] = static_cast<std::int32_t>(faces[i + 3]) - 1;
    }
    for (int round = 0; round < kQualityRounds; ++round) {
      std::vector<char> fixed(mesh.nb_tets(), 0);
      for (index_t t = 0; t < mesh.nb_tets(); ++t) fixed[t] = in_one_cell(t) || in_one_slab(t);
      // Boundary faces swapped by an earlier round are not in face_marker: they stay (-1).
      std::vector<std::int32_t> boundary_patch(4 * static_cast<std::size_t>(mesh.nb_tets()), -1);
      for (index_t t = 0; t < mesh.nb_tets(); ++t)
        for (int f = 0; f < 4; ++f) {
          const index_t* v = mesh.tet(t);
          std::array<index_t, 3> key{v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]};
          std::sort(key.begin(), key.end());
          const auto it = face_marker.find(key);
          if (it != face_marker.end())
            boundary_patch[4 * static_cast<std::size_t>(t) + f] = it->second;
        }
      RemoveSliversReport flips;
      // Boundary triangles of one face may swap their side where the boundary moves by no more
      // than the surface's chord deflection (a flat tet on two triangles across a seam).
      RemoveSliversParameters flip_parameters;
      flip_parameters.max_boundary_shift = deflection;
      remove_slivers(mesh, fixed, boundary_patch, flip_parameters, flips);
      if (round == 0) report.min_tet_quality_before = flips.min_before;
      report.nb_face_flips += flips.face_removals;
      report.nb_edge_flips += flips.edge_removals;
      report.nb_boundary_swaps += flips.boundary_swaps;
      if (round + 1 == kQualityRounds) break;
      SmoothNodesReport moves;
      smooth_nodes(mesh, movable, SmoothNodesParameters{}, moves);
      report.nb_node_moves += moves.moves;
      if (moves.moves == 0) break;
    }
  }
  clock.lap("slivers");
  validate_tet_mesh(mesh);

  // How far the boundary nodes are from the CAD faces they lie on.
  {
    // Face f of a tet is the one opposite its vertex f (TetTopology).
    const TetTopology topology(mesh);
    std::vector<char> boundary(made, 0);
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      for (int f = 0; f < 4; ++f)
        if (topology.on_boundary(t, f))
          for (int k = 0; k < 4; ++k)
            if (k != f) boundary[mesh.tet(t)[k]] = 1;
    std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(shape.faces.Extent());
    double worst = 0;
    for (std::size_t v = 0; v < made; ++v) {
      if (!boundary[v]) continue;
      int face = -1;
      if (v < nodes.size())
        face = surface.node_face[v];
      else if (v < given)
        face = inserted_face[v - nodes.size()];
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
      analysis[face]->ValueOfUV(p, 1e-6 * h);
      worst = std::max(worst, analysis[face]->Gap());
    }
    report.max_boundary_distance = worst;
  }
  clock.lap("check");
  return mesh;
}

}  // namespace hexmerge
