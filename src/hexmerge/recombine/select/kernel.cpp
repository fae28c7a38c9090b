// Selection kernel: the candidate index, a candidate's conformity against what is chosen, the
// closers of pending quad faces, the ranking at a tet, and the move journal.
#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {
namespace {
const CellDescriptor& kTet = descriptor(CellType::Tet);

// Per cell type and set of its corners (as bits, at most 8): the first face of the cell with
// three of its corners in the set, or -1. The face of a candidate's cell that a triangle of its
// tets lies in is then one look-up.
using FaceOfCorners = std::array<std::array<signed char, 256>, NB_CELL_TYPES>;

FaceOfCorners face_of_corners() {
  FaceOfCorners table;
  for (int type = 0; type < NB_CELL_TYPES; ++type) {
    const CellDescriptor& d = descriptor(static_cast<CellType>(type));
    for (unsigned set = 0; set < 256; ++set) {
      table[type][set] = -1;
      for (int f = d.nb_faces - 1; f >= 0; --f) {
        int hits = 0;
        for (int i = 0; i < d.face_size[f]; ++i) hits += (set >> d.face[f][i]) & 1;
        if (hits == 3) table[type][set] = static_cast<signed char>(f);
      }
    }
  }
  return table;
}

// CandidateIndex::cell_face of candidate c (its tets ct), from `out` on. The corners of c that
// are each vertex of a tet, as bits, are found once per tet (unused corners are NO_VERTEX,
// never a vertex), and each triangle's face is then a look-up, instead of comparing every
// corner of every face with each vertex of each triangle.
void index_faces(const TetMesh& mesh, const TetTopology& topo, const Candidate& c, TetSpan ct,
                 const FaceOfCorners& face_of, signed char* out) {
  const auto& face_of_type = face_of[static_cast<int>(c.type)];
  for (int i = 0; i < ct.size(); ++i) {
    const index_t t = ct[i];
    const index_t* q = mesh.tet(t);
    unsigned at[4] = {0, 0, 0, 0};
    for (int v = 0; v < 4; ++v) {
      for (int k = 0; k < 8; ++k) at[v] |= static_cast<unsigned>(c.vertices[k] == q[v]) << k;
    }
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo.neighbor(t, f);
      if (n != NO_CELL && ct.contains(n)) continue;  // internal face of the candidate
      const int cf = face_of_type[at[kTet.face[f][0]] | at[kTet.face[f][1]] | at[kTet.face[f][2]]];
      HEXMERGE_ASSERT(cf >= 0, "a candidate's boundary triangle is not on its cell");
      const int nf = n == NO_CELL ? 0 : topo.neighbor_face(t, f);
      const int quad = descriptor(c.type).face_size[cf] == 4 ? 32 : 0;
      out[4 * i + f] = static_cast<signed char>(cf | nf << 3 | quad);
    }
  }
}

}  // namespace

CandidateIndex::CandidateIndex(const TetMesh& mesh, const TetTopology& topo,
                               const Candidates& cands, bool respect_regions, int threads) {
  const index_t nt = mesh.nb_tets();
  offsets.assign(static_cast<std::size_t>(nt) + 1, 0);
  for (const index_t t : cands.all_tets()) ++offsets[t + 1];
  for (index_t t = 0; t < nt; ++t) offsets[t + 1] += offsets[t];
  ids.resize(offsets[nt]);
  types.resize(offsets[nt]);
  std::vector<index_t> fill(offsets.begin(), offsets.end() - 1);
  for (index_t ci = 0; ci < cands.size(); ++ci) {
    const Candidate& c = cands[ci];
    for (const index_t t : cands.tets(c)) {
      types[fill[t]] = c.type;
      ids[fill[t]++] = ci;
    }
  }
  // Each candidate writes only its own entries of cell_face: the candidates are shared out
  // among the threads (at 1M tets this is a tenth of the selection on one thread).
  cell_face.assign(4 * cands.all_tets().size(), -1);
  const FaceOfCorners face_of = face_of_corners();
  parallel_chunks(static_cast<index_t>(cands.size()), 1u << 14, threads,
                  [&](index_t, index_t begin, index_t end) {
                    for (index_t ci = begin; ci < end; ++ci) {
                      const Candidate& c = cands[ci];
                      index_faces(mesh, topo, c, cands.tets(c), face_of,
                                  &cell_face[4 * static_cast<std::size_t>(c.first_tet)]);
                    }
                  });
  is_boundary.assign(nt, 0);
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo.neighbor(t, f);
      if (n == NO_CELL || (respect_regions && mesh.region(n) != mesh.region(t))) {
        is_boundary[t] = 1;
      }
    }
  }
}

