#include "hexmerge/recombine/prune_candidates.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <unordered_map>

#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {
namespace {

using QuadKey = FaceKey;

struct QuadKeyHash {
  std::size_t operator()(const QuadKey& k) const {
    std::uint64_t h = 1469598103934665603ULL;
    for (index_t v : k) h = (h ^ v) * 1099511628211ULL;
    return static_cast<std::size_t>(h);
  }
};

bool holds(const Candidate& c, index_t t) {
  return std::binary_search(c.tets.begin(), c.tets.begin() + c.nb_tets, t);
}

// A quad face of a candidate: its key and the tets across its triangles.
struct Quad {
  QuadKey key;
  std::array<index_t, 2> behind{NO_CELL, NO_CELL};
  int nb_behind = 0;   // triangles found (2 for a proper quad)
  bool open = false;   // some triangle on the boundary
  bool inner = false;  // some triangle with a tet behind
};

Quad quad_of(const TetMesh& mesh, const TetTopology& topology, const Candidate& c, int f) {
  Quad q;
  q.key = face_key(c, f);
  for (int i = 0; i < c.nb_tets; ++i) {
    const index_t t = c.tets[i];
    const index_t* v = mesh.tet(t);
    for (int lf = 0; lf < 4; ++lf) {
      bool in_quad = true;
      for (int k = 0; k < 4 && in_quad; ++k)
        if (k != lf) in_quad = std::binary_search(q.key.begin(), q.key.end(), v[k]);
      if (!in_quad) continue;
      const index_t n = topology.neighbor(t, lf);
      if (n != NO_CELL && holds(c, n)) continue;  // a face inside the cell (flat tets)
      if (n == NO_CELL)
        q.open = true;
      else {
        q.inner = true;
        if (q.nb_behind < 2) q.behind[q.nb_behind] = n;
      }
      ++q.nb_behind;
    }
  }
  return q;
}

}  // namespace

std::vector<Candidate> prune_unclosable(const TetMesh& mesh, const TetTopology& topology,
                                        const std::vector<Candidate>& candidates,
                                        std::size_t& removed) {
  const std::size_t n = candidates.size();
  // Every quad face of every candidate, and the candidates per quad key.
  std::vector<std::size_t> first(n + 1, 0);
  std::vector<Quad> quads;
  std::unordered_map<QuadKey, std::vector<index_t>, QuadKeyHash> by_key;
  for (std::size_t ci = 0; ci < n; ++ci) {
    const Candidate& c = candidates[ci];
    const CellDescriptor& d = descriptor(c.type);
    first[ci] = quads.size();
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      quads.push_back(quad_of(mesh, topology, c, f));
      by_key[quads.back().key].push_back(static_cast<index_t>(ci));
    }
  }
  first[n] = quads.size();

  std::vector<char> viable(n, 1);
  auto closed = [&](std::size_t ci, const Quad& q) {
    if (q.open) return !q.inner;  // on the boundary, unless half of it is inside
    for (index_t p : by_key[q.key]) {
      if (p == ci || !viable[p]) continue;
      const Candidate& other = candidates[p];
      bool across = true;  // the partner holds the tets behind: it is on the other side
      for (int i = 0; i < std::min(q.nb_behind, 2) && across; ++i)
        across = holds(other, q.behind[i]);
      if (across) return true;
    }
    return false;
  };
  std::deque<index_t> work;
  std::vector<char> queued(n, 0);
  for (std::size_t ci = 0; ci < n; ++ci)
    if (first[ci + 1] > first[ci]) {
      work.push_back(static_cast<index_t>(ci));
      queued[ci] = 1;
    }
  while (!work.empty()) {
    const index_t ci = work.front();
    work.pop_front();
    queued[ci] = 0;
    if (!viable[ci]) continue;
    bool ok = true;
    for (std::size_t k = first[ci]; k < first[ci + 1] && ok; ++k) ok = closed(ci, quads[k]);
    if (ok) continue;
    viable[ci] = 0;
    // Whoever shared a quad with it may have counted on it.
    for (std::size_t k = first[ci]; k < first[ci + 1]; ++k)
      for (index_t p : by_key[quads[k].key])
        if (viable[p] && !queued[p]) {
          queued[p] = 1;
          work.push_back(p);
        }
  }
  std::vector<Candidate> kept;
  kept.reserve(n);
  for (std::size_t ci = 0; ci < n; ++ci)
    if (viable[ci]) kept.push_back(candidates[ci]);
  removed = n - kept.size();
  return kept;
}

}  // namespace hexmerge
