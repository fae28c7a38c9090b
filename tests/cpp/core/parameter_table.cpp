#include "hexmerge/core/parameter_table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace hexmerge::test {
namespace {

enum class Shade { Light, Dark };

struct Options {
  double angle = 150.0;
  double size = 0.0;
  int count = 2;
  bool on = true;
  Shade shade = Shade::Dark;
  std::string frame = "auto";
  std::string program = "tetgen";
};

const ParameterTable<Options>& table() {
  using namespace parameter_rows;
  using O = Options;
  static const ParameterTable<O> t({
      number(&O::angle, "angle", "deg", 90, 180, "Angle", "an angle"),
      number(&O::size, "size", "mm", 0, std::numeric_limits<double>::infinity(), "Size", "a length",
             {"--size", "TargetSize"}, /*min_exclusive=*/true),
      whole(&O::count, "count", "", 0, 3, "Count", "a count", {"--many"}),
      flag(&O::on, "on", "On", "a switch"),
      choice(&O::shade, "shade", {"light", "dark"}, "Shade", "an enum"),
      choice(&O::frame, "frame", {"auto", "global"}, "Frame", "a string choice",
             {"", "LatticeFrame"}),
      text(&O::program, "program", "Program", "free text", {"", ""}),
  });
  return t;
}

std::string message_of(const Options& o, const char* name, const char* value) {
  Options copy = o;
  try {
    table().set(copy, name, value);
  } catch (const InputError& e) {
    EXPECT_EQ(e.entity(), Entity::Parameter);
    return e.what();
  }
  return "";
}

TEST(ParameterTable, ExportsTheStructDefaultsAndTheFrontEndNames) {
  const auto& info = table().info();
  ASSERT_EQ(info.size(), 7u);
  EXPECT_EQ(info[0].default_value, "150");
  EXPECT_EQ(info[0].type, "float");
  EXPECT_EQ(info[0].cli_flag, "--angle");
  EXPECT_EQ(info[0].freecad_property, "Angle");
  EXPECT_EQ(info[1].freecad_property, "TargetSize");
  EXPECT_TRUE(info[1].min_exclusive);
  EXPECT_EQ(info[2].cli_flag, "--many");
  EXPECT_EQ(info[2].type, "int");
  EXPECT_EQ(info[3].default_value, "true");
  EXPECT_EQ(info[4].default_value, "dark");
  EXPECT_EQ(info[4].type, "choice");
  EXPECT_EQ(info[5].default_value, "auto");
  EXPECT_EQ(info[5].freecad_property, "LatticeFrame");
  EXPECT_EQ(info[6].type, "text");
  EXPECT_EQ(info[6].freecad_property, "");
  EXPECT_EQ(default_freecad_property("min_dihedral_angle"), "MinDihedralAngle");
  EXPECT_EQ(default_cli_flag("min_dihedral_angle"), "--min-dihedral-angle");
}

TEST(ParameterTable, SetThenTextRoundTripsEveryRow) {
  // Each row's text, set into a struct holding other values, gives the same text back.
  const Options defaults;
  Options changed;
  changed.angle = 91.5;
  changed.size = 2.25;
  changed.count = 0;
  changed.on = false;
  changed.shade = Shade::Light;
  changed.frame = "global";
  changed.program = "/usr/bin/tetgen";
  for (const auto& row : table().rows()) {
    Options target = defaults;
    table().set(target, row.info.name, ParameterTable<Options>::text(row, changed));
    EXPECT_EQ(ParameterTable<Options>::text(row, target),
              ParameterTable<Options>::text(row, changed))
        << row.info.name;
  }
  Options target;
  table().set(target, "shade", "light");
  EXPECT_EQ(target.shade, Shade::Light);
  table().set(target, "on", "OFF");
  EXPECT_FALSE(target.on);
  table().set(target, "count", "3");
  EXPECT_EQ(target.count, 3);
}

TEST(ParameterTable, RangesAreClosedUnlessTheRowSaysOtherwise) {
  const Options o;
  EXPECT_EQ(message_of(o, "angle", "90"), "");
  EXPECT_EQ(message_of(o, "angle", "180"), "");
  EXPECT_EQ(message_of(o, "angle", "89.999"),
            "parameter 'angle' must be between 90 and 180 deg (got '89.999')");
  EXPECT_NE(message_of(o, "angle", "180.001").find("must be between 90 and 180"),
            std::string::npos);
  EXPECT_EQ(message_of(o, "size", "0"), "parameter 'size' must be greater than 0 mm (got '0')");
  EXPECT_EQ(message_of(o, "size", "1e-300"), "");
  EXPECT_NE(message_of(o, "size", "inf").find("must be greater than 0"), std::string::npos);
  EXPECT_NE(message_of(o, "angle", "nan").find("must be a number"), std::string::npos);
  EXPECT_NE(message_of(o, "angle", "150x").find("must be a number"), std::string::npos);
  EXPECT_NE(message_of(o, "angle", "").find("must be a number"), std::string::npos);
  EXPECT_NE(message_of(o, "count", "1.5").find("must be a whole number"), std::string::npos);
  EXPECT_NE(message_of(o, "count", "4").find("between 0 and 3"), std::string::npos);
  EXPECT_NE(message_of(o, "on", "maybe").find("must be true or false"), std::string::npos);
  EXPECT_EQ(message_of(o, "shade", "grey"),
            "parameter 'shade' must be one of light, dark (got 'grey')");
  EXPECT_NE(message_of(o, "frame", "diagonal").find("must be one of auto, global"),
            std::string::npos);
  EXPECT_EQ(message_of(o, "program", "anything at all"), "");
  EXPECT_EQ(message_of(o, "colour", "1"),
            "unknown parameter 'colour' (the parameters are: angle, size, count, on, shade, "
            "frame, program)");
}

TEST(ParameterTable, FailedSetLeavesTheStructUnchanged) {
  Options o;
  EXPECT_THROW(table().set(o, "angle", "10"), InputError);
  EXPECT_THROW(table().set(o, "count", "2.5"), InputError);
  EXPECT_THROW(table().set(o, "frame", "diagonal"), InputError);
  EXPECT_EQ(o.angle, 150.0);
  EXPECT_EQ(o.count, 2);
  EXPECT_EQ(o.frame, "auto");
}

TEST(ParameterTable, ValidateChecksEveryFieldAgainstItsRow) {
  Options o;
  o.size = 1.0;
  EXPECT_NO_THROW(table().validate(o));
  const auto fails = [](auto change) {
    Options bad;
    bad.size = 1.0;
    change(bad);
    EXPECT_THROW(table().validate(bad), InputError);
  };
  fails([](Options& b) { b.angle = 180.0000001; });
  fails([](Options& b) { b.angle = std::nan(""); });
  fails([](Options& b) { b.size = 0.0; });
  fails([](Options& b) { b.size = std::numeric_limits<double>::infinity(); });
  fails([](Options& b) { b.count = -1; });
  fails([](Options& b) { b.shade = static_cast<Shade>(7); });
  fails([](Options& b) { b.frame = "diagonal"; });
  // The defaults themselves: size 0 is outside (0, inf), the user must give it.
  try {
    table().validate(Options{});
    ADD_FAILURE() << "size 0 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "parameter 'size' must be greater than 0 mm (got '0')");
  }
}

}  // namespace
}  // namespace hexmerge::test
