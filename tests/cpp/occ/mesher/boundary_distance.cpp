#include "hexmerge/occ/mesher/boundary_distance.h"

#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <TopoDS.hxx>
#include <cmath>
#include <gp_Pln.hxx>

#include "fixtures.h"
#include "hexmerge/core/error.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// The box [0, 10]^3 as 6 tets on its corners (corner i at 10 (i & 1, (i >> 1) & 1, (i >> 2) & 1))
// and the shape; per corner, the index of the box face normal to x through it.
struct BoxMesh {
  mesher::Shape shape = load(occ_box(0, 0, 0, 10, 10, 10));
  TetMesh mesh;
  std::vector<int> x_face;
  BoxMesh() {
    std::vector<Point> points;
    for (int i = 0; i < 8; ++i)
      points.push_back({10.0 * (i & 1), 10.0 * ((i >> 1) & 1), 10.0 * ((i >> 2) & 1)});
    mesh = make_tet_mesh(points, {});
    for (const auto& t : std::vector<std::array<index_t, 4>>{
             {0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}})
      add_tet(mesh, t[0], t[1], t[2], t[3]);
    for (int i = 0; i < 8; ++i)
      for (int f = 0; f < shape.faces.Extent(); ++f) {
        const BRepAdaptor_Surface s(TopoDS::Face(shape.faces(f + 1)));
        const gp_Pln plane = s.Plane();
        if (std::abs(plane.Axis().Direction().X()) > 0.5 &&
            std::abs(plane.Location().X() - 10.0 * (i & 1)) < 1e-9)
          x_face.push_back(f);
      }
  }
};

// Points added on the boundary take a boundary triangle's face (marker - 1); added points
// inside stay on none; the given points keep theirs.
TEST(point_faces, points_added_on_the_boundary_take_a_triangles_face) {
  const std::vector<std::array<index_t, 3>> boundary = {{0, 1, 4}, {1, 2, 4}, {2, 3, 5}};
  const std::vector<int> marker = {3, 3, 8};
  const std::vector<int> faces = mesher::point_faces({2, 2, 7, -1}, 7, boundary, marker);
  EXPECT_EQ(faces, (std::vector<int>{2, 2, 7, -1, 2, 7, -1}));
  // Given points beyond the mesh's: kept as given.
  EXPECT_EQ(mesher::point_faces({1, 1, 1}, 2, {}, {}), (std::vector<int>{1, 1, 1}));
}

// Per vertex: its own face first, then its triangles' faces once each, in their order; faces
// under 0 and vertices past the count left out.
TEST(vertex_faces, own_face_then_the_triangles_faces_once_each) {
  const std::vector<std::array<index_t, 3>> boundary = {{0, 1, 2}, {0, 2, 3}, {0, 3, 9}, {1, 2, 3}};
  const std::vector<std::int32_t> face = {5, 4, 5, -1};
  const auto faces = mesher::vertex_faces(4, {4, -1}, boundary, face);
  EXPECT_EQ(faces, (std::vector<std::vector<int>>{{4, 5}, {5}, {5, 4}, {4, 5}}));
}

// A box's added point on its boundary, on no face before: measured (before: refused).
TEST(point_faces, an_added_boundary_point_is_measured) {
  BoxMesh box;
  std::vector<int> given(box.x_face.begin(), box.x_face.begin() + 7);  // corner 7 "added"
  // The face x = 10's two triangles (corners 1, 3, 5, 7), its marker its index + 1.
  const std::vector<std::array<index_t, 3>> boundary = {{1, 3, 7}, {1, 7, 5}};
  const std::vector<int> marker(2, box.x_face[7] + 1);
  const std::vector<int> faces = mesher::point_faces(given, 8, boundary, marker);
  EXPECT_EQ(faces[7], box.x_face[7]);
  EXPECT_LT(mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9), 1e-12);
  EXPECT_THROW(mesher::max_boundary_distance(box.shape, box.mesh, given, 1e-9), InputError);
}

TEST(max_boundary_distance, nodes_on_their_faces_are_at_zero) {
  BoxMesh box;
  ASSERT_EQ(box.x_face.size(), 8u);
  EXPECT_LT(mesher::max_boundary_distance(box.shape, box.mesh, box.x_face, 1e-9), 1e-12);
}

TEST(max_boundary_distance, moved_node_is_at_its_offset) {
  for (const double offset : {0.3, -0.7}) {
    BoxMesh moved;
    moved.mesh.points[3 * 7] += offset;  // corner 7, on face x = 10, moved along x
    EXPECT_NEAR(mesher::max_boundary_distance(moved.shape, moved.mesh, moved.x_face, 1e-9),
                std::abs(offset), 1e-9);
  }
}

// A node given the wrong face (corner 7 of the box, on x = 10, given x = 0's) is measured
// against the faces of the boundary triangles at it too: on one of them, it is on the CAD.
TEST(max_boundary_distance, a_node_on_a_face_of_its_triangles_is_on_the_cad) {
  BoxMesh box;
  std::vector<int> faces = box.x_face;
  faces[7] = box.x_face[0];
  EXPECT_NEAR(mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9), 10.0, 1e-9);
  std::vector<std::vector<int>> others(8);
  others[7] = {box.x_face[0], box.x_face[7]};
  EXPECT_LT(mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9, others), 1e-12);
  // Moved off every face it may lie on: measured as before.
  box.mesh.points[3 * 7] += 0.3;
  EXPECT_NEAR(mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9, others), 0.3, 1e-9);
}

TEST(max_boundary_distance, boundary_node_on_no_face_is_named) {
  BoxMesh box;
  std::vector<int> faces = box.x_face;
  faces[5] = -1;
  try {
    mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Node);
    EXPECT_EQ(e.id(), 5u);
  }
  faces.resize(4);  // nodes past the list are on no face either
  EXPECT_THROW(mesher::max_boundary_distance(box.shape, box.mesh, faces, 1e-9), InputError);
}

}  // namespace
}  // namespace hexmerge::test
