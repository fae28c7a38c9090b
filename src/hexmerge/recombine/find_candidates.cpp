#include "hexmerge/recombine/find_candidates.h"

#include <algorithm>
#include <utility>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/spatial_order.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/quad_pairs.h"
#include "hexmerge/recombine/rf_graph.h"

namespace hexmerge {
namespace {

constexpr int kMaxNodes = 6;
constexpr int kMaxQuads = 6;

const CellDescriptor& kTet = descriptor(CellType::Tet);

// Sorting networks: branch-free compare-exchanges, for the small sorts every match makes.
template <std::size_t N, std::size_t M>
std::array<index_t, N> sorted_by(std::array<index_t, N> a,
                                 const std::array<std::pair<int, int>, M>& network) {
  for (const auto& [i, j] : network) {
    const index_t lo = std::min(a[i], a[j]);
    a[j] = std::max(a[i], a[j]);
    a[i] = lo;
  }
  return a;
}

std::array<index_t, 4> sorted(const std::array<index_t, 4>& a) { return sorted4(a); }

// Whether v is among the n ids at `ids`. (A plain loop: std::find is a call on these short
// lists, 3k instructions per tet on lattice meshes.)
bool contains(const index_t* ids, int n, index_t v) {
  bool found = false;
  for (int i = 0; i < n; ++i) found |= ids[i] == v;
  return found;
}

// a == b for face keys, element by element (std::array's == calls memcmp).
bool same_key(const std::array<index_t, 4>& a, const std::array<index_t, 4>& b) {
  return ((a[0] ^ b[0]) | (a[1] ^ b[1]) | (a[2] ^ b[2]) | (a[3] ^ b[3])) == 0;
}

std::array<index_t, 8> sorted(const std::array<index_t, 8>& a) {
  static constexpr std::array<std::pair<int, int>, 19> kNetwork{{{0, 2},
                                                                 {1, 3},
                                                                 {4, 6},
                                                                 {5, 7},
                                                                 {0, 4},
                                                                 {1, 5},
                                                                 {2, 6},
                                                                 {3, 7},
                                                                 {0, 1},
                                                                 {2, 3},
                                                                 {4, 5},
                                                                 {6, 7},
                                                                 {2, 4},
                                                                 {3, 5},
                                                                 {1, 4},
                                                                 {3, 6},
                                                                 {1, 2},
                                                                 {3, 4},
                                                                 {5, 6}}};
  return sorted_by(a, kNetwork);
}

// The vertex joined to v by an edge of one of the faces, not in `exclude` (3 or 4 vertices: a
// prism's or a hexahedron's base). NO_VERTEX when there is none or more than one.
index_t unique_other_neighbor(index_t v, const std::array<index_t, 4>* faces, const int* sizes,
                              int nb_faces, const index_t* exclude, int nex) {
  HEXMERGE_ASSERT(nex == 3 || nex == 4, "unique_other_neighbor: a base has 3 or 4 vertices");
  // Four compares whatever nex (the fourth repeats the first for a triangle): a loop of nex
  // steps was 3k instructions per tet on lattice meshes.
  const index_t e0 = exclude[0], e1 = exclude[1], e2 = exclude[2], e3 = exclude[nex - 1];
  index_t found = NO_VERTEX;
  for (int f = 0; f < nb_faces; ++f) {
    const int n = sizes[f];
    // v's places in the face, bit i (four compares, the fourth masked off for a triangle): most
    // faces do not hold v.
    const std::array<index_t, 4>& face = faces[f];
    unsigned at = static_cast<unsigned>(face[0] == v) | static_cast<unsigned>(face[1] == v) << 1 |
                  static_cast<unsigned>(face[2] == v) << 2 |
                  static_cast<unsigned>(n == 4 && face[3] == v) << 3;
    for (; at != 0; at &= at - 1) {
      static constexpr signed char kLowest[16] = {-1, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0};
      const int i = kLowest[at];
      // Its two neighbours along the face (no modulo: a division per vertex of every face).
      const index_t around[2] = {faces[f][i + 1 == n ? 0 : i + 1],
                                 faces[f][i == 0 ? n - 1 : i - 1]};
      for (const index_t u : around) {
        if ((u == e0) | (u == e1) | (u == e2) | (u == e3)) continue;
        if (found != NO_VERTEX && found != u) return NO_VERTEX;
        found = u;
      }
    }
  }
  return found;
}

}  // namespace

// Two tets sharing a face, whose base triangles leave out the same vertex, are the pyramid with
// that apex: each tet's other two faces through the apex are the four sides. (The same answer as
// the general assembly, without its search: pyramids are most of the matches.)
bool assemble_pyramid(const TetMesh& mesh, const TetTopology& topology, const index_t* tets, int nb,
                      const std::array<index_t, 2>* quad_pairs, int nb_quad_pairs,
                      std::array<index_t, 8>& vertices) {
  if (nb != 2 || nb_quad_pairs != 1) return false;
  const index_t t0 = quad_pairs[0][0] / 4, t1 = quad_pairs[0][1] / 4;
  const int f0 = static_cast<int>(quad_pairs[0][0] % 4),
            f1 = static_cast<int>(quad_pairs[0][1] % 4);
  if (t0 == t1 || !((t0 == tets[0] && t1 == tets[1]) || (t0 == tets[1] && t1 == tets[0]))) {
    return false;
  }
  const index_t apex = mesh.tet(t0)[f0];
  if (mesh.tet(t1)[f1] != apex) return false;
  // The shared face holds the apex and the base's diagonal: it is the face of t0 opposite the
  // vertex that t1 lacks.
  bool shares_face = false;
  for (int f = 0; f < 4; ++f) shares_face = shares_face || topology.neighbor(t0, f) == t1;
  if (!shares_face) return false;
  std::array<index_t, 4> base;
  if (!quad_from_triangles(tet_face(mesh, t0, f0), tet_face(mesh, t1, f1), base)) return false;
  vertices.fill(NO_VERTEX);
  for (int i = 0; i < 4; ++i) vertices[i] = base[(4 - i) % 4];  // reversed: normal into the cell
  vertices[4] = apex;
  return true;
}

bool assemble_cell(const TetMesh& mesh, const TetTopology& topology, CellType type,
                   const index_t* tets, int nb, const std::array<index_t, 2>* quad_pairs,
                   int nb_quad_pairs, std::array<index_t, 8>& vertices) {
  if (type == CellType::Pyramid) {
    return assemble_pyramid(mesh, topology, tets, nb, quad_pairs, nb_quad_pairs, vertices);
  }
  const CellDescriptor& d = descriptor(type);
  // The group's ids modulo 64 as bits first: about half the neighbours are outside, and most of
  // those are told apart without the search.
  std::uint64_t group_bits = 0;
  for (int i = 0; i < nb; ++i) group_bits |= std::uint64_t{1} << (tets[i] & 63u);
  auto in_group = [&](index_t t) {
    return ((group_bits >> (t & 63u)) & 1u) != 0 && contains(tets, nb, t);
  };
  // The group's boundary triangles (4 * tet + face), each marked when a quad uses it.
  std::array<index_t, 24> boundary;
  std::array<bool, 24> used{};
  int nb_boundary = 0;
  for (int i = 0; i < nb; ++i) {
    for (int f = 0; f < 4; ++f) {
      const index_t n = topology.neighbor(tets[i], f);
      if (n != NO_CELL && in_group(n)) continue;
      if (nb_boundary == static_cast<int>(boundary.size())) return false;  // too many for any cell
      boundary[nb_boundary++] = 4 * tets[i] + f;
    }
  }
  const int nb_tris = d.nb_faces - d.nb_quad_faces;
  if (nb_boundary != 2 * d.nb_quad_faces + nb_tris) return false;
  if (nb_quad_pairs != d.nb_quad_faces) return false;

  // The cell's faces as outward cycles, with their sorted vertex keys.
  std::array<std::array<index_t, 4>, 6> faces, keys;
  std::array<int, 6> sizes;
  int nb_faces = 0;
  auto use = [&](index_t code) {
    for (int i = 0; i < nb_boundary; ++i) {
      if (boundary[i] == code && !used[i]) return used[i] = true;
    }
    return false;
  };
  for (int q = 0; q < nb_quad_pairs; ++q) {
    const auto& pair = quad_pairs[q];
    if (!use(pair[0]) || !use(pair[1])) return false;
    if (!quad_from_triangles(tet_face(mesh, pair[0] / 4, pair[0] % 4),
                             tet_face(mesh, pair[1] / 4, pair[1] % 4), faces[nb_faces])) {
      return false;
    }
    sizes[nb_faces++] = 4;
  }
  for (int i = 0; i < nb_boundary; ++i) {
    if (used[i]) continue;
    const auto tri = tet_face(mesh, boundary[i] / 4, boundary[i] % 4);
    faces[nb_faces] = {tri[0], tri[1], tri[2], NO_VERTEX};
    sizes[nb_faces++] = 3;
  }
  for (int g = 0; g < nb_faces; ++g) keys[g] = sorted(faces[g]);

  // Base face, reversed so that its normal points into the cell (cell_type.h).
  vertices.fill(NO_VERTEX);
  const int base_size = d.face_size[0];
  int base = 0;
  while (base < nb_faces && sizes[base] != base_size) ++base;
  if (base == nb_faces) return false;
  for (int i = 0; i < base_size; ++i) vertices[i] = faces[base][(base_size - i) % base_size];
  if (type == CellType::Pyramid) {
    // The apex: the one vertex of the group not on the base.
    for (int g = 0; g < nb_faces; ++g) {
      for (int i = 0; i < sizes[g]; ++i) {
        if (std::find(vertices.begin(), vertices.begin() + 4, faces[g][i]) ==
            vertices.begin() + 4) {
          vertices[4] = faces[g][i];
        }
      }
    }
  } else {
    // Prism and hex: the vertex above base vertex i is its only neighbour off the base.
    for (int i = 0; i < base_size; ++i) {
      vertices[base_size + i] = unique_other_neighbor(vertices[i], faces.data(), sizes.data(),
                                                      nb_faces, vertices.data(), base_size);
      if (vertices[base_size + i] == NO_VERTEX) return false;
    }
  }
  for (int i = 0; i < d.nb_vertices; ++i) {
    if (vertices[i] == NO_VERTEX) return false;
    for (int j = 0; j < i; ++j) {
      if (vertices[i] == vertices[j]) return false;
    }
  }
  // Verification: the cell's faces are exactly the group's boundary faces.
  std::array<bool, 6> matched{};
  for (int f = 0; f < d.nb_faces; ++f) {
    std::array<index_t, 4> cf{NO_VERTEX, NO_VERTEX, NO_VERTEX, NO_VERTEX};
    for (int i = 0; i < d.face_size[f]; ++i) cf[i] = vertices[d.face[f][i]];
    cf = sorted(cf);
    bool found = false;
    for (int g = 0; g < nb_faces && !found; ++g) {
      if (!matched[g] && sizes[g] == d.face_size[f] && same_key(keys[g], cf))
        matched[g] = found = true;
    }
    if (!found) return false;
  }
  return true;
}

namespace {

// A match as the search makes it (the matches of one root, until they are kept).
struct Match {
  std::array<index_t, 8> vertices;
  std::array<index_t, kMaxNodes> tets;  // sorted; first nb_tets used
  float quality;
  CellType type;
  std::uint8_t graph;
  std::uint8_t nb_tets;
};

// The kept matches of one chunk of roots, held until every chunk is searched and then put in
// root order (the search's peak of memory): per match 16 bytes, its corners as places among
// its tets' vertices, and its tets in one list.
struct ChunkMatches {
  struct Packed {
    std::uint64_t corners;  // corner j: bits 5j to 5j + 4, 4 * (place of a tet) + its vertex
    float quality;
    CellType type;
    std::uint8_t graph;
    std::uint8_t nb_tets;
  };
  static_assert(sizeof(Packed) == 16, "the per-chunk lists are the search's peak of memory");
  static_assert(4 * kMaxNodes <= 32, "a corner's place is 5 bits");
  std::vector<Packed> matches;
  std::vector<index_t> tets;  // the matches' tets (input ids), one after the other

