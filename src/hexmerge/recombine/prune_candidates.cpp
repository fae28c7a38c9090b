#include "hexmerge/recombine/prune_candidates.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include "hexmerge/core/work_queue.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {
namespace {

using QuadKey = FaceKey;

bool holds(const Candidate& c, index_t t) {
  return std::binary_search(c.tets.begin(), c.tets.begin() + c.nb_tets, t);
}

// A quad face of a candidate: the tets across its triangles, and its key's group of sides.
struct Quad {
  std::array<index_t, 2> behind{NO_CELL, NO_CELL};
  index_t group = 0;           // index into group_start
  std::uint8_t nb_behind = 0;  // triangles found (2 for a proper quad)
  bool open = false;           // some triangle on the boundary
  bool inner = false;          // some triangle with a tet behind
};

// A candidate with a given quad face, as the candidates across it see it: whether it holds a
// tet that touches the quad. Its tets on the quad's triangles (front) answer that without
// reading the candidate, unless it has more than two such triangles or a triangle of the quad
// inside it (flat tets): then `exact` is false and only its tets tell.
struct Side {
  index_t candidate;
  std::array<index_t, 2> front{NO_CELL, NO_CELL};
  bool exact = true;
};

// The quad faces of a candidate, in face order: their quads and sides.
struct CandidateQuads {
  std::array<Quad, 6> quad;
  std::array<Side, 6> side;
  int count = 0;
};

CandidateQuads quads_of(const TetMesh& mesh, const TetTopology& topology, const Candidate& c,
                        index_t ci) {
  const CellDescriptor& d = descriptor(c.type);
  CandidateQuads out;
  std::array<std::uint8_t, 8> quads_at{};  // per local vertex: bit k for the k-th quad face
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] != 4) continue;
    for (int i = 0; i < 4; ++i) quads_at[d.face[f][i]] |= static_cast<std::uint8_t>(1 << out.count);
    out.side[out.count].candidate = ci;
    ++out.count;
  }
  std::array<int, 6> nb_front{};
  for (int i = 0; i < c.nb_tets; ++i) {
    const index_t t = c.tets[i];
    const index_t* v = mesh.tet(t);
    std::array<std::uint8_t, 4> at{};
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < d.nb_vertices; ++j)
        if (c.vertices[j] == v[k]) at[k] |= quads_at[j];
    for (int lf = 0; lf < 4; ++lf) {
      // The quads holding the triangle opposite vertex lf.
      unsigned in = 0xff;
      for (int k = 0; k < 4; ++k)
        if (k != lf) in &= at[k];
      if (in == 0) continue;
      const index_t n = topology.neighbor(t, lf);
      const bool inside = n != NO_CELL && holds(c, n);  // a face inside the cell (flat tets)
      for (int k = 0; k < out.count; ++k) {
        if (!(in & (1u << k))) continue;
        Side& s = out.side[k];
        if (inside) {
          s.exact = false;
          continue;
        }
        Quad& q = out.quad[k];
        if (n == NO_CELL)
          q.open = true;
        else {
          q.inner = true;
          if (q.nb_behind < 2) q.behind[q.nb_behind] = n;
        }
        ++q.nb_behind;
        if (nb_front[k] < 2)
          s.front[nb_front[k]] = t;
        else
          s.exact = false;
        ++nb_front[k];
      }
    }
  }
  return out;
}

}  // namespace

