#pragma once
/// @file
/// Extended RF-graphs (Meshkat & Talmor, section 2) and the LINK/QUAD search programs compiled
/// from them (section 3).
///
/// An RF-graph has one node per tetrahedron of a decomposition; a solid edge (a "link") joins
/// two tets that share an internal face; a dashed edge (a "quad") joins two tets whose external
/// faces pair up into one quadrilateral face of the element.

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

/// One extended RF-graph: a template of a decomposition into tets.
struct RFGraph {
  std::string name;                        ///< "pyramid", "prism", "hex5", "hex6_cycle6", ...
  CellType type;                           ///< the element it makes
  int nb_nodes;                            ///< number of tets
  std::vector<std::pair<int, int>> links;  ///< solid edges: shared internal faces
  std::vector<std::pair<int, int>> quads;  ///< dashed edges: quadrilateral pairs
  /// One decomposition with this graph: tets on the corners of the reference cell (local
  /// numbering of cell_type.h), node i = tet i. The graph is checked against it at start-up,
  /// and the search programs take from it at which step a tet brings a new vertex (each class
  /// is a single orbit of the cell's symmetries, so that step is the same in every member).
  std::vector<std::array<int, 4>> realisation;
};

/// The paper's graphs: the pyramid (2 tets), the prism (3 tets, figure 2) and the six hexahedron
/// graphs of Theorem 1 (figures 4-9: 5 tets; 6 tets with a 6-, 5-, 4-, 4- and 3-cycle).
const std::vector<RFGraph>& rf_graphs();

/// One instruction of a search program. Nodes are numbered in assignment order: node 0 is the
/// root, and a LINK whose b equals the number of nodes assigned so far assigns a new node.
struct Instruction {
  enum Op : unsigned char { Link, Quad };
  Op op;
  unsigned char a;  ///< an assigned node
  unsigned char b;  ///< the node to assign (LINK to a new node) or an assigned node (check)
};

/// A search tree compiled into a program (section 3, figure 10).
struct SearchProgram {
  int graph;  ///< index into rf_graphs()
  int root;   ///< the graph node that is the program's node 0
  CellType type;
  int nb_nodes;
  std::vector<Instruction> code;
  /// Per program node: how many of its tet's faces are halves of the element's quad faces (its
  /// number of dashed edges). A tet with fewer faces that can pair into a quad cannot be there.
  std::vector<unsigned char> quad_degree;
  /// Per instruction: for a LINK to a new node, 1 when its tet brings a vertex not yet in the
  /// match, 0 when all four of its vertices are already there; unused for other instructions.
  std::vector<unsigned char> adds_vertex;
};

/// Graph nodes grouped by symmetry: two nodes are in one orbit when an automorphism of the
/// extended graph (preserving links and quads) maps one to the other.
std::vector<std::vector<int>> root_orbits(const RFGraph& graph);

/// One program per symmetry-distinct root of `graph` (the first node of each orbit). Nodes are
/// assigned in breadth-first order over links; after each new node come the checks it enables:
/// LINKs closing a cycle, then QUADs with earlier nodes.
std::vector<SearchProgram> compile_search_programs(const RFGraph& graph, int graph_index);

/// Every program of every graph (15 for the hexahedra, 2 for the prism, 1 for the pyramid),
/// compiled once.
const std::vector<SearchProgram>& search_programs();

}  // namespace hexmerge