  // m's corners are vertices of its tets, which are the input's tets of those ids.
  void push_back(const TetMesh& input, const Match& m) {
    std::uint64_t corners = 0;
    const int nv = descriptor(m.type).nb_vertices;
    for (int j = 0; j < nv; ++j) {
      int place = -1;
      for (int i = 0; i < m.nb_tets && place < 0; ++i) {
        const index_t* q = input.tet(m.tets[i]);
        for (int k = 0; k < 4; ++k)
          if (q[k] == m.vertices[j]) place = 4 * i + k;
      }
      HEXMERGE_ASSERT(place >= 0, "find_candidates: a corner of a match is not on its tets");
      corners |= static_cast<std::uint64_t>(place) << (5 * j);
    }
    matches.push_back({corners, m.quality, m.type, m.graph, m.nb_tets});
    tets.insert(tets.end(), m.tets.begin(), m.tets.begin() + m.nb_tets);
  }

  void shrink_to_fit() {
    matches.shrink_to_fit();
    tets.shrink_to_fit();
  }
};

// The matches of every chunk as candidates, in the order of their roots' input ids (a stable
// counting sort on the root, each group's smallest tet), each root's own in the order they were
// found. Each chunk's lists are freed once its matches are placed.
Candidates in_root_order(const TetMesh& input, std::vector<ChunkMatches>& per_chunk) {
  const index_t nt = input.nb_tets();
  // Per root: where its first candidate and its first candidate's first tet go.
  std::vector<std::size_t> start(static_cast<std::size_t>(nt) + 1, 0);
  std::vector<std::size_t> tet_start(static_cast<std::size_t>(nt) + 1, 0);
  for (const ChunkMatches& chunk : per_chunk) {
    std::size_t at = 0;
    for (const ChunkMatches::Packed& m : chunk.matches) {
      const index_t root = chunk.tets[at];
      ++start[root + 1];
      tet_start[root + 1] += m.nb_tets;
      at += m.nb_tets;
    }
  }
  for (index_t t = 0; t < nt; ++t) {
    start[t + 1] += start[t];
    tet_start[t + 1] += tet_start[t];
  }
  if (tet_start[nt] >= NO_INDEX) {
    throw ResourceError("the candidates hold more than 2^32 - 2 tets in all");
  }
  std::vector<Candidate> all(start[nt]);
  std::vector<index_t> tets(tet_start[nt]);
  for (ChunkMatches& chunk : per_chunk) {
    std::size_t at = 0;
    for (const ChunkMatches::Packed& m : chunk.matches) {
      const index_t* group = chunk.tets.data() + at;
      Candidate& c = all[start[group[0]]++];
      std::size_t& first = tet_start[group[0]];
      c.vertices.fill(NO_VERTEX);
      for (int j = 0; j < descriptor(m.type).nb_vertices; ++j) {
        const unsigned place = (m.corners >> (5 * j)) & 31u;
        c.vertices[j] = input.tet(group[place / 4])[place % 4];
      }
      c.first_tet = static_cast<index_t>(first);
      std::copy_n(group, m.nb_tets, tets.begin() + first);
      first += m.nb_tets;
      at += m.nb_tets;
      c.type = m.type;
      c.graph = m.graph;
      c.nb_tets = m.nb_tets;
      c.quality = m.quality;
    }
    chunk = ChunkMatches();
  }
  return Candidates(std::move(all), std::move(tets));
}

// The enabled search programs merged into one tree: programs that begin with the same steps
// (the same instruction with the same filters) run those steps once for all of them. Node 0 is
// the root (no instruction); each other node is one instruction, and lists the programs whose
// code ends there.
//
// A node's children that run the same instruction with different filters (a new node's
// quad_degree and adds_vertex, the root's quad_degree) form one group: the instruction runs once
// for the group (one walk over a tet's free faces, over a face's quad partners), and each of its
// results goes on into the members whose filters it passes. That interleaves the members'
// programs, but not the steps of any one program, whose matches come in the same order as when
// it ran alone: run_from keeps them program by program.
class SearchTree {
 public:
  struct Node {
    Instruction in{};
    unsigned char adds_vertex = 0;       // a LINK to a new node: SearchProgram::adds_vertex
    unsigned char quad_degree = 0;       // a LINK: the new node's SearchProgram::quad_degree
    unsigned char root_quad_degree = 0;  // a program's first instruction: its node 0's
    bool assigns = false;                // a LINK to a new node
    std::vector<int> children;
    std::vector<int> programs;  // indices into search_programs()
  };
  /// Children of one node that run the same instruction, in the order of their first member;
  /// their filters as masks of members (bit i: members[i]).
  struct Group {
    enum Kind : unsigned char { LinkNew, LinkClose, Quad };
    Instruction in{};
    Kind kind = LinkNew;       // a LINK to a new node, a LINK closing a cycle, a QUAD
    std::vector<int> members;  // nodes, at most 32
    unsigned adds_vertex = 0;  // adds_vertex set
    std::array<unsigned, 5> quad_degree_up_to{};       // [k]: quad_degree <= k
    std::array<unsigned, 5> root_quad_degree_up_to{};  // [k]: root_quad_degree <= k
  };

