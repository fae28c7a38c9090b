// solid_regions: the solid of each tet from the triangles kept on the shape's faces.
#include "hexmerge/occ/mesher/solid_regions.h"

#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <TopoDS_Compound.hxx>
#include <array>
#include <cmath>
#include <vector>

#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// Two unit cubes side by side along x ([0, 1] and [1, 2]), as a compound of two boxes that
// touch over a whole face: loaded (glued) as the mesher loads shapes.
mesher::Shape two_cubes() {
  TopoDS_Compound c;
  BRep_Builder builder;
  builder.MakeCompound(c);
  builder.Add(c, occ_box(0, 0, 0, 1, 1, 1));
  builder.Add(c, occ_box(1, 0, 0, 2, 1, 1));
  return load(c);
}

struct CubeMesh {
  std::vector<Vec3> points;  // the 3 x 2 x 2 grid, x fastest
  std::vector<index_t> tets;
  std::vector<std::array<index_t, 3>> triangles;  // the tets' faces on a plane of a cube
  TetMesh mesh() const {
    TetMesh m;
    for (const Vec3& p : points) m.points.insert(m.points.end(), {p.x, p.y, p.z});
    m.tets = tets;
    return m;
  }
  std::vector<int> markers;  // their faces in shape.faces, + 1
  std::vector<bool> shared;  // on the plane x = 1
};

// Each cube in 6 tets around its diagonal (Kuhn), the faces on the cubes' planes marked with
// the face of the shape holding their centroid.
CubeMesh cube_mesh(const mesher::Shape& shape) {
  CubeMesh m;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) m.points.push_back(Vec3{double(i), double(j), double(k)});
  auto node = [](int i, int j, int k) { return static_cast<index_t>(i + 3 * (j + 2 * k)); };
  const int paths[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int cube = 0; cube < 2; ++cube)
    for (const auto& path : paths) {
      int at[3] = {cube, 0, 0};
      std::array<index_t, 4> t{node(at[0], at[1], at[2]), 0, 0, 0};
      for (int s = 0; s < 3; ++s) {
        ++at[path[s]];
        t[s + 1] = node(at[0], at[1], at[2]);
      }
      const Vec3 &p0 = m.points[t[0]], &p1 = m.points[t[1]], &p2 = m.points[t[2]],
                 &p3 = m.points[t[3]];
      if (det3(p1 - p0, p2 - p0, p3 - p0) < 0) std::swap(t[1], t[2]);
      m.tets.insert(m.tets.end(), t.begin(), t.end());
    }
  std::vector<Bnd_Box> boxes(shape.faces.Extent());
  for (int f = 0; f < shape.faces.Extent(); ++f) {
    BRepBndLib::Add(shape.faces(f + 1), boxes[f]);
    boxes[f].Enlarge(1e-7);
  }
  for (std::size_t t = 0; t < m.tets.size() / 4; ++t)
    for (int f = 0; f < 4; ++f) {
      const index_t a = m.tets[4 * t + (f + 1) % 4], b = m.tets[4 * t + (f + 2) % 4],
                    c = m.tets[4 * t + (f + 3) % 4];
      const Vec3 centre = (m.points[a] + m.points[b] + m.points[c]) * (1.0 / 3);
      for (int face = 0; face < shape.faces.Extent(); ++face) {
        if (boxes[face].IsOut(gp_Pnt(centre.x, centre.y, centre.z)) ||
            distance_to_face(shape, face, centre) > 1e-9)
          continue;
        // Each triangle once (the shared plane's triangles are faces of two tets).
        bool seen = false;
        for (const auto& s : m.triangles)
          seen = seen || (std::is_permutation(s.begin(), s.end(), std::array{a, b, c}.begin()));
        if (!seen) {
          m.triangles.push_back({a, b, c});
          m.markers.push_back(face + 1);
          m.shared.push_back(std::abs(centre.x - 1) < 1e-12);
        }
        break;
      }
    }
  return m;
}

TEST(solid_regions, two_touching_cubes_one_region_each) {
  const mesher::Shape shape = two_cubes();
  ASSERT_EQ(shape.solids.Extent(), 2);
  const CubeMesh m = cube_mesh(shape);
  // 6 faces of 2 triangles per cube, the shared square once: 22.
  ASSERT_EQ(m.triangles.size(), 22u);
  const auto regions = mesher::solid_regions(shape, m.mesh(), m.triangles, m.markers);
  ASSERT_TRUE(regions.has_value());
  ASSERT_EQ(regions->size(), 12u);
  for (std::size_t t = 0; t < 12; ++t) {
    double x = 0;
    for (int k = 0; k < 4; ++k) x += 0.25 * m.points[m.tets[4 * t + k]].x;
    EXPECT_EQ((*regions)[t], x < 1 ? 0 : 1) << "tet " << t;
  }
}

TEST(solid_regions, nothing_when_the_triangles_do_not_separate_the_solids) {
  const mesher::Shape shape = two_cubes();
  CubeMesh m = cube_mesh(shape);
  // Without the shared square's triangles the two cubes' tets are one component touching faces
  // of both solids.
  std::vector<std::array<index_t, 3>> triangles;
  std::vector<int> markers;
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    if (!m.shared[i]) triangles.push_back(m.triangles[i]), markers.push_back(m.markers[i]);
  ASSERT_EQ(triangles.size(), 20u);
  EXPECT_FALSE(mesher::solid_regions(shape, m.mesh(), triangles, markers).has_value());
  // A marker naming no face of the shape.
  m.markers[0] = shape.faces.Extent() + 5;
  EXPECT_FALSE(mesher::solid_regions(shape, m.mesh(), m.triangles, m.markers).has_value());
}

// The cubes' tets as two components (the square at x = 1 among the triangles): the one `inside`
// says is out goes whole, whatever its other tets' centroids say; the regions follow the tets.
// Without the square, one component: all stay.
TEST(remove_outside_components, a_component_outside_goes_whole) {
  const mesher::Shape shape = two_cubes();
  const CubeMesh m = cube_mesh(shape);
  TetMesh mesh = m.mesh();
  for (std::size_t t = 0; t < 12; ++t) mesh.regions.push_back(static_cast<std::int32_t>(t));
  std::size_t asked = 0;
  const auto inside = [&](const Vec3& q) {
    ++asked;
    return q.x < 1;
  };
  EXPECT_EQ(mesher::remove_outside_components(mesh, m.triangles, inside), 6u);
  EXPECT_EQ(asked, 2u);  // once per component
  ASSERT_EQ(mesh.nb_tets(), 6u);
  ASSERT_EQ(mesh.regions.size(), 6u);
  for (index_t t = 0; t < 6; ++t) {
    EXPECT_EQ(mesh.regions[t], static_cast<std::int32_t>(t));  // the first cube's, in order
    for (int k = 0; k < 4; ++k) EXPECT_LE(m.points[mesh.tet(t)[k]].x, 1.0);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(mesh.tet(t)[k], m.tets[4 * t + k]);
  }
  std::vector<std::array<index_t, 3>> outer;
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    if (!m.shared[i]) outer.push_back(m.triangles[i]);
  TetMesh whole = m.mesh();
  EXPECT_EQ(
      mesher::remove_outside_components(whole, outer, [](const Vec3& q) { return q.x < 1.5; }), 0u);
  EXPECT_EQ(whole.nb_tets(), 12u);
}

}  // namespace
}  // namespace hexmerge::test
