// QuadPairs' ranges: every face's [begin, end) lies inside the partner array, including the last
// face's end and meshes with no partner at all (the accessors indexed past the end and into an
// empty vector: undefined behaviour, an abort under -D_GLIBCXX_ASSERTIONS). Its partners: those a
// test of every pair of faces from each side gives (QuadPairs tests each pair once).
#include "hexmerge/recombine/quad_pairs.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "fixtures.h"
#include "hexmerge/geometry/quality.h"

namespace hexmerge::test {
namespace {

void expect_ranges_inside(const TetMesh& mesh, const QuadPairs& pairs) {
  const QuadPartner* first = mesh.nb_tets() ? pairs.begin(0, 0) : nullptr;
  std::size_t total = 0;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    for (int f = 0; f < 4; ++f) {
      ASSERT_LE(pairs.begin(t, f), pairs.end(t, f));
      total += static_cast<std::size_t>(pairs.end(t, f) - pairs.begin(t, f));
      EXPECT_EQ(((pairs.mask(t) >> f) & 1u) != 0, pairs.begin(t, f) != pairs.end(t, f));
      for (const QuadPartner* p = pairs.begin(t, f); p != pairs.end(t, f); ++p) {
        EXPECT_LT(p->face / 4, mesh.nb_tets());
        EXPECT_NE(p->face / 4, t);
      }
    }
  }
  EXPECT_EQ(total, pairs.size());
  if (mesh.nb_tets()) {
    EXPECT_EQ(pairs.end(mesh.nb_tets() - 1, 3), first + pairs.size());
  }
}

TEST(QuadPairs, RangesOfAGridStayInsideThePartners) {
  const TetMesh mesh = kuhn_grid(2);
  const TetTopology topology(mesh);
  const QuadPairs pairs(mesh, topology, 150.0, 179.0, 150.0, 2, true);
  EXPECT_GT(pairs.size(), 0u);
  expect_ranges_inside(mesh, pairs);
}

TEST(QuadPairs, ATetAloneHasEmptyRanges) {
  const TetMesh mesh = make_tet_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2, 3}});
  const TetTopology topology(mesh);
  const QuadPairs pairs(mesh, topology, 150.0, 179.0, 150.0, 1, true);
  EXPECT_EQ(pairs.size(), 0u);
  expect_ranges_inside(mesh, pairs);
}

// Face g of tet s is a partner of face f of tet t exactly when, seen from (t, f), the two
// triangles make a quad (quad_from_triangles), flat enough (its dihedral angle across the diagonal
// from its first vertex; the boundary's bound when both triangles are on the boundary) and with
// no corner above the bound: every pair of faces of the mesh tested from each side.
void expect_partners_of_each_side(const TetMesh& mesh, double dihedral, double boundary_dihedral,
                                  double corner) {
  const TetTopology topology(mesh);
  const QuadPairs pairs(mesh, topology, dihedral, boundary_dihedral, corner, 2, true);
  const index_t nt = mesh.nb_tets();
  std::size_t total = 0;
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      std::set<index_t> expected, got;
      for (const QuadPartner* p = pairs.begin(t, f); p != pairs.end(t, f); ++p) got.insert(p->face);
      for (index_t s = 0; s < nt; ++s) {
        if (s == t) continue;
        for (int g = 0; g < 4; ++g) {
          std::array<index_t, 4> q;
          if (!quad_from_triangles(tet_face(mesh, t, f), tet_face(mesh, s, g), q)) continue;
          const bool boundary = topology.on_boundary(t, f) && topology.on_boundary(s, g);
          const double* a = mesh.point(q[0]);
          const double* b = mesh.point(q[1]);
          const double* c = mesh.point(q[2]);
          const double* d = mesh.point(q[3]);
          if (quad_dihedral_angle(a, b, c, d) < (boundary ? boundary_dihedral : dihedral)) continue;
          if (quad_max_corner_angle(a, b, c, d) > corner) continue;
          expected.insert(4 * s + g);
        }
      }
      EXPECT_EQ(got, expected) << "face " << f << " of tet " << t;
      total += got.size();
    }
  }
  EXPECT_EQ(total, pairs.size());
  EXPECT_GT(total, 0u);
}

TEST(QuadPairs, PartnersAreThoseOfATestFromEachSide) {
  std::mt19937 rng(7);
  TetMesh grid = kuhn_grid(3);
  random_perturbation(grid, rng, 0.08);
  expect_partners_of_each_side(grid, 150.0, 179.0, 150.0);
  expect_partners_of_each_side(grid, 120.0, 150.0, 160.0);
  expect_partners_of_each_side(tetgen_lattice(3, 0.1, 3), 150.0, 179.0, 150.0);
}

}  // namespace
}  // namespace hexmerge::test