  explicit SearchTree(const std::array<bool, NB_CELL_TYPES>& types) {
    const auto& programs = search_programs();
    for (int p = 0; p < static_cast<int>(programs.size()); ++p) {
      const SearchProgram& program = programs[p];
      if (!types[static_cast<int>(program.type)]) continue;
      int at = 0;
      int nb_assigned = 1;
      for (std::size_t pc = 0; pc < program.code.size(); ++pc) {
        Node step;
        step.in = program.code[pc];
        step.assigns = step.in.op == Instruction::Link && step.in.b == nb_assigned;
        nb_assigned += step.assigns;
        step.adds_vertex = program.adds_vertex[pc];
        if (step.in.op == Instruction::Link) step.quad_degree = program.quad_degree[step.in.b];
        if (pc == 0) step.root_quad_degree = program.quad_degree[0];
        at = child(at, step);
      }
      nodes_[at].programs.push_back(p);
    }
    groups_.resize(nodes_.size());
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      for (const int c : nodes_[i].children) {
        const Instruction& in = nodes_[c].in;
        auto g = std::find_if(groups_[i].begin(), groups_[i].end(), [&](const Group& o) {
          return o.in.op == in.op && o.in.a == in.a && o.in.b == in.b;
        });
        if (g == groups_[i].end()) {
          const Group::Kind kind = in.op == Instruction::Quad ? Group::Quad
                                   : nodes_[c].assigns        ? Group::LinkNew
                                                              : Group::LinkClose;
          g = groups_[i].insert(g, Group{in, kind, {}});
        }
        HEXMERGE_ASSERT(g->members.size() < 32, "SearchTree: a group's members are a 32-bit mask");
        const unsigned bit = 1u << g->members.size();
        const Node& n = nodes_[c];
        g->members.push_back(c);
        if (n.adds_vertex != 0) g->adds_vertex |= bit;
        for (int k = 0; k < 5; ++k) {
          if (n.quad_degree <= k) g->quad_degree_up_to[k] |= bit;
          if (n.root_quad_degree <= k) g->root_quad_degree_up_to[k] |= bit;
        }
      }
    }
  }

