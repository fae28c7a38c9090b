// The paper's RF-graphs and the search programs compiled from them, checked against independent
// oracles: the realisations are decompositions of the reference cells with exactly the graph's
// links and quads, the symmetry orbits are those of a brute-force automorphism search, and every
// program is the graph itself (an isomorphism sending node 0 to the root).
#include "hexmerge/recombine/rf_graph.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <set>
#include <vector>

namespace hexmerge::test {
namespace {

using Edge = std::pair<int, int>;

std::set<Edge> edge_set(const std::vector<std::pair<int, int>>& edges) {
  std::set<Edge> out;
  for (auto [a, b] : edges) out.insert({std::min(a, b), std::max(a, b)});
  return out;
}

std::set<int> vertex_set(const std::array<int, 4>& tet) { return {tet.begin(), tet.end()}; }

int shared(const std::array<int, 4>& a, const std::array<int, 4>& b) {
  int n = 0;
  for (int x : a) n += static_cast<int>(std::count(b.begin(), b.end(), x));
  return n;
}

// The faces (as vertex triples) of a tet of the realisation.
std::vector<std::set<int>> tet_faces(const std::array<int, 4>& t) {
  return {{t[1], t[2], t[3]}, {t[0], t[2], t[3]}, {t[0], t[1], t[3]}, {t[0], t[1], t[2]}};
}

// The solid (link) graph's single cycle length, 0 for a tree: prune leaves until none is left.
int cycle_length(int nb_nodes, const std::set<Edge>& links) {
  std::vector<int> degree(nb_nodes, 0);
  for (auto [a, b] : links) ++degree[a], ++degree[b];
  std::vector<bool> gone(nb_nodes, false);
  for (bool pruned = true; pruned;) {
    pruned = false;
    for (int v = 0; v < nb_nodes; ++v) {
      if (gone[v] || degree[v] > 1) continue;
      gone[v] = pruned = true;
      for (auto [a, b] : links) {
        if (a == v && !gone[b]) --degree[b];
        if (b == v && !gone[a]) --degree[a];
      }
    }
  }
  return static_cast<int>(std::count(gone.begin(), gone.end(), false));
}

// Every permutation p of the nodes with p(links) = links and p(quads) = quads.
std::vector<std::vector<int>> automorphisms(const RFGraph& g) {
  const auto links = edge_set(g.links), quads = edge_set(g.quads);
  std::vector<int> p(g.nb_nodes);
  std::iota(p.begin(), p.end(), 0);
  std::vector<std::vector<int>> out;
  const auto mapped = [&](const std::set<Edge>& edges) {
    std::set<Edge> m;
    for (auto [a, b] : edges) m.insert({std::min(p[a], p[b]), std::max(p[a], p[b])});
    return m;
  };
  do {
    if (mapped(links) == links && mapped(quads) == quads) out.push_back(p);
  } while (std::next_permutation(p.begin(), p.end()));
  return out;
}

TEST(rf_graph, the_papers_eight_graphs) {
  const auto& graphs = rf_graphs();
  ASSERT_EQ(graphs.size(), 8u);
  std::multiset<int> hex6_cycles;
  int hex5 = 0;
  for (const RFGraph& g : graphs) {
    const auto links = edge_set(g.links);
    // A decomposition's dual graph over internal faces is connected: at least a tree.
    EXPECT_GE(links.size(), static_cast<std::size_t>(g.nb_nodes - 1)) << g.name;
    EXPECT_EQ(edge_set(g.quads).size(), static_cast<std::size_t>(descriptor(g.type).nb_quad_faces))
        << g.name << ": one dashed edge per quadrilateral face";
    if (g.type == CellType::Pyramid) {
      EXPECT_EQ(g.nb_nodes, 2);
    }
    if (g.type == CellType::Prism) {
      EXPECT_EQ(g.nb_nodes, 3);
    }
    if (g.type == CellType::Hex && g.nb_nodes == 5) {
      ++hex5;
      EXPECT_EQ(cycle_length(g.nb_nodes, links), 0) << g.name;
    } else if (g.type == CellType::Hex) {
      EXPECT_EQ(g.nb_nodes, 6) << g.name;
      hex6_cycles.insert(cycle_length(g.nb_nodes, links));
    }
  }
  EXPECT_EQ(hex5, 1);
  EXPECT_EQ(hex6_cycles, (std::multiset<int>{3, 4, 4, 5, 6}));  // Theorem 1
}

TEST(rf_graph, realisations_decompose_the_cell_with_exactly_the_graphs_edges) {
  for (const RFGraph& g : rf_graphs()) {
    SCOPED_TRACE(g.name);
    const CellDescriptor& d = descriptor(g.type);
    ASSERT_EQ(static_cast<int>(g.realisation.size()), g.nb_nodes);
    std::set<int> used;
    for (const auto& t : g.realisation) {
      EXPECT_EQ(vertex_set(t).size(), 4u);
      for (int v : t) EXPECT_TRUE(v >= 0 && v < d.nb_vertices);
      used.insert(t.begin(), t.end());
    }
    EXPECT_EQ(static_cast<int>(used.size()), d.nb_vertices) << "a corner of the cell unused";
    // Links: the pairs of tets sharing a face (three vertices).
    std::set<Edge> links, quads;
    for (int a = 0; a < g.nb_nodes; ++a) {
      for (int b = a + 1; b < g.nb_nodes; ++b) {
        if (shared(g.realisation[a], g.realisation[b]) == 3) links.insert({a, b});
      }
    }
    EXPECT_EQ(links, edge_set(g.links));
    // Every face of a tet is internal (shared with one other tet) or inside one face of the
    // cell; triangles of the cell are covered once, quads twice, by tets that form the quads.
    std::vector<int> cover(d.nb_faces, 0);
    std::map<int, std::vector<int>> quad_tets;  // cell face -> tets with a triangle on it
    for (int t = 0; t < g.nb_nodes; ++t) {
      for (const std::set<int>& face : tet_faces(g.realisation[t])) {
        int internal = 0;
        for (int u = 0; u < g.nb_nodes; ++u) {
          const std::set<int> other = vertex_set(g.realisation[u]);
          if (u != t && std::includes(other.begin(), other.end(), face.begin(), face.end())) {
            ++internal;
          }
        }
        int on = -1;
        for (int f = 0; f < d.nb_faces; ++f) {
          const std::set<int> cell_face(d.face[f].begin(), d.face[f].begin() + d.face_size[f]);
          if (std::includes(cell_face.begin(), cell_face.end(), face.begin(), face.end())) on = f;
        }
        EXPECT_TRUE((internal == 1) != (on >= 0)) << "tet " << t
                                                  << ": a face neither internal "
                                                     "nor on the boundary, or both";
        if (on >= 0) {
          ++cover[on];
          if (d.face_size[on] == 4) quad_tets[on].push_back(t);
        }
      }
    }
    for (int f = 0; f < d.nb_faces; ++f) EXPECT_EQ(cover[f], d.face_size[f] == 4 ? 2 : 1) << f;
    for (const auto& [f, tets] : quad_tets) {
      ASSERT_EQ(tets.size(), 2u);
      EXPECT_NE(tets[0], tets[1]) << "both triangles of quad face " << f << " in one tet";
      quads.insert({std::min(tets[0], tets[1]), std::max(tets[0], tets[1])});
    }
    EXPECT_EQ(quads, edge_set(g.quads));
  }
}

TEST(rf_graph, root_orbits_are_the_orbits_of_every_automorphism) {
  for (const RFGraph& g : rf_graphs()) {
    SCOPED_TRACE(g.name);
    std::vector<std::set<int>> expected(g.nb_nodes);
    for (const auto& p : automorphisms(g)) {
      for (int v = 0; v < g.nb_nodes; ++v) expected[v].insert(p[v]);
    }
    const auto orbits = root_orbits(g);
    std::vector<int> seen(g.nb_nodes, 0);
    for (const auto& orbit : orbits) {
      ASSERT_FALSE(orbit.empty());
      EXPECT_EQ(std::set<int>(orbit.begin(), orbit.end()), expected[orbit.front()]);
      for (int v : orbit) ++seen[v];
    }
    EXPECT_EQ(seen, std::vector<int>(g.nb_nodes, 1)) << "the orbits do not partition the nodes";
  }
}

// A permutation of the program's nodes onto the graph's (node 0 onto the root) that maps the
// program's LINKs onto the graph's links and its QUADs onto its quads; empty when none does.
std::vector<std::vector<int>> isomorphisms(const SearchProgram& program, const RFGraph& g) {
  std::set<Edge> links, quads;
  for (const Instruction& i : program.code) {
    const Edge e{std::min<int>(i.a, i.b), std::max<int>(i.a, i.b)};
    (i.op == Instruction::Link ? links : quads).insert(e);
  }
  std::vector<std::vector<int>> out;
  std::vector<int> p(g.nb_nodes);
  std::iota(p.begin(), p.end(), 0);
  do {
    if (p[0] != program.root) continue;
    std::set<Edge> ml, mq;
    for (auto [a, b] : links) ml.insert({std::min(p[a], p[b]), std::max(p[a], p[b])});
    for (auto [a, b] : quads) mq.insert({std::min(p[a], p[b]), std::max(p[a], p[b])});
    if (ml == edge_set(g.links) && mq == edge_set(g.quads)) out.push_back(p);
  } while (std::next_permutation(p.begin(), p.end()));
  return out;
}

TEST(rf_graph, every_program_is_its_graph_rooted_at_one_node_per_orbit) {
  const auto& graphs = rf_graphs();
  std::map<int, int> programs_per_graph;
  for (const SearchProgram& program : search_programs()) {
    const RFGraph& g = graphs.at(program.graph);
    SCOPED_TRACE(g.name + " root " + std::to_string(program.root));
    ++programs_per_graph[program.graph];
    EXPECT_EQ(program.type, g.type);
    EXPECT_EQ(program.nb_nodes, g.nb_nodes);
    // Nodes are assigned in order, each by a LINK from an assigned node; checks name only
    // assigned nodes.
    int assigned = 1;
    for (const Instruction& i : program.code) {
      ASSERT_LT(i.a, assigned);
      if (i.op == Instruction::Link && i.b == assigned) {
        ++assigned;
      } else {
        ASSERT_LT(i.b, assigned);
      }
    }
    EXPECT_EQ(assigned, g.nb_nodes);
    EXPECT_EQ(program.code.size(), edge_set(g.links).size() + edge_set(g.quads).size())
        << "every edge checked exactly once";
    const auto maps = isomorphisms(program, g);
    ASSERT_FALSE(maps.empty()) << "the program is not its graph";
    // Quad degree per program node: its dashed edges in the graph.
    for (int k = 0; k < g.nb_nodes; ++k) {
      int degree = 0;
      for (auto [a, b] : edge_set(g.quads)) degree += (a == maps[0][k]) + (b == maps[0][k]);
      EXPECT_EQ(program.quad_degree.at(k), degree) << "node " << k;
    }
    // adds_vertex: the new tet brings a vertex of the realisation not yet matched, for some
    // placement of the program on the realisation.
    const bool placed = std::any_of(maps.begin(), maps.end(), [&](const std::vector<int>& p) {
      std::set<int> matched = vertex_set(g.realisation[p[0]]);
      int next = 1;
      for (std::size_t s = 0; s < program.code.size(); ++s) {
        const Instruction& i = program.code[s];
        if (i.op != Instruction::Link || i.b != next) continue;
        const auto& tet = g.realisation[p[i.b]];
        const bool adds =
            std::any_of(tet.begin(), tet.end(), [&](int v) { return matched.count(v) == 0; });
        if (adds != (program.adds_vertex.at(s) != 0)) return false;
        matched.insert(tet.begin(), tet.end());
        ++next;
      }
      return true;
    });
    EXPECT_TRUE(placed) << "adds_vertex matches no placement of the program";
  }
  int hex_programs = 0;
  for (std::size_t g = 0; g < graphs.size(); ++g) {
    EXPECT_EQ(programs_per_graph[static_cast<int>(g)],
              static_cast<int>(root_orbits(graphs[g]).size()))
        << graphs[g].name << ": one program per orbit";
    if (graphs[g].type == CellType::Hex) hex_programs += programs_per_graph[static_cast<int>(g)];
  }
  EXPECT_EQ(hex_programs, 15);
  EXPECT_EQ(search_programs().size(), 18u);  // the prism has two orbits: its end tets, its middle
}

}  // namespace
}  // namespace hexmerge::test
