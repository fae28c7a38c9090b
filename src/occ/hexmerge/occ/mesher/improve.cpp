#include "hexmerge/occ/mesher/improve.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <unordered_map>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/frame.h"
#include "hexmerge/occ/mesher/remove_slivers.h"
#include "hexmerge/occ/mesher/smooth_nodes.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge::mesher {
namespace {

// Whether a pyramid on `base` (around) with apex `apex` keeps `floor` in either of its
// orientations: the base's two triangles' tets sharing that apex close it.
bool closes(const TetMesh& mesh, const std::array<index_t, 4>& base, index_t apex, double floor) {
  const index_t around[5] = {base[0], base[1], base[2], base[3], apex},
                other_way[5] = {base[0], base[3], base[2], base[1], apex};
  return std::max(scaled_jacobian(CellType::Pyramid, mesh.points.data(), around),
                  scaled_jacobian(CellType::Pyramid, mesh.points.data(), other_way)) >= floor;
}

// The corners of a quad face split into triangles `tris` (sharing a side), around: the first
// triangle's corner not on the second, then round that triangle with the second's corner not on
// the first between; the shared side is the diagonal from the second to the fourth. The third is
// NO_INDEX where the triangles share no side.
std::array<index_t, 4> face_around(const std::array<std::array<index_t, 3>, 2>& tris) {
  const auto in = [](const std::array<index_t, 3>& tri, index_t v) {
    return v == tri[0] || v == tri[1] || v == tri[2];
  };
  std::size_t lone = 0;
  index_t extra = NO_INDEX;
  for (std::size_t k = 0; k < 3; ++k) {
    if (!in(tris[1], tris[0][k])) lone = k;
    if (!in(tris[0], tris[1][k])) extra = tris[1][k];
  }
  return {tris[0][lone], tris[0][(lone + 1) % 3], extra, tris[0][(lone + 2) % 3]};
}

// Lattice cells split into six pyramids to a new vertex at their centre (twelve tets), replacing
// their six tets (the lattice's split), applied at once.
class CellSplits {
 public:
  explicit CellSplits(TetMesh& mesh) : mesh_(mesh), drop_(mesh.nb_tets(), 0) {}
  // The split of a cell (its corners `cell`, its boundary triangles `faces`, its tets `own`),
  // where each new tet keeps `floor`; whether it is made.
  bool add(const std::vector<index_t>& cell, const std::vector<std::array<index_t, 3>>& faces,
           const std::vector<index_t>& own, double floor) {
    for (const index_t t : own)
      if (drop_[t]) return false;
    const auto at = [&](index_t v) { return Vec3::of(mesh_.point(v)); };
    Vec3 centre{0, 0, 0};
    for (const index_t v : cell) centre = centre + at(v) * (1.0 / static_cast<double>(cell.size()));
    const index_t middle = static_cast<index_t>(mesh_.nb_vertices() + nb_split_);
    std::vector<index_t> made;
    for (std::array<index_t, 3> f : faces) {
      if (det3(at(f[1]) - at(f[0]), at(f[2]) - at(f[0]), centre - at(f[0])) < 0)
        std::swap(f[1], f[2]);
      if (tet_quality(at(f[0]), at(f[1]), at(f[2]), centre) < floor) return false;
      made.insert(made.end(), {f[0], f[1], f[2], middle});
    }
    for (const index_t t : own) drop_[t] = 1;
    added_.insert(added_.end(), made.begin(), made.end());
    added_region_.insert(added_region_.end(), faces.size(), mesh_.region(own[0]));
    centres_.insert(centres_.end(), {centre.x, centre.y, centre.z});
    ++nb_split_;
    return true;
  }
  // The mesh with the splits made; how many.
  std::size_t apply() {
    if (nb_split_ == 0) return 0;
    std::vector<index_t> tets;
    std::vector<std::int32_t> regions;
    tets.reserve(mesh_.tets.size() + added_.size());
    for (index_t t = 0; t < mesh_.nb_tets(); ++t) {
      if (drop_[t]) continue;
      tets.insert(tets.end(), mesh_.tet(t), mesh_.tet(t) + 4);
      if (!mesh_.regions.empty()) regions.push_back(mesh_.regions[t]);
    }
    tets.insert(tets.end(), added_.begin(), added_.end());
    if (!mesh_.regions.empty())
      regions.insert(regions.end(), added_region_.begin(), added_region_.end());
    mesh_.tets = std::move(tets);
    mesh_.regions = std::move(regions);
    mesh_.points.insert(mesh_.points.end(), centres_.begin(), centres_.end());
    return nb_split_;
  }

