#include "hexmerge/recombine/rf_graph.h"

#include <algorithm>
#include <numeric>
#include <set>

#include "hexmerge/core/error.h"

namespace hexmerge {
namespace {

// Node numbering is ours; the structure is the paper's. Boundary-face counts (4 - degree) are
// given per node in the comments, as the paper labels its figures.
std::vector<RFGraph> make_graphs() {
  return {
      // Figure 1: two tets sharing a face, with one quad pair.
      {"pyramid", CellType::Pyramid, 2, {{0, 1}}, {{0, 1}}, {{{0, 1, 2, 4}}, {{0, 2, 3, 4}}}},
      // Figure 2: a path of three tets (3 2 3); every pair shares a quad.
      {"prism",
       CellType::Prism,
       3,
       {{0, 1}, {1, 2}},
       {{0, 1}, {0, 2}, {1, 2}},
       {{{0, 1, 2, 3}}, {{1, 2, 3, 4}}, {{2, 3, 4, 5}}}},
      // Figure 4: a central tet with no boundary face and four corner tets (3 3 0 3 3).
      {"hex5",
       CellType::Hex,
       5,
       {{0, 1}, {0, 2}, {0, 3}, {0, 4}},
       {{1, 2}, {1, 3}, {1, 4}, {2, 3}, {2, 4}, {3, 4}},
       {{{0, 2, 5, 7}}, {{0, 1, 2, 5}}, {{0, 2, 3, 7}}, {{0, 4, 5, 7}}, {{2, 5, 6, 7}}}},
      // Figure 5: Kuhn's decomposition, a 6-cycle (2 2 2 2 2 2).
      {"hex6_cycle6",
       CellType::Hex,
       6,
       {{0, 1}, {0, 2}, {1, 3}, {2, 4}, {3, 5}, {4, 5}},
       {{0, 1}, {0, 2}, {1, 3}, {2, 4}, {3, 5}, {4, 5}},
       {{{0, 1, 2, 4}},
        {{0, 2, 3, 4}},
        {{1, 2, 4, 5}},
        {{2, 3, 4, 7}},
        {{2, 4, 5, 6}},
        {{2, 4, 6, 7}}}},
      // Figure 6: a 5-cycle 0-1-4-5-2 with tet 3 hanging on 0 (1 2 2 3 2 2).
      {"hex6_cycle5",
       CellType::Hex,
       6,
       {{0, 1}, {0, 2}, {0, 3}, {1, 4}, {2, 5}, {4, 5}},
       {{0, 3}, {1, 3}, {1, 4}, {2, 3}, {2, 5}, {4, 5}},
       {{{0, 1, 2, 4}},
        {{0, 2, 3, 4}},
        {{1, 2, 4, 5}},
        {{2, 3, 4, 6}},
        {{2, 4, 5, 6}},
        {{3, 4, 6, 7}}}},
      // Figure 7: a 4-cycle 0-1-4-2 with tets hanging on two adjacent nodes (1 1 2 3 2 3).
      {"hex6_cycle4a",
       CellType::Hex,
       6,
       {{0, 1}, {0, 2}, {0, 3}, {1, 4}, {1, 5}, {2, 4}},
       {{0, 3}, {1, 5}, {2, 3}, {2, 4}, {3, 5}, {4, 5}},
       {{{0, 1, 2, 4}},
        {{0, 2, 3, 4}},
        {{1, 2, 4, 6}},
        {{1, 4, 5, 6}},
        {{2, 3, 4, 6}},
        {{3, 4, 6, 7}}}},
      // Figure 8: a 4-cycle 0-1-4-2 with tets hanging on two opposite nodes (1 2 2 3 1 3).
      {"hex6_cycle4b",
       CellType::Hex,
       6,
       {{0, 1}, {0, 2}, {0, 3}, {1, 4}, {2, 4}, {4, 5}},
       {{0, 3}, {1, 3}, {1, 5}, {2, 3}, {2, 5}, {4, 5}},
       {{{0, 1, 2, 4}},
        {{0, 2, 3, 7}},
        {{0, 2, 4, 7}},
        {{1, 2, 4, 6}},
        {{1, 4, 5, 6}},
        {{2, 4, 6, 7}}}},
      // Figure 9: a 3-cycle 0-1-2, each with a corner tet hanging on it (1 1 1 3 3 3).
      {"hex6_cycle3",
       CellType::Hex,
       6,
       {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 4}, {2, 5}},
       {{0, 3}, {1, 4}, {2, 5}, {3, 4}, {3, 5}, {4, 5}},
       {{{0, 1, 2, 5}},
        {{0, 2, 3, 5}},
        {{0, 3, 5, 7}},
        {{0, 4, 5, 7}},
        {{2, 3, 5, 7}},
        {{2, 5, 6, 7}}}},
  };
}

using EdgeSet = std::set<std::pair<int, int>>;

EdgeSet edge_set(const std::vector<std::pair<int, int>>& edges, const std::vector<int>& perm) {
  EdgeSet out;
  for (const auto& [a, b] : edges) {
    const int pa = perm[a], pb = perm[b];
    out.insert({std::min(pa, pb), std::max(pa, pb)});
  }
  return out;
}

std::vector<int> identity_of(int n) {
  std::vector<int> id(n);
  std::iota(id.begin(), id.end(), 0);
  return id;
}

bool has_edge(const std::vector<std::pair<int, int>>& edges, int a, int b) {
  for (const auto& [x, y] : edges) {
    if ((x == a && y == b) || (x == b && y == a)) return true;
  }
  return false;
}

// The extended RF-graph of a realisation: links between tets sharing three corners, quads
// between tets with a face in the same quad face of the reference cell.
std::pair<EdgeSet, EdgeSet> realised_graph(const RFGraph& graph) {
  const CellDescriptor& d = descriptor(graph.type);
  const auto& tets = graph.realisation;
  auto on_quad = [&](const std::array<int, 4>& t, int f) {
    int hits = 0;
    for (int v : t) {
      for (int i = 0; i < 4; ++i) hits += (d.face[f][i] == v);
    }
    return hits == 3;
  };
  EdgeSet links, quads;
  for (int a = 0; a < graph.nb_nodes; ++a) {
    for (int b = a + 1; b < graph.nb_nodes; ++b) {
      int shared = 0;
      for (int v : tets[a]) shared += std::count(tets[b].begin(), tets[b].end(), v);
      if (shared == 3) links.insert({a, b});
      for (int f = 0; f < d.nb_faces; ++f) {
        if (d.face_size[f] == 4 && on_quad(tets[a], f) && on_quad(tets[b], f)) quads.insert({a, b});
      }
    }
  }
  return {links, quads};
}

// Reorders each graph's realisation so that its tet i is node i: finds the isomorphism between
// the realisation's graph and the graph data (asserting there is one: this checks the data).
std::vector<RFGraph> checked_graphs() {
  std::vector<RFGraph> graphs = make_graphs();
  for (RFGraph& g : graphs) {
    const auto [links, quads] = realised_graph(g);
    std::vector<int> perm(g.nb_nodes);
    std::iota(perm.begin(), perm.end(), 0);
    bool found = false;
    do {  // perm maps realisation tet -> graph node
      found = edge_set(std::vector<std::pair<int, int>>(links.begin(), links.end()), perm) ==
                  edge_set(g.links, identity_of(g.nb_nodes)) &&
              edge_set(std::vector<std::pair<int, int>>(quads.begin(), quads.end()), perm) ==
                  edge_set(g.quads, identity_of(g.nb_nodes));
    } while (!found && std::next_permutation(perm.begin(), perm.end()));
    HEXMERGE_ASSERT(found, "an RF-graph does not match its realisation");
    std::vector<std::array<int, 4>> ordered(g.nb_nodes);
    for (int t = 0; t < g.nb_nodes; ++t) ordered[perm[t]] = g.realisation[t];
    g.realisation = ordered;
  }
  return graphs;
}

}  // namespace