  const Node& node(int i) const { return nodes_[i]; }
  /// The groups of node i's children.
  const std::vector<Group>& groups(int i) const { return groups_[i]; }
  int nb_programs() const { return static_cast<int>(search_programs().size()); }

 private:
  // The child of `parent` that runs `step`, made when missing.
  int child(int parent, const Node& step) {
    for (const int c : nodes_[parent].children) {
      const Node& n = nodes_[c];
      if (n.in.op == step.in.op && n.in.a == step.in.a && n.in.b == step.in.b &&
          n.adds_vertex == step.adds_vertex && n.quad_degree == step.quad_degree &&
          n.root_quad_degree == step.root_quad_degree) {
        return c;
      }
    }
    nodes_.push_back(step);
    nodes_[parent].children.push_back(static_cast<int>(nodes_.size()) - 1);
    return static_cast<int>(nodes_.size()) - 1;
  }

  std::vector<Node> nodes_{1};
  std::vector<std::vector<Group>> groups_;  // per node
};

// One search: the interpreter's state while it runs the search tree from one root tet.
//
// It works on the renumbered mesh (spatial_order.h); its candidates name the input's tets, and
// every choice that depends on tet ids (which tet is the root, the order of a group's tets) is
// made on the input's ids, so the result is the same as a search on the input itself.
class Matcher {
 public:
  /// @param[in] input_id  the input's id of each tet of `mesh`
  /// @param[in] input     the mesh `mesh` renumbers (the same vertices)
  Matcher(const TetMesh& input, const TetMesh& mesh, const TetTopology& topology,
          const QuadPairs& quad_pairs, const std::vector<index_t>& input_id,
          const AcceptanceCriteria& criteria, const SearchTree& tree, ChunkMatches& out)
      : input_(input),
        mesh_(mesh),
        topology_(topology),
        pairs_(quad_pairs),
        input_id_(input_id),
        criteria_(criteria),
        tree_(tree),
        programs_(search_programs()),
        split_regions_(criteria.respect_regions && !mesh.regions.empty()),
        found_(tree.nb_programs()),
        found_quads_(tree.nb_programs()),
        out_(out) {}