 private:
  TetMesh& mesh_;
  std::vector<char> drop_;
  std::vector<index_t> added_;  // 4 per new tet
  std::vector<std::int32_t> added_region_;
  std::vector<double> centres_;
  std::size_t nb_split_ = 0;
};

// The most open faces a cell split_open_cells() splits may have.
constexpr int kMostOpenFaces = 2;

// Splits each hexahedral cell the recombination's block would take (a lattice cell filled by
// five or six tets of its corners, or a buffer hexahedron, `kept_cells` (corners in
// buffer_hex_corners() order), still its six tets) one of whose faces nothing closes into six
// pyramids to a new vertex at its centre, each new tet keeping `floor`; how many. A face is
// closed where it lies on the boundary, against another such cell, or where the two tets across
// share their fourth vertex in a pyramid of `pyramid_floor` neither of whose tets lies on another
// such cell's open face (a pyramid to a lattice corner beside the face does: the block cannot
// take it for both). Else the block loses the cell and, a cell's six tets closing at most three
// of its faces, cells beside it after it, to the block's edge: beside a released buffer
// hexahedron whose flips took its tets apart, pyocc_face_recognition_sample_part at h 7.474 lost
// 1,829 of its block's 4,653 hexahedra to one such face.
std::size_t split_open_cells(TetMesh& mesh, const std::vector<std::array<double, 3>>& cell_of,
                             const std::vector<char>& lattice_point,
                             const std::vector<std::vector<index_t>>& kept_cells, double floor,
                             double pyramid_floor) {
  const std::size_t made = lattice_point.size();
  const auto sorted = [](std::array<index_t, 4> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  struct Cell {
    std::vector<index_t> corner;                                // 8
    std::vector<index_t> tets;                                  // its own
    std::array<std::array<std::array<index_t, 3>, 2>, 6> face;  // its faces' triangles
  };
  std::vector<Cell> cells;
  using Key = std::array<std::int64_t, 3>;
  struct KeyHash {
    std::size_t operator()(const Key& c) const {
      return static_cast<std::size_t>(c[0] * 73856093 ^ c[1] * 19349663 ^ c[2] * 83492791);
    }
  };
  std::unordered_map<Key, std::size_t, KeyHash> lattice_cell;  // by its lowest corner
  std::vector<std::int64_t> cell_of_tet(mesh.nb_tets(), -1);
  // The lattice cells: tets of lattice points within one cell, by its lowest corner.
  {
    std::unordered_map<Key, Cell, KeyHash> by_key;
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      const index_t* v = mesh.tet(t);
      if (std::any_of(v, v + 4, [&](index_t w) { return w >= made || !lattice_point[w]; }))
        continue;
      std::array<double, 3> least{1e300, 1e300, 1e300}, most{-1e300, -1e300, -1e300};
      for (int k = 0; k < 4; ++k)
        for (std::size_t a = 0; a < 3; ++a)
          least[a] = std::min(least[a], cell_of[v[k]][a]),
          most[a] = std::max(most[a], cell_of[v[k]][a]);
      bool one = true;
      for (std::size_t a = 0; a < 3; ++a) one = one && std::abs(most[a] - least[a] - 1) < 1e-6;
      if (!one) continue;
      Cell& cell = by_key[{std::llround(least[0]), std::llround(least[1]), std::llround(least[2])}];
      if (cell.corner.empty()) cell.corner.assign(8, NO_INDEX);
      cell.tets.push_back(t);
      for (int k = 0; k < 4; ++k) {
        std::size_t bits = 0;
        for (std::size_t a = 0; a < 3; ++a)
          if (cell_of[v[k]][a] > least[a] + 0.5) bits |= std::size_t{1} << a;
        cell.corner[bits] = v[k];
      }
    }
    for (auto& [key, cell] : by_key) {
      if ((cell.tets.size() != 5 && cell.tets.size() != 6) ||
          std::find(cell.corner.begin(), cell.corner.end(), NO_INDEX) != cell.corner.end())
        continue;
      // Its boundary triangles (a side of one of its tets only), in sorted order, each on the
      // face of the corner bit its three corners share.
      std::array<std::array<index_t, 3>, 24> sides{};
      std::size_t nb_sides = 0;
      for (const index_t t : cell.tets) {
        const index_t* v = mesh.tet(t);
        for (int f = 0; f < 4; ++f) {
          std::array<index_t, 3> tri{v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]};
          std::sort(tri.begin(), tri.end());
          sides[nb_sides++] = tri;
        }
      }
      std::sort(sides.begin(), sides.begin() + static_cast<std::ptrdiff_t>(nb_sides));
      std::array<std::size_t, 6> n{};
      bool filled = true;
      for (std::size_t i = 0; i < nb_sides; ++i) {
        const std::array<index_t, 3>& tri = sides[i];
        if ((i > 0 && sides[i - 1] == tri) || (i + 1 < nb_sides && sides[i + 1] == tri)) continue;
        std::array<int, 3> bits{};
        for (std::size_t k = 0; k < 3; ++k)
          bits[k] = static_cast<int>(std::find(cell.corner.begin(), cell.corner.end(), tri[k]) -
                                     cell.corner.begin());
        int face = -1;
        for (int bit = 0; bit < 3 && face < 0; ++bit) {
          const int value = bits[0] >> bit & 1;
          if ((bits[1] >> bit & 1) == value && (bits[2] >> bit & 1) == value)
            face = 2 * bit + value;
        }
        if (face < 0 || n[static_cast<std::size_t>(face)] >= 2) {
          filled = false;
          break;
        }
        const auto f = static_cast<std::size_t>(face);
        cell.face[f][n[f]++] = tri;
      }
      if (!filled || std::any_of(n.begin(), n.end(), [](std::size_t k) { return k != 2; }))
        continue;
      for (const index_t t : cell.tets) cell_of_tet[t] = static_cast<std::int64_t>(cells.size());
      lattice_cell.emplace(key, cells.size());
      cells.push_back(std::move(cell));
    }
  }
  // The buffer hexahedra still their six tets.
  {
    // Their splits' tets by sorted corners (NO_INDEX until found), asked only of the tets whose
    // corners are all buffer hexahedra's.
    std::map<std::array<index_t, 4>, index_t> tet_id;
    std::vector<char> on_hex(mesh.nb_vertices(), 0);
    for (const std::vector<index_t>& hex : kept_cells)
      if (hex.size() == 8) {
        for (const auto& q : kKuhnPaths)
          tet_id.emplace(sorted({hex[0], hex[static_cast<std::size_t>(q[0])],
                                 hex[static_cast<std::size_t>(q[1])], hex[7]}),
                         NO_INDEX);
        for (const index_t v : hex) on_hex[v] = 1;
      }
    for (index_t t = 0; t < mesh.nb_tets() && !tet_id.empty(); ++t) {
      const index_t* v = mesh.tet(t);
      if (!on_hex[v[0]] || !on_hex[v[1]] || !on_hex[v[2]] || !on_hex[v[3]]) continue;
      const auto it = tet_id.find(sorted({v[0], v[1], v[2], v[3]}));
      if (it != tet_id.end() && it->second == NO_INDEX) it->second = t;
    }
    for (const std::vector<index_t>& hex : kept_cells) {
      if (hex.size() != 8) continue;
      Cell cell{hex, {}, {}};
      std::array<std::size_t, 6> n{};
      for (const auto& q : kKuhnPaths) {
        const auto it = tet_id.find(sorted({hex[0], hex[static_cast<std::size_t>(q[0])],
                                            hex[static_cast<std::size_t>(q[1])], hex[7]}));
        if (it->second == NO_INDEX || cell_of_tet[it->second] >= 0) break;
        cell.tets.push_back(it->second);
        // Its faces {0, a, b} and {a, b, 7} on the hexahedron's faces (the bit they share).
        for (const std::array<int, 3> tri :
             {std::array<int, 3>{0, q[0], q[1]}, std::array<int, 3>{q[0], q[1], 7}})
          for (int bit = 0; bit < 3; ++bit) {
            const int value = tri[0] >> bit & 1;
            if ((tri[1] >> bit & 1) != value || (tri[2] >> bit & 1) != value) continue;
            const auto face = static_cast<std::size_t>(2 * bit + value);
            std::array<index_t, 3> corners{hex[static_cast<std::size_t>(tri[0])],
                                           hex[static_cast<std::size_t>(tri[1])],
                                           hex[static_cast<std::size_t>(tri[2])]};
            std::sort(corners.begin(), corners.end());
            cell.face[face][n[face]++ % 2] = corners;
          }
      }
      if (cell.tets.size() != 6) continue;
      for (const index_t t : cell.tets) cell_of_tet[t] = static_cast<std::int64_t>(cells.size());
      cells.push_back(std::move(cell));
    }
  }
  if (cells.empty()) return 0;
  // The tet across each of the cells' faces' triangles (NO_INDEX on the boundary) and the cell
  // it is in (-1 for none): where the lattice cell beside a face has the same triangles, its own
  // (found when the face is open), else found by one pass over the tets that asks only about
  // tets whose three corners lie on such a triangle.
  struct Across {
    std::array<index_t, 2> tet{NO_INDEX, NO_INDEX};
    std::array<std::int64_t, 2> cell{-1, -1};
  };
  std::vector<std::array<Across, 6>> across_of(cells.size());
  {
    struct Alone {
      FaceKey tri;
      std::size_t cell, face, k;
      bool operator<(const Alone& other) const { return tri < other.tri; }
    };
    std::vector<Alone> alone;
    std::vector<char> on_alone(mesh.nb_vertices(), 0);
    const auto add_alone = [&](std::size_t c, std::size_t f, std::size_t k) {
      const auto& tri = cells[c].face[f][k];
      alone.push_back({face_key(tri[0], tri[1], tri[2]), c, f, k});
      for (const index_t v : tri) on_alone[v] = 1;
    };
    for (const auto& [key, c] : lattice_cell)
      for (std::size_t f = 0; f < 6; ++f) {
        Key beside = key;
        beside[f / 2] += f % 2 == 1 ? 1 : -1;
        const auto it = lattice_cell.find(beside);
        for (std::size_t k = 0; k < 2; ++k) {
          const auto& tri = cells[c].face[f][k];
          if (it != lattice_cell.end() && (cells[it->second].face[f ^ 1][0] == tri ||
                                           cells[it->second].face[f ^ 1][1] == tri)) {
            across_of[c][f].cell[k] = static_cast<std::int64_t>(it->second);
            continue;
          }
          add_alone(c, f, k);
        }
      }
    for (std::size_t c = lattice_cell.size(); c < cells.size(); ++c)  // the buffer hexahedra
      for (std::size_t f = 0; f < 6; ++f)
        for (std::size_t k = 0; k < 2; ++k) add_alone(c, f, k);
    std::sort(alone.begin(), alone.end());
    for (index_t t = 0; t < mesh.nb_tets() && !alone.empty(); ++t) {
      const index_t* v = mesh.tet(t);
      for (int f = 0; f < 4; ++f) {
        const index_t a = v[(f + 1) % 4], b = v[(f + 2) % 4], c = v[(f + 3) % 4];
        if (!on_alone[a] || !on_alone[b] || !on_alone[c]) continue;
        const auto [first, last] =
            std::equal_range(alone.begin(), alone.end(), Alone{face_key(a, b, c), 0, 0, 0});
        for (auto it = first; it != last; ++it) {
          const auto& [tri, cell, face, k] = *it;
          if (cell_of_tet[t] != static_cast<std::int64_t>(cell)) {
            across_of[cell][face].tet[k] = t;
            across_of[cell][face].cell[k] = cell_of_tet[t];
          }
        }
      }
    }
  }
  // The cells the block takes: their hexahedron a candidate (each face's two triangles folding
  // by no more than the quad pairs let them, min_boundary_dihedral_angle on the boundary and
  // between regions, min_dihedral_angle inside; no corner wider than max_face_angle), a lattice
  // cell near-perfect (kBlockHexQuality) or with planar quads, a buffer hexahedron at
  // min_scaled_jacobian (the block's fringe takes it). The others lend their tets to the
  // pyramids closing the faces beside them; where their tets cannot close all of those, they are
  // split instead (below).
  std::vector<char> member(cells.size(), 1);
  std::vector<double> quality(cells.size(), 0);  // the hexahedron's scaled Jacobian
  {
    const RecombineParameters recombine;
    static constexpr int kBitsAt[8] = {0, 1, 3, 2, 4, 5, 7, 6};  // cell_type.h's order
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const Cell& cell = cells[c];
      bool good = true, planar = true;
      for (std::size_t f = 0; f < 6 && good; ++f) {
        // The quad from a corner of its diagonal (the triangles' shared side).
        const std::array<index_t, 4> around = face_around(cell.face[f]);
        const double *a = mesh.point(around[1]), *b = mesh.point(around[2]),
                     *q = mesh.point(around[3]), *d = mesh.point(around[0]);
        const Across& across = across_of[c][f];
        bool boundary = across.cell[0] < 0 && across.cell[1] < 0 && across.tet[0] == NO_INDEX &&
                        across.tet[1] == NO_INDEX;
        for (std::size_t k = 0; k < 2 && !boundary; ++k)
          boundary =
              across.tet[k] != NO_INDEX && mesh.region(across.tet[k]) != mesh.region(cell.tets[0]);
        good = quad_dihedral_angle(a, b, q, d) >= (boundary ? recombine.min_boundary_dihedral_angle
                                                            : recombine.min_dihedral_angle) &&
               quad_max_corner_angle(a, b, q, d) <= recombine.max_face_angle;
        const Vec3 pa = Vec3::of(a), pb = Vec3::of(b), pq = Vec3::of(q), pd = Vec3::of(d);
        const double scale = (pb - pa).norm() * (pq - pa).norm() * (pd - pa).norm();
        planar = planar && std::abs(det3(pb - pa, pq - pa, pd - pa)) <= 1e-9 * scale;
      }
      index_t corners[8];
      for (int k = 0; k < 8; ++k) corners[k] = cell.corner[static_cast<std::size_t>(kBitsAt[k])];
      quality[c] = std::abs(scaled_jacobian(CellType::Hex, mesh.points.data(), corners));
      member[c] = good && (c < lattice_cell.size() ? planar || quality[c] >= kBlockHexQuality
                                                   : quality[c] >= recombine.min_scaled_jacobian);
    }
  }
  // The tets across face f of cell c (NO_INDEX on the boundary); against a lattice cell with
  // the same triangles, found in it when first asked.
  const auto tets_across = [&](std::size_t c, std::size_t f) -> const std::array<index_t, 2>& {
    Across& across = across_of[c][f];
    for (std::size_t k = 0; k < 2; ++k)
      if (across.cell[k] >= 0 && across.tet[k] == NO_INDEX) {
        const auto& tri = cells[c].face[f][k];
        for (const index_t t : cells[static_cast<std::size_t>(across.cell[k])].tets) {
          const index_t* v = mesh.tet(t);
          if (std::all_of(tri.begin(), tri.end(), [&](index_t w) {
                return w == v[0] || w == v[1] || w == v[2] || w == v[3];
              }))
            across.tet[k] = t;
        }
      }
    return across.tet;
  };
  // Whether face f of cell c lies against a cell the block takes.
  const auto against_member = [&](std::size_t c, std::size_t f) {
    const Across& across = across_of[c][f];
    return across.cell[0] >= 0 && across.cell[0] == across.cell[1] &&
           member[static_cast<std::size_t>(across.cell[0])];
  };
  // Whether face f of cell c is open: neither on the boundary nor against a cell the block takes.
  const auto is_open = [&](std::size_t c, std::size_t f) {
    if (against_member(c, f)) return false;
    const std::array<index_t, 2>& tets = tets_across(c, f);
    return tets[0] != NO_INDEX || tets[1] != NO_INDEX;
  };
  // The apex of the pyramid of `pyramid_floor` that the two tets across open face f of cell c
  // make (sharing their fourth vertex), or NO_INDEX.
  const auto pyramid_apex = [&](std::size_t c, std::size_t f) {
    const std::array<index_t, 2>& tets = tets_across(c, f);
    if (tets[0] == NO_INDEX || tets[1] == NO_INDEX) return NO_INDEX;
    const auto& tris = cells[c].face[f];
    std::array<index_t, 2> apex{NO_INDEX, NO_INDEX};
    for (std::size_t k = 0; k < 2; ++k) {
      const index_t* v = mesh.tet(tets[k]);
      for (int m = 0; m < 4; ++m)
        if (v[m] != tris[k][0] && v[m] != tris[k][1] && v[m] != tris[k][2]) apex[k] = v[m];
    }
    if (apex[0] == NO_INDEX || apex[0] != apex[1]) return NO_INDEX;
    return closes(mesh, face_around(tris), apex[0], pyramid_floor) ? apex[0] : NO_INDEX;
  };
  // Per open face of a cell the block takes, until none leaves: whether a pyramid of the tets
  // across closes it, its tets' faces at the apex on no other such cell's open face (but one
  // of a cell split already, which its own pyramid closes). Where none does, the cell split is
  // the cell across when the block does not take it (its pyramid closes the face), else of two
  // cells that need one pyramid the one the block drops first (not near-perfect, then fewer
  // faces shared with the block, then the lesser scaled Jacobian), else the cell itself, where
  // it has at most kMostOpenFaces open faces. A cell with more lies at the block's edge, where
  // little leaves with it (random_20261204_023 at its 30k size: 88 lattice cells the core did
  // not take, each open on three to five faces, split for 0.3 points less hex volume): it
  // leaves, and the faces beside it are open then (gmsh_t20_data at h 0.8434: a lattice cell
  // open on three faces, one unclosable, left two of the block's cells needing one tet of its
  // for their pyramids, and 4,551 cells left after them).
  std::vector<char> split(cells.size(), 0);
  for (bool left = true; left;) {
    left = false;
    struct Open {
      std::size_t cell, face;
    };
    std::vector<Open> open;
    // The open faces' corners, any three of them: a tet with a face there lies on one.
    std::unordered_map<FaceKey, std::size_t, FaceKeyHash> on_open;  // -> its cell
    std::vector<int> nb_open(cells.size(), 0), nb_shared(cells.size(), 0);
    for (std::size_t c = 0; c < cells.size(); ++c)
      for (std::size_t f = 0; f < 6 && member[c]; ++f) {
        if (against_member(c, f)) ++nb_shared[c];
        if (!is_open(c, f)) continue;
        open.push_back({c, f});
        ++nb_open[c];
        const std::array<index_t, 4> corners = face_around(cells[c].face[f]);
        if (corners[2] == NO_INDEX) continue;
        for (std::size_t skip = 0; skip < 4; ++skip) {
          std::array<index_t, 3> three{};
          for (std::size_t k = 0, m = 0; k < 4; ++k)
            if (k != skip) three[m++] = corners[k];
          on_open.emplace(face_key(three[0], three[1], three[2]), c);
        }
      }
    const auto near_perfect = [&](std::size_t c) { return quality[c] >= kBlockHexQuality; };
    const auto lesser = [&](std::size_t a, std::size_t b) {
      if (near_perfect(a) != near_perfect(b)) return near_perfect(b);
      if (nb_shared[a] != nb_shared[b]) return nb_shared[a] < nb_shared[b];
      if (quality[a] != quality[b]) return quality[a] < quality[b];
      return a > b;
    };
    for (const Open& o : open) {
      if (split[o.cell] || !member[o.cell]) continue;
      const std::int64_t beside = across_of[o.cell][o.face].cell[0];
      const bool lends = beside >= 0 && beside == across_of[o.cell][o.face].cell[1];
      if (lends && split[static_cast<std::size_t>(beside)]) continue;
      const index_t apex = pyramid_apex(o.cell, o.face);
      bool closed = apex != NO_INDEX;
      std::size_t rival = o.cell;
      for (const index_t t : tets_across(o.cell, o.face)) {
        if (!closed) break;
        const index_t* v = mesh.tet(t);
        for (int m = 0; m < 4 && closed; ++m) {
          if (v[m] == apex) continue;
          const auto it = on_open.find(face_key(v[(m + 1) % 4], v[(m + 2) % 4], v[(m + 3) % 4]));
          closed = it == on_open.end() || it->second == o.cell || split[it->second] ||
                   !member[it->second];
          if (!closed) rival = it->second;
        }
      }
      if (closed) continue;
      if (lends) {
        split[static_cast<std::size_t>(beside)] = 1;
        continue;
      }
      const std::size_t loser = rival != o.cell && lesser(rival, o.cell) ? rival : o.cell;
      if (nb_open[loser] <= kMostOpenFaces)
        split[loser] = 1;
      else
        member[loser] = 0, left = true;
    }
  }
  CellSplits splits(mesh);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!split[c]) continue;
    std::vector<std::array<index_t, 3>> faces;
    for (const auto& face : cells[c].face) faces.insert(faces.end(), face.begin(), face.end());
    splits.add(cells[c].corner, faces, cells[c].tets, floor);
  }
  return splits.apply();
}

