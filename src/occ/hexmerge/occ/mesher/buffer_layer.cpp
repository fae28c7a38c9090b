#include "hexmerge/occ/mesher/buffer_layer.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/face_chart.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface_check.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge::mesher {

namespace {

// A top lies at least kLowest h and at most kHighest h from its base's corner, within kTilt
// degrees of the base's normal. The hexahedron meets the recombination's defaults
// (RecombineParameters: min_scaled_jacobian, its quad faces' folds inside the shape and on its
// surface, max_face_angle), or it is not found (a chord quad of a curved face folds by about its
// width over the radius; a cylinder's quads between two of its lines do not); a side pyramid
// keeps kCorePyramidFloor.
constexpr double kLowest = 0.15;
constexpr double kHighest = 1.5;
constexpr double kTilt = 35.0;
// Their tets (the lattice's split) keep kTetFloor, the mesher's floor for the tets it makes:
// where the recombination does not take a hexahedron or pyramid, its tets stay.
constexpr double kTetFloor = 0.2;
// Tops lie at least kQuadEdgeClearance h inside their face's edges (face_chart.h: its limits
// on the face triangulated again too), and the face's inner nodes nearer than kNodeClearance h to
// a top's quad go (the triangles between are no needles).
constexpr double kNodeClearance = 0.35;
// A top's quad is a chord of its face: its middle at most kSagitta h off the face's triangles.
constexpr double kSagitta = 0.05;

// A base corner's projection onto the surface: its face, parameters and place (frame).
struct Top {
  int face = -1;
  UV uv;
  Vec3 at;
};

// The hexahedron of base corners b (base_corners() order, the base facing +axis when `up`) and
// tops t, in cell_type.h's order: its scaled Jacobian.
double hex_quality(const std::array<Vec3, 4>& b, const std::array<Vec3, 4>& t, bool up) {
  double xyz[24];
  for (int m = 0; m < 4; ++m) {
    xyz[3 * m] = b[m].x, xyz[3 * m + 1] = b[m].y, xyz[3 * m + 2] = b[m].z;
    xyz[12 + 3 * m] = t[m].x, xyz[13 + 3 * m] = t[m].y, xyz[14 + 3 * m] = t[m].z;
  }
  static const index_t kUp[8] = {0, 1, 2, 3, 4, 5, 6, 7}, kDown[8] = {0, 3, 2, 1, 4, 7, 6, 5};
  return scaled_jacobian(CellType::Hex, xyz, up ? kUp : kDown);
}

// The smallest scaled Jacobian of the six tets around the hexahedron's diagonal from its base's
// first corner to its top's third (base corners b in base_corners() order, the base facing +axis
// when `up`; the bits u, v swapped when not, as emit_core() splits it), each taken positive.
double worst_split_tet(const std::array<Vec3, 4>& b, const std::array<Vec3, 4>& t, bool up) {
  const std::array<Vec3, 8> corner = buffer_hex_corners(b, t, up);
  double worst = 1;
  for (const auto& q : kKuhnPaths)
    worst =
        std::min(worst, std::abs(tet_quality(corner[0], corner[q[0]], corner[q[1]], corner[7])));
  return worst;
}

// Whether quad abcd (around) has a dihedral angle of at least `dihedral` degrees across either
// diagonal and no corner wider than `widest` degrees.
bool flat_enough(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double dihedral,
                 double widest) {
  const double pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z}, pc[3] = {c.x, c.y, c.z},
               pd[3] = {d.x, d.y, d.z};
  return quad_dihedral_angle(pa, pb, pc, pd) >= dihedral &&
         quad_dihedral_angle(pb, pc, pd, pa) >= dihedral &&
         quad_max_corner_angle(pa, pb, pc, pd) <= widest;
}

// The pyramid of base corners q (around) and apex: its scaled Jacobian, the base taken round
// whichever way puts the apex on its inner side.
double pyramid_quality(const std::array<Vec3, 4>& q, const Vec3& apex) {
  return closing_pyramid_quality(q, apex, det3(q[1] - q[0], q[2] - q[0], apex - q[0]) > 0);
}

std::uint64_t edge_key(std::size_t a, std::size_t b) {
  return pair_key(static_cast<int>(std::min(a, b)), static_cast<int>(std::max(a, b)));
}

}  // namespace