  void run_from(index_t root) {
    root_ = root;
    root_input_id_ = input_id_[root];
    root_region_ = mesh_.region(root);
    root_quad_faces_ = quad_faces(root, -1);
    nb_assigned_ = 1;
    node_.fill(NO_CELL);
    node_[0] = root;
    node_bits_[1] = bit_of(root);
    used_[0] = 0;
    const index_t* q = mesh_.tet(root);
    nb_vertices_ = 4;
    vertex_.fill(NO_VERTEX);
    std::copy(q, q + 4, vertex_.begin());
    for (int i = 0; i < 4; ++i) vertex_bits_[i + 1] = vertex_bits_[i] | bit_of(q[i]);
    nb_quads_ = 0;
    descend(0);
    // Program by program, as if each ran alone in turn: the same group may be matched again
    // through an automorphism that fixes the root, and the first match is kept.
    kept_.clear();
    for (std::vector<Match>& found : found_) {
      for (const Match& c : found) {
        if (!seen(c)) kept_.push_back(c);
      }
      found.clear();
    }
    for (const Match& c : kept_) out_.push_back(input_, c);
    for (std::vector<QuadSet>& quads : found_quads_) quads.clear();
  }

 private:
  // Unassigned node_ and vertex_ slots hold NO_INDEX, so these look-ups need no branch.
  bool in_match(index_t t) const {
    if ((node_bits_[nb_assigned_] & bit_of(t)) == 0) return false;
    bool found = false;
    for (const index_t n : node_) found |= n == t;
    return found;
  }
  // (Most tets and apexes asked about are not there: their bit among the match's ids modulo 64
  // tells, without the compares.)
  bool has_vertex(index_t v) const {
    if ((vertex_bits_[nb_vertices_] & bit_of(v)) == 0) return false;
    bool found = false;
    for (const index_t u : vertex_) found |= u == v;
    return found;
  }
  static std::uint64_t bit_of(index_t v) { return std::uint64_t{1} << (v & 63u); }

