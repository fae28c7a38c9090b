#include "hexmerge/occ/mesher/lattice.h"

#include <BRepAdaptor_Curve.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_set>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/sweep.h"

namespace hexmerge::mesher {

namespace {
// A closing pyramid's apex lies at least this fraction of the cell's circumradius outside the
// circumsphere of the core cell beside it (lay_lattice()).
constexpr double kCellSphereClearance = 1e-3;
// The counts per axis lay_lattice() tries together when the best per axis break that.
constexpr std::size_t kCountChoices = 6;
// Uniform cells are this many times h wide at least and at most.
constexpr double kNarrowest = 0.75;
constexpr double kWidest = 1.5;
// A rectilinear axis's cells are within this factor of the uniform spacing the axis would have
// (its neighbours' widths then differ little, and a closing pyramid's apex stays out of the cell's
// circumsphere: 0.75 to 1.5 h cells beside each other lost 410 of gmsh_as1-tu-203's 1,616 cells).
constexpr double kBand = 1.25;
// Rectilinear lattice planes go through the planar faces this many times h wide or wider (twice
// their area over their perimeter): a narrower face gets no lattice point inside, and as a
// lattice face only its loops' triangles and the points refine_facet() adds (an impeller's
// blades: 100 elements under 0.2 with its 2 uniform lattice faces, 347 with 38).
constexpr double kWideFace = 1.0;
// The lattice's box is taken to the outermost planar faces across an axis where the surface's
// nodes pass them by no more than this fraction of h (lay_lattice()).
constexpr double kBoxSnap = 1e-3;
// ... but not where they are the box's sides to round-off (moving the lattice by 1e-15 changed
// gmsh_as1-tu-203's hex volume at its 50k size by 2 points: its cells are cospherical, and
// TetGen's and the recombination's choices among equals follow the last bits).
constexpr double kBoxSame = 1e-9;

// The planes of a rectilinear lattice axis of length L: through 0, L and as many of the planar
// faces' offsets as can be (the most faces; then cells nearest `width`), each gap between two of
// them cut into equal cells within kBand of `width`, as near `width` as that allows; nothing
// when no such cut reaches L.
std::vector<double> rectilinear_ticks(std::vector<double> offsets, double L, double h,
                                      double width) {
  const double tolerance = 1e-7 * h;
  std::sort(offsets.begin(), offsets.end());
  // Stations: 0, the distinct offsets strictly inside, L; the faces at each.
  std::vector<double> at{0.0};
  std::vector<int> faces{0};
  for (double o : offsets) {
    if (o <= tolerance || o >= L - tolerance) continue;
    if (o - at.back() < tolerance) {
      ++faces.back();
    } else {
      at.push_back(o);
      faces.push_back(1);
    }
  }
  at.push_back(L);
  faces.push_back(0);
  // Cells for a gap (0: none fits), and how far their width is from `width`: cells times the
  // difference, over h.
  const auto cut = [&](double gap) -> std::pair<int, double> {
    const int fewest = std::max(1, static_cast<int>(std::ceil(gap / (kBand * width) - 1e-9)));
    const int most = static_cast<int>(std::floor(gap * kBand / width + 1e-9));
    if (most < fewest) return {0, 0.0};
    const int n = std::clamp(static_cast<int>(std::lround(gap / width)), fewest, most);
    return {n, n * std::abs(gap / n - width) / h};
  };
  const std::size_t m = at.size();
  std::vector<int> best_faces(m, -1), from(m, -1);
  std::vector<double> best_off(m, 0.0);
  best_faces[0] = 0;
  for (std::size_t q = 1; q < m; ++q)
    for (std::size_t p = 0; p < q; ++p) {
      if (best_faces[p] < 0) continue;
      const auto [n, off] = cut(at[q] - at[p]);
      if (n == 0) continue;
      const int f = best_faces[p] + faces[q];
      const double o = best_off[p] + off;
      if (f > best_faces[q] || (f == best_faces[q] && o < best_off[q]))
        best_faces[q] = f, best_off[q] = o, from[q] = static_cast<int>(p);
    }
  if (best_faces[m - 1] < 0) return {};  // shorter than a cell: no rectilinear axis
  std::vector<std::size_t> kept;
  for (long q = static_cast<long>(m) - 1; q >= 0; q = from[q]) {
    kept.push_back(static_cast<std::size_t>(q));
    if (q == 0) break;
  }
  std::reverse(kept.begin(), kept.end());
  std::vector<double> ticks{0.0};
  for (std::size_t k = 1; k < kept.size(); ++k) {
    const double lo = at[kept[k - 1]], hi = at[kept[k]];
    const int n = cut(hi - lo).first;
    for (int i = 1; i < n; ++i) ticks.push_back(lo + (hi - lo) * i / n);
    ticks.push_back(hi);
  }
  return ticks;
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
    // The axes the edge runs across; along the others its ends differ by round-off at most
    // (1e-9 of its length), and every node of the edge takes the first end's value there:
    // gmsh_part at h 4.196 had an edge along z whose nodes' y differed in the last bits, and
    // TetGen never ended meshing that lattice face (a run of three nodes collinear to 3e-15).
    const double length = (b - a).norm();
    std::vector<int> across, along;
    for (int c = 0; c < 3; ++c)
      (std::abs(coord(a, c) - coord(b, c)) > 1e-9 * length ? across : along).push_back(c);
    if (across.empty() || t1 <= t0) continue;
    for (int c : along)
      for (const auto& [t, node] : list) set_coord(nodes[node], c, coord(a, c));
    if (across.size() < 2) continue;
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

}  // namespace

double Lattice::widest(int a) const {
  if (uniform(a)) return spacing[a];
  double w = 0;
  for (std::size_t i = 1; i < ticks[a].size(); ++i) w = std::max(w, ticks[a][i] - ticks[a][i - 1]);
  return w;
}

bool Lattice::on_plane(int a, double x, double tolerance) const {
  return on_lattice_plane(ticks[a], spacing[a], x, tolerance);
}

Lattice lay_lattice(const Shape& shape, const Frame& frame, const std::vector<Vec3>& surface_nodes,
                    double h, bool lattice_faces) {
  Lattice lattice;
  lattice.frame = frame;
  Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
          std::numeric_limits<double>::max()};
  Vec3 hi = lo * -1.0;
  for (const Vec3& p : surface_nodes) {
    const Vec3 q = frame.to_frame(p);
    lo = vmin(lo, q), hi = vmax(hi, q);
  }
  const double largest = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  if (h > largest)
    throw InputError("mesh_shape: size " + std::to_string(h) + " is larger than the shape (" +
                         std::to_string(largest) + " across)",
                     Entity::Parameter);
  // The box's sides on the outermost planar faces across each axis where the surface's nodes
  // pass them by at most kBoxSnap h (a tolerant file's curved faces beside them: gmsh_t20_data's
  // top and bottom faces 1.1e-4 mm inside its nodes' box, h 1.637, so that no lattice plane
  // held them and its core ended a cell short of them on both sides).
  lattice.frame.origin = frame.to_world(lo);
  for (const auto& plane : face_planes(shape, lattice.frame)) {
    if (!plane) continue;
    const int a = plane->axis;
    const double o = plane->offset, top = coord(hi, a) - coord(lo, a);
    if (o > kBoxSame * h && o <= kBoxSnap * h) set_coord(lo, a, coord(lo, a) + o);
    if (top - o > kBoxSame * h && top - o <= kBoxSnap * h) set_coord(hi, a, coord(lo, a) + o);
  }
  lattice.extent = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
  const auto& extent = lattice.extent;
  lattice.largest = std::max({extent[0], extent[1], extent[2]});
  lattice.frame.origin = frame.to_world(lo);  // lattice planes through the box's lower corner
  lattice.face_plane = face_planes(shape, lattice.frame);
  const auto& face_plane = lattice.face_plane;
  std::vector<double> offsets[3], wide[3];  // wide: of faces at least h across (kWideFace)
  for (const auto& plane : face_plane)
    if (plane) {
      offsets[plane->axis].push_back(plane->offset);
      if (plane->width >= kWideFace * h) wide[plane->axis].push_back(plane->offset);
    }
  const double plane_tolerance = 1e-7 * h;
  // Cells per axis: about h wide, chosen so that as many axis-normal planar faces as possible
  // lie on lattice planes (the box's own faces always do). Per axis, the counts from 1.5 h to
  // 0.75 h wide, best first: more faces on lattice planes, then nearer L / h.
  struct Count {
    int n, hits;
    double off;  // |n - L / h|
  };
  std::array<std::vector<Count>, 3> counts;
  for (int a = 0; a < 3; ++a) {
    const double L = extent[a];
    const int lo_n = std::max(1, static_cast<int>(std::floor(L / (kWidest * h))));
    const int hi_n = std::max(lo_n, static_cast<int>(std::ceil(L / (kNarrowest * h))));
    for (int n = lo_n; n <= hi_n; ++n) {
      int hits = 0;
      for (double o : offsets[a]) hits += on_lattice_plane({}, L / n, o, plane_tolerance);
      counts[a].push_back({n, hits, std::abs(n - L / h)});
    }
    std::stable_sort(counts[a].begin(), counts[a].end(), [](const Count& x, const Count& y) {
      return x.hits != y.hits ? x.hits > y.hits : x.off < y.off;
    });
  }
  // The cells' Delaunay tets hold only where the centre of the cell across a face (a closing
  // pyramid's apex) lies outside the cell's circumsphere: every spacing above half the cell's
  // diagonal. Counts chosen per axis alone broke that on thin extents (gmsh_as1-tu-203 at its
  // 50k size: spacings 0.84, 1.25 and 1.00 h, TetGen joined the apexes across 634 of its 1,707
  // core cells): the best counts that keep it are taken, among the best few per axis (more
  // faces on lattice planes in all, then nearer L / h); the best per axis where none does.
  const auto spacing_of = [&](int a, const Count& c) { return extent[a] / c.n; };
  const auto delaunay_cells = [&](const Count& x, const Count& y, const Count& z) {
    const double s[3] = {spacing_of(0, x), spacing_of(1, y), spacing_of(2, z)};
    const double half_diagonal = 0.5 * std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    return std::min({s[0], s[1], s[2]}) > (1 + kCellSphereClearance) * half_diagonal;
  };
  std::array<Count, 3> chosen{counts[0][0], counts[1][0], counts[2][0]};
  if (!delaunay_cells(chosen[0], chosen[1], chosen[2])) {
    bool found = false;
    const std::size_t few[3] = {std::min<std::size_t>(kCountChoices, counts[0].size()),
                                std::min<std::size_t>(kCountChoices, counts[1].size()),
                                std::min<std::size_t>(kCountChoices, counts[2].size())};
    for (std::size_t i = 0; i < few[0]; ++i)
      for (std::size_t j = 0; j < few[1]; ++j)
        for (std::size_t k = 0; k < few[2]; ++k) {
          const Count &x = counts[0][i], &y = counts[1][j], &z = counts[2][k];
          if (!delaunay_cells(x, y, z)) continue;
          const int hits = x.hits + y.hits + z.hits,
                    best_hits = chosen[0].hits + chosen[1].hits + chosen[2].hits;
          const double off = x.off + y.off + z.off,
                       best_off = chosen[0].off + chosen[1].off + chosen[2].off;
          if (!found || hits > best_hits || (hits == best_hits && off < best_off))
            chosen = {x, y, z}, found = true;
        }
    if (!found) chosen = {counts[0][0], counts[1][0], counts[2][0]};
  }
  for (int a = 0; a < 3; ++a) {
    lattice.cells[a] = chosen[a].n;
    lattice.spacing[a] = extent[a] / chosen[a].n;
    // Rectilinear where that puts more planar faces at least h wide on lattice planes than the
    // uniform spacing chosen (a stepped part: faces at offsets no one spacing divides).
    if (lattice_faces) {
      std::vector<double> ticks = rectilinear_ticks(wide[a], extent[a], h, lattice.spacing[a]);
      const auto wide_hits = [&](const std::vector<double>& planes, double spacing) {
        int hits = 0;
        for (double o : wide[a]) hits += on_lattice_plane(planes, spacing, o, plane_tolerance);
        return hits;
      };
      if (!ticks.empty() && wide_hits(ticks, 0) > wide_hits({}, lattice.spacing[a])) {
        lattice.cells[a] = static_cast<int>(ticks.size()) - 1;
        lattice.spacing[a] = extent[a] / lattice.cells[a];
        lattice.ticks[a] = std::move(ticks);
      }
    }
  }