// Rounds of flips (remove_slivers) and node moves (smooth_nodes); the last is flips. The count
// of tets under 0.2 still falls after the fourth round (gmsh_917_fusee at its 50k size, after each
// round's flips: 1314, 300, 167, 118, 94, 76, 64, 64, then 64 to 62 by the sixteenth); the rounds
// stop sooner when no node moves.
constexpr int kQualityRounds = 8;

// The path of the boundary nodes along the CAD (the surface's, `boundary_path()`), and of the
// lattice points inside a lattice face that are corners of no core cell along the face's plane
// once released (`add`). The lattice places a lattice face's points for the core cells that reach
// it; where none does (a disc 0.35 h thick holds no core: gmsh_1385_Laufrad_1000 at its 50k
// size), they stood fixed under the tets from the other side's nodes, 88 of its 109 tets under
// 0.2 among them.
class LatticeFacePath final : public SurfacePath {
 public:
  explicit LatticeFacePath(SurfacePath& faces) : faces_(faces) {}

  // Node v, standing at `at`, moves in the plane of unit normal n.
  void add(index_t v, const Vec3& at, const Vec3& n) {
    if (v >= planes_.size()) planes_.resize(static_cast<std::size_t>(v) + 1);
    Vec3 u = n.cross(std::abs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
    u = u * (1.0 / u.norm());
    planes_[v] = Plane{true, at, u, n.cross(u)};
  }

  int dimension(index_t v) const override { return on_plane(v) ? 2 : faces_.dimension(v); }
  void tangents(index_t v, Vec3& along_u, Vec3& along_v) const override {
    if (!on_plane(v)) return faces_.tangents(v, along_u, along_v);
    along_u = planes_[v].u, along_v = planes_[v].w;
  }
  bool at(index_t v, double a, double b, Vec3& point) const override {
    if (!on_plane(v)) return faces_.at(v, a, b, point);
    point = planes_[v].at + planes_[v].u * a + planes_[v].w * b;
    return true;
  }
  void moved(index_t v, double a, double b) override {
    if (!on_plane(v)) return faces_.moved(v, a, b);
    planes_[v].at = planes_[v].at + planes_[v].u * a + planes_[v].w * b;
  }

 private:
  struct Plane {
    bool on = false;
    Vec3 at, u, w;  // where the node stands; the plane's unit tangents
  };
  bool on_plane(index_t v) const { return v < planes_.size() && planes_[v].on; }
  SurfacePath& faces_;
  std::vector<Plane> planes_;
};

}  // namespace

