#pragma once
/// @file
/// The ways mesh_shape() places its points (internal header): the table it tries in order until
/// TetGen tetrahedralises the input, the simplest input last.

#include "hexmerge/occ/mesh_shape.h"

namespace hexmerge::mesher {

/// How one attempt places its points. mesh_shape() tries them in this order until TetGen
/// tetrahedralises the input; the later ones hand TetGen simpler input (no planar facets holding
/// lattice points, on which TetGen 1.5 fails for some shapes and sizes; no boundary layers; no
/// points inside at all, TetGen adding its own) and give fewer hexahedra.
struct Strategy {
  const char* name;
  double size_factor;   // the lattice spacing and surface size: this times the size asked for
  bool lattice_faces;   // planar faces on lattice planes carry lattice points (and sweeps)
  bool layers;          // boundary-layer points
  bool lattice_points;  // lattice points inside the shape (the hexahedral core)
  bool pull;            // the core pulled towards the surface (MeshShapeParameters::pull_core)
  // The surface's chord deflection: this times MeshShapeParameters::surface_deflection. A way
  // with a finer one is tried only when a way on the finest tried before failed on a surface too
  // coarse for it.
  double deflection_factor = 1.0;
  bool buffer = false;  // the buffer layer (MeshShapeParameters::buffer_layer)
};
/// TetGen's failures on the lattice come and go with the size (FreeCAD's plate with a hole fails
/// at h 2.25, 2.375 and 2.5 and meshes at 2.75 and 3), so the lattice is tried at a slightly finer
/// and a slightly coarser size before it is simplified (which costs most of the hexahedra).
/// The core pulled towards the surface with a buffer layer is tried first, then without the
/// layer, then the lattice as it is.
constexpr Strategy kStrategies[] = {
    {"lattice", 1.0, true, true, true, true, 1.0, true},
    {"lattice without the buffer layer", 1.0, true, true, true, true},
    {"lattice, core not pulled", 1.0, true, true, true, false},
    // Where a way's surface was too coarse (faces closer than the chord deflection that the
    // crossing rounds do not part, walls the swaps moved past their thickness), the surface at a
    // quarter of the deflection before the sizes change: a random part's 2.8 mm rib with a sphere
    // of radius 2.6 cut into it crossed in every way at h 35 to 60 and meshes so.
    {"lattice on a surface of a quarter of the chord deflection", 1.0, true, true, true, false,
     0.25},
    // Where that one too was too coarse, an eighth: a random part's cylinder of radius 5.64 and a
    // fillet of radius 0.45 beside it, closer than the chord deflection at h 6, cross on a
    // quarter and mesh so.
    {"lattice on a surface of an eighth of the chord deflection", 1.0, true, true, true, false,
     0.125},
    {"lattice at 0.95 of the size", 0.95, true, true, true, false},
    {"lattice at 1.1 of the size", 1.1, true, true, true, false},
    {"lattice without lattice faces", 1.0, false, true, true, false},
    {"lattice without boundary layers", 1.0, false, false, true, false},
    {"surface only", 1.0, false, false, false, false},
};

/// The boundary layers a way places: none where the way places none, else the ones asked for;
/// -1 (the default): one on swept shapes, none on the others.
inline int boundary_layers_placed(const MeshShapeParameters& parameters, const Strategy& strategy,
                                  bool swept) {
  if (!strategy.layers) return 0;
  if (parameters.boundary_layers >= 0) return parameters.boundary_layers;
  return swept ? 1 : 0;
}

}  // namespace hexmerge::mesher
