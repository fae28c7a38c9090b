#pragma once
/// @file
/// How far a selection is from the best one: the selection solved as an integer program (set
/// packing) with GLPK, time-limited, for a bound on the fewest elements any selection of the same
/// candidates can reach.
///
/// The program: maximise the elements saved, sum over chosen candidates c of (nb_tets(c) - 1),
/// subject to every tet lying in at most one chosen candidate. Conformity of quad faces is not a
/// constraint of it, so its optimum is a bound for every conformity mode: no selection of these
/// candidates, conforming or not, has fewer elements than `bound_elements`.

#include <cstddef>
#include <vector>

#include "hexmerge/core/index.h"
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
  std::vector<index_t> best;     ///< that selection, as candidate indices; tet sets disjoint
  bool proved = false;           ///< the solver finished: best_elements == bound_elements
  double seconds = 0.0;          ///< wall time of the solve
};

/// True when HexMerge was built with GLPK (CMake option HEXMERGE_WITH_GLPK and libglpk-dev).
bool selection_bound_available();

/// Solves the selection of disjoint candidates as an integer program (GLPK's branch and cut,
/// started from the LP relaxation) within a time limit.
///
/// @param[in] nb_tets       tets of the mesh the candidates were found in
/// @param[in] candidates    the candidates (find_candidates.h)
/// @param[in] initial       a feasible selection (disjoint candidates) handed to the solver as its
///                          first incumbent; may be empty
/// @param[in] time_limit    seconds (> 0); past it, the best bound and solution so far are returned
/// Throws InputError (Entity::Parameter, naming optimality_bound) when GLPK is not compiled in.
SelectionBound bound_selection(index_t nb_tets, const std::vector<Candidate>& candidates,
                               const std::vector<index_t>& initial, double time_limit);

}  // namespace hexmerge
