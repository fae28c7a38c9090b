#include "hexmerge/occ/mesher/surface.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_OBB.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Surface.hxx>
#include <Poly_PolygonOnTriangulation.hxx>
#include <Poly_Triangulation.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <ShapeCustom.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface_check.h"
#include "hexmerge/occ/mesher/surface_mend.h"
#include "hexmerge/occ/mesher/surface_unfold.h"

namespace hexmerge::mesher {
namespace {
// The angle at v between the sides to a and b.
double angle_at(const Vec3& v, const Vec3& a, const Vec3& b) {
  const Vec3 x = a - v, y = b - v;
  return std::atan2(x.cross(y).norm(), x.dot(y));
}
}  // namespace

double angle_at(const std::vector<Vec3>& nodes, int v, int a, int b) {
  return angle_at(nodes[v], nodes[a], nodes[b]);
}
Vec3 normal_of(const std::vector<Vec3>& nodes, int a, int b, int c) {
  return (nodes[b] - nodes[a]).cross(nodes[c] - nodes[a]);
}
double enclosed_volume(const std::vector<Vec3>& nodes,
                       const std::vector<SurfaceTriangle>& triangles,
                       const std::vector<int>& face_solid_count) {
  double volume = 0;
  for (const SurfaceTriangle& t : triangles)
    if (face_solid_count[static_cast<std::size_t>(t.face)] == 1)
      volume += nodes[t.node[0]].dot(nodes[t.node[1]].cross(nodes[t.node[2]])) / 6;
  return volume;
}

double smallest_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::min({angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
}
double smallest_angle(const std::vector<Vec3>& nodes, const std::array<int, 3>& v) {
  return smallest_angle(nodes[v[0]], nodes[v[1]], nodes[v[2]]);
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
    on_edge[pair_lo(key)] = on_edge[pair_hi(key)] = 1;
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

namespace {

// The triangles of faces that bound no area (a line on the axis of a revolution makes one: all
// its nodes on the axis). They are flat, overlap their own sides, and TetGen refuses them
// ("two segments intersect"); the faces around meet at the axis without them.
void remove_faces_without_area(Surface& surface) {
  std::map<int, double> area, longest;
  for (const SurfaceTriangle& t : surface.triangles) {
    const Vec3 &a = surface.nodes[t.node[0]], &b = surface.nodes[t.node[1]],
               &c = surface.nodes[t.node[2]];
    area[t.face] += 0.5 * (b - a).cross(c - a).norm();
    longest[t.face] = std::max({longest[t.face], (b - a).norm(), (c - b).norm(), (a - c).norm()});
  }
  std::vector<SurfaceTriangle> kept;
  kept.reserve(surface.triangles.size());
  for (const SurfaceTriangle& t : surface.triangles)
    if (area[t.face] > 1e-12 * longest[t.face] * longest[t.face]) kept.push_back(t);
  surface.triangles.swap(kept);
}

// Triangles on the same three nodes (faces of the CAD that coincide over a patch, or nodes of
// two faces merged within the tolerance): a pair facing opposite ways bounds no volume and both
// go; of triangles facing the same way one stays. TetGen refuses such duplicated facets.
void remove_coincident_triangles(Surface& surface) {
  std::map<std::array<int, 3>, std::vector<std::size_t>> by_nodes;
  for (std::size_t i = 0; i < surface.triangles.size(); ++i) {
    std::array<int, 3> key = surface.triangles[i].node;
    std::sort(key.begin(), key.end());
    by_nodes[key].push_back(i);
  }
  std::vector<char> drop(surface.triangles.size(), 0);
  // Whether triangles a and b run their nodes the same way round.
  const auto same_way = [&](std::size_t a, std::size_t b) {
    const auto& u = surface.triangles[a].node;
    const auto& v = surface.triangles[b].node;
    for (int r = 0; r < 3; ++r)
      if (u[0] == v[r] && u[1] == v[(r + 1) % 3]) return true;
    return false;
  };
  for (const auto& [key, list] : by_nodes) {
    if (list.size() < 2) continue;
    std::vector<std::size_t> left(list);
    while (left.size() >= 2) {  // take out opposite pairs
      bool paired = false;
      for (std::size_t j = 1; j < left.size() && !paired; ++j)
        if (!same_way(left[0], left[j])) {
          drop[left[0]] = drop[left[j]] = 1;
          left.erase(left.begin() + static_cast<std::ptrdiff_t>(j));
          left.erase(left.begin());
          paired = true;
        }
      if (!paired) break;
    }
    for (std::size_t j = 1; j < left.size(); ++j) drop[left[j]] = 1;  // the same way: one stays
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < surface.triangles.size(); ++i)
    if (!drop[i]) surface.triangles[kept++] = surface.triangles[i];
  surface.triangles.resize(kept);
}

// A triangle whose third node is within this fraction of its longest side from that side, or
// within the nodes' merging tolerance, is flat (an angle under 1e-4 degrees): a STEP file's
// coordinates in single precision put collinear nodes 5e-7 apart on a side of 1.2.
constexpr double kFlatTriangle = 1e-6;
// Rounds of remove_flat_triangles(): a split can bring the next flat triangle of a run along one
// line across a new side (FreeCAD's SOT404.stp has runs of two on a face). Flat triangles left
// after them stay as they are (not counted in nb_flat_triangles).
constexpr int kFlatTriangleRounds = 8;

// Triangles whose three nodes lie on one line (kFlatTriangle): BRepMesh closes so a
// face whose outline runs twice along one line (FreeCAD's SOT404.stp: a wall below a tab whose
// outline passes along the tab's top edge and back), and the face across that line has one
// side where the flat triangle has two (its third node lies on the side, not on the face's
// loop). TetGen fills such a place with tets of no volume (scaled Jacobian 1e-6). The flat
// triangle goes, and the triangle across its longest side is split at its third node, so that
// every side stays between two triangles; a CAD edge's segment split so takes the parameter
// at the node. Returns how many went.
std::size_t remove_flat_triangles(Surface& surface, double tolerance) {
  std::size_t removed = 0;
  for (int round = 0; round < kFlatTriangleRounds; ++round) {
    std::unordered_map<std::uint64_t, std::vector<std::size_t>> by_side;
    for (std::size_t i = 0; i < surface.triangles.size(); ++i)
      for (int c = 0; c < 3; ++c) by_side[side_key(surface.triangles[i], c)].push_back(i);
    std::vector<char> drop(surface.triangles.size(), 0), touched(surface.triangles.size(), 0);
    std::vector<SurfaceTriangle> added;
    std::size_t this_round = 0;
    for (std::size_t i = 0; i < surface.triangles.size(); ++i) {
      const SurfaceTriangle& flat = surface.triangles[i];
      if (touched[i]) continue;
      // The longest side (a, b) and the node v across it, within the tolerance of the side.
      int c = 0;
      double longest = -1;
      for (int k = 0; k < 3; ++k) {
        const double l =
            (surface.nodes[flat.node[(k + 1) % 3]] - surface.nodes[flat.node[k]]).norm();
        if (l > longest) longest = l, c = k;
      }
      const int a = flat.node[c], b = flat.node[(c + 1) % 3], v = flat.node[(c + 2) % 3];
      const Vec3 &pa = surface.nodes[a], &pb = surface.nodes[b], &pv = surface.nodes[v];
      const Vec3 ab = pb - pa;
      const double along = (pv - pa).dot(ab) / ab.dot(ab);
      if (along <= 0 || along >= 1 ||
          (pa + ab * along - pv).norm() > std::max(tolerance, kFlatTriangle * longest))
        continue;
      const auto it = by_side.find(pair_key(a, b));
      if (it == by_side.end() || it->second.size() != 2) continue;
      const std::size_t j = it->second[0] == i ? it->second[1] : it->second[0];
      if (touched[j]) continue;
      const SurfaceTriangle& across = surface.triangles[j];
      if (std::find(across.node.begin(), across.node.end(), v) != across.node.end()) continue;
      // Split `across` at v, its nodes in their order: (p, v, r) and (v, q, r) for its side
      // (p, q) = {a, b}.
      const int k = side_with_key(across, pair_key(a, b));
      const int p = across.node[k], q = across.node[(k + 1) % 3], r = across.node[(k + 2) % 3];
      const double at_p = p == a ? along : 1 - along;  // v's place from p towards q
      const UV uv_v{across.uv[k].u + at_p * (across.uv[(k + 1) % 3].u - across.uv[k].u),
                    across.uv[k].v + at_p * (across.uv[(k + 1) % 3].v - across.uv[k].v)};
      SurfaceTriangle first = across, second = across;
      first.node = {p, v, r}, first.uv = {across.uv[k], uv_v, across.uv[(k + 2) % 3]};
      second.node = {v, q, r}, second.uv = {uv_v, across.uv[(k + 1) % 3], across.uv[(k + 2) % 3]};
      added.push_back(first), added.push_back(second);
      drop[i] = drop[j] = 1;
      for (const std::size_t t : {i, j})
        for (int s = 0; s < 3; ++s)
          for (const std::size_t n : by_side[side_key(surface.triangles[t], s)]) touched[n] = 1;
      // The CAD edge's segment (a, b), if any, becomes (a, v) and (v, b) where those are none.
      const auto seg = surface.segments.find(pair_key(a, b));
      if (seg != surface.segments.end()) {
        const EdgeSegment whole = seg->second;
        surface.segments.erase(seg);
        const double t_a = a < b ? whole.t_lo : whole.t_hi, t_b = a < b ? whole.t_hi : whole.t_lo;
        const double t_v = t_a + along * (t_b - t_a);
        for (const auto& [x, t_x] : {std::pair<int, double>{a, t_a}, {b, t_b}})
          if (!surface.segments.count(pair_key(x, v)))
            surface.segments[pair_key(x, v)] =
                x < v ? EdgeSegment{whole.edge, t_x, t_v} : EdgeSegment{whole.edge, t_v, t_x};
      }
      ++this_round;
    }
    if (this_round == 0) break;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < surface.triangles.size(); ++i)
      if (!drop[i]) surface.triangles[kept++] = surface.triangles[i];
    surface.triangles.resize(kept);
    surface.triangles.insert(surface.triangles.end(), added.begin(), added.end());
    removed += this_round;
  }
  return removed;
}

}  // namespace

void drop_unused_nodes(Surface& surface) {
  std::vector<int> renumber(surface.nodes.size(), -1);
  for (const SurfaceTriangle& t : surface.triangles)
    for (int n : t.node) renumber[n] = 0;
  int next = 0;
  for (std::size_t n = 0; n < renumber.size(); ++n)
    if (renumber[n] == 0) {
      renumber[n] = next;
      surface.nodes[next] = surface.nodes[n];
      surface.node_face[next] = surface.node_face[n];
      ++next;
    }
  if (next == static_cast<int>(renumber.size())) return;
  if (!surface.seed.empty()) {
    for (std::size_t n = 0; n < renumber.size(); ++n)
      if (renumber[n] >= 0) surface.seed[static_cast<std::size_t>(renumber[n])] = surface.seed[n];
    surface.seed.resize(next);
  }
  surface.nodes.resize(next);
  surface.node_face.resize(next);
  for (SurfaceTriangle& t : surface.triangles)
    for (int& n : t.node) n = renumber[n];
  std::unordered_map<std::uint64_t, EdgeSegment> segments;
  for (const auto& [key, segment] : surface.segments) {
    const int a = renumber[pair_lo(key)], b = renumber[pair_hi(key)];
    if (a >= 0 && b >= 0) segments[pair_key(a, b)] = segment;
  }
  surface.segments = std::move(segments);
}

void remove_folds(Surface& surface, double tolerance) {
  // Nodes within the tolerance of another become one (NodeMerger, as in triangulate()); a
  // merged node keeps the seed of the first of its nodes.
  Surface merged;
  NodeMerger merger(merged, tolerance);
  std::vector<int> to(surface.nodes.size());
  for (std::size_t v = 0; v < surface.nodes.size(); ++v)
    to[v] = merger.id(surface.nodes[v], surface.node_face[v]);
  if (merged.nodes.size() < surface.nodes.size()) {
    if (!surface.seed.empty()) {
      merged.seed.assign(merged.nodes.size(), -1);
      for (std::size_t v = 0; v < surface.nodes.size(); ++v)
        if (merged.seed[static_cast<std::size_t>(to[v])] < 0)
          merged.seed[static_cast<std::size_t>(to[v])] = surface.seed[v];
    }
    std::vector<SurfaceTriangle> kept;
    kept.reserve(surface.triangles.size());
    for (SurfaceTriangle t : surface.triangles) {
      for (int& v : t.node) v = to[static_cast<std::size_t>(v)];
      if (t.node[0] != t.node[1] && t.node[1] != t.node[2] && t.node[0] != t.node[2])
        kept.push_back(t);
    }
    surface.triangles.swap(kept);
    std::unordered_map<std::uint64_t, EdgeSegment> segments;
    for (const auto& [key, segment] : surface.segments) {
      const int a = to[pair_lo(key)], b = to[pair_hi(key)];
      if (a != b) segments[pair_key(a, b)] = segment;
    }
    surface.segments = std::move(segments);
    surface.nodes = std::move(merged.nodes);
    surface.node_face = std::move(merged.node_face);
    surface.seed = std::move(merged.seed);
  }
  remove_coincident_triangles(surface);
  drop_unused_nodes(surface);
}

std::vector<double> face_spans(const Shape& s, const std::vector<double>& face_width,
                               double below) {
  std::vector<double> span(static_cast<std::size_t>(s.faces.Extent()),
                           std::numeric_limits<double>::infinity());
  for (int f = 1; f <= s.faces.Extent(); ++f) {
    if (!(face_width[static_cast<std::size_t>(f - 1)] < below)) continue;
    Bnd_OBB box;
    BRepBndLib::AddOBB(s.faces(f), box, /*theIsTriangulationUsed=*/false,
                       /*theIsOptimal=*/false, /*theIsShapeToleranceUsed=*/false);
    if (box.IsVoid()) continue;  // no points to measure: no limit
    std::array<double, 3> sides = {box.XHSize(), box.YHSize(), box.ZHSize()};
    std::sort(sides.begin(), sides.end());
    span[static_cast<std::size_t>(f - 1)] = 2 * sides[1];
  }
  return span;
}

std::size_t merge_narrow_faces(Surface& surface, const Shape& s,
                               const std::vector<double>& face_width, double width) {
  if (!(width > 0) || surface.nodes.empty()) return 0;
  std::vector<char> narrow(face_width.size(), 0);
  for (std::size_t f = 0; f < face_width.size(); ++f) narrow[f] = face_width[f] < width;
  if (std::find(narrow.begin(), narrow.end(), 1) == narrow.end()) return 0;
  std::vector<char> on_narrow(surface.nodes.size(), 0);
  std::size_t faces = 0;
  std::vector<char> counted(narrow.size(), 0);
  for (const SurfaceTriangle& t : surface.triangles)
    if (narrow[static_cast<std::size_t>(t.face)]) {
      for (const int n : t.node) on_narrow[static_cast<std::size_t>(n)] = 1;
      faces += !counted[static_cast<std::size_t>(t.face)];
      counted[static_cast<std::size_t>(t.face)] = 1;
    }
  NodeHash hash(surface.nodes, width);
  for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) hash.add(n);
  std::vector<int> root(surface.nodes.size());
  for (std::size_t v = 0; v < root.size(); ++v) root[v] = static_cast<int>(v);
  const auto find = [&](int v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) {
    if (!on_narrow[static_cast<std::size_t>(n)]) continue;
    hash.for_each_within(surface.nodes[n], width, [&](int m) {
      const int a = find(n), b = find(m);
      if (a != b) root[std::max(a, b)] = std::min(a, b);
    });
  }
  Surface merged = surface;
  for (std::size_t v = 0; v < root.size(); ++v)
    merged.nodes[v] = surface.nodes[static_cast<std::size_t>(find(static_cast<int>(v)))];
  remove_folds(merged, 1e-9 * width);
  if (!find_overused_sides(merged, s.face_solids, s.edge_faces).empty() ||
      !faces_with_open_sides(merged).empty())
    return 0;
  surface = std::move(merged);
  return faces;
}

namespace {

// The faces of `shape` (numbered as in `faces`) BRepMesh left without triangles, after meshing
// it afresh, or whose triangles all collapse (triangulation_collapsed()).
std::vector<int> faces_not_triangulated(const TopoDS_Shape& shape,
                                        const TopTools_IndexedMapOfShape& faces, double deflection,
                                        double tolerance) {
  try {
    // A triangulation left in the shape by an earlier call (another attempt, another size) would
    // be kept where it meets the deflection: each call starts from none.
    BRepTools::Clean(shape);
    BRepMesh_IncrementalMesh mesher(shape, deflection, false, kSurfaceAngle, true);
    if (!mesher.IsDone())
      throw FacesNotTriangulated("OpenCASCADE could not triangulate the shape's faces");
  } catch (const Standard_Failure& e) {
    throw FacesNotTriangulated(
        std::string("OpenCASCADE could not triangulate the shape's faces: ") +
        e.GetMessageString());
  }
  std::vector<int> missing;
  for (int fi = 1; fi <= faces.Extent(); ++fi) {
    TopLoc_Location loc;
    const Handle(Poly_Triangulation)& tri = BRep_Tool::Triangulation(TopoDS::Face(faces(fi)), loc);
    if (tri.IsNull() || tri->NbTriangles() == 0) {
      missing.push_back(fi - 1);
      continue;
    }
    if (triangulation_collapsed(TopoDS::Face(faces(fi)), *tri, tolerance))
      missing.push_back(fi - 1);
  }
  return missing;
}

// q's parameters, each shifted by whole periods of the surface (where it is periodic in it) to
// lie within half a period of near's.
UV periodic_near(const Geom_Surface& surface, UV q, const UV& near) {
  const auto shift = [](double x, double target, double period) {
    return x + period * std::round((target - x) / period);
  };
  if (surface.IsUPeriodic()) q.u = shift(q.u, near.u, surface.UPeriod());
  if (surface.IsVPeriodic()) q.v = shift(q.v, near.v, surface.VPeriod());
  return q;
}

// The point of a segment's CAD edge at the middle of its parameters.
Vec3 middle(const TopTools_IndexedMapOfShape& edges, const EdgeSegment& segment) {
  const BRepAdaptor_Curve curve(TopoDS::Edge(edges(segment.edge + 1)));
  return of(curve.Value(0.5 * (segment.t_lo + segment.t_hi)));
}

// A face BRepMesh left without triangles between two edges with the same ends (0-based).
struct LensFace {
  int face;
  int e1, e2;
};

// A segment of a CAD edge between two nodes that already hold another edge's segment.
struct DoubledSegment {
  std::uint64_t key;  // pair_key of the nodes
  EdgeSegment segment;
};

// Moves from `missing` to `lenses` the faces BRepMesh left without triangles that are bounded by
// two edges between the same two vertices: a random part's sliver of a cylinder 1.26 mm long and
// 0.007 wide between a plane and a cylinder tangent to it, where a torus was fused
// (bench/random_parts.py, seed 20261204, part 031).
void take_lens_faces(const TopTools_IndexedMapOfShape& faces,
                     const TopTools_IndexedMapOfShape& edges, std::vector<int>& missing,
                     std::vector<LensFace>& lenses) {
  std::vector<int> rest;
  for (const int f : missing) {
    TopTools_IndexedMapOfShape face_edges;
    TopExp::MapShapes(faces(f + 1), TopAbs_EDGE, face_edges);
    if (face_edges.Extent() == 2 &&
        lens_edges(TopoDS::Edge(face_edges(1)), TopoDS::Edge(face_edges(2))))
      lenses.push_back({f, edges.FindIndex(face_edges(1)) - 1, edges.FindIndex(face_edges(2)) - 1});
    else
      rest.push_back(f);
  }
  missing = rest;
}

// The lens faces (take_lens_faces()) zipped shut: the nodes of their two edges' segments (the
// faces across them made them), in their order along the line between the edges' ends, become
// one chain of segments, on the second edge (the parameters interpolated along it), and the
// faces' triangles along either edge are split into fans over the chain's nodes between their
// side's ends. The lens gets no triangle: the faces across meet along the chain, within the
// lens's width of both edges (BRepMesh made no triangle there). A lens wider than `width` (a
// node of one chain further from the other chain) is left as it is. Returns the faces not zipped.
// A segment of the lens's edges that a third edge also holds (`doubled`: a random part's
// protrusion 0.45 mm deep under a plate, its cap's chord, arc and the plate's ellipse all one
// segment at h 68) keeps that edge: the triangles along it stay (those of a face bounded by both
// lie on the third edge's side of the segment), the rest are fanned; the lens's own entries in
// `doubled` are taken out.
std::vector<int> zip_lens_faces(const Shape& s, const TopTools_IndexedMapOfShape& edges,
                                const std::vector<LensFace>& lenses, double width,
                                std::vector<DoubledSegment>& doubled, Surface& surface) {
  std::vector<int> left;
  for (const auto& [lens_face, e1, e2] : lenses) {
    const auto on_lens = [&](int edge) { return edge == e1 || edge == e2; };
    std::vector<std::uint64_t> keys;
    std::map<int, double> along;  // node -> its place along the line between the ends
    std::map<int, int> uses;
    // Per key, the lens's edge's segment on it, and the third edge's where one shares it.
    std::unordered_map<std::uint64_t, EdgeSegment> lens_segment, third;
    for (const auto& [key, segment] : surface.segments)
      if (on_lens(segment.edge)) {
        keys.push_back(key);
        lens_segment.emplace(key, segment);
        ++uses[pair_lo(key)], ++uses[pair_hi(key)];
      }
    for (const auto& [key, segment] : doubled) {
      const auto held = surface.segments.find(key);
      if (held == surface.segments.end()) continue;
      if (on_lens(segment.edge) && !on_lens(held->second.edge)) {
        keys.push_back(key);
        lens_segment.emplace(key, segment);
        third.emplace(key, held->second);
        ++uses[pair_lo(key)], ++uses[pair_hi(key)];
      } else if (!on_lens(segment.edge) && on_lens(held->second.edge)) {
        third.emplace(key, segment);
      }
    }
    std::vector<int> ends;
    for (const auto& [n, count] : uses)
      if (count == 2 && ends.size() < 2) {
        // an end is on both edges' chains: two segments (or one of each edge)
        int with_e1 = 0, with_e2 = 0;
        for (const std::uint64_t key : keys)
          if (pair_lo(key) == n || pair_hi(key) == n)
            (lens_segment.at(key).edge == e1 ? with_e1 : with_e2) = 1;
        if (with_e1 && with_e2) ends.push_back(n);
      }
    if (ends.size() != 2) {  // the chains do not run between two common ends
      left.push_back(lens_face);
      continue;
    }
    const Vec3 a = surface.nodes[ends[0]], b = surface.nodes[ends[1]];
    const Vec3 ab = b - a;
    for (const auto& [n, count] : uses) along[n] = (surface.nodes[n] - a).dot(ab) / ab.dot(ab);
    std::vector<int> chain;
    for (const auto& [n, t] : along) chain.push_back(n);
    std::sort(chain.begin(), chain.end(), [&](int x, int y) { return along[x] < along[y]; });
    // The lens's width: its nodes' distances to the other edge's chain.
    double widest = 0;
    for (const auto& [n, count] : uses)
      for (const int other : {e1, e2}) {
        bool on = false;
        double nearest = std::numeric_limits<double>::infinity();
        for (const std::uint64_t key : keys) {
          const int x = pair_lo(key), y = pair_hi(key);
          if (lens_segment.at(key).edge != other) continue;
          on = on || x == n || y == n;
          const Vec3 xy = surface.nodes[y] - surface.nodes[x];
          const double f =
              std::clamp((surface.nodes[n] - surface.nodes[x]).dot(xy) / xy.dot(xy), 0.0, 1.0);
          nearest = std::min(nearest, (surface.nodes[x] + xy * f - surface.nodes[n]).norm());
        }
        if (!on) widest = std::max(widest, nearest);
      }
    if (widest > width) {
      left.push_back(lens_face);
      continue;
    }
    // The second edge's parameters at the ends, interpolated along the chain.
    double t_a = 0, t_b = 0;
    bool found_a = false, found_b = false;
    for (const std::uint64_t key : keys) {
      const EdgeSegment& segment = lens_segment.at(key);
      if (segment.edge != e2) continue;
      const int lo = pair_lo(key), hi = pair_hi(key);
      for (const auto& [n, t] : {std::pair<int, double>{lo, segment.t_lo}, {hi, segment.t_hi}}) {
        if (n == ends[0]) t_a = t, found_a = true;
        if (n == ends[1]) t_b = t, found_b = true;
      }
    }
    if (!found_a || !found_b) {
      left.push_back(lens_face);
      continue;
    }
    std::map<int, std::size_t> place;
    for (std::size_t i = 0; i < chain.size(); ++i) place[chain[i]] = i;
    // Each triangle with a side on either chain: a fan over the chain's nodes within that side.
    std::set<std::uint64_t> on_chain(keys.begin(), keys.end());
    const std::size_t count = surface.triangles.size();
    for (std::size_t i = 0; i < count; ++i) {
      for (int c = 0; c < 3; ++c) {
        SurfaceTriangle& t = surface.triangles[i];
        const std::uint64_t key = side_key(t, c);
        if (!on_chain.count(key)) continue;
        const auto shared = third.find(key);
        if (shared != third.end()) {  // along the lens's edge, or the third edge's?
          const EdgeSegment& mine = lens_segment.at(key);
          const auto bounds = [&](const EdgeSegment& segment) {
            const std::vector<int>& faces = s.edge_faces[static_cast<std::size_t>(segment.edge)];
            return std::find(faces.begin(), faces.end(), t.face) != faces.end();
          };
          if (!bounds(mine)) continue;
          if (bounds(shared->second)) {
            const Vec3 chord_middle =
                (surface.nodes[t.node[c]] + surface.nodes[t.node[(c + 1) % 3]]) * 0.5;
            if ((surface.nodes[t.node[(c + 2) % 3]] - chord_middle)
                    .dot(middle(edges, mine) - middle(edges, shared->second)) <= 0)
              continue;
          }
        }
        const int p = t.node[c], q = t.node[(c + 1) % 3];
        const std::size_t from = place[p], to = place[q];
        if (from + 1 == to || to + 1 == from) break;  // no chain node within
        const UV uv_p = t.uv[c], uv_q = t.uv[(c + 1) % 3];
        const int r = t.node[(c + 2) % 3];
        const UV uv_r = t.uv[(c + 2) % 3];
        const int step = from < to ? 1 : -1;
        const double span = along[q] - along[p];
        int previous = p;
        UV uv_previous = uv_p;
        SurfaceTriangle base = t;
        for (std::size_t k = from + step; k != to; k += step) {
          const int n = chain[k];
          const double w = (along[n] - along[p]) / span;
          const UV uv_n{uv_p.u + w * (uv_q.u - uv_p.u), uv_p.v + w * (uv_q.v - uv_p.v)};
          SurfaceTriangle piece = base;
          piece.node = {previous, n, r};
          piece.uv = {uv_previous, uv_n, uv_r};
          surface.triangles.push_back(piece);
          previous = n, uv_previous = uv_n;
        }
        t.node = {previous, q, r};
        t.uv = {uv_previous, uv_q, uv_r};
        break;
      }
    }
    for (const std::uint64_t key : keys) surface.segments.erase(key);
    for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
      const int x = chain[i], y = chain[i + 1];
      const double tx = t_a + along[x] * (t_b - t_a), ty = t_a + along[y] * (t_b - t_a);
      surface.segments[pair_key(x, y)] = x < y ? EdgeSegment{e2, tx, ty} : EdgeSegment{e2, ty, tx};
    }
    // The third edges keep their segments: alone where the chain does not hold them, else
    // doubled with the chain's (split_doubled_segments() parts them).
    std::vector<DoubledSegment> kept;
    for (const DoubledSegment& d : doubled) {
      const auto shared = third.find(d.key);
      if (!on_lens(d.segment.edge) &&
          (shared == third.end() || shared->second.edge != d.segment.edge))
        kept.push_back(d);
    }
    for (const auto& [key, segment] : third) {
      const auto [it, added] = surface.segments.try_emplace(key, segment);
      if (!added) kept.push_back({key, segment});
    }
    doubled.swap(kept);
  }
  return left;
}

// Two CAD edges between the same two nodes, each one segment there: a lens-shaped face or hole
// far smaller than the size (a random part's hole in a plane between a line and a hyperbola
// 0.19 mm apart, 3 mm long, at h 23.7), whose side four triangles then share as if the solid
// touched itself. Of each two whose middles lie more than 10 times the tolerance apart (else
// they are one curve, and the shape is refused as touching itself: pyocc_11752's plane's circle
// on a cylinder that has its own arcs there), the edge whose middle lies further from the
// segment gets a node at its middle: its triangles on that side are split there (on a face
// bounded by both edges, those whose third node lies on the middle's side), and its segment
// becomes two.
void split_doubled_segments(const Shape& s, const TopTools_IndexedMapOfShape& faces,
                            const TopTools_IndexedMapOfShape& edges,
                            const std::vector<DoubledSegment>& doubled, NodeMerger& merger,
                            Surface& surface, double tolerance) {
  for (const auto& [key, other] : doubled) {
    const auto it = surface.segments.find(key);
    if (it == surface.segments.end()) continue;
    const int a = pair_lo(key), b = pair_hi(key);
    const Vec3 chord_middle = (surface.nodes[a] + surface.nodes[b]) * 0.5;
    const EdgeSegment first = it->second, second = other;
    const Vec3 m_first = middle(edges, first), m_second = middle(edges, second);
    const bool split_first = (m_first - chord_middle).norm() > (m_second - chord_middle).norm();
    const EdgeSegment& split = split_first ? first : second;
    const Vec3 m = split_first ? m_first : m_second;
    const Vec3 bulge = m - chord_middle;
    if ((m_first - m_second).norm() <= 10 * tolerance) continue;  // one curve: they coincide
    const TopoDS_Edge& edge = TopoDS::Edge(edges(split.edge + 1));
    const double t_m = 0.5 * (split.t_lo + split.t_hi);
    const std::vector<int>& split_faces = s.edge_faces[static_cast<std::size_t>(split.edge)];
    const int other_edge = split_first ? second.edge : first.edge;
    const std::vector<int>& other_faces = s.edge_faces[static_cast<std::size_t>(other_edge)];
    const int node = merger.id(m, split_faces.front());
    const std::size_t count = surface.triangles.size();
    for (std::size_t t = 0; t < count; ++t) {
      SurfaceTriangle& tri = surface.triangles[t];
      if (std::find(split_faces.begin(), split_faces.end(), tri.face) == split_faces.end())
        continue;
      int c = 0;
      while (c < 3 && side_key(tri, c) != key) ++c;
      if (c == 3) continue;
      const int third = tri.node[(c + 2) % 3];
      if (std::find(other_faces.begin(), other_faces.end(), tri.face) != other_faces.end() &&
          (surface.nodes[third] - chord_middle).dot(bulge) <= 0)
        continue;  // the other edge's triangle on a face bounded by both
      const TopoDS_Face& face = TopoDS::Face(faces(tri.face + 1));
      double first_t = 0, last_t = 0;
      const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, face, first_t, last_t);
      UV uv = tri.uv[c];
      if (!pcurve.IsNull()) {
        const gp_Pnt2d q = pcurve->Value(t_m);
        uv = periodic_near(*BRep_Tool::Surface(face), UV{q.X(), q.Y()}, tri.uv[c]);
      }
      // (p, q, r) becomes (p, node, r) and (node, q, r).
      SurfaceTriangle second_half = tri;
      second_half.node = {node, tri.node[(c + 1) % 3], third};
      second_half.uv = {uv, tri.uv[(c + 1) % 3], tri.uv[(c + 2) % 3]};
      tri.node[(c + 1) % 3] = node;
      tri.uv[(c + 1) % 3] = uv;
      surface.triangles.push_back(second_half);
    }
    const EdgeSegment kept = split_first ? second : first;
    if (split_first) it->second = kept;
    const double t_a = a < b ? split.t_lo : split.t_hi, t_b = a < b ? split.t_hi : split.t_lo;
    surface.segments[pair_key(a, node)] =
        a < node ? EdgeSegment{split.edge, t_a, t_m} : EdgeSegment{split.edge, t_m, t_a};
    surface.segments[pair_key(node, b)] =
        node < b ? EdgeSegment{split.edge, t_m, t_b} : EdgeSegment{split.edge, t_b, t_m};
  }
}

