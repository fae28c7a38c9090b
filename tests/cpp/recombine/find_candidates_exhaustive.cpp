// The exhaustive finder: a superset of the search programs, agreement with a brute-force oracle on
// TetGen-tetrahedralised jittered lattices, and hexahedra whose subdivisions hold flat tets.
#include "hexmerge/recombine/find_candidates_exhaustive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "fixtures.h"
#include "hexmerge/check/check_mesh.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/recombine/recombine.h"

namespace hexmerge::test {
namespace {

const CellDescriptor& kTetD = descriptor(CellType::Tet);

/// Accepts every cell whose quads are folded by less than 90 degrees, so that the lattice oracle
/// compares filling only.
AcceptanceCriteria anything() {
  AcceptanceCriteria c;
  c.min_scaled_jacobian = -1.0;
  c.min_dihedral_angle = 90.0;
  c.min_boundary_dihedral_angle = 90.0;
  c.max_face_angle = 180.0;
  return c;
}

/// A cell as the tests compare them: type, tets, and its faces as sorted vertex sets.
using CellKey = std::tuple<int, std::vector<index_t>, std::set<std::vector<index_t>>>;

std::set<std::vector<index_t>> faces_of(const Candidate& c) {
  const CellDescriptor& d = descriptor(c.type);
  std::set<std::vector<index_t>> faces;
  for (int f = 0; f < d.nb_faces; ++f) {
    std::vector<index_t> face;
    for (int i = 0; i < d.face_size[f]; ++i) face.push_back(c.vertices[d.face[f][i]]);
    std::sort(face.begin(), face.end());
    faces.insert(face);
  }
  return faces;
}

std::vector<index_t> tets_of(const Candidates& cs, const Candidate& c) {
  return std::vector<index_t>(cs.tets(c).begin(), cs.tets(c).end());
}

CellKey key_of(const Candidates& cs, const Candidate& c) {
  return {static_cast<int>(c.type), tets_of(cs, c), faces_of(c)};
}

/// Independent check that `tets` fill the cell of `type` on `v` (local order): every face of a
/// tet is shared with another tet of the group or lies on one of the cell's faces; each quad face
/// gets two triangles on one diagonal, each triangular face one triangle; and the tets' volume
/// equals the volume that the cell's faces, triangulated that way and oriented by the cell's
/// local order, enclose. (Brute force: no adjacency, no orientation taken from the tets.)
bool fills(const TetMesh& mesh, const std::vector<index_t>& tets, CellType type, const index_t* v) {
  const CellDescriptor& d = descriptor(type);
  std::map<std::set<index_t>, int> face_count;
  for (index_t t : tets) {
    for (int f = 0; f < 4; ++f) {
      std::set<index_t> tri;
      for (int k = 0; k < 3; ++k) tri.insert(mesh.tet(t)[kTetD.face[f][k]]);
      ++face_count[tri];
    }
  }
  std::vector<std::set<index_t>> boundary;
  for (const auto& [tri, n] : face_count) {
    if (n > 2) return false;
    if (n == 1) boundary.push_back(tri);
  }
  std::size_t expected = 0;
  double enclosed = 0.0;
  const double origin[3] = {0.0, 0.0, 0.0};
  auto flux = [&](index_t a, index_t b, index_t c) {
    enclosed += tet_volume(origin, mesh.point(a), mesh.point(b), mesh.point(c));
  };
  for (int f = 0; f < d.nb_faces; ++f) {
    const int n = d.face_size[f];
    std::vector<index_t> cyc;
    for (int i = 0; i < n; ++i) cyc.push_back(v[d.face[f][i]]);
    std::vector<std::set<index_t>> on_face;
    for (const auto& tri : boundary) {
      if (std::all_of(tri.begin(), tri.end(), [&](index_t x) {
            return std::find(cyc.begin(), cyc.end(), x) != cyc.end();
          })) {
        on_face.push_back(tri);
      }
    }
    if (n == 3) {
      if (on_face.size() != 1) return false;
      flux(cyc[0], cyc[1], cyc[2]);
      expected += 1;
      continue;
    }
    if (on_face.size() != 2) return false;
    // Two triangles on diagonal cyc[k]-cyc[k+2]: each misses one of the other two corners.
    bool diagonal_found = false;
    for (int k = 0; k < 2 && !diagonal_found; ++k) {
      const std::set<index_t> t1{cyc[k], cyc[k + 1], cyc[k + 2]};
      const std::set<index_t> t2{cyc[k + 2], cyc[(k + 3) % 4], cyc[k]};
      if ((on_face[0] == t1 && on_face[1] == t2) || (on_face[0] == t2 && on_face[1] == t1)) {
        diagonal_found = true;
        flux(cyc[k], cyc[k + 1], cyc[k + 2]);
        flux(cyc[k + 2], cyc[(k + 3) % 4], cyc[k]);
      }
    }
    if (!diagonal_found) return false;
    expected += 2;
  }
  if (boundary.size() != expected) return false;
  double volume = 0.0;
  for (index_t t : tets) {
    const index_t* q = mesh.tet(t);
    volume += std::abs(
        tet_volume(mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3])));
  }
  return std::abs(volume - enclosed) <= 1e-9 * std::max(1.0, std::abs(volume));
}

