#pragma once
/// @file
/// Moving free nodes of a tet mesh to raise the worst tet around them.

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

#include "hexmerge/geometry/vec3.h"
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
  /// On a surface: moved as a free node, but along the surface through it (SurfacePath), as a
  /// boundary node inside a CAD face.
  kOnSurface = 3,
};

/// The surface kOnSurface nodes move along (the CAD face through each): positions by lengths
/// along the surface's two parameter directions from where the node stands.
class SurfacePath {
 public:
  virtual ~SurfacePath() = default;
  /// The dimension of the path node v may move along: 2 a surface, 1 a curve (its second
  /// parameter direction unused), 0 none.
  virtual int dimension(index_t v) const = 0;
  /// Unit tangents along the surface's two parameters at node v, where it stands.
  virtual void tangents(index_t v, Vec3& along_u, Vec3& along_v) const = 0;
  /// The surface's point at lengths (a, b) along those tangents from node v (its parameters
  /// offset by a / |dS/du| and b / |dS/dv|); false where that leaves the surface's domain.
  virtual bool at(index_t v, double a, double b, Vec3& point) const = 0;
  /// Node v was left at (a, b) from where it stood: its parameters follow.
  virtual void moved(index_t v, double a, double b) = 0;
};

/// How smooth_nodes() works.
struct SmoothNodesParameters {
  /// Free nodes with a tet below this scaled Jacobian around them are moved, in (0, 1].
  double target = 0.3;
  /// Nudged nodes with a tet below this scaled Jacobian around them are moved, in (0, 1].
  double nudge_target = 0.2;
  /// Nodes on a surface take a position only where no more of their tets than before are below
  /// this (a node of the boundary moves its triangles too: the worst tet alone raised, others
  /// fell below the floor); the others end their search at the last position that left no more
  /// there than before.
  double floor = 0.2;
  /// Passes over the nodes, at least 1; a pass that moves nothing ends the run.
  int max_passes = 4;
  /// A move of a kept pyramid's apex (smooth_nodes()' `pyramids`) leaves the pyramid's scaled
  /// Jacobian at least this, or no lower than it was where it was below: the elements that rely
  /// on the apex stay acceptable to the recombination. In (0, 1].
  double pyramid_floor = 0.3;
};

/// What smooth_nodes() did.
struct SmoothNodesReport {
  double min_before = 0.0;        ///< smallest scaled Jacobian of a tet, before
  double min_after = 0.0;         ///< and after
  std::size_t moves = 0;          ///< node moves done
  std::size_t surface_moves = 0;  ///< of those, of nodes on a surface (kOnSurface)
};

/// Raises the smallest scaled Jacobian (quality.h) of the tets around free nodes by moving those
/// nodes: a compass search (the axis and diagonal directions and the centroid of the node's
/// neighbours, steps from a quarter of its shortest edge down to a thousandth) that takes a
/// position only when the worst tet around the node gets strictly better. Nudged nodes: the
/// same search without the centroid, from a twentieth of the shortest edge, ended as soon as
/// the worst tet reaches `nudge_target`. Nodes on a surface: the free nodes' search in the
/// surface's two parameter directions and their diagonals (on a curve: its one direction; the
/// centroid taken along the tangents), each position tried on the path. Only the tets around
/// a moved node change, so the mesh's minimum never decreases and no tet turns over. The tets
/// stay as they are (no flips; see remove_slivers()). A node that is the apex of some of
/// `pyramids` takes a position only where each of them keeps `pyramid_floor`.
///
/// @param[in,out] mesh        a valid tet mesh (validate_tet_mesh); only `points` change
/// @param[in]     movable     #V NodeMobility values: the nodes that may move and how (say,
///                            interior nodes that carry no geometry); the caller keeps boundary
///                            nodes out
/// @param[in]     parameters  see SmoothNodesParameters
/// @param[out]    report      the minimum before and after, the moves
/// @param[in,out] surface     where kOnSurface nodes go (null: they stay)
/// @param[in]     pyramids    pyramids to keep (cell_type.h's order: base 0-1-2-3, apex 4),
///                            each the union of tets of the mesh, positively oriented
/// @param[in,out] settled     null, or #V flags: in, nodes whose search would leave them where
///                            they stand (the caller vouches: no tet at the node was added or
///                            removed, nor its mobility, the parameters or the pyramids at it
///                            changed, since a call left it flagged),
///                            which are not searched until a node of a tet at them moves; out,
///                            the same as the mesh stands. The moves made do not depend on it.
/// @param[in]     keeps       empty, or whether the elements made of the mesh's tets that rely on
///                            node v stay acceptable where it stands now (asked of a position
///                            that is otherwise better): a node takes no position it refuses
/// @throws InputError for a `movable` or `settled` of another size than #V, a pyramid with a
///         node out of range, or bad parameters
void smooth_nodes(TetMesh& mesh, const std::vector<char>& movable,
                  const SmoothNodesParameters& parameters, SmoothNodesReport& report,
                  SurfacePath* surface = nullptr,
                  const std::vector<std::array<index_t, 5>>& pyramids = {},
                  std::vector<char>* settled = nullptr,
                  const std::function<bool(index_t)>& keeps = {});

}  // namespace hexmerge
