// QuadPairs' ranges: every face's [begin, end) lies inside the partner array, including the last
// face's end and meshes with no partner at all (the accessors indexed past the end and into an
// empty vector: undefined behaviour, an abort under -D_GLIBCXX_ASSERTIONS).
#include "hexmerge/recombine/quad_pairs.h"

#include <gtest/gtest.h>

#include "fixtures.h"

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

}  // namespace
}  // namespace hexmerge::test
