#include "hexmerge/occ/mesher/lattice.h"

#include <BRepAdaptor_Curve.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/sweep.h"

namespace hexmerge::mesher {

namespace {
// The counts per axis lay_lattice() tries together when the best per axis break that.
constexpr std::size_t kCountChoices = 6;
// Uniform cells are this many times h wide at least and at most. Up to 1.5 h, a count that put
// one more planar face on a lattice plane won over cells of about h: gmsh_Angled at its 50k size
// got cells 1.16 x 1.39 x 1.06 h and 56.0 % hex volume; with cells of at most 1.2 h, at the same
// count of tets (h 11 % larger), 1.05 x 1.01 x 0.96 h and 59.9 %.
constexpr double kNarrowest = 0.75;
constexpr double kWidest = 1.2;
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
    list.emplace_back(segment.t_lo, pair_lo(key));  // the smaller id
    list.emplace_back(segment.t_hi, pair_hi(key));
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
  // lie on lattice planes (the box's own faces always do). Per axis, the counts from 1.2 h to
  // 0.75 h wide (kWidest, kNarrowest), best first: more faces on lattice planes, then nearer
  // L / h.
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
  // By their smallest x (each computed once), so that a bucket's list runs along x and inside()
  // stops at q.x.
  std::vector<std::pair<double, std::array<int, 3>>> by_x;
  for (const SurfaceTriangle& t : surface.triangles)
    if (face_solid_count[t.face] <= 1)
      by_x.emplace_back(std::min({nodes[t.node[0]].x, nodes[t.node[1]].x, nodes[t.node[2]].x}),
                        t.node);
  std::stable_sort(by_x.begin(), by_x.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [x, t] : by_x) least_x_.push_back(x), triangles_.push_back(t);
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    const auto& t = triangles_[i];
    Vec3 a{nodes[t[0]].y, nodes[t[0]].z, 0}, b{nodes[t[1]].y, nodes[t[1]].z, 0},
        c{nodes[t[2]].y, nodes[t[2]].z, 0};
    yz_.add(static_cast<int>(i), vmin(a, vmin(b, c)), vmax(a, vmax(b, c)));
  }
}

template <typename F>
void Parity::for_each_crossing(double y, double z, double before, F&& f) const {
  y += 1.234567e-7 * h_, z += 2.345678e-7 * h_;
  // (The point's box lies in one bucket, which holds each triangle once.)
  yz_.any_in(Vec3{y, z, 0}, Vec3{y, z, 0}, [&](int i) {
    if (least_x_[static_cast<std::size_t>(i)] > before) return true;  // the rest start beyond
    const auto& t = triangles_[i];
    const Vec3 &p0 = nodes_[t[0]], &p1 = nodes_[t[1]], &p2 = nodes_[t[2]];
    double u, v;
    if (!coordinates_across(Vec3{0, y, z}, p0, p1, p2, 0, u, v)) return false;
    if (u < 0 || v < 0 || u + v > 1) return false;
    f(p0.x + u * (p1.x - p0.x) + v * (p2.x - p0.x));
    return false;
  });
}

std::vector<double> Parity::crossings(double y, double z) const {
  std::vector<double> xs;
  for_each_crossing(y, z, std::numeric_limits<double>::infinity(),
                    [&](double x) { xs.push_back(x); });
  std::sort(xs.begin(), xs.end());
  return xs;
}

bool Parity::inside_given(const std::vector<double>& xs, double x) {
  return (std::lower_bound(xs.begin(), xs.end(), x) - xs.begin()) % 2 == 1;
}

bool Parity::inside(const Vec3& q) const {
  std::size_t before = 0;
  for_each_crossing(q.y, q.z, q.x, [&](double x) { before += x < q.x; });
  return before % 2 == 1;
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
