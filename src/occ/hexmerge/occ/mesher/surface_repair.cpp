#include "hexmerge/occ/mesher/surface_repair.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <gp_Pnt2d.hxx>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface_edit.h"

namespace hexmerge::mesher {
namespace {

// Rounds of smoothing and flips after the surface refinement.
// A bisection point on a face further than this fraction of the side from the side's middle
// means the parametrisation is distorted there: the middle is projected on the face instead.
constexpr double kDistortedMiddle = 0.25;
// A side is not split where its middle on the CAD is nearer than this fraction of the side to
// one of its ends.
constexpr double kSplitEnd = 0.1;
// A face whose splits put this many new nodes on nodes already there is given up.
constexpr int kStackedLimit = 100;
// No flip makes a triangle with a smaller angle than this (radians, about 0.06 degrees).
constexpr double kFlatAngle = 1e-3;
constexpr int kSmoothingRounds = 5;
// Surface nodes with a smaller angle than this (radians, 20 degrees) in their triangles are
// smoothed.
constexpr double kNeedleAngle = 20.0 * M_PI / 180;
// A needle's node moves no nearer than this fraction of h to its neighbours.
constexpr double kNeedleNearest = 0.125;
// A triangle whose shortest side lies on a CAD edge and whose longest side is more than this
// many times longer (a strip of BRepMesh's between two finely divided edges: the sides of a
// short cylinder, 0.12 x 0.75 h, 9 degrees) has its longest side split, down to
// kStripSmallest of the size wanted: a tet on it is no better than its smallest angle.
constexpr double kStripRatio = 3.0;
constexpr double kStripSmallest = 0.2;
// Sides shorter than this fraction of h inside one face are collapsed after the refinement.
constexpr double kCollapseSide = 0.25;
// Triangles with a smaller angle than this (radians, 5 degrees) have their nodes inside a face
// collapsed away where that makes no triangle worse.
constexpr double kCapAngle = 5.0 * M_PI / 180;
// Collapsing a cap's node may leave sides up to this many times h.
constexpr double kCapSide = 2.0;
// A node of a CAD edge goes only where the chord it leaves is within this fraction of h of it
// (the default surface deflection, 0.02 h).
constexpr double kEdgeSagitta = 0.02;

gp_Pnt2d point2d(const UV& uv) { return gp_Pnt2d(uv.u, uv.v); }

}  // namespace

// Splits the triangles of the faces that are not lattice faces until no side is longer than
// `target` (sides on edges between lattice faces excepted), nor a strip along a CAD edge
// (kStripRatio); lattice-face triangles are split only where a neighbour's side must be and on a
// seam between lattice faces on one plane. New
// nodes lie on the CAD edge (sides on an edge) or on the face's surface.
void refine(const Shape& s, Surface& surface, double target, double deflection,
            const std::vector<bool>& lattice_face, const std::vector<bool>& lattice_edge,
            const SizeField* field, const SizeField* deflection_field) {
  FaceGaps gaps(s, deflection, target, deflection_field);
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
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> projector(s.faces.Extent());
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
  // The size wanted at node n (target without local sizes), and at a side: the smaller at its
  // ends, so that the sides around a finely meshed face grade out from it.
  std::vector<double> node_size;
  auto size_at = [&](int n) {
    if (!field) return target;
    if (node_size.size() <= static_cast<std::size_t>(n))
      node_size.resize(surface.nodes.size(), -1.0);
    if (node_size[n] < 0) node_size[n] = field->at(surface.nodes[n]);
    return node_size[n];
  };
  auto side_target = [&](int a, int b) { return std::min(size_at(a), size_at(b)); };
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
  auto midpoint = [&](int ti, int c, int node, UV& uv) {
    const SurfaceTriangle& t = tris[ti];
    const int a = t.node[c], b = t.node[(c + 1) % 3];
    uv = UV{0.5 * (t.uv[c].u + t.uv[(c + 1) % 3].u), 0.5 * (t.uv[c].v + t.uv[(c + 1) % 3].v)};
    auto seg = surface.segments.find(pair_key(a, b));
    const bool on_edge = seg != surface.segments.end();
    const double tm = on_edge ? 0.5 * (seg->second.t_lo + seg->second.t_hi) : 0.0;
    if (on_edge) {
      const EdgeSegment& e = seg->second;
      const double ta = a < b ? e.t_lo : e.t_hi;
      double best = std::numeric_limits<double>::max();
      for (const PCurve& pc : pcurves[t.face]) {  // the pcurve through node a (seams have two)
        if (pc.edge != e.edge) continue;
        const double d = pc.curve->Value(ta).Distance(point2d(t.uv[c]));
        if (d < best) {
          best = d;
          const gp_Pnt2d at = pc.curve->Value(tm);
          uv = UV{at.X(), at.Y()};
        }
      }
    }
    if (node >= 0) return node;
    Vec3 p = on_edge ? of(edge_curve(seg->second.edge).Value(tm))
                     : of(face_surface(t.face).Value(uv.u, uv.v));
    // Where the face's parametrisation is distorted (near a pole, a seam, a B-spline's collapsed
    // side), the middle of the parameters is far from the middle of the side, and bisecting there
    // never shortens it: the side's own middle, projected on the face, is taken instead.
    const Vec3 chord_middle = (surface.nodes[a] + surface.nodes[b]) * 0.5;
    const double side = length(a, b);
    if (!on_edge && (p - chord_middle).norm() > kDistortedMiddle * side) {
      if (!projector[t.face]) {
        const TopoDS_Face& f = TopoDS::Face(s.faces(t.face + 1));
        projector[t.face] = std::make_unique<ShapeAnalysis_Surface>(BRep_Tool::Surface(f));
      }
      const gp_Pnt2d at = projector[t.face]->ValueOfUV(
          gp_Pnt(chord_middle.x, chord_middle.y, chord_middle.z), 1e-9 * side);
      uv = UV{at.X(), at.Y()};
      p = of(projector[t.face]->Value(at));
    }
    surface.nodes.push_back(p);
    surface.node_face.push_back(t.face);
    return static_cast<int>(surface.nodes.size()) - 1;
  };
  // The nodes by position (cells of the target's size), to find a node already at a point.
  NodeHash node_cells(surface.nodes, target);
  for (int n = 0; n < static_cast<int>(surface.nodes.size()); ++n) node_cells.add(n);
  // Per face: given up (see below), and the new nodes that landed on a node already there.
  std::vector<char> given_up(s.faces.Extent(), 0);
  std::vector<int> stacked(s.faces.Extent(), 0);
  // Sides whose middle on the CAD falls on one of their ends (a face's pole or collapsed side:
  // splitting them again and again stacked 1,054 nodes on one point of gmsh_917_fusee's face 60).
  std::unordered_set<std::uint64_t> unsplittable;
  // Faces not brought to the target size everywhere, each listed once.
  auto list_unrefined = [&](int face) {
    std::vector<int>& listed = surface.unrefined_faces;
    if (std::find(listed.begin(), listed.end(), face) == listed.end()) listed.push_back(face);
  };
  // Splits side (a, b) in every triangle that has it; the halves of an edge segment stay one.
  // Returns the sides around the new node, or nothing when the side cannot be split.
  auto split_side = [&](int a, int b) {
    const std::uint64_t key = pair_key(a, b);
    const std::vector<int> around = at_edge[key];
    int m = -1;
    if (!around.empty()) {
      const int t0 = around.front();
      UV uv;
      m = midpoint(t0, side_with_key(tris[t0], key), -1, uv);
      const double side = length(a, b);
      // A middle on a node already there: the face's parameters collapse to one point there (a
      // pole, a B-spline's collapsed side) and the side crosses it. Splitting stacks nodes there
      // (remove_folds() merges them later) without shortening anything: a face that does it
      // kStackedLimit times is given up at once (gmsh_t20_data at h 0.66 stacked 42,345 nodes on
      // one point of face 16, 300 s, until the limit on a face's nodes gave it up).
      // (m itself is filed below, once kept.)
      if (node_cells.find(surface.nodes[m], 1e-6 * side) >= 0 &&
          ++stacked[tris[t0].face] >= kStackedLimit)
        given_up[tris[t0].face] = 1, list_unrefined(tris[t0].face);
      if (length(m, a) < kSplitEnd * side || length(m, b) < kSplitEnd * side) {
        surface.nodes.pop_back();
        surface.node_face.pop_back();
        unsplittable.insert(key);
        list_unrefined(tris[t0].face);
        return std::vector<std::uint64_t>{};
      }
    }
    if (m >= 0) node_cells.add(m);
    for (int ti : around) {
      const SurfaceTriangle t = tris[ti];
      const int c = side_with_key(t, key);
      UV uv;
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
  auto angle_at = [&](int v, int a, int b) { return mesher::angle_at(surface.nodes, v, a, b); };
  auto normal_of = [&](int a, int b, int c) { return mesher::normal_of(surface.nodes, a, b, c); };
  // (`keep_sizes`: after the refinement, no flip makes a side longer than the size wanted.)
  auto restore_delaunay = [&](std::vector<std::uint64_t> stack, bool keep_sizes) {
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
      if (keep_sizes && length(m, x) > side_target(m, x)) continue;
      // No flip to a side that exists already: two more triangles on it, the surface no longer a
      // manifold. Among nearly collinear nodes the 3D test can ask for one (gmsh_Kurbelwelle at
      // h 0.57, needles along a half cone's seam): the sides split there came back, were split
      // again onto the nodes already there until the face was given up, and TetGen got triangles
      // of 177 degrees, the tets on them of scaled Jacobian 0.003.
      if (const auto there = at_edge.find(pair_key(m, x));
          there != at_edge.end() && !there->second.empty())
        continue;
      // Off the plane the test can fail both ways: flip only to a strictly better pair.
      const double now = angle_at(m, p, q) + angle_at(x, q, p);
      if (now <= M_PI * (1 + 1e-9) || angle_at(p, x, m) + angle_at(q, m, x) >= now - 1e-9) continue;
      // Off the plane the test can also pass where the flip makes a flat triangle (a side's
      // ends and the node that split it: gmsh_917_fusee's B-spline faces), which the next split
      // stacks a node on: a flip must not make the pair's smallest angle smaller.
      const double least_before = std::min(mesher::smallest_angle(surface.nodes, a.node),
                                           mesher::smallest_angle(surface.nodes, b.node));
      const double least_after =
          std::min(mesher::smallest_angle(surface.nodes, std::array<int, 3>{m, p, x}),
                   mesher::smallest_angle(surface.nodes, std::array<int, 3>{x, q, m}));
      if (least_after < least_before || least_after < kFlatAngle) continue;
      const Vec3 before = normal_of(p, q, m) + normal_of(q, p, x);
      // Nor across the surface's curvature: both new triangles within 20 degrees of the old.
      const Vec3 n1 = normal_of(m, p, x), n2 = normal_of(x, q, m);
      const double c20 = std::cos(20.0 * M_PI / 180);
      if (n1.dot(before) <= c20 * n1.norm() * before.norm() ||
          n2.dot(before) <= c20 * n2.norm() * before.norm())
        continue;
      const UV up = a.uv[c1], uq = a.uv[(c1 + 1) % 3], um = a.uv[(c1 + 2) % 3];
      const UV ux = b.uv[(c2 + 2) % 3];
      const std::vector<Vec3>& at = surface.nodes;
      if (!gaps.keeps_close(
              [&] {
                return std::max(gaps.of(a.face, {at[m], at[p], at[x]}, {um, up, ux}),
                                gaps.of(a.face, {at[x], at[q], at[m]}, {ux, uq, um}));
              },
              [&] { return std::max(gaps.of(at, a), gaps.of(at, b)); }))
        continue;
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
  // The side of triangle ti to split (its longest), -1 for none. With local sizes, a lattice
  // face's sides on CAD edges are split where the size wanted there is below the target (its
  // inside is cut by the tetrahedraliser, between its boundary and its points).
  auto side_to_split = [&](int ti) {
    const SurfaceTriangle& t = tris[ti];
    if (lattice_face[t.face]) {
      // A seam between lattice faces on one plane: no lattice point comes onto it, and no other
      // face's triangle splits it, so it is split here to the size wanted.
      for (int c = 0; c < 3; ++c) {
        const int a = t.node[c], b = t.node[(c + 1) % 3];
        const auto seg = surface.segments.find(pair_key(a, b));
        if (seg == surface.segments.end() || lattice_edge[seg->second.edge] ||
            unsplittable.count(pair_key(a, b)) || length(a, b) <= side_target(a, b))
          continue;
        const auto& around = s.edge_faces[static_cast<std::size_t>(seg->second.edge)];
        if (std::all_of(around.begin(), around.end(), [&](int f) { return lattice_face[f]; }))
          return c;
      }
      if (!field) return -1;
      for (int c = 0; c < 3; ++c) {
        const int a = t.node[c], b = t.node[(c + 1) % 3];
        const double wanted = side_target(a, b);
        if (wanted < target && length(a, b) > wanted && surface.segments.count(pair_key(a, b)) &&
            !unsplittable.count(pair_key(a, b)))
          return c;
      }
      return -1;
    }
    const int c = longest(ti);
    const int a = t.node[c], b = t.node[(c + 1) % 3];
    const double wanted = side_target(a, b);
    auto seg = surface.segments.find(pair_key(a, b));
    if (seg != surface.segments.end() && lattice_edge[seg->second.edge] && wanted >= target)
      return -1;
    if (unsplittable.count(pair_key(a, b))) return -1;
    if (length(a, b) > wanted) return c;
    // A strip along a CAD edge (kStripRatio).
    int shortest = 0;
    for (int k = 1; k < 3; ++k)
      if (length(t.node[k], t.node[(k + 1) % 3]) <
          length(t.node[shortest], t.node[(shortest + 1) % 3]))
        shortest = k;
    const int p = t.node[shortest], q = t.node[(shortest + 1) % 3];
    return length(a, b) > kStripRatio * length(p, q) && length(a, b) > kStripSmallest * wanted &&
                   surface.segments.count(pair_key(p, q))
               ? c
               : -1;
  };
  // Splits side c of triangle ti (in every triangle that has it), then restores the Delaunay
  // property around the new node. Rivara's longest-edge propagation: the side is split only
  // where it is also the longest side of the triangle across (or there is none of the face);
  // else that triangle's longer side goes first, and so on along the path. Splitting a side that
  // is not the longest of the triangle across made needles there, which the next splits made
  // worse: gmsh_U_Joint_2 at h 0.96 (its 1M size), three half cylinders whose BRepMesh strips
  // are 76 mm long got 19k sides under h / 8 and nodes 0.001 mm off their straight edges, four
  // times the nodes their area needs (refine 7.5 s, the second collapse 7.1 s, then crossing
  // triangles and the repairs again).
  auto split = [&](int ti, int c) {
    int t = ti, side = c;
    while (true) {
      const std::uint64_t key = side_key(tris[t], side);
      const auto it = at_edge.find(key);
      if (it == at_edge.end() || it->second.size() != 2) break;
      const int tj = it->second[0] == t ? it->second[1] : it->second[0];
      if (tris[tj].face != tris[t].face) break;
      const int cj = side_to_split(tj);
      if (cj < 0 || side_key(tris[tj], cj) == key) break;
      if (!(length(tris[tj].node[cj], tris[tj].node[(cj + 1) % 3]) >
            length(tris[t].node[side], tris[t].node[(side + 1) % 3])))
        break;
      t = tj, side = cj;
    }
    restore_delaunay(split_side(tris[t].node[side], tris[t].node[(side + 1) % 3]), false);
  };
  // Per face: a face whose refinement adds more nodes than twenty times its area over the
  // target's square (plus 200) is not converging there (a distorted parametrisation, flips that
  // bring long sides back): it is left as it is then, and listed.
  // (With local sizes: over the square of the smallest size wanted at the face's nodes.)
  std::vector<double> face_area(s.faces.Extent(), 0.0), face_target(s.faces.Extent(), target);
  for (const SurfaceTriangle& t : tris) {
    face_area[t.face] += 0.5 * normal_of(t.node[0], t.node[1], t.node[2]).norm();
    for (int n : t.node) face_target[t.face] = std::min(face_target[t.face], size_at(n));
  }
  std::vector<std::size_t> added(s.faces.Extent(), 0);
  // Passes until no side is longer than wanted: a flip after a split (or a split along the
  // propagation path) can make a side of a triangle passed before longer (a few of them, by
  // under 1 %).
  for (int pass = 0, splits = 1; splits > 0 && pass < 4; ++pass) {
    splits = 0;
    for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
      for (int c = -1; !given_up[tris[ti].face] && (c = side_to_split(ti)) >= 0; ++splits) {
        const int face = tris[ti].face;
        const std::size_t before = surface.nodes.size();
        split(ti, c);
        added[face] += surface.nodes.size() - before;
        if (added[face] > 20 * face_area[face] / (face_target[face] * face_target[face]) + 200) {
          given_up[face] = 1;
          list_unrefined(face);
        }
      }
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
  auto longest_around = [&](int n) {
    double most = 0;
    for (int ti : around[n])
      for (int m : tris[ti].node)
        if (m != n) most = std::max(most, length(n, m));
    return most;
  };
  auto smallest_angle = [&](int n) {
    double worst = M_PI;
    for (int ti : around[n])
      worst = std::min(worst, mesher::smallest_angle(surface.nodes, tris[ti].node));
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
      auto worst_gap = [&] {
        double worst = 0;
        for (int ti : around[n]) worst = std::max(worst, gaps.of(surface.nodes, tris[ti]));
        return worst;
      };
      const double gap_before = gaps.bounded() ? worst_gap() : 0.0;
      // No side grows past the size wanted (unless it already was longer).
      const double longest_before = std::max(longest_around(n), size_at(n));
      // To the centroid, else half or a quarter of the way, put back on the surface: better
      // angles, no triangle turned more than 20 degrees from the reference, and no nearer than
      // h / 8 to a neighbour (unless it was already): nodes must not gather (TetGen drops points
      // too close together). With only the whole way and h / 4, needles whose node sat within
      // h / 4 of the seam's nodes stayed (cylinder: tets of scaled Jacobian 0.006 on triangles
      // of 179.4 degrees at the seam).
      // The node's parameters on its face (a seam node's differ by triangle: either is a start).
      // Newton's method from them finds the surface's point nearest the goal, which lies within
      // a side of the node; the global search only where it fails (NextValueOfUV falls back to
      // it). The global search alone rebuilt a B-spline face's cache at every evaluation: a
      // helical spring at h 0.7, 98,494 projections in 170 s of its 180.
      const SurfaceTriangle& first = tris[around[n].front()];
      const UV& start = first.uv[first.node[0] == n ? 0 : first.node[1] == n ? 1 : 2];
      bool keep = false;
      for (double fraction : {1.0, 0.5, 0.25}) {
        const Vec3 goal = old + (centroid - old) * fraction;
        const gp_Pnt2d uv = analysis[face]->NextValueOfUV(
            point2d(start), gp_Pnt(goal.x, goal.y, goal.z), 1e-9 * target);
        surface.nodes[n] = of(analysis[face]->Value(uv));
        keep = smallest_angle(n) > before &&
               shortest_side(n) >= std::min(shortest, kNeedleNearest * size_at(n)) &&
               longest_around(n) <= longest_before;
        for (std::size_t k = 0; k < around[n].size() && keep; ++k) {
          const auto& v = tris[around[n][k]].node;
          keep = !turned_over(normal_of(v[0], v[1], v[2]), reference);
        }
        keep = keep && gaps.keeps_close(worst_gap, [&] { return gap_before; });
        if (keep) break;
      }
      if (!keep) surface.nodes[n] = old;
    }
    std::vector<std::uint64_t> all_sides;
    for (const SurfaceTriangle& t : tris)
      for (int c = 0; c < 3; ++c) all_sides.push_back(side_key(t, c));
    restore_delaunay(all_sides, true);
  }
}

// Removes nodes inside faces (not on a CAD edge, not on a lattice face) by collapsing one of
// their sides: one end goes to the other, which stays where it is (so on its face), where the
// link condition holds, no triangle turns more than 20 degrees from the surface's normal at the
// removed node, no side gets longer than `max_side`, and the smallest angle of the triangles
// around both ends does not get worse. The sides tried are those of needles and caps (triangles
// with an angle under kCapAngle: worst first) and then the sides shorter than kCollapseSide h
// (shortest first). Runs of nodes 0.1 to 0.3 h apart (cylinder at h 2.7: twenty in a line on the
// side face) otherwise make triangles of 179 degrees, and tets on them of scaled Jacobian 0.003;
// BRepMesh leaves nodes a few thousandths of h from a CAD edge on B-spline faces (gmsh_t20_data),
// and bisecting the sides of such a cap makes triangles whose three nodes lie on one line. The
// removed nodes are dropped and the rest renumbered.
void collapse_sides(const Shape& s, Surface& surface, double target, double max_side,
                    double deflection, const std::vector<bool>& lattice_face,
                    const SizeField* field, const SizeField* deflection_field) {
  FaceGaps gaps(s, deflection, target, deflection_field);
  std::vector<SurfaceTriangle>& tris = surface.triangles;
  const std::vector<Vec3>& nodes = surface.nodes;
  const int nb_nodes = static_cast<int>(nodes.size());
  // Per node, the size wanted there over the target (1 without local sizes).
  std::vector<double> scale(nb_nodes, 1.0);
  if (field)
    for (int n = 0; n < nb_nodes; ++n) scale[n] = field->at(nodes[n]) / target;
  // Per node, the CAD edges' segments at it (> 0: the node lies on a CAD edge; a collapse of
  // an edge's cap keeps every other node's count).
  std::vector<int> nb_segments(nb_nodes, 0);
  for (const auto& [key, segment] : surface.segments) {
    (void)segment;
    ++nb_segments[pair_lo(key)], ++nb_segments[pair_hi(key)];
  }
  std::vector<std::vector<int>> around(nb_nodes);
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
    for (int n : tris[ti].node) around[n].push_back(ti);
  std::vector<char> dead(tris.size(), 0), removed(nb_nodes, 0);
  auto normal_of = [&](const std::array<int, 3>& v) {
    return mesher::normal_of(nodes, v[0], v[1], v[2]);
  };
  auto smallest_angle = [&](const std::array<int, 3>& v) {
    return mesher::smallest_angle(nodes, v);
  };
  auto has = [](const SurfaceTriangle& t, int n) {
    return t.node[0] == n || t.node[1] == n || t.node[2] == n;
  };
  // Link condition for moving node r onto node k: the ends have two common neighbours (the
  // third nodes of the two triangles on the side r k).
  auto link_holds = [&](int r, int k) {
    std::unordered_set<int> near_r, common;
    for (int ti : around[r])
      for (int n : tris[ti].node) near_r.insert(n);
    for (int ti : around[k])
      for (int n : tris[ti].node)
        if (n != r && n != k && near_r.count(n)) common.insert(n);
    return common.size() == 2;
  };
  // The smallest angle of node r's triangles that do not have node k once r is on k, or -1 when
  // one of them gets a side longer than `limit` or turns over from `reference`.
  auto moved_angle = [&](int r, int k, double limit, const Vec3& reference) {
    double after = M_PI;
    for (int ti : around[r]) {
      if (has(tris[ti], k)) continue;
      std::array<int, 3> v = tris[ti].node;
      for (int& n : v)
        if (n == r) n = k;
      for (int n : v)
        if ((nodes[n] - nodes[k]).norm() > limit) return -1.0;
      if (turned_over(normal_of(v), reference)) return -1.0;
      after = std::min(after, smallest_angle(v));
    }
    return after;
  };
  // The farthest from its face of node r's triangles now (with the two it shares with k), and
  // of those that do not have k once r is on k (at k's parameters on their face).
  auto gap_around = [&](int r) {
    double worst = 0;
    for (int ti : around[r]) worst = std::max(worst, gaps.of(nodes, tris[ti]));
    return worst;
  };
  auto moved_gap = [&](int r, int k) {
    std::unordered_map<int, UV> uv_k;  // per face (a node on a CAD edge has one on each)
    for (int ti : around[r])
      for (int c = 0; c < 3; ++c)
        if (tris[ti].node[c] == k) uv_k[tris[ti].face] = tris[ti].uv[c];
    double worst = 0;
    for (int ti : around[r]) {
      if (has(tris[ti], k)) continue;
      SurfaceTriangle t = tris[ti];
      for (int c = 0; c < 3; ++c)
        if (t.node[c] == r) t.node[c] = k, t.uv[c] = uv_k[t.face];
      worst = std::max(worst, gaps.of(nodes, t));
    }
    return worst;
  };
  // The smallest angle after moving node r onto node k, or -1 when that is not allowed.
  auto try_collapse = [&](int r, int k, double limit) {
    if (nb_segments[r] > 0 || around[r].empty()) return -1.0;
    const int face = tris[around[r].front()].face;
    if (lattice_face[face]) return -1.0;
    std::vector<int> shared;
    Vec3 reference{0, 0, 0};
    for (int ti : around[r]) {
      if (tris[ti].face != face) return -1.0;
      if (has(tris[ti], k)) shared.push_back(ti);
      reference = reference + normal_of(tris[ti].node);
    }
    if (shared.size() != 2 || !link_holds(r, k)) return -1.0;
    double before = M_PI, after = M_PI;
    for (int ti : around[k]) before = std::min(before, smallest_angle(tris[ti].node));
    for (int ti : around[k])
      if (!has(tris[ti], r)) after = std::min(after, smallest_angle(tris[ti].node));
    for (int ti : around[r]) before = std::min(before, smallest_angle(tris[ti].node));
    const double moved = moved_angle(r, k, limit, reference);
    if (moved < 0) return -1.0;
    after = std::min(after, moved);
    if (after < before ||
        !gaps.keeps_close([&] { return moved_gap(r, k); }, [&] { return gap_around(r); }))
      return -1.0;
    return after;
  };
  // A side whose collapse failed is tried again only after a collapse changed the triangles
  // around one of its ends (its outcome depends on nothing else): per node, the collapse count
  // when its triangles last changed; per side (and kind: cap or short), the count when it
  // failed. Retrying them all in every pass took minutes on a surface of 575k triangles.
  std::uint64_t nb_collapses = 0;
  std::vector<std::uint64_t> changed_at(nb_nodes, 0);
  std::unordered_map<std::uint64_t, std::uint64_t> failed[2];
  auto collapse = [&](int r, int k) {
    ++nb_collapses;
    for (int end : {r, k})
      for (int ti : around[end])
        for (int n : tris[ti].node) changed_at[n] = nb_collapses;
    std::unordered_map<int, UV> uv_k;  // per face (a node on a CAD edge has one on each)
    for (int ti : around[r])
      if (has(tris[ti], k)) {
        dead[ti] = 1;
        for (int c = 0; c < 3; ++c)
          if (tris[ti].node[c] == k) uv_k[tris[ti].face] = tris[ti].uv[c];
      }
    for (int ti : around[r]) {
      if (dead[ti]) {
        for (int n : tris[ti].node)
          if (n != r)
            around[n].erase(std::remove(around[n].begin(), around[n].end(), ti), around[n].end());
        continue;
      }
      for (int c = 0; c < 3; ++c)
        if (tris[ti].node[c] == r) tris[ti].node[c] = k, tris[ti].uv[c] = uv_k[tris[ti].face];
      around[k].push_back(ti);
    }
    around[r].clear();
    removed[r] = 1;
  };
  // Node r removed and its ring of neighbours triangulated anew, the triangulation with the
  // largest smallest angle (dynamic programming over the ring polygon): where no collapse of a
  // side may go (a node inside a face beside three or more nodes of one CAD edge: a collapse onto
  // any of them leaves a triangle of three nodes on the edge). Under the same conditions as a
  // collapse (one face, no triangle turned over, no side longer than `limit`, no side that
  // already exists, the smallest angle better).
  auto remove_node = [&](int r, double limit) {
    if (nb_segments[r] > 0 || around[r].size() < 3) return false;
    const int face = tris[around[r].front()].face;
    if (lattice_face[face]) return false;
    // The ring in the triangles' order: the triangle (r, v[i], v[i + 1]) is outward.
    std::unordered_map<int, int> next;
    std::unordered_map<int, UV> uv;
    Vec3 reference{0, 0, 0};
    double before = M_PI;
    for (int ti : around[r]) {
      const SurfaceTriangle& t = tris[ti];
      if (t.face != face) return false;
      int c = 0;
      while (t.node[c] != r) ++c;
      if (!next.emplace(t.node[(c + 1) % 3], t.node[(c + 2) % 3]).second) return false;
      for (int k = 0; k < 3; ++k) uv[t.node[k]] = t.uv[k];
      reference = reference + normal_of(t.node);
      before = std::min(before, smallest_angle(t.node));
    }
    std::vector<int> v{next.begin()->first};
    while (v.size() <= next.size()) {
      const auto it = next.find(v.back());
      if (it == next.end()) return false;
      if (it->second == v.front()) break;
      v.push_back(it->second);
    }
    const int m = static_cast<int>(v.size());
    if (m != static_cast<int>(next.size())) return false;
    // Sides between ring nodes that exist outside the ring may not be made again.
    auto connected = [&](int a, int b) {
      for (int ti : around[a])
        if (!has(tris[ti], r) && has(tris[ti], b)) return true;
      return false;
    };
    const PolygonTriangulation made_polygon =
        best_triangulation(nodes, v, face, uv, reference, limit, connected);
    if (!(made_polygon.smallest > before)) return false;
    const std::vector<SurfaceTriangle>& made = made_polygon.triangles;
    auto made_gap = [&] {
      double worst = 0;
      for (const SurfaceTriangle& t : made) worst = std::max(worst, gaps.of(nodes, t));
      return worst;
    };
    if (!gaps.keeps_close(made_gap, [&] { return gap_around(r); })) return false;
    ++nb_collapses;
    for (int ti : around[r])
      for (int n : tris[ti].node) changed_at[n] = nb_collapses;
    const std::vector<int> slots = around[r];
    replace_triangles(tris, around, dead, slots, made);
    removed[r] = 1;
    return true;
  };
  // A cap whose three nodes lie on one CAD edge, its middle node r between two of the edge's
  // segments and in no other triangle of its face (BRepMesh puts a node inside every curved
  // edge, however short: gmsh_918_pump at h 10.3, a 0.056 h edge, a 2.45 / 175.1 / 2.45 degree
  // cap and a tet of scaled Jacobian 1.3e-4 on it): r goes onto one of the edge's two nodes
  // beside it, the cap with it, where the chord between them stays within kEdgeSagitta target
  // of r, the ends' common neighbours are the cap's and the other face's triangle's third
  // nodes, no triangle of the other face turns over and no side grows past `max_side`. The
  // chord becomes the edge's segment.
  auto collapse_edge_cap = [&](int ti) {
    const SurfaceTriangle& cap = tris[ti];
    for (int c = 0; c < 3; ++c) {
      const int r = cap.node[c], a = cap.node[(c + 1) % 3], b = cap.node[(c + 2) % 3];
      const auto ra = surface.segments.find(pair_key(r, a)),
                 rb = surface.segments.find(pair_key(r, b));
      // (r on those two segments only: a node where edges meet, as a random part's vertex of
      // three edges, keeps its place; removed, the third edge's segment lost its node.)
      if (ra == surface.segments.end() || rb == surface.segments.end() ||
          ra->second.edge != rb->second.edge || nb_segments[r] != 2 ||
          surface.segments.count(pair_key(a, b)))
        continue;
      const Vec3 chord = nodes[b] - nodes[a];
      if (chord.cross(nodes[r] - nodes[a]).norm() > kEdgeSagitta * target * chord.norm()) continue;
      int other_face = -1, in_cap_face = 0;
      Vec3 reference{0, 0, 0};
      double before = M_PI;
      for (int tj : around[r]) {
        before = std::min(before, smallest_angle(tris[tj].node));
        if (tris[tj].face == cap.face) {
          ++in_cap_face;
        } else {
          if (other_face >= 0 && tris[tj].face != other_face) other_face = -2;
          if (other_face == -1) other_face = tris[tj].face;
          reference = reference + normal_of(tris[tj].node);
        }
      }
      if (in_cap_face != 1 || other_face < 0) continue;
      double best = -1.0;
      int onto = -1;
      for (int k : {a, b}) {
        if (!link_holds(r, k)) continue;
        const double after = moved_angle(r, k, max_side, reference);
        if (after > before && after > best &&
            gaps.keeps_close([&] { return moved_gap(r, k); }, [&] { return gap_around(r); }))
          best = after, onto = k;
      }
      if (onto < 0) continue;
      join_segments(surface, r, a, b);
      collapse(r, onto);
      return true;
    }
    return false;
  };
  for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti)
    if (!dead[ti] && !lattice_face[tris[ti].face] && smallest_angle(tris[ti].node) < kCapAngle)
      collapse_edge_cap(ti);
  for (bool changed = true; changed;) {
    changed = false;
    // Needles' and caps' sides first (priority below 0: their smallest angle minus pi), then the
    // short sides (priority: their length).
    std::vector<std::pair<double, std::uint64_t>> sides;
    for (int ti = 0; ti < static_cast<int>(tris.size()); ++ti) {
      if (dead[ti] || lattice_face[tris[ti].face]) continue;
      const double angle = smallest_angle(tris[ti].node);
      for (int c = 0; c < 3; ++c) {
        const int a = tris[ti].node[c], b = tris[ti].node[(c + 1) % 3];
        if (surface.segments.count(pair_key(a, b))) continue;
        const double l = (nodes[a] - nodes[b]).norm();
        if (angle < kCapAngle) sides.push_back({angle - M_PI, pair_key(a, b)});
        if (a < b && l < kCollapseSide * target * std::min(scale[a], scale[b]))
          sides.push_back({l, pair_key(a, b)});
      }
    }
    std::sort(sides.begin(), sides.end());
    for (const auto& [priority, key] : sides) {
      const int a = pair_lo(key), b = pair_hi(key);
      if (removed[a] || removed[b]) continue;
      // A cap's node may leave sides up to twice the target: a long side is better than a flat
      // triangle.
      const double local = std::min(scale[a], scale[b]);
      const double limit =
          (priority < 0 ? std::max(max_side, kCapSide * target) : max_side) * local;
      auto& failed_kind = failed[priority < 0 ? 0 : 1];
      const auto before = failed_kind.find(key);
      if (before != failed_kind.end() && changed_at[a] <= before->second &&
          changed_at[b] <= before->second)
        continue;  // as it was when it failed
      const double ab = try_collapse(a, b, limit), ba = try_collapse(b, a, limit);
      if (ab < 0 && ba < 0) {
        if (priority < 0 && (remove_node(a, limit) || remove_node(b, limit))) {
          changed = true;
          continue;
        }
        failed_kind[key] = nb_collapses;
        continue;
      }
      if (ab >= ba)
        collapse(a, b);
      else
        collapse(b, a);
      changed = true;
    }
  }
  drop_removed(surface, removed, dead, false);
}

}  // namespace hexmerge::mesher
