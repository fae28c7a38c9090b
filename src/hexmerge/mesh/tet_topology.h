#pragma once
/// @file
/// Face adjacency of a tetrahedral mesh.

#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// Tet-to-tet adjacency through faces. Face f of tet t is the face opposite its local vertex f
/// (table in cell_type.h). neighbor(t, f) is the tet across that face, or NO_CELL on the boundary
/// of the domain. Faces between tets of different regions keep their neighbour: region
/// boundaries are decided by the caller.
class TetTopology {
 public:
  /// Builds the adjacency. Throws InputError when a face is shared by three or more tets, or
  /// by two tets on the same side of it (a fold; the tets must be positively oriented), naming
  /// one of them. Linear in the number of tets.
  explicit TetTopology(const TetMesh& mesh);

  /// The adjacency of reorder_tets(mesh, order) (spatial_order.h), from this one without a
  /// search: tet i of the result is tet order[i] here.
  TetTopology reordered(const std::vector<index_t>& order) const;

  index_t neighbor(index_t t, int f) const {
    return neighbors_[4 * static_cast<std::size_t>(t) + f];
  }
  /// Local index, in the neighbour, of the face shared with t through face f (valid only when
  /// neighbor(t, f) != NO_CELL).
  int neighbor_face(index_t t, int f) const {
    return neighbor_faces_[4 * static_cast<std::size_t>(t) + f];
  }
  bool on_boundary(index_t t, int f) const { return neighbor(t, f) == NO_CELL; }
  /// True when at least one face of t is on the boundary of the domain.
  bool is_boundary_tet(index_t t) const;
  index_t nb_tets() const { return static_cast<index_t>(neighbors_.size() / 4); }
  std::size_t nb_boundary_faces() const { return nb_boundary_faces_; }

 private:
  TetTopology() = default;

  std::vector<index_t> neighbors_;
  std::vector<signed char> neighbor_faces_;
  std::size_t nb_boundary_faces_ = 0;
};

}  // namespace hexmerge