/// Runs both finders; expects every program candidate among the exhaustive ones, no exhaustive
/// candidate twice, and every exhaustive candidate filled (independent check). Returns the
/// exhaustive candidates.
Candidates compare(const TetMesh& mesh, const AcceptanceCriteria& criteria) {
  const TetTopology topology(mesh);
  const auto programs = find_candidates(mesh, topology, criteria, 1);
  const auto exhaustive = find_candidates_exhaustive(mesh, topology, criteria, 2);
  std::set<CellKey> found;
  for (const Candidate& c : exhaustive) {
    EXPECT_EQ(c.graph, EXHAUSTIVE_GRAPH);
    const std::vector<index_t> tets = tets_of(exhaustive, c);
    EXPECT_EQ(tets.size(), c.nb_tets);
    EXPECT_TRUE(std::is_sorted(tets.begin(), tets.end()));
    EXPECT_TRUE(found.insert(key_of(exhaustive, c)).second) << "found twice";
    EXPECT_TRUE(fills(mesh, tets, c.type, c.vertices.data()));
    EXPECT_GE(c.quality, criteria.min_scaled_jacobian);
    EXPECT_NEAR(c.quality, scaled_jacobian(c.type, mesh.points.data(), c.vertices.data()), 1e-6);
  }
  for (const Candidate& c : programs) {
    EXPECT_EQ(found.count(key_of(programs, c)), 1u)
        << descriptor(c.type).name << " of " << int(c.nb_tets) << " tets from template "
        << int(c.graph) << " not found exhaustively";
  }
  // Same threads-independent order.
  const auto again = find_candidates_exhaustive(mesh, topology, criteria, 1);
  EXPECT_EQ(again.size(), exhaustive.size());
  for (std::size_t i = 0; i < std::min(again.size(), exhaustive.size()); ++i) {
    EXPECT_EQ(key_of(again, again[i]), key_of(exhaustive, exhaustive[i]));
  }
  return exhaustive;
}

std::size_t count_type(const Candidates& cs, CellType type) {
  return std::count_if(cs.begin(), cs.end(), [&](const Candidate& c) { return c.type == type; });
}

TEST(find_candidates_exhaustive, finds_every_program_candidate_on_the_cube_triangulations) {
  std::mt19937 rng(7);
  const auto triangulations = enumerate_triangulations(unit_cube());
  ASSERT_EQ(triangulations.size(), 74u);
  for (std::size_t i = 0; i < triangulations.size(); ++i) {
    for (int k = 0; k < 4; ++k) {
      SCOPED_TRACE("cube triangulation " + std::to_string(i) + ", variant " + std::to_string(k));
      TetMesh mesh = polytope_mesh(unit_cube(), triangulations[i]);
      if (k >= 1) random_affine_map(mesh, rng);
      if (k >= 2) random_perturbation(mesh, rng, 0.03);
      const auto found = compare(mesh, k == 0 ? AcceptanceCriteria{} : permissive_criteria());
      // Skewed and then perturbed, some fall below the permissive thresholds.
      if (k <= 1) {
        EXPECT_EQ(count_type(found, CellType::Hex), 1u);
      }
    }
  }
}