BufferCells buffer_layer(const Shape& shape, const Lattice& lattice, const CoreLayout& layout,
                         const std::vector<Vec3>& nodes, const Surroundings& around,
                         const std::vector<char>& eligible, double h, Surface& surface,
                         BufferReport& report) {
  BufferCells out;
  const std::vector<PyramidFace>& faces = layout.pyramid_faces;
  if (faces.empty()) return out;
  const auto cell_of = [&](const int(&c)[3]) {
    return (static_cast<std::size_t>(c[2]) * lattice.cells[1] + c[1]) * lattice.cells[0] + c[0];
  };
  // 1. The bases whose pyramid's apex closes no other base.
  std::unordered_map<std::size_t, int> at_apex;
  for (const PyramidFace& f : faces) ++at_apex[cell_of(f.n)];
  // 2. The base corners' projections onto the nearest face: the nearest point of the surface's
  // triangles, then Newton's method on the face's surface from its parameters there.
  std::vector<std::unique_ptr<ShapeAnalysis_Surface>> analysis(
      static_cast<std::size_t>(shape.faces.Extent()));
  // Per lattice point, its top, or why it has none (a BufferBaseCounts member).
  struct Found {
    std::optional<Top> top;
    std::size_t BufferBaseCounts::*miss = nullptr;
  };
  std::unordered_map<std::size_t, Found> top_cache;
  const auto top_of = [&](std::size_t p) -> const std::optional<Top>& {
    const auto found = top_cache.find(p);
    if (found != top_cache.end()) return found->second.top;
    Found& entry = top_cache[p];
    std::optional<Top>& top = entry.top;
    std::size_t BufferBaseCounts::*& miss = entry.miss;
    miss = &BufferBaseCounts::no_top_far;
    const Vec3 q = layout.point_at(lattice, p);
    int nearest = -1;
    double best = kHighest * h * kHighest * h;
    around.every_face.any_within(q, kHighest * h, [&](int i) {
      const SurfaceTriangle& t = surface.triangles[static_cast<std::size_t>(i)];
      const double d2 = squared_distance_to_triangle(q, nodes[static_cast<std::size_t>(t.node[0])],
                                                     nodes[static_cast<std::size_t>(t.node[1])],
                                                     nodes[static_cast<std::size_t>(t.node[2])]);
      if (d2 < best) best = d2, nearest = i;
      return false;
    });
    if (nearest < 0) return top;
    const SurfaceTriangle& t = surface.triangles[static_cast<std::size_t>(nearest)];
    miss = &BufferBaseCounts::no_top_face;
    if (!eligible[static_cast<std::size_t>(t.face)]) return top;
    const int its_face = t.face;
    double s = 0, r = 0;
    const Vec3 on = nearest_on_triangle(q, nodes[static_cast<std::size_t>(t.node[0])],
                                        nodes[static_cast<std::size_t>(t.node[1])],
                                        nodes[static_cast<std::size_t>(t.node[2])], s, r);
    std::unique_ptr<ShapeAnalysis_Surface>& a = analysis[static_cast<std::size_t>(t.face)];
    if (!a)
      a = std::make_unique<ShapeAnalysis_Surface>(
          BRep_Tool::Surface(TopoDS::Face(shape.faces(t.face + 1))));
    const UV guess{t.uv[0].u + s * (t.uv[1].u - t.uv[0].u) + r * (t.uv[2].u - t.uv[0].u),
                   t.uv[0].v + s * (t.uv[1].v - t.uv[0].v) + r * (t.uv[2].v - t.uv[0].v)};
    const Vec3 world = lattice.frame.to_world(q);
    const gp_Pnt2d found_uv = a->NextValueOfUV(gp_Pnt2d(guess.u, guess.v),
                                               gp_Pnt(world.x, world.y, world.z), 1e-7 * h, -1.0);
    const Vec3 at = lattice.frame.to_frame(of(a->Value(found_uv)));
    miss = &BufferBaseCounts::no_top_projection;
    if ((at - on).norm() > 0.1 * h) return top;  // Newton went elsewhere
    miss = &BufferBaseCounts::no_top_clearance;
    // Clear of the other faces (across a thin wall or a concave edge), as of its face's edges.
    if (around.every_face.any_within(at, kQuadEdgeClearance * h, [&](int i) {
          return surface.triangles[static_cast<std::size_t>(i)].face != its_face;
        }))
      return top;
    top = Top{t.face, UV{found_uv.X(), found_uv.Y()}, at};
    miss = nullptr;
    return top;
  };
  // 3. The hexahedra each base could have.
  const RecombineParameters recombine;
  const double tilt = std::cos(kTilt * M_PI / 180);
  std::vector<char> chosen(faces.size(), 0);
  std::vector<std::array<std::size_t, 4>> base_of(faces.size());
  BufferBaseCounts& count = report.bases;
  count.considered = faces.size();
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const PyramidFace& f = faces[i];
    if (at_apex[cell_of(f.n)] != 1) {
      ++count.apex_shared;
      continue;
    }
    // The cell across is beside no other core cell (one on the boundary needs no pyramid).
    bool alone = true;
    for (int dir = 0; dir < 6 && alone; ++dir) {
      int n[3] = {f.n[0], f.n[1], f.n[2]};
      n[dir / 2] += dir % 2 ? 1 : -1;
      if (n[0] == f.c[0] && n[1] == f.c[1] && n[2] == f.c[2]) continue;
      alone = n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= lattice.cells[0] ||
              n[1] >= lattice.cells[1] || n[2] >= lattice.cells[2] || !layout.core[cell_of(n)];
    }
    if (!alone) {
      ++count.apex_shared;
      continue;
    }
    base_of[i] = base_corners(lattice, f);
    const int axis = f.dir / 2;
    Vec3 normal{0, 0, 0};
    set_coord(normal, axis, f.dir % 2 ? 1.0 : -1.0);
    std::array<Vec3, 4> b, t;
    int face = -1;
    bool ok = true;
    std::size_t BufferBaseCounts::*failed = nullptr;  // the test it fails
    for (int m = 0; m < 4 && ok; ++m) {
      const std::optional<Top>& top = top_of(base_of[i][m]);
      if (!top || (face >= 0 && top->face != face)) {
        ok = false;
        failed = top ? &BufferBaseCounts::two_faces : top_cache.at(base_of[i][m]).miss;
        break;
      }
      face = top->face;
      b[m] = layout.point_at(lattice, base_of[i][m]);
      t[m] = top->at;
      const Vec3 d = t[m] - b[m];
      const double length = d.norm();
      ok = length >= kLowest * h && length <= kHighest * h && d.dot(normal) >= tilt * length;
      if (!ok) failed = &BufferBaseCounts::height_or_tilt;
    }
    if (ok && !(hex_quality(b, t, f.dir % 2 == 1) >= recombine.min_scaled_jacobian))
      ok = false, failed = &BufferBaseCounts::hex_quality;
    if (ok && !(worst_split_tet(b, t, f.dir % 2 == 1) >= kTetFloor))
      ok = false, failed = &BufferBaseCounts::split_quality;
    ok = ok && flat_enough(t[0], t[1], t[2], t[3], recombine.min_boundary_dihedral_angle,
                           recombine.max_face_angle);
    for (int m = 0; m < 4 && ok; ++m)
      ok = flat_enough(b[m], b[(m + 1) % 4], t[(m + 1) % 4], t[m], recombine.min_dihedral_angle,
                       recombine.max_face_angle);
    if (!ok && !failed) failed = &BufferBaseCounts::folds;
    if (ok)
      chosen[i] = 1;
    else
      ++(count.*failed);
  }
  const std::size_t passed = static_cast<std::size_t>(std::count(chosen.begin(), chosen.end(), 1));
  // 4. Per face, its chart; the tops placed in it, clear of its edges.
  std::unordered_map<int, std::vector<int>> face_triangles;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    face_triangles[surface.triangles[t].face].push_back(static_cast<int>(t));
  std::map<int, FaceChart> charts;
  std::unordered_map<std::size_t, P2> top_xy;
  std::unordered_map<std::size_t, UV> top_uv;
  const auto face_of = [&](std::size_t i) { return top_of(base_of[i][0])->face; };
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!chosen[i]) continue;
    const int face = face_of(i);
    auto it = charts.find(face);
    if (it == charts.end()) {
      std::optional<FaceChart> chart = chart_of(shape, surface, face_triangles[face], face);
      if (!chart) {
        chosen[i] = 0;
        continue;
      }
      it = charts.emplace(face, std::move(*chart)).first;
    }
    const FaceChart& chart = it->second;
    std::array<P2, 4> xy;
    for (int m = 0; m < 4 && chosen[i]; ++m) {
      const std::size_t p = base_of[i][m];
      if (!top_xy.count(p)) {
        UV uv = top_of(p)->uv;
        const std::optional<P2> placed = place_clear(chart, uv, h);
        if (!placed) {
          chosen[i] = 0;
          break;
        }
        top_xy[p] = *placed;
        top_uv[p] = uv;
      }
      xy[m] = top_xy[p];
    }
    if (!chosen[i]) continue;
    // The quad in the chart: its two triangles turning the same way, its sides crossing no edge
    // and passing the edges' nodes at half the clearance.
    bool ok = quad_clear(chart, xy, h);
    if (ok) {
      Vec3 middle{0, 0, 0};
      for (int m = 0; m < 4; ++m) middle = middle + top_of(base_of[i][m])->at * 0.25;
      ok = around.every_face.any_within(middle, kSagitta * h);
    }
    if (!ok) chosen[i] = 0;
  }
  // The quads of one face lie side by side: a quad whose sides or diagonal cross those of one
  // taken before on its face, or that holds a corner of one or has a corner in one, goes.
  {
    struct Taken {
      std::array<std::size_t, 4> top;
      std::array<P2, 4> xy;
      P2 lo, hi;
    };
    std::map<int, std::vector<Taken>> taken;
    const auto strictly_inside = [](const P2& p, const std::array<P2, 4>& q) {
      const bool turn = cross2(q[0], q[1], q[2]) > 0;
      for (int k = 0; k < 4; ++k) {
        const double side = cross2(q[k], q[(k + 1) % 4], p);
        if (side == 0 || (side > 0) != turn) return false;
      }
      return true;
    };
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (!chosen[i]) continue;
      Taken quad;
      for (int m = 0; m < 4; ++m)
        quad.top[m] = base_of[i][m], quad.xy[m] = top_xy.at(base_of[i][m]);
      quad.lo = quad.hi = quad.xy[0];
      for (const P2& p : quad.xy)
        for (int a = 0; a < 2; ++a)
          quad.lo[a] = std::min(quad.lo[a], p[a]), quad.hi[a] = std::max(quad.hi[a], p[a]);
      // Its sides and diagonal, by their tops.
      const int segment[5][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}};
      bool ok = true;
      for (const Taken& other : taken[face_of(i)]) {
        if (!ok) break;
        if (other.hi[0] < quad.lo[0] || quad.hi[0] < other.lo[0] || other.hi[1] < quad.lo[1] ||
            quad.hi[1] < other.lo[1])
          continue;
        for (int m = 0; m < 4 && ok; ++m) {
          const bool shared =
              std::find(other.top.begin(), other.top.end(), quad.top[m]) != other.top.end();
          ok = shared || !strictly_inside(quad.xy[m], other.xy);
          const bool theirs_shared =
              std::find(quad.top.begin(), quad.top.end(), other.top[m]) != quad.top.end();
          ok = ok && (theirs_shared || !strictly_inside(other.xy[m], quad.xy));
        }
        for (const auto& s : segment)
          for (const auto& t : segment) {
            if (!ok) break;
            const std::size_t a = quad.top[s[0]], b = quad.top[s[1]], c = other.top[t[0]],
                              d = other.top[t[1]];
            if (a == c || a == d || b == c || b == d) continue;  // they meet at a top
            ok = !segments_meet(quad.xy[s[0]], quad.xy[s[1]], other.xy[t[0]], other.xy[t[1]]);
          }
      }
      if (ok)
        taken[face_of(i)].push_back(quad);
      else
        chosen[i] = 0;
    }
  }
  // The corners of base i (base_of is filled for the bases whose apex closes no other).
  const auto base_of_face = [&](std::size_t i) { return base_corners(lattice, faces[i]); };
  // Per base side (its two lattice points), the bases that have it.
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> side_bases;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::array<std::size_t, 4> b = base_corners(lattice, faces[i]);
    for (int m = 0; m < 4; ++m) side_bases[edge_key(b[m], b[(m + 1) % 4])].push_back(i);
  }
  // 5. The side pyramids, the hexahedra that cannot have them dropped, until none drops; then
  // each face with tops triangulated again, a face where that fails losing its hexahedra, and
  // again. (The surface nodes any other face uses stay.)
  const std::vector<char> node_elsewhere = nodes_on_several_faces(surface);
  std::vector<BufferCells::SidePyramid> pyramids;
  const auto close_sides = [&]() {
    for (bool dropped = true; dropped;) {
      dropped = false;
      pyramids.clear();
      for (std::size_t i = 0; i < faces.size(); ++i) {
        if (!chosen[i]) continue;
        for (int m = 0; m < 4 && chosen[i]; ++m) {
          const std::size_t p = base_of[i][m], q = base_of[i][(m + 1) % 4];
          const std::vector<std::size_t>& having = side_bases[edge_key(p, q)];
          if (having.size() != 2) {  // the core touches itself along the side
            chosen[i] = 0;
            break;
          }
          const std::size_t other = having[0] == i ? having[1] : having[0];
          if (chosen[other]) continue;
          const std::size_t apex_cell = cell_of(faces[other].n);
          const std::size_t lo = std::min(p, q), hi = std::max(p, q);
          const std::array<Vec3, 4> side{layout.point_at(lattice, lo), layout.point_at(lattice, hi),
                                         top_of(hi)->at, top_of(lo)->at};
          const Vec3 apex = layout.apex_at(lattice, apex_cell);
          if (pyramid_quality(side, apex) < kCorePyramidFloor ||
              std::abs(tet_quality(side[0], side[1], side[2], apex)) < kTetFloor ||
              std::abs(tet_quality(side[0], side[2], side[3], apex)) < kTetFloor) {
            chosen[i] = 0;
            break;
          }
          pyramids.push_back({lo, hi, apex_cell});
        }
        dropped = dropped || !chosen[i];
      }
    }
  };
  // Steps 5 to 7 again from the surface as it was while step 7 drops a hexahedron (its quad
  // left in the face, the tets on it flat).
  const Surface original = surface;
  std::unordered_map<std::size_t, int> top_node;  // per lattice point, its top's node
  std::vector<Vec3> frame_points;                 // the surface's nodes, frame coordinates
  std::map<int, Retriangulated> remeshed;
  // The tops in the faces triangulated again (-1 - k in their triangles): lattice point, world.
  std::vector<std::size_t> top_point;
  std::vector<Vec3> top_world;
  for (bool again = true; again;) {
    again = false;
    surface = original;
    for (bool failed = true; failed;) {
      failed = false;
      close_sides();
      remeshed.clear();
      top_point.clear(), top_world.clear();
      std::unordered_map<std::size_t, int> top_index;
      std::map<int, std::vector<std::size_t>> on_face;
      for (std::size_t i = 0; i < faces.size(); ++i)
        if (chosen[i]) on_face[face_of(i)].push_back(i);
      for (const auto& [face, bases] : on_face) {
        std::unordered_map<std::size_t, int> index;
        std::vector<P2> xy;
        std::vector<UV> uv;
        std::vector<Vec3> world;
        std::vector<std::array<int, 4>> quads;
        for (const std::size_t i : bases) {
          std::array<int, 4> q{};
          for (int m = 0; m < 4; ++m) {
            const std::size_t p = base_of[i][m];
            const auto [it, fresh] = index.emplace(p, static_cast<int>(xy.size()));
            if (fresh) {
              xy.push_back(top_xy.at(p));
              uv.push_back(top_uv.at(p));
              world.push_back(lattice.frame.to_world(top_of(p)->at));
            }
            q[m] = it->second;
          }
          quads.push_back(q);
        }
        std::vector<int> poor_tops;
        std::optional<Retriangulated> made =
            retriangulate(charts.at(face), surface, quads, xy, uv, world, node_elsewhere, h,
                          {kNodeClearance, kQuadAreaChange, kQuadLeastAngle}, &poor_tops);
        if (!made) {
          // Where only new triangles too thin fail it, the hexahedra whose tops they have (or
          // whose quads took the nodes beside them) go; else all of the face's.
          std::vector<char> poor(xy.size(), 0);
          for (const int k : poor_tops) poor[static_cast<std::size_t>(k)] = 1;
          bool any = false;
          for (std::size_t b = 0; b < bases.size(); ++b)
            for (const int k : quads[b])
              if (poor[static_cast<std::size_t>(k)]) {
                chosen[bases[b]] = 0, any = true;
                break;
              }
          if (!any)
            for (const std::size_t i : bases) chosen[i] = 0;
          failed = true;
          continue;
        }
        // This face's k-th top is the lattice point's among all faces' tops.
        std::vector<int> top(index.size());
        for (const auto& [p, k] : index) {
          const auto [it, fresh] = top_index.emplace(p, static_cast<int>(top_point.size()));
          if (fresh)
            top_point.push_back(p), top_world.push_back(world[static_cast<std::size_t>(k)]);
          top[static_cast<std::size_t>(k)] = it->second;
        }
        for (auto& t : made->node)
          for (int& n : t)
            if (n < 0) n = -1 - top[static_cast<std::size_t>(-1 - n)];
        remeshed.emplace(face, std::move(*made));
      }
    }
    if (remeshed.empty()) {
      surface = original;
      count.dropped_later = passed;
      return out;
    }
    // 6. The surface with the new triangles and tops.
    {
      const std::vector<int> node = put_in_surface(surface, remeshed, top_world, h);
      top_node.clear();
      for (std::size_t k = 0; k < node.size(); ++k)
        if (node[k] >= 0) top_node[top_point[k]] = node[k];
    }
    report.nb_faces = remeshed.size();
    report.faces.clear();
    for (const auto& [face, made] : remeshed) report.faces.push_back(face);
    // 7. The cells whose faces cross the surface, or that hold a surface node or a point of the
    // core, go; then steps 5 to 7 again without them.
    frame_points.resize(surface.nodes.size());
    for (std::size_t n = 0; n < frame_points.size(); ++n)
      frame_points[n] = lattice.frame.to_frame(surface.nodes[n]);
    NodeHash node_at(frame_points, h);
    for (int n = 0; n < static_cast<int>(frame_points.size()); ++n) node_at.add(n);
    std::vector<std::array<int, 3>> surface_triangles;
    for (const SurfaceTriangle& t : surface.triangles) surface_triangles.push_back(t.node);
    {
      bool dropped = false;
      // The core's points: its cells' corners and the apexes of the pyramids left.
      PointSet core_points(around.box_lo, around.box_hi, h);
      for (std::size_t p = 0; p < layout.core_corner.size(); ++p)
        if (layout.core_corner[p]) core_points.add(layout.point_at(lattice, p));
      {
        std::unordered_set<std::size_t> left;
        for (std::size_t i = 0; i < faces.size(); ++i)
          if (!chosen[i] && left.insert(cell_of(faces[i].n)).second)
            core_points.add(layout.apex_at(lattice, cell_of(faces[i].n)));
      }
      // The cells' corners and their faces but the tops' (by index into `points`).
      std::vector<Vec3> points = frame_points;
      std::unordered_map<std::size_t, int> base_point;
      const auto base_index = [&](std::size_t p) {
        const auto [it, fresh] = base_point.emplace(p, static_cast<int>(points.size()));
        if (fresh) points.push_back(layout.point_at(lattice, p));
        return it->second;
      };
      const auto top_index = [&](std::size_t p) { return top_node.at(p); };
      std::vector<std::array<int, 3>> inner;
      std::vector<std::size_t> owner;  // per inner triangle: its base (a side pyramid: its hex's)
      std::vector<char> bad(faces.size(), 0);
      for (std::size_t i = 0; i < faces.size(); ++i) {
        if (!chosen[i]) continue;
        const std::array<std::size_t, 4>& b = base_of[i];
        bool all_tops = true;
        for (const std::size_t p : b) all_tops = all_tops && top_node.count(p);
        if (!all_tops) {
          bad[i] = 1;
          continue;
        }
        for (int m = 0; m < 4; ++m) {
          std::size_t lo = b[m], hi = b[(m + 1) % 4];
          if (lo > hi) std::swap(lo, hi);
          inner.push_back({base_index(lo), base_index(hi), top_index(hi)});
          inner.push_back({base_index(lo), top_index(hi), top_index(lo)});
          owner.push_back(i), owner.push_back(i);
        }
        // A point inside the hexahedron (its six tets) goes with it.
        std::array<Vec3, 4> base_at, top_at;
        for (int m = 0; m < 4; ++m) {
          base_at[m] = layout.point_at(lattice, b[m]);
          top_at[m] = frame_points[static_cast<std::size_t>(top_node.at(b[m]))];
        }
        const std::array<Vec3, 8> corner =
            buffer_hex_corners(base_at, top_at, faces[i].dir % 2 == 1);
        Vec3 lo_box = corner[0], hi_box = corner[0];
        for (const Vec3& c : corner) lo_box = vmin(lo_box, c), hi_box = vmax(hi_box, c);
        const Vec3 centre = (lo_box + hi_box) * 0.5;
        const double radius = 0.5 * (hi_box - lo_box).norm();
        // (On its faces too: TetGen would split them there; not at its corners.)
        const auto holds = [&](const Vec3& q) { return cell_holds(corner, q, h); };
        bool holds_node = false;
        node_at.for_each_within(centre, std::min(radius, h), [&](int n) {
          holds_node = holds_node || holds(frame_points[static_cast<std::size_t>(n)]);
        });
        if (radius > h)  // (the node hash looks one cell around)
          for (std::size_t n = 0; n < frame_points.size() && !holds_node; ++n)
            holds_node = (frame_points[n] - centre).norm() <= radius && holds(frame_points[n]);
        if (holds_node || core_points.any_within(centre, radius, holds)) bad[i] = 1;
      }
      std::unordered_map<std::size_t, int> apex_point;  // the side pyramids' apexes
      for (const BufferCells::SidePyramid& p : pyramids) {
        const auto [at, fresh] = apex_point.emplace(p.apex_cell, static_cast<int>(points.size()));
        if (fresh) points.push_back(layout.apex_at(lattice, p.apex_cell));
        const int apex = at->second;
        const int id[4] = {base_index(p.lo), base_index(p.hi), top_index(p.hi), top_index(p.lo)};
        // Its hexahedron: the chosen base with side (lo, hi).
        std::size_t hex = 0;
        for (const std::size_t i : side_bases[edge_key(p.lo, p.hi)])
          if (chosen[i]) hex = i;
        for (int m = 0; m < 4; ++m) {
          inner.push_back({id[m], id[(m + 1) % 4], apex});
          owner.push_back(hex);
        }
      }
      // Against the surface, each other and the core's pyramids whose apexes they share (TetGen
      // stops on constraints that cross).
      std::vector<std::array<int, 3>> against = surface_triangles;
      against.insert(against.end(), inner.begin(), inner.end());
      {
        for (std::size_t i = 0; i < faces.size(); ++i) {
          const auto it = apex_point.find(cell_of(faces[i].n));
          if (chosen[i] || it == apex_point.end()) continue;
          for (int m = 0; m < 4; ++m)
            against.push_back({base_index(base_of_face(i)[m]),
                               base_index(base_of_face(i)[(m + 1) % 4]), it->second});
        }
      }
      const std::vector<char> crossing = crosses_any(points, against, inner);
      for (std::size_t k = 0; k < inner.size(); ++k)
        if (crossing[k]) bad[owner[k]] = 1;
      for (std::size_t i = 0; i < faces.size(); ++i)
        if (bad[i] && chosen[i]) chosen[i] = 0, dropped = true;
      again = dropped;
    }
  }
  // 8. The cells.
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!chosen[i]) continue;
    BufferCells::Hex hex;
    hex.face = i;
    for (int m = 0; m < 4; ++m) {
      const std::size_t p = base_of[i][m];
      hex.top[m] = frame_points[static_cast<std::size_t>(top_node.at(p))];
      out.top_of[p] = hex.top[m];
    }
    out.hexes.push_back(hex);
  }
  out.pyramids = pyramids;
  report.nb_hexes = out.hexes.size();
  report.nb_pyramids = out.pyramids.size();
  count.kept = out.hexes.size();
  count.dropped_later = passed - count.kept;
  return out;
}

}  // namespace hexmerge::mesher
