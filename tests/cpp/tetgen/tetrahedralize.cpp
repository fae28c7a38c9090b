#include "hexmerge/tetgen/tetrahedralize.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include "hexmerge/core/error.h"

namespace hexmerge::test {
namespace {

using tetgen::Facet;
using tetgen::TetrahedralizeInput;
using tetgen::TetrahedralizeOutput;
using tetgen::TetrahedralizeParameters;
using tetgen::Tetrahedralizer;

bool have_tetgen() {
  try {
    Tetrahedralizer{TetrahedralizeParameters{}};
    return true;
  } catch (const InputError&) {
    return false;
  }
}

// The cube [0, 2]^3: its 8 corners (corner i at 2 (i & 1, (i >> 1) & 1, (i >> 2) & 1)) and its
// 6 faces as quads, outward, markers 1 (x = 0) to 6 (z = 2); then `inside` isolated points.
TetrahedralizeInput cube(const std::vector<Vec3>& inside) {
  TetrahedralizeInput in;
  for (int i = 0; i < 8; ++i)
    in.points.push_back(Vec3{2.0 * (i & 1), 2.0 * ((i >> 1) & 1), 2.0 * ((i >> 2) & 1)});
  const std::vector<std::vector<int>> quads{{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                            {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int f = 0; f < 6; ++f) in.facets.push_back(Facet{{quads[f]}, {}, f + 1});
  in.first_isolated = in.points.size();
  in.points.insert(in.points.end(), inside.begin(), inside.end());
  return in;
}

double signed_volume(const TetrahedralizeOutput& out, std::size_t t) {
  const auto p = [&](int k) { return Vec3::of(&out.points[3 * out.tets[4 * t + k]]); };
  return det3(p(1) - p(0), p(2) - p(0), p(3) - p(0)) / 6;
}

// The tets fill the cube: one orientation, no flat tet, volumes summing to 8; the input points
// come back first, unmoved; the boundary is the 6 faces, each of area 4 under its marker.
void expect_fills_cube(const TetrahedralizeInput& in, const TetrahedralizeOutput& out) {
  ASSERT_EQ(out.tets.size() % 4, 0u);
  ASSERT_GT(out.tets.size(), 0u);
  ASSERT_GE(out.points.size() / 3, in.points.size());
  for (std::size_t i = 0; i < in.points.size(); ++i)
    EXPECT_EQ((Vec3::of(&out.points[3 * i]) - in.points[i]).norm(), 0.0) << "point " << i;
  double total = 0;
  const double first = signed_volume(out, 0);
  for (std::size_t t = 0; t < out.tets.size() / 4; ++t) {
    const double v = signed_volume(out, t);
    EXPECT_GT(v * first, 1e-9) << "tet " << t;
    total += std::abs(v);
  }
  EXPECT_NEAR(total, 8.0, 1e-12);
  ASSERT_EQ(out.boundary.size(), out.boundary_marker.size());
  std::map<int, double> area;
  for (std::size_t i = 0; i < out.boundary.size(); ++i) {
    const auto p = [&](int k) { return Vec3::of(&out.points[3 * out.boundary[i][k]]); };
    area[out.boundary_marker[i]] += 0.5 * (p(1) - p(0)).cross(p(2) - p(0)).norm();
  }
  ASSERT_EQ(area.size(), 6u);
  for (const auto& [marker, a] : area) EXPECT_NEAR(a, 4.0, 1e-12) << "marker " << marker;
}

TEST(Tetrahedralizer, cube_with_inner_points) {
  if (!have_tetgen()) GTEST_SKIP() << "the tetgen program is not installed";
  const TetrahedralizeInput in = cube({{1, 1, 1}, {0.5, 0.7, 1.3}, {1.4, 0.6, 0.5}});
  const TetrahedralizeOutput out = Tetrahedralizer(TetrahedralizeParameters{}).run(in);
  expect_fills_cube(in, out);
  EXPECT_EQ(out.nb_restarts, 0u);
  EXPECT_EQ(out.nb_nudged, 0u);
  EXPECT_NE(out.command.find("-pYz "), std::string::npos);
  // No Steiner point: the isolated points are vertices of some tet.
  EXPECT_EQ(out.points.size() / 3, in.points.size());
  std::vector<char> used(in.points.size(), 0);
  for (index_t v : out.tets) used[v] = 1;
  for (std::size_t i = 0; i < used.size(); ++i) EXPECT_TRUE(used[i]) << "point " << i;
}

TEST(Tetrahedralizer, point_on_a_facet_is_in_its_triangles) {
  if (!have_tetgen()) GTEST_SKIP() << "the tetgen program is not installed";
  TetrahedralizeInput in = cube({{1, 1, 1}});
  // A point inside face z = 0 (marker 5), given with the facet as a polygon of one point.
  in.points.insert(in.points.begin() + 8, Vec3{0.8, 1.1, 0});
  ++in.first_isolated;
  in.facets[4].polygons.push_back({8});
  const TetrahedralizeOutput out = Tetrahedralizer(TetrahedralizeParameters{}).run(in);
  expect_fills_cube(in, out);
  int around = 0;
  for (std::size_t i = 0; i < out.boundary.size(); ++i)
    for (index_t v : out.boundary[i])
      if (v == 8) {
        EXPECT_EQ(out.boundary_marker[i], 5);
        ++around;
      }
  EXPECT_EQ(around, 4);  // the point splits face 5 into 4 triangles
}

TEST(Tetrahedralizer, keeps_its_files_in_the_work_directory) {
  if (!have_tetgen()) GTEST_SKIP() << "the tetgen program is not installed";
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / "hexmerge-tetrahedralize-test";
  std::filesystem::remove_all(folder);
  TetrahedralizeParameters parameters;
  parameters.work_directory = folder.string();
  Tetrahedralizer(parameters).run(cube({{1, 1, 1}}));
  EXPECT_TRUE(std::filesystem::exists(folder / "shape.poly"));
  EXPECT_TRUE(std::filesystem::exists(folder / "shape.1.ele"));
  std::filesystem::remove_all(folder);
}

// No facets: the Delaunay tetrahedralisation of the points. The cube's corners and three inner
// points fill the cube (its convex hull) with every point kept in order and no point added; the
// boundary is the hull, 12 triangles of total area 24, marker 0. As the fixtures use it.
TEST(Tetrahedralizer, no_facets_is_the_delaunay_tetrahedralisation_of_the_points) {
  if (!have_tetgen()) GTEST_SKIP() << "the tetgen program is not installed";
  TetrahedralizeInput in = cube({{1, 1, 1}, {0.5, 0.7, 1.3}, {1.4, 0.6, 0.5}});
  in.facets.clear();
  in.first_isolated = 0;
  const TetrahedralizeOutput out = Tetrahedralizer(TetrahedralizeParameters{}).run(in);
  ASSERT_EQ(out.points.size(), 3 * in.points.size()) << "TetGen added points";
  for (std::size_t i = 0; i < in.points.size(); ++i)
    EXPECT_EQ((Vec3::of(&out.points[3 * i]) - in.points[i]).norm(), 0.0) << "point " << i;
  std::vector<int> used(in.points.size(), 0);
  double total = 0;
  const double first = signed_volume(out, 0);
  for (std::size_t t = 0; t < out.tets.size() / 4; ++t) {
    const double v = signed_volume(out, t);
    EXPECT_GT(v * first, 1e-9) << "tet " << t;
    total += std::abs(v);
    for (int k = 0; k < 4; ++k) used.at(out.tets[4 * t + k]) = 1;
  }
  EXPECT_NEAR(total, 8.0, 1e-12);
  EXPECT_EQ(used, std::vector<int>(in.points.size(), 1));
  double area = 0;
  for (std::size_t i = 0; i < out.boundary.size(); ++i) {
    const auto p = [&](int k) { return Vec3::of(&out.points[3 * out.boundary[i][k]]); };
    area += 0.5 * (p(1) - p(0)).cross(p(2) - p(0)).norm();
    EXPECT_EQ(out.boundary_marker[i], 0);
  }
  EXPECT_EQ(out.boundary.size(), 12u);
  EXPECT_NEAR(area, 24.0, 1e-12);
  EXPECT_NE(out.command.find(" -z "), std::string::npos) << out.command;
}

TEST(Tetrahedralizer, missing_program_is_an_input_error) {
  TetrahedralizeParameters parameters;
  parameters.program = "no-such-tetgen-program";
  try {
    Tetrahedralizer{parameters};
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("\"no-such-tetgen-program\" is not found"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(e.entity(), Entity::Parameter);
  }
}

}  // namespace
}  // namespace hexmerge::test
