#pragma once
/// @file
/// Boundary-layer points (internal header of mesh_shape(); no OpenCASCADE): the surface's nodes
/// where the surface is smooth, moved along the inward normal by up to `layers` layer depths,
/// where there is room, so that TetGen's tets there recombine into prisms.

#include <cstddef>
#include <string>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/mesher/lattice.h"
#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/occ/mesher/sweep.h"

namespace hexmerge::mesher {

/// Boundary layers asked on some faces (MeshShapeParameters::face_layers), on the shape's faces.
struct FaceLayerSpec {
  std::vector<int> faces;  ///< the shape's faces (0-based)
  int layers = 0;          ///< layers of points
  double thickness = 0.0;  ///< the first layer's depth (a length)
  double growth = 1.0;     ///< each layer's depth over the one before

  /// The depth of layer k (1-based) from the face: thickness (1 + growth + ... + growth^(k-1)).
  double depth(int k) const;
};

/// "Face3,Face5": faces numbered from 1.
std::string faces_text(const std::vector<int>& faces);

/// The face layers on the shape's faces, checked: faces that exist, a first layer not thicker
/// than h.
/// @throws InputError (Entity::Parameter) naming the entry otherwise
std::vector<FaceLayerSpec> face_layer_specs(const std::vector<FaceLayers>& entries,
                                            const ItemNumbering& faces, double h);

/// Fails naming the first face-layer entry whose faces got no point in the first layer: no node
/// of theirs off their edges, or no room anywhere.
/// @throws InputError (Entity::Parameter)
void check_face_layers_placed(const std::vector<FaceLayers>& entries,
                              const std::vector<FaceLayersApplied>& applied, double h);

/// Drops the kept lattice points nearer to a face of `specs` than its layers' depth (grown by
/// the depths' variation) plus `margin` plus half a lattice cell, so that the core, its closing
/// pyramids' apexes and their circumspheres keep out of the face layers.
/// @param[in] nodes  the surface's nodes in frame coordinates
/// @return the number of points dropped
std::size_t clear_face_layers(const std::vector<FaceLayerSpec>& specs,
                              const std::vector<Vec3>& nodes, const Surface& surface,
                              const Lattice& lattice, const Surroundings& around, double margin,
                              KeptPoints& kept);

/// Places the boundary-layer points, appending them to `inserted` and to around.layer_points.
/// Nodes of lattice faces and of faces between two solids get none (swept: the walls between
/// two solids get layers on both sides); depths vary by up to 10 % per node (from
/// Surface::seed) so that the layers' sides are not cocircular quads. A point is placed only
/// inside the shape (`parity`) and clear of every face by half its depth; when the core is laid
/// first (emit_core()), out of its cells' and closing pyramids' circumspheres and at least
/// `core_margin` from its points.
/// @param[in] nodes             the surface's nodes in frame coordinates
/// @param[in] face_solid_count  per face, the solids it bounds
/// @param[in] sweep_axis        the sweep's axis, -1: not swept (then `swept` is unused)
/// @param[in] layers            number of layers (0 to 3)
/// @param[in] thickness         one layer's depth (a length)
/// @param[in] core_margin       the least distance from a core point (a length)
/// @param[in] no_layers         per node, 1 where it gets no layers (null: none such; local sizes:
///                              the nodes where the size wanted is below h)
/// @param[in] face_layers       the faces with layers of their own: their nodes (those of the first
///                              spec holding one of its faces) take that spec's layers, depths
///                              and growth instead, no_layers or not, a layer only where the node
///                              got the one before; swept, on walls only, placed on the first
///                              plane and repeated. Their points are placed after the global
///                              layers' and come last in `inserted`
/// @param[out] applied          per spec, its counts (nodes, faces, layers, thickness and growth
///                              left to the caller); resized to face_layers' size
/// @return the number of points placed
std::size_t place_layers(const std::vector<Vec3>& nodes, const Surface& surface,
                         const std::vector<int>& face_solid_count, const Lattice& lattice,
                         int sweep_axis, const SweptSurface& swept, int layers, double thickness,
                         double core_margin, const Parity& parity, Surroundings& around,
                         InsertedPoints& inserted, const std::vector<char>* no_layers = nullptr,
                         const std::vector<FaceLayerSpec>& face_layers = {},
                         std::vector<FaceLayersApplied>* applied = nullptr);

}  // namespace hexmerge::mesher
