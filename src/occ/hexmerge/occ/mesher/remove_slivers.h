#pragma once
/// @file
/// Removal of badly shaped tets by flips: the points stay, the tets around them change.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// How remove_slivers() works.
struct RemoveSliversParameters {
  /// Tets whose scaled Jacobian is below this are worked on, in (0, 1].
  double target = 0.3;
  /// Passes over the tets below target, at least 1; a pass that flips nothing ends the run.
  int max_passes = 10;
  /// Largest number of tets around an edge that edge removal replaces, in [3, 10].
  int max_ring = 7;
  /// Two boundary triangles of one patch may swap their shared side when the lines of the old
  /// and the new side are no farther apart than this (the boundary moves by no more: on a curved
  /// patch, the chord's sagitta); 0: only triangles in one plane. >= 0.
  double max_boundary_shift = 0.0;
  /// A tet below this that no flip improves gets a vertex: the tets of a cavity around it
  /// (itself and the tets across its faces, or those and the tets across theirs; within its
  /// region, none fixed) are replaced by the tets joining the cavity's boundary faces to a new
  /// vertex inside, where the worst of them is best (Klingner and Shewchuk's vertex insertion).
  /// 0: never. In [0, 1].
  double insert_below = 0.0;
};

/// What remove_slivers() did.
struct RemoveSliversReport {
  double min_before = 0.0;         ///< smallest scaled Jacobian of a tet, before
  double min_after = 0.0;          ///< and after
  std::size_t below_before = 0;    ///< tets below the target, before
  std::size_t below_after = 0;     ///< and after
  std::size_t face_removals = 0;   ///< 2-3 flips done
  std::size_t edge_removals = 0;   ///< n-to-(2n-4) flips done (3-2, 4-4, ...), boundary included
  std::size_t boundary_swaps = 0;  ///< of which on a boundary edge (see max_boundary_shift)
  std::size_t insertions = 0;      ///< vertices inserted (see insert_below), appended to the points
};

/// What remove_slivers() knows of the mesh it leaves, for a caller that calls it again (between
/// rounds of node moves): the flips done do not depend on it, only the work.
struct RemoveSliversState {
  /// #T flags: in, tets that no flip improves as the mesh stands, not examined again until a
  /// tet at one of their vertices changes (the caller vouches for them: a tet near which a node
  /// moved since, one whose vertices or the other vertices of the tets around these moved, or
  /// a tet near it whose `fixed` flag changed, is not settled; empty: none); out, the same for
  /// the tets written.
  std::vector<char> settled;
  /// Out, #V flags (with the vertices inserted): the vertices at which a tet was added or
  /// removed.
  std::vector<char> touched;
};

/// Raises the smallest scaled Jacobian (quality.h) of a tet mesh by flips, Shewchuk's "face
/// removal" (two tets across a face become three around the edge joining their apexes) and
/// "edge removal" (the n tets around an interior edge become 2n - 4, the best triangulation of
/// the ring of their other vertices, found by dynamic programming). A flip is done only when the
/// smallest scaled Jacobian of the tets it makes is larger than that of the tets it replaces, so
/// the mesh's minimum never decreases. A tet no flip improves may get a new vertex inside
/// (insert_below; the points before stay where they are); faces between tets of two
/// regions and the tets marked `fixed` never change, nor does the boundary of the domain as a
/// surface: its triangles change only where two of them on one patch, in one plane or within
/// max_boundary_shift of it, swap their shared side (edge removal on a boundary edge, the ring
/// closed by the new side).
///
/// @param[in,out] mesh            a valid tet mesh (validate_tet_mesh); tets are renumbered,
///                                regions follow their tets, inserted vertices are appended
/// @param[in]     fixed           #T flags (or empty: none): tets kept as they are
/// @param[in]     boundary_patch  #T by 4 (or empty: no boundary triangle changes): the patch
///                                (say, the CAD face) of face f (opposite vertex f) of tet t when
///                                it is on the boundary, >= 0; -1: never changed
/// @param[in]     parameters      see RemoveSliversParameters
/// @param[out]    report      the minimum and the flips done
/// @param[in,out] state           null, or what the flips leave for the next call (see
///                                RemoveSliversState)
void remove_slivers(TetMesh& mesh, const std::vector<char>& fixed,
                    const std::vector<std::int32_t>& boundary_patch,
                    const RemoveSliversParameters& parameters, RemoveSliversReport& report,
                    RemoveSliversState* state = nullptr);

}  // namespace hexmerge