  // The programs ending at node `i` have a match; its children continue the others.
  void descend(int i) {
    for (const int p : tree_.node(i).programs) finish(programs_[p], found_[p], found_quads_[p]);
    for (const SearchTree::Group& g : tree_.groups(i)) {
      if (g.kind == SearchTree::Group::LinkNew)
        link_new(g);
      else if (g.kind == SearchTree::Group::LinkClose)
        link_close(g);
      else
        quad(g);
    }
  }

  // The group's instruction: a LINK to a new node.
  void link_new(const SearchTree::Group& g) {
    const Instruction& in = g.in;
    const index_t ta = node_[in.a];
    // The members whose filter on the root passes (it is 0 but in programs' first steps).
    const unsigned live = g.root_quad_degree_up_to[root_quad_faces_];
    if (live == 0) return;
    for (unsigned free = ~used_[in.a] & 15u; free != 0; free &= free - 1) {
      const int f = lowest_bit(free);
      const index_t nb = topology_.neighbor(ta, f);
      // The root is the group's smallest tet: each group is found from one root only.
      if (nb == NO_CELL || input_id_[nb] < root_input_id_) continue;
      if (split_regions_ && mesh_.regions[nb] != root_region_) continue;
      const int fn = topology_.neighbor_face(ta, f);
      // The node's tet needs as many faces that can pair into quads as the node has quads.
      const unsigned fit = live & g.quad_degree_up_to[quad_faces(nb, fn)];
      if (fit == 0) continue;
      const index_t apex = mesh_.tet(nb)[fn];
      const bool new_vertex = !has_vertex(apex);
      const unsigned pass = fit & (new_vertex ? g.adds_vertex : ~g.adds_vertex);
      if (pass == 0) continue;
      // A tet of the match has all its vertices in it: asked last, and only when the apex is
      // not new (the cheaper tests reject most neighbours, and the answer is the same).
      if (!new_vertex && in_match(nb)) continue;
      if (new_vertex) {
        vertex_bits_[nb_vertices_ + 1] = vertex_bits_[nb_vertices_] | bit_of(apex);
        vertex_[nb_vertices_++] = apex;
      }
      node_[nb_assigned_] = nb;
      node_bits_[nb_assigned_ + 1] = node_bits_[nb_assigned_] | bit_of(nb);
      used_[nb_assigned_] = static_cast<unsigned char>(1u << fn);
      ++nb_assigned_;
      used_[in.a] |= static_cast<unsigned char>(1u << f);
      for (unsigned m = pass; m != 0; m &= m - 1) descend(g.members[lowest_set_bit(m)]);
      used_[in.a] &= static_cast<unsigned char>(~(1u << f));
      node_[--nb_assigned_] = NO_CELL;
      if (new_vertex) vertex_[--nb_vertices_] = NO_VERTEX;
    }
  }

  // A LINK between two assigned nodes: they share a face, free on both.
  void link_close(const SearchTree::Group& g) {
    const Instruction& in = g.in;
    const index_t ta = node_[in.a];
    const index_t tb = node_[in.b];
    for (int f = 0; f < 4; ++f) {
      if (topology_.neighbor(ta, f) != tb) continue;
      const int fb = topology_.neighbor_face(ta, f);
      if ((used_[in.a] & (1u << f)) || (used_[in.b] & (1u << fb))) return;
      used_[in.a] |= static_cast<unsigned char>(1u << f);
      used_[in.b] |= static_cast<unsigned char>(1u << fb);
      for (const int c : g.members) descend(c);
      used_[in.a] &= static_cast<unsigned char>(~(1u << f));
      used_[in.b] &= static_cast<unsigned char>(~(1u << fb));
      return;
    }
  }

