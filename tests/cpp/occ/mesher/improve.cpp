#include "hexmerge/occ/mesher/improve.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fixtures.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge::test {
namespace {

// The boundary triangles of a tet mesh (face f of a tet is opposite its vertex f).
std::vector<std::array<index_t, 3>> boundary_of(const TetMesh& mesh) {
  const TetTopology topology(mesh);
  std::vector<std::array<index_t, 3>> out;
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (topology.on_boundary(t, f))
        out.push_back(
            {mesh.tet(t)[(f + 1) % 4], mesh.tet(t)[(f + 2) % 4], mesh.tet(t)[(f + 3) % 4]});
  return out;
}

mesher::ImproveReport improve(TetMesh& mesh) {
  const auto boundary = boundary_of(mesh);
  mesher::ImproveParameters parameters;
  parameters.spacing = {1, 1, 1};
  mesher::ImproveReport report;
  mesher::improve_tets(mesh, mesh.points, boundary, std::vector<std::int32_t>(boundary.size(), -1),
                       parameters, report);
  return report;
}

// Points on the lattice (spacing 1): every tet lies in one cell, so nothing changes.
TEST(improve_tets, lattice_tets_stay) {
  TetMesh mesh = tetgen_lattice(3, 0.0, 1);
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  const TetMesh before = mesh;
  const mesher::ImproveReport report = improve(mesh);
  EXPECT_EQ(mesh.tets, before.tets);
  EXPECT_EQ(mesh.points, before.points);
  EXPECT_EQ(report.face_flips + report.edge_flips + report.node_moves, 0u);
}

// Jittered points: flips and moves take out poor tets, never lower the worst, keep the volume,
// the boundary nodes and a valid mesh of positive tets.
TEST(improve_tets, takes_out_poor_tets_and_keeps_the_boundary) {
  TetMesh mesh = tetgen_lattice(4, 0.2, 11);
  if (mesh.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
  const TetMesh before = mesh;
  const double worst = min_quality(mesh);
  const mesher::ImproveReport report = improve(mesh);
  validate_tet_mesh(mesh);
  EXPECT_DOUBLE_EQ(report.min_quality_before, worst);
  // The worst tet can be a flat one on the (jittered, unchangeable) boundary: it stays; the
  // poor tets inside go.
  EXPECT_GE(min_quality(mesh), worst);
  EXPECT_LT(count_below(mesh, 0.2), count_below(before, 0.2));
  EXPECT_GT(report.face_flips + report.edge_flips, 0u);
  EXPECT_GT(report.node_moves, 0u);
  EXPECT_NEAR(total_volume(mesh), total_volume(before), 1e-9 * total_volume(before));
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    EXPECT_GT(scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)), 0) << "tet " << t;
  std::vector<char> on_boundary(before.points.size() / 3, 0);
  for (const auto& f : boundary_of(before))
    for (index_t v : f) on_boundary[v] = 1;
  for (std::size_t v = 0; v < on_boundary.size(); ++v)
    if (on_boundary[v]) {
      for (int a = 0; a < 3; ++a) EXPECT_EQ(mesh.points[3 * v + a], before.points[3 * v + a]);
    }
}

// A 3^3 lattice with the centres of its middle cell and of a corner cell: the centres are the
// apexes of the pyramids over their cells' faces, six each. A point inside the middle cell near
// its bottom face takes that face's pyramid apart: five there.
TEST(closing_pyramids, finds_the_pyramids_over_the_faces_of_a_centres_cell) {
  std::vector<test::Point> points;
  for (int k = 0; k <= 3; ++k)
    for (int j = 0; j <= 3; ++j)
      for (int i = 0; i <= 3; ++i) points.push_back({double(i), double(j), double(k)});
  points.push_back({1.5, 1.5, 1.5});
  points.push_back({0.5, 0.5, 0.5});
  for (const bool with_point : {false, true}) {
    std::vector<test::Point> all = points;
    if (with_point) all.push_back({1.5, 1.5, 1.2});
    const TetMesh mesh = tetgen_mesh(all);
    if (mesh.nb_tets() == 0) GTEST_SKIP() << "the tetgen program is not installed";
    std::vector<char> apex(mesh.nb_vertices(), 0);
    apex[64] = apex[65] = 1;
    std::vector<std::array<double, 3>> cell_of(mesh.nb_vertices());  // spacing 1
    for (index_t v = 0; v < mesh.nb_vertices(); ++v)
      for (int a = 0; a < 3; ++a) cell_of[v][a] = mesh.point(v)[a];
    const auto pyramids = mesher::closing_pyramids(mesh, cell_of, apex);
    EXPECT_EQ(pyramids.size(), with_point ? 11u : 12u);
    for (const auto& pyramid : pyramids) {
      // A face of the apex's cell (one axis at a whole coordinate 0.5 off the apex), positive,
      // and two tets of the mesh.
      const Vec3 apex_at = Vec3::of(mesh.point(pyramid[4]));
      int apex_tets = 0;
      for (index_t t = 0; t < mesh.nb_tets(); ++t) {
        const index_t* v = mesh.tet(t);
        int on = 0;
        for (int k = 0; k < 4; ++k)
          on += std::find(pyramid.begin(), pyramid.end(), v[k]) != pyramid.end();
        apex_tets += on == 4 && std::find(v, v + 4, pyramid[4]) != v + 4;
      }
      EXPECT_EQ(apex_tets, 2);
      for (int k = 0; k < 4; ++k) {
        const Vec3 corner = Vec3::of(mesh.point(pyramid[k]));
        EXPECT_NEAR(std::abs(corner.x - apex_at.x), 0.5, 1e-12);
        EXPECT_NEAR(std::abs(corner.y - apex_at.y), 0.5, 1e-12);
        EXPECT_NEAR(std::abs(corner.z - apex_at.z), 0.5, 1e-12);
      }
      // Height half the side: Verdict's sqrt(2/3).
      EXPECT_NEAR(scaled_jacobian(CellType::Pyramid, mesh.points.data(), pyramid.data()),
                  std::sqrt(2.0 / 3), 1e-9);
      EXPECT_NEAR(cell_volume(CellType::Pyramid, mesh.points.data(), pyramid.data()), 1.0 / 6,
                  1e-12);
    }
  }
}

}  // namespace
}  // namespace hexmerge::test
