#include <limits>

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
      whole(&P::boundary_layers, "boundary_layers", "", 0, 3, "Boundary layers",
            "Layers of points offset from the curved and unaligned faces along the inward "
            "normal, so that the boundary becomes prisms",
            {"--layers"}),
      number(&P::layer_thickness, "layer_thickness", "h", 0.1, 1, "Layer thickness",
             "Thickness of one boundary layer, as a fraction of the target size h"),
      number(&P::lattice_margin, "lattice_margin", "h", 0.1, 2, "Lattice margin",
             "Lattice points nearer than this to a face off the lattice planes (or to the "
             "outermost boundary layer) are dropped; a fraction of h"),
      number(&P::surface_deflection, "surface_deflection", "h", 0.001, 0.5, "Surface deflection",
             "Chord deflection of the surface triangulation on curved faces, as a fraction of h"),
      choice(&P::frame, "frame", {"auto", "principal", "global"}, "Lattice frame",
             "Orientation of the lattice: auto (normals of the largest planar faces, else the "
             "principal axes of inertia), principal (principal axes of inertia), global (x, y, z)",
             {"", "LatticeFrame"}),
      flag(&P::sweep, "sweep", "Sweep extrusions",
           "Where the shape is one cross-section extruded along a lattice axis between two "
           "planar caps (plates with holes, cylinders, profiles; one solid or several), sweep "
           "the tets too: the same cross-section on every lattice plane, so that they recombine "
           "into hexahedra and prisms only"),
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
  });
}

}  // namespace

const ParameterTable<MeshShapeParameters>& mesh_shape_parameter_table() {
  static const ParameterTable<MeshShapeParameters> table = make_table();
  return table;
}

void validate_mesh_shape_parameters(const MeshShapeParameters& parameters) {
  mesh_shape_parameter_table().validate(parameters);
  if (parameters.tetgen.empty()) {
    throw InputError("parameter 'tetgen' must name the TetGen program (got '')", Entity::Parameter);
  }
}

}  // namespace hexmerge
