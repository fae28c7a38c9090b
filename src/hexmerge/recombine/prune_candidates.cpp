#include "hexmerge/recombine/prune_candidates.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/spatial_order.h"

namespace hexmerge {
namespace {

using QuadKey = FaceKey;

bool holds(TetSpan tets, index_t t) { return std::binary_search(tets.begin(), tets.end(), t); }

// A quad face of a candidate: what is across its triangles (the tets there are the neighbours of
// the Side's front tets across their faces on the quad).
struct Quad {
  std::uint8_t nb_behind = 0;  // triangles found (2 for a proper quad)
  bool open = false;           // some triangle on the boundary
  bool inner = false;          // some triangle with a tet behind
};

// A candidate with a given quad face, as the candidates across it see it: whether it holds a
// tet that touches the quad. Its tets on the quad's triangles (front, by their places among the
// candidate's tets) answer that, unless it has more than two such triangles or a triangle of
// the quad inside it (flat tets): then `exact` is false and all its tets tell.
struct Side {
  index_t candidate;                             // local id (prune_unclosable)
  std::array<std::uint8_t, 2> front{0, 0};       // places among the candidate's tets
  std::array<std::uint8_t, 2> front_face{0, 0};  // the local face of each on the quad
  bool exact = true;
};

// The quad faces of a candidate, in face order: their quads and sides.
struct CandidateQuads {
  std::array<Quad, 6> quad;
  std::array<Side, 6> side;
  int count = 0;
};

CandidateQuads quads_of(const TetMesh& mesh, const TetTopology& topology, const Candidate& c,
                        TetSpan tets, index_t ci) {
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
  for (int place = 0; place < tets.size(); ++place) {
    const index_t t = tets[place];
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
      const bool inside = n != NO_CELL && holds(tets, n);  // a face inside the cell (flat tets)
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
        else
          q.inner = true;
        ++q.nb_behind;
        if (nb_front[k] < 2) {
          s.front[nb_front[k]] = static_cast<std::uint8_t>(place);
          s.front_face[nb_front[k]] = static_cast<std::uint8_t>(lf);
        } else
          s.exact = false;
        ++nb_front[k];
      }
    }
  }
  return out;
}

}  // namespace