const std::vector<RFGraph>& rf_graphs() {
  static const std::vector<RFGraph> graphs = checked_graphs();
  return graphs;
}

std::vector<std::vector<int>> root_orbits(const RFGraph& graph) {
  const int n = graph.nb_nodes;
  std::vector<int> identity(n);
  std::iota(identity.begin(), identity.end(), 0);
  const EdgeSet links = edge_set(graph.links, identity);
  const EdgeSet quads = edge_set(graph.quads, identity);
  // Graphs have at most 6 nodes: trying all 720 permutations is instant.
  std::vector<int> orbit_of(n, -1);
  std::vector<std::vector<int>> orbits;
  std::vector<std::vector<int>> automorphisms;
  std::vector<int> perm = identity;
  do {
    if (edge_set(graph.links, perm) == links && edge_set(graph.quads, perm) == quads) {
      automorphisms.push_back(perm);
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  for (int v = 0; v < n; ++v) {
    if (orbit_of[v] >= 0) continue;
    std::set<int> members;
    for (const auto& aut : automorphisms) members.insert(aut[v]);
    for (int m : members) orbit_of[m] = static_cast<int>(orbits.size());
    orbits.emplace_back(members.begin(), members.end());
  }
  return orbits;
}

std::vector<SearchProgram> compile_search_programs(const RFGraph& graph, int graph_index) {
  std::vector<SearchProgram> programs;
  for (const auto& orbit : root_orbits(graph)) {
    const int root = orbit.front();
    SearchProgram program{graph_index, root, graph.type, graph.nb_nodes, {}, {}, {}};
    // Breadth-first assignment order over links; slot[g] = program node of graph node g.
    std::vector<int> slot(graph.nb_nodes, -1), order{root};
    slot[root] = 0;
    for (std::size_t head = 0; head < order.size(); ++head) {
      const int g = order[head];
      for (int h = 0; h < graph.nb_nodes; ++h) {
        if (slot[h] >= 0 || !has_edge(graph.links, g, h)) continue;
        slot[h] = static_cast<int>(order.size());
        order.push_back(h);
        auto node = [&](int x) { return static_cast<unsigned char>(slot[x]); };
        program.code.push_back({Instruction::Link, node(g), node(h)});
        // Checks that the new node enables: cycle-closing links, then quads.
        for (int k = 0; k + 1 < static_cast<int>(order.size()); ++k) {
          const int other = order[k];
          if (other != g && has_edge(graph.links, other, h)) {
            program.code.push_back({Instruction::Link, node(other), node(h)});
          }
        }
        for (int k = 0; k + 1 < static_cast<int>(order.size()); ++k) {
          const int other = order[k];
          if (has_edge(graph.quads, other, h)) {
            program.code.push_back({Instruction::Quad, node(other), node(h)});
          }
        }
      }
    }
    HEXMERGE_ASSERT(static_cast<int>(order.size()) == graph.nb_nodes, "RF-graph not connected");
    // Which LINKs bring a new vertex, replayed on the realisation in program order.
    program.adds_vertex.assign(program.code.size(), 0);
    std::set<int> seen(graph.realisation[root].begin(), graph.realisation[root].end());
    for (std::size_t pc = 0; pc < program.code.size(); ++pc) {
      const Instruction& in = program.code[pc];
      if (in.op != Instruction::Link) continue;
      const auto& tet = graph.realisation[order[in.b]];
      const std::size_t before = seen.size();
      seen.insert(tet.begin(), tet.end());
      program.adds_vertex[pc] = seen.size() > before ? 1 : 0;
    }
    program.quad_degree.assign(graph.nb_nodes, 0);
    for (const auto& [a, b] : graph.quads) {
      ++program.quad_degree[slot[a]];
      ++program.quad_degree[slot[b]];
    }
    programs.push_back(std::move(program));
  }
  return programs;
}

const std::vector<SearchProgram>& search_programs() {
  static const std::vector<SearchProgram> programs = [] {
    std::vector<SearchProgram> all;
    const auto& graphs = rf_graphs();
    for (int g = 0; g < static_cast<int>(graphs.size()); ++g) {
      auto p = compile_search_programs(graphs[g], g);
      all.insert(all.end(), p.begin(), p.end());
    }
    return all;
  }();
  return programs;
}

}  // namespace hexmerge
