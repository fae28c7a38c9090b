#pragma once
/// @file
/// Candidate elements: every hex, prism and pyramid that a group of tets forms and that passes
/// the geometric acceptance, found by running the compiled search programs from every tet.

#include <array>
#include <cstdint>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/candidates.h"

namespace hexmerge {

/// The sorted vertices of a face of a candidate's cell (NO_VERTEX past a triangle's three): equal
/// for two cells exactly when they share that face. Inline, a sorting network: the selection's
/// groups ask for keys in their inner loops (as a call, 10 % of the samples on Gmsh's frontal
/// tets of the box at 100k).
using FaceKey = std::array<index_t, 4>;

/// Four ids in increasing order (a sorting network of five branch-free compare-exchanges).
inline FaceKey sorted4(FaceKey k) {
  const auto order = [&k](int i, int j) {
    const index_t lo = k[i] < k[j] ? k[i] : k[j];
    k[j] = k[i] < k[j] ? k[j] : k[i];
    k[i] = lo;
  };
  order(0, 1);
  order(2, 3);
  order(0, 2);
  order(1, 3);
  order(1, 2);
  return k;
}

inline FaceKey face_key(const Candidate& c, int f) {
  const CellDescriptor& d = descriptor(c.type);
  const std::array<int, 4>& face = d.face[f];
  return sorted4({c.vertices[face[0]], c.vertices[face[1]], c.vertices[face[2]],
                  d.face_size[f] == 4 ? c.vertices[face[3]] : NO_VERTEX});
}

/// What a candidate must satisfy.
struct AcceptanceCriteria {
  double min_dihedral_angle = 150.0;           ///< degrees
  double min_boundary_dihedral_angle = 179.0;  ///< degrees, quads on the domain boundary
  double max_face_angle = 150.0;               ///< degrees
  double min_scaled_jacobian = 0.3;
  /// Between this and min_scaled_jacobian, a hex or prism at least as good as the worst tet it
  /// replaces passes
  double lowest_scaled_jacobian = 0.0;
  bool respect_regions = true;
  std::array<bool, NB_CELL_TYPES> types{{false, true, true, true}};  ///< by CellType
};

/// Whether a new element of type `type` and scaled Jacobian `sj` made of the tets `tets`
/// (nb_tets of them, ids into `mesh`) is good enough: at least min_scaled_jacobian, or, a hex or
/// prism, at least lowest_scaled_jacobian (and kMinElementScaledJacobian) and the worst of its
/// tets' scaled Jacobians.
bool good_enough(const AcceptanceCriteria& criteria, const TetMesh& mesh, CellType type, double sj,
                 const index_t* tets, int nb_tets);

/// Runs every search program (rf_graph.h) from every tet.
///
/// Each group of tets is reported once (from its smallest tet), per distinct element it forms.
/// The order of the result does not depend on the number of threads. (The search runs on a copy
/// of the mesh renumbered along a space-filling curve, spatial_order.h, for the cache; the
/// result names the input's tets, in the order a search on the input itself gives.)
/// @param[in] threads  worker threads (>= 1)
Candidates find_candidates(const TetMesh& mesh, const TetTopology& topology,
                           const AcceptanceCriteria& criteria, int threads,
                           const ProgressCallback& progress = {});

/// Builds the cell formed by a group of tets, given which of the group's boundary triangles pair
/// into quads, and checks it: the group's boundary must be exactly the cell's faces (triangles
/// as such, quads as two triangles on one diagonal). Returns false when it is not a valid cell
/// of that type. Exposed for the tests and the other finders.
/// @param[in]  tets        the group (nb entries)
/// @param[in]  quad_pairs     pairs of boundary triangles as (4 * tet + face) codes, one per quad
/// @param[in]  nb_quad_pairs  their number
/// @param[out] vertices       the cell's vertices in local order
bool assemble_cell(const TetMesh& mesh, const TetTopology& topology, CellType type,
                   const index_t* tets, int nb, const std::array<index_t, 2>* quad_pairs,
                   int nb_quad_pairs, std::array<index_t, 8>& vertices);

}  // namespace hexmerge
