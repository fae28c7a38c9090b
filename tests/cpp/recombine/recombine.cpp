// Engine tests: every output goes through the independent checker (check_mesh).
#include "hexmerge/recombine/recombine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <random>
#include <set>
#include <string>

#include "fixtures.h"
#include "hexmerge/check/check_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/bound_selection.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/select_candidates.h"

namespace hexmerge::test {
namespace {

std::string describe(const CheckReport& r) {
  std::string out = "check_mesh: " + std::to_string(r.counts[0]) + " tets, " +
                    std::to_string(r.counts[1]) + " pyramids, " + std::to_string(r.counts[2]) +
                    " prisms, " + std::to_string(r.counts[3]) + " hexes; " +
                    std::to_string(r.nonconforming_quads) + " non-conforming quads, " +
                    std::to_string(r.cracks) + " cracks";
  for (const auto& line : r.problems) out += "\n  " + line;
  return out;
}

/// Largest volume change that non-planar quads can explain: a bilinear quad a-b-c-d encloses
/// the mean of its two triangulations, which differ by the tet (a, b, c, d); so each quad face
/// moves the volume by at most half that tet's volume from its tets' triangles.
double quad_volume_bound(const MixedMesh& mesh) {
  double bound = 0.0;
  for (index_t c = 0; c < mesh.nb_cells(); ++c) {
    const CellDescriptor& d = descriptor(mesh.types[c]);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      const auto p = [&](int i) {
        return &mesh.points[3 * std::size_t(mesh.cell(c)[d.face[f][i]])];
      };
      bound += 0.5 * std::abs(tet_volume(p(0), p(1), p(2), p(3)));
    }
  }
  return bound;
}

struct Outcome {
  MixedMesh mesh;
  RecombineReport report;
  CheckReport check;
};

/// Recombines, checks the output independently, and expects it valid; `flat` when every quad
/// face is planar, so that the volume must be kept to round-off; `conforming` when no quad may
/// meet two triangles; `regions_kept` unless cells may span regions.
Outcome recombine_and_check(const TetMesh& input, const RecombineParameters& parameters,
                            bool flat = true, bool conforming = true, bool regions_kept = true) {
  Outcome run;
  run.mesh = recombine(input, parameters, run.report);
  run.check = check_mesh(run.mesh, input);
  if (regions_kept) {
    EXPECT_TRUE(run.check.valid()) << describe(run.check);
  } else {
    CheckReport without_regions = run.check;
    without_regions.region_mismatches = 0;
    EXPECT_TRUE(without_regions.valid()) << describe(run.check);
  }
  if (conforming) {
    EXPECT_EQ(run.check.nonconforming_quads, 0u) << describe(run.check);
  }
  if (flat) {
    EXPECT_LT(std::abs(run.check.relative_volume_difference), 1e-12);
  } else {
    EXPECT_LE(std::abs(run.check.output_volume - run.check.input_volume),
              quad_volume_bound(run.mesh) + 1e-12);
  }
  // The report and the checker agree on what was made.
  EXPECT_EQ(run.report.output_cells, run.mesh.nb_cells());
  for (int t = 0; t < NB_CELL_TYPES; ++t)
    EXPECT_EQ(run.report.output_counts[t], run.check.counts[t]);
  EXPECT_EQ(run.report.input_tets, input.nb_tets());
  return run;
}

std::size_t hexes(const Outcome& run) { return run.check.counts[static_cast<int>(CellType::Hex)]; }

/// Hex templates with at least one accepted candidate.
std::set<std::string> hex_templates(const RecombineReport& report) {
  std::set<std::string> names;
  for (const auto& [name, count] : report.candidates_per_template) {
    if (count > 0 && name.rfind("hex", 0) == 0) names.insert(name);
  }
  return names;
}

struct CubeCase {
  std::vector<Tet> tets;
  int cls;
  std::size_t nb_tets;
  int cycle;
};

std::vector<CubeCase> cube_cases() {
  const Polytope cube = unit_cube();
  const auto triangulations = enumerate_triangulations(cube);
  std::vector<std::string> keys;
  for (const auto& tets : triangulations) keys.push_back(canonical_form(rf_graph(cube, tets)));
  std::vector<int> sizes;
  const std::vector<int> cls = classes_of(keys, sizes);
  std::vector<CubeCase> out;
  for (std::size_t i = 0; i < triangulations.size(); ++i) {
    out.push_back({triangulations[i], cls[i], triangulations[i].size(),
                   solid_cycle_length(rf_graph(cube, triangulations[i]))});
  }
  return out;
}

TEST(recombine, every_cube_triangulation_is_one_hex_of_its_class_template) {
  const auto cases = cube_cases();
  ASSERT_EQ(cases.size(), 74u);
  std::map<int, std::set<std::string>> names_of_class;
  std::map<int, std::pair<std::size_t, int>> shape_of_class;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("cube triangulation " + std::to_string(i));
    const Outcome run = recombine_and_check(polytope_mesh(unit_cube(), cases[i].tets), {});
    EXPECT_EQ(run.mesh.nb_cells(), 1u);
    EXPECT_EQ(hexes(run), 1u);
    EXPECT_DOUBLE_EQ(run.check.min_scaled_jacobian, 1.0);
    const std::set<std::string> names = hex_templates(run.report);
    EXPECT_EQ(names.size(), 1u) << "hex templates found: " << names.size();
    names_of_class[cases[i].cls].insert(names.begin(), names.end());
    shape_of_class[cases[i].cls] = {cases[i].nb_tets, cases[i].cycle};
  }
  ASSERT_EQ(names_of_class.size(), 6u);
  std::set<std::string> all;
  for (const auto& [cls, names] : names_of_class) {
    ASSERT_EQ(names.size(), 1u) << "class " << cls << " maps to several templates";
    const std::string& name = *names.begin();
    all.insert(name);
    const auto [nb_tets, cycle] = shape_of_class[cls];
    // The paper's figures: the 5-tet tree, and 6-tet graphs named after their cycle length.
    if (nb_tets == 5) {
      EXPECT_EQ(name, "hex5");
    } else if (cycle == 4) {
      EXPECT_TRUE(name == "hex6_cycle4a" || name == "hex6_cycle4b") << name;
    } else {
      EXPECT_EQ(name, "hex6_cycle" + std::to_string(cycle));
    }
  }
  EXPECT_EQ(all.size(), 6u) << "the six classes must map to six different templates";
}

