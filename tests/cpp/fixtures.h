#pragma once
/// @file
/// Shared fixtures of the C++ tests (libigl's test_common.h way): small polytopes and all their
/// triangulations, enumerated here rather than written out; structured tet grids; random affine
/// maps and perturbations; and a TetMesh builder.

#include <array>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"

namespace hexmerge::test {

using Point = std::array<double, 3>;
using Tet = std::array<index_t, 4>;

/// A TetMesh from points and tets (regions optional). Tets are taken as given (no reorienting).
TetMesh make_tet_mesh(const std::vector<Point>& points, const std::vector<Tet>& tets,
                      const std::vector<std::int32_t>& regions = {});

/// The Delaunay tetrahedralisation of `points` by the tetgen program, through the library's
/// TetGen interface (tetgen/tetrahedralize.h, no facets; no Steiner points: the points keep
/// their order), positively oriented. Empty when tetgen is not installed.
TetMesh tetgen_mesh(const std::vector<Point>& points);

/// A lattice of n x n x n unit cells, its points jittered by up to `jitter` per coordinate,
/// through tetgen_mesh. With no jitter, TetGen splits each cube (eight cospherical points) its
/// own way: 5 or 6 tets, diagonals as they come.
TetMesh tetgen_lattice(int n, double jitter, unsigned seed);

/// Appends tet (a, b, c, d) to the mesh, c and d swapped when needed to make it positive.
void add_tet(TetMesh& mesh, index_t a, index_t b, index_t c, index_t d);

/// The smallest scaled Jacobian of the mesh's tets (1 for none).
double min_quality(const TetMesh& mesh);
/// The mesh's tets whose scaled Jacobian is below `quality`.
std::size_t count_below(const TetMesh& mesh, double quality);

/// Swaps two vertices of every negatively oriented tet so that all have positive volume.
void orient_positively(TetMesh& mesh);

/// A convex polytope given by its corners (small integer coordinates, so every orientation test
/// below is exact in double precision).
struct Polytope {
  std::string name;
  std::vector<Point> corners;
};

/// Unit cube; corner i is at (i & 1, (i >> 1) & 1, (i >> 2) & 1).
Polytope unit_cube();
/// Right-triangle prism: bottom (0,0,0) (1,0,0) (0,1,0), vertex i+3 above vertex i at z = 1.
Polytope unit_prism();
/// Square pyramid: base (0,0,0) (2,0,0) (2,2,0) (0,2,0), apex (1,1,1).
Polytope square_pyramid();

/// Every triangulation of a polytope on its corners: sets of positively oriented tets on the
/// corners that are pairwise interior-disjoint (exact separating-plane test), fill the volume,
/// and meet face to face (each tet face inside the polytope shared by exactly one other tet).
std::vector<std::vector<Tet>> enumerate_triangulations(const Polytope& polytope);

/// Non-degenerate 4-subsets of the corners (the candidate tets of the enumeration).
std::vector<Tet> candidate_tets(const Polytope& polytope);

/// The extended RF-graph of a triangulation (Meshkat & Talmor): tets are nodes; adjacency bit 1
/// for a shared face (solid edge), bit 2 for two boundary faces on one facet of the polytope
/// (dashed "quad" edge).
struct RFGraph {
  int nb_nodes = 0;
  std::vector<std::vector<int>> adjacency;  ///< nb_nodes by nb_nodes, bits as above
  int degree(int node) const;               ///< number of solid edges
};
RFGraph rf_graph(const Polytope& polytope, const std::vector<Tet>& tets);

/// A canonical form of an RF-graph: equal for isomorphic graphs (solid and dashed edges kept
/// apart), different otherwise. Brute force over node permutations (graphs of up to ~8 nodes).
std::string canonical_form(const RFGraph& graph);

/// Length of the single cycle of the solid RF-graph (0 for a tree): what is left after pruning
/// leaves repeatedly.
int solid_cycle_length(const RFGraph& graph);

/// Groups items by equal keys: returns the class of each item (0, 1, ... in order of first
/// appearance) and fills `sizes` with the class sizes.
std::vector<int> classes_of(const std::vector<std::string>& keys, std::vector<int>& sizes);

/// A polytope and one of its triangulations as a TetMesh (the polytope's corners as points).
TetMesh polytope_mesh(const Polytope& polytope, const std::vector<Tet>& tets);

/// An n x n x n grid of unit cubes, each split into the 6 tets of Kuhn's triangulation around
/// its (0,0,0)-(1,1,1) diagonal (conforming: every cube uses the same diagonals).
TetMesh kuhn_grid(int n);
/// An n x n x n grid of unit cubes, each split into 5 tets, the split alternating in a
/// checkerboard so that face diagonals match.
TetMesh five_tet_grid(int n);
/// Point index of grid node (i, j, k) in the grids above.
index_t grid_node(int n, int i, int j, int k);

/// x -> A x + b with a random A of determinant >= 0.2 (positive: orientation kept) and entries
/// within `spread` of the identity's.
void random_affine_map(TetMesh& mesh, std::mt19937& rng, double spread = 0.4);
/// Moves every point by a uniform random offset in [-amplitude, amplitude]^3; retries until no
/// tet is inverted (the amplitude must be small against the tets).
void random_perturbation(TetMesh& mesh, std::mt19937& rng, double amplitude);

/// Sum of the tets' signed volumes.
double total_volume(const TetMesh& mesh);

/// Candidate thresholds loose enough for the skewed cells of random affine maps and
/// perturbations (scaled Jacobian 0.05, dihedral angles 120, face angle 175).
AcceptanceCriteria permissive_criteria();
/// The engine's parameters with those thresholds.
RecombineParameters permissive_parameters();

}  // namespace hexmerge::test