std::vector<Candidate> prune_unclosable(const TetMesh& mesh, const TetTopology& topology,
                                        const std::vector<Candidate>& candidates,
                                        std::size_t& removed) {
  const std::size_t n = candidates.size();
  // Every quad face of every candidate (first: per candidate), its side, and how many quads
  // have each smallest vertex.
  std::vector<std::size_t> first(n + 1, 0);
  std::vector<Quad> quads;
  std::vector<Side> own;
  std::vector<std::size_t> bucket(static_cast<std::size_t>(mesh.nb_vertices()) + 1, 0);
  for (std::size_t ci = 0; ci < n; ++ci) {
    const Candidate& c = candidates[ci];
    const CellDescriptor& d = descriptor(c.type);
    first[ci] = quads.size();
    if (d.nb_quad_faces == 0) continue;
    const CandidateQuads cq = quads_of(mesh, topology, c, static_cast<index_t>(ci));
    quads.insert(quads.end(), cq.quad.begin(), cq.quad.begin() + cq.count);
    own.insert(own.end(), cq.side.begin(), cq.side.begin() + cq.count);
    for (int f = 0; f < d.nb_faces; ++f)
      if (d.face_size[f] == 4) ++bucket[face_key(c, f)[0] + 1];
  }
  first[n] = quads.size();

  // The quads grouped by key: a counting sort on the smallest vertex, then each bucket sorted by
  // the other three (and the quad, so a group lists its candidates in id order).
  struct Entry {
    std::array<index_t, 3> rest;
    index_t quad;
    bool operator<(const Entry& o) const { return rest != o.rest ? rest < o.rest : quad < o.quad; }
  };
  for (std::size_t v = 0; v + 1 < bucket.size(); ++v) bucket[v + 1] += bucket[v];
  std::vector<Entry> entries(quads.size());
  {
    std::vector<std::size_t> fill(bucket.begin(), bucket.end() - 1);
    for (std::size_t ci = 0; ci < n; ++ci) {
      const Candidate& c = candidates[ci];
      const CellDescriptor& d = descriptor(c.type);
      std::size_t k = first[ci];
      for (int f = 0; f < d.nb_faces; ++f) {
        if (d.face_size[f] != 4) continue;
        const QuadKey key = face_key(c, f);
        entries[fill[key[0]]++] = {{key[1], key[2], key[3]}, static_cast<index_t>(k++)};
      }
    }
  }
  // sides[group_start[g] .. group_start[g + 1]): the candidates with the quad of group g.
  std::vector<Side> sides(quads.size());
  std::vector<index_t> group_start;
  for (std::size_t v = 0; v + 1 < bucket.size(); ++v) {
    const auto begin = entries.begin() + static_cast<std::ptrdiff_t>(bucket[v]);
    const auto end = entries.begin() + static_cast<std::ptrdiff_t>(bucket[v + 1]);
    std::sort(begin, end);
    for (auto e = begin; e != end; ++e) {
      const std::size_t j = static_cast<std::size_t>(e - entries.begin());
      if (e == begin || e->rest != (e - 1)->rest) group_start.push_back(static_cast<index_t>(j));
      quads[e->quad].group = static_cast<index_t>(group_start.size() - 1);
      sides[j] = own[e->quad];
    }
  }
  group_start.push_back(static_cast<index_t>(quads.size()));
  std::vector<Entry>().swap(entries);
  std::vector<Side>().swap(own);
  std::vector<std::size_t>().swap(bucket);

  std::vector<char> viable(n, 1);
  // Whether the candidate of `s` holds the tets behind q: it is on the quad's other side.
  auto across = [&](const Quad& q, const Side& s) {
    for (int i = 0; i < std::min<int>(q.nb_behind, 2); ++i) {
      const index_t b = q.behind[i];
      if (s.exact ? b != s.front[0] && b != s.front[1] : !holds(candidates[s.candidate], b))
        return false;
    }
    return true;
  };
  auto closed = [&](std::size_t ci, const Quad& q) {
    if (q.open) return !q.inner;  // on the boundary, unless half of it is inside
    for (index_t j = group_start[q.group]; j < group_start[q.group + 1]; ++j) {
      const Side& s = sides[j];
      if (s.candidate != ci && viable[s.candidate] && across(q, s)) return true;
    }
    return false;
  };
  WorkQueue work(n);
  for (std::size_t ci = 0; ci < n; ++ci)
    if (first[ci + 1] > first[ci]) work.push(static_cast<index_t>(ci));
  while (!work.empty()) {
    const index_t ci = work.pop();
    if (!viable[ci]) continue;
    bool ok = true;
    for (std::size_t k = first[ci]; k < first[ci + 1] && ok; ++k) ok = closed(ci, quads[k]);
    if (ok) continue;
    viable[ci] = 0;
    // Whoever shared a quad with it may have counted on it.
    for (std::size_t k = first[ci]; k < first[ci + 1]; ++k)
      for (index_t j = group_start[quads[k].group]; j < group_start[quads[k].group + 1]; ++j)
        if (viable[sides[j].candidate]) work.push(sides[j].candidate);
  }
  std::vector<Candidate> kept;
  kept.reserve(static_cast<std::size_t>(std::count(viable.begin(), viable.end(), 1)));
  for (std::size_t ci = 0; ci < n; ++ci)
    if (viable[ci]) kept.push_back(candidates[ci]);
  removed = n - kept.size();
  return kept;
}

}  // namespace hexmerge
