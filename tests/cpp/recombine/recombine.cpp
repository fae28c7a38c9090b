// Engine tests: every output goes through the independent checker (check_mesh).
#include "hexmerge/recombine/recombine.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
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
#include "recombine/recombine_checks.h"

namespace hexmerge::test {
namespace {

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

// A cylinder of 24-gon rings (the Delaunay tets of its points): its side turns by 15 degrees
// from one strip of triangles to the next, its ends are flat. With pyramids off curved parts of
// the boundary no output pyramid has a face on the side, though pyramids anywhere put some
// there, and with pyramids off the curved parts' nodes none has a vertex there either; on a box
// (a Kuhn grid: flat faces and sharp edges) the output is the one pyramids anywhere give.
TEST(recombine, pyramids_off_the_curved_boundary_keep_off_the_cylinders_side) {
  const double radius = 6.0, height = 8.0;
  const int sides = 24;
  std::vector<Point> points;
  for (int k = 0; k <= 8; ++k)
    for (int i = 0; i < sides; ++i) {
      const double a = 2 * M_PI * i / sides;
      points.push_back({radius * std::cos(a), radius * std::sin(a), height * k / 8});
    }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n = 0; points.size() < 1200 && n < 20000; ++n) {
    const Point p = {radius * u(rng), radius * u(rng), 0.5 * height * (1 + u(rng))};
    if (std::hypot(p[0], p[1]) > radius - 0.6 || p[2] < 0.5 || p[2] > height - 0.5) continue;
    const bool spaced = std::none_of(points.begin(), points.end(), [&](const Point& q) {
      return std::hypot(std::hypot(p[0] - q[0], p[1] - q[1]), p[2] - q[2]) < 0.9;
    });
    if (spaced) points.push_back(p);
  }
  const TetMesh mesh = tetgen_mesh(points);
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  // The input's boundary triangles.
  std::map<std::array<index_t, 3>, int> faces;
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f) {
      std::array<index_t, 3> tri{};
      for (int i = 0, n = 0; i < 4; ++i)
        if (i != f) tri[n++] = mesh.tet(t)[i];
      std::sort(tri.begin(), tri.end());
      ++faces[tri];
    }
  // Pyramid faces (sides, or a half of the base on either diagonal) that are boundary
  // triangles on the side.
  const auto side_faces = [&](const MixedMesh& out) {
    int n = 0;
    for (index_t c = 0; c < out.nb_cells(); ++c) {
      if (out.types[c] != CellType::Pyramid) continue;
      const index_t* v = out.cell(c);
      const std::array<index_t, 3> tris[] = {
          {v[0], v[1], v[4]}, {v[1], v[2], v[4]}, {v[2], v[3], v[4]}, {v[3], v[0], v[4]},
          {v[0], v[1], v[2]}, {v[0], v[2], v[3]}, {v[0], v[1], v[3]}, {v[1], v[2], v[3]}};
      for (std::array<index_t, 3> tri : tris) {
        std::sort(tri.begin(), tri.end());
        const auto it = faces.find(tri);
        if (it == faces.end() || it->second != 1) continue;
        bool end = true;
        for (index_t w : tri) {
          const double z = out.points[3 * static_cast<std::size_t>(w) + 2];
          end = end && (z == 0.0 || z == height);
        }
        n += !end;
      }
    }
    return n;
  };
  // Pyramids with a vertex on the side: a node of a boundary triangle that is not on an end
  // (a node on an end's rim is on both).
  std::set<index_t> side_nodes;
  for (const auto& [tri, count] : faces) {
    if (count != 1) continue;
    bool end = true;
    for (index_t w : tri) {
      const double z = mesh.point(w)[2];
      end = end && (z == 0.0 || z == height);
    }
    if (!end) side_nodes.insert(tri.begin(), tri.end());
  }
  const auto side_vertices = [&](const MixedMesh& out) {
    int n = 0;
    for (index_t c = 0; c < out.nb_cells(); ++c) {
      if (out.types[c] != CellType::Pyramid) continue;
      const index_t* v = out.cell(c);
      n += std::any_of(v, v + 5, [&](index_t w) { return side_nodes.count(w) > 0; });
    }
    return n;
  };
  RecombineParameters anywhere, off_curved, off_curved_nodes;
  off_curved.pyramid_placement = PyramidPlacement::NoCurvedBoundaryFace;
  off_curved_nodes.pyramid_placement = PyramidPlacement::NoCurvedBoundaryNode;
  RecombineReport report;
  const MixedMesh before = recombine(mesh, anywhere, report);
  const MixedMesh after = recombine(mesh, off_curved, report);
  const MixedMesh after_nodes = recombine(mesh, off_curved_nodes, report);
  for (const MixedMesh* out : {&before, &after, &after_nodes}) {
    const CheckReport check = check_mesh(*out, mesh);
    EXPECT_TRUE(check.valid()) << (check.problems.empty() ? "" : check.problems[0]);
    EXPECT_EQ(check.nonconforming_quads, 0u);
  }
  EXPECT_GT(side_faces(before), 0);
  EXPECT_EQ(side_faces(after), 0);
  EXPECT_GT(side_vertices(after), 0);  // a face off the side, a vertex on it
  EXPECT_EQ(side_vertices(after_nodes), 0);
  EXPECT_GT(after_nodes.nb_cells(), 0u);

  // Flat faces keep their pyramids: a box's output is the same with either placement.
  const TetMesh box = kuhn_grid(4);
  RecombineReport box_report;
  const MixedMesh box_anywhere = recombine(box, anywhere, box_report);
  const MixedMesh box_off = recombine(box, off_curved, box_report);
  const MixedMesh box_off_nodes = recombine(box, off_curved_nodes, box_report);
  EXPECT_EQ(box_anywhere.cell_vertices, box_off.cell_vertices);
  EXPECT_EQ(box_anywhere.cell_vertices, box_off_nodes.cell_vertices);
}

}  // namespace
}  // namespace hexmerge::test
