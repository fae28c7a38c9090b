#pragma once
/// @file
/// The engine's output: a mesh of tets, pyramids, prisms and hexes as flat arrays.

#include <cstdint>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

/// A mixed linear mesh, compacted (no deleted cells). Cell c has type types[c] and vertices
/// cell_vertices[offsets[c] .. offsets[c+1]) in the local order of hexmerge/mesh/cell_type.h
/// (VTK's). Every cell also records the input tets it is the union of
/// (source_tets[source_offsets[c] .. source_offsets[c+1])), so volumes and regions can be traced.
struct MixedMesh {
  std::vector<double> points;           ///< #V by 3 (the input's points; see changed_nodes)
  std::vector<CellType> types;          ///< #C
  std::vector<index_t> offsets;         ///< #C + 1, offsets[0] = 0
  std::vector<index_t> cell_vertices;   ///< concatenated vertex lists
  std::vector<std::int32_t> regions;    ///< #C region ids (empty when the input had none)
  std::vector<index_t> source_offsets;  ///< #C + 1
  std::vector<index_t> source_tets;     ///< input tet ids of each cell
  /// Nodes the engine changed, sorted: input nodes it moved (points differ from the input's) or
  /// removed (used by no cell), and nodes it added (ids past the input's). Empty: the input's
  /// nodes untouched, all used (check_mesh then checks coordinates bit for bit).
  std::vector<index_t> changed_nodes;

  index_t nb_cells() const { return static_cast<index_t>(types.size()); }
  index_t nb_vertices() const { return static_cast<index_t>(points.size() / 3); }
  index_t cell_size(index_t c) const { return offsets[c + 1] - offsets[c]; }
  const index_t* cell(index_t c) const { return &cell_vertices[offsets[c]]; }
  std::int32_t region(index_t c) const { return regions.empty() ? 0 : regions[c]; }
};

}  // namespace hexmerge