TEST(find_candidates_exhaustive, finds_every_program_candidate_on_prisms_and_pyramids) {
  for (const Polytope& p : {unit_prism(), square_pyramid()}) {
    for (const auto& tets : enumerate_triangulations(p)) {
      SCOPED_TRACE(p.name);
      const auto found = compare(polytope_mesh(p, tets), AcceptanceCriteria{});
      // A prism's triangulation also holds a pyramid on one of its quads.
      EXPECT_EQ(count_type(found, tets.size() == 3 ? CellType::Prism : CellType::Pyramid), 1u);
    }
  }
}

TEST(find_candidates_exhaustive, finds_every_program_candidate_on_grids) {
  std::mt19937 rng(11);
  for (int n : {1, 2, 3}) {
    for (bool five : {false, true}) {
      SCOPED_TRACE("n = " + std::to_string(n) + (five ? ", five-tet" : ", Kuhn"));
      TetMesh mesh = five ? five_tet_grid(n) : kuhn_grid(n);
      const auto exact = compare(mesh, AcceptanceCriteria{});
      // Every cube, and in Kuhn grids sheared hexahedra across cubes too.
      EXPECT_GE(count_type(exact, CellType::Hex), std::size_t(n) * n * n);
      if (five) {
        EXPECT_EQ(count_type(exact, CellType::Hex), std::size_t(n) * n * n);
      }
      random_affine_map(mesh, rng, 0.2);
      random_perturbation(mesh, rng, 0.02);
      compare(mesh, permissive_criteria());
      compare(mesh, anything());
      AcceptanceCriteria only_prisms = permissive_criteria();
      only_prisms.types[static_cast<int>(CellType::Hex)] = false;
      EXPECT_EQ(count_type(compare(mesh, only_prisms), CellType::Hex), 0u);
    }
  }
}

TEST(find_candidates_exhaustive, respects_regions) {
  TetMesh mesh = kuhn_grid(2);
  mesh.regions.assign(mesh.nb_tets(), 0);
  for (index_t t = 0; t < mesh.nb_tets(); t += 7) mesh.regions[t] = 1;
  const TetTopology topology(mesh);
  const Candidates found = find_candidates_exhaustive(mesh, topology, AcceptanceCriteria{}, 1);
  for (const Candidate& c : found) {
    const TetSpan tets = found.tets(c);
    for (index_t t : tets) EXPECT_EQ(mesh.region(t), mesh.region(tets[0]));
  }
  compare(mesh, AcceptanceCriteria{});
}

// ----------------------------------------------------------------------- flat tets, 7 tets

/// The unit cube (fixture numbering: corner i at (i & 1, (i >> 1) & 1, (i >> 2) & 1)) with corner
/// 4 moved to (e, 0, 1): two prisms either side of the bent rectangle 0-3-7-4, each triangulating
/// it on its own diagonal, and the flat tet (0, 3, 4, 7) between them: 7 tets.
TetMesh seven_tet_cube(double e) {
  std::vector<Point> p = unit_cube().corners;
  p[4] = {e, 0.0, 1.0};
  const std::vector<Tet> tets = {{0, 4, 6, 7}, {0, 2, 3, 7}, {0, 2, 7, 6},  // x <= y
                                 {0, 1, 3, 4}, {1, 3, 4, 7}, {1, 4, 5, 7},  // x >= y
                                 {0, 3, 4, 7}};                             // the sliver
  TetMesh mesh = make_tet_mesh(p, tets);
  orient_positively(mesh);
  return mesh;
}

/// Hex vertices of the unit cube in the local order of cell_type.h.
std::array<index_t, 8> cube_hex() { return {0, 1, 3, 2, 4, 5, 7, 6}; }

