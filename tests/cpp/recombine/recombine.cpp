// Engine tests: every output goes through the independent checker (check_mesh).
#include "hexmerge/recombine/recombine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>

#include "fixtures.h"
#include "hexmerge/check/check_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"

namespace hexmerge::test {
namespace {

/// Thresholds loose enough for the skewed hexes of random affine maps and perturbations.
RecombineParameters permissive() {
  RecombineParameters p;
  p.min_scaled_jacobian = 0.05;
  p.min_dihedral_angle = 120.0;
  p.min_boundary_dihedral_angle = 120.0;
  p.max_face_angle = 175.0;
  return p;
}

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
      const auto p = [&](int i) { return &mesh.points[3 * std::size_t(mesh.cell(c)[d.face[f][i]])]; };
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
  for (int t = 0; t < NB_CELL_TYPES; ++t) EXPECT_EQ(run.report.output_counts[t], run.check.counts[t]);
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
      const Outcome run = recombine_and_check(mesh, permissive());
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
      SCOPED_TRACE("cube triangulation " + std::to_string(i) + ", perturbation " + std::to_string(k));
      TetMesh mesh = polytope_mesh(unit_cube(), cases[i].tets);
      if (k == 2) random_affine_map(mesh, rng, 0.2);
      random_perturbation(mesh, rng, 0.03);
      const Outcome run = recombine_and_check(mesh, permissive(), /*flat=*/false);
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

}  // namespace
}  // namespace hexmerge::test