TEST(recombine, cube_triangulations_after_random_affine_maps) {
  std::mt19937 rng(2024);
  const auto cases = cube_cases();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      SCOPED_TRACE("cube triangulation " + std::to_string(i) + ", map " + std::to_string(k));
      TetMesh mesh = polytope_mesh(unit_cube(), cases[i].tets);
      random_affine_map(mesh, rng);
      const Outcome run = recombine_and_check(mesh, permissive_parameters());
      EXPECT_EQ(run.mesh.nb_cells(), 1u);
      EXPECT_EQ(hexes(run), 1u);
    }
  }
}

TEST(recombine, cube_triangulations_after_small_perturbations) {
  std::mt19937 rng(99);
  const auto cases = cube_cases();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      SCOPED_TRACE("cube triangulation " + std::to_string(i) + ", perturbation " +
                   std::to_string(k));
      TetMesh mesh = polytope_mesh(unit_cube(), cases[i].tets);
      if (k == 2) random_affine_map(mesh, rng, 0.2);
      random_perturbation(mesh, rng, 0.03);
      const Outcome run = recombine_and_check(mesh, permissive_parameters(), /*flat=*/false);
      EXPECT_EQ(run.mesh.nb_cells(), 1u);
      EXPECT_EQ(hexes(run), 1u);
    }
  }
}

TEST(recombine, every_prism_triangulation_is_one_prism) {
  const auto triangulations = enumerate_triangulations(unit_prism());
  ASSERT_EQ(triangulations.size(), 6u);
  for (bool make_hexahedra : {true, false}) {
    for (std::size_t i = 0; i < triangulations.size(); ++i) {
      SCOPED_TRACE("prism triangulation " + std::to_string(i));
      RecombineParameters p;
      p.make_hexahedra = make_hexahedra;
      const Outcome run = recombine_and_check(polytope_mesh(unit_prism(), triangulations[i]), p);
      EXPECT_EQ(run.mesh.nb_cells(), 1u);
      EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Prism)], 1u);
      EXPECT_GT(run.report.candidates_per_template.at("prism"), 0u);
    }
  }
}