std::vector<std::array<index_t, 5>> closing_pyramids(
    const TetMesh& mesh, const std::vector<std::array<double, 3>>& cell_of,
    const std::vector<char>& apex_of) {
  const std::size_t made = apex_of.size();
  // Per vertex: whether on the lattice (all its coordinates whole).
  std::vector<char> on_lattice(made, 1);
  for (std::size_t v = 0; v < made; ++v)
    for (int a = 0; a < 3; ++a)
      if (std::abs(cell_of[v][a] - std::round(cell_of[v][a])) > 1e-6) on_lattice[v] = 0;
  // Per (apex, face of its cell: axis and side): the corners met and the tets.
  struct Face {
    std::array<index_t, 4> corners{};
    int nb_corners = 0, nb_tets = 0;
  };
  std::map<std::pair<index_t, int>, Face> faces;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* v = mesh.tet(t);
    int apex = -1, nb_centres = 0;
    for (int k = 0; k < 4; ++k)
      if (v[k] < made && apex_of[v[k]]) apex = k, ++nb_centres;
    if (nb_centres != 1) continue;
    const index_t c = v[apex];
    // The side of the cell each other corner is on, per axis (-1, +1), when all are corners of
    // the cell.
    int side[3][3], n = 0;
    bool corners = true;
    for (int k = 0; k < 4 && corners; ++k) {
      if (k == apex) continue;
      const index_t w = v[k];
      if (w >= made || !on_lattice[w]) corners = false;
      for (int a = 0; a < 3 && corners; ++a) {
        const double d = cell_of[w][a] - cell_of[c][a];
        if (std::abs(std::abs(d) - 0.5) > 1e-6) corners = false;
        side[n][a] = d > 0 ? 1 : -1;
      }
      ++n;
    }
    if (!corners) continue;
    for (int a = 0; a < 3; ++a) {
      if (side[0][a] != side[1][a] || side[0][a] != side[2][a]) continue;
      Face& face = faces[{c, 2 * a + (side[0][a] > 0)}];
      ++face.nb_tets;
      for (int k = 0; k < 4; ++k) {
        if (k == apex) continue;
        if (std::find(face.corners.begin(), face.corners.begin() + face.nb_corners, v[k]) ==
                face.corners.begin() + face.nb_corners &&
            face.nb_corners < 4)
          face.corners[face.nb_corners++] = v[k];
      }
    }
  }
  std::vector<std::array<index_t, 5>> pyramids;
  for (const auto& [key, face] : faces) {
    if (face.nb_tets != 2 || face.nb_corners != 4) continue;
    const index_t c = key.first;
    const int a = key.second / 2, b = (a + 1) % 3, d = (a + 2) % 3;
    // Around the face: (-, -), (+, -), (+, +), (-, +) along axes b and d.
    std::array<index_t, 5> pyramid{0, 0, 0, 0, c};
    for (index_t w : face.corners) {
      const bool up_b = cell_of[w][b] > cell_of[c][b], up_d = cell_of[w][d] > cell_of[c][d];
      pyramid[up_d ? (up_b ? 2 : 3) : (up_b ? 1 : 0)] = w;
    }
    if (scaled_jacobian(CellType::Pyramid, mesh.points.data(), pyramid.data()) < 0)
      std::swap(pyramid[1], pyramid[3]);
    pyramids.push_back(pyramid);
  }
  return pyramids;
}