Sides Selector::sides(index_t ci) const {
  const Candidate& c = cands_[ci];
  const TetSpan ct = cands_.tets(c);
  Sides s;
  for (int i = 0; i < ct.size(); ++i) {
    for (int f = 0; f < 4; ++f) {
      const int packed = face_entry(c, i, f);
      if (packed < 0) continue;
      const index_t n = topo_.neighbor(ct[i], f);
      s.side[s.count++] = {n, n == NO_CELL ? -1 : (packed >> 3) & 3, packed & 7};
    }
  }
  return s;
}

// Quad faces of chosen elements that touch free tet t through one of its faces: their keys
// must all be quad faces of whatever element takes t.
void Selector::required_quads(index_t t, QuadKeys& keys) const {
  for (int f = 0; f < 4; ++f) {
    const index_t n = topo_.neighbor(t, f);
    if (n == NO_CELL || is_free(n)) continue;
    const int nf = topo_.neighbor_face(t, f);
    if (owner_quad(n, nf)) keys.add(face_key(cands_[owner_[n]], owner_face(n, nf)));
  }
}

bool Selector::has_quad(const Candidate& x, const QuadKey& key) const {
  const CellDescriptor& d = descriptor(x.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] == 4 && face_key(x, f) == key) return true;
  }
  return false;
}

// The best available candidate that takes free tets n1 and n2, avoids the tets of `exclude`
// (may be null) and has every quad face the chosen elements and `extra` ask of n1 and n2 —
// the element that would close a pending quad face. NO_INDEX when there is none.
index_t Selector::closer(index_t n1, index_t n2, const QuadKey* extra,
                         const Candidate* exclude) const {
  if (strict_) return closing_pyramid(n1, n2, extra);
  QuadKeys keys;
  if (extra) keys.add(*extra);
  required_quads(n1, keys);
  required_quads(n2, keys);
  index_t best = NO_INDEX;
  for (index_t k = offsets_[n1]; k < offsets_[n1 + 1]; ++k) {
    const index_t xi = ids_[k];
    const Candidate& x = cands_[xi];
    if (!contains(x, n2) || !available(xi)) continue;
    if (exclude) {
      bool overlap = false;
      for (const index_t t : cands_.tets(x)) overlap = overlap || contains(*exclude, t);
      if (overlap) continue;
    }
    bool all = true;
    for (const QuadKey& key : keys) all = all && has_quad(x, key);
    if (!all) continue;
    if (best == NO_INDEX || better(x, 0, cands_[best], 0)) best = xi;
  }
  return best;
}

// A pending quad face is safe when the two free tets behind it form a pyramid with that quad
// as its base and no other chosen quad face touches them: nothing chosen later can take
// either tet without matching the quad, so the pyramid is certain to be there at the end.
index_t Selector::closing_pyramid(index_t n1, index_t n2, const QuadKey* key) const {
  QuadKeys keys;
  if (key) keys.add(*key);
  required_quads(n1, keys);
  required_quads(n2, keys);
  return keys.count == 1 ? pyramid_on(n1, n2, keys.key[0]) : NO_INDEX;
}

// An available pyramid of tets n1 and n2 with base `key`, or NO_INDEX.
index_t Selector::pyramid_on(index_t n1, index_t n2, const QuadKey& key) const {
  for (index_t k = offsets_[n1]; k < offsets_[n1 + 1]; ++k) {
    if (types_[k] != CellType::Pyramid) continue;
    const index_t xi = ids_[k];
    const Candidate& x = cands_[xi];
    if (contains(x, n2) && available(xi) && face_key(x, 0) == key) {
      return xi;
    }
  }
  return NO_INDEX;
}

