#include "hexmerge/occ/mesher/pull_core.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface_check.h"

namespace hexmerge::mesher {

namespace {
// The core pulled towards the surface (pull_core()): its closing pyramids' apexes come this
// fraction of h from the faces at the nearest, each node moves at most kPullMost h, and the
// cells it moves keep scaled Jacobian kPullCellFloor (the pyramids kCorePyramidFloor) and their
// quad faces fold by no more than kPullFold degrees across either diagonal. Chosen on the real
// parts at their 50k sizes (docs/benchmarks-real-parts.md): cells under 0.9 stay out of the
// recombination's block of near-perfect hexahedra, whose members beside them then leave it one
// after the other (gmsh_part: 88.6 -> 67.9 % hex volume with a floor of 0.5); a fold of 25 degrees
// took hexahedra from gmsh_Angled and gmsh_wrenchnut; apexes 0.05 h from the faces left flat tets
// between them and the boundary triangles (gmsh_Kurbelwelle at its 250k size: 98 elements under
// 0.2 against 23 at 0.15 h, for 63.9 against 63.0 % hex volume).
constexpr double kPullTarget = 0.15;
constexpr double kPullMost = 0.5;
constexpr double kPullCellFloor = 0.9;
constexpr double kPullFold = 15.0;
// A face across a gap of one cell in the core (see core_beyond in pull_core()) moves at most this
// fraction of h: the gap closes by at most twice that, and its apexes stay short of each other's
// bases.
constexpr double kPullGapMost = 0.1;
// Moved core nodes keep this fraction of h from the faces and the surface's nodes: at 0.1 h the
// tets between them and the boundary triangles were flat (real parts at their 250k sizes: 1,413
// elements under scaled Jacobian 0.2 against 1,095 unpulled; hex_bolt 194, thin_bracket 47; at
// 0.25 h 101 and 0, the same hex volume).
constexpr double kPullNodeClearance = 0.25;
// Rounds of halving the moves of failing cells' and pyramids' nodes before they stay put.
constexpr int kPullHalvings = 5;
// A closing pyramid's apex placed inside, nearer its face, where the centre of the cell across
// is outside the shape (place_inner_apex()), keeps these fractions of h from every face (the
// pulled apexes' target) and from the surface's nodes (the pulled nodes'): with 0.15 h from the
// nodes too, gmsh_918_pump_carter_sup_21_03_2006 at its 50k size had 50 tets under scaled
// Jacobian 0.2 against 23, for 46.0 against 45.4 % hex volume.
constexpr double kInnerApexClearance = 0.15;
constexpr double kInnerApexNodeClearance = 0.25;

// Distance from q to the nearest item of `set` (a PointSet or TriangleSet), `far` when none is
// nearer, to within `tolerance`.
template <typename Set>
double distance_to(const Set& set, const Vec3& q, double far, double tolerance) {
  if (!set.any_within(q, far)) return far;
  double lo = 0, hi = far;
  while (hi - lo > tolerance) {
    const double mid = 0.5 * (lo + hi);
    (set.any_within(q, mid) ? hi : lo) = mid;
  }
  return lo;
}

// Whether the quad a-b-c-d folds by at most `fold` degrees across either diagonal.
bool quad_flat(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double fold) {
  const double cos_fold = std::cos(fold * M_PI / 180);
  const auto folds_less = [&](const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& t) {
    // Triangles p-q-r and p-r-t on diagonal p-r.
    const Vec3 n1 = (q - p).cross(r - p), n2 = (r - p).cross(t - p);
    const double l = n1.norm() * n2.norm();
    return l > 0 && n1.dot(n2) >= cos_fold * l;
  };
  return folds_less(a, b, c, d) && folds_less(b, c, d, a);
}

// Whether the pyramid of corners `corner` (around) and `apex` is clear: the apex inside, the way
// from the base to it crossing no face, no surface node inside it (to a thousandth of h beyond
// its faces).
bool pyramid_clear(const Surroundings& around, const Parity& parity,
                   const std::array<Vec3, 4>& corner, const Vec3& apex, double h) {
  if (!parity.inside(apex)) return false;
  const Vec3 centre = (corner[0] + corner[1] + corner[2] + corner[3]) * 0.25;
  for (const Vec3& from : {centre, corner[0], corner[1], corner[2], corner[3]}) {
    const int steps = 1 + static_cast<int>((apex - from).norm() / (kApexClearance * h));
    for (int s = 1; s < steps; ++s)
      if (around.every_face.any_within(from + (apex - from) * (static_cast<double>(s) / steps),
                                       kApexClearance * h))
        return false;
  }
  const double slack = 1e-3 * h;
  const Vec3 up = apex - centre;
  const auto inside = [&](const Vec3& q) {  // on the inner side of its base and its four sides
    if ((q - centre).dot(up) < -slack * up.norm()) return false;
    for (int m = 0; m < 4; ++m) {
      const Vec3 a = corner[m], b = corner[(m + 1) % 4];
      Vec3 normal = (b - a).cross(apex - a);
      if (normal.dot(centre - a) > 0) normal = normal * -1.0;  // outward
      if ((q - a).dot(normal) > slack * normal.norm()) return false;
    }
    return true;
  };
  double reach = (apex - centre).norm();
  for (const Vec3& c : corner) reach = std::max(reach, (c - centre).norm());
  return !around.surface_points.any_within(centre, reach * (1 + 1e-6), inside);
}

}  // namespace

Vec3 apex_home(const Lattice& lattice, const std::unordered_map<std::size_t, Vec3>& inner_apex,
               std::size_t cell) {
  const auto it = inner_apex.find(cell);
  return it == inner_apex.end() ? lattice.cell_centre(lattice.cell_ijk(cell)) : it->second;
}

double closing_pyramid_quality(const std::array<Vec3, 4>& base, const Vec3& apex, bool up) {
  double xyz[15];
  for (int m = 0; m < 4; ++m)
    xyz[3 * m] = base[m].x, xyz[3 * m + 1] = base[m].y, xyz[3 * m + 2] = base[m].z;
  xyz[12] = apex.x, xyz[13] = apex.y, xyz[14] = apex.z;
  // Around the base as seen from the apex: the base's corners go around +u, +v, which is
  // right-handed seen from +axis.
  static const index_t kUp[5] = {0, 1, 2, 3, 4}, kDown[5] = {0, 3, 2, 1, 4};
  return scaled_jacobian(CellType::Pyramid, xyz, up ? kUp : kDown);
}

std::array<Vec3, 4> lattice_points(const Lattice& lattice,
                                   const std::array<std::size_t, 4>& points) {
  std::array<Vec3, 4> out;
  for (int m = 0; m < 4; ++m) out[m] = lattice.point(lattice.point_ijk(points[m]));
  return out;
}

std::optional<Vec3> place_inner_apex(const Lattice& lattice, const Surroundings& around,
                                     const Parity& parity, const PyramidFace& f,
                                     const std::optional<Vec3>& at, double h) {
  const std::array<Vec3, 4> corner = lattice_points(lattice, base_corners(lattice, f));
  const auto good = [&](const Vec3& apex) {
    return closing_pyramid_quality(corner, apex, f.dir % 2 == 1) >= kCorePyramidFloor &&
           !around.every_face.any_within(apex, kInnerApexClearance * h) &&
           !around.surface_points.any_within(apex, kInnerApexNodeClearance * h) &&
           !around.layer_points.any_within(apex, 0.25 * h) &&
           pyramid_clear(around, parity, corner, apex, h);
  };
  if (at) return good(*at) ? at : std::nullopt;
  const Vec3 centre = (corner[0] + corner[1] + corner[2] + corner[3]) * 0.25;
  const Vec3 towards = lattice.cell_centre(f.n[0], f.n[1], f.n[2]) - centre;
  for (int step = 9; step >= 5; --step) {
    const Vec3 apex = centre + towards * (0.1 * step);
    if (good(apex)) return apex;
  }
  return std::nullopt;
}

// The lattice point indices of the corners of face `f`'s base, around it.
std::array<std::size_t, 4> face_corners(const Lattice& lattice, int axis, int plane, int p, int q) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::array<std::size_t, 4> out{};
  static constexpr int kAround[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int corner = 0; corner < 4; ++corner) {
    int c[3];
    c[axis] = plane, c[u] = p + kAround[corner][0], c[v] = q + kAround[corner][1];
    out[corner] = lattice.point_index(c[0], c[1], c[2]);
  }
  return out;
}

