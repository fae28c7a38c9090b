#include "hexmerge/occ/mesher/sweep.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <gp_Cylinder.hxx>
#include <gp_Lin.hxx>
#include <gp_Pln.hxx>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/shape.h"

namespace hexmerge::mesher {

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
    // A cap split into faces: the edges between them are no wall's, so nothing splits them, and
    // the lattice points of the cap come as near them as the points' margin allows (KiCad's
    // SMD resistor R_0402, its terminations' seams 0.005 mm from a lattice line at h 0.044:
    // boundary triangles of 0.7 degrees, tets of scaled Jacobian 0.004; not swept, its smallest
    // is 0.21 and it has more hexahedra). The unswept surface repairs split such seams.
    for (std::size_t e = 0; e < s.edge_faces.size() && ok; ++e)
      ok = s.edge_faces[e].empty() ||
           !std::all_of(s.edge_faces[e].begin(), s.edge_faces[e].end(),
                        [&](int f) { return sweep.cap[static_cast<std::size_t>(f)] >= 0; });
    if (ok && bottom && top && unaligned_wall) return sweep;
  }
  return std::nullopt;
}

std::optional<SweptSurface> sweep_surface(const Shape& s, const Sweep& sweep, const Frame& frame,
                                          const Vec3& step, int levels, double target,
                                          double deflection, const std::vector<bool>& lattice_face,
                                          Surface& surface,
                                          const std::vector<double>* wall_target) {
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
    double side_target = target;
    if (wall_target)
      for (const int w : side.wall) side_target = std::min(side_target, (*wall_target)[w]);
    int pieces = static_cast<int>(std::ceil(length / side_target - 1e-9));
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
    swept.segments[pair_key(renumber[pair_lo(key)], renumber[pair_hi(key)])] = segment;
  for (const SurfaceTriangle& t : bottom)
    swept.triangles.push_back(
        {{renumber[t.node[0]], renumber[t.node[1]], renumber[t.node[2]]}, {}, t.face});
  for (const Side& side : sides) {
    const int a = renumber[side.from], b = renumber[side.to];
    result.sides.push_back({a, b});
    result.shared.push_back(s.face_solid_count[side.wall[0]] > 1);
    result.on_lattice_face.push_back(lattice_face[side.wall[0]]);
    result.wall.push_back(side.wall);
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

namespace {

constexpr index_t kNoIndex = std::numeric_limits<index_t>::max();
constexpr int kNoLevel = std::numeric_limits<int>::min();

// Points (#points by 3, frame coordinates) as a stack of lattice planes: per point its plane
// (level) and its place across the axis (the bits of its two other coordinates: the sweep
// repeats them exactly), and the point at each place on each level.
struct Stack {
  std::vector<int> level, place;
  int lowest = 0, highest = 0, nb_levels = 0;
  std::vector<index_t> at;
  index_t point_at(int where, int l) const {
    return at[static_cast<std::size_t>(where) * nb_levels + (l - lowest)];
  }
  int level_of_triangle(const std::array<index_t, 3>& t) const {
    return level[t[0]] == level[t[1]] && level[t[1]] == level[t[2]] ? level[t[0]] : kNoLevel;
  }
};

// The stack, or nothing when a point lies off the planes, two share a place and a level, a
// place lacks a point on some level, or there are fewer than two levels.
std::optional<Stack> stack_points(const std::vector<double>& points, int axis, double spacing) {
  const std::size_t nb_points = points.size() / 3;
  if (nb_points == 0) return std::nullopt;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  Stack stack;
  stack.level.resize(nb_points);
  stack.place.resize(nb_points);
  std::map<std::pair<double, double>, int> place_of;
  int lowest = std::numeric_limits<int>::max(), highest = std::numeric_limits<int>::min();
  for (std::size_t i = 0; i < nb_points; ++i) {
    const double* p = &points[3 * i];
    const double k = std::round(p[axis] / spacing);
    if (std::abs(p[axis] - k * spacing) > 1e-7 * spacing) return std::nullopt;
    stack.level[i] = static_cast<int>(k);
    lowest = std::min(lowest, stack.level[i]), highest = std::max(highest, stack.level[i]);
    stack.place[i] = place_of.emplace(std::make_pair(p[u], p[v]), static_cast<int>(place_of.size()))
                         .first->second;
  }
  stack.lowest = lowest, stack.highest = highest, stack.nb_levels = highest - lowest + 1;
  if (stack.nb_levels < 2) return std::nullopt;
  stack.at.assign(place_of.size() * static_cast<std::size_t>(stack.nb_levels), kNoIndex);
  for (std::size_t i = 0; i < nb_points; ++i) {
    index_t& slot = stack.at[static_cast<std::size_t>(stack.place[i]) * stack.nb_levels +
                             (stack.level[i] - lowest)];
    if (slot != kNoIndex) return std::nullopt;  // two points at one place
    slot = static_cast<index_t>(i);
  }
  if (std::find(stack.at.begin(), stack.at.end(), kNoIndex) != stack.at.end()) return std::nullopt;
  return stack;
}

double tet_volume(const std::vector<double>& points, index_t a, index_t b, index_t c, index_t d) {
  const Vec3 p = Vec3::of(&points[3 * a]);
  return det3(Vec3::of(&points[3 * b]) - p, Vec3::of(&points[3 * c]) - p,
              Vec3::of(&points[3 * d]) - p) /
         6;
}

// The prisms over the section's triangles (places) through every slab, each split into three
// tets by the smallest point index (Dompierre et al. 1999), so that neighbours agree on every
// quad's diagonal. False when a tet is flat; `volume` per slab.
bool extrude_section(const Stack& stack, const std::vector<std::array<int, 3>>& section,
                     const std::vector<double>& points, std::vector<index_t>& made,
                     std::vector<double>& volume) {
  // Rotated so that the smallest is vertex 0; the quad 1-2-5-4 is cut through its own smallest.
  static constexpr int kRotation[6][6] = {{0, 1, 2, 3, 4, 5}, {1, 2, 0, 4, 5, 3},
                                          {2, 0, 1, 5, 3, 4}, {3, 5, 4, 0, 2, 1},
                                          {4, 3, 5, 1, 0, 2}, {5, 4, 3, 2, 1, 0}};
  made.clear();
  made.reserve(section.size() * 3 * 4 * static_cast<std::size_t>(stack.nb_levels - 1));
  volume.assign(static_cast<std::size_t>(stack.nb_levels - 1), 0.0);
  for (const auto& tri : section)
    for (int l = stack.lowest; l < stack.highest; ++l) {
      const index_t prism[6] = {stack.point_at(tri[0], l),     stack.point_at(tri[1], l),
                                stack.point_at(tri[2], l),     stack.point_at(tri[0], l + 1),
                                stack.point_at(tri[1], l + 1), stack.point_at(tri[2], l + 1)};
      const int first = static_cast<int>(std::min_element(prism, prism + 6) - prism);
      index_t r[6];
      for (int k = 0; k < 6; ++k) r[k] = prism[kRotation[first][k]];
      const index_t cut[3][4] = {
          {r[0], r[1], r[2], r[5]}, {r[0], r[1], r[5], r[4]}, {r[0], r[4], r[5], r[3]}};
      const index_t other[3][4] = {
          {r[0], r[1], r[2], r[4]}, {r[0], r[4], r[2], r[5]}, {r[0], r[4], r[5], r[3]}};
      const auto& split = std::min(r[1], r[5]) < std::min(r[2], r[4]) ? cut : other;
      for (const auto& tet : split) {
        index_t q[4] = {tet[0], tet[1], tet[2], tet[3]};
        double vol = tet_volume(points, q[0], q[1], q[2], q[3]);
        if (vol < 0) std::swap(q[1], q[2]), vol = -vol;
        if (!(vol > 0)) return false;
        volume[l - stack.lowest] += vol;
        made.insert(made.end(), q, q + 4);
      }
    }
  return true;
}

// The extruded boundary triangles: over each side of the section (once, in the order of their
// places) in each slab the quad cut through its smallest corner, where `quad_marker` gives it a
// marker (>= 0); then on each of `cap_levels` every section triangle `cap_marker` gives one.
template <class QuadMarker, class CapMarker>
void extruded_boundary(const Stack& stack, const std::vector<std::array<int, 3>>& section,
                       const std::vector<int>& cap_levels, QuadMarker quad_marker,
                       CapMarker cap_marker, std::vector<std::array<index_t, 3>>& boundary,
                       std::vector<int>& markers) {
  boundary.clear(), markers.clear();
  std::set<std::pair<int, int>> sides;
  for (const auto& tri : section)
    for (int c = 0; c < 3; ++c) sides.insert(std::minmax(tri[c], tri[(c + 1) % 3]));
  for (const auto& [a, b] : sides)
    for (int l = stack.lowest; l < stack.highest; ++l) {
      const index_t q[4] = {stack.point_at(a, l), stack.point_at(b, l), stack.point_at(b, l + 1),
                            stack.point_at(a, l + 1)};
      const int marker = quad_marker(a, b, l, q);
      if (marker < 0) continue;
      const int s = static_cast<int>(std::min_element(q, q + 4) - q);
      const index_t p0 = q[s], p1 = q[(s + 1) % 4], p2 = q[(s + 2) % 4], p3 = q[(s + 3) % 4];
      boundary.push_back({p0, p1, p2});
      boundary.push_back({p0, p2, p3});
      markers.push_back(marker);
      markers.push_back(marker);
    }
  for (const int l : cap_levels)
    for (const auto& tri : section) {
      const std::array<index_t, 3> corners{stack.point_at(tri[0], l), stack.point_at(tri[1], l),
                                           stack.point_at(tri[2], l)};
      const int marker = cap_marker(l, corners);
      if (marker < 0) continue;
      boundary.push_back(corners);
      markers.push_back(marker);
    }
}

}  // namespace

std::size_t extrude_tets(int axis, double spacing, std::size_t given,
                         tetgen::TetrahedralizeOutput& tets) {
  const std::size_t nb_points = tets.points.size() / 3;
  if (nb_points != given) return 0;
  const std::optional<Stack> stack = stack_points(tets.points, axis, spacing);
  if (!stack) return 0;
  // The cross-section: TetGen's boundary triangles on the first plane, as places.
  std::vector<std::array<int, 3>> section;
  for (const auto& t : tets.boundary)
    if (stack->level_of_triangle(t) == stack->lowest)
      section.push_back({stack->place[t[0]], stack->place[t[1]], stack->place[t[2]]});
  std::vector<index_t> made;
  std::vector<double> volume;
  if (!extrude_section(*stack, section, tets.points, made, volume)) return 0;
  double before = 0, after = 0;
  for (std::size_t t = 0; t < tets.tets.size() / 4; ++t) {
    const index_t* w = &tets.tets[4 * t];
    before += std::abs(tet_volume(tets.points, w[0], w[1], w[2], w[3]));
  }
  for (const double v : volume) after += v;
  if (std::abs(after - before) > 1e-9 * before) return 0;
  // The boundary triangles: where TetGen had boundary triangles over the same quad (walls,
  // faces between solids) or over the same part of a plane (caps), with their markers.
  std::map<std::array<index_t, 3>, int> marker_of;   // sorted corners
  std::map<int, std::vector<std::size_t>> on_level;  // TetGen's triangles on each plane
  for (std::size_t i = 0; i < tets.boundary.size(); ++i) {
    std::array<index_t, 3> key = tets.boundary[i];
    std::sort(key.begin(), key.end());
    marker_of[key] = tets.boundary_marker[i];
    const int l = stack->level_of_triangle(tets.boundary[i]);
    if (l != kNoLevel) on_level[l].push_back(i);
  }
  // A quad's marker: TetGen's on one of its triangles.
  auto quad_marker = [&](int, int, int, const index_t(&q)[4]) {
    for (int skip = 0; skip < 4; ++skip) {
      std::array<index_t, 3> key{};
      for (int k = 0, n = 0; k < 4; ++k)
        if (k != skip) key[n++] = q[k];
      std::sort(key.begin(), key.end());
      const auto it = marker_of.find(key);
      if (it != marker_of.end()) return it->second;
    }
    return -1;
  };
  // Caps: the marker of TetGen's triangle on the same corners, else (TetGen cut that part of
  // the plane otherwise) of its triangle on that plane holding the triangle's centroid.
  auto cap_marker = [&](int l, const std::array<index_t, 3>& corners) {
    std::array<index_t, 3> key = corners;
    std::sort(key.begin(), key.end());
    const auto same = marker_of.find(key);
    if (same != marker_of.end()) return same->second;
    auto frame_point = [&](index_t i) { return Vec3::of(&tets.points[3 * i]); };
    const Vec3 centroid =
        (frame_point(corners[0]) + frame_point(corners[1]) + frame_point(corners[2])) * (1.0 / 3);
    for (std::size_t i : on_level[l]) {
      const auto& t = tets.boundary[i];
      double s, r;
      if (!coordinates_across(centroid, frame_point(t[0]), frame_point(t[1]), frame_point(t[2]),
                              axis, s, r))
        continue;
      if (s < -1e-9 || r < -1e-9 || s + r > 1 + 1e-9) continue;
      return tets.boundary_marker[i];
    }
    return -1;
  };
  std::vector<int> cap_levels;
  for (const auto& entry : on_level) cap_levels.push_back(entry.first);
  std::vector<std::array<index_t, 3>> boundary;
  std::vector<int> markers;
  extruded_boundary(*stack, section, cap_levels, quad_marker, cap_marker, boundary, markers);
  tets.tets = std::move(made);
  tets.boundary = std::move(boundary);
  tets.boundary_marker = std::move(markers);
  return section.size();
}

std::optional<tetgen::TetrahedralizeOutput> tetrahedralize_swept(
    const tetgen::Tetrahedralizer& tetgen, const tetgen::TetrahedralizeInput& input,
    const SweptSurface& swept, std::size_t nb_surface_nodes, int axis, double spacing,
    std::size_t& extruded) {
  extruded = 0;
  std::vector<double> points;
  points.reserve(3 * input.points.size());
  for (const Vec3& p : input.points) points.insert(points.end(), {p.x, p.y, p.z});
  const std::optional<Stack> found = stack_points(points, axis, spacing);
  if (!found) return std::nullopt;
  const Stack& stack = *found;
  const int bottom = stack.lowest;
  // The facets on each plane (all their points on it), by index.
  std::map<int, std::vector<std::size_t>> facets_on;
  for (std::size_t f = 0; f < input.facets.size(); ++f) {
    int l = kNoLevel;
    bool flat = true;
    for (const auto& polygon : input.facets[f].polygons)
      for (const int n : polygon) {
        if (l == kNoLevel) l = stack.level[n];
        flat = flat && stack.level[n] == l;
      }
    if (flat && l != kNoLevel) facets_on[l].push_back(f);
  }
  if (!facets_on.count(bottom)) return std::nullopt;
  // Each wall side of the first plane with the points added on it (lattice walls: their
  // lattice points), from the loops of the first plane's facets.
  std::unordered_map<int, std::vector<std::pair<std::size_t, std::size_t>>> in_loop;
  for (const std::size_t f : facets_on[bottom])
    for (std::size_t p = 0; p < input.facets[f].polygons.size(); ++p)
      for (std::size_t k = 0; k < input.facets[f].polygons[p].size(); ++k)
        in_loop[input.facets[f].polygons[p][k]].emplace_back(f, p * (std::size_t{1} << 32) + k);
  auto chain_of = [&](int a, int b) {
    std::vector<int> chain;
    for (const auto& [f, where] : in_loop[a]) {
      const auto& loop = input.facets[f].polygons[pair_lo(where)];
      const std::size_t n = loop.size(), k = pair_hi(where);
      if (n < 3) continue;
      for (const int direction : {1, -1}) {
        chain = {a};
        for (std::size_t j = 1; j < n; ++j) {
          const long m = static_cast<long>(n);
          const int next =
              loop[((static_cast<long>(k) + direction * static_cast<long>(j)) % m + m) % m];
          chain.push_back(next);
          if (next == b) return chain;
          if (static_cast<std::size_t>(next) < nb_surface_nodes) break;
        }
      }
    }
    chain.clear();
    return chain;
  };
  // The slab between the first two planes: its points (the facets' first), the first plane's
  // facets, their copies on the second plane, and the walls between.
  const double step = spacing;
  std::vector<int> slab_index(input.points.size(), -1);
  std::vector<int> slab_points;  // global index per slab point
  auto up = [&](int n) { return static_cast<int>(stack.point_at(stack.place[n], bottom + 1)); };
  std::vector<tetgen::Facet> facets;
  for (const std::size_t f : facets_on[bottom]) {
    tetgen::Facet lower = input.facets[f], upper = input.facets[f];
    for (auto& polygon : upper.polygons) {
      for (int& n : polygon) n = up(n);
      std::reverse(polygon.begin(), polygon.end());
    }
    for (Vec3& hole : upper.holes) set_coord(hole, axis, coord(hole, axis) + step);
    facets.push_back(std::move(lower));
    facets.push_back(std::move(upper));
  }
  for (std::size_t i = 0; i < swept.sides.size(); ++i) {
    const int a = swept.sides[i][0], b = swept.sides[i][1];
    if (stack.level[a] != bottom || stack.level[b] != bottom) return std::nullopt;
    std::vector<int> chain = chain_of(a, b);
    if (chain.empty()) return std::nullopt;  // a wall side on no facet
    std::vector<int> polygon = chain;
    for (auto n = chain.rbegin(); n != chain.rend(); ++n) polygon.push_back(up(*n));
    facets.push_back(tetgen::Facet{{polygon}, {}, swept.wall[i][0] + 1});
  }
  for (const auto& facet : facets)
    for (const auto& polygon : facet.polygons)
      for (const int n : polygon) slab_index[n] = 0;
  for (std::size_t n = 0; n < input.points.size(); ++n)
    if (slab_index[n] == 0) slab_index[n] = 1, slab_points.push_back(static_cast<int>(n));
  const std::size_t first_isolated = slab_points.size();
  for (std::size_t n = 0; n < input.points.size(); ++n)
    if (slab_index[n] < 0 && stack.level[n] <= bottom + 1)
      slab_points.push_back(static_cast<int>(n));
  for (std::size_t i = 0; i < slab_points.size(); ++i)
    slab_index[slab_points[i]] = static_cast<int>(i);
  tetgen::TetrahedralizeInput slab;
  for (const int n : slab_points) slab.points.push_back(input.points[n]);
  for (auto& facet : facets)
    for (auto& polygon : facet.polygons)
      for (int& n : polygon) n = slab_index[n];
  slab.facets = std::move(facets);
  slab.first_isolated = first_isolated;
  slab.to_world = input.to_world;
  // TetGen failing on the slab leaves the whole volume to it, as before slabs.
  tetgen::TetrahedralizeOutput made;
  try {
    made = tetgen.run(std::move(slab));
  } catch (const tetgen::TetrahedralizeFailure&) {
    return std::nullopt;
  }
  // TetGen added or moved points: not a stack of planes any more.
  if (made.points.size() != 3 * slab_points.size() || made.nb_nudged > 0) return std::nullopt;
  // The section: the slab's boundary triangles on the first plane, as places.
  std::vector<std::array<int, 3>> section;
  for (const auto& t : made.boundary) {
    const std::array<index_t, 3> global{static_cast<index_t>(slab_points[t[0]]),
                                        static_cast<index_t>(slab_points[t[1]]),
                                        static_cast<index_t>(slab_points[t[2]])};
    if (stack.level_of_triangle(global) == bottom)
      section.push_back({stack.place[global[0]], stack.place[global[1]], stack.place[global[2]]});
  }
  tetgen::TetrahedralizeOutput tets;
  std::vector<double> volume;
  if (!extrude_section(stack, section, points, tets.tets, volume)) return std::nullopt;
  double slab_volume = 0;
  for (std::size_t t = 0; t < made.tets.size() / 4; ++t) {
    const index_t* w = &made.tets[4 * t];
    slab_volume += std::abs(tet_volume(made.points, w[0], w[1], w[2], w[3]));
  }
  if (std::abs(volume[0] - slab_volume) > 1e-9 * slab_volume) return std::nullopt;
  // Markers: a quad over a wall side takes the side's wall face in its slab; a cap triangle the
  // marker of the facet on its plane that holds its centroid.
  std::map<std::pair<int, int>, std::size_t> wall_side;  // places, sorted -> side
  for (std::size_t i = 0; i < swept.sides.size(); ++i) {
    const std::vector<int> chain = chain_of(swept.sides[i][0], swept.sides[i][1]);
    for (std::size_t k = 0; k + 1 < chain.size(); ++k)
      wall_side[std::minmax(stack.place[chain[k]], stack.place[chain[k + 1]])] = i;
  }
  auto quad_marker = [&](int a, int b, int l, const index_t(&)[4]) {
    const auto it = wall_side.find(std::minmax(a, b));
    return it == wall_side.end() ? -1 : swept.wall[it->second][l - bottom] + 1;
  };
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  auto cap_marker = [&](int l, const std::array<index_t, 3>& corners) {
    Vec3 centroid{0, 0, 0};
    for (const index_t n : corners) centroid = centroid + input.points[n] * (1.0 / 3);
    const double cu = coord(centroid, u), cv = coord(centroid, v);
    for (const std::size_t f : facets_on[l]) {
      bool inside = false;  // even-odd rule along +u over the facet's loops
      for (const auto& loop : input.facets[f].polygons)
        for (std::size_t k = 0; k < loop.size() && loop.size() >= 3; ++k) {
          const Vec3 &p = input.points[loop[k]], &q = input.points[loop[(k + 1) % loop.size()]];
          const double pv = coord(p, v), qv = coord(q, v);
          if ((pv > cv) != (qv > cv) &&
              cu < coord(p, u) + (cv - pv) * (coord(q, u) - coord(p, u)) / (qv - pv))
            inside = !inside;
        }
      if (inside) return input.facets[f].marker;
    }
    return -1;
  };
  std::vector<int> cap_levels;
  for (const auto& entry : facets_on) cap_levels.push_back(entry.first);
  extruded_boundary(stack, section, cap_levels, quad_marker, cap_marker, tets.boundary,
                    tets.boundary_marker);
  tets.points = std::move(points);
  tets.nb_restarts = made.nb_restarts;
  tets.command = made.command;
  extruded = section.size();
  return tets;
}

}  // namespace hexmerge::mesher