// Quad faces of candidate ci that would not conform if it were (or, when it is, as it is)
// chosen now. A quad facing two free tets conforms while some available candidate can close
// it; with `pending_ok` false (the final count) it does not.
std::size_t Selector::violations(index_t ci, bool pending_ok, bool count_triangles) const {
  const Candidate& c = cands_[ci];
  const Sides s = sides(ci);
  std::size_t bad = 0;
  const CellDescriptor& d = descriptor(c.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    const Side* half[2] = {nullptr, nullptr};
    int nh = 0;
    for (int i = 0; i < s.count; ++i) {
      if (s.side[i].cell_face == f && nh < 2) half[nh++] = &s.side[i];
    }
    if (d.face_size[f] == 3) {
      // Our triangle must not meet half of a chosen element's quad (counted once, on the
      // quad's side, in the final count).
      const index_t n = half[0]->neighbor;
      if (!count_triangles) continue;
      if (n != NO_CELL && !is_free(n) && owner_quad(n, half[0]->neighbor_face)) ++bad;
      continue;
    }
    HEXMERGE_ASSERT(nh == 2, "a quad face of a candidate is not two triangles");
    const index_t n1 = half[0]->neighbor, n2 = half[1]->neighbor;
    if (n1 == NO_CELL && n2 == NO_CELL) continue;
    if (n1 == NO_CELL || n2 == NO_CELL) {
      ++bad;
      continue;
    }
    if (!is_free(n1) || !is_free(n2)) {
      if (owner_[n1] != owner_[n2]) {
        ++bad;
        continue;
      }
      const int nf = half[0]->neighbor_face;
      if (!owner_quad(n1, nf) ||
          face_key(cands_[owner_[n1]], owner_face(n1, nf)) != face_key(c, f)) {
        ++bad;
      }
      continue;
    }
    if (!pending_ok) {
      ++bad;
      continue;
    }
    const QuadKey key = face_key(c, f);
    if (closer(n1, n2, &key, chosen_[ci] ? nullptr : &c) == NO_INDEX) ++bad;
  }
  return bad;
}

// Pending quad faces of candidate ci (not chosen) that are not safe (closing_pyramid).
std::size_t Selector::risky_quads(index_t ci) const {
  const Candidate& c = cands_[ci];
  const Sides s = sides(ci);
  const CellDescriptor& d = descriptor(c.type);
  std::size_t risky = 0;
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] != 4) continue;
    const auto n = tets_behind(s, f);
    if (n[0] == NO_CELL || n[1] == NO_CELL || !is_free(n[0]) || !is_free(n[1])) continue;
    const QuadKey key = face_key(c, f);
    if (closing_pyramid(n[0], n[1], &key) == NO_INDEX) ++risky;
  }
  return risky;
}

// The best available candidate of `stage` that takes tet t, or NO_INDEX.
index_t Selector::best_at(index_t t, const Stage& stage) const {
  index_t best = NO_INDEX;
  std::size_t best_v = 0;
  for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
    if (types_[k] != stage.type) continue;
    const index_t ci = ids_[k];
    const Candidate& c = cands_[ci];
    if (!available(ci)) continue;
    std::size_t v = violations(ci);
    if (v > 0 && !stage.allow_nonconforming) continue;
    if (v == 0 && params_.conformity == Conformity::Conforming && !strict_) v = risky_quads(ci);
    if (best == NO_INDEX || better(c, v, cands_[best], best_v)) {
      best = ci;
      best_v = v;
    }
  }
  return best;
}

void Selector::begin_move() {
  journaling_ = true;
  journal_.clear();
  chosen_journal_.clear();
}

void Selector::rollback() {
  for (auto it = journal_.rbegin(); it != journal_.rend(); ++it) {
    const index_t t = it->first, ci = it->second;
    if (ci == NO_INDEX) {
      put_owner(t, ci, 0);
    } else {
      const TetSpan ct = cands_.tets(ci);
      put_owner(t, ci, static_cast<int>(std::find(ct.begin(), ct.end(), t) - ct.begin()));
    }
  }
  for (auto it = chosen_journal_.rbegin(); it != chosen_journal_.rend(); ++it) {
    chosen_[it->first] = it->second;
  }
  journaling_ = false;
}

}  // namespace hexmerge::select