  std::vector<bool>& lattice_face = lattice.lattice_face;
  lattice_face.assign(shape.faces.Extent(), false);
  for (int f = 0; f < shape.faces.Extent(); ++f) {
    if (!face_plane[f]) continue;
    lattice_face[f] = lattice_faces &&
                      lattice.on_plane(face_plane[f]->axis, face_plane[f]->offset, plane_tolerance);
    lattice.nb_lattice_faces += lattice_face[f];
  }
  std::vector<bool>& lattice_edge = lattice.lattice_edge;
  lattice_edge.assign(shape.edges.Extent(), false);
  for (int e = 0; e < shape.edges.Extent(); ++e) {
    const auto& around = shape.edge_faces[e];
    // Between lattice faces on two planes: on a lattice line, where lattice points lie. A seam
    // between faces on one plane (a planar face split in two) lies on no lattice line.
    const auto other_plane = [&](int f) {
      const AxisPlane &p = *face_plane[f], &q = *face_plane[around[0]];
      return p.axis != q.axis || std::abs(p.offset - q.offset) > plane_tolerance;
    };
    lattice_edge[e] = !around.empty() && std::all_of(around.begin(), around.end(), [&](int f) {
      return lattice_face[f];
    }) && std::any_of(around.begin(), around.end(), other_plane);
  }
  return lattice;
}

std::vector<Vec3> frame_nodes(const Shape& shape, const Surface& surface, const Lattice& lattice,
                              int sweep_axis, const SweptSurface& swept) {
  // Everything below in frame coordinates; nodes of lattice faces exactly on their planes.
  std::vector<Vec3> nodes(surface.nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i)
    nodes[i] = lattice.frame.to_frame(surface.nodes[i]);
  for (const SurfaceTriangle& t : surface.triangles)
    if (lattice.lattice_face[t.face])
      for (int n : t.node) {
        const AxisPlane& plane = *lattice.face_plane[t.face];
        const double k = std::round(lattice.cells_at(plane.axis, coord(nodes[n], plane.axis)));
        set_coord(nodes[n], plane.axis, lattice.at(plane.axis, k));
      }
  align_straight_edges(shape, surface, lattice.lattice_face, lattice.largest, nodes);
  if (sweep_axis >= 0) {
    const int a = sweep_axis;
    // Every node exactly on its lattice plane, and across the axis exactly where the node on the
    // bottom plane it repeats is: the slabs are then equal to the last bit.
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const double level = std::round(lattice.cells_at(a, coord(nodes[i], a)));
      Vec3 p = nodes[swept.base[i]];
      set_coord(p, a, lattice.at(a, level));
      nodes[i] = p;
    }
  }
  return nodes;
}

