#pragma once
/// @file
/// The post-merge stage (Meshkat & Talmor, section 4.3: transformations that change the tet mesh
/// under a merged mesh): flips that close the open quad faces of hexahedron candidates, so that
/// a conforming selection can take them, and the census of the candidates that can be closed.
///
/// A quad face of a hexahedron candidate is *closed by the tets* when it lies on the domain
/// boundary (both triangles), or when the two tets behind its triangles share their fourth vertex
/// and so form a pyramid that passes the acceptance (one region, scaled Jacobian, the pyramid
/// placement). Otherwise the tets behind it turn around its diagonal a-c in a fan b, x1, ..., xk,
/// d (k >= 2). Each xi but one (the apex kept) is taken out of the fan by one flip of tets outside
/// the candidate: a 2-3 flip of face (a, c, xi), a 3-2 flip of edge (a, xi) or (c, xi), or a 4-4
/// flip of one of those edges; failing those (with contract_edges), the paper's edge contraction:
/// xi, an inner node, merged into its neighbour along the fan. Flips keep every node, a
/// contraction leaves one inner node unused; both keep every boundary triangle and every region's
/// volume; every new tet is positively oriented, in the region of the tets it replaces, with a
/// scaled Jacobian of at least the floor given. With move_nodes, a refused flip or contraction is
/// tried again with one inner node moved (every tet at it stays positive, none falls below the
/// floor or, if it was below, below itself), and an apex whose pyramid falls short of the
/// acceptance is moved to lift it: the paper's smoothing.

#include <cstddef>
#include <vector>

#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/postmerge/flip_mesh.h"
#include "hexmerge/recombine/select/select_candidates.h"

namespace hexmerge {

/// recombine() looks for liftable hexahedron candidates with the minimum dihedral angle lowered
/// by this many degrees, the maximum face angle raised by as many, and this minimum scaled
/// Jacobian.
constexpr double kLiftAngle = 15.0;
constexpr double kLiftScaledJacobian = 0.15;

struct PostMergeOptions {
  double min_pyramid_quality = 0.3;  ///< scaled Jacobian of a closing pyramid
  double min_tet_quality = 0.3;      ///< scaled Jacobian of every tet a flip makes
  PyramidPlacement placement = PyramidPlacement::Anywhere;
  /// Longest fan of tets behind a quad face that is worked on (k + 1 tets): bounds the flips per
  /// face to max_fan - 2 and the apexes tried to max_fan - 1.
  int max_fan = 6;
  /// When no flip takes a vertex out of the fan, contract it into a neighbour along the fan
  /// (FlipMesh::contract: inner nodes only; the node leaves the mesh).
  bool contract_edges = false;
  /// Node moves (the paper's smoothing; FlipMesh::smooth, inner nodes only): a flip or
  /// contraction refused because a new tet would invert or fall below min_tet_quality is tried
  /// again with one of its nodes moved, and a pyramid apex whose pyramid fails
  /// min_pyramid_quality is moved to lift it.
  bool move_nodes = false;
  /// A move may not make a protected candidate at the node (close_open_quads) that passed the
  /// acceptance fail it (its tets alive and not about to be replaced): its scaled Jacobian stays at
  /// least min_pyramid_quality (or its own, when lower), and each of its quad faces at the node at
  /// least this dihedral angle across its diagonal and at most max_face_angle at its corners
  /// (degrees; the moved node is inside the domain, so its quads are inner ones).
  double min_dihedral_angle = 150.0;
  double max_face_angle = 150.0;
  /// The paper's vertex split (FlipMesh::split; inner nodes only, one node added each): after
  /// the hexahedra are closed, a prism candidate and the pyramid closing one of its quad faces
  /// become a hexahedron when the pyramid's apex is split into an edge (the pyramid then a
  /// second prism on that face), kept when the hexahedron passes the acceptance and its quad
  /// faces close as any other's.
  bool split_nodes = false;
};

/// Hexahedron candidates, and those whose every quad face the tets close as they are.
struct QuadCensus {
  std::size_t hex_candidates = 0;
  std::size_t closable = 0;
};

/// The census on `mesh` (candidates found on it; their tet ids are the mesh's).
QuadCensus quad_census(const TetMesh& mesh, const Candidates& candidates,
                       const PostMergeOptions& options);

struct PostMergeResult {
  TetMesh tets;                    ///< the tets after the flips (points as moved, compact)
  FlipCounts flips;                ///< flips, contractions and node moves kept
  std::size_t attempted = 0;       ///< hexahedron candidates worked on (each once)
  std::size_t closed = 0;          ///< of them: every quad face closed, by at least one flip
  std::size_t already_closed = 0;  ///< of them: every quad face closed as the tets were
  /// Of the closed: liftable candidates that a node move made pass the acceptance.
  std::size_t lifted = 0;
  /// Hexahedra made of a prism and a pyramid by a vertex split, their quad faces closed
  /// (split_nodes; flips.splits of them).
  std::size_t split_hexes = 0;
};

/// Works on the hexahedron candidates of `candidates` (found on `mesh`, any pruning), best
/// scaled Jacobian first, after those already closed: the tets of `selection`'s hexahedra
/// (indices into `selected_from`) and of the elements on their quad faces are kept as they are;
/// for each other candidate whose tets are all still there, each open quad face is closed by
/// flips of tets that no kept candidate or closing pyramid holds. When every face closes, its
/// tets and pyramids are kept; otherwise every flip made for it is undone and it is not tried
/// again. Work: at most (max_fan - 1)^2 flips tried per face.
/// With move_nodes, `liftable` (hexahedron candidates found with looser bounds: recombine()
/// uses kLiftAngle and kLiftScaledJacobian) are worked on too, in the same order: one that fails
/// the acceptance is first made to pass it by moving one of its nodes (Stage::lift), then closed as
/// the others. Every node move keeps the hexahedron candidates of `candidates` and the selection's
/// elements that pass the acceptance passing it (PostMergeOptions::min_dihedral_angle).
/// With split_nodes, then, the prism candidates of `candidates` whose tets are all still free,
/// best scaled Jacobian first: each quad face closed by a pyramid whose apex is an inner node is
/// tried for a vertex split that makes the prism and the pyramid one hexahedron (see
/// PostMergeOptions::split_nodes); its faces are closed as above, or the split is undone.
PostMergeResult close_open_quads(const TetMesh& mesh, const Candidates& candidates,
                                 const Candidates& selected_from, const Selection& selection,
                                 const PostMergeOptions& options,
                                 const Candidates& liftable = Candidates{});

}  // namespace hexmerge
