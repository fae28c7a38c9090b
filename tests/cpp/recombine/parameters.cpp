#include "hexmerge/recombine/parameters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <string>

namespace hexmerge::test {
namespace {

using Table = ParameterTable<RecombineParameters>;

// A number as text to the last bit (the tables' own text has 6 digits).
std::string exact(double x) {
  std::ostringstream out;
  out << std::setprecision(17) << x;
  return out.str();
}

std::string text_of(const std::string& name, const RecombineParameters& p) {
  return Table::text(*recombine_parameter_table().find(name), p);
}

TEST(parameters, TableDefaultsAreTheStructDefaults) {
  const RecombineParameters defaults;
  for (const ParameterInfo& row : parameter_table()) {
    EXPECT_EQ(row.default_value, text_of(row.name, defaults)) << row.name;
    RecombineParameters p;
    set_parameter(p, row.name, row.default_value);
    EXPECT_EQ(text_of(row.name, p), row.default_value) << row.name;
  }
  EXPECT_NO_THROW(validate_parameters(defaults));
}

TEST(parameters, EveryRowNamesItsFrontEnds) {
  std::set<std::string> names, flags, properties;
  for (const ParameterInfo& row : parameter_table()) {
    EXPECT_TRUE(names.insert(row.name).second) << row.name;
    EXPECT_TRUE(flags.insert(row.cli_flag).second) << row.cli_flag;
    EXPECT_TRUE(properties.insert(row.freecad_property).second) << row.freecad_property;
    EXPECT_EQ(row.cli_flag, default_cli_flag(row.name));
    EXPECT_FALSE(row.label.empty() || row.doc.empty()) << row.name;
    EXPECT_NE(row.type, "text") << row.name;  // every engine parameter has a type to check
  }
}

TEST(parameters, RangeEndsPassAndJustBeyondFails) {
  for (const ParameterInfo& row : parameter_table()) {
    if (row.type != "float" && row.type != "int") continue;
    RecombineParameters p;
    set_parameter(p, row.name, parameter_number_text(row.min));
    set_parameter(p, row.name, parameter_number_text(row.max));
    EXPECT_EQ(text_of(row.name, p), parameter_number_text(row.max)) << row.name;
    const double step = row.type == "int" ? 1.0 : 1e-6 * std::max(1.0, std::abs(row.max));
    EXPECT_THROW(set_parameter(p, row.name, exact(row.min - step)), InputError) << row.name;
    EXPECT_THROW(set_parameter(p, row.name, exact(row.max + step)), InputError) << row.name;
    EXPECT_EQ(text_of(row.name, p), parameter_number_text(row.max)) << row.name << " changed";
  }
}

TEST(parameters, EveryChoiceIsItsEnumValue) {
  RecombineParameters p;
  for (const ParameterInfo& row : parameter_table()) {
    if (row.type != "choice") continue;
    ASSERT_GE(row.choices.size(), 2u) << row.name;
    for (const std::string& choice : row.choices) {
      set_parameter(p, row.name, choice);
      EXPECT_EQ(text_of(row.name, p), choice) << row.name;
    }
    EXPECT_THROW(set_parameter(p, row.name, row.choices[0] + "x"), InputError) << row.name;
  }
  set_parameter(p, "conformity", "last_resort");
  EXPECT_EQ(p.conformity, Conformity::LastResort);
  EXPECT_EQ(to_string(p.conformity), "last_resort");
  set_parameter(p, "pyramid_placement", "no_boundary_node");
  EXPECT_EQ(p.pyramid_placement, PyramidPlacement::NoBoundaryNode);
  set_parameter(p, "boundary_order", "fewest_matches");
  EXPECT_EQ(to_string(p.boundary_order), "fewest_matches");
}

TEST(parameters, ValidateNamesTheFieldOutOfRange) {
  const auto message = [](auto change) -> std::string {
    RecombineParameters p;
    change(p);
    try {
      validate_parameters(p);
    } catch (const InputError& e) {
      EXPECT_EQ(e.entity(), Entity::Parameter);
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message([](RecombineParameters& p) {
              p.max_face_angle = 200;
            }).find("parameter 'max_face_angle' must be between 90 and 180 deg"),
            std::string::npos);
  EXPECT_NE(message([](RecombineParameters& p) {
              p.min_scaled_jacobian = std::nan("");
            }).find("'min_scaled_jacobian'"),
            std::string::npos);
  EXPECT_NE(message([](RecombineParameters& p) { p.threads = -1; }).find("'threads'"),
            std::string::npos);
  EXPECT_NE(message([](RecombineParameters& p) {
              p.conformity = static_cast<Conformity>(9);
            }).find("'conformity'"),
            std::string::npos);
  EXPECT_NE(message([](RecombineParameters& p) {
              p.make_hexahedra = p.make_prisms = p.make_pyramids = false;
            }).find("no element type is enabled"),
            std::string::npos);
  EXPECT_EQ(message([](RecombineParameters& p) { p.bound_time_limit = 3600; }), "");
}

}  // namespace
}  // namespace hexmerge::test