Surroundings::Surroundings(const std::vector<Vec3>& nodes, const Surface& surface,
                           const Lattice& lattice, double h)
    : box_lo(Vec3{0, 0, 0} - Vec3{2 * h, 2 * h, 2 * h}),
      box_hi(Vec3{lattice.extent[0], lattice.extent[1], lattice.extent[2]} +
             Vec3{2 * h, 2 * h, 2 * h}),
      curved(nodes, box_lo, box_hi, h),
      every_face(nodes, box_lo, box_hi, h),
      surface_points(box_lo, box_hi, h),
      layer_points(box_lo, box_hi, h),
      core_points(box_lo, box_hi, h),
      core_balls(box_lo, box_hi, h),
      buffer_cells(box_lo, box_hi, h),
      nodes_(nodes) {
  for (const SurfaceTriangle& t : surface.triangles) {
    if (!lattice.lattice_face[t.face]) curved.add(t.node);
    every_face.add(t.node);
  }
  for (const Vec3& p : nodes) surface_points.add(p);
  for (const SurfaceTriangle& t : surface.triangles)
    if (lattice.lattice_face[t.face]) {
      const AxisPlane& plane = *lattice.face_plane[t.face];
      plane_triangles_[{plane.axis, std::lround(lattice.cells_at(plane.axis, plane.offset))}]
          .push_back(&t);
    }
}

int Surroundings::face_on_plane(const Vec3& q, const int (&index)[3], int axis) const {
  auto it = plane_triangles_.find({axis, index[axis]});
  return it == plane_triangles_.end() ? -1 : face_holding(q, it->second, nodes_, axis);
}

int Surroundings::on_lattice_face(const Vec3& q, const int (&index)[3]) const {
  for (int a = 0; a < 3; ++a) {
    const int face = face_on_plane(q, index, a);
    if (face >= 0) return face;
  }
  return -1;
}

int Surroundings::lattice_planes(const Vec3& q, const int (&index)[3]) const {
  int planes = 0;
  for (int a = 0; a < 3; ++a)
    if (face_on_plane(q, index, a) >= 0) planes |= 1 << a;
  return planes;
}

bool Surroundings::ball_is_empty(const Vec3& centre, double r) const {
  const double inner = r * (1 - 1e-9);
  return !curved.any_within(centre, inner) && !surface_points.any_within(centre, inner) &&
         !layer_points.any_within(centre, inner);
}

Parity::Parity(const std::vector<Vec3>& nodes, const Surface& surface,
               const std::vector<int>& face_solid_count, const Surroundings& around, double h)
    : nodes_(nodes),
      h_(h),
      yz_(Vec3{around.box_lo.y, around.box_lo.z, 0}, Vec3{around.box_hi.y, around.box_hi.z, 0}, h) {
  for (const SurfaceTriangle& t : surface.triangles)
    if (face_solid_count[t.face] <= 1) triangles_.push_back(t.node);
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    const auto& t = triangles_[i];
    Vec3 a{nodes[t[0]].y, nodes[t[0]].z, 0}, b{nodes[t[1]].y, nodes[t[1]].z, 0},
        c{nodes[t[2]].y, nodes[t[2]].z, 0};
    yz_.add(static_cast<int>(i), vmin(a, vmin(b, c)), vmax(a, vmax(b, c)));
  }
}

std::vector<double> Parity::crossings(double y, double z) const {
  y += 1.234567e-7 * h_, z += 2.345678e-7 * h_;
  std::vector<double> xs;
  std::unordered_set<int> seen;
  yz_.any_in(Vec3{y, z, 0}, Vec3{y, z, 0}, [&](int i) {
    if (!seen.insert(i).second) return false;
    const auto& t = triangles_[i];
    const Vec3 &p0 = nodes_[t[0]], &p1 = nodes_[t[1]], &p2 = nodes_[t[2]];
    double u, v;
    if (!coordinates_across(Vec3{0, y, z}, p0, p1, p2, 0, u, v)) return false;
    if (u < 0 || v < 0 || u + v > 1) return false;
    xs.push_back(p0.x + u * (p1.x - p0.x) + v * (p2.x - p0.x));
    return false;
  });
  std::sort(xs.begin(), xs.end());
  return xs;
}

bool Parity::inside_given(const std::vector<double>& xs, double x) {
  return (std::lower_bound(xs.begin(), xs.end(), x) - xs.begin()) % 2 == 1;
}