TEST(recombine, every_pyramid_triangulation_is_one_pyramid) {
  const auto triangulations = enumerate_triangulations(square_pyramid());
  ASSERT_EQ(triangulations.size(), 2u);
  for (std::size_t i = 0; i < triangulations.size(); ++i) {
    SCOPED_TRACE("pyramid triangulation " + std::to_string(i));
    const Outcome run = recombine_and_check(polytope_mesh(square_pyramid(), triangulations[i]), {});
    EXPECT_EQ(run.mesh.nb_cells(), 1u);
    EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Pyramid)], 1u);
  }
}

TEST(recombine, structured_grids_become_all_hexes) {
  for (int n : {1, 2, 4, 6}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const std::size_t cubes = std::size_t(n) * n * n;
    const Outcome kuhn = recombine_and_check(kuhn_grid(n), {});
    EXPECT_EQ(hexes(kuhn), cubes);
    EXPECT_EQ(kuhn.mesh.nb_cells(), cubes);
    EXPECT_DOUBLE_EQ(kuhn.check.min_scaled_jacobian, 1.0);
    const Outcome five = recombine_and_check(five_tet_grid(n), {});
    EXPECT_EQ(hexes(five), cubes);
    EXPECT_EQ(five.mesh.nb_cells(), cubes);
    EXPECT_NEAR(five.report.element_reduction_percent, 80.0, 1e-9);
    EXPECT_NEAR(five.report.volume_fraction[static_cast<int>(CellType::Hex)], 1.0, 1e-12);
  }
}

TEST(recombine, without_hexahedra_a_kuhn_grid_becomes_conforming_prisms) {
  RecombineParameters p;
  p.make_hexahedra = false;
  p.conformity = Conformity::Conforming;
  const Outcome run = recombine_and_check(kuhn_grid(3), p);
  EXPECT_EQ(hexes(run), 0u);
  EXPECT_GT(run.check.counts[static_cast<int>(CellType::Prism)], 0u);
  EXPECT_EQ(run.report.nonconforming_quads, 0u);
}

TEST(recombine, report_counts_the_non_conforming_quads_the_checker_finds) {
  RecombineParameters p;
  p.make_hexahedra = false;
  p.conformity = Conformity::Allow;
  const Outcome run = recombine_and_check(kuhn_grid(3), p, true, /*conforming=*/false);
  EXPECT_EQ(run.report.nonconforming_quads, run.check.nonconforming_quads);
}

/// Regions of a Kuhn grid split by the plane x = y, which cuts the cubes on the diagonal along
/// tet faces: region 1 where the tet's centroid has x > y.
TetMesh diagonal_regions(int n) {
  TetMesh mesh = kuhn_grid(n);
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    double x = 0, y = 0;
    for (int i = 0; i < 4; ++i) {
      x += mesh.point(mesh.tet(t)[i])[0];
      y += mesh.point(mesh.tet(t)[i])[1];
    }
    mesh.regions.push_back(x > y ? 1 : 0);
  }
  return mesh;
}

TEST(recombine, regions_are_never_merged_across) {
  const int n = 4;
  const TetMesh input = diagonal_regions(n);
  // Cells may not cross regions; conformity is the next test's business.
  const Outcome run = recombine_and_check(input, {}, true, /*conforming=*/false);
  EXPECT_EQ(run.check.region_mismatches, 0u);
  ASSERT_EQ(run.mesh.source_offsets.size(), std::size_t(run.mesh.nb_cells()) + 1);
  for (index_t c = 0; c < run.mesh.nb_cells(); ++c) {
    std::set<std::int32_t> regions;
    for (index_t k = run.mesh.source_offsets[c]; k < run.mesh.source_offsets[c + 1]; ++k) {
      regions.insert(input.region(run.mesh.source_tets[k]));
    }
    EXPECT_EQ(regions.size(), 1u) << "cell " << c << " spans regions";
  }
  // The n x n cubes cut by the plane x = y cannot be hexes.
  EXPECT_LE(hexes(run), std::size_t(n * n * n - n * n));

  RecombineParameters ignore;
  ignore.respect_regions = false;
  const Outcome merged = recombine_and_check(input, ignore, true, true, /*regions_kept=*/false);
  EXPECT_EQ(hexes(merged), std::size_t(n * n * n));
  // The n x n cut hexes hold tets of both regions: whichever region they carry, the checker
  // sees it differ from one of their tets.
  EXPECT_EQ(merged.check.region_mismatches, std::size_t(n * n));
}