// "Face61 (a cone), Face70 (a cylinder)".
std::string faces_named(const std::vector<int>& faces, const TopTools_IndexedMapOfShape& shapes,
                        const std::vector<std::string>& face_names) {
  static const char* const kinds[] = {"plane",
                                      "cylinder",
                                      "cone",
                                      "sphere",
                                      "torus",
                                      "Bezier surface",
                                      "B-spline surface",
                                      "surface of revolution",
                                      "extrusion",
                                      "offset surface",
                                      "surface"};
  std::string out;
  for (const int f : faces) {
    const int kind = BRepAdaptor_Surface(TopoDS::Face(shapes(f + 1))).GetType();
    out += (out.empty() ? "" : ", ") + face_names[static_cast<std::size_t>(f)] + " (a " +
           kinds[std::min(kind, 10)] + ")";
  }
  return out;
}

}  // namespace

Surface triangulate(const Shape& s, double deflection, double tolerance,
                    const std::vector<std::string>& face_names) {
  // BRepMesh fails on some analytic faces that are valid CAD (a cone whose apex is a circle
  // of radius 1e-15, in a KiCad connector model): the same shape with its cylinders, cones,
  // spheres and tori as surfaces of revolution (the same geometry; planes stay) is meshed
  // instead, the nodes' parameters taken back onto the faces' own surfaces.
  TopoDS_Shape meshed = s.shape;
  TopTools_IndexedMapOfShape faces = s.faces, edges = s.edges;
  std::vector<int> missing = faces_not_triangulated(meshed, faces, deflection, tolerance);
  std::vector<LensFace> lenses;  // left without triangles: zip_lens_faces()
  take_lens_faces(faces, edges, missing, lenses);
  std::size_t nb_converted = 0;
  if (!missing.empty()) {
    lenses.clear();
    const std::string failed = faces_named(missing, s.faces, face_names);
    meshed = ShapeCustom::ConvertToRevolution(s.shape);
    faces.Clear(), edges.Clear();
    TopExp::MapShapes(meshed, TopAbs_FACE, faces);
    TopExp::MapShapes(meshed, TopAbs_EDGE, edges);
    if (faces.Extent() != s.faces.Extent() || edges.Extent() != s.edges.Extent())
      throw FacesNotTriangulated("OpenCASCADE could not triangulate " + failed + " of the shape");
    missing = faces_not_triangulated(meshed, faces, deflection, tolerance);
    take_lens_faces(faces, edges, missing, lenses);
    if (!missing.empty())
      throw FacesNotTriangulated("OpenCASCADE could not triangulate " + failed +
                                 " of the shape, nor the same faces as surfaces of revolution");
    for (int fi = 1; fi <= faces.Extent(); ++fi)
      nb_converted += BRepAdaptor_Surface(TopoDS::Face(faces(fi))).GetType() !=
                      BRepAdaptor_Surface(TopoDS::Face(s.faces(fi))).GetType();
  }
  Surface surface;
  surface.nb_revolution_faces = nb_converted;
  NodeMerger merger(surface, tolerance);
  // Segments of a second CAD edge between two nodes that already hold one (and their keys).
  std::vector<DoubledSegment> doubled;
  for (int fi = 1; fi <= faces.Extent(); ++fi) {
    const int face_index = fi - 1;
    const TopoDS_Face& face = TopoDS::Face(faces(fi));
    TopLoc_Location loc;
    const Handle(Poly_Triangulation)& tri = BRep_Tool::Triangulation(face, loc);
    if (tri.IsNull() || tri->NbTriangles() == 0) continue;  // a lens face: zip_lens_faces()
    // The parameters on the face's own surface, where the face was meshed as another.
    std::optional<ShapeAnalysis_Surface> own;
    const TopoDS_Face& given = TopoDS::Face(s.faces(fi));
    if (nb_converted > 0 &&
        BRepAdaptor_Surface(face).GetType() != BRepAdaptor_Surface(given).GetType())
      own.emplace(BRep_Tool::Surface(given));
    const gp_Trsf trsf = loc.Transformation();
    std::vector<int> global(static_cast<std::size_t>(tri->NbNodes()) + 1);
    for (int i = 1; i <= tri->NbNodes(); ++i)
      global[i] = merger.id(of(tri->Node(i).Transformed(trsf)), face_index);
    // Each node's parameters on the face's own surface, projected once.
    std::vector<UV> own_uv;
    if (own) {
      own_uv.resize(global.size());
      for (int i = 1; i <= tri->NbNodes(); ++i) {
        const gp_Pnt2d q = own->ValueOfUV(tri->Node(i).Transformed(trsf), tolerance);
        own_uv[i] = UV{q.X(), q.Y()};
      }
    }
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (int k = 1; k <= tri->NbTriangles(); ++k) {
      int n[3];
      tri->Triangle(k).Get(n[0], n[1], n[2]);
      if (reversed) std::swap(n[1], n[2]);
      SurfaceTriangle t;
      t.face = face_index;
      for (int c = 0; c < 3; ++c) {
        t.node[c] = global[n[c]];
        if (own) {
          // The first corner's within half a period of the meshed surface's (a surface of
          // revolution's angle is its cone's or cylinder's), the others within half a period of
          // the first's: the triangle does not straddle a seam.
          const UV q = own_uv[static_cast<std::size_t>(n[c])];
          const UV near = c > 0               ? t.uv[0]
                          : tri->HasUVNodes() ? UV{tri->UVNode(n[c]).X(), tri->UVNode(n[c]).Y()}
                                              : q;
          t.uv[c] = periodic_near(*own->Surface(), q, near);
        } else if (tri->HasUVNodes()) {
          t.uv[c] = UV{tri->UVNode(n[c]).X(), tri->UVNode(n[c]).Y()};
        }
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
      const int edge_index = edges.FindIndex(edge) - 1;
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
        const EdgeSegment segment =
            a < b ? EdgeSegment{edge_index, ta, tb} : EdgeSegment{edge_index, tb, ta};
        const auto [it, added] = surface.segments.try_emplace(pair_key(a, b), segment);
        if (!added && it->second.edge != edge_index &&
            std::none_of(doubled.begin(), doubled.end(), [&](const DoubledSegment& d) {
              return d.segment.edge == edge_index && d.segment.t_lo == segment.t_lo;
            }))
          doubled.push_back({pair_key(a, b), segment});
      }
    }
  }
  const std::vector<int> not_zipped =
      zip_lens_faces(s, edges, lenses, deflection, doubled, surface);
  surface.nb_zipped_faces = lenses.size() - not_zipped.size();
  if (!not_zipped.empty())
    throw FacesNotTriangulated(
        "OpenCASCADE could not triangulate " + faces_named(not_zipped, s.faces, face_names) +
        " of the shape (between two edges with the same ends, wider than the chord "
        "deflection)");
  split_doubled_segments(s, faces, edges, doubled, merger, surface, tolerance);
  insert_internal_vertices(s, deflection, merger, surface);
  remove_coincident_triangles(surface);
  remove_faces_without_area(surface);
  surface.nb_flat_triangles = remove_flat_triangles(surface, tolerance);
  drop_unused_nodes(surface);
  surface.nb_unfolded_patches = unfold_faces(surface).patches;
  // (Apart by more than ten merging tolerances, about 1e-4 h: what the refusal of a surface
  // touching itself measures too.)
  surface.nb_parted_sides = part_shared_sides(s, 10 * tolerance, merger, surface);
  return surface;
}

}  // namespace hexmerge::mesher