TEST(find_candidates_exhaustive, finds_a_hex_of_seven_tets_around_a_flat_tet) {
  for (double e : {0.05, 1e-3, 1e-7}) {
    SCOPED_TRACE("e = " + std::to_string(e));
    const TetMesh mesh = seven_tet_cube(e);
    std::vector<index_t> all(mesh.nb_tets());
    for (index_t t = 0; t < mesh.nb_tets(); ++t) all[t] = t;
    ASSERT_TRUE(fills(mesh, all, CellType::Hex, cube_hex().data())) << "bad fixture";
    const auto found = compare(mesh, permissive_criteria());
    ASSERT_EQ(count_type(found, CellType::Hex), 1u);
    const Candidate& hex = *std::find_if(
        found.begin(), found.end(), [](const Candidate& c) { return c.type == CellType::Hex; });
    EXPECT_EQ(hex.nb_tets, 7);
    // The programs know only 5- and 6-tet hexahedra.
    const TetTopology topology(mesh);
    EXPECT_EQ(count_type(find_candidates(mesh, topology, permissive_criteria(), 1), CellType::Hex),
              0u);
  }
  // Through the engine: one hexahedron, valid.
  RecombineParameters p;
  p.finder = Finder::Exhaustive;
  p.min_scaled_jacobian = 0.05;
  p.min_boundary_dihedral_angle = 150.0;
  RecombineReport report;
  const TetMesh mesh = seven_tet_cube(0.05);
  const MixedMesh out = recombine(mesh, p, report);
  const CheckReport check = check_mesh(out, mesh);
  EXPECT_TRUE(check.valid());
  EXPECT_EQ(out.nb_cells(), 1u);
  EXPECT_EQ(check.counts[static_cast<int>(CellType::Hex)], 1u);
  EXPECT_EQ(report.candidates_per_template.at("exhaustive_hex"), 1u);
}

TEST(find_candidates_exhaustive, a_flat_tet_on_a_quad_face_is_taken_in_or_left_out) {
  // A cube triangulation with the bottom face split on diagonal 1-2, corner 0 lowered: the flat
  // tet (0, 1, 2, 3) closes the bottom between the two diagonals.
  const auto triangulations = enumerate_triangulations(unit_cube());
  int tried = 0;
  for (const auto& tets : triangulations) {
    const bool uses_12 = std::any_of(tets.begin(), tets.end(), [](const Tet& t) {
      return std::count(t.begin(), t.end(), 1u) && std::count(t.begin(), t.end(), 2u);
    });
    if (!uses_12 || tried == 8) continue;
    ++tried;
    std::vector<Point> p = unit_cube().corners;
    p[0][2] = -0.01;
    std::vector<Tet> with_cap = tets;
    with_cap.push_back({0, 1, 2, 3});
    TetMesh mesh = make_tet_mesh(p, with_cap);
    orient_positively(mesh);
    const auto found = compare(mesh, permissive_criteria());
    std::set<int> sizes;
    for (const Candidate& c : found) {
      if (c.type == CellType::Hex) sizes.insert(c.nb_tets);
    }
    EXPECT_EQ(sizes, (std::set<int>{int(tets.size()), int(tets.size()) + 1}));
  }
  EXPECT_GT(tried, 0);
}

// ----------------------------------------------------------------------- TetGen lattices

