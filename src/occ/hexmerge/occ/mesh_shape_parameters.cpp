#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesh_shape.h"

namespace hexmerge {
namespace {

ParameterTable<MeshShapeParameters> make_table() {
  using P = MeshShapeParameters;
  using namespace parameter_rows;
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  return ParameterTable<P>({
      // (0, inf): "not larger than the shape" needs the shape, mesh_shape() checks it.
      number(&P::size, "size", "mm", 0, kUnbounded, "Target size",
             "Target element size h: the lattice spacing and the surface's longest edge, in the "
             "shape's units (millimetres for STEP and IGES files); not larger than the shape",
             {"--size", "TargetSize"}, /*min_exclusive=*/true),
      whole(&P::boundary_layers, "boundary_layers", "", -1, 3, "Boundary layers",
            "Layers of points offset from the curved and unaligned faces along the inward "
            "normal (-1: one on swept shapes, where they become a ring of prisms and hexahedra "
            "along the walls, none on the others, where they add tets and no prisms)",
            {"--layers"}),
      number(&P::layer_thickness, "layer_thickness", "h", 0.1, 1, "Layer thickness",
             "Thickness of one boundary layer, as a fraction of the target size h"),
      number(&P::lattice_margin, "lattice_margin", "h", 0.1, 2, "Lattice margin",
             "Lattice points nearer than this to a face off the lattice planes (swept shapes: "
             "this beyond their boundary layers) are dropped; a fraction of h"),
      number(&P::surface_deflection, "surface_deflection", "h", 0.001, 0.5, "Surface deflection",
             "Chord deflection of the surface triangulation on curved faces, as a fraction of h"),
      number(&P::feature_size, "feature_size", "h", 0, 0.5, "Feature size",
             "CAD edges shorter than twice this fraction of h get a local size of their length, "
             "at least this, and faces 0.01 h to 0.1 h wide three times their width: the surface "
             "and the inside graded out to h around them, so that short edges and narrow faces "
             "make no needle triangles (0: none; swept shapes are meshed without)"),
      choice(&P::frame, "frame", {"auto", "principal", "global"}, "Lattice frame",
             "Orientation of the lattice: auto (normals of the largest planar faces, else the "
             "principal axes of inertia), principal (principal axes of inertia), global (x, y, z)",
             {"", "LatticeFrame"}),
      flag(&P::sweep, "sweep", "Sweep extrusions",
           "Where the shape is one cross-section extruded along a lattice axis between two "
           "planar caps (plates with holes, cylinders, profiles; one solid or several), sweep "
           "the tets too: the same cross-section on every lattice plane, so that they recombine "
           "into hexahedra and prisms only"),
      flag(&P::pull_core, "pull_core", "Pull the core to the surface",
           "Move the hexahedral core's boundary towards the surface (not on swept shapes, nor "
           "with boundary layers or face layers): "
           "the lattice's steps otherwise leave up to a cell of pyramids and tets between the "
           "core and the faces; its moved cells and pyramids are kept whole (TetGen "
           "constraints), as are core cells whose closing pyramid's apex lies in their "
           "circumsphere (narrow cells beside wide ones) or is placed nearer the face (the "
           "centre of the cell across outside the shape), which would otherwise leave the core; "
           "when TetGen fails on them the lattice is tried without"),
      flag(&P::buffer_layer, "buffer_layer", "Buffer layer",
           "With the core pulled: hexahedra between the core's closing pyramids' bases and the "
           "surface, the bases' corners projected onto one CAD face (not a lattice face, a face "
           "with a local size or one between two solids) and the face triangulated again with "
           "their tops in it; their open side faces closed by pyramids; and hexahedra across "
           "tube walls (two coaxial cylinders 0.5 h to 2.5 h apart) too thin for the core, their "
           "quads put into both cylinders' triangles; when TetGen fails on them the pulled core "
           "is tried without"),
      flag(&P::polish, "polish", "Polish the tets left",
           "After the flips and moves against slivers, the recombination is run once to see "
           "which tets its hexahedra, prisms and pyramids take; the other tets under a scaled "
           "Jacobian of 0.2 get flips and moves of their nodes (those of faces and edges sized "
           "for their features too, along them) that keep every element at the nodes "
           "acceptable; not on swept shapes; costs one more recombination"),
      number(&P::tetgen_time_limit, "tetgen_time_limit", "s", 0, 86400, "TetGen time limit",
             "Time limit of one TetGen run (0: 30 s plus 1 ms per point); a run past it, or one "
             "that leaves no tet, is restarted with the lattice faces' loops started elsewhere, "
             "up to 5 times, then the meshing fails"),
      number(&P::memory_limit, "memory_limit", "GB", 0, 1e6, "Memory limit",
             "Memory the meshing and recombination may take (0: what the system has available); "
             "a size whose estimated tets would need more is refused before any work"),
      text(&P::tetgen, "tetgen", "TetGen program",
           "The TetGen program: a name looked up on PATH, or a path", {"", ""}),
      text(&P::work_directory, "work_directory", "Work directory",
           "A folder for TetGen's files, kept afterwards (made when missing); empty: a "
           "temporary one, removed",
           {"", ""}),
      // The add-on fills it from the analysis' mesh regions: no property of its own.
      text(&P::local_sizes, "local_sizes", "Local sizes",
           "Finer sizes on some faces and edges (1-based, as FreeCAD's FaceN, EdgeN): entries "
           "ITEMS:SIZE separated by ';', ITEMS a comma-separated list of N or FaceN (faces), "
           "EdgeN (edges); e.g. '5:1.5; Edge3:0.5'. Sizes in (0, size]; an extrusion stays "
           "swept only for local sizes on its caps' edges",
           {"--local-size", ""}),
      // The add-on fills it from the analysis' boundary layer objects: no property of its own.
      text(&P::face_layers, "face_layers", "Face layers",
           "Boundary layers on some faces (1-based, as FreeCAD's FaceN): entries "
           "FACES:LAYERS:THICKNESS[:GROWTH] separated by ';', FACES a comma-separated list of N "
           "or FaceN; e.g. '3:4:0.5:1.2' (4 layers on Face3, the first 0.5 deep, each next 1.2 "
           "times thicker). LAYERS 1 to 10, THICKNESS in (0, size], GROWTH 1 to 3 (default 1); "
           "an extrusion stays swept for layers on its walls, not on its caps",
           {"--face-layer", ""}),
  });
}

std::string trimmed(const std::string& text) {
  std::size_t a = 0, b = text.size();
  while (a < b && std::isspace(static_cast<unsigned char>(text[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(text[b - 1]))) --b;
  return text.substr(a, b - a);
}

InputError bad_local_size(const std::string& entry, const std::string& why) {
  return InputError("parameter 'local_sizes': entry '" + entry + "' " + why, Entity::Parameter);
}

InputError bad_face_layers(const std::string& entry, const std::string& why) {
  return InputError("parameter 'face_layers': entry '" + entry + "' " + why, Entity::Parameter);
}

// The fields of a text separated by `separator`, trimmed (empty ones too).
std::vector<std::string> fields_of(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find(separator, start);
    if (end == std::string::npos) end = text.size();
    out.push_back(trimmed(text.substr(start, end - start)));
    start = end + 1;
  }
  return out;
}

// The number of an item "N", "FaceN" or "EdgeN" (-1: not one), and whether it is an edge.
int item_number(const std::string& item, bool& edge) {
  std::string lower;
  for (const char c : item) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::size_t digits = 0;
  edge = false;
  if (lower.rfind("face", 0) == 0) {
    digits = 4;
  } else if (lower.rfind("edge", 0) == 0) {
    edge = true, digits = 4;
  }
  const std::string number = item.substr(digits);
  const bool whole = !number.empty() && number.size() < 10 &&
                     std::all_of(number.begin(), number.end(), [](char c) {
                       return std::isdigit(static_cast<unsigned char>(c));
                     });
  if (!whole || std::stoi(number) < 1) return -1;
  return std::stoi(number);
}

// A number field of a face_layers entry, or -1 when it is not a finite number.
double number_of(const std::string& field) {
  const std::string text = trimmed(field);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) return -1;
  return value;
}

}  // namespace

const ParameterTable<MeshShapeParameters>& mesh_shape_parameter_table() {
  static const ParameterTable<MeshShapeParameters> table = make_table();
  return table;
}

std::vector<LocalSize> parse_local_sizes(const std::string& text) {
  std::vector<LocalSize> out;
  for (const std::string& entry : fields_of(text, ';')) {
    if (entry.empty()) continue;
    const std::size_t colon = entry.rfind(':');
    if (colon == std::string::npos)
      throw bad_local_size(entry, "is not ITEMS:SIZE (e.g. '5,6:1.5' or 'Edge3:0.5')");
    LocalSize local;
    const std::string size_text = trimmed(entry.substr(colon + 1));
    char* size_end = nullptr;
    local.size = std::strtod(size_text.c_str(), &size_end);
    if (size_text.empty() || *size_end != '\0' || !std::isfinite(local.size) || local.size <= 0)
      throw bad_local_size(entry, "has size '" + size_text + "': it must be a number > 0");
    for (const std::string& item : fields_of(entry.substr(0, colon), ',')) {
      bool edge = false;
      const int number = item_number(item, edge);
      if (number < 0)
        throw bad_local_size(entry, "names '" + item +
                                        "': items are N or FaceN (a face), EdgeN (an edge), "
                                        "numbered from 1");
      (edge ? local.edges : local.faces).push_back(number);
    }
    out.push_back(local);
  }
  return out;
}

std::vector<FaceLayers> parse_face_layers(const std::string& text) {
  std::vector<FaceLayers> out;
  for (const std::string& entry : fields_of(text, ';')) {
    if (entry.empty()) continue;
    const std::vector<std::string> fields = fields_of(entry, ':');
    if (fields.size() < 3 || fields.size() > 4)
      throw bad_face_layers(entry,
                            "is not FACES:LAYERS:THICKNESS[:GROWTH] (e.g. '3:4:0.5:1.2' or "
                            "'Face3,Face5:2:0.25')");
    FaceLayers layers;
    for (const std::string& item : fields_of(fields[0], ',')) {
      bool edge = false;
      const int number = item_number(item, edge);
      if (number < 0 || edge)
        throw bad_face_layers(entry, "names '" + item +
                                         "': boundary layers go on faces, N or FaceN, numbered "
                                         "from 1");
      layers.faces.push_back(number);
    }
    const double count = number_of(fields[1]);
    if (count < 1 || count > 10 || count != std::floor(count))
      throw bad_face_layers(entry,
                            "has " + fields[1] + " layers: give a whole number from 1 to 10");
    layers.layers = static_cast<int>(count);
    layers.thickness = number_of(fields[2]);
    if (layers.thickness <= 0)
      throw bad_face_layers(entry, "has thickness '" + fields[2] + "': it must be a length > 0");
    if (fields.size() == 4) {
      layers.growth = number_of(fields[3]);
      if (layers.growth < 1 || layers.growth > 3)
        throw bad_face_layers(entry,
                              "has growth rate '" + fields[3] + "': give a number from 1 to 3");
    }
    out.push_back(layers);
  }
  return out;
}

void validate_mesh_shape_parameters(const MeshShapeParameters& parameters) {
  mesh_shape_parameter_table().validate(parameters);
  parse_local_sizes(parameters.local_sizes);
  parse_face_layers(parameters.face_layers);
  if (parameters.tetgen.empty()) {
    throw InputError("parameter 'tetgen' must name the TetGen program (got '')", Entity::Parameter);
  }
}

}  // namespace hexmerge