  // A QUAD: a free face of each pairs into a quad.
  void quad(const SearchTree::Group& g) {
    const Instruction& in = g.in;
    const index_t ta = node_[in.a];
    const index_t tb = node_[in.b];
    if (!pairs_.may_pair(ta, tb)) return;
    for (unsigned free = pairs_.mask(ta) & ~used_[in.a] & 15u; free != 0; free &= free - 1) {
      const int fa = lowest_bit(free);
      // Whether face fa is internal is asked only once a partner on tb is found.
      int external = -1;
      const QuadPartner* const last = pairs_.end(ta, fa);  // (read once: descend writes)
      for (const QuadPartner* p = pairs_.begin(ta, fa); p != last; ++p) {
        if (p->face / 4 != tb) continue;
        if (external < 0) external = !internal(topology_.neighbor(ta, fa));
        if (!external) break;
        const int fb = static_cast<int>(p->face % 4);
        if ((used_[in.b] & (1u << fb)) || internal(topology_.neighbor(tb, fb))) continue;
        used_[in.a] |= static_cast<unsigned char>(1u << fa);
        used_[in.b] |= static_cast<unsigned char>(1u << fb);
        quad_[nb_quads_] = {4 * ta + fa, p->face};
        ++nb_quads_;
        for (const int c : g.members) descend(c);
        --nb_quads_;
        used_[in.a] &= static_cast<unsigned char>(~(1u << fa));
        used_[in.b] &= static_cast<unsigned char>(~(1u << fb));
      }
    }
  }

  // The lowest set bit of a nonzero mask.
  static int lowest_set_bit(unsigned m) {
    int i = 0;
    for (; (m & 15u) == 0; m >>= 4) i += 4;
    return i + lowest_bit(m & 15u);
  }

  // The lowest set bit of a nonzero 4-bit mask.
  static int lowest_bit(unsigned m) {
    static constexpr signed char kLowest[16] = {-1, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0};
    return kLowest[m];
  }

  // Faces of tet t, other than `except`, that have at least one quad partner.
  int quad_faces(index_t t, int except) const {
    unsigned m = pairs_.mask(t);
    if (except >= 0) m &= ~(1u << except);
    static constexpr unsigned char kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    return kBits[m & 15u];
  }

  // A quad uses external faces only: faces on the domain boundary or towards tets outside the
  // current match. (A tet joining the match later through such a face is rejected when the
  // cell is assembled.)
  bool internal(index_t neighbor) const { return neighbor != NO_CELL && in_match(neighbor); }

  // The quad pairs of a match, each as (smaller face code, larger) in one number, sorted; the
  // unused slots hold the largest number.
  using QuadSet = std::array<std::uint64_t, kMaxQuads>;
  QuadSet quad_set() const {
    QuadSet set;
    set.fill(~std::uint64_t{0});
    for (int q = 0; q < nb_quads_; ++q) {
      const std::uint64_t a = quad_[q][0], b = quad_[q][1];
      std::uint64_t key = a < b ? a << 32 | b : b << 32 | a;
      int j = q;  // insertion sort: at most six
      for (; j > 0 && set[j - 1] > key; --j) set[j] = set[j - 1];
      set[j] = key;
    }
    return set;
  }

  void finish(const SearchProgram& program, std::vector<Match>& found,
              std::vector<QuadSet>& found_quads) {
    if (nb_vertices_ != descriptor(program.type).nb_vertices) return;
    Match c;
    c.type = program.type;
    c.graph = static_cast<std::uint8_t>(program.graph);
    c.nb_tets = static_cast<std::uint8_t>(program.nb_nodes);
    // The group in the input's id order, as the input's ids (c.tets) and as ours (group).
    // (Insertion sort: at most six entries.)
    std::array<index_t, kMaxNodes> group;
    c.tets.fill(NO_CELL);
    for (int i = 0; i < nb_assigned_; ++i) {
      const index_t id = input_id_[node_[i]];
      int j = i;
      for (; j > 0 && c.tets[j - 1] > id; --j) {
        c.tets[j] = c.tets[j - 1];
        group[j] = group[j - 1];
      }
      c.tets[j] = id;
      group[j] = node_[i];
    }
    // The same tets with the same quads, matched again through an automorphism that fixes the
    // root, make the same cell as a match kept before: run_from would drop it as seen, so it is
    // dropped before its assembly.
    const QuadSet quads = quad_set();
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (found_quads[i] == quads && found[i].tets == c.tets) return;
    }
    if (!assemble_cell(mesh_, topology_, program.type, group.data(), nb_assigned_, quad_.data(),
                       nb_quads_, c.vertices)) {
      return;
    }
    const double sj = scaled_jacobian(c.type, mesh_.points.data(), c.vertices.data());
    if (!good_enough(criteria_, mesh_, c.type, sj, group.data(), nb_assigned_)) return;
    c.quality = static_cast<float>(sj);
    found.push_back(c);
    found_quads.push_back(quads);
  }

  // True when a candidate kept from this root is the same cell.
  bool seen(const Match& c) const {
    for (const Match& k : kept_) {
      if (k.type == c.type && k.tets == c.tets && sorted(k.vertices) == sorted(c.vertices) &&
          same_cell(k, c)) {
        return true;
      }
    }
    return false;
  }

