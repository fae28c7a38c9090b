#pragma once
/// @file
/// One table of a parameters struct's fields, from which every front end is built.
///
/// Each row names one field of the struct (through a pointer to the member) with its type,
/// unit, range or choices, a short label, one line of documentation, the command-line flag and
/// the FreeCAD property. Setting a field from text, checking a whole struct and exporting the
/// table (with the struct's default values) all run over the rows, so a field added to the
/// table is parsed, checked and shown everywhere with no other change.
///
/// A table is written as a list of rows made by the helpers below, e.g.
/// @code
///   using P = RecombineParameters;
///   static const ParameterTable<P> table({
///       number(&P::max_face_angle, "max_face_angle", "deg", 90, 180, "Max. face angle", "..."),
///       flag(&P::make_prisms, "make_prisms", "Prisms", "..."),
///       choice(&P::conformity, "conformity", {"conforming", "last_resort", "allow"}, ...),
///   });
/// @endcode

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "hexmerge/core/error.h"

namespace hexmerge {

/// One row of a parameter table as the front ends see it (no struct involved).
struct ParameterInfo {
  std::string name;                  ///< the struct's field name, also the Python keyword
  std::string type;                  ///< "float", "int", "bool", "choice" or "text"
  std::string default_value;         ///< the struct's default as text: "160", "true", "last_resort"
  std::string unit;                  ///< "deg", "s", "GB", "h" (a fraction of a size), "" when none
  double min = 0.0;                  ///< for float and int; -inf when unbounded
  double max = 0.0;                  ///< for float and int; +inf when unbounded
  bool min_exclusive = false;        ///< the range is (min, max] rather than [min, max]
  std::vector<std::string> choices;  ///< for "choice", in the order of the enum's values
  std::string label;                 ///< short human label for GUIs
  std::string doc;                   ///< one-line documentation
  std::string cli_flag;              ///< the command-line option, e.g. "--min-dihedral-angle"
  /// The FreeCAD document-object property, e.g. "MinDihedralAngle"; "" when the add-on does not
  /// show the parameter
  std::string freecad_property;
};

/// Text of a number as the tables show it ("150", "0.3", "1e+06").
inline std::string parameter_number_text(double value) {
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::ostringstream out;
  out << value;
  return out.str();
}

/// "min_dihedral_angle" -> "--min-dihedral-angle".
inline std::string default_cli_flag(const std::string& name) {
  std::string flag = "--" + name;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

/// "min_dihedral_angle" -> "MinDihedralAngle".
inline std::string default_freecad_property(const std::string& name) {
  std::string out;
  bool upper = true;
  for (const char c : name) {
    if (c == '_') {
      upper = true;
    } else {
      out += upper ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
      upper = false;
    }
  }
  return out;
}

/// The table of the fields of a parameters struct P.
template <class P>
class ParameterTable {
 public:
  /// An enum field: its value is the index of its text in the row's choices.
  struct EnumField {
    std::function<int(const P&)> get;
    std::function<void(P&, int)> set;
  };
  /// The member a row reads and writes. A std::string member is a "choice" when the row has
  /// choices, else free "text".
  using Field = std::variant<double P::*, int P::*, bool P::*, std::string P::*, EnumField>;

  struct Row {
    ParameterInfo info;  ///< default_value is filled in by the table from P{}
    Field field;
  };

  explicit ParameterTable(std::vector<Row> rows) : rows_(std::move(rows)) {
    const P defaults{};
    for (Row& row : rows_) {
      if (row.info.cli_flag.empty()) row.info.cli_flag = default_cli_flag(row.info.name);
      row.info.default_value = text(row, defaults);
      info_.push_back(row.info);
    }
  }

  const std::vector<Row>& rows() const { return rows_; }

  /// The rows without their fields, in display order, with P{}'s defaults.
  const std::vector<ParameterInfo>& info() const { return info_; }

  /// The row of a parameter, nullptr for an unknown name.
  const Row* find(const std::string& name) const {
    for (const Row& row : rows_) {
      if (row.info.name == name) return &row;
    }
    return nullptr;
  }

  /// Sets one field from text (a command line, a property, a Python value as text).
  /// @throws InputError (Entity::Parameter) naming the parameter when the name is unknown or
  ///         the value is not of its type or out of its range
  void set(P& parameters, const std::string& name, const std::string& value) const {
    const Row* row = find(name);
    if (row == nullptr) {
      std::string all;
      for (const Row& r : rows_) all += (all.empty() ? "" : ", ") + r.info.name;
      throw InputError("unknown parameter '" + name + "' (the parameters are: " + all + ")",
                       Entity::Parameter);
    }
    const ParameterInfo& info = row->info;
    std::visit(
        [&](const auto& field) {
          using F = std::decay_t<decltype(field)>;
          if constexpr (std::is_same_v<F, double P::*>) {
            parameters.*field = checked(info, parse_number(info, value), value);
          } else if constexpr (std::is_same_v<F, int P::*>) {
            const double x = checked(info, parse_number(info, value), value);
            if (x != std::floor(x)) throw bad_value(info, value, "must be a whole number");
            parameters.*field = static_cast<int>(x);
          } else if constexpr (std::is_same_v<F, bool P::*>) {
            parameters.*field = parse_bool(info, value);
          } else if constexpr (std::is_same_v<F, std::string P::*>) {
            if (!info.choices.empty()) choice_index(info, value);
            parameters.*field = value;
          } else {
            field.set(parameters, choice_index(info, value));
          }
        },
        row->field);
  }

  /// Checks every field of a struct against its row.
  /// @throws InputError naming the first parameter out of its range or choices
  void validate(const P& parameters) const {
    for (const Row& row : rows_) {
      const ParameterInfo& info = row.info;
      std::visit(
          [&](const auto& field) {
            using F = std::decay_t<decltype(field)>;
            if constexpr (std::is_same_v<F, double P::*> || std::is_same_v<F, int P::*>) {
              const double x = static_cast<double>(parameters.*field);
              checked(info, x, parameter_number_text(x));
            } else if constexpr (std::is_same_v<F, std::string P::*>) {
              if (!info.choices.empty()) choice_index(info, parameters.*field);
            } else if constexpr (std::is_same_v<F, EnumField>) {
              const int i = field.get(parameters);
              if (i < 0 || i >= static_cast<int>(info.choices.size())) {
                throw bad_value(info, std::to_string(i), "is not one of its choices");
              }
            }
          },
          row.field);
    }
  }

  /// The value of a row's field as text, in the form set() reads.
  static std::string text(const Row& row, const P& parameters) {
    return std::visit(
        [&](const auto& field) -> std::string {
          using F = std::decay_t<decltype(field)>;
          if constexpr (std::is_same_v<F, double P::*> || std::is_same_v<F, int P::*>) {
            return parameter_number_text(static_cast<double>(parameters.*field));
          } else if constexpr (std::is_same_v<F, bool P::*>) {
            return parameters.*field ? "true" : "false";
          } else if constexpr (std::is_same_v<F, std::string P::*>) {
            return parameters.*field;
          } else {
            const int i = field.get(parameters);
            return i >= 0 && i < static_cast<int>(row.info.choices.size()) ? row.info.choices[i]
                                                                           : std::to_string(i);
          }
        },
        row.field);
  }

 private:
  static InputError bad_value(const ParameterInfo& info, const std::string& value,
                              const std::string& why) {
    return InputError("parameter '" + info.name + "' " + why + " (got '" + value + "')",
                      Entity::Parameter);
  }

  static double parse_number(const ParameterInfo& info, const std::string& value) {
    char* end = nullptr;
    const double x = std::strtod(value.c_str(), &end);
    if (value.empty() || end == nullptr || *end != '\0' || std::isnan(x)) {
      throw bad_value(info, value, "must be a number");
    }
    return x;
  }

  // x itself when it is in the row's range; `value` is what the user gave, for the message.
  static double checked(const ParameterInfo& info, double x, const std::string& value) {
    const bool above_min = info.min_exclusive ? x > info.min : x >= info.min;
    if (above_min && x <= info.max && std::isfinite(x)) return x;
    const std::string lo = parameter_number_text(info.min);
    const std::string hi = parameter_number_text(info.max);
    const std::string unit = info.unit.empty() ? "" : " " + info.unit;
    if (std::isinf(info.max)) {
      throw bad_value(
          info, value,
          (info.min_exclusive ? "must be greater than " : "must be at least ") + lo + unit);
    }
    throw bad_value(info, value,
                    info.min_exclusive ? "must be greater than " + lo + " and at most " + hi + unit
                                       : "must be between " + lo + " and " + hi + unit);
  }

  static bool parse_bool(const ParameterInfo& info, const std::string& value) {
    std::string v = value;
    std::transform(v.begin(), v.end(), v.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
    if (v == "false" || v == "0" || v == "no" || v == "off") return false;
    throw bad_value(info, value, "must be true or false");
  }

  static int choice_index(const ParameterInfo& info, const std::string& value) {
    const auto it = std::find(info.choices.begin(), info.choices.end(), value);
    if (it == info.choices.end()) {
      std::string all;
      for (const auto& c : info.choices) all += (all.empty() ? "" : ", ") + c;
      throw bad_value(info, value, "must be one of " + all);
    }
    return static_cast<int>(it - info.choices.begin());
  }

  std::vector<Row> rows_;
  std::vector<ParameterInfo> info_;
};

/// Row helpers: the front-end names default to default_cli_flag(name) and
/// default_freecad_property(name); give `cli_flag` / `freecad_property` to differ ("" for
/// freecad_property: not a FreeCAD property).
namespace parameter_rows {

struct Names {
  std::string cli_flag;                    ///< "" : default_cli_flag(name)
  const char* freecad_property = nullptr;  ///< nullptr: default_freecad_property(name)
};

inline ParameterInfo info(const char* name, const char* type, const char* unit, double min,
                          double max, const char* label, const char* doc, const Names& names) {
  ParameterInfo i;
  i.name = name;
  i.type = type;
  i.unit = unit;
  i.min = min;
  i.max = max;
  i.label = label;
  i.doc = doc;
  i.cli_flag = names.cli_flag;
  i.freecad_property =
      names.freecad_property ? names.freecad_property : default_freecad_property(name);
  return i;
}

/// A float field in [min, max] (min_exclusive: (min, max]).
template <class P>
typename ParameterTable<P>::Row number(double P::*field, const char* name, const char* unit,
                                       double min, double max, const char* label, const char* doc,
                                       const Names& names = {}, bool min_exclusive = false) {
  ParameterInfo i = info(name, "float", unit, min, max, label, doc, names);
  i.min_exclusive = min_exclusive;
  return {i, field};
}

/// An int field in [min, max].
template <class P>
typename ParameterTable<P>::Row whole(int P::*field, const char* name, const char* unit, double min,
                                      double max, const char* label, const char* doc,
                                      const Names& names = {}) {
  return {info(name, "int", unit, min, max, label, doc, names), field};
}

/// A bool field.
template <class P>
typename ParameterTable<P>::Row flag(bool P::*field, const char* name, const char* label,
                                     const char* doc, const Names& names = {}) {
  return {info(name, "bool", "", 0, 1, label, doc, names), field};
}

/// An enum field whose values are 0, 1, ... in the order of `choices`.
template <class P, class E>
typename ParameterTable<P>::Row choice(E P::*field, const char* name,
                                       std::vector<std::string> choices, const char* label,
                                       const char* doc, const Names& names = {}) {
  static_assert(std::is_enum_v<E>, "choice() of an enum field");
  ParameterInfo i = info(name, "choice", "", 0, 0, label, doc, names);
  i.choices = std::move(choices);
  typename ParameterTable<P>::EnumField access{
      [field](const P& p) { return static_cast<int>(p.*field); },
      [field](P& p, int value) { p.*field = static_cast<E>(value); }};
  return {i, access};
}

/// A string field holding one of `choices`.
template <class P>
typename ParameterTable<P>::Row choice(std::string P::*field, const char* name,
                                       std::vector<std::string> choices, const char* label,
                                       const char* doc, const Names& names = {}) {
  ParameterInfo i = info(name, "choice", "", 0, 0, label, doc, names);
  i.choices = std::move(choices);
  return {i, field};
}

/// A free text field (a program's name, a folder).
template <class P>
typename ParameterTable<P>::Row text(std::string P::*field, const char* name, const char* label,
                                     const char* doc, const Names& names = {}) {
  return {info(name, "text", "", 0, 0, label, doc, names), field};
}

}  // namespace parameter_rows
}  // namespace hexmerge
