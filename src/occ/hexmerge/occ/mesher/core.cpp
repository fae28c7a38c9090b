#include "hexmerge/occ/mesher/core.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/spatial.h"

namespace hexmerge::mesher {

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

double tet_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double xyz[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
  static const index_t kTet[4] = {0, 1, 2, 3};
  return scaled_jacobian(CellType::Tet, xyz, kTet);
}

bool cell_holds(const std::array<Vec3, 8>& corner, const Vec3& q, double h) {
  for (const Vec3& c : corner)
    if ((c - q).norm() <= 1e-6 * h) return false;
  for (const auto& path : kKuhnPaths)
    if (in_tet(q, corner[0], corner[path[0]], corner[path[1]], corner[7], -1e-6)) return true;
  return false;
}

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

}  // namespace hexmerge::mesher