  // Two cells on the same tets and vertices are the same cell when they have the same faces.
  static bool same_cell(const Match& a, const Match& b) {
    const CellDescriptor& d = descriptor(a.type);
    for (int f = 0; f < d.nb_faces; ++f) {
      std::array<index_t, 4> fa{NO_VERTEX, NO_VERTEX, NO_VERTEX, NO_VERTEX};
      for (int i = 0; i < d.face_size[f]; ++i) fa[i] = a.vertices[d.face[f][i]];
      bool found = false;
      for (int g = 0; g < d.nb_faces && !found; ++g) {
        if (d.face_size[g] != d.face_size[f]) continue;
        std::array<index_t, 4> fb{NO_VERTEX, NO_VERTEX, NO_VERTEX, NO_VERTEX};
        for (int i = 0; i < d.face_size[g]; ++i) fb[i] = b.vertices[d.face[g][i]];
        found = sorted(fa) == sorted(fb);
      }
      if (!found) return false;
    }
    return true;
  }

  const TetMesh& input_;
  const TetMesh& mesh_;
  const TetTopology& topology_;
  const QuadPairs& pairs_;
  const std::vector<index_t>& input_id_;
  const AcceptanceCriteria& criteria_;
  const SearchTree& tree_;
  const std::vector<SearchProgram>& programs_;     // search_programs()
  bool split_regions_;                             // respect_regions, and the mesh has regions
  std::vector<std::vector<Match>> found_;          // this root's matches, per program
  std::vector<std::vector<QuadSet>> found_quads_;  // and their quad_set()s
  std::vector<Match> kept_;                        // this root's matches kept
  ChunkMatches& out_;
  index_t root_ = 0;
  index_t root_input_id_ = 0;
  std::int32_t root_region_ = 0;
  int root_quad_faces_ = 0;  // quad_faces(root, -1)
  int nb_assigned_ = 0;
  std::array<index_t, kMaxNodes> node_{};
  // [k]: the first k nodes' ids modulo 64 as bits (in_match)
  std::array<std::uint64_t, kMaxNodes + 1> node_bits_{};
  std::array<unsigned char, kMaxNodes> used_{};  // faces of each node taken by a LINK or QUAD
  std::array<index_t, 8> vertex_{};
  int nb_vertices_ = 0;
  // [k]: the first k vertices' ids modulo 64 as bits (has_vertex)
  std::array<std::uint64_t, 9> vertex_bits_{};
  std::array<std::array<index_t, 2>, kMaxQuads> quad_{};
  int nb_quads_ = 0;
};

}  // namespace

Candidates find_candidates(const TetMesh& mesh, const TetTopology& topology,
                           const AcceptanceCriteria& criteria, int threads,
                           const ProgressCallback& progress) {
  const index_t nt = mesh.nb_tets();
  // The search runs on a copy in space-filling-curve order (spatial_order.h), where the tets it
  // walks are mostly in cache; root i there is the input's tet input_id[i].
  const std::vector<index_t> input_id = spatial_order(mesh);
  const TetMesh local = reorder_tets(mesh, input_id);
  const TetTopology local_topology = topology.reordered(input_id);
  const QuadPairs quad_pairs(local, local_topology, criteria.min_dihedral_angle,
                             criteria.min_boundary_dihedral_angle, criteria.max_face_angle,
                             std::max(1, threads), criteria.respect_regions);
  // Small chunks: the threads finish together (the search time per root varies a lot).
  constexpr index_t kChunk = 2048;
  const SearchTree tree(criteria.types);
  std::vector<ChunkMatches> per_chunk((nt + kChunk - 1) / kChunk);
  parallel_chunks(
      nt, kChunk, std::max(1, threads),
      [&](index_t chunk, index_t begin, index_t end) {
        Matcher matcher(mesh, local, local_topology, quad_pairs, input_id, criteria, tree,
                        per_chunk[chunk]);
        for (index_t t = begin; t < end; ++t) matcher.run_from(t);
        // Without the growth slack: the lists are held until the last chunk is searched.
        per_chunk[chunk].shrink_to_fit();
      },
      [&](double fraction) { return !progress || progress("candidates", fraction); });
  return in_root_order(mesh, per_chunk);
}

bool good_enough(const AcceptanceCriteria& criteria, const TetMesh& mesh, CellType type, double sj,
                 const index_t* tets, int nb_tets) {
  if (sj >= criteria.min_scaled_jacobian) return true;
  // Pyramids are not: CalculiX gets them as collapsed hexahedra (docs/fem-accuracy.md).
  if (type != CellType::Hex && type != CellType::Prism) return false;
  if (sj < std::max(criteria.lowest_scaled_jacobian, kMinElementScaledJacobian)) return false;
  for (int i = 0; i < nb_tets; ++i)
    if (sj < scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(tets[i]))) return false;
  return true;
}

}  // namespace hexmerge