void improve_tets(TetMesh& mesh, const std::vector<double>& frame_points,
                  const std::vector<std::array<index_t, 3>>& boundary,
                  const std::vector<std::int32_t>& boundary_face,
                  const ImproveParameters& parameters, ImproveReport& report) {
  report = ImproveReport{};
  const std::size_t made = frame_points.size() / 3;
  // TetGen leaves slivers where the lattice meets the boundary layers and the surface (four
  // nearly cocircular points, as the sides of the layers' prisms are): flips take them out, then
  // the free nodes (boundary-layer and Steiner points, inside) move to raise the worst tet around
  // them, then flips again, for kQualityRounds rounds. The lattice's own tets, in one cell or one
  // closing pyramid, stay for the hexahedra, and lattice points and cell centres do not move.
  // Per vertex: whether it is a lattice point or a cell centre, whether a cell centre, and its
  // coordinates in cells.
  std::vector<char> half_lattice(made, 1), centre(made, 1), lattice_point(made, 1);
  std::vector<std::array<double, 3>> cell_of(made);
  for (std::size_t v = 0; v < made; ++v)
    for (int a = 0; a < 3; ++a) {
      cell_of[v][a] =
          cells_coordinate(parameters.ticks[a], parameters.spacing[a], frame_points[3 * v + a]);
      if (std::abs(2 * cell_of[v][a] - std::round(2 * cell_of[v][a])) > 1e-6) half_lattice[v] = 0;
      if (std::abs(cell_of[v][a] - std::round(cell_of[v][a])) < 1e-6)
        centre[v] = 0;
      else
        lattice_point[v] = 0;
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
  // Flat on the lattice: the four corners of a cell's face, moved off their plane (a core
  // pulled towards the surface, pull_core()), a sliver between the face's two splits.
  auto flat_on_lattice = [&](index_t t) {
    const auto at = [&](int k) {
      const std::array<double, 3>& c = cell_of[mesh.tet(t)[k]];
      return Vec3{c[0], c[1], c[2]};
    };
    return std::abs(det3(at(1) - at(0), at(2) - at(0), at(3) - at(0))) < 1e-6;
  };
  // Swept: whether tet t lies between two consecutive lattice planes (its prism or hexahedron
  // stays as TetGen made it).
  auto in_one_slab = [&](index_t t) {
    if (parameters.sweep_axis < 0) return false;
    double least = 1e300, most = -1e300;
    for (int k = 0; k < 4; ++k) {
      const double level = cell_of[mesh.tet(t)[k]][parameters.sweep_axis];
      least = std::min(least, level), most = std::max(most, level);
    }
    return most - least <= 1 + 1e-6;
  };
  // The CAD face of each boundary face, from TetGen's markers (face index + 1), so that
  // triangles of one planar face may swap their shared sides.
  std::unordered_map<FaceKey, std::int32_t, FaceKeyHash> face_marker;
  std::vector<char> on_boundary(made, 0);  // per vertex: a corner of a boundary triangle
  // Free: the layer and Steiner points. Nudged: the cell centres, the apexes of the closing
  // pyramids, which lie as near the faces as the core does (a tet of three surface nodes and an
  // apex reached 0.155 on the suite's cylinder): moved only as far as lifts their tets to 0.2,
  // which keeps their pyramids. The lattice points stay, but those in no tet of a cell or closing
  // pyramid (kept, but a corner of no core cell): free, and off the lattice from then on (moving
  // them takes no hexahedron away).
  std::vector<char> in_lattice_tet(made, 0);
  if (parameters.sweep_axis < 0)
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      if (in_one_cell(t))
        for (int k = 0; k < 4; ++k) in_lattice_tet[mesh.tet(t)[k]] = 1;
  std::vector<char> movable(made, kFixed);
  for (std::size_t v = parameters.nb_surface_nodes; v < made; ++v)
    if (parameters.sweep_axis < 0) {
      if (lattice_point[v] && !in_lattice_tet[v]) half_lattice[v] = lattice_point[v] = 0;
      movable[v] = !half_lattice[v] ? kFree : centre[v] ? kNudged : kFixed;
    }
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    const std::array<index_t, 3>& corners = boundary[i];
    for (index_t v : corners) movable[v] = kFixed, on_boundary[v] = 1;
    face_marker[face_key(corners[0], corners[1], corners[2])] = boundary_face[i];
  }
  std::vector<char> nudged(made, 0);
  for (std::size_t v = 0; v < made; ++v) nudged[v] = movable[v] == kNudged;
  const std::vector<std::array<index_t, 5>> pyramids = closing_pyramids(mesh, cell_of, nudged);
  // Boundary nodes inside a CAD face move along it, inside a CAD edge along that (a tet on a
  // needle of the surface gets better only so); swept, none.
  std::optional<LatticeFacePath> paths;
  if (parameters.sweep_axis < 0 && parameters.surface != nullptr)
    paths.emplace(*parameters.surface);
  SurfacePath* const surface = paths ? &*paths : nullptr;
  // The lattice points no core cell has kept (off the half lattice now) inside a lattice face
  // (every boundary triangle at them of one face and in one plane), by that plane's normal: they
  // are released with the kept cells, those at a tet under insert_below then.
  std::vector<std::int32_t> face_at;  // -2: no triangle yet, -1: not inside one plane
  std::vector<Vec3> normal_at;
  if (surface) {
    face_at.assign(made, -2), normal_at.resize(made);
    for (std::size_t i = 0; i < boundary.size(); ++i) {
      const std::array<index_t, 3>& c = boundary[i];
      const Vec3 a = Vec3::of(mesh.point(c[0]));
      const Vec3 n = (Vec3::of(mesh.point(c[1])) - a).cross(Vec3::of(mesh.point(c[2])) - a);
      const double length = n.norm();
      for (const index_t v : c) {
        if (v < parameters.nb_surface_nodes || half_lattice[v] || face_at[v] == -1) continue;
        if (!(length > 0))
          face_at[v] = -1;
        else if (face_at[v] == -2)
          face_at[v] = boundary_face[i], normal_at[v] = n * (1.0 / length);
        else if (face_at[v] != boundary_face[i] || n.cross(normal_at[v]).norm() > 1e-9 * length)
          face_at[v] = -1;
      }
    }
  }
  // A lattice point on the boundary (a corner of the core's cells on a lattice face) stays.
  if (surface)
    for (std::size_t v = 0; v < made; ++v)
      if (on_boundary[v] && surface->dimension(static_cast<index_t>(v)) > 0 && !lattice_point[v])
        movable[v] = kOnSurface;
  // The buffer's cells: their tets stay, their vertices do not move, unless a tet under
  // insert_below outside them touches one after the last flips; then that cell is released (its
  // tets and corners are the mesh's like any other) for one more round (gmsh_Angled at its 250k
  // size: 8 tets from 0.116 beside buffer cells).
  std::unordered_map<index_t, std::vector<std::size_t>> kept_cells_at;
  std::vector<char> movable_unkept = movable;
  std::vector<char> released(parameters.kept_cells.size(), 0);
  // (A pyramid's apex, a core pyramid's too, is nudged as the closing pyramids' are, the pyramid
  // kept at pyramid_floor.)
  std::vector<std::array<index_t, 5>> kept_pyramids;
  const auto keep_cells = [&]() {
    kept_cells_at.clear();
    kept_pyramids = pyramids;
    movable = movable_unkept;
    movable.resize(mesh.nb_vertices(), parameters.sweep_axis < 0 ? kFree : kFixed);
    for (std::size_t c = 0; c < parameters.kept_cells.size(); ++c) {
      if (released[c]) continue;
      const std::vector<index_t>& cell = parameters.kept_cells[c];
      for (std::size_t k = 0; k < cell.size(); ++k) {
        kept_cells_at[cell[k]].push_back(c);
        if (cell.size() != 5 || k != 4) movable[cell[k]] = kFixed;
      }
      if (cell.size() == 5) kept_pyramids.push_back({cell[0], cell[1], cell[2], cell[3], cell[4]});
    }
  };
  keep_cells();
  const auto in_kept_cell = [&](index_t t) {
    const index_t* v = mesh.tet(t);
    const auto it = kept_cells_at.find(v[0]);
    if (it == kept_cells_at.end()) return false;
    for (const std::size_t c : it->second) {
      const std::vector<index_t>& cell = parameters.kept_cells[c];
      bool all = true;
      for (int k = 1; k < 4 && all; ++k)
        all = std::find(cell.begin(), cell.end(), v[k]) != cell.end();
      if (all) return true;
    }
    return false;
  };
  // What the rounds know of the mesh they leave (the output does not depend on it, only the
  // work): per tet, no flip improves it as the mesh stands (remove_slivers' `settled`: the
  // flips of the next round skip it, unless a node moved near it since or the fixed tets
  // changed); per node, its search leaves it where it stands (smooth_nodes' `settled`: skipped
  // until a tet at it changes or a node of one moves).
  RemoveSliversState flip_state;
  std::vector<char>& settled = flip_state.settled;
  settled.assign(mesh.nb_tets(), 0);
  std::vector<char> still(mesh.nb_vertices(), 0);
  // Releases the lattice face's points (face_at) at a tet under insert_below outside the kept
  // cells and, with `cells`, the kept cells such a tet touches at one of their boundary corners
  // (the tops: their corners inside stay either way). Whether points were released now, or with
  // `cells`, whether cells were now or points ever (the extra round follows).
  const auto release = [&](bool cells) {
    if (kept_cells_at.empty() && face_at.empty()) return false;
    const std::size_t points_before = report.released_face_points;
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      const index_t* v = mesh.tet(t);
      if (!(scaled_jacobian(CellType::Tet, mesh.points.data(), v) < parameters.insert_below) ||
          in_kept_cell(t))
        continue;
      for (int k = 0; k < 4; ++k) {
        if (!on_boundary[v[k]]) continue;
        if (v[k] < face_at.size() && face_at[v[k]] >= 0) {
          paths->add(v[k], Vec3::of(mesh.point(v[k])), normal_at[v[k]]);
          face_at[v[k]] = -1, movable_unkept[v[k]] = kOnSurface, ++report.released_face_points;
        }
        if (!cells) continue;
        const auto it = kept_cells_at.find(v[k]);
        if (it == kept_cells_at.end()) continue;
        for (const std::size_t c : it->second)
          if (!released[c]) released[c] = 1, ++report.released_cells;
      }
    }
    const bool any = cells ? report.released_cells + report.released_face_points > 0
                           : report.released_face_points > points_before;
    if (any) keep_cells(), settled.assign(settled.size(), 0), still.assign(still.size(), 0);
    return any;
  };
  int extra = 0;  // the round after a release
  const auto release_once = [&]() {
    if (extra > 0) return false;
    extra = release(true) ? 1 : 0;
    return extra > 0;
  };
  std::vector<FaceKey> flat_before;  // the faces of the flat tets of the round before
  for (int round = 0;; ++round) {
    std::vector<char> fixed(mesh.nb_tets(), 0);
    for (index_t t = 0; t < mesh.nb_tets(); ++t) fixed[t] = in_one_cell(t) || in_one_slab(t);
    // A flat one and the tets on its faces are free: flips take the sliver out.
    {
      std::unordered_map<FaceKey, index_t, FaceKeyHash> flat_faces;
      for (index_t t = 0; t < mesh.nb_tets(); ++t)
        if (fixed[t] && flat_on_lattice(t)) {
          fixed[t] = 0;
          const index_t* v = mesh.tet(t);
          for (int f = 0; f < 4; ++f)
            flat_faces[face_key(v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4])] = t;
        }
      if (!flat_faces.empty())
        for (index_t t = 0; t < mesh.nb_tets(); ++t) {
          const index_t* v = mesh.tet(t);
          for (int f = 0; f < 4 && fixed[t]; ++f)
            if (flat_faces.count(face_key(v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4])))
              fixed[t] = 0;
        }
      // Other flat tets, other tets freed: the settled tets are examined anew.
      std::vector<FaceKey> flat;
      flat.reserve(flat_faces.size());
      for (const auto& entry : flat_faces) flat.push_back(entry.first);
      std::sort(flat.begin(), flat.end());
      if (flat != flat_before) settled.assign(settled.size(), 0);
      flat_before = std::move(flat);
    }
    if (!kept_cells_at.empty())
      for (index_t t = 0; t < mesh.nb_tets(); ++t)
        if (in_kept_cell(t)) fixed[t] = 1;
    // Boundary faces swapped by an earlier round are not in face_marker: they stay (-1).
    std::vector<std::int32_t> boundary_patch(4 * static_cast<std::size_t>(mesh.nb_tets()), -1);
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      for (int f = 0; f < 4; ++f) {
        const index_t* v = mesh.tet(t);
        const index_t a = v[(f + 1) % 4], b = v[(f + 2) % 4], c = v[(f + 3) % 4];
        if (!on_boundary[a] || !on_boundary[b] || !on_boundary[c]) continue;
        const auto it = face_marker.find(face_key(a, b, c));
        if (it != face_marker.end())
          boundary_patch[4 * static_cast<std::size_t>(t) + f] = it->second;
      }
    RemoveSliversReport flips;
    // Boundary triangles of one face may swap their side where the boundary moves by no more
    // than the surface's chord deflection (a flat tet on two triangles across a seam).
    RemoveSliversParameters flip_parameters;
    flip_parameters.max_boundary_shift = parameters.max_boundary_shift;
    flip_parameters.insert_below = parameters.insert_below;
    remove_slivers(mesh, fixed, boundary_patch, flip_parameters, flips, &flip_state);
    still.resize(mesh.nb_vertices(), 0);
    for (std::size_t v = 0; v < still.size(); ++v)
      if (flip_state.touched[v]) still[v] = 0;
    // The inserted vertices: free, off the lattice, inside.
    half_lattice.resize(mesh.nb_vertices(), 0);
    cell_of.resize(mesh.nb_vertices());
    on_boundary.resize(mesh.nb_vertices(), 0);
    movable.resize(mesh.nb_vertices(), parameters.sweep_axis < 0 ? kFree : kFixed);
    report.inserted_vertices += flips.insertions;
    if (round == 0) report.min_quality_before = flips.min_before;
    report.face_flips += flips.face_removals;
    report.edge_flips += flips.edge_removals;
    report.boundary_swaps += flips.boundary_swaps;
    if (round + 1 >= kQualityRounds + extra && !release_once()) break;
    // The lattice faces' points at tets still under insert_below half way, too (the rounds left
    // move them: gmsh_1385_Laufrad_1000 at its 50k size 25 -> 13 elements under 0.2 after the
    // recombination, where at the end only).
    if (round + 1 == kQualityRounds / 2) release(false);
    SmoothNodesReport moves;
    SmoothNodesParameters move_parameters;
    move_parameters.pyramid_floor = parameters.pyramid_floor;
    const std::vector<double> unmoved = mesh.points;
    smooth_nodes(mesh, movable, move_parameters, moves, surface, kept_pyramids, &still);
    // A moved node changes the tets around it and the flips of every tet at their vertices.
    std::vector<char> near_move(mesh.nb_vertices(), 0);
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      const index_t* v = mesh.tet(t);
      if (std::any_of(v, v + 4, [&](index_t w) {
            const std::size_t i = 3 * static_cast<std::size_t>(w);
            return mesh.points[i] != unmoved[i] || mesh.points[i + 1] != unmoved[i + 1] ||
                   mesh.points[i + 2] != unmoved[i + 2];
          }))
        for (int k = 0; k < 4; ++k) near_move[v[k]] = 1;
    }
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      if (std::any_of(mesh.tet(t), mesh.tet(t) + 4, [&](index_t w) { return near_move[w]; }))
        settled[t] = 0;
    report.node_moves += moves.moves;
    report.boundary_node_moves += moves.surface_moves;
    if (moves.moves == 0 && !release_once()) break;
  }
  if (parameters.sweep_axis < 0)
    report.split_open_cells = split_open_cells(mesh, cell_of, lattice_point, parameters.kept_cells,
                                               parameters.insert_below, parameters.pyramid_floor);
}

}  // namespace hexmerge::mesher
