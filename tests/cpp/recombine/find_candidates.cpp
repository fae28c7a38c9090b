// The search programs' candidate finder: every candidate is a valid cell its tets tile (volume,
// vertices, orientation, quality), reported once, in an order and number that do not depend on
// the threads; acceptance is monotone; element types and regions are respected.
#include "hexmerge/recombine/find_candidates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "fixtures.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/rf_graph.h"

namespace hexmerge::test {
namespace {

Candidates find(const TetMesh& mesh, const AcceptanceCriteria& criteria, int threads = 1) {
  const TetTopology topology(mesh);
  return find_candidates(mesh, topology, criteria, threads);
}

using Key = std::tuple<int, std::vector<index_t>, std::vector<index_t>>;

Key key_of(const Candidates& cs, const Candidate& c) {
  const TetSpan tets = cs.tets(c);
  return {static_cast<int>(c.type), std::vector<index_t>(tets.begin(), tets.end()),
          std::vector<index_t>(c.vertices.begin(), c.vertices.begin() + nb_vertices(c.type))};
}

double det(const double* o, const double* a, const double* b, const double* c) {
  const double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
  const double v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
  const double w[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}

// Checks that the group's boundary triangles (tet faces not shared within the group) lie on the
// cell's faces, each triangle face once and each quad face as two triangles on one diagonal, and
// returns the volume the cell's faces enclose, each quad split on the group's own diagonal (so
// that it must equal the tets' volume exactly, planar or not). NaN when the boundary is wrong.
double enclosed_volume(const TetMesh& mesh, const Candidate& c, TetSpan tets) {
  const CellDescriptor& d = descriptor(c.type);
  std::vector<std::set<index_t>> boundary;
  for (int i = 0; i < c.nb_tets; ++i) {
    const index_t* q = mesh.tet(tets[i]);
    for (int f = 0; f < 4; ++f) {
      std::set<index_t> face;
      for (int k = 0; k < 4; ++k) {
        if (k != f) face.insert(q[k]);
      }
      int shared = 0;
      for (int j = 0; j < c.nb_tets; ++j) {
        const index_t* r = mesh.tet(tets[j]);
        const std::set<index_t> other(r, r + 4);
        shared += j != i && std::includes(other.begin(), other.end(), face.begin(), face.end());
      }
      if (shared == 0) boundary.push_back(face);
    }
  }
  const double* o = mesh.point(c.vertices[0]);
  const auto p = [&](int f, int k) { return mesh.point(c.vertices[d.face[f][k]]); };
  double six_volume = 0.0;
  std::size_t covered = 0;
  for (int f = 0; f < d.nb_faces; ++f) {
    std::set<index_t> cell_face;
    for (int k = 0; k < d.face_size[f]; ++k) cell_face.insert(c.vertices[d.face[f][k]]);
    std::vector<std::set<index_t>> on;
    for (const auto& t : boundary) {
      if (std::includes(cell_face.begin(), cell_face.end(), t.begin(), t.end())) on.push_back(t);
    }
    covered += on.size();
    if (d.face_size[f] == 3) {
      if (on.size() != 1) return std::nan("");
      six_volume += det(o, p(f, 0), p(f, 1), p(f, 2));
      continue;
    }
    if (on.size() != 2) return std::nan("");
    const index_t v0 = c.vertices[d.face[f][0]], v2 = c.vertices[d.face[f][2]];
    const bool diagonal_02 = on[0].count(v0) && on[0].count(v2);
    six_volume += diagonal_02
                      ? det(o, p(f, 0), p(f, 1), p(f, 2)) + det(o, p(f, 0), p(f, 2), p(f, 3))
                      : det(o, p(f, 0), p(f, 1), p(f, 3)) + det(o, p(f, 1), p(f, 2), p(f, 3));
  }
  if (covered != boundary.size()) return std::nan("");  // a boundary triangle off the cell
  return six_volume / 6.0;
}

// The meshes the properties are checked on: grids, a sheared and perturbed grid, and a jittered
// TetGen lattice (when tetgen is installed) with two regions.
std::vector<std::pair<std::string, TetMesh>> meshes() {
  std::vector<std::pair<std::string, TetMesh>> out;
  out.emplace_back("kuhn 3", kuhn_grid(3));
  out.emplace_back("five-tet 3", five_tet_grid(3));
  std::mt19937 rng(5);
  TetMesh sheared = kuhn_grid(3);
  random_affine_map(sheared, rng, 0.2);
  random_perturbation(sheared, rng, 0.03);
  out.emplace_back("kuhn 3, sheared and perturbed", sheared);
  TetMesh lattice = tetgen_lattice(4, 0.05, 3);
  if (!lattice.tets.empty()) {
    lattice.regions.resize(lattice.nb_tets());
    for (index_t t = 0; t < lattice.nb_tets(); ++t) {
      lattice.regions[t] = lattice.point(lattice.tet(t)[0])[0] < 2.0 ? 1 : 2;
    }
    out.emplace_back("tetgen lattice 4, two regions", lattice);
  }
  return out;
}

TEST(find_candidates, every_candidate_is_a_valid_cell_its_tets_tile) {
  for (const auto& [name, mesh] : meshes()) {
    SCOPED_TRACE(name);
    const AcceptanceCriteria criteria = permissive_criteria();
    const auto candidates = find(mesh, criteria);
    ASSERT_FALSE(candidates.empty());
    std::set<Key> seen;
    for (const Candidate& c : candidates) {
      const int nv = nb_vertices(c.type);
      ASSERT_NE(c.type, CellType::Tet);
      ASSERT_LT(c.graph, rf_graphs().size());
      EXPECT_EQ(rf_graphs()[c.graph].type, c.type);
      EXPECT_EQ(c.nb_tets, rf_graphs()[c.graph].nb_nodes);
      // Tets sorted, distinct, ids of the mesh; vertices distinct, then NO_VERTEX.
      const TetSpan tets = candidates.tets(c);
      EXPECT_EQ(tets.size(), c.nb_tets);
      EXPECT_TRUE(std::is_sorted(tets.begin(), tets.end()));
      EXPECT_EQ(std::adjacent_find(tets.begin(), tets.end()), tets.end());
      for (index_t t : tets) EXPECT_LT(t, mesh.nb_tets());
      const std::set<index_t> corners(c.vertices.begin(), c.vertices.begin() + nv);
      EXPECT_EQ(static_cast<int>(corners.size()), nv);
      for (int i = nv; i < 8; ++i) EXPECT_EQ(c.vertices[i], NO_VERTEX);
      // The tets use exactly the cell's corners and tile its volume.
      std::set<index_t> used;
      double tets_volume = 0.0;
      for (index_t t : tets) {
        const index_t* q = mesh.tet(t);
        used.insert(q, q + 4);
        tets_volume += cell_volume(CellType::Tet, mesh.points.data(), q);
        if (criteria.respect_regions && !mesh.regions.empty()) {
          EXPECT_EQ(mesh.regions[t], mesh.regions[tets[0]]) << "across regions";
        }
      }
      EXPECT_EQ(used, corners);
      EXPECT_GT(cell_volume(c.type, mesh.points.data(), c.vertices.data()), 0.0) << "inverted";
      const double enclosed = enclosed_volume(mesh, c, tets);
      ASSERT_FALSE(std::isnan(enclosed)) << "the tets' boundary is not the cell's faces";
      EXPECT_NEAR(enclosed, tets_volume, 1e-9 * tets_volume) << "the tets do not tile the cell";
      // Quality is the cell's scaled Jacobian, and passes the criteria.
      const double sj = scaled_jacobian(c.type, mesh.points.data(), c.vertices.data());
      EXPECT_NEAR(c.quality, sj, 1e-6);
      if (c.quality < criteria.min_scaled_jacobian - 1e-6) {  // no worse than its tets
        EXPECT_TRUE(c.type == CellType::Hex || c.type == CellType::Prism);
        for (index_t t : tets)
          EXPECT_GE(c.quality,
                    scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)) - 1e-6);
      }
      EXPECT_TRUE(seen.insert(key_of(candidates, c)).second) << "reported twice";
    }
  }
}

TEST(find_candidates, does_not_depend_on_the_threads) {
  for (const auto& [name, mesh] : meshes()) {
    SCOPED_TRACE(name);
    const auto one = find(mesh, permissive_criteria(), 1);
    const auto two = find(mesh, permissive_criteria(), 2);
    const auto three = find(mesh, permissive_criteria(), 3);
    ASSERT_EQ(one.size(), two.size());
    ASSERT_EQ(one.size(), three.size());
    for (std::size_t i = 0; i < one.size(); ++i) {
      EXPECT_EQ(key_of(one, one[i]), key_of(two, two[i])) << i;
      EXPECT_EQ(key_of(one, one[i]), key_of(three, three[i])) << i;
      EXPECT_EQ(one[i].quality, two[i].quality) << i;
    }
  }
}

TEST(find_candidates, stricter_acceptance_keeps_a_subset) {
  for (const auto& [name, mesh] : meshes()) {
    SCOPED_TRACE(name);
    const auto loose = find(mesh, permissive_criteria());
    std::set<Key> loose_keys;
    for (const Candidate& c : loose) loose_keys.insert(key_of(loose, c));
    AcceptanceCriteria strict = permissive_criteria();
    strict.min_scaled_jacobian = 0.6;
    strict.lowest_scaled_jacobian = 0.6;
    strict.min_dihedral_angle = 170.0;
    strict.max_face_angle = 120.0;
    const auto kept = find(mesh, strict);
    EXPECT_LE(kept.size(), loose.size());
    for (const Candidate& c : kept) {
      EXPECT_TRUE(loose_keys.count(key_of(kept, c)))
          << "a candidate only the stricter criteria find";
      EXPECT_GE(c.quality, 0.6 - 1e-6);
    }
  }
}

// Below min_scaled_jacobian, down to lowest_scaled_jacobian, only hexes and prisms at least as
// good as their worst tet pass.
TEST(find_candidates, below_the_minimum_only_hexes_and_prisms_better_than_their_tets) {
  std::size_t relaxed = 0;
  for (const auto& [name, mesh] : meshes()) {
    SCOPED_TRACE(name);
    AcceptanceCriteria criteria = permissive_criteria();
    criteria.min_scaled_jacobian = 0.6;
    criteria.lowest_scaled_jacobian = 0.1;
    const Candidates found = find(mesh, criteria);
    for (const Candidate& c : found) {
      if (c.quality >= 0.6 - 1e-6) continue;
      ++relaxed;
      EXPECT_TRUE(c.type == CellType::Hex || c.type == CellType::Prism);
      EXPECT_GE(c.quality, 0.1 - 1e-6);
      for (index_t t : found.tets(c)) {
        EXPECT_GE(c.quality,
                  scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)) - 1e-6);
      }
    }
  }
  EXPECT_GT(relaxed, 0u);  // the rule is exercised
}

