#pragma once
/// @file
/// Moving free nodes of a tet mesh to raise the worst tet around them.

#include <cstddef>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// What smooth_nodes() may do with a node.
enum NodeMobility : char {
  kFixed = 0,  ///< the node stays
  kFree = 1,   ///< moved wherever its worst tet gets best (below `target`)
  /// Nudged: moved by small steps only while its worst tet is below `nudge_target`, and no
  /// further once it reaches it (a node that placed elements rely on, as the apex of a closing
  /// pyramid: the least move that makes its tets usable).
  kNudged = 2,
};

/// How smooth_nodes() works.
struct SmoothNodesParameters {
  /// Free nodes with a tet below this scaled Jacobian around them are moved, in (0, 1].
  double target = 0.3;
  /// Nudged nodes with a tet below this scaled Jacobian around them are moved, in (0, 1].
  double nudge_target = 0.2;
  /// Passes over the nodes, at least 1; a pass that moves nothing ends the run.
  int max_passes = 4;
};

/// What smooth_nodes() did.
struct SmoothNodesReport {
  double min_before = 0.0;  ///< smallest scaled Jacobian of a tet, before
  double min_after = 0.0;   ///< and after
  std::size_t moves = 0;    ///< node moves done
};

/// Raises the smallest scaled Jacobian (quality.h) of the tets around free nodes by moving those
/// nodes: a compass search (the axis and diagonal directions and the centroid of the node's
/// neighbours, steps from a quarter of its shortest edge down to a thousandth) that takes a
/// position only when the worst tet around the node gets strictly better. Nudged nodes: the
/// same search without the centroid, from a twentieth of the shortest edge, ended as soon as
/// the worst tet reaches `nudge_target`. Only the tets around
/// a moved node change, so the mesh's minimum never decreases and no tet turns over. The tets
/// stay as they are (no flips; see remove_slivers()).
///
/// @param[in,out] mesh        a valid tet mesh (validate_tet_mesh); only `points` change
/// @param[in]     movable     #V NodeMobility values: the nodes that may move and how (say,
///                            interior nodes that carry no geometry); the caller keeps boundary
///                            nodes out
/// @param[in]     parameters  see SmoothNodesParameters
/// @param[out]    report      the minimum before and after, the moves
/// @throws InputError for a `movable` of another size than #V or bad parameters
void smooth_nodes(TetMesh& mesh, const std::vector<char>& movable,
                  const SmoothNodesParameters& parameters, SmoothNodesReport& report);

}  // namespace hexmerge
