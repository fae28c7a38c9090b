#pragma once
/// @file
/// Pairs of tet faces that can form one quadrilateral face of an element: two outward
/// triangles of two different tets sharing an edge (run in opposite directions), flat enough
/// and with corner angles small enough. Computed once, so that the search programs' QUAD
/// instructions are look-ups.

#include <array>
#include <cstdint>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge {

/// Outward triangle of face f of tet t (the face opposite its local vertex f, cell_type.h).
std::array<index_t, 3> tet_face(const TetMesh& mesh, index_t t, int f);

/// The quad (x, w, y, z) made of outward triangles (x, y, z) and (y, x, w): its diagonal x-y is
/// positions 0 and 2, and it is outward like them. False when the triangles do not share exactly
/// one edge run in opposite directions.
bool quad_from_triangles(const std::array<index_t, 3>& t1, const std::array<index_t, 3>& t2,
                         std::array<index_t, 4>& quad);

/// One acceptable partner of a tet face.
struct QuadPartner {
  index_t face;  ///< the partner as 4 * tet + local face
};

/// For every face of every tet, its acceptable quad partners (CSR).
class QuadPairs {
 public:
  /// @param[in] min_dihedral_angle           degrees, the paper's dangle
  /// @param[in] min_boundary_dihedral_angle  degrees, dangle when both triangles are on the
  ///                                         domain boundary
  /// @param[in] max_face_angle               degrees, the paper's fangle
  /// @param[in] threads                      worker threads (>= 1)
  /// @param[in] region_interfaces_are_boundary  a face between tets of two regions takes the
  ///                                         boundary's dangle (when regions are kept apart,
  ///                                         the interface is each region's boundary: a bent
  ///                                         quad there would move volume between regions)
  QuadPairs(const TetMesh& mesh, const TetTopology& topology, double min_dihedral_angle,
            double min_boundary_dihedral_angle, double max_face_angle, int threads,
            bool region_interfaces_are_boundary);

  /// The partners of face f of tet t: [begin, end). Pointer arithmetic on data(), never
  /// operator[]: end() of the last face is one past the last partner, and `partners_` may be
  /// empty.
  const QuadPartner* begin(index_t t, int f) const {
    return partners_.data() + offsets_[4 * std::size_t(t) + f];
  }
  const QuadPartner* end(index_t t, int f) const {
    return partners_.data() + offsets_[4 * std::size_t(t) + f + 1];
  }
  /// Bit f set when face f of tet t has at least one partner.
  unsigned char mask(index_t t) const { return masks_[t]; }
  /// False when no face of tet t has a partner on tet s; true when one may (a 64-bit filter on
  /// the partners' ids modulo 64: exact for tets with ids close to each other).
  bool may_pair(index_t t, index_t s) const { return (partner_bits_[t] >> (s & 63u)) & 1u; }
  std::size_t size() const { return partners_.size(); }

 private:
  std::vector<index_t> offsets_;  // 4 * #T + 1
  std::vector<QuadPartner> partners_;
  std::vector<unsigned char> masks_;
  std::vector<std::uint64_t> partner_bits_;
};

}  // namespace hexmerge