std::array<std::size_t, 4> base_corners(const Lattice& lattice, const PyramidFace& f) {
  const int axis = f.dir / 2;
  return face_corners(lattice, axis, f.c[axis] + f.dir % 2, f.c[(axis + 1) % 3],
                      f.c[(axis + 2) % 3]);
}

// The core's nodes on closing pyramids' bases moved out along the bases' normals (at an edge
// or corner of the core, along each base's), each apex by the mean of its bases' corners' moves,
// so that each apex comes kPullTarget h from the faces; the moves halved where a cell or
// pyramid they change would fall below kPullCellFloor / kCorePyramidFloor, fold a quad face by
// more than kPullFold, or an apex would come nearer than kApexClearance h to a face
// (kApexNodeClearance h to a node) or leave the solid; dropped after kPullHalvings.
PulledCore pull_core(const Lattice& lattice, const Surroundings& around, const Parity& parity,
                     const KeptPoints& kept, const std::vector<char>& core,
                     const std::vector<char>& core_corner, const std::vector<PyramidFace>& faces,
                     const std::unordered_map<std::size_t, Vec3>& inner_apex, double h) {
  PulledCore out;
  if (faces.empty()) return out;
  const int c0 = lattice.cells[0], c1 = lattice.cells[1];
  const auto cell_index = [&](const int(&c)[3]) {
    return (static_cast<std::size_t>(c[2]) * c1 + c[1]) * c0 + c[0];
  };
  // Where the apex of cell a's pyramids is before the pull.
  const auto home = [&](std::size_t a) { return apex_home(lattice, inner_apex, a); };
  const auto point_of = [&](std::size_t p) { return lattice.point(lattice.point_ijk(p)); };
  const double tolerance = 1e-3 * h;
  // Per node: the least room of the apexes above it, per base direction, and which directions.
  struct Room {
    double s[6];
    unsigned has = 0;
    bool fixed = false;
  };
  std::unordered_map<std::size_t, Room> room;
  // A node beside a kept point that is no core cell's corner, or that lies on a lattice face,
  // stays: the lattice's squares through both would no longer be flat, and their cells'
  // hexahedra go (gmsh_as1-tu-203 at its 50k size: 500 of 2,965 core cells lost beside the
  // lattice faces between its solids).
  const auto beside_other = [&](std::size_t p) {
    const std::array<int, 3> ijk = lattice.point_ijk(p);
    const int size[3] = {lattice.cells[0] + 1, lattice.cells[1] + 1, lattice.cells[2] + 1};
    for (int a = 0; a < 3; ++a)
      for (int side = -1; side <= 1; side += 2) {
        int c[3] = {ijk[0], ijk[1], ijk[2]};
        c[a] += side;
        if (c[a] < 0 || c[a] >= size[a]) continue;
        const std::size_t q = lattice.point_index(c[0], c[1], c[2]);
        if (kept.kept[q] && (!core_corner[q] || kept.face[q] >= 0)) return true;
      }
    return false;
  };
  // Whether the core lies beyond the apex cell of face f, one cell on along the face's normal
  // (that cell, or one beside it whose cell beside the apex cell is not in the core): the apex
  // cell is a gap of one cell between two parts of the core, and the face is pulled by at most
  // kPullGapMost h. Pulled from both sides by up to kPullMost h, the gap closed and the apexes in
  // it passed each other's bases: flat tets between them that no flip or move takes out
  // (gmsh_Kurbelwelle at its 250k size: 84 tets of two apexes and two core nodes and 24 of an
  // apex and three, down to scaled Jacobian 0.038).
  const auto core_beyond = [&](const PyramidFace& f) {
    const int axis = f.dir / 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
    int c[3] = {f.n[0], f.n[1], f.n[2]};
    c[axis] += f.dir % 2 ? 1 : -1;
    if (c[axis] < 0 || c[axis] >= lattice.cells[axis]) return false;
    for (int du = -1; du <= 1; ++du)
      for (int dv = -1; dv <= 1; ++dv) {
        int m[3] = {c[0], c[1], c[2]};
        m[u] += du, m[v] += dv;
        if (m[u] < 0 || m[u] >= lattice.cells[u] || m[v] < 0 || m[v] >= lattice.cells[v]) continue;
        // (The cell beside the apex cell towards it not in the core: else the apex cell is a
        // notch of the core, which both faces fill.)
        int beside[3] = {f.n[0], f.n[1], f.n[2]};
        beside[u] += du, beside[v] += dv;
        if (core[cell_index(m)] && !core[cell_index(beside)]) return true;
      }
    return false;
  };
  for (const PyramidFace& f : faces) {
    const Vec3 apex = home(cell_index(f.n));
    const double s =
        std::clamp(distance_to(around.every_face, apex, 2 * h, tolerance) - kPullTarget * h, 0.0,
                   (core_beyond(f) ? kPullGapMost : kPullMost) * h);
    for (const std::size_t p : base_corners(lattice, f)) {
      Room& r = room[p];
      if (!(r.has >> f.dir & 1)) r.s[f.dir] = s;
      r.s[f.dir] = std::min(r.s[f.dir], s);
      r.has |= 1u << f.dir;
      if (kept.face[p] >= 0 || around.surface_points.any_within(point_of(p), 1e-6 * h) ||
          beside_other(p))
        r.fixed = true;
    }
  }
  std::unordered_map<std::size_t, Vec3> move;  // full move per node
  for (const auto& [p, r] : room) {
    if (r.fixed) continue;
    Vec3 d{0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      const bool minus = r.has >> (2 * a) & 1, plus = r.has >> (2 * a + 1) & 1;
      if (plus != minus) set_coord(d, a, plus ? r.s[2 * a + 1] : -r.s[2 * a]);
    }
    if (d.norm() > tolerance) move[p] = d;
  }
  if (move.empty()) return out;
  // Per apex: its pyramids and their bases' corners (once each).
  std::unordered_map<std::size_t, std::vector<std::size_t>> apex_pyramids, apex_corners;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::size_t a = cell_index(faces[i].n);
    apex_pyramids[a].push_back(i);
    std::vector<std::size_t>& corners = apex_corners[a];
    for (const std::size_t p : base_corners(lattice, faces[i]))
      if (std::find(corners.begin(), corners.end(), p) == corners.end()) corners.push_back(p);
  }
  std::unordered_map<std::size_t, double> scale;
  for (const auto& [p, d] : move) scale[p] = 1.0;
  const auto node_shift = [&](std::size_t p) {
    const auto it = move.find(p);
    return it == move.end() ? Vec3{0, 0, 0} : it->second * scale[p];
  };
  const auto apex_shift = [&](std::size_t a) {
    Vec3 sum{0, 0, 0};
    const std::vector<std::size_t>& corners = apex_corners[a];
    for (const std::size_t p : corners) sum = sum + node_shift(p);
    return sum * (1.0 / static_cast<double>(corners.size()));
  };
  // The core cells with a corner that may move.
  std::vector<std::array<int, 3>> cells;
  {
    std::unordered_set<std::size_t> seen;
    for (const auto& [p, d] : move) {
      const auto [i, j, k] = lattice.point_ijk(p);
      for (int corner = 0; corner < 8; ++corner) {
        const int c[3] = {i - (corner & 1), j - ((corner >> 1) & 1), k - ((corner >> 2) & 1)};
        if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= c0 || c[1] >= c1 ||
            c[2] >= lattice.cells[2])
          continue;
        if (core[cell_index(c)] && seen.insert(cell_index(c)).second)
          cells.push_back({c[0], c[1], c[2]});
      }
    }
  }
  // Whether the way from a to b keeps `clearance` from every face (a moved point crosses none,
  // into another solid or through a thin wall).
  const auto clear_path = [&](const Vec3& a, const Vec3& b, double clearance) {
    const int steps = 1 + static_cast<int>((b - a).norm() / clearance);
    for (int i = 0; i <= steps; ++i)
      if (around.every_face.any_within(a + (b - a) * (static_cast<double>(i) / steps), clearance))
        return false;
    return true;
  };
  // Whether a pyramid's side from base corner c to its apex keeps kApexClearance h from every
  // face beyond kPullNodeClearance h of c (a moved corner keeps that much, an unmoved one may lie
  // on a lattice face): the apex and its corners each clear, a side between them crossed the
  // surface, and TetGen stopped on it (a random part at h 4.44: "a segment and a subface
  // intersect", with the buffer layer and without).
  const auto side_clear = [&](const Vec3& c, const Vec3& apex) {
    const double length = (apex - c).norm();
    if (length <= kPullNodeClearance * h) return true;
    const Vec3 from = c + (apex - c) * (kPullNodeClearance * h / length);
    return clear_path(from, apex, kApexClearance * h);
  };
  // The faces of the cells with a corner that may move, of the core cells beside them and of
  // every closing pyramid, each quad split on its diagonal from its least corner (as emit_core()
  // gives them to TetGen), where the moves put them; the moving corners of those that cross
  // another go into `failing`.
  std::vector<std::array<int, 3>> near_cells = cells;
  {
    std::unordered_set<std::size_t> seen;
    for (const auto& c : cells) {
      const int ijk[3] = {c[0], c[1], c[2]};
      seen.insert(cell_index(ijk));
    }
    for (const auto& c : cells)
      for (int a = 0; a < 3; ++a)
        for (int side = -1; side <= 1; side += 2) {
          int n[3] = {c[0], c[1], c[2]};
          n[a] += side;
          if (n[a] < 0 || n[a] >= lattice.cells[a] || !core[cell_index(n)]) continue;
          if (seen.insert(cell_index(n)).second) near_cells.push_back({n[0], n[1], n[2]});
        }
  }
  // Their corners (lattice points, and apexes tagged by kApexTag) and triangles, made once (a
  // face two cells share comes twice: a triangle and its copy do not cross).
  constexpr std::size_t kApexTag = std::size_t{1} << 62;
  std::vector<std::size_t> corner_of;  // per corner: its lattice point, or apex cell | kApexTag
  std::vector<std::array<int, 3>> face_triangles;
  std::size_t first_side = 0;  // the pyramids' sides come last, from here
  {
    std::unordered_map<std::size_t, int> id;
    const auto corner_id = [&](std::size_t key) {
      const auto [it, fresh] = id.emplace(key, static_cast<int>(corner_of.size()));
      if (fresh) corner_of.push_back(key);
      return it->second;
    };
    // A square split on its diagonal from its least corner, as emit_core() gives it to TetGen.
    const auto square = [&](const std::array<std::size_t, 4>& corners) {
      int k[4];
      for (int m = 0; m < 4; ++m) k[m] = corner_id(corners[m]);
      face_triangles.push_back({k[0], k[1], k[2]});
      face_triangles.push_back({k[0], k[2], k[3]});
    };
    for (const auto& c : near_cells)
      for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
          square(face_corners(lattice, axis, c[axis] + side, c[(axis + 1) % 3], c[(axis + 2) % 3]));
    for (const PyramidFace& f : faces) square(base_corners(lattice, f));
    first_side = face_triangles.size();
    for (const PyramidFace& f : faces) {
      const std::array<std::size_t, 4> base = base_corners(lattice, f);
      const int apex = corner_id(cell_index(f.n) | kApexTag);
      for (int m = 0; m < 4; ++m)
        face_triangles.push_back({corner_id(base[m]), corner_id(base[(m + 1) % 4]), apex});
    }
  }
  const auto crossing_faces = [&](std::unordered_set<std::size_t>& failing) {
    std::vector<Vec3> at(corner_of.size());
    std::vector<char> moved(corner_of.size(), 0);
    for (std::size_t k = 0; k < corner_of.size(); ++k) {
      const std::size_t n = corner_of[k];
      const Vec3 d = n & kApexTag ? apex_shift(n & ~kApexTag) : node_shift(n);
      at[k] = (n & kApexTag ? home(n & ~kApexTag) : point_of(n)) + d;
      moved[k] = d.norm() > 0;
    }
    // The pyramids' sides that moved, against every face: a cell that keeps its shape (scaled
    // Jacobian 0.9, flat quads) meets its neighbours on their common faces, but an apex moves
    // with the mean of its bases' corners and its sides can pass through the next cell's face.
    std::vector<std::array<int, 3>> moving;
    for (std::size_t i = first_side; i < face_triangles.size(); ++i) {
      const auto& t = face_triangles[i];
      if (moved[t[0]] || moved[t[1]] || moved[t[2]]) moving.push_back(t);
    }
    const std::vector<char> crosses = crosses_any(at, face_triangles, moving);
    for (std::size_t t = 0; t < moving.size(); ++t) {
      if (!crosses[t]) continue;
      for (const int k : moving[t]) {
        const std::size_t n = corner_of[static_cast<std::size_t>(k)];
        if (n & kApexTag) {
          for (const std::size_t p : apex_corners[n & ~kApexTag])
            if (move.count(p) && scale[p] > 0) failing.insert(p);
        } else if (move.count(n) && scale[n] > 0) {
          failing.insert(n);
        }
      }
    }
  };
  static constexpr int kHexCorner[8] = {0, 1, 3, 2, 4, 5, 7, 6};  // cell_type.h's order by bits
  static constexpr int kHexFaces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                          {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  static const index_t kOrder[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  // Each round tests again only what a node moved back in the round before touches: the cells
  // with it as a corner, the node, the apexes over it (a cell, node or apex depends on those
  // alone; 38 rounds over every cell took 64 s of gmsh_U_Joint_2 at h 0.963).
  std::unordered_map<std::size_t, std::vector<std::size_t>> cells_at, apexes_at;
  for (std::size_t i = 0; i < cells.size(); ++i)
    for (int corner = 0; corner < 8; ++corner) {
      const auto& c = cells[i];
      cells_at[lattice.point_index(c[0] + (corner & 1), c[1] + ((corner >> 1) & 1),
                                   c[2] + ((corner >> 2) & 1))]
          .push_back(i);
    }
  for (const auto& [a, corners] : apex_corners)
    for (const std::size_t p : corners) apexes_at[p].push_back(a);
  std::vector<std::size_t> dirty;  // the nodes moved back in the last round (all: the first)
  for (int round = 0;; ++round) {
    std::unordered_set<std::size_t> failing;
    std::vector<std::size_t> cells_to_test, apexes_to_test, nodes_to_test;
    if (round == 0) {
      for (std::size_t i = 0; i < cells.size(); ++i) cells_to_test.push_back(i);
      for (const auto& [a, list] : apex_pyramids) apexes_to_test.push_back(a);
      for (const auto& [p, d] : move) nodes_to_test.push_back(p);
    } else {
      std::unordered_set<std::size_t> seen_cells, seen_apexes;
      for (const std::size_t p : dirty) {
        nodes_to_test.push_back(p);
        if (const auto it = cells_at.find(p); it != cells_at.end())
          for (const std::size_t i : it->second)
            if (seen_cells.insert(i).second) cells_to_test.push_back(i);
        if (const auto it = apexes_at.find(p); it != apexes_at.end())
          for (const std::size_t a : it->second)
            if (seen_apexes.insert(a).second) apexes_to_test.push_back(a);
      }
    }
    for (const std::size_t cell : cells_to_test) {
      const auto& c = cells[cell];
      double xyz[24];
      Vec3 at[8];
      std::size_t ids[8];
      for (int m = 0; m < 8; ++m) {
        const int bits = kHexCorner[m];
        ids[m] = lattice.point_index(c[0] + (bits & 1), c[1] + ((bits >> 1) & 1),
                                     c[2] + ((bits >> 2) & 1));
        at[m] = point_of(ids[m]) + node_shift(ids[m]);
        xyz[3 * m] = at[m].x, xyz[3 * m + 1] = at[m].y, xyz[3 * m + 2] = at[m].z;
      }
      bool ok = scaled_jacobian(CellType::Hex, xyz, kOrder) >= kPullCellFloor;
      for (int q = 0; q < 6 && ok; ++q)
        ok = quad_flat(at[kHexFaces[q][0]], at[kHexFaces[q][1]], at[kHexFaces[q][2]],
                       at[kHexFaces[q][3]], kPullFold);
      if (!ok)
        for (const std::size_t p : ids)
          if (move.count(p) && scale[p] > 0) failing.insert(p);
    }
    // Moved nodes stay clear of the faces and the surface's nodes (TetGen drops a point on a
    // face) and inside. (Not tested where a cell has failed them already: the costly tests
    // only ever add to `failing`.)
    for (const std::size_t p : nodes_to_test) {
      if (scale[p] == 0 || failing.count(p)) continue;
      const Vec3 q = point_of(p) + node_shift(p);
      if (!parity.inside(q) || !clear_path(point_of(p), q, kPullNodeClearance * h) ||
          around.surface_points.any_within(q, kPullNodeClearance * h))
        failing.insert(p);
    }
    for (const std::size_t a : apexes_to_test) {
      if (std::none_of(apex_corners[a].begin(), apex_corners[a].end(), [&](std::size_t p) {
            return move.count(p) && scale[p] > 0 && !failing.count(p);
          }))
        continue;
      const std::vector<std::size_t>& list = apex_pyramids[a];
      const Vec3 centre = home(a), apex = centre + apex_shift(a);
      bool ok = parity.inside(apex) && clear_path(centre, apex, kApexClearance * h) &&
                !around.surface_points.any_within(apex, kApexNodeClearance * h);
      for (std::size_t i = 0; i < list.size() && ok; ++i) {
        const std::array<std::size_t, 4> base = base_corners(lattice, faces[list[i]]);
        std::array<Vec3, 4> corner;
        for (int m = 0; m < 4; ++m) corner[m] = point_of(base[m]) + node_shift(base[m]);
        ok =
            closing_pyramid_quality(corner, apex, faces[list[i]].dir % 2 == 1) >= kCorePyramidFloor;
        for (int m = 0; m < 4 && ok; ++m) ok = side_clear(corner[m], apex);
      }
      if (!ok)
        for (const std::size_t p : apex_corners[a])
          if (move.count(p) && scale[p] > 0) failing.insert(p);
    }
    // Once every cell, pyramid and node passes: no face of a moved cell or pyramid may cross
    // another's (TetGen keeps them all as constraints and stops where two cross: "a segment and
    // a subface intersect"; gmsh_U_Joint_2 at its 250k size then fell back to the core not
    // pulled). The corners that move of the faces that cross are held back.
    if (failing.empty()) crossing_faces(failing);
    // (A cell or pyramid that fails unmoved, on a rectilinear axis, holds nothing back.)
    if (failing.empty()) break;
    dirty.clear();
    for (const std::size_t p : failing) {
      const double before = scale[p];
      scale[p] = round < kPullHalvings ? 0.5 * scale[p] : 0.0;
      if (scale[p] != before) dirty.push_back(p);
    }
  }
  for (const auto& [p, d] : move)
    if (scale[p] > 0) out.node[p] = node_shift(p);
  for (const auto& [a, corners] : apex_corners) {
    const Vec3 d = apex_shift(a);
    if (d.norm() > 0) out.apex[a] = d;
  }
  return out;
}

std::size_t resplit_core(const std::vector<double>& coordinates, std::vector<index_t>& tets,
                         const std::vector<std::array<int, 3>>& constraints,
                         const std::vector<InsertedPoints::Split>& splits, double tolerance) {
  const std::size_t nb_points = coordinates.size() / 3, nb_tets = tets.size() / 4;
  std::vector<Vec3> points(nb_points);
  for (std::size_t i = 0; i < nb_points; ++i) points[i] = Vec3::of(&coordinates[3 * i]);
  NodeHash at(points, 1e3 * tolerance);
  for (std::size_t i = 0; i < nb_points; ++i) at.add(static_cast<int>(i));
  // The constraints' faces, sorted for look-ups; only a face whose three vertices are the
  // constraints' can be one (no look-up for the rest).
  std::vector<FaceKey> barrier;
  barrier.reserve(constraints.size());
  std::vector<char> on_barrier(nb_points, 0);
  for (const std::array<int, 3>& t : constraints) {
    barrier.push_back(face_key(t[0], t[1], t[2]));
    for (const int v : t) on_barrier[static_cast<std::size_t>(v)] = 1;
  }
  std::sort(barrier.begin(), barrier.end());
  // Regions: union-find over the tets across the faces that are no barrier, each face joined
  // from the later of its two tets (the order decides the roots, which key the regions below).
  std::vector<index_t> parent(nb_tets);
  for (index_t t = 0; t < nb_tets; ++t) parent[t] = t;
  const auto find = [&](index_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  {
    TetMesh mesh;  // (the tets lent to it for the topology, and taken back)
    mesh.points = coordinates;
    mesh.tets = std::move(tets);
    const TetTopology topology(mesh);
    for (index_t t = 0; t < nb_tets; ++t) {
      const index_t* v = &mesh.tets[4 * t];
      for (int f = 0; f < 4; ++f) {
        const index_t n = topology.neighbor(t, f);
        if (n == NO_CELL || n > t) continue;
        const index_t a = v[(f + 1) % 4], b = v[(f + 2) % 4], c = v[(f + 3) % 4];
        if (on_barrier[a] && on_barrier[b] && on_barrier[c] &&
            std::binary_search(barrier.begin(), barrier.end(), face_key(a, b, c)))
          continue;
        parent[find(t)] = find(n);
      }
    }
    tets = std::move(mesh.tets);
  }
  // The regions of at most 12 tets (a cell's or a pyramid's): their tets in order, by root
  // (compressed rows), and their sorted corners, the regions sorted by those for look-ups.
  std::vector<index_t> root(nb_tets);
  std::vector<std::size_t> size(nb_tets, 0);
  for (index_t t = 0; t < nb_tets; ++t) ++size[root[t] = find(t)];
  std::vector<std::size_t> first(nb_tets + 1, 0);
  for (index_t t = 0; t < nb_tets; ++t)
    if (size[root[t]] <= 12) ++first[root[t] + 1];
  for (index_t t = 0; t < nb_tets; ++t) first[t + 1] += first[t];
  std::vector<index_t> member(first[nb_tets]);
  {
    std::vector<std::size_t> fill(first.begin(), first.end() - 1);
    for (index_t t = 0; t < nb_tets; ++t)
      if (size[root[t]] <= 12) member[fill[root[t]]++] = t;
  }
  struct Region {
    std::size_t begin, end;  // its corners in `corners`
    index_t root;
  };
  std::vector<index_t> corners;
  std::vector<Region> regions;
  for (index_t r = 0; r < nb_tets; ++r) {
    if (first[r] == first[r + 1]) continue;
    const std::size_t begin = corners.size();
    for (std::size_t i = first[r]; i < first[r + 1]; ++i)
      corners.insert(corners.end(), &tets[4 * member[i]], &tets[4 * member[i] + 4]);
    std::sort(corners.begin() + static_cast<std::ptrdiff_t>(begin), corners.end());
    corners.erase(std::unique(corners.begin() + static_cast<std::ptrdiff_t>(begin), corners.end()),
                  corners.end());
    regions.push_back({begin, corners.size(), r});
  }
  const auto from = [&](const Region& x) {
    return corners.begin() + static_cast<std::ptrdiff_t>(x.begin);
  };
  const auto to = [&](const Region& x) {
    return corners.begin() + static_cast<std::ptrdiff_t>(x.end);
  };
  std::sort(regions.begin(), regions.end(), [&](const Region& x, const Region& y) {
    return std::lexicographical_compare(from(x), to(x), from(y), to(y));
  });
  // The region whose corners are `sorted`, or null.
  const auto region_of = [&](const std::vector<index_t>& sorted) -> const Region* {
    const auto it = std::lower_bound(regions.begin(), regions.end(), sorted,
                                     [&](const Region& x, const std::vector<index_t>& key) {
                                       return std::lexicographical_compare(from(x), to(x),
                                                                           key.begin(), key.end());
                                     });
    if (it == regions.end() || !std::equal(from(*it), to(*it), sorted.begin(), sorted.end()))
      return nullptr;
    return &*it;
  };
  const auto volume = [&](index_t a, index_t b, index_t c, index_t d) {
    return det3(points[b] - points[a], points[c] - points[a], points[d] - points[a]) / 6;
  };
  std::vector<char> drop(nb_tets, 0);
  std::vector<index_t> added;
  std::size_t replaced = 0;
  for (const InsertedPoints::Split& split : splits) {
    std::vector<index_t> ids;
    for (const Vec3& q : split.corners) {
      const int i = at.find(q, tolerance);
      if (i < 0) break;
      ids.push_back(static_cast<index_t>(i));
    }
    if (ids.size() != split.corners.size()) continue;
    std::vector<index_t> sorted = ids;
    std::sort(sorted.begin(), sorted.end());
    const Region* region = region_of(sorted);
    if (region == nullptr) continue;
    // The region's tets, in place.
    const index_t* const list = member.data() + first[region->root];
    const index_t* const list_end = member.data() + first[region->root + 1];
    double before = 0, after = 0;
    for (const index_t* t = list; t != list_end; ++t) {
      const index_t* v = &tets[4 * *t];
      before += std::abs(volume(v[0], v[1], v[2], v[3]));
    }
    std::vector<std::array<index_t, 4>> made;
    bool positive = true;
    for (const auto& q : split.tets) {
      std::array<index_t, 4> t{ids[q[0]], ids[q[1]], ids[q[2]], ids[q[3]]};
      double v = volume(t[0], t[1], t[2], t[3]);
      if (v < 0) std::swap(t[1], t[2]), v = -v;
      positive = positive && v > 0;
      after += v;
      made.push_back(t);
    }
    // The same outer faces (the region's are constraints, or it touches the surface and its
    // faces there are the surface's triangles, which the split need not have).
    // (In order, each face once that one tet only has.)
    const auto outer_faces = [](auto begin, auto end, const auto& corners_of) {
      std::vector<FaceKey> all;
      for (auto t = begin; t != end; ++t) {
        const index_t* v = corners_of(*t);
        for (int f = 0; f < 4; ++f)
          all.push_back(face_key(v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]));
      }
      std::sort(all.begin(), all.end());
      std::vector<FaceKey> once;
      for (std::size_t i = 0; i < all.size();) {
        std::size_t j = i;
        while (j < all.size() && all[j] == all[i]) ++j;
        if (j - i == 1) once.push_back(all[i]);
        i = j;
      }
      return once;
    };
    if (!positive || std::abs(after - before) > 1e-9 * after ||
        outer_faces(list, list_end, [&](index_t t) { return &tets[4 * t]; }) !=
            outer_faces(made.begin(), made.end(),
                        [](const std::array<index_t, 4>& t) { return t.data(); }))
      continue;
    for (const index_t* t = list; t != list_end; ++t) drop[*t] = 1;
    for (const auto& t : made) added.insert(added.end(), t.begin(), t.end());
    ++replaced;
  }
  std::vector<index_t> kept_tets;
  kept_tets.reserve(tets.size() + added.size());
  for (index_t t = 0; t < nb_tets; ++t)
    if (!drop[t]) kept_tets.insert(kept_tets.end(), &tets[4 * t], &tets[4 * t + 4]);
  kept_tets.insert(kept_tets.end(), added.begin(), added.end());
  tets = std::move(kept_tets);
  return replaced;
}

}  // namespace hexmerge::mesher
