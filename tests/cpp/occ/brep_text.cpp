// BREP text, the form shapes cross the public headers in (brep_text.h), and CAD files read into
// it (read_shape_file.h): round trips keep the shape (topology, volume, position), files written
// in another length unit come back in millimetres naming that unit, and every file the reader
// cannot take is refused in one sentence naming it.
#include "hexmerge/occ/brep_text.h"

#include <gtest/gtest.h>

#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools.hxx>
#include <GProp_GProps.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Writer.hxx>
#include <TopAbs_ShapeEnum.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <gp_Ax2.hxx>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/read_shape_file.h"

namespace hexmerge::test {
namespace {

namespace fs = std::filesystem;

int count(const TopoDS_Shape& shape, TopAbs_ShapeEnum kind) {
  TopTools_IndexedMapOfShape map;
  TopExp::MapShapes(shape, kind, map);
  return map.Extent();
}

double volume(const TopoDS_Shape& shape) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(shape, props);
  return props.Mass();
}

gp_Pnt centre(const TopoDS_Shape& shape) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(shape, props);
  return props.CentreOfMass();
}

// A box with a cylinder's hole would need booleans; a box and a cylinder apart are enough to
// check that every solid, face and edge survives.
TopoDS_Shape box(double dx, double dy, double dz) {
  return BRepPrimAPI_MakeBox(gp_Pnt(1, 2, 3), dx, dy, dz).Shape();
}

// A scratch folder removed afterwards.
class ShapeFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("hexmerge-brep-text-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

void expect_same_shape(const TopoDS_Shape& a, const TopoDS_Shape& b, double scale = 1.0) {
  for (TopAbs_ShapeEnum kind : {TopAbs_SOLID, TopAbs_FACE, TopAbs_EDGE, TopAbs_VERTEX}) {
    EXPECT_EQ(count(a, kind), count(b, kind)) << kind;
  }
  EXPECT_NEAR(volume(b), volume(a) * scale * scale * scale,
              1e-9 * volume(a) * scale * scale * scale);
  EXPECT_LT(centre(b).Distance(centre(a).XYZ() * scale), 1e-9 * scale);
}

TEST(brep_text, write_then_read_keeps_the_shape) {
  const TopoDS_Shape cylinder =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(-4, 0, 2), gp_Dir(0.6, 0, 0.8)), 3.5, 12).Shape();
  for (const TopoDS_Shape& shape : {box(10, 4, 3), cylinder}) {
    const std::string text = write_brep(shape);
    EXPECT_NE(text.find("CASCADE Topology"), std::string::npos);
    const TopoDS_Shape back = read_brep(text);
    expect_same_shape(shape, back);
    expect_same_shape(shape, read_brep(write_brep(back)));  // and again
  }
}

TEST(brep_text, text_that_is_no_shape_is_an_input_error) {
  for (const std::string text : {"", "not a shape", "DBRep_DrawableShape\n\nCASCADE Topology V1"}) {
    try {
      read_brep(text);
      ADD_FAILURE() << "read: '" << text << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("the shape's BREP text cannot be read", 0), 0u)
          << e.what();
    }
  }
}

TEST_F(ShapeFiles, brep_file_is_read_as_its_text) {
  const std::string text = write_brep(box(10, 4, 3));
  for (const char* name : {"part.brep", "PART.BRP"}) {
    std::ofstream(path(name)) << text;
    std::string unit = "unset";
    EXPECT_EQ(read_shape_file(path(name), &unit), text);
    EXPECT_EQ(unit, "") << "a BREP file declares no unit";
  }
}

TEST_F(ShapeFiles, step_in_inches_comes_back_in_millimetres_naming_the_unit) {
  const TopoDS_Shape shape = box(10, 4, 3);
  const struct {
    const char* unit;    // as written
    const char* name;    // as the file names it
    double millimetres;  // per unit of the file
  } units[] = {{"MM", "millimetre", 1.0}, {"INCH", "INCH", 25.4}};
  for (const auto& [unit, name, millimetres] : units) {
    STEPControl_Writer writer;
    Interface_Static::SetCVal("write.step.unit", unit);
    ASSERT_EQ(writer.Transfer(shape, STEPControl_AsIs), IFSelect_RetDone);
    const std::string file = path(std::string("part-") + unit + ".step");
    ASSERT_EQ(writer.Write(file.c_str()), IFSelect_RetDone);
    std::string declared;
    const TopoDS_Shape back = read_brep(read_shape_file(file, &declared));
    EXPECT_EQ(declared, name);
    // OpenCASCADE writes the shape's numbers as they are, in the unit asked for, and reads any
    // file back in millimetres: a box of 10 x 4 x 3 inches is 254 x 101.6 x 76.2 mm.
    expect_same_shape(shape, back, millimetres);
  }
  Interface_Static::SetCVal("write.step.unit", "MM");
}

TEST_F(ShapeFiles, iges_file_is_read) {
  IGESControl_Controller::Init();
  IGESControl_Writer writer("MM", 1);  // BRep mode: solids as solids
  ASSERT_TRUE(writer.AddShape(box(10, 4, 3)));
  writer.ComputeModel();
  const std::string file = path("part.igs");
  ASSERT_TRUE(writer.Write(file.c_str()));
  std::string declared;
  const TopoDS_Shape back = read_brep(read_shape_file(file, &declared));
  EXPECT_EQ(count(back, TopAbs_FACE), 6);
  EXPECT_EQ(declared, "MM");
}

TEST_F(ShapeFiles, files_the_reader_cannot_take_are_refused_by_name) {
  std::ofstream(path("notes.txt")) << "hello";
  std::ofstream(path("broken.step")) << "ISO-10303-21;\nnonsense\n";
  std::ofstream(path("empty.brep")) << "";
  const struct {
    std::string file;
    std::string message;
  } cases[] = {
      {path("missing.step"), "cannot open the shape file " + path("missing.step")},
      {path("notes.txt"), "cannot read " + path("notes.txt") +
                              ": the file name must end in .step, .stp, .brep, .brp, .iges or "
                              ".igs"},
      {path("broken.step"), "cannot read " + path("broken.step") + " as a STEP file"},
      {path("empty.brep"),
       "cannot read " + path("empty.brep") + ": the shape's BREP text cannot be read"},
  };
  for (const auto& c : cases) {
    const auto before = fs::exists(c.file) ? fs::file_size(c.file) : 0;
    try {
      read_shape_file(c.file);
      ADD_FAILURE() << c.file << " read";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(c.message, 0), 0u) << e.what();
    }
    if (fs::exists(c.file)) {
      EXPECT_EQ(fs::file_size(c.file), before) << "input modified";
    }
  }
}

}  // namespace
}  // namespace hexmerge::test
