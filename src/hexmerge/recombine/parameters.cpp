#include "hexmerge/recombine/parameters.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "hexmerge/core/error.h"

namespace hexmerge {
namespace {

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

std::string flag(bool value) { return value ? "true" : "false"; }

const std::vector<std::string> kConformityChoices = {"conforming", "last_resort", "allow"};
const std::vector<std::string> kFinderChoices = {"programs", "exhaustive"};
const std::vector<std::string> kBoundaryOrderChoices = {"quality", "fewest_matches"};
const std::vector<std::string> kLocalSearchSeedsChoices = {"unmatched", "all"};
const std::vector<std::string> kPyramidPlacementChoices = {"anywhere", "no_boundary_face",
                                                           "no_boundary_node"};

InputError bad_value(const std::string& name, const std::string& value, const std::string& why) {
  return InputError("parameter '" + name + "': " + why + " (got '" + value + "')",
                    Entity::Parameter);
}

double parse_number(const std::string& name, const std::string& value, double lo, double hi) {
  char* end = nullptr;
  const double x = std::strtod(value.c_str(), &end);
  if (value.empty() || end == nullptr || *end != '\0') throw bad_value(name, value, "not a number");
  if (!(x >= lo && x <= hi)) {
    throw bad_value(name, value, "must be between " + number(lo) + " and " + number(hi));
  }
  return x;
}

int parse_int(const std::string& name, const std::string& value, double lo, double hi) {
  const double x = parse_number(name, value, lo, hi);
  if (x != static_cast<int>(x)) throw bad_value(name, value, "must be a whole number");
  return static_cast<int>(x);
}

bool parse_bool(const std::string& name, const std::string& value) {
  std::string v = value;
  std::transform(v.begin(), v.end(), v.begin(), ::tolower);
  if (v == "true" || v == "1" || v == "yes" || v == "on") return true;
  if (v == "false" || v == "0" || v == "no" || v == "off") return false;
  throw bad_value(name, value, "must be true or false");
}

int parse_choice(const std::string& name, const std::string& value,
                 const std::vector<std::string>& choices) {
  const auto it = std::find(choices.begin(), choices.end(), value);
  if (it == choices.end()) {
    std::string all;
    for (const auto& c : choices) all += (all.empty() ? "" : ", ") + c;
    throw bad_value(name, value, "must be one of " + all);
  }
  return static_cast<int>(it - choices.begin());
}

std::vector<ParameterInfo> make_table() {
  const RecombineParameters d;
  return {
      {"min_dihedral_angle", "float", number(d.min_dihedral_angle), "deg", 90, 180, {},
       "Min. quad dihedral angle",
       "Smallest accepted dihedral angle between the two triangles of a quad face (180 = flat)"},
      {"min_boundary_dihedral_angle", "float", number(d.min_boundary_dihedral_angle), "deg", 90,
       180, {}, "Min. boundary dihedral angle",
       "Smallest accepted dihedral angle of a quad face on the domain boundary (keeps the "
       "boundary on the geometry)"},
      {"max_face_angle", "float", number(d.max_face_angle), "deg", 90, 180, {},
       "Max. face angle",
       "Largest accepted corner angle of a quad face (90 = rectangle)"},
      {"min_scaled_jacobian", "float", number(d.min_scaled_jacobian), "", -1, 1, {},
       "Min. scaled Jacobian",
       "Smallest accepted scaled Jacobian (Verdict) of a new hex, prism or pyramid (1 = ideal; "
       "below 1e-9 counts as 1e-9: no element is ever flat or inverted)"},
      {"make_hexahedra", "bool", flag(d.make_hexahedra), "", 0, 1, {}, "Hexahedra",
       "Merge tetrahedra into hexahedra"},
      {"make_prisms", "bool", flag(d.make_prisms), "", 0, 1, {}, "Prisms",
       "Merge tetrahedra into prisms (pentahedra)"},
      {"make_pyramids", "bool", flag(d.make_pyramids), "", 0, 1, {}, "Pyramids",
       "Merge tetrahedra into pyramids. In conforming mode pyramids close the quad faces of "
       "hexes and prisms: without them almost nothing merges on unstructured meshes (for "
       "CalculiX, keep them off the boundary with pyramid_placement)"},
      {"pyramid_placement", "choice", to_string(d.pyramid_placement), "", 0, 0,
       kPyramidPlacementChoices, "Pyramid placement",
       "Where pyramids may be made: anywhere, not with a face on the boundary "
       "(no_boundary_face), or not with a node on it (no_boundary_node); tets stay there "
       "instead. For CalculiX (no pyramid element: collapsed hexahedra) no_boundary_node keeps "
       "peak stresses as accurate as the tets' (docs/fem-accuracy.md)"},
      {"conformity", "choice", to_string(d.conformity), "", 0, 0, kConformityChoices,
       "Conformity",
       "Quad faces meeting two triangles: never (conforming), only where nothing else is "
       "possible (last_resort), or freely (allow)"},
      {"respect_regions", "bool", flag(d.respect_regions), "", 0, 1, {}, "Respect regions",
       "Never merge tetrahedra of different regions (materials, solids)"},
      {"local_optimisation", "bool", flag(d.local_optimisation), "", 0, 1, {},
       "Local optimisation",
       "Rearrange elements around unmatched boundary tetrahedra (Meshkat-Talmor 4.2)"},
      {"local_search", "bool", flag(d.local_search), "", 0, 1, {}, "Local search",
       "After the selection, re-select exactly each element next to free tetrahedra with them "
       "(swaps) and, with a local search radius above 0, every neighbourhood of that radius, "
       "whenever that lowers the element count (conformity mode kept)"},
      {"local_search_radius", "int", number(d.local_search_radius), "", 0, 4, {},
       "Local search radius",
       "Face hops around a tetrahedron within which the local search releases the elements and "
       "re-selects them exactly; 0: swaps only (cheap). 3 with local_search_seeds = all comes "
       "within about 2 % of the optimum in allow mode, at about 1.5 s per 10k tetrahedra"},
      {"local_search_nodes", "int", number(d.local_search_nodes), "", 1, 1000000, {},
       "Local search effort",
       "Branch-and-bound nodes the local search may spend on one neighbourhood (bounds its "
       "time; past it the best re-selection found so far is kept)"},
      {"local_search_seeds", "choice", to_string(d.local_search_seeds), "", 0, 0,
       kLocalSearchSeedsChoices, "Local search seeds",
       "Where the local search re-selects: around unmatched tetrahedra, or around every "
       "tetrahedron (also merges elements into fewer; slower)"},
      {"boundary_order", "choice", to_string(d.boundary_order), "", 0, 0, kBoundaryOrderChoices,
       "Boundary order",
       "Order of the greedy boundary phase: best quality first, or the paper's fewest remaining "
       "matches first"},
      {"finder", "choice", to_string(d.finder), "", 0, 0, kFinderChoices, "Candidate finder",
       "How candidate elements are found: the paper's RF-graph search programs (5- and 6-tet "
       "hexahedra), or exhaustively (every cell its vertices' tets fill, any subdivision)"},
      {"threads", "int", number(d.threads), "", 0, 1024, {}, "Threads",
       "Threads for the candidate search; 0 uses every hardware thread"},
      {"optimality_bound", "bool", flag(d.optimality_bound), "", 0, 1, {}, "Optimality bound",
       "Also solve the selection as an integer program (GLPK) for a bound on the element count "
       "and one on the hexahedron volume; meshes up to about 20k tets (no cap: larger ones stop "
       "at the time limit with a looser bound)"},
      {"bound_time_limit", "float", number(d.bound_time_limit), "s", 1, 3600, {},
       "Bound time limit",
       "Time limit of each of the optimality bound's two integer programs; past it the best "
       "bound so far is reported"},
      {"same_nodes", "bool", flag(d.same_nodes), "", 0, 1, {}, "Same tets",
       "Keep the input's tetrahedra: every output cell is a union of them. Off, in conforming "
       "mode, a post-merge stage flips tets (2-3, 3-2, 4-4; nodes kept) so that pyramids close "
       "the open quad faces of more hexahedra, and the selection is run again on the new tets "
       "(kept only when it has fewer elements); the cells then list no source tets"},
      {"post_merge_rounds", "int", number(d.post_merge_rounds), "", 1, 10, {},
       "Post-merge rounds",
       "Rounds of the post-merge stage (same_nodes off): each closes more quads around the "
       "last selection and selects again; the stage stops at the first round that does not "
       "lower the element count"},
  };
}

}  // namespace

std::string to_string(Conformity conformity) {
  return kConformityChoices[static_cast<int>(conformity)];
}

std::string to_string(Finder finder) { return kFinderChoices[static_cast<int>(finder)]; }

std::string to_string(BoundaryOrder order) {
  return kBoundaryOrderChoices[static_cast<int>(order)];
}

std::string to_string(LocalSearchSeeds seeds) {
  return kLocalSearchSeedsChoices[static_cast<int>(seeds)];
}

std::string to_string(PyramidPlacement placement) {
  return kPyramidPlacementChoices[static_cast<int>(placement)];
}

const std::vector<ParameterInfo>& parameter_table() {
  static const std::vector<ParameterInfo> table = make_table();
  return table;
}

void set_parameter(RecombineParameters& p, const std::string& name, const std::string& value) {
  const auto& table = parameter_table();
  const auto row = std::find_if(table.begin(), table.end(),
                                [&](const ParameterInfo& info) { return info.name == name; });
  if (row == table.end()) {
    throw InputError("unknown parameter '" + name + "'", Entity::Parameter);
  }
  if (name == "min_dihedral_angle") {
    p.min_dihedral_angle = parse_number(name, value, row->min, row->max);
  } else if (name == "min_boundary_dihedral_angle") {
    p.min_boundary_dihedral_angle = parse_number(name, value, row->min, row->max);
  } else if (name == "max_face_angle") {
    p.max_face_angle = parse_number(name, value, row->min, row->max);
  } else if (name == "min_scaled_jacobian") {
    p.min_scaled_jacobian = parse_number(name, value, row->min, row->max);
  } else if (name == "make_hexahedra") {
    p.make_hexahedra = parse_bool(name, value);
  } else if (name == "make_prisms") {
    p.make_prisms = parse_bool(name, value);
  } else if (name == "make_pyramids") {
    p.make_pyramids = parse_bool(name, value);
  } else if (name == "pyramid_placement") {
    p.pyramid_placement = static_cast<PyramidPlacement>(parse_choice(name, value, row->choices));
  } else if (name == "conformity") {
    p.conformity = static_cast<Conformity>(parse_choice(name, value, row->choices));
  } else if (name == "respect_regions") {
    p.respect_regions = parse_bool(name, value);
  } else if (name == "local_optimisation") {
    p.local_optimisation = parse_bool(name, value);
  } else if (name == "local_search") {
    p.local_search = parse_bool(name, value);
  } else if (name == "local_search_radius") {
    p.local_search_radius = parse_int(name, value, row->min, row->max);
  } else if (name == "local_search_nodes") {
    p.local_search_nodes = parse_int(name, value, row->min, row->max);
  } else if (name == "local_search_seeds") {
    p.local_search_seeds = static_cast<LocalSearchSeeds>(parse_choice(name, value, row->choices));
  } else if (name == "boundary_order") {
    p.boundary_order = static_cast<BoundaryOrder>(parse_choice(name, value, row->choices));
  } else if (name == "finder") {
    p.finder = static_cast<Finder>(parse_choice(name, value, row->choices));
  } else if (name == "threads") {
    p.threads = parse_int(name, value, row->min, row->max);
  } else if (name == "optimality_bound") {
    p.optimality_bound = parse_bool(name, value);
  } else if (name == "bound_time_limit") {
    p.bound_time_limit = parse_number(name, value, row->min, row->max);
  } else if (name == "same_nodes") {
    p.same_nodes = parse_bool(name, value);
  } else if (name == "post_merge_rounds") {
    p.post_merge_rounds = parse_int(name, value, row->min, row->max);
  } else {
    HEXMERGE_ASSERT(false, "parameter in the table without a setter");
  }
}

void validate_parameters(const RecombineParameters& p) {
  // Range checks go through the same parser as text input, so the two can never disagree.
  RecombineParameters scratch;
  set_parameter(scratch, "min_dihedral_angle", number(p.min_dihedral_angle));
  set_parameter(scratch, "min_boundary_dihedral_angle", number(p.min_boundary_dihedral_angle));
  set_parameter(scratch, "max_face_angle", number(p.max_face_angle));
  set_parameter(scratch, "min_scaled_jacobian", number(p.min_scaled_jacobian));
  set_parameter(scratch, "threads", number(p.threads));
  set_parameter(scratch, "local_search_radius", number(p.local_search_radius));
  set_parameter(scratch, "local_search_nodes", number(p.local_search_nodes));
  set_parameter(scratch, "bound_time_limit", number(p.bound_time_limit));
  set_parameter(scratch, "post_merge_rounds", number(p.post_merge_rounds));
  if (!p.make_hexahedra && !p.make_prisms && !p.make_pyramids) {
    throw InputError("no element type is enabled: enable hexahedra, prisms or pyramids",
                     Entity::Parameter);
  }
}

}  // namespace hexmerge