KeptPoints keep_lattice_points(const Lattice& lattice, const Surroundings& around,
                               const Parity& parity, double keep_distance, double margin,
                               int sweep_axis) {
  // Lattice points: kept when inside (or on a lattice face) and far enough from the other faces.
  const int n0 = lattice.cells[0] + 1, n1 = lattice.cells[1] + 1, n2 = lattice.cells[2] + 1;
  KeptPoints out;
  std::vector<char>& kept = out.kept;
  std::vector<int>& kept_face = out.face;
  kept.assign(static_cast<std::size_t>(n0) * n1 * n2, 0);
  kept_face.assign(kept.size(), -1);
  const double same = 1e-6 * std::min({lattice.spacing[0], lattice.spacing[1], lattice.spacing[2]});
  for (int k = 0; k < n2; ++k)
    for (int j = 0; j < n1; ++j) {
      const std::vector<double> xs = parity.crossings(lattice.at(1, j), lattice.at(2, k));
      for (int i = 0; i < n0; ++i) {
        const Vec3 q = lattice.point(i, j, k);
        const int index[3] = {i, j, k};
        const int face = around.on_lattice_face(q, index);
        if (face < 0 && !Parity::inside_given(xs, q.x)) continue;
        // A point on an edge between lattice faces (the edge's side is split at the lattice
        // points only, and without them stays as long as the edge) stays near other faces, and
        // near surface nodes off the edge: FreeCAD's I22_2_5_16withEPL22_6_16.stp at h 0.812,
        // an E core's legs 0.1 mm below an I core, their top faces' sides 15.8 mm long, tets on
        // them of scaled Jacobian 0.005.
        // Swept: a point on a wall (FreeCAD's PathTests/test_holes00: holes 0.5 mm from a side,
        // h 6.3, the side's points dropped near them, its tets on a side 56 mm long flat).
        int planes = -1;  // the planes of its edge's lines (0: on no edge), asked where needed
        const auto on_edge = [&] {
          if (planes >= 0) return planes != 0;
          planes = face >= 0 ? around.lattice_planes(q, index) : 0;
          if (sweep_axis < 0)
            planes = (planes & (planes - 1)) ? planes : 0;  // two bits or three
          else
            planes = (planes & ~(1 << sweep_axis)) ? planes | 1 << sweep_axis : 0;
          return planes != 0;
        };
        if (around.curved.any_within(q, keep_distance) && !on_edge()) continue;
        if (around.layer_points.any_within(q, margin)) continue;
        // On a lattice face, a surface node near it but not at it (a side of a lattice edge
        // split to a local size) would leave a sliver of a side between the two; on an edge,
        // such a node on one of its lines.
        const auto on_its_line = [&](const Vec3& p) {
          int shared = 0;
          for (int a = 0; a < 3; ++a)
            shared += (planes >> a & 1) && std::abs(coord(p, a) - coord(q, a)) < same;
          return shared >= 2;
        };
        if (face >= 0 && around.surface_points.any_within(q, margin) &&
            !around.surface_points.any_within(q, same) &&
            (!on_edge() || around.surface_points.any_within(q, margin, on_its_line)))
          continue;
        // Swept, a wall's point near where its side meets another face (a node on its line, a
        // bore's corner on a symmetry plane) leaves the room the layers carried onto the wall
        // take there, as it did when dropped near the curved face.
        if (sweep_axis >= 0 && on_edge() && !around.surface_points.any_within(q, same) &&
            around.surface_points.any_within(q, keep_distance, on_its_line))
          continue;
        kept[lattice.point_index(i, j, k)] = 1;
        kept_face[lattice.point_index(i, j, k)] = face;
      }
    }
  return out;
}

bool in_kept_square(const Lattice& lattice, const KeptPoints& kept, const Vec3& q, int axis) {
  int at[3];
  at[axis] = static_cast<int>(std::lround(lattice.cells_at(axis, coord(q, axis))));
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  for (const int c : {u, v}) {
    at[c] = static_cast<int>(std::floor(lattice.cells_at(c, coord(q, c))));
    if (at[c] < 0 || at[c] >= lattice.cells[c]) return false;
  }
  for (int corner = 0; corner < 4; ++corner) {
    int c[3] = {at[0], at[1], at[2]};
    c[u] += corner & 1, c[v] += corner >> 1;
    if (!kept.kept[lattice.point_index(c[0], c[1], c[2])]) return false;
  }
  return true;
}

namespace {
// The index of cell (i, j, k) (i fastest).
std::size_t cell_index_of(const Lattice& lattice, int i, int j, int k) {
  return (static_cast<std::size_t>(k) * lattice.cells[1] + j) * lattice.cells[0] + i;
}
// Half the diagonal of cell (i, j, k): its circumradius.
double half_diagonal_of(const Lattice& lattice, int i, int j, int k) {
  const double s[3] = {lattice.width(0, i), lattice.width(1, j), lattice.width(2, k)};
  return 0.5 * std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
}
// The sphere through the corners of face dir of cell (i, j, k) and the apex of its closing
// pyramid (the centre of the cell n across).
std::pair<Vec3, double> pyramid_sphere_of(const Lattice& lattice, int i, int j, int k, int dir,
                                          const int (&n)[3]) {
  const int axis = dir / 2, side = dir % 2 ? 1 : -1;
  const int ijk[3] = {i, j, k};
  const double a = 0.5 * lattice.width(axis, ijk[axis]);  // the cell's centre to the face
  const double d = 0.5 * lattice.width(axis, n[axis]);    // the face to the apex
  double rho2 = 0;
  for (int b = 0; b < 3; ++b)
    if (b != axis) rho2 += 0.25 * lattice.width(b, ijk[b]) * lattice.width(b, ijk[b]);
  const double c = (d * d - rho2) / (2 * d);
  Vec3 to_face{0, 0, 0}, towards{0, 0, 0};
  set_coord(to_face, axis, side * a);
  set_coord(towards, axis, side * d);  // from the face's centre to the apex
  const Vec3 face_centre = lattice.cell_centre(i, j, k) + to_face;
  return {face_centre + towards * (c / d), d - c};
}
}  // namespace

