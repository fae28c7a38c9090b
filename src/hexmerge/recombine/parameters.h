#pragma once
/// @file
/// The engine's parameters and the one table that documents them for every front end.
///
/// The CLI's options, the FreeCAD object's properties and the task panel's widgets are all built
/// from recombine_parameter_table() (exported by the Python module), so names, ranges and
/// defaults never drift apart.

#include <string>
#include <vector>

#include "hexmerge/core/parameter_table.h"

namespace hexmerge {

/// How quad faces that would meet two triangles (of tets or other elements) are treated.
enum class Conformity {
  /// Never: every quad face ends on the boundary or on the identical quad face of another
  /// element, or is closed by a pyramid made of the two tets behind it.
  Conforming,
  /// Only when nothing else is possible at a tet: a non-conforming element is taken only where
  /// no conforming element exists; each one is counted in the report.
  LastResort,
  /// The paper's liberty: element type first, non-conformities only break ties.
  Allow,
};

/// In which order the exhaustive-greedy boundary phase takes candidates.
enum class BoundaryOrder {
  /// Best scaled Jacobian first.
  Quality,
  /// The paper's: the boundary tet with the fewest remaining candidates first, its best one.
  FewestMatches,
};

/// Which candidate finder produces the elements that the selection chooses from.
enum class Finder {
  /// The paper's RF-graph search programs (LINK/QUAD), 5- and 6-tet hexahedra.
  Programs,
  /// Every cell whose vertices' tets fill it, any subdivision (find_candidates_exhaustive.h).
  Exhaustive,
};

/// Where the local search's re-selection is tried (select_candidates.h).
enum class LocalSearchSeeds {
  /// Around every tet left unmatched.
  Unmatched,
  /// Around every tet: also merges of elements into fewer where no tet is left (slower).
  All,
};

/// Where pyramids may be made (for solvers that take a pyramid only as a collapsed hexahedron or
/// wedge, whose stresses are poor on the surface: docs/fem-accuracy.md).
enum class PyramidPlacement {
  /// Wherever a pyramid passes the acceptance.
  Anywhere,
  /// Not with a face (base or side) on the domain boundary: those tets stay tets.
  NoBoundaryFace,
  /// Not with a vertex on the domain boundary.
  NoBoundaryNode,
  /// Not with a face on a curved part of the domain boundary: a boundary triangle whose normal
  /// turns by kCurvedMin to kCurvedMax degrees to one of the boundary triangles beside it (flat
  /// faces and sharp edges allowed). The post-merge stage takes it as NoBoundaryFace.
  NoCurvedBoundaryFace,
  /// Not with a vertex on a curved part of the domain boundary (a vertex of a boundary triangle
  /// NoCurvedBoundaryFace forbids): the tets at a curved face stay tets, as NoBoundaryNode keeps
  /// them everywhere, and flat faces keep their pyramids. The post-merge stage takes it as
  /// NoBoundaryNode.
  NoCurvedBoundaryNode,
};

/// Scaled Jacobian from which a hexahedron candidate is near-perfect: the conforming selection
/// takes those first, together (its block, select/block.cpp), and the mesher predicts that block
/// with it (split_open_cells()). The share of hexahedra on lattice-seeded meshes is the same from
/// 0.7 to 0.95.
inline constexpr float kBlockHexQuality = 0.9f;

/// Parameters of hexmerge::recombine. Every field is listed in parameter_table() with its unit,
/// range and documentation.
struct RecombineParameters {
  double min_dihedral_angle = 150.0;  ///< degrees, [90, 180]: the paper's dangle
  /// degrees, [90, 180]: dangle for quad faces on the domain boundary, which must follow the
  /// geometry (a fold there changes the domain's volume)
  double min_boundary_dihedral_angle = 179.0;
  double max_face_angle = 150.0;  ///< degrees, [90, 180]: the paper's fangle
  /// [-1, 1]: Verdict scaled Jacobian of every new element; recombine() never goes below
  /// kMinElementScaledJacobian, whatever this says
  double min_scaled_jacobian = 0.3;
  /// [0, 1]: between this and min_scaled_jacobian, a new hex or prism at least as good as the
  /// worst tet it replaces is accepted (it never lowers the quality where it merges)
  double lowest_scaled_jacobian = 0.0;
  bool make_hexahedra = true;
  bool make_prisms = true;
  bool make_pyramids = true;
  PyramidPlacement pyramid_placement = PyramidPlacement::Anywhere;
  Conformity conformity = Conformity::Conforming;
  bool respect_regions = true;     ///< never merge tets of different regions
  bool local_optimisation = true;  ///< the paper's section 4.2
  /// after the selection: swaps and exact re-selection around unmatched tets (select_candidates.h)
  bool local_search = true;
  /// [0, 4]: face hops around a tet within which the elements are released and re-selected;
  /// 0: swaps only
  int local_search_radius = 0;
  /// [0, 10000]: conforming mode with pyramids: most hexahedra and prisms taken together in one
  /// conforming group (select/groups.cpp); 0: no groups, one element at a time
  int group_size = 64;
  int local_search_nodes = 2000;  ///< [1, 1e6]: branch-and-bound nodes per neighbourhood
  LocalSearchSeeds local_search_seeds = LocalSearchSeeds::Unmatched;
  BoundaryOrder boundary_order = BoundaryOrder::Quality;
  Finder finder = Finder::Programs;
  int threads = 0;  ///< candidate search threads; 0: all hardware threads
  /// also solve the selection as an integer program (bound_selection.h) and report the gap
  bool optimality_bound = false;
  double bound_time_limit = 30.0;  ///< seconds, [1, 3600]: time limit of that solve
  /// true: every output cell is a union of the input's tets (no post-merge stage); false
  /// (conforming mode): the post-merge stage may flip tets behind open quad faces
  /// (recombine/postmerge/postmerge.h), nodes kept
  bool same_nodes = true;
  /// [1, 10]: rounds of the post-merge stage (each kept only if it helps)
  int post_merge_rounds = 1;
  /// The post-merge stage may also contract nodes away (same_nodes off; FlipMesh::contract)
  bool post_merge_contractions = true;
  /// The post-merge stage may also move inner nodes (same_nodes off; FlipMesh::smooth)
  bool post_merge_moves = true;
  /// The post-merge stage may also split inner nodes into edges, adding nodes (same_nodes off;
  /// FlipMesh::split)
  bool post_merge_splits = false;
};

/// The floor under min_scaled_jacobian: an element at or below 0 would be flat or inverted (the
/// checker refuses it), so recombine() accepts none below this, whatever the option says.
constexpr double kMinElementScaledJacobian = 1e-9;

/// The table of every engine parameter (core/parameter_table.h), in display order; its
/// defaults are RecombineParameters{}'s. A parameter is added by one row in parameters.cpp.
const ParameterTable<RecombineParameters>& recombine_parameter_table();

/// recombine_parameter_table().info(): the rows as the front ends see them.
const std::vector<ParameterInfo>& parameter_table();

/// Sets one parameter from text (as given on a command line or in a property); throws
/// InputError (Entity::Parameter) naming the parameter when the name or value is invalid or out
/// of range.
void set_parameter(RecombineParameters& parameters, const std::string& name,
                   const std::string& value);

/// Checks every parameter against its row of the table, and that some element type is enabled;
/// throws InputError naming the first bad one.
void validate_parameters(const RecombineParameters& parameters);

/// Text of an enum value as used in the table ("conforming", "last_resort", "allow", ...).
std::string to_string(Conformity conformity);
std::string to_string(Finder finder);
std::string to_string(BoundaryOrder order);
std::string to_string(LocalSearchSeeds seeds);
std::string to_string(PyramidPlacement placement);

}  // namespace hexmerge
