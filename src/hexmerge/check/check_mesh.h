#pragma once
/// @file
/// An independent validity check of any mixed mesh against the tet mesh it came from.
///
/// It shares no code path with the engine beyond the cell tables and the geometric measures:
/// faces are rebuilt from the output cells alone.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "hexmerge/mesh/mixed_mesh.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// Lines of CheckReport::problems kept per kind of fault.
constexpr std::size_t kMaxProblemsPerKind = 10;
/// A changed node on the output's boundary must lie within this distance of the input's boundary
/// triangles, relative to the longest output edge at the node.
constexpr double kBoundaryNodeTolerance = 1e-6;
/// With changed nodes, every region's volume (quad faces split into triangles) must be the
/// input's to this relative difference.
constexpr double kChangedVolumeTolerance = 1e-6;

/// What the checker found. A mesh is valid when `valid()` holds.
struct CheckReport {
  std::size_t nb_cells = 0;
  std::array<std::size_t, NB_CELL_TYPES> counts{};
  std::size_t inverted_cells = 0;       ///< scaled Jacobian <= 0
  double min_scaled_jacobian = 0.0;     ///< over all cells
  index_t worst_cell = NO_INDEX;        ///< the cell with the minimum scaled Jacobian
  std::size_t nonconforming_quads = 0;  ///< unpaired quads whose halves on one diagonal are
                                        ///< faces of other cells: two triangles, or a
                                        ///< triangle or two halves of other quads
  std::size_t cracks = 0;               ///< interior faces with no partner at all
  std::size_t overshared_faces = 0;     ///< faces shared by three or more cells
  std::size_t unused_input_nodes = 0;   ///< corner nodes of the input missing from the output
  std::size_t moved_nodes = 0;          ///< nodes whose coordinates differ from the input's
  std::size_t region_mismatches = 0;    ///< cells whose region differs from a source tet's
  std::size_t malformed_cells = 0;  ///< wrong vertex count, vertex id out of range, repeated vertex
  std::size_t mismatched_faces = 0;  ///< shared faces whose two cells disagree (same side, or
                                     ///< one vertex set on two different quads)
  std::size_t source_errors = 0;     ///< source tets that are not a partition of the input,
                                     ///< or a cell whose corners are not its tets' corners
  /// Nodes the mesh declares changed (MixedMesh::changed_nodes): moved, removed or added.
  std::size_t declared_changed_nodes = 0;
  /// Declared nodes on the output's boundary farther than kBoundaryNodeTolerance from the input's
  /// boundary triangles, and faulty declarations (an id past the nodes, or not sorted).
  std::size_t off_boundary_nodes = 0;
  /// With declared changes: 1 when a region's volume (the whole mesh's without regions), with
  /// quad faces split into triangles, differs from the input's by more than
  /// kChangedVolumeTolerance (relative), else 0.
  std::size_t volume_not_kept = 0;
  /// With declared changes: that largest relative difference (0 otherwise).
  double linear_volume_difference = 0.0;
  double input_volume = 0.0;
  double output_volume = 0.0;  ///< with bilinear quad faces
  double relative_volume_difference = 0.0;
  /// Per region (when both meshes have regions): the largest |output - input| / input volume,
  /// and the region it is in (0 and -1 without regions). Volume moved from one material to
  /// another through a bent region interface shows here, not in the total.
  double max_region_volume_difference = 0.0;
  std::int32_t worst_region = -1;
  std::vector<std::string> problems;  ///< human-readable, one line each, first few of each kind

  bool valid() const {
    return inverted_cells == 0 && cracks == 0 && overshared_faces == 0 && unused_input_nodes == 0 &&
           moved_nodes == 0 && region_mismatches == 0 && malformed_cells == 0 &&
           mismatched_faces == 0 && source_errors == 0 && off_boundary_nodes == 0 &&
           volume_not_kept == 0;
  }
};

/// Checks `mesh` against the tet mesh `input` it was made from.
///
/// Every cell positively oriented (scaled Jacobian > 0); every face of the domain's interior
/// shared by exactly two cells, a quad with the identical quad or counted as non-conforming when
/// two triangles cover it, no unpaired interior face (a crack); every corner node of the input
/// used, at its exact coordinates (the output's points must equal the input's, same count and
/// bitwise-equal coordinates); regions preserved and every cell the union of its source tets
/// (via MixedMesh::source_tets when present, else skipped); total volume compared with the
/// input's, and every region's volume with the input's. Nodes the mesh declares changed
/// (MixedMesh::changed_nodes) may be moved, unused or added (ids past the input's); then every
/// declared node on the output's boundary must lie on the input's boundary triangles
/// (kBoundaryNodeTolerance), an unpaired face with a declared node or a node next to one (in an
/// input tet with a declared node) counts as boundary when its corners and centroid lie on the
/// input's boundary triangles, and every region's volume must be kept (kChangedVolumeTolerance),
/// measured with every quad face split into two triangles (a shared quad on one diagonal for both
/// its cells, an unpaired one on the triangles covering it), so that a quad's bending, the same
/// with or without changed nodes, does not count. With no declared node the checks are exactly
/// those above. Runs on the points scaled by normalising_exponent (exact), so the answers do not
/// depend on the model's scale. The domain boundary is the input's boundary triangles: a boundary
/// quad must be covered by two of them on one of its diagonals. Never throws on a bad `mesh`: every
/// fault is counted and described in CheckReport::problems (at most kMaxProblemsPerKind lines per
/// kind). Runs in O(#faces log(faces per vertex)) time.
/// @param[in] mesh   the mixed mesh to check
/// @param[in] input  the tet mesh it was made from (assumed valid: see validate_tet_mesh)
CheckReport check_mesh(const MixedMesh& mesh, const TetMesh& input);

}  // namespace hexmerge