std::array<Vec3, 8> buffer_hex_corners(const std::array<Vec3, 4>& base,
                                       const std::array<Vec3, 4>& top, bool up) {
  static constexpr int kBits[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::array<Vec3, 8> corner;
  for (int m = 0; m < 4; ++m) {
    const int u = kBits[m][0], v = kBits[m][1];
    const int bits = up ? u + 2 * v : v + 2 * u;
    corner[static_cast<std::size_t>(bits)] = base[m];
    corner[static_cast<std::size_t>(bits + 4)] = top[m];
  }
  return corner;
}

Vec3 CoreLayout::point_at(const Lattice& lattice, std::size_t p) const {
  const Vec3 q = lattice.point(lattice.point_ijk(p));
  const auto it = pulled.node.find(p);
  return it == pulled.node.end() ? q : q + it->second;
}

Vec3 CoreLayout::apex_at(const Lattice& lattice, std::size_t c) const {
  const Vec3 q = apex_home(lattice, inner_apex, c);
  const auto it = pulled.apex.find(c);
  return it == pulled.apex.end() ? q : q + it->second;
}

CoreLayout lay_core(const Lattice& lattice, const Surroundings& around, const Parity& parity,
                    const KeptPoints& kept_points, int sweep_axis, double h, bool pull) {
  // The hexahedral core: cells with 8 kept corners whose circumsphere holds nothing else; then
  // every quad face between the core and another cell inside needs a closing pyramid whose apex
  // is that cell's centre and whose circumsphere holds nothing else, or the core cell goes.
  const int c0 = lattice.cells[0], c1 = lattice.cells[1], c2 = lattice.cells[2];
  const std::vector<char>& kept = kept_points.kept;
  CoreLayout out;
  CoreCounts& counts = out.counts;
  auto cell_index = [&](int i, int j, int k) { return cell_index_of(lattice, i, j, k); };
  // The cell across face dir (0..5: -x, +x, -y, +y, -z, +z) of cell (i, j, k), in n; whether it
  // is in the lattice.
  auto across = [&](int i, int j, int k, int dir, int(&n)[3]) {
    n[0] = i, n[1] = j, n[2] = k;
    n[dir / 2] += dir % 2 ? 1 : -1;
    return n[0] >= 0 && n[0] < c0 && n[1] >= 0 && n[1] < c1 && n[2] >= 0 && n[2] < c2;
  };
  auto cell_centre = [&](int i, int j, int k) { return lattice.cell_centre(i, j, k); };
  auto half_diagonal = [&](int i, int j, int k) { return half_diagonal_of(lattice, i, j, k); };
  std::vector<char> core(static_cast<std::size_t>(c0) * c1 * c2, 0);
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        bool all = true;
        for (int corner = 0; corner < 8 && all; ++corner)
          all = kept[lattice.point_index(i + (corner & 1), j + ((corner >> 1) & 1),
                                         k + ((corner >> 2) & 1))];
        if (!all) continue;
        const Vec3 centre = cell_centre(i, j, k);
        if (!parity.inside(centre) || !around.ball_is_empty(centre, half_diagonal(i, j, k)))
          continue;
        core[cell_index(i, j, k)] = 1;
      }
  auto pyramid_sphere = [&](int i, int j, int k, int dir, const int(&n)[3]) {
    return pyramid_sphere_of(lattice, i, j, k, dir, n);
  };
  // Whether the centre of cell n across face dir of cell (i, j, k) lies in that cell's
  // circumsphere.
  auto narrow = [&](int i, int j, int k, int dir, const int(&n)[3]) {
    const int axis = dir / 2, ijk[3] = {i, j, k};
    return 0.5 * (lattice.width(axis, ijk[axis]) + lattice.width(axis, n[axis])) <=
           (1 + kCellSphereClearance) * half_diagonal(i, j, k);
  };
  // Per cell across a core face whose centre is outside: the apex inside, nearer the face, that
  // closes it (and the other core faces towards that cell, where it closes them too).
  std::unordered_map<std::size_t, Vec3> inner_apex;
  // Whether an apex nearer face dir of cell (i, j, k) than the centre of cell n across (which
  // is outside) closes it: the one cell n has already, or a new one (place_inner_apex()).
  auto inner_apex_closes = [&](int i, int j, int k, int dir, const int(&n)[3]) {
    const std::size_t a = cell_index(n[0], n[1], n[2]);
    const auto it = inner_apex.find(a);
    const std::optional<Vec3> at = place_inner_apex(
        lattice, around, parity, PyramidFace{{i, j, k}, dir, {n[0], n[1], n[2]}},
        it == inner_apex.end() ? std::nullopt : std::optional<Vec3>(it->second), h);
    if (at) inner_apex.emplace(a, *at);
    return at.has_value();
  };
  // Per directed face (cell, direction 0..5): 0 unknown, 1 boundary (no pyramid needed),
  // 2 pyramid possible, 3 impossible.
  std::vector<std::uint8_t> face_state(core.size() * 6, 0);
  auto face_kind = [&](int i, int j, int k, int dir) -> std::uint8_t {
    std::uint8_t& state = face_state[cell_index(i, j, k) * 6 + dir];
    if (state) return state;
    const int axis = dir / 2, side = dir % 2 ? 1 : -1;
    // Swept: the prisms and hexahedra of the slab close the core's sides.
    if (sweep_axis >= 0 && axis != sweep_axis) return state = 1;
    int n[3];
    if (!across(i, j, k, dir, n)) return state = 1;  // on the lattice's box: on the boundary
    const Vec3 apex = cell_centre(n[0], n[1], n[2]);
    if (!parity.inside(apex)) {
      // The cell across is outside: the face needs no pyramid when it lies on the boundary (its
      // corners on lattice faces); else the surface passes between the face and the apex, and
      // the tets of that gap would leave the face open, unless (with `pull`) an apex nearer the
      // face closes it.
      const int plane = (side > 0) + (axis == 0 ? i : axis == 1 ? j : k);
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int corner = 0; corner < 4; ++corner) {
        int c[3] = {i, j, k};
        c[axis] = plane;
        c[u] += corner & 1, c[v] += corner >> 1;
        if (kept_points.face[lattice.point_index(c[0], c[1], c[2])] < 0)
          return state = pull && sweep_axis < 0 && inner_apex_closes(i, j, k, dir, n) ? 2 : 3;
      }
      return state = 1;
    }
    // The apex outside the cell's circumsphere, or Delaunay joins it to the cell's corners (a
    // rectilinear axis's narrow cell beside a wide one; see lay_lattice()): then, with `pull`,
    // the cell and its pyramid are constrained (gmsh_Angled at its 50k size: 254 of its 1,793
    // cells went so, and 90 more with them), where the pyramid is good enough.
    if (narrow(i, j, k, dir, n)) {
      if (!pull || sweep_axis >= 0) return state = 3;
      if (closing_pyramid_quality(
              lattice_points(
                  lattice, base_corners(lattice, PyramidFace{{i, j, k}, dir, {n[0], n[1], n[2]}})),
              apex, dir % 2 == 1) < kCorePyramidFloor)
        return state = 3;
    }
    const auto [centre, r] = pyramid_sphere(i, j, k, dir, n);
    // The apex off every face: on a face its sphere can touch the face's plane at the apex
    // only (a face across the pyramid's axis), and the apex makes flat tets with the face's
    // triangles (gmsh_SampleCrankshaft4A at h 4.61: apexes on a planar end face half a cell
    // off the lattice planes).
    const bool ok = around.ball_is_empty(centre, r) &&
                    !around.surface_points.any_within(apex, kApexNodeClearance * h) &&
                    !around.every_face.any_within(apex, kApexClearance * h) &&
                    !around.layer_points.any_within(apex, 0.25 * h);
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
  std::vector<PyramidFace> pyramid_faces;
  std::vector<char> apex_cell(core.size(), 0);
  // The apexes in the circumsphere of a cell they close (only with `pull`).
  std::vector<char> narrow_apex(core.size(), 0);
  std::vector<std::size_t> narrow_apexes;
  std::unordered_set<std::size_t> used_inner;  // the inner apexes of the core's faces
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        if (!core[cell_index(i, j, k)]) continue;
        ++counts.nb_core_cells;
        for (int dir = 0; dir < 6; ++dir) {
          int n[3];
          if (!across(i, j, k, dir, n) || core[cell_index(n[0], n[1], n[2])]) continue;
          if (face_kind(i, j, k, dir) != 2) continue;
          apex_cell[cell_index(n[0], n[1], n[2])] = 1;
          pyramid_faces.push_back({{i, j, k}, dir, {n[0], n[1], n[2]}});
          const std::size_t a = cell_index(n[0], n[1], n[2]);
          if (inner_apex.count(a)) {
            used_inner.insert(a);
          } else if (narrow(i, j, k, dir, n)) {
            if (!narrow_apex[a]) narrow_apexes.push_back(a);
            narrow_apex[a] = 1;
            ++counts.nb_narrow_pyramids;
          }
        }
      }
  for (auto it = inner_apex.begin(); it != inner_apex.end();)
    it = used_inner.count(it->first) ? std::next(it) : inner_apex.erase(it);
  counts.nb_inner_apexes = inner_apex.size();
  // The core pulled towards the surface: the lattice steps, not the surface, set where the core
  // ends (its closing pyramids' apexes lie up to a cell from the faces), so each core node on a
  // closing pyramid's base moves out along the bases' normals, the apexes with their bases,
  // until the apexes come within kPullTarget h of the faces, as far as the cells and pyramids
  // stay good (pull_core()).
  std::vector<char> core_corner(kept.size(), 0);
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i)
        if (core[cell_index(i, j, k)])
          for (int corner = 0; corner < 8; ++corner)
            core_corner[lattice.point_index(i + (corner & 1), j + ((corner >> 1) & 1),
                                            k + ((corner >> 2) & 1))] = 1;
  if (pull && sweep_axis < 0)
    out.pulled = pull_core(lattice, around, parity, kept_points, core, core_corner, pyramid_faces,
                           inner_apex, h);
  out.core = std::move(core);
  out.core_corner = std::move(core_corner);
  out.pyramid_faces = std::move(pyramid_faces);
  out.apex_cell = std::move(apex_cell);
  out.narrow_apexes = std::move(narrow_apexes);
  out.inner_apex = std::move(inner_apex);
  return out;
}