TEST(recombine, a_region_cut_through_cubes_gives_hexes_and_half_cube_prisms) {
  // The best answer exists and is conforming: every uncut cube a hex, every cut cube two
  // prisms (the three Kuhn tets on each side of x = y form a prism). Taking a skewed hex
  // (a parallelepiped over two cubes, scaled Jacobian 0.71) instead costs a hex and conformity.
  const int n = 4;
  const Outcome run = recombine_and_check(diagonal_regions(n), {});
  EXPECT_EQ(hexes(run), std::size_t(n * n * n - n * n));
  EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Prism)], std::size_t(2 * n * n));
}

/// A Kuhn grid capped on its x = n side: over each boundary square, the two tets from its
/// triangles to an apex half a cube out (a closing pyramid), except over square (j, k) = `open`,
/// whose two tets get apexes of their own over their triangles' centroids (no pyramid).
TetMesh capped_kuhn_grid(int n, std::array<int, 2> open = {-1, -1}) {
  TetMesh mesh = kuhn_grid(n);
  const index_t nt = mesh.nb_tets();
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<index_t, 3> tri;
      int m = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != f) tri[m++] = mesh.tet(t)[i];
      }
      bool on_cap = true;
      double c[3] = {0, 0, 0};
      for (index_t v : tri) {
        on_cap = on_cap && mesh.point(v)[0] == n;
        for (int a = 0; a < 3; ++a) c[a] += mesh.point(v)[a] / 3;
      }
      if (!on_cap) continue;
      const int j = int(std::floor(c[1])), k = int(std::floor(c[2]));
      const bool own_apex = j == open[0] && k == open[1];
      const double apex[3] = {n + 0.5, own_apex ? c[1] : j + 0.5, own_apex ? c[2] : k + 0.5};
      index_t a = NO_INDEX;
      for (index_t v = 0; v < mesh.nb_vertices() && a == NO_INDEX; ++v) {
        const double* p = mesh.point(v);
        if (p[0] == apex[0] && p[1] == apex[1] && p[2] == apex[2]) a = v;
      }
      if (a == NO_INDEX) {
        a = mesh.nb_vertices();
        mesh.points.insert(mesh.points.end(), apex, apex + 3);
      }
      mesh.tets.insert(mesh.tets.end(), {tri[0], tri[1], tri[2], a});
    }
  }
  orient_positively(mesh);
  return mesh;
}

TEST(recombine, a_grid_capped_by_pyramids_is_kept_whole_with_its_pyramids) {
  const int n = 4;
  const Outcome run = recombine_and_check(capped_kuhn_grid(n), {});
  EXPECT_EQ(hexes(run), std::size_t(n * n * n));
  EXPECT_EQ(run.check.counts[static_cast<int>(CellType::Pyramid)], std::size_t(n * n));
  EXPECT_EQ(run.mesh.nb_cells(), std::size_t(n * n * n + n * n));
  EXPECT_EQ(run.report.block_hexahedra, std::size_t(n * n * n));
}