TEST(find_candidates_exhaustive, agrees_cell_by_cell_with_a_brute_force_oracle_on_tetgen_lattices) {
  if (std::system("command -v tetgen > /dev/null 2>&1") != 0) GTEST_SKIP() << "no tetgen";
  constexpr int n = 4;
  std::size_t cells_filled = 0, strict_filled = 0, hexes_elsewhere = 0, many_caps = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    for (double jitter : {0.05, 0.2}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", jitter " + std::to_string(jitter));
      const TetMesh mesh = tetgen_lattice(n, jitter, seed);
      ASSERT_GT(mesh.nb_tets(), 0u);
      const auto found = compare(mesh, anything());
      // The finder's hexahedra by their faces (the same 8 vertices may make differently
      // connected, twisted hexahedra: the criteria here accept anything).
      std::map<std::set<std::vector<index_t>>, std::set<std::vector<index_t>>> hex_groups;
      for (const Candidate& c : found) {
        if (c.type != CellType::Hex) continue;
        hex_groups[faces_of(c)].insert(tets_of(found, c));
      }
      std::size_t lattice_hexes = 0;
      auto id = [&](int i, int j, int k) { return index_t((k * (n + 1) + j) * (n + 1) + i); };
      for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
          for (int i = 0; i < n; ++i) {
            const std::array<index_t, 8> v = {
                id(i, j, k),     id(i + 1, j, k),     id(i + 1, j + 1, k),     id(i, j + 1, k),
                id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
            // The oracle: the tets with all four corners among the cell's 8 vertices...
            std::vector<index_t> inside;
            for (index_t t = 0; t < mesh.nb_tets(); ++t) {
              const index_t* q = mesh.tet(t);
              if (std::all_of(q, q + 4, [&](index_t x) {
                    return std::find(v.begin(), v.end(), x) != v.end();
                  })) {
                inside.push_back(t);
              }
            }
            // ... fill it (strict), or some of them do (flat tets on its faces may belong to the
            // cell next door): every subset, by brute force.
            ASSERT_LE(inside.size(), 16u);
            std::set<std::vector<index_t>> groups;
            for (unsigned mask = 1; mask < (1u << inside.size()); ++mask) {
              std::vector<index_t> g;
              for (std::size_t b = 0; b < inside.size(); ++b) {
                if (mask & (1u << b)) g.push_back(inside[b]);
              }
              if (fills(mesh, g, CellType::Hex, v.data())) groups.insert(g);
            }
            if (fills(mesh, inside, CellType::Hex, v.data())) ++strict_filled;
            if (!groups.empty()) ++cells_filled;
            Candidate cell{};
            cell.type = CellType::Hex;
            std::copy(v.begin(), v.end(), cell.vertices.begin());
            const auto it = hex_groups.find(faces_of(cell));
            const std::set<std::vector<index_t>> by_finder =
                it == hex_groups.end() ? std::set<std::vector<index_t>>{} : it->second;
            // Flat tets on the cell's faces ("caps", in the fullest group only) may be left out:
            // the finder gives every subset of up to 3 caps, otherwise none and all.
            std::size_t smallest = 99, largest = 0;
            for (const auto& g : groups) {
              smallest = std::min(smallest, g.size());
              largest = std::max(largest, g.size());
            }
            if (groups.empty() || largest - smallest <= 3) {
              EXPECT_EQ(by_finder, groups) << "cell " << i << ' ' << j << ' ' << k;
            } else {
              EXPECT_EQ(by_finder.size(), 2u);
              for (const auto& g : by_finder) {
                EXPECT_EQ(groups.count(g), 1u);
                EXPECT_TRUE(g.size() == smallest || g.size() == largest);
              }
              ++many_caps;
            }
            lattice_hexes += it == hex_groups.end() ? 0 : 1;
          }
        }
      }
      hexes_elsewhere += hex_groups.size() - lattice_hexes;
    }
  }
  // Most cells of a lightly jittered Delaunay lattice are hexahedra.
  EXPECT_GT(cells_filled, 6u * 64u / 2u);
  RecordProperty("cells_filled", static_cast<int>(cells_filled));
  RecordProperty("cells_filled_by_all_their_tets", static_cast<int>(strict_filled));
  RecordProperty("hexes_not_lattice_cells", static_cast<int>(hexes_elsewhere));
  RecordProperty("cells_with_more_than_3_caps", static_cast<int>(many_caps));
  std::printf(
      "[ lattice  ] %zu of %d cells filled (%zu by all their tets, %zu with > 3 caps), "
      "%zu other hexes\n",
      cells_filled, 6 * 64, strict_filled, many_caps, hexes_elsewhere);
}

}  // namespace
}  // namespace hexmerge::test