CoreCounts emit_core(const Lattice& lattice, const CoreLayout& layout, const BufferCells& buffer,
                     const KeptPoints& kept_points, double h, Surroundings& around,
                     InsertedPoints& inserted) {
  const int c0 = lattice.cells[0], c1 = lattice.cells[1], c2 = lattice.cells[2];
  const int n0 = lattice.cells[0] + 1, n1 = lattice.cells[1] + 1, n2 = lattice.cells[2] + 1;
  const std::vector<char>& kept = kept_points.kept;
  const std::vector<char>& core = layout.core;
  const PulledCore& pulled = layout.pulled;
  const std::unordered_map<std::size_t, Vec3>& inner_apex = layout.inner_apex;
  const std::vector<PyramidFace>& pyramid_faces = layout.pyramid_faces;
  CoreCounts counts = layout.counts;
  auto cell_index = [&](int i, int j, int k) { return cell_index_of(lattice, i, j, k); };
  auto cell_centre = [&](int i, int j, int k) { return lattice.cell_centre(i, j, k); };
  auto half_diagonal = [&](int i, int j, int k) { return half_diagonal_of(lattice, i, j, k); };
  auto pyramid_sphere = [&](int i, int j, int k, int dir, const int(&n)[3]) {
    return pyramid_sphere_of(lattice, i, j, k, dir, n);
  };
  auto point_at = [&](std::size_t p) { return layout.point_at(lattice, p); };
  auto apex_at = [&](std::size_t c) { return layout.apex_at(lattice, c); };
  // The buffer: the pyramids its hexahedra replace, the apexes no pyramid is left at, the core
  // cells under its hexahedra and the apexes its pyramids share with the core's.
  std::vector<char> buffered(pyramid_faces.size(), 0);
  std::unordered_set<std::size_t> under_hex, shared_apex;
  for (const BufferCells::Hex& hex : buffer.hexes) {
    buffered[hex.face] = 1;
    const PyramidFace& f = pyramid_faces[hex.face];
    under_hex.insert(cell_index(f.c[0], f.c[1], f.c[2]));
  }
  for (const BufferCells::SidePyramid& p : buffer.pyramids) shared_apex.insert(p.apex_cell);
  std::vector<char> apex_left(core.size(), 0);  // a pyramid of the core is left at the apex
  for (std::size_t f = 0; f < pyramid_faces.size(); ++f)
    if (!buffered[f]) {
      const PyramidFace& face = pyramid_faces[f];
      apex_left[cell_index(face.n[0], face.n[1], face.n[2])] = 1;
    }
  auto top_at = [&](std::size_t p) { return buffer.top_of.at(p); };
  // A ball holding points a, ..., (their centroid, the farthest from it).
  auto ball_of = [](const Vec3* points, int count) {
    Vec3 centre{0, 0, 0};
    for (int m = 0; m < count; ++m) centre = centre + points[m];
    centre = centre * (1.0 / count);
    double r = 0;
    for (int m = 0; m < count; ++m) r = std::max(r, (points[m] - centre).norm());
    return std::pair<Vec3, double>{centre, r};
  };
  BallSet moved_balls(around.box_lo, around.box_hi, h);
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        if (!core[cell_index(i, j, k)]) continue;
        Vec3 corners[8];
        bool moved = false;
        for (int corner = 0; corner < 8; ++corner) {
          const std::size_t p = lattice.point_index(i + (corner & 1), j + ((corner >> 1) & 1),
                                                    k + ((corner >> 2) & 1));
          corners[corner] = point_at(p);
          moved = moved || pulled.node.count(p);
        }
        if (!moved) {
          around.core_balls.add(cell_centre(i, j, k), half_diagonal(i, j, k));
          continue;
        }
        const auto [centre, r] = ball_of(corners, 8);
        around.core_balls.add(centre, r);
        moved_balls.add(centre, r);
      }
  for (std::size_t index = 0; index < pyramid_faces.size(); ++index) {
    if (buffered[index]) continue;
    const PyramidFace& f = pyramid_faces[index];
    const std::size_t apex = cell_index(f.n[0], f.n[1], f.n[2]);
    Vec3 points[5];
    bool moved = pulled.apex.count(apex) > 0 || inner_apex.count(apex) > 0;
    const std::array<std::size_t, 4> base = base_corners(lattice, f);
    for (int corner = 0; corner < 4; ++corner) {
      points[corner] = point_at(base[corner]);
      moved = moved || pulled.node.count(base[corner]);
    }
    if (!moved) {
      const auto [centre, r] = pyramid_sphere(f.c[0], f.c[1], f.c[2], f.dir, f.n);
      around.core_balls.add(centre, r);
      continue;
    }
    points[4] = apex_at(apex);
    const auto [centre, r] = ball_of(points, 5);
    around.core_balls.add(centre, r);
    moved_balls.add(centre, r);
  }
  // The buffer's cells' corners: a hexahedron's base (base_corners() order) and tops, a side
  // pyramid's base (around, from lo's corner) and apex.
  auto hex_corners = [&](const BufferCells::Hex& hex) {
    const std::array<std::size_t, 4> base = base_corners(lattice, pyramid_faces[hex.face]);
    std::array<Vec3, 8> at;
    for (int m = 0; m < 4; ++m) at[m] = point_at(base[m]), at[4 + m] = hex.top[m];
    return at;
  };
  auto side_corners = [&](const BufferCells::SidePyramid& p) {
    return std::array<Vec3, 5>{point_at(p.lo), point_at(p.hi), top_at(p.hi), top_at(p.lo),
                               apex_at(p.apex_cell)};
  };
  // The pulled cells and pyramids are no longer cospherical: their faces go to TetGen as
  // constraints (each quad split on its diagonal from its least corner, as the cells' six tets
  // around their diagonal from the least corner split it), but those on lattice faces (the
  // surface's own). So do the buffer's cells, but their faces on the surface.
  if (!pulled.node.empty() || !layout.narrow_apexes.empty() || !inner_apex.empty() ||
      !buffer.hexes.empty()) {
    // By lattice ids: points 0.., centres after, then the tops of the points.
    std::set<std::array<std::size_t, 3>> seen;
    const std::size_t centres = kept.size(), tops = centres + core.size();
    auto add_triangle = [&](std::size_t a, std::size_t b, std::size_t c, const Vec3& pa,
                            const Vec3& pb, const Vec3& pc) {
      if (a < centres && b < centres && c < centres && kept_points.face[a] >= 0 &&
          kept_points.face[b] >= 0 && kept_points.face[c] >= 0)
        return;
      std::array<std::size_t, 3> key{a, b, c};
      std::sort(key.begin(), key.end());
      if (seen.insert(key).second) inserted.constraints.push_back({pa, pb, pc});
    };
    // The face across `axis` at plane index `plane`, its least corner (u, v) = (p, q).
    auto add_quad = [&](int axis, int plane, int p, int q) {
      const std::array<std::size_t, 4> id = face_corners(lattice, axis, plane, p, q);
      Vec3 at[4];
      for (int m = 0; m < 4; ++m) at[m] = point_at(id[m]);
      add_triangle(id[0], id[1], id[2], at[0], at[1], at[2]);
      add_triangle(id[0], id[2], id[3], at[0], at[2], at[3]);
    };
    // The moved points: a cell or pyramid whose circumsphere holds one is no longer Delaunay
    // either, and is constrained too.
    PointSet moved_points(around.box_lo, around.box_hi, h);
    for (const auto& [p, d] : pulled.node) moved_points.add(point_at(p));
    for (const auto& [a, d] : pulled.apex) moved_points.add(apex_at(a));
    for (const std::size_t a : layout.narrow_apexes)
      if (!pulled.apex.count(a)) moved_points.add(apex_at(a));
    for (const auto& [a, at] : inner_apex)
      if (!pulled.apex.count(a)) moved_points.add(apex_at(a));
    for (const auto& [p, at] : buffer.top_of) moved_points.add(at);
    for (int k = 0; k < c2; ++k)
      for (int j = 0; j < c1; ++j)
        for (int i = 0; i < c0; ++i) {
          if (!core[cell_index(i, j, k)]) continue;
          bool moved =
              under_hex.count(cell_index(i, j, k)) > 0 ||
              moved_points.any_within(cell_centre(i, j, k), half_diagonal(i, j, k) * (1 + 1e-6));
          for (int corner = 0; corner < 8 && !moved; ++corner)
            moved = pulled.node.count(lattice.point_index(i + (corner & 1), j + ((corner >> 1) & 1),
                                                          k + ((corner >> 2) & 1))) > 0;
          if (!moved) continue;
          // The six tets around the diagonal from corner 0 to corner 7 (bits x, y, z).
          InsertedPoints::Split split;
          for (int b = 0; b < 8; ++b)
            split.corners.push_back(
                point_at(lattice.point_index(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1))));
          for (const auto& q : kKuhnPaths) split.tets.push_back({0, q[0], q[1], 7});
          inserted.splits.push_back(std::move(split));
          const int ijk[3] = {i, j, k};
          for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side)
              add_quad(axis, ijk[axis] + side, ijk[(axis + 1) % 3], ijk[(axis + 2) % 3]);
        }
    for (std::size_t index = 0; index < pyramid_faces.size(); ++index) {
      if (buffered[index]) continue;
      const PyramidFace& f = pyramid_faces[index];
      const std::size_t a = cell_index(f.n[0], f.n[1], f.n[2]);
      const std::array<std::size_t, 4> base = base_corners(lattice, f);
      bool moved = pulled.apex.count(a) > 0 || inner_apex.count(a) > 0 || shared_apex.count(a) > 0;
      for (const std::size_t p : base) moved = moved || pulled.node.count(p);
      if (!moved) {
        const auto [centre, r] = pyramid_sphere(f.c[0], f.c[1], f.c[2], f.dir, f.n);
        moved = moved_points.any_within(centre, r * (1 + 1e-6));
      }
      if (!moved) continue;
      const int axis = f.dir / 2;
      add_quad(axis, f.c[axis] + f.dir % 2, f.c[(axis + 1) % 3], f.c[(axis + 2) % 3]);
      const Vec3 apex = apex_at(a);
      InsertedPoints::Split split;  // two tets on the base's diagonal from its least corner
      for (const std::size_t p : base) split.corners.push_back(point_at(p));
      split.corners.push_back(apex);
      split.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}};
      inserted.splits.push_back(std::move(split));
      for (int m = 0; m < 4; ++m) {
        const std::size_t p = base[m], q = base[(m + 1) % 4];
        add_triangle(p, q, centres + a, point_at(p), point_at(q), apex);
      }
    }
    // A buffer cell: its tets go to around.buffer_cells, its corners to inserted.kept_cells.
    auto keep_cell = [&](const InsertedPoints::Split& split) {
      for (const std::array<int, 4>& t : split.tets)
        around.buffer_cells.add(
            {split.corners[t[0]], split.corners[t[1]], split.corners[t[2]], split.corners[t[3]]});
      inserted.kept_cells.push_back(split.corners);
    };
    // A buffer hexahedron: the six tets around the diagonal from its base's least corner to the
    // top of the opposite one (corner bits u, v across the base, w out of it; u and v swapped
    // on a base facing down its axis, so that the bits are right-handed), its base the core's
    // (constrained above) and its side faces split on the diagonal from their lesser lattice
    // point's corner to the greater one's top, as the split has them; its top is the surface's.
    for (const BufferCells::Hex& hex : buffer.hexes) {
      const PyramidFace& f = pyramid_faces[hex.face];
      const int axis = f.dir / 2;
      const std::array<std::size_t, 4> base = base_corners(lattice, f);
      const std::array<Vec3, 8> at = hex_corners(hex);
      InsertedPoints::Split split;
      const std::array<Vec3, 8> corners =
          buffer_hex_corners({at[0], at[1], at[2], at[3]}, hex.top, f.dir % 2 == 1);
      split.corners.assign(corners.begin(), corners.end());
      for (const auto& q : kKuhnPaths) split.tets.push_back({0, q[0], q[1], 7});
      keep_cell(split);
      inserted.splits.push_back(std::move(split));
      add_quad(axis, f.c[axis] + f.dir % 2, f.c[(axis + 1) % 3], f.c[(axis + 2) % 3]);
      for (int m = 0; m < 4; ++m) {
        int lo = m, hi = (m + 1) % 4;
        if (base[lo] > base[hi]) std::swap(lo, hi);
        add_triangle(base[lo], base[hi], tops + base[hi], at[lo], at[hi], at[4 + hi]);
        add_triangle(base[lo], tops + base[hi], tops + base[lo], at[lo], at[4 + hi], at[4 + lo]);
      }
    }
    // A side pyramid: two tets on its base's diagonal (the hexahedron's), its sides constrained
    // (the one on the core's side face is its neighbour pyramid's too).
    for (const BufferCells::SidePyramid& p : buffer.pyramids) {
      std::array<Vec3, 5> at = side_corners(p);
      std::array<std::size_t, 5> id{p.lo, p.hi, tops + p.hi, tops + p.lo, centres + p.apex_cell};
      // Around, so that the apex lies on the base's inner side (its diagonal kept).
      if (det3(at[1] - at[0], at[2] - at[0], at[4] - at[0]) < 0) {
        std::swap(at[1], at[3]);
        std::swap(id[1], id[3]);
      }
      InsertedPoints::Split split;
      split.corners.assign(at.begin(), at.end());
      split.tets = {{0, 1, 2, 4}, {0, 2, 3, 4}};
      keep_cell(split);
      inserted.splits.push_back(std::move(split));
      for (int m = 0; m < 4; ++m) {
        const int n = (m + 1) % 4;
        add_triangle(id[m], id[n], id[4], at[m], at[n], at[4]);
      }
    }
  }
  for (int k = 0; k < n2; ++k)
    for (int j = 0; j < n1; ++j)
      for (int i = 0; i < n0; ++i) {
        const std::size_t p = lattice.point_index(i, j, k);
        if (!kept[p]) continue;
        const Vec3 q = lattice.point(i, j, k);
        if (around.surface_points.any_within(q, 1e-6 * h)) continue;  // already a surface node
        // A kept point that is no core cell's corner goes where the pulled core now is, and
        // near the buffer's cells.
        if (!layout.core_corner[p] &&
            (moved_balls.holds(q, 0) || around.buffer_cells.near(q, kBufferClearance * h)))
          continue;
        const Vec3 at = point_at(p);
        if (pulled.node.count(p)) inserted.pulled.emplace_back(at, q);
        inserted.points.push_back(at);
        inserted.face.push_back(kept_points.face[p]);
        around.core_points.add(at);
        ++counts.nb_lattice_points;
      }
  for (int k = 0; k < c2; ++k)
    for (int j = 0; j < c1; ++j)
      for (int i = 0; i < c0; ++i) {
        const std::size_t c = cell_index(i, j, k);
        if (!layout.apex_cell[c] || !apex_left[c]) continue;
        const Vec3 q = cell_centre(i, j, k);
        const Vec3 at = apex_at(c);
        if (pulled.apex.count(c) || inner_apex.count(c)) inserted.pulled.emplace_back(at, q);
        inserted.points.push_back(at);
        inserted.face.push_back(-1);
        around.core_points.add(at);
        ++counts.nb_apex_points;
      }
  counts.nb_pulled_points = pulled.node.size() + pulled.apex.size();
  return counts;
}

std::size_t face_points_first(InsertedPoints& inserted) {
  std::vector<std::size_t> order(inserted.points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_partition(order.begin(), order.end(),
                        [&](std::size_t i) { return inserted.face[i] >= 0; });
  std::vector<Vec3> points(order.size());
  std::vector<int> faces(order.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    points[i] = inserted.points[order[i]], faces[i] = inserted.face[order[i]];
  inserted.points.swap(points);
  inserted.face.swap(faces);
  return static_cast<std::size_t>(
      std::count_if(inserted.face.begin(), inserted.face.end(), [](int f) { return f >= 0; }));
}

}  // namespace hexmerge::mesher