TEST(recombine, a_cube_whose_face_nothing_closes_leaves_the_block_and_the_rest_conforms) {
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

TEST(recombine, the_hex_volume_bound_leaves_out_the_cube_nothing_closes) {
  if (!selection_bound_available()) GTEST_SKIP() << "built without GLPK";
  // Volume: 27 cubes and 9 cap squares of two tets, 1/6 each (apex 1/2 above the square).
  const int n = 3;
  const double volume = n * n * n + n * n / 6.0;
  RecombineParameters p;
  p.optimality_bound = true;
  const Outcome whole = recombine_and_check(capped_kuhn_grid(n), p);
  EXPECT_TRUE(whole.report.hex_volume_bound_proved);
  EXPECT_NEAR(whole.report.hex_volume_bound, n * n * n / volume, 1e-9);
  EXPECT_NEAR(whole.report.volume_fraction[static_cast<int>(CellType::Hex)],
              whole.report.hex_volume_bound, 1e-9);
  // Conforming: the cube behind the open square is no candidate any more, so at most 26 cubes.
  const Outcome open = recombine_and_check(capped_kuhn_grid(n, {1, 2}), p);
  EXPECT_TRUE(open.report.hex_volume_bound_proved);
  EXPECT_LE(open.report.hex_volume_bound, (n * n * n - 1) / volume + 1e-9);
  EXPECT_GE(open.report.hex_volume_bound + 1e-9,
            open.report.volume_fraction[static_cast<int>(CellType::Hex)]);
  // Allowed to leave the quad open, every cube can be a hex again.
  p.conformity = Conformity::Allow;
  RecombineReport allowed;
  recombine(capped_kuhn_grid(n, {1, 2}), p, allowed);
  EXPECT_NEAR(allowed.hex_volume_bound, n * n * n / volume, 1e-9);
}

TEST(recombine, a_hole_in_a_tetgen_lattice_leaves_most_of_the_block) {
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

TEST(recombine, a_swept_disc_becomes_hexahedra_and_prisms_only) {
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

TEST(recombine, invalid_input_is_an_input_error) {
  TetMesh mesh = kuhn_grid(1);
  std::swap(mesh.tets[4 * 3 + 1], mesh.tets[4 * 3 + 2]);
  RecombineReport report;
  try {
    recombine(mesh, {}, report);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Element);
    EXPECT_EQ(e.id(), 3u);
  }
  EXPECT_THROW(recombine(TetMesh{}, {}, report), InputError);
}

// ---- Local search (select_candidates.h, step 5) ---------------------------------------------

/// The cells of a selection: tets minus the tets merged away.
std::size_t cells_of(const TetMesh& mesh, const std::vector<Candidate>& candidates,
                     const Selection& selection) {
  std::size_t cells = mesh.nb_tets();
  for (index_t c : selection.elements) cells -= candidates[c].nb_tets - 1u;
  return cells;
}

/// The candidates of one Kuhn cube with exactly the given tet sets, in that order; the first gets
/// the best quality, so that the greedy takes it first.
std::vector<Candidate> kuhn_cube_candidates(const TetMesh& cube,
                                            const std::vector<std::set<index_t>>& wanted) {
  const TetTopology topology(cube);
  const std::vector<Candidate> all = find_candidates(cube, topology, AcceptanceCriteria{}, 1);
  std::vector<Candidate> out;
  for (const std::set<index_t>& tets : wanted) {
    for (const Candidate& c : all) {
      if (std::set<index_t>(c.tets.begin(), c.tets.begin() + c.nb_tets) == tets) out.push_back(c);
    }
  }
  EXPECT_EQ(out.size(), wanted.size());
  if (!out.empty()) out[0].quality = 0.99f;
  return out;
}

// A Kuhn cube is a ring of six tets around its diagonal, 1-0-2-3-5-4-1: every three consecutive
// tets make a prism, every two a pyramid. Offered only prism {0,1,2} (best quality), prism
// {0,2,3} and pyramid {1,4}, the greedy takes the first prism and nothing else fits: 6 - 2 = 4
// cells. The optimum is the other prism and the pyramid, 6 - 2 - 1 = 3 cells: one element for
// two, which the swap finds (the free tets 3 and 4 are next to the first prism).
TEST(local_search, a_swap_undoes_the_greedys_trap_one_element_for_two) {
  const TetMesh cube = kuhn_grid(1);
  const TetTopology topology(cube);
  const std::vector<Candidate> candidates =
      kuhn_cube_candidates(cube, {{0, 1, 2}, {0, 2, 3}, {1, 4}});
  ASSERT_EQ(candidates.size(), 3u);
  RecombineParameters p;
  p.conformity = Conformity::Allow;
  p.local_optimisation = false;  // the paper's move would find it too: leave it to the swap
  p.local_search = false;
  const Selection greedy = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, greedy), 4u);
  EXPECT_EQ(greedy.elements, (std::vector<index_t>{0}));
  p.local_search = true;
  const Selection swapped = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, swapped), 3u);
  EXPECT_EQ(swapped.elements, (std::vector<index_t>{1, 2}));
  EXPECT_EQ(swapped.swap_moves, 1u);
  EXPECT_EQ(swapped.reselection_moves, 0u);
  EXPECT_EQ(swapped.local_search_saved, 1u);
  if (selection_bound_available()) {  // and 3 is the optimum
    const SelectionBound bound = bound_selection(cube.nb_tets(), candidates, {}, 5.0);
    EXPECT_TRUE(bound.proved);
    EXPECT_EQ(bound.bound_elements, 3u);
  }
}

