#pragma once
/// @file
/// How far a selection is from the best one: the selection solved as an integer program (set
/// packing) with GLPK, time-limited, for a bound on the fewest elements any selection of the same
/// candidates can reach.
///
/// The program: maximise the elements saved, sum over chosen candidates c of (nb_tets(c) - 1),
/// subject to every tet lying in at most one chosen candidate (set packing). Without conformity
/// rows its optimum is a bound for every conformity mode: no selection of these candidates,
/// conforming or not, has fewer elements than `bound_elements`. With the conformity rows of
/// conformity_rows() it bounds the conforming selections only (a tighter bound).

#include <cstddef>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"

namespace hexmerge {

/// The outcome of bound_selection.
struct SelectionBound {
  /// Fewest elements (cells, tets included) any selection of the candidates can reach: the
  /// number of tets minus the best bound on the elements saved (the LP relaxation's, or the
  /// branch-and-bound's best open node's, whichever is smaller), rounded to a whole count.
  std::size_t bound_elements = 0;
  /// Elements of the best selection the solver found (at least as good as `initial`'s).
  std::size_t best_elements = 0;
  std::vector<index_t> best;        ///< that selection, as candidate indices; tet sets disjoint
  bool proved = false;              ///< the solver finished: best_elements == bound_elements
  std::size_t conformity_rows = 0;  ///< conformity rows in the program
  std::size_t dropped_rows = 0;     ///< conformity rows left out because `initial` breaks them
  double seconds = 0.0;             ///< wall time of the solve
};

/// One conformity row: choosing `candidate` needs one of `partners` chosen as well
/// (x_candidate <= sum of x_partners).
struct ConformityRow {
  index_t candidate;
  std::vector<index_t> partners;
};

/// The conformity rows of conforming mode: for every quad face of a candidate whose two triangles
/// both have a tet on their far side, the candidates with a quad face on the same four vertices
/// (an element chosen on the far side must close it: select_candidates.h). A quad face on the
/// domain boundary, or one the rule cannot read plainly (not exactly two of the candidate's tet
/// faces on it), gets no row: leaving a row out only loosens the bound, never breaks it.
std::vector<ConformityRow> conformity_rows(const TetMesh& mesh, const TetTopology& topology,
                                           const Candidates& candidates);

/// True when HexMerge was built with GLPK (CMake option HEXMERGE_WITH_GLPK and libglpk-dev).
bool selection_bound_available();

/// Throws InputError (Entity::Parameter, naming optimality_bound) unless
/// selection_bound_available().
void require_selection_bound();

/// Solves the selection of disjoint candidates as an integer program (GLPK's branch and cut,
/// started from the LP relaxation) within a time limit.
///
/// @param[in] nb_tets       tets of the mesh the candidates were found in
/// @param[in] candidates    the candidates (find_candidates.h)
/// @param[in] initial       a feasible selection (disjoint candidates) handed to the solver as its
///                          first incumbent; may be empty
/// @param[in] time_limit    seconds (> 0); past it, the best bound and solution so far are returned
/// @param[in] conformity    rows added to the packing (conformity_rows()); empty: none. Rows that
///                          `initial` breaks are left out, so that it stays a solution.
/// Throws InputError (Entity::Parameter, naming optimality_bound) when GLPK is not compiled in.
SelectionBound bound_selection(index_t nb_tets, const Candidates& candidates,
                               const std::vector<index_t>& initial, double time_limit,
                               const std::vector<ConformityRow>& conformity = {});

/// The outcome of bound_hex_volume.
struct VolumeBound {
  /// No selection of the candidates gives hexahedra more than this share of the mesh's volume:
  /// the integer program's optimum when proved, else the smaller of its LP relaxation's and the
  /// branch-and-bound's best open node's bound.
  double bound = 0.0;
  double best = 0.0;          ///< share of the best set of disjoint hexahedra the solver found
  bool proved = false;        ///< the solver finished: best == bound
  std::size_t hexahedra = 0;  ///< hexahedron candidates in the program
  double seconds = 0.0;       ///< wall time of the solve
};

/// The largest share of the mesh's volume that the hexahedra of any selection of `candidates` can
/// fill: the hexahedra must have disjoint tets (set packing weighted by volume, GLPK,
/// time-limited). It ignores what the other elements need, so it is an upper bound on the
/// hexahedron volume of every selection. Given the candidates left by prune_unclosable, it bounds
/// the conforming selections, whatever the selection strategy. Throws InputError
/// (Entity::Parameter, naming optimality_bound) when GLPK is not compiled in.
VolumeBound bound_hex_volume(const TetMesh& mesh, const Candidates& candidates, double time_limit);

}  // namespace hexmerge
