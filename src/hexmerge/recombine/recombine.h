#pragma once
/// @file
/// The engine's entry point: recombine a tetrahedral mesh into a hex-dominant mesh
/// (Meshkat & Talmor).

#include <array>
#include <map>
#include <string>
#include <vector>

#include "hexmerge/core/phase_timer.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/mixed_mesh.h"
#include "hexmerge/mesh/second_order.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge {

/// Statistics of one run. Counts and per-type arrays are indexed by CellType.
struct RecombineReport {
  std::size_t input_tets = 0;
  std::array<std::size_t, NB_CELL_TYPES> output_counts{};  ///< cells of each type
  std::size_t output_cells = 0;
  double element_reduction_percent = 0.0;               ///< 100 * (1 - output_cells / input_tets)
  double input_volume = 0.0;                            ///< sum of the input tets' volumes
  std::array<double, NB_CELL_TYPES> volume_fraction{};  ///< share of input volume per type
  std::size_t nonconforming_quads = 0;  ///< quad faces meeting two triangles in the output
  std::size_t block_hexahedra = 0;      ///< hexahedra kept as a block (structured regions)
  std::size_t group_seeds = 0;          ///< conforming groups: seeds tried (select/groups.cpp)
  std::size_t groups = 0;               ///< conforming groups accepted
  std::size_t group_hexahedra = 0;      ///< hexahedra in the accepted groups
  std::size_t groups_failed = 0;        ///< groups rolled back: a face nothing could close
  std::size_t groups_capped = 0;        ///< groups given up at group_size members
  std::size_t closing_pyramids = 0;     ///< pyramids made to close a quad face
  std::size_t released_elements = 0;    ///< elements split back to tets to restore conformity
  std::size_t local_moves = 0;          ///< accepted local optimisation moves (section 4.2)
  std::size_t swap_moves = 0;           ///< local search: accepted swaps of one element
  std::size_t reselection_moves = 0;    ///< local search: accepted neighbourhood re-selections
  std::size_t local_search_saved = 0;   ///< elements the local search removed (both moves)
  std::string selection_strategy;       ///< conforming mode: which selection was kept
  std::array<double, NB_CELL_TYPES> min_scaled_jacobian{};     ///< per type (0 when none)
  std::array<double, NB_CELL_TYPES> mean_scaled_jacobian{};    ///< per type (0 when none)
  std::map<std::string, std::size_t> candidates_per_template;  ///< accepted candidates
  std::size_t candidates_total = 0;
  /// Conforming mode: candidates no conforming selection can hold, removed before the selection
  /// (prune_unclosable).
  std::size_t candidates_unclosable = 0;
  /// The post-merge stage (parameter same_nodes; recombine/postmerge/postmerge.h): "off" (same
  /// nodes), "off: conformity mode" (it closes quads for conforming mode only), "kept" (the output
  /// is on the flipped tets), "not kept" (the reselection had no fewer elements).
  std::string post_merge = "off";
  /// Census (conforming mode, post-merge on): hexahedron candidates on the input's tets, and
  /// those whose every quad face lies on the boundary or is closed by a pyramid of the two tets
  /// behind it.
  std::size_t census_hex_candidates = 0;
  std::size_t census_closable = 0;
  /// The same on the tets after the stage's flips.
  std::size_t census_hex_candidates_after = 0;
  std::size_t census_closable_after = 0;
  std::size_t post_merge_rounds = 0;     ///< rounds of the stage kept
  std::size_t post_merge_closed = 0;     ///< hex candidates whose open quads the flips closed
  std::size_t post_merge_attempted = 0;  ///< hex candidates the flips were tried on
  std::size_t flips_23 = 0;              ///< flips the stage kept, by kind
  std::size_t flips_32 = 0;
  std::size_t flips_44 = 0;
  std::size_t contractions = 0;   ///< edge contractions the stage kept (one inner node each)
  std::size_t node_moves = 0;     ///< inner-node moves the stage kept (post_merge_moves)
  std::size_t vertex_splits = 0;  ///< vertex splits the stage kept (one node added each)
  /// Hexahedron candidates closed by the stage that a node move made pass the acceptance
  std::size_t post_merge_lifted = 0;
  PhaseSeconds phase_seconds;  ///< wall time per phase, in order
  /// The optimality bound (parameter optimality_bound, bound_selection.h); the fields below are
  /// set only when it ran. In conforming mode the program has the conformity rows and bounds the
  /// conforming selections; in the other modes it is plain set packing and bounds every selection.
  bool bound_computed = false;
  bool bound_conforming = false;        ///< the program had the conformity rows
  std::size_t bound_elements = 0;       ///< fewest elements any selection of the candidates reaches
  std::size_t bound_best_elements = 0;  ///< elements of the best selection the solver found
  bool bound_proved = false;            ///< the solver proved bound_best_elements optimal
  double gap_percent = 0.0;             ///< 100 * (output_cells - bound_elements) / bound_elements
  /// No selection of the candidates (in conforming mode: no conforming selection) fills more than
  /// this share of the volume with hexahedra (bound_hex_volume, bound_selection.h).
  double hex_volume_bound = 0.0;
  bool hex_volume_bound_proved = false;  ///< that share is reached by disjoint hexahedra
};

/// Merges groups of tetrahedra into hexahedra, prisms and pyramids.
///
/// @param[in]  input       linear tet mesh; validated first (InputError names what is wrong)
/// @param[in]  parameters  acceptance thresholds, element types, strategy
/// @param[out] report      statistics of the run
/// @param[in]  progress    optional progress callback (may cancel)
/// @return the mixed mesh on the input's points; every cell is the union of its source tets,
///         positively oriented in the local order of cell_type.h, in the region of its tets.
MixedMesh recombine(const TetMesh& input, const RecombineParameters& parameters,
                    RecombineReport& report, const ProgressCallback& progress = {});

/// A recombined second-order mesh: the linear cells and, on the same cells, their quadratic
/// nodes (corners, then the input's mid-edge nodes).
struct QuadraticMixedMesh {
  MixedMesh linear;          ///< recombine() of the corner mesh, on all the input's points
  QuadraticCells quadratic;  ///< quadratic_cells(linear, input): Pyramid13, Wedge15, Hexa20, Tet10
};

/// Merges the tetrahedra of a Tet10 mesh: its corner mesh (corner_mesh) is checked
/// (validate_tet10_mesh, before any work) and recombined, then every cell gets the input's
/// mid-edge nodes of its edges (quadratic_cells).
///
/// @param[in]  input       Tet10 mesh (VTK order); its mid-edge nodes stay where they are
/// @param[in]  parameters  as for the linear recombine()
/// @param[out] report      statistics of the run (of the corner mesh)
/// @param[in]  progress    optional progress callback (may cancel)
/// @throws InputError as the linear recombine(), corner_mesh() and validate_tet10_mesh()
QuadraticMixedMesh recombine(const Tet10Mesh& input, const RecombineParameters& parameters,
                             RecombineReport& report, const ProgressCallback& progress = {});

}  // namespace hexmerge