// Prism {0,1,2} (best), prism {2,3,5}, pyramid {0,1}: the greedy keeps the first prism (4 cells);
// the optimum, the second prism and the pyramid (3 cells), needs tet 5, which is not next to the
// first prism: swaps alone cannot reach it, a re-selection within one face hop of free tet 3 can.
TEST(local_search, a_reselection_reaches_what_a_swap_cannot) {
  const TetMesh cube = kuhn_grid(1);
  const TetTopology topology(cube);
  const std::vector<Candidate> candidates =
      kuhn_cube_candidates(cube, {{0, 1, 2}, {2, 3, 5}, {0, 1}});
  ASSERT_EQ(candidates.size(), 3u);
  RecombineParameters p;
  p.conformity = Conformity::Allow;
  p.local_optimisation = false;
  p.local_search_radius = 0;
  const Selection swaps_only = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, swaps_only), 4u);
  EXPECT_EQ(swaps_only.swap_moves, 0u);
  p.local_search_radius = 1;
  const Selection reselected = select_candidates(cube, topology, candidates, p);
  EXPECT_EQ(cells_of(cube, candidates, reselected), 3u);
  EXPECT_EQ(reselected.elements, (std::vector<index_t>{1, 2}));
  EXPECT_EQ(reselected.reselection_moves, 1u);
  EXPECT_EQ(reselected.local_search_saved, 1u);
}

// On jittered grids (many skewed candidates, so the greedy is far from optimal) in every
// conformity mode: never more cells than without the local search (in allow and last_resort
// mode, where the elements that would leave a crack are released after the search, when
// neither run released one); every cell positive, no face shared by three cells, every node
// kept, the volume kept up to what non-planar quads explain; every mode valid (no crack);
// conforming mode with no non-conforming quad; last_resort no more non-conforming quads than
// without.
TEST(local_search, keeps_validity_and_conformity_and_never_adds_cells) {
  std::mt19937 rng(7);
  std::size_t moves = 0, saved = 0;
  for (int grid = 0; grid < 4; ++grid) {
    TetMesh mesh = grid % 2 ? five_tet_grid(4) : kuhn_grid(4);
    random_perturbation(mesh, rng, 0.15);
    for (Conformity mode : {Conformity::Conforming, Conformity::LastResort, Conformity::Allow}) {
      for (bool hexes_on : {true, false}) {
        SCOPED_TRACE("grid " + std::to_string(grid) + ", " + to_string(mode) +
                     (hexes_on ? "" : ", no hexahedra"));
        RecombineParameters p = permissive_parameters();
        p.conformity = mode;
        p.make_hexahedra = hexes_on;
        p.local_search = false;
        RecombineReport off_report, on_report;
        const MixedMesh off = recombine(mesh, p, off_report);
        p.local_search = true;
        p.local_search_radius = 2;
        p.local_search_seeds = LocalSearchSeeds::All;
        const MixedMesh on = recombine(mesh, p, on_report);
        const CheckReport off_check = check_mesh(off, mesh), on_check = check_mesh(on, mesh);
        const bool released = off_report.released_elements + on_report.released_elements > 0;
        if (mode == Conformity::Conforming || !released) {
          EXPECT_LE(on.nb_cells(), off.nb_cells());
        }
        if (mode != Conformity::Conforming && !released) {
          // One selection, so the saving is all the search's.
          EXPECT_EQ(off.nb_cells() - on.nb_cells(), on_report.local_search_saved);
        }
        EXPECT_TRUE(on_check.valid()) << describe(on_check);
        EXPECT_TRUE(off_check.valid()) << describe(off_check);
        EXPECT_EQ(on_check.inverted_cells, 0u) << describe(on_check);
        EXPECT_GT(on_check.min_scaled_jacobian, 0.0);
        EXPECT_EQ(on_check.overshared_faces, 0u);
        EXPECT_EQ(on_check.unused_input_nodes, 0u);
        EXPECT_EQ(on_check.region_mismatches, 0u);
        EXPECT_LE(std::abs(on_check.output_volume - on_check.input_volume),
                  quad_volume_bound(on) + 1e-12);
        for (int t = 0; t < NB_CELL_TYPES; ++t) {
          EXPECT_EQ(on_report.output_counts[t], on_check.counts[t]);
        }
        if (mode == Conformity::Conforming) {
          EXPECT_TRUE(on_check.valid()) << describe(on_check);
          EXPECT_EQ(on_check.nonconforming_quads, 0u);
          EXPECT_EQ(on_report.nonconforming_quads, 0u);
        } else if (mode == Conformity::LastResort && !released) {
          EXPECT_LE(on_check.nonconforming_quads, off_check.nonconforming_quads);
          EXPECT_LE(on_report.nonconforming_quads, off_report.nonconforming_quads);
        }
        moves += on_report.swap_moves + on_report.reselection_moves;
        saved += on_report.local_search_saved;
      }
    }
  }
  EXPECT_GT(moves, 0u);  // the meshes do exercise the moves
  EXPECT_GE(saved, moves);
}

