// glue_solids: touching solids share their common faces; overlapping ones are refused by name.
#include "hexmerge/occ/mesher/glue_solids.h"

#include <gtest/gtest.h>

#include <BRepGProp.hxx>
#include <BRep_Builder.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Compound.hxx>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hexmerge/core/error.h"
#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

TopoDS_Shape compound(const std::vector<TopoDS_Shape>& solids) {
  TopoDS_Compound c;
  BRep_Builder builder;
  builder.MakeCompound(c);
  for (const TopoDS_Shape& s : solids) builder.Add(c, s);
  return c;
}

double volume(const TopoDS_Shape& s) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(s, props);
  return props.Mass();
}

TEST(glue_solids, touching_boxes_share_the_common_face_and_keep_their_order_and_volumes) {
  // A 10 x 10 x 10 box and a 20 x 4 x 4 bar touching its +x face over a 4 x 4 patch only.
  const TopoDS_Shape box = occ_box(0, 0, 0, 10, 10, 10);
  const TopoDS_Shape bar = occ_box(10, 3, 3, 30, 7, 7);
  mesher::GlueSolidsReport report;
  const TopoDS_Shape glued = mesher::glue_solids(compound({box, bar}), 1e-7, report);
  EXPECT_TRUE(report.glued);
  EXPECT_EQ(report.nb_solids, 2u);
  EXPECT_EQ(report.nb_shared_faces, 1u);
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(glued, TopAbs_SOLID, solids);
  ASSERT_EQ(solids.Extent(), 2);
  EXPECT_NEAR(volume(solids(1)), 1000, 1e-6);
  EXPECT_NEAR(volume(solids(2)), 320, 1e-6);
  // The shared face bounds both solids and is the 4 x 4 patch.
  TopTools_IndexedDataMapOfShapeListOfShape face_solids;
  TopExp::MapShapesAndAncestors(glued, TopAbs_FACE, TopAbs_SOLID, face_solids);
  int shared = 0;
  for (int f = 1; f <= face_solids.Extent(); ++f) {
    TopTools_IndexedMapOfShape around;
    for (const TopoDS_Shape& s : face_solids(f)) around.Add(s);
    if (around.Extent() < 2) continue;
    ++shared;
    GProp_GProps props;
    BRepGProp::SurfaceProperties(face_solids.FindKey(f), props);
    EXPECT_NEAR(props.Mass(), 16, 1e-9);
  }
  EXPECT_EQ(shared, 1);
  // The mesher loads the glued shape with the shared face counted for both solids.
  const mesher::Shape loaded = load(compound({box, bar}));
  int twice = 0;
  for (int count : loaded.face_solid_count) twice += count == 2;
  EXPECT_EQ(twice, 1);
}

TEST(glue_solids, one_solid_is_returned_as_it_is) {
  const TopoDS_Shape box = occ_box(0, 0, 0, 1, 2, 3);
  mesher::GlueSolidsReport report;
  EXPECT_TRUE(mesher::glue_solids(box, 1e-7, report).IsSame(box));
  EXPECT_FALSE(report.glued);
  EXPECT_EQ(report.nb_solids, 1u);
}

TEST(glue_solids, overlapping_solids_are_refused_by_name) {
  const TopoDS_Shape a = occ_box(0, 0, 0, 10, 10, 10);
  const TopoDS_Shape far = occ_box(20, 0, 0, 30, 10, 10);
  const TopoDS_Shape b = occ_box(5, 5, 5, 15, 15, 15);  // overlaps a in a 5 x 5 x 5 cube
  mesher::GlueSolidsReport report;
  try {
    mesher::glue_solids(compound({a, far, b}), 1e-7, report);
    FAIL() << "overlapping solids were glued";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("Solid1 and Solid3"), std::string::npos) << what;
    EXPECT_NE(what.find("overlap"), std::string::npos) << what;
    EXPECT_NE(what.find("125"), std::string::npos) << what;
  }
}

// The faces and edges as given (FreeCAD's FaceN, EdgeN of the compound) through the gluing: the
// box's +x face becomes the shared patch and the rest (same area in all), the bar's -x face the
// shared patch; the other faces one each, of their own area; every glued face is some given
// face's image.
TEST(glue_solids, reports_what_each_face_and_edge_given_became) {
  const TopoDS_Shape box = occ_box(0, 0, 0, 10, 10, 10);
  const TopoDS_Shape bar = occ_box(10, 3, 3, 30, 7, 7);
  const TopoDS_Shape given = compound({box, bar});
  mesher::GlueSolidsReport report;
  const TopoDS_Shape glued = mesher::glue_solids(given, 1e-7, report);
  TopTools_IndexedMapOfShape before, after, edges_before;
  TopExp::MapShapes(given, TopAbs_FACE, before);
  TopExp::MapShapes(glued, TopAbs_FACE, after);
  TopExp::MapShapes(given, TopAbs_EDGE, edges_before);
  ASSERT_EQ(report.face_images.size(), static_cast<std::size_t>(before.Extent()));
  ASSERT_EQ(report.edge_images.size(), static_cast<std::size_t>(edges_before.Extent()));
  const auto area = [](const TopoDS_Shape& face) {
    GProp_GProps props;
    BRepGProp::SurfaceProperties(face, props);
    return props.Mass();
  };
  std::vector<char> imaged(static_cast<std::size_t>(after.Extent()), 0);
  std::vector<int> named_by(static_cast<std::size_t>(after.Extent()), 0);
  int split = 0;
  for (int f = 1; f <= before.Extent(); ++f) {
    const std::vector<int>& images = report.face_images[static_cast<std::size_t>(f - 1)];
    ASSERT_FALSE(images.empty()) << "Face" << f;
    double total = 0;
    for (const int i : images) {
      total += area(after(i + 1));
      imaged[static_cast<std::size_t>(i)] = 1;
      ++named_by[static_cast<std::size_t>(i)];
    }
    EXPECT_NEAR(total, area(before(f)), 1e-6) << "Face" << f;
    if (images.size() == 2) ++split;
  }
  EXPECT_EQ(split, 1);  // the box's +x face: the patch and the rest
  // One glued face is named by two given faces (the box's +x face, the bar's -x face): the patch.
  int shared = 0;
  for (std::size_t i = 0; i < named_by.size(); ++i)
    if (named_by[i] == 2) {
      ++shared;
      EXPECT_NEAR(area(after(static_cast<int>(i) + 1)), 16, 1e-6);
    } else {
      EXPECT_EQ(named_by[i], 1) << "glued face " << i;
    }
  EXPECT_EQ(shared, 1);
  for (std::size_t i = 0; i < imaged.size(); ++i) EXPECT_TRUE(imaged[i]) << "glued face " << i;
  for (std::size_t e = 0; e < report.edge_images.size(); ++e)
    EXPECT_FALSE(report.edge_images[e].empty()) << "Edge" << e + 1;
}

}  // namespace
}  // namespace hexmerge::test
