#pragma once
/// @file
/// The exhaustive, vertex-based candidate finder, after Pellerin, Johnen, Verhetsel & Remacle,
/// "Identifying combinations of tetrahedra into hexahedra: a vertex based strategy" (CAD 2018).
///
/// Every set of 8 (6, 5) vertices with a hexahedron's (prism's, pyramid's) connectivity whose
/// tets exactly fill it is a candidate, whatever the subdivision: slivers, flat tets and groups
/// of up to kMaxCandidateTets tets included, not only the paper's 5- and 6-tet templates.
///
/// How: the accepted quads (QuadPairs: two tet faces forming a flat enough quad, oriented
/// outwards from their tets) are indexed by directed edge. A hexahedron is grown from each quad
/// as its base: the side quads on the base's edges give the top vertices, then the top quad must
/// exist. Prisms grow from one quad and two more around it; pyramids take the apex of the tet
/// behind the base. Each cell is enumerated once (from its smallest vertex). The cell is then
/// verified: starting from a tet behind the base quad, the group grows across every tet face
/// that does not lie on one of the cell's faces; every tet reached must have its 4 vertices among
/// the cell's; the group's boundary must be exactly the cell's faces, quads as two triangles on
/// one diagonal, each oriented outwards. Since the tets of a valid mesh do not overlap, that
/// boundary condition means the group fills the cell exactly (and its volume is the cell's).
/// Flat tets lying on a quad face of the cell ("caps", 4 vertices on that face) are outside the
/// grown group; when they exist, a second candidate with the caps included is reported too.
///
/// Acceptance is the programs': each quad face's two triangles must be a QuadPairs entry (in
/// either direction), scaled Jacobian >= min_scaled_jacobian, one region when asked.

#include <cstdint>
#include <vector>

#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"

namespace hexmerge {

/// Candidate::graph of the exhaustive finder's candidates (not an index into rf_graphs()).
constexpr std::uint8_t EXHAUSTIVE_GRAPH = 255;

/// Finds every candidate hex, prism and pyramid (as enabled in `criteria.types`).
///
/// Candidates come with tets sorted, vertices in the local order of cell_type.h, graph
/// EXHAUSTIVE_GRAPH. The order of the result does not depend on the number of threads.
/// @param[in] threads  worker threads (>= 1)
Candidates find_candidates_exhaustive(const TetMesh& mesh, const TetTopology& topology,
                                      const AcceptanceCriteria& criteria, int threads,
                                      const ProgressCallback& progress = {});

}  // namespace hexmerge