TEST(local_search, is_deterministic) {
  std::mt19937 rng(3);
  TetMesh mesh = kuhn_grid(4);
  random_perturbation(mesh, rng, 0.15);
  RecombineParameters p = permissive_parameters();
  p.local_search_radius = 2;
  p.local_search_seeds = LocalSearchSeeds::All;
  RecombineReport r1, r2;
  const MixedMesh a = recombine(mesh, p, r1);
  const MixedMesh b = recombine(mesh, p, r2);
  EXPECT_EQ(a.types, b.types);
  EXPECT_EQ(a.cell_vertices, b.cell_vertices);
  EXPECT_EQ(r1.swap_moves, r2.swap_moves);
  EXPECT_EQ(r1.reselection_moves, r2.reselection_moves);
}

TEST(local_search, parameters_are_in_the_table_with_their_ranges) {
  RecombineParameters p;
  EXPECT_TRUE(p.local_search);
  EXPECT_EQ(p.local_search_radius, 0);
  EXPECT_EQ(p.local_search_nodes, 2000);
  EXPECT_EQ(p.local_search_seeds, LocalSearchSeeds::Unmatched);
  set_parameter(p, "local_search", "false");
  set_parameter(p, "local_search_radius", "3");
  set_parameter(p, "local_search_nodes", "50000");
  set_parameter(p, "local_search_seeds", "all");
  EXPECT_FALSE(p.local_search);
  EXPECT_EQ(p.local_search_radius, 3);
  EXPECT_EQ(p.local_search_nodes, 50000);
  EXPECT_EQ(p.local_search_seeds, LocalSearchSeeds::All);
  EXPECT_THROW(set_parameter(p, "local_search_radius", "5"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_radius", "1.5"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_nodes", "0"), InputError);
  EXPECT_THROW(set_parameter(p, "local_search_seeds", "some"), InputError);
  RecombineParameters bad;
  bad.local_search_nodes = -1;
  EXPECT_THROW(validate_parameters(bad), InputError);
  std::set<std::string> names;
  for (const ParameterInfo& row : parameter_table()) names.insert(row.name);
  for (const char* name :
       {"local_search", "local_search_radius", "local_search_nodes", "local_search_seeds"}) {
    EXPECT_TRUE(names.count(name)) << name;
  }
}

}  // namespace
}  // namespace hexmerge::test