Candidates prune_unclosable(const TetMesh& mesh, const TetTopology& topology, Candidates candidates,
                            std::size_t& removed, int threads) {
  const index_t n = static_cast<index_t>(candidates.size());
  constexpr index_t kChunk = 4096;
  auto go_on = [](double) { return true; };
  // The work runs on local ids: the candidates in the order of their first tet along a
  // space-filling curve (spatial_order.h), by_local[l] being the candidate id, and the vertices
  // ranked in the order that curve first meets them. Candidates close in space, which share
  // quads and tets, then get close ids, and so do their quads' groups: on large meshes the
  // walks below stay in cache.
  const index_t nv = mesh.nb_vertices();
  std::vector<index_t> by_local(n);
  std::vector<index_t> vertex_rank(nv, NO_INDEX);
  {
    const std::vector<index_t> order = spatial_order(mesh);
    std::vector<index_t> rank(order.size());
    index_t next = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      rank[order[i]] = static_cast<index_t>(i);
      for (int k = 0; k < 4; ++k) {
        const index_t v = mesh.tet(order[i])[k];
        if (vertex_rank[v] == NO_INDEX) vertex_rank[v] = next++;
      }
    }
    std::vector<index_t> start(order.size() + 1, 0);  // first local id per rank of first tet
    for (const Candidate& c : candidates) ++start[rank[candidates.tets(c)[0]] + 1];
    for (std::size_t i = 0; i < order.size(); ++i) start[i + 1] += start[i];
    for (index_t ci = 0; ci < n; ++ci) by_local[start[rank[candidates.tets(ci)[0]]]++] = ci;
  }
  // Quad face k of the candidate of local id l: first[l] <= k < first[l + 1]. Places of quad
  // faces are below 2^31: the sort below marks a group's first place in at[]'s top bit.
  constexpr index_t kGroupStart = index_t(1) << 31;
  std::vector<index_t> first(static_cast<std::size_t>(n) + 1, 0);
  std::size_t total = 0;
  for (index_t l = 0; l < n; ++l) {
    total += descriptor(candidates[by_local[l]].type).nb_quad_faces;
    if (total >= kGroupStart) {
      throw ResourceError("prune_unclosable: more than 2^31 - 1 quad faces of candidates");
    }
    first[l + 1] = static_cast<index_t>(total);
  }
  const index_t nb_quads = first[n];
  // The key of the i-th quad face of the candidate of local id l.
  auto key_of = [&](index_t l, int i) {
    const Candidate& c = candidates[by_local[l]];
    const CellDescriptor& d = descriptor(c.type);
    for (int f = 0; f < d.nb_faces; ++f)
      if (d.face_size[f] == 4 && i-- == 0) return face_key(c, f);
    return QuadKey{};
  };

  // The quads in the order of their keys, the quads of one key making a group: at[k] is quad
  // k's place in that order, with kGroupStart when the place begins a group (until the
  // records below take that flag over). The keys are not held
  // (this step's tables are the engine's peak of memory on lattice meshes): a counting sort on
  // the rank of the smallest vertex, then each bucket sorted by a hash of the other three and
  // the quad, in 8-byte entries; a run of one hash is one key but for collisions: its keys are
  // made again and it is sorted by key, then quad. The groups are in no useful order, each in
  // the order of its quads, which is all the steps below read.
  std::vector<index_t> at(nb_quads);
  {
    // The hash's top 29 bits, and the quad as its candidate (local id) and its place among the
    // candidate's quad faces (the low 3 bits): ordered as (hash, quad), quad = first[l] + place.
    struct Entry {
      std::uint32_t hash_place;
      index_t candidate;
      bool operator<(const Entry& o) const {
        if ((hash_place ^ o.hash_place) >> 3) return hash_place < o.hash_place;
        if (candidate != o.candidate) return candidate < o.candidate;
        return hash_place < o.hash_place;
      }
      bool same_hash(const Entry& o) const { return ((hash_place ^ o.hash_place) >> 3) == 0; }
      int place() const { return static_cast<int>(hash_place & 7u); }
    };
    static_assert(sizeof(Entry) == 8, "the entries are this step's peak of memory");
    auto hash_of = [](const QuadKey& key) {
      std::uint32_t h = key[1] * 0x9E3779B1u;
      h = (h ^ (h >> 15) ^ key[2]) * 0x85EBCA77u;
      h = (h ^ (h >> 13) ^ key[3]) * 0xC2B2AE3Du;
      return h ^ (h >> 16);
    };
    std::vector<index_t> bucket(static_cast<std::size_t>(nv) + 1, 0);
    for (index_t l = 0; l < n; ++l) {  // counted by the smallest vertex, the key's first
      const Candidate& c = candidates[by_local[l]];
      const CellDescriptor& d = descriptor(c.type);
      for (int f = 0; f < d.nb_faces; ++f) {
        if (d.face_size[f] != 4) continue;
        index_t low = c.vertices[d.face[f][0]];
        for (int i = 1; i < 4; ++i) low = std::min(low, c.vertices[d.face[f][i]]);
        ++bucket[vertex_rank[low] + 1];
      }
    }
    for (index_t v = 0; v < nv; ++v) bucket[v + 1] += bucket[v];
    std::vector<Entry> entries(nb_quads);
    {
      std::vector<index_t> fill(bucket.begin(), bucket.end() - 1);
      for (index_t l = 0; l < n; ++l) {
        const Candidate& c = candidates[by_local[l]];
        const CellDescriptor& d = descriptor(c.type);
        std::uint32_t place = 0;
        for (int f = 0; f < d.nb_faces; ++f) {
          if (d.face_size[f] != 4) continue;
          const QuadKey key = face_key(c, f);
          entries[fill[vertex_rank[key[0]]]++] = {(hash_of(key) & ~7u) | place++, l};
        }
      }
    }
    parallel_chunks(
        nv, kChunk, threads,
        [&](index_t, index_t begin, index_t end) {
          struct Keyed {
            QuadKey key;
            index_t quad;
            // (key, quad), element by element (std::array's comparisons call memcmp).
            bool operator<(const Keyed& o) const {
              for (int i = 0; i < 4; ++i)
                if (key[i] != o.key[i]) return key[i] < o.key[i];
              return quad < o.quad;
            }
            bool same_key(const Keyed& o) const {
              return ((key[0] ^ o.key[0]) | (key[1] ^ o.key[1]) | (key[2] ^ o.key[2]) |
                      (key[3] ^ o.key[3])) == 0;
            }
          };
          std::vector<Keyed> run;
          for (index_t v = begin; v < end; ++v) {
            const index_t last = bucket[v + 1];
            std::sort(entries.begin() + bucket[v], entries.begin() + last);
            for (index_t j = bucket[v], e; j < last; j = e) {
              e = j + 1;
              while (e < last && entries[e].same_hash(entries[j])) ++e;
              if (e == j + 1) {
                at[first[entries[j].candidate] + entries[j].place()] = j | kGroupStart;
                continue;
              }
              // By key, then quad: one key (the quads' order, as sorted) but for collisions.
              // (Insertion sort: a run is a few quads.)
              run.clear();
              for (index_t i = j; i < e; ++i) {
                const Entry& x = entries[i];
                const Keyed k{key_of(x.candidate, x.place()), first[x.candidate] + x.place()};
                std::size_t m = run.size();
                run.push_back(k);
                for (; m > 0 && k < run[m - 1]; --m) run[m] = run[m - 1];
                run[m] = k;
              }
              for (index_t i = j; i < e; ++i) {
                const bool start = i == j || !run[i - j].same_key(run[i - j - 1]);
                at[run[i - j].quad] = i | (start ? kGroupStart : 0);
              }
            }
          }
        },
        go_on);
  }

  // Every quad face of every candidate, at its place: its candidate's tets on its triangles (by
  // their places among the candidate's tets) and flags, 8 bytes. The tets across the triangles
  // are not held: the i-th is the neighbour of front i across its face on the quad (quads_of
  // counts both in step), as `behind` reads it.
  struct QuadFace {
    index_t candidate;           // local id
    std::uint8_t front;          // bits 4i to 4i + 3: the place of front i among its tets
    std::uint8_t faces;          // bits 2i, 2i+1: front i's local face on the quad
    std::uint8_t nb_behind : 2;  // triangles found, at most 2 counted
    bool open : 1;
    bool inner : 1;
    bool exact : 1;
    bool start : 1;  // the first of its group
  };
  static_assert(sizeof(QuadFace) == 8, "the record's size is this step's peak of memory");
  static_assert(MAX_CANDIDATE_TETS <= 16, "a front's place is 4 bits");
  std::vector<QuadFace> faces(nb_quads);
  parallel_chunks(
      n, kChunk, threads,
      [&](index_t, index_t begin, index_t end) {
        for (index_t l = begin; l < end; ++l) {
          if (l + 8 < end) {  // local order jumps between the candidates' runs: fetch ahead
            const char* ahead = reinterpret_cast<const char*>(&candidates[by_local[l + 8]]);
            __builtin_prefetch(ahead);
            __builtin_prefetch(ahead + sizeof(Candidate) - 1);
            __builtin_prefetch(candidates.tets(by_local[l + 4]).data());
          }
          const Candidate& c = candidates[by_local[l]];
          const CandidateQuads cq = quads_of(mesh, topology, c, candidates.tets(c), l);
          for (int i = 0; i < cq.count; ++i) {
            const index_t at_flag = at[first[l] + i];
            const index_t j = at_flag & ~kGroupStart;
            at[first[l] + i] = j;
            const Quad& q = cq.quad[i];
            const Side& s = cq.side[i];
            QuadFace& face = faces[j];
            face.candidate = s.candidate;
            face.front = static_cast<std::uint8_t>(s.front[0] | s.front[1] << 4);
            face.faces = static_cast<std::uint8_t>(s.front_face[0] | s.front_face[1] << 2);
            face.nb_behind = std::min<std::uint8_t>(q.nb_behind, 2) & 3u;
            face.open = q.open;
            face.inner = q.inner;
            face.exact = s.exact;
            face.start = (at_flag & kGroupStart) != 0;
          }
        }
      },
      go_on);
  // The places [begin, end) of the group of the quad at place j.
  auto group_of = [&](index_t j) {
    index_t begin = j, end = j + 1;
    while (!faces[begin].start) --begin;
    while (end < nb_quads && !faces[end].start) ++end;
    return std::make_pair(begin, end);
  };

  std::vector<char> viable(n, 1);  // by local id
  auto tets_of = [&](index_t l) { return candidates.tets(by_local[l]); };
  // The tets behind quad face q (q.nb_behind of them; q not open).
  auto behind = [&](const QuadFace& q) {
    std::array<index_t, 2> b{NO_CELL, NO_CELL};
    const TetSpan tets = tets_of(q.candidate);
    for (int i = 0; i < q.nb_behind; ++i)
      b[i] = topology.neighbor(tets[(q.front >> (4 * i)) & 15], (q.faces >> (2 * i)) & 3);
    return b;
  };
  // Whether the candidate of `s` holds the tets b behind a quad face (nb of them): it is on the
  // quad's other side.
  auto across = [&](const std::array<index_t, 2>& b, int nb, const QuadFace& s) {
    const TetSpan tets = tets_of(s.candidate);
    for (int i = 0; i < nb; ++i) {
      bool in = false;
      if (s.exact) {
        for (int k = 0; k < s.nb_behind; ++k) in = in || tets[(s.front >> (4 * k)) & 15] == b[i];
      } else {
        in = holds(tets, b[i]);
      }
      if (!in) return false;
    }
    return true;
  };
  // Whether some other viable candidate closes the quad at place j, of candidate l.
  auto closed = [&](index_t l, index_t j) {
    const QuadFace& q = faces[j];
    if (q.open) return !q.inner;  // on the boundary, unless half of it is inside
    const std::array<index_t, 2> b = behind(q);
    const auto [begin, end] = group_of(j);
    for (index_t i = begin; i < end; ++i) {
      const QuadFace& s = faces[i];
      if (s.candidate != l && viable[s.candidate] && across(b, q.nb_behind, s)) return true;
    }
    return false;
  };
  auto fails = [&](index_t l) {
    for (index_t k = first[l]; k < first[l + 1]; ++k)
      if (!closed(l, at[k])) return true;
    return false;
  };
  // The first look at every candidate, against all of them, in parallel. Then each candidate
  // that goes is followed up: a candidate that still counts on it across a quad has that quad
  // looked at again, and goes too when nothing else closes it.
  std::vector<char> gone(n, 0);
  parallel_chunks(
      n, kChunk, threads,
      [&](index_t, index_t begin, index_t end) {
        for (index_t l = begin; l < end; ++l) gone[l] = fails(l);
      },
      go_on);
  std::vector<index_t> to_follow;
  for (index_t l = 0; l < n; ++l) {
    if (!gone[l]) continue;
    viable[l] = 0;
    to_follow.push_back(l);
  }
  std::vector<char>().swap(gone);
  while (!to_follow.empty()) {
    const index_t l = to_follow.back();
    to_follow.pop_back();
    for (index_t k = first[l]; k < first[l + 1]; ++k) {
      const QuadFace& mine = faces[at[k]];
      const auto [begin, end] = group_of(at[k]);
      for (index_t j = begin; j < end; ++j) {
        const index_t p = faces[j].candidate;
        const QuadFace& q = faces[j];
        if (!viable[p] || q.open || !across(behind(q), q.nb_behind, mine) || closed(p, j)) {
          continue;
        }
        viable[p] = 0;
        to_follow.push_back(p);
      }
    }
  }
  std::vector<QuadFace>().swap(faces);
  std::vector<index_t>().swap(at);
  std::vector<char> keep(n, 0);
  for (index_t l = 0; l < n; ++l) keep[by_local[l]] = viable[l];
  // The kept ones moved up in place: no second array of candidates.
  candidates.keep_if([&](index_t ci) { return keep[ci] != 0; });
  removed = n - candidates.size();
  return candidates;
}

}  // namespace hexmerge
