// The block (select/block.cpp): hexahedra and prisms kept together before the greedy stages.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "fixtures.h"
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

TEST(select_block, a_grid_capped_by_pyramids_is_kept_whole_with_its_pyramids) {
  const int n = 4;
  const Outcome run = recombine_and_check(capped_kuhn_grid(n), {});
  EXPECT_EQ(hexes(run), std::size_t(n * n * n));
  EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Pyramid)], std::size_t(n * n));
  EXPECT_EQ(run.mesh.nb_cells(), std::size_t(n * n * n + n * n));
  EXPECT_EQ(run.report.block_hexahedra, std::size_t(n * n * n));
}

TEST(select_block, a_cube_whose_face_nothing_closes_leaves_the_block_and_the_rest_conforms) {
  // Square (1, 2) of the cap has no pyramid: the cube behind it cannot be a hex, and neither
  // can every cube whose face would then meet two of its tets; the rest stays hexes.
  const int n = 4;
  const Outcome run = recombine_and_check(capped_kuhn_grid(n, {1, 2}), {});
  EXPECT_LT(hexes(run), std::size_t(n * n * n));
  EXPECT_LT(run.report.block_hexahedra, std::size_t(n * n * n));
  EXPECT_GE(hexes(run), std::size_t(n * n * n / 2));
  for (index_t c = 0; c < run.mesh.nb_cells(); ++c) {
    if (run.mesh.types[c] != CellType::Hex) continue;
    double x_max = 0, y_min = n, z_min = n;
    for (index_t i = 0; i < run.mesh.cell_size(c); ++i) {
      const double* p = &run.mesh.points[3 * std::size_t(run.mesh.cell(c)[i])];
      x_max = std::max(x_max, p[0]);
      y_min = std::min(y_min, p[1]);
      z_min = std::min(z_min, p[2]);
    }
    EXPECT_FALSE(x_max == n && y_min == 1 && z_min == 2) << "the cube behind the open square";
  }
}

TEST(select_block, a_hole_in_a_tetgen_lattice_leaves_most_of_the_block) {
  // An exact lattice that TetGen splits cube by cube its own way (5 or 6 tets, diagonals as they
  // come), one interior point moved: the eight cubes around it are no near-perfect hexahedra,
  // and the cubes next to them need closers from their tets. Letting the lesser by quality (all
  // 1) leave, the hole grew through the lattice: 193, 216 and 212 of 512 hexes on these seeds.
  if (std::system("command -v tetgen > /dev/null 2>&1") != 0) GTEST_SKIP() << "no tetgen";
  const int n = 8;
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> pick(1, n - 1);
    std::vector<Point> points;
    for (int k = 0; k <= n; ++k) {
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) points.push_back({double(i), double(j), double(k)});
      }
    }
    const int i = pick(rng), j = pick(rng), k = pick(rng);
    Point& moved = points[(k * (n + 1) + j) * (n + 1) + i];
    moved = {moved[0] + 0.35, moved[1] + 0.3, moved[2] + 0.25};
    const TetMesh mesh = tetgen_mesh(points);
    ASSERT_GT(mesh.nb_tets(), 0u);
    const Outcome run = recombine_and_check(mesh, {}, false);
    EXPECT_GE(hexes(run), std::size_t(0.7 * n * n * n));
    EXPECT_GE(run.report.block_hexahedra, std::size_t(0.65 * n * n * n));
  }
}

TEST(select_block, a_swept_disc_becomes_hexahedra_and_prisms_only) {
  // A disc's cross-section (unit lattice points at least 0.6 inside, a ring of 50 points on the
  // circle of radius 8 and one 0.3 inside) repeated on 10 planes, as hexmerge mesh sweeps an
  // extruded shape, through TetGen: every slab is prisms over the section's triangles, which
  // pair into hexahedra. The section is symmetric, so rival pairings tie in quality; ordered by
  // index, planes paired them differently and the block unravelled.
  if (std::system("command -v tetgen > /dev/null 2>&1") != 0) GTEST_SKIP() << "no tetgen";
  const double radius = 8.0, pi = std::acos(-1.0);
  std::vector<std::array<double, 2>> section;
  const int stations = 50;
  for (double r : {radius, radius - 0.3})
    for (int i = 0; i < stations; ++i)
      section.push_back({r * std::cos(2 * pi * i / stations), r * std::sin(2 * pi * i / stations)});
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      if (std::hypot(i, j) <= radius - 0.6) section.push_back({double(i), double(j)});
  std::vector<Point> points;
  for (int k = 0; k <= 9; ++k)
    for (const auto& p : section) points.push_back({p[0], p[1], double(k)});
  const TetMesh mesh = tetgen_mesh(points);
  ASSERT_GT(mesh.nb_tets(), 0u);
  const Outcome run = recombine_and_check(mesh, {});
  EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Tet)], 0u);
  EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Pyramid)], 0u);
  // Measured: 2142 hexahedra (94 % of the volume) and 234 prisms; by index, 853 hexahedra
  // and 4141 tets left.
  EXPECT_GE(run.report.volume_fraction[static_cast<int>(CellType::Hex)], 0.9);
}

}  // namespace
}  // namespace hexmerge::test