namespace hexmerge::test {
namespace {

// Issue 14, item 13: coordinates scaled by 1e-105 .. 1e-90 or 1e77 .. 1e100 gave the input back
// unmerged. Scaled by powers of two (exact), the cells must be exactly those made at scale 1.
TEST(recombine, results_do_not_depend_on_the_scale) {
  std::mt19937 rng(14);
  TetMesh mesh = kuhn_grid(3);
  random_perturbation(mesh, rng, 0.05);
  const Outcome reference = recombine_and_check(mesh, RecombineParameters{}, false);
  ASSERT_GT(hexes(reference), 0u);
  for (const int exponent : {-345, -320, -300, -40, 40, 260, 300, 330}) {
    TetMesh scaled = mesh;
    for (double& c : scaled.points) c = std::ldexp(c, exponent);
    RecombineReport report;
    const MixedMesh out = recombine(scaled, RecombineParameters{}, report);
    EXPECT_EQ(out.types, reference.mesh.types) << "2^" << exponent;
    EXPECT_EQ(out.cell_vertices, reference.mesh.cell_vertices) << "2^" << exponent;
    EXPECT_EQ(out.points, scaled.points);  // the input's points, untouched
    EXPECT_EQ(report.input_volume, std::ldexp(reference.report.input_volume, 3 * exponent));
    const CheckReport check = check_mesh(out, scaled);
    EXPECT_TRUE(check.valid()) << "2^" << exponent << " " << describe(check);
  }
}

// Issue 14, item 14: a quad face on a region interface is each region's boundary: it must be as
// flat as the boundary's rule (min_boundary_dihedral_angle), or the bilinear face moves volume
// from one material to the other while the total stays the same.
TEST(recombine, quads_on_a_region_interface_take_the_boundary_dihedral_angle) {
  const int n = 4;
  TetMesh mesh = kuhn_grid(n);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> bend(-0.06, 0.06);
  std::vector<char> on_interface(mesh.nb_vertices(), 0);
  for (int j = 0; j <= n; ++j) {
    for (int k = 0; k <= n; ++k) {
      const index_t v = grid_node(n, 2, j, k);
      on_interface[v] = 1;
      mesh.points[3 * v] += bend(rng);  // stays on the outer faces it lies on
    }
  }
  mesh.regions.resize(mesh.nb_tets());
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    double x = 0.0;
    for (int i = 0; i < 4; ++i) x += 0.25 * mesh.point(mesh.tet(t)[i])[0];
    mesh.regions[t] = x < 2.0 ? 1 : 2;
  }
  const RecombineParameters parameters;
  const Outcome run = recombine_and_check(mesh, parameters, false);
  EXPECT_GT(hexes(run), 0u);
  std::size_t interface_quads = 0;
  double movable = 0.0;  // the most volume the interface's bilinear quads can move
  for (index_t c = 0; c < run.mesh.nb_cells(); ++c) {
    const CellDescriptor& d = descriptor(run.mesh.types[c]);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      const index_t* v = run.mesh.cell(c);
      bool all = true;
      for (int i = 0; i < 4; ++i) all = all && on_interface[v[d.face[f][i]]];
      if (!all) continue;
      ++interface_quads;
      const auto p = [&](int i) { return &run.mesh.points[3 * std::size_t(v[d.face[f][i]])]; };
      EXPECT_GE(quad_dihedral_angle(p(0), p(1), p(2), p(3)),
                parameters.min_boundary_dihedral_angle - 1e-9)
          << "cell " << c << " face " << f;
      movable += 0.5 * std::abs(tet_volume(p(0), p(1), p(2), p(3)));
    }
  }
  // The checker sees the regions' volumes move by no more than those quads allow (each region
  // holds about half the grid's volume, n^3 / 2).
  EXPECT_TRUE(run.check.worst_region == 1 || run.check.worst_region == 2);
  EXPECT_LE(run.check.max_region_volume_difference * 0.45 * n * n * n, movable + 1e-12)
      << interface_quads << " interface quads";
}

// The checker compares every region's volume: moving a node of the interface into the other
// region changes both regions' volumes, not the total.
TEST(check_mesh, compares_every_regions_volume) {
  TetMesh input = kuhn_grid(2);
  input.regions.resize(input.nb_tets());
  for (index_t t = 0; t < input.nb_tets(); ++t) {
    double x = 0.0;
    for (int i = 0; i < 4; ++i) x += 0.25 * input.point(input.tet(t)[i])[0];
    input.regions[t] = x < 1.0 ? 3 : 4;
  }
  RecombineReport report;
  const MixedMesh out = recombine(input, RecombineParameters{}, report);
  const CheckReport same = check_mesh(out, input);
  EXPECT_LT(same.max_region_volume_difference, 1e-12);
  // The same cells, the regions of two tets of region 3 swapped to 4: the totals agree, the
  // regions do not.
  MixedMesh relabelled = out;
  int changed = 0;
  for (index_t c = 0; c < relabelled.nb_cells() && changed < 1; ++c) {
    if (relabelled.regions[c] == 3) {
      relabelled.regions[c] = 4;
      ++changed;
    }
  }
  const CheckReport moved = check_mesh(relabelled, input);
  EXPECT_NEAR(moved.relative_volume_difference, 0.0, 1e-12);
  EXPECT_GT(moved.max_region_volume_difference, 0.1);
}

}  // namespace
}  // namespace hexmerge::test
