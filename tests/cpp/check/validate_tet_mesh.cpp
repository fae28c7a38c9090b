#include "hexmerge/check/validate_tet_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "fixtures.h"
#include "hexmerge/core/error.h"

namespace hexmerge::test {
namespace {

/// Two tets sharing face (0,1,2); node 5 is spare.
TetMesh two_tets() {
  return make_tet_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}, {5, 5, 5}},
                       {{0, 1, 2, 3}, {0, 2, 1, 4}});
}

/// Runs validate_tet_mesh and returns the InputError it must throw.
InputError expect_input_error(const TetMesh& mesh) {
  try {
    validate_tet_mesh(mesh);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "validate_tet_mesh accepted a bad mesh";
  return InputError("none");
}

void expect_names(const InputError& e, Entity entity, index_t id, const std::string& word) {
  EXPECT_EQ(e.entity(), entity) << e.what();
  EXPECT_EQ(e.id(), id) << e.what();
  EXPECT_NE(std::string(e.what()).find(std::to_string(id)), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
}

TEST(validate_tet_mesh, accepts_valid_meshes) {
  EXPECT_NO_THROW(validate_tet_mesh(two_tets()));
  EXPECT_NO_THROW(validate_tet_mesh(kuhn_grid(3)));
  EXPECT_NO_THROW(validate_tet_mesh(five_tet_grid(3)));
}

TEST(validate_tet_mesh, empty_mesh) {
  TetMesh mesh = two_tets();
  mesh.tets.clear();
  const InputError e = expect_input_error(mesh);
  EXPECT_EQ(e.entity(), Entity::None);
  EXPECT_EQ(e.id(), NO_INDEX);
}

TEST(validate_tet_mesh, nan_and_infinite_coordinates_name_the_node) {
  TetMesh mesh = two_tets();
  mesh.points[3 * 2 + 1] = std::numeric_limits<double>::quiet_NaN();
  expect_names(expect_input_error(mesh), Entity::Node, 2, "NaN");
  mesh = two_tets();
  mesh.points[3 * 4 + 2] = -std::numeric_limits<double>::infinity();
  expect_names(expect_input_error(mesh), Entity::Node, 4, "infinite");
}

TEST(validate_tet_mesh, id_out_of_range_names_the_tet) {
  TetMesh mesh = two_tets();
  mesh.tets[4 + 3] = 6;
  expect_names(expect_input_error(mesh), Entity::Element, 1, "6");
  mesh.tets[4 + 3] = NO_VERTEX;
  expect_names(expect_input_error(mesh), Entity::Element, 1, "nodes");
}

TEST(validate_tet_mesh, repeated_vertex_names_the_tet) {
  TetMesh mesh = two_tets();
  mesh.tets[4 + 3] = mesh.tets[4 + 0];
  expect_names(expect_input_error(mesh), Entity::Element, 1, "twice");
}

TEST(validate_tet_mesh, inverted_tet) {
  TetMesh mesh = two_tets();
  std::swap(mesh.tets[4 + 1], mesh.tets[4 + 2]);
  expect_names(expect_input_error(mesh), Entity::Element, 1, "inverted");
}

TEST(validate_tet_mesh, zero_volume_tet) {
  TetMesh mesh = two_tets();
  mesh.points[3 * 4 + 2] = 0.0;  // node 4 into the plane of face (0,1,2)
  mesh.points[3 * 4 + 0] = 0.5;
  expect_names(expect_input_error(mesh), Entity::Element, 1, "zero volume");
}

TEST(validate_tet_mesh, duplicate_tets_name_both) {
  TetMesh mesh = two_tets();
  mesh.tets.insert(mesh.tets.end(), {1, 2, 0, 3});  // tet 0 again, rotated
  const InputError e = expect_input_error(mesh);
  EXPECT_EQ(e.entity(), Entity::Element);
  EXPECT_TRUE(e.id() == 0 || e.id() == 2) << e.id();
  const std::string what = e.what();
  EXPECT_NE(what.find('0'), std::string::npos) << what;
  EXPECT_NE(what.find('2'), std::string::npos) << what;
  EXPECT_NE(what.find("duplicate"), std::string::npos) << what;
}

TEST(validate_tet_mesh, a_tet_flat_to_round_off_is_named_at_any_scale) {
  // Node 4 on the plane of nodes 0, 1, 2 but for the last bits: the volume is positive noise.
  for (const double scale : {1e-60, 1e-3, 1.0, 1e5, 1e60}) {
    TetMesh mesh = two_tets();
    mesh.points[3 * 4 + 2] = -1e-15;
    for (double& c : mesh.points) c *= scale;
    expect_names(expect_input_error(mesh), Entity::Element, 1, "flat to round-off");
    // A thin but real tet passes, at the same scale.
    mesh.points[3 * 4 + 2] = -1e-6 * scale;
    EXPECT_NO_THROW(validate_tet_mesh(mesh)) << scale;
  }
}

TEST(validate_tet_mesh, array_sizes) {
  TetMesh mesh = two_tets();
  mesh.points.pop_back();
  expect_input_error(mesh);
  mesh = two_tets();
  mesh.tets.pop_back();
  expect_input_error(mesh);
  mesh = two_tets();
  mesh.regions = {1, 2, 3};
  expect_input_error(mesh);
}

}  // namespace
}  // namespace hexmerge::test