TEST(find_candidates, finds_each_cube_of_a_grid_and_only_enabled_types) {
  for (int n : {1, 2}) {
    const TetMesh mesh = five_tet_grid(n);
    const auto all = find(mesh, AcceptanceCriteria{});
    std::size_t hexes = 0;
    for (const Candidate& c : all) hexes += c.type == CellType::Hex;
    EXPECT_EQ(hexes, static_cast<std::size_t>(n * n * n));  // one per cube, nothing across
    for (CellType off : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
      AcceptanceCriteria criteria;
      criteria.types[static_cast<int>(off)] = false;
      const auto some = find(mesh, criteria);
      for (const Candidate& c : some) EXPECT_NE(c.type, off);
      std::size_t others = 0;
      for (const Candidate& c : all) others += c.type != off;
      EXPECT_EQ(some.size(), others) << "turning one type off changes the others";
    }
  }
}

TEST(find_candidates, respect_regions_splits_the_candidates_at_the_interface) {
  TetMesh mesh = kuhn_grid(2);
  mesh.regions.resize(mesh.nb_tets());
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    double x = 0.0;
    for (int i = 0; i < 4; ++i) x += mesh.point(mesh.tet(t)[i])[0];
    mesh.regions[t] = x < 4.0 ? 0 : 1;  // the plane x = 1 between the two layers of cubes
  }
  AcceptanceCriteria criteria;
  const auto apart = find(mesh, criteria);
  criteria.respect_regions = false;
  const auto together = find(mesh, criteria);
  EXPECT_LT(apart.size(), together.size()) << "nothing crossed the interface";
  for (const Candidate& c : apart) {
    const TetSpan tets = apart.tets(c);
    for (index_t t : tets) EXPECT_EQ(mesh.regions[t], mesh.regions[tets[0]]);
  }
}

}  // namespace
}  // namespace hexmerge::test
