#pragma once
/// @file
/// Choosing which candidates become elements: the global strategy of Meshkat & Talmor,
/// section 4, with conformity of quad faces as a constraint of the choice.

#include <cstddef>
#include <string>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge {

/// The chosen elements, as indices into the candidate array, and how the choice went.
struct Selection {
  std::vector<index_t> elements;        ///< chosen candidates; their tet sets are disjoint
  std::size_t nonconforming_quads = 0;  ///< quad faces left meeting two triangles
  std::size_t block_hexahedra = 0;      ///< hexahedra chosen in the block, before the greedy
  std::size_t group_seeds = 0;          ///< conforming groups: seeds tried
  std::size_t groups = 0;               ///< conforming groups: accepted
  std::size_t group_hexahedra = 0;      ///< hexahedra in the accepted groups
  std::size_t groups_failed = 0;        ///< groups rolled back: a face nothing could close
  std::size_t groups_capped = 0;        ///< groups given up at group_size members
  std::size_t closing_pyramids = 0;     ///< pyramids chosen to close a quad face
  std::size_t released_elements = 0;    ///< elements given up to restore conformity
  std::size_t local_moves = 0;          ///< accepted local optimisation moves (section 4.2)
  std::size_t swap_moves = 0;           ///< local search: accepted swaps of one element
  std::size_t reselection_moves = 0;    ///< local search: accepted neighbourhood re-selections
  std::size_t local_search_saved = 0;   ///< elements the local search removed
  std::size_t local_search_nodes = 0;   ///< local search: branch-and-bound nodes in all
  std::string strategy;                 ///< conforming mode: "safe_pyramids" or "closable"
};

/// Chooses disjoint candidates, on the calling thread, in these steps (Selector::run; each
/// step's code is named in select/selector.h):
///
/// 0. The block (conforming mode only): the near-perfect hexahedra (scaled Jacobian >= 0.9) and
///    the hexahedra and prisms with planar quad faces that can all be kept together, every open
///    quad face of them closable by a pyramid no other quad needs, chosen at once.
/// 0b. Conforming groups (conforming mode with pyramids, group_size > 0): from each hexahedron
///    candidate, then each prism candidate, best scaled Jacobian first, a group is grown: each
///    quad face of a member lies on the domain boundary, on the identical quad face of a chosen
///    element or member, or over the two tets of a pyramid no other quad needs (reserved, as in
///    the greedy); any other quad face gets a partner, the best available hexahedron (else
///    prism) with that quad that meets nothing chosen badly (fewest open quads, then quality),
///    which joins the group. The group is kept whole when every face is closed, else rolled
///    back (the move journal): a hexahedron whose faces only other hexahedra can close is taken
///    with them, where one at a time it never is. Each candidate seeds once; a group that would
///    need more than group_size members is given up (report: group_seeds, groups,
///    groups_failed, groups_capped, group_hexahedra).
/// 1. Exhaustive-greedy over boundary tets (tets with a face on the domain boundary or, when
///    regions are respected, on a region boundary): hexes, then prisms, then pyramids. With
///    boundary_order = quality (the default) every candidate holding a boundary tet, best scaled
///    Jacobian first; with fewest_matches (the paper's) the boundary tet with the fewest
///    remaining candidates first, and there the candidate with the fewest non-conformities, then
///    the best scaled Jacobian.
/// 2. Local optimisation (section 4.2, parameter local_optimisation) at every boundary tet left
///    unmatched: take one of its candidates in place of the elements in the way, refill the
///    freed tets greedily, keep the change only when it removes more elements.
/// 3. Greedy over the interior, in breadth-first order from the boundary: hexes, prisms,
///    pyramids (in last_resort mode then again, non-conforming ones allowed).
/// 4. Quad faces of chosen elements that face free tets are closed by the candidate that covers
///    them (a pyramid, usually); in conforming mode an element whose quad cannot be closed is
///    released back to tets.
/// 5. Local search (parameter local_search), on the finished selection, kept only when it lowers
///    the element count:
///    - swaps: one element next to free tets is released, and its tets with the free tets next
///      to them re-selected exactly (one element for two or more, or for a bigger one);
///    - re-selection (local_search_radius > 0): around each free tet (every tet with
///      local_search_seeds = all), every element within local_search_radius face hops is
///      released, and the released and free tets re-selected exactly.
///    "Exactly": a branch and bound over the candidates lying wholly in the neighbourhood, at
///    most local_search_nodes nodes per neighbourhood (past that, the best re-selection found
///    so far). In conforming and last_resort modes every face inside or around the
///    neighbourhood must conform afterwards (a move never adds a non-conforming quad); in allow
///    mode only the count matters. Neighbourhoods are visited in candidate or tet order, then
///    again around each accepted move, so the result is deterministic and the work is bounded
///    by (tets + moves) x nodes (every accepted move lowers the count).
///    The bound of the branch and bound: each undecided tet saves at most (n - 1) / n, n the
///    size of the largest pool candidate that takes it and has no decided tet.
/// 6. Outside conforming mode, elements that would leave a crack are released.
///
/// Pending quad faces (a chosen element's quad facing two free tets), the strategy named in
/// Selection::strategy: in conforming mode with pyramids, only where a closing pyramid is
/// reserved for it ("safe_pyramids": nothing is released in step 4); otherwise wherever some
/// available candidate could close it ("closable"; in conforming mode the unclosed ones are
/// released in step 4; the other modes name no strategy).
///
/// A quad face conforms when it lies on the domain boundary or on the identical quad face of
/// another element. The Conformity parameter decides whether a candidate that would break that
/// may be chosen (parameters.h).
Selection select_candidates(const TetMesh& mesh, const TetTopology& topology,
                            const Candidates& candidates, const RecombineParameters& parameters,
                            const ProgressCallback& progress = {});

}  // namespace hexmerge
