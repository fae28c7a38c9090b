#include "hexmerge/recombine/parameters.h"

#include "hexmerge/core/error.h"

namespace hexmerge {
namespace {

const std::vector<std::string> kConformityChoices = {"conforming", "last_resort", "allow"};
const std::vector<std::string> kFinderChoices = {"programs", "exhaustive"};
const std::vector<std::string> kBoundaryOrderChoices = {"quality", "fewest_matches"};
const std::vector<std::string> kLocalSearchSeedsChoices = {"unmatched", "all"};
const std::vector<std::string> kPyramidPlacementChoices = {
    "anywhere", "no_boundary_face", "no_boundary_node", "no_curved_boundary_face",
    "no_curved_boundary_node"};

ParameterTable<RecombineParameters> make_table() {
  using P = RecombineParameters;
  using namespace parameter_rows;
  return ParameterTable<P>({
      number(&P::min_dihedral_angle, "min_dihedral_angle", "deg", 90, 180,
             "Min. quad dihedral angle",
             "Smallest accepted dihedral angle between the two triangles of a quad face (180 = "
             "flat)"),
      number(&P::min_boundary_dihedral_angle, "min_boundary_dihedral_angle", "deg", 90, 180,
             "Min. boundary dihedral angle",
             "Smallest accepted dihedral angle of a quad face on the domain boundary (keeps the "
             "boundary on the geometry)"),
      number(&P::max_face_angle, "max_face_angle", "deg", 90, 180, "Max. face angle",
             "Largest accepted corner angle of a quad face (90 = rectangle)"),
      number(&P::min_scaled_jacobian, "min_scaled_jacobian", "", -1, 1, "Min. scaled Jacobian",
             "Smallest accepted scaled Jacobian (Verdict) of a new hex, prism or pyramid (1 = "
             "ideal; below 1e-9 counts as 1e-9: no element is ever flat or inverted)"),
      number(&P::lowest_scaled_jacobian, "lowest_scaled_jacobian", "", 0, 1,
             "Lowest scaled Jacobian",
             "A new hex or prism between this and the min. scaled Jacobian is accepted when it is "
             "at least as good as the worst tet it replaces (it never lowers the quality where it "
             "merges; a poor prism left as tets turns its neighbours into pyramids: a swept "
             "plate with holes had 40 % hex volume at 0.3, 87 % at 0); at or above the min. "
             "scaled Jacobian: none"),
      flag(&P::make_hexahedra, "make_hexahedra", "Hexahedra", "Merge tetrahedra into hexahedra"),
      flag(&P::make_prisms, "make_prisms", "Prisms", "Merge tetrahedra into prisms (pentahedra)"),
      flag(&P::make_pyramids, "make_pyramids", "Pyramids",
           "Merge tetrahedra into pyramids. In conforming mode pyramids close the quad faces of "
           "hexes and prisms: without them almost nothing merges on unstructured meshes (for "
           "CalculiX, keep them off the boundary with pyramid_placement)"),
      choice(&P::pyramid_placement, "pyramid_placement", kPyramidPlacementChoices,
             "Pyramid placement",
             "Where pyramids may be made: anywhere, not with a face on the boundary "
             "(no_boundary_face), not with a node on it (no_boundary_node), or not with a face "
             "on a curved part of it (no_curved_boundary_face: a boundary triangle turning by 1 "
             "to 30 degrees to one beside it), or not with a node on a curved part of it "
             "(no_curved_boundary_node); tets stay there "
             "instead. For CalculiX (no pyramid element: collapsed hexahedra) no_boundary_node "
             "keeps peak stresses as accurate as the tets' (docs/fem-accuracy.md)"),
      choice(&P::conformity, "conformity", kConformityChoices, "Conformity",
             "Quad faces meeting two triangles: never (conforming), only where nothing else is "
             "possible (last_resort), or freely (allow)"),
      flag(&P::respect_regions, "respect_regions", "Respect regions",
           "Never merge tetrahedra of different regions (materials, solids)"),
      flag(&P::local_optimisation, "local_optimisation", "Local optimisation",
           "Rearrange elements around unmatched boundary tetrahedra (Meshkat-Talmor 4.2)"),
      flag(&P::local_search, "local_search", "Local search",
           "After the selection, re-select exactly each element next to free tetrahedra with "
           "them (swaps) and, with a local search radius above 0, every neighbourhood of that "
           "radius, whenever that lowers the element count (conformity mode kept)"),
      whole(&P::local_search_radius, "local_search_radius", "", 0, 4, "Local search radius",
            "Face hops around a tetrahedron within which the local search releases the elements "
            "and re-selects them exactly; 0: swaps only (cheap). 3 with local_search_seeds = all "
            "comes within about 2 % of the optimum in allow mode, at about 1.5 s per 10k "
            "tetrahedra"),
      whole(&P::group_size, "group_size", "", 0, 10000, "Group size",
            "Conforming mode with pyramids: the most hexahedra and prisms taken together in one "
            "group whose quad faces close each other (each shared with the next member, on the "
            "boundary, or closed by a pyramid), grown from each hexahedron and prism candidate; a "
            "group that needs more is given up (the report counts them: groups_capped). 0: one "
            "element at a time, as the greedy takes them"),
      whole(&P::local_search_nodes, "local_search_nodes", "", 1, 1000000, "Local search effort",
            "Branch-and-bound nodes the local search may spend on one neighbourhood (bounds its "
            "time; past it the best re-selection found so far is kept)"),
      choice(&P::local_search_seeds, "local_search_seeds", kLocalSearchSeedsChoices,
             "Local search seeds",
             "Where the local search re-selects: around unmatched tetrahedra, or around every "
             "tetrahedron (also merges elements into fewer; slower)"),
      choice(&P::boundary_order, "boundary_order", kBoundaryOrderChoices, "Boundary order",
             "Order of the greedy boundary phase: best quality first, or the paper's fewest "
             "remaining matches first"),
      choice(&P::finder, "finder", kFinderChoices, "Candidate finder",
             "How candidate elements are found: the paper's RF-graph search programs (5- and "
             "6-tet hexahedra), or exhaustively (every cell its vertices' tets fill, any "
             "subdivision)"),
      whole(&P::threads, "threads", "", 0, 1024, "Threads",
            "Threads for the candidate search; 0 uses every hardware thread"),
      flag(&P::optimality_bound, "optimality_bound", "Optimality bound",
           "Also solve the selection as an integer program (GLPK) for a bound on the element "
           "count and one on the hexahedron volume; meshes up to about 20k tets (no cap: larger "
           "ones stop at the time limit with a looser bound)"),
      number(&P::bound_time_limit, "bound_time_limit", "s", 1, 3600, "Bound time limit",
             "Time limit of each of the optimality bound's two integer programs; past it the "
             "best bound so far is reported"),
      flag(&P::same_nodes, "same_nodes", "Same tets",
           "Keep the input's tetrahedra: every output cell is a union of them. Off, in conforming "
           "mode, a post-merge stage flips tets (2-3, 3-2, 4-4; nodes kept) so that pyramids "
           "close the open quad faces of more hexahedra, and the selection is run again on the "
           "new tets (kept only when it has fewer elements); the cells then list no source tets"),
      whole(&P::post_merge_rounds, "post_merge_rounds", "", 1, 10, "Post-merge rounds",
            "Rounds of the post-merge stage (same_nodes off): each closes more quads around the "
            "last selection and selects again; the stage stops at the first round that does not "
            "lower the element count"),
      flag(&P::post_merge_contractions, "post_merge_contractions", "Edge contractions",
           "In the post-merge stage (same_nodes off), where no flip closes an open quad face, "
           "contract a node behind it (inside the domain or inside a flat face of it) into its "
           "neighbour (the paper's edge contraction): the node leaves the mesh, no node moves, "
           "the boundary and every region's volume are kept"),
      flag(&P::post_merge_moves, "post_merge_moves", "Node moves",
           "In the post-merge stage (same_nodes off), move an inner node (the paper's smoothing) "
           "where that makes a refused flip or contraction valid or lifts a closing pyramid "
           "above the acceptance; every tet at the node stays positive and at the quality floor "
           "(or not worse where it was below), boundary nodes never move, every region's volume "
           "is kept"),
      flag(&P::post_merge_splits, "post_merge_splits", "Vertex splits",
           "In the post-merge stage (same_nodes off), split the apex of a pyramid on a prism's "
           "quad face into an edge (the paper's vertex split, one node added inside the domain) "
           "where that makes the prism and the pyramid one hexahedron whose quad faces close; "
           "every new tet is positive and at the quality floor, every region's volume is kept"),
  });
}

}  // namespace

std::string to_string(Conformity conformity) {
  return kConformityChoices[static_cast<int>(conformity)];
}

std::string to_string(Finder finder) { return kFinderChoices[static_cast<int>(finder)]; }

std::string to_string(BoundaryOrder order) {
  return kBoundaryOrderChoices[static_cast<int>(order)];
}

std::string to_string(LocalSearchSeeds seeds) {
  return kLocalSearchSeedsChoices[static_cast<int>(seeds)];
}

std::string to_string(PyramidPlacement placement) {
  return kPyramidPlacementChoices[static_cast<int>(placement)];
}

const ParameterTable<RecombineParameters>& recombine_parameter_table() {
  static const ParameterTable<RecombineParameters> table = make_table();
  return table;
}

const std::vector<ParameterInfo>& parameter_table() { return recombine_parameter_table().info(); }

void set_parameter(RecombineParameters& parameters, const std::string& name,
                   const std::string& value) {
  recombine_parameter_table().set(parameters, name, value);
}

void validate_parameters(const RecombineParameters& parameters) {
  recombine_parameter_table().validate(parameters);
  if (!parameters.make_hexahedra && !parameters.make_prisms && !parameters.make_pyramids) {
    throw InputError("no element type is enabled: enable hexahedra, prisms or pyramids",
                     Entity::Parameter);
  }
}

}  // namespace hexmerge
