// Selection step 0b (conforming mode with pyramids): hexahedra taken in conforming groups.
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {

// A face of candidate ci against what is chosen now (ci itself chosen or not). `behind` gets
// the tets behind a quad face.
Selector::FaceState Selector::face_state(index_t ci, const Sides& s, int f,
                                         std::array<index_t, 2>& behind) const {
  const Candidate& c = cands_[ci];
  if (!is_quad(c, f)) {
    // Our triangle must not meet half of a chosen element's quad.
    for (int i = 0; i < s.count; ++i) {
      if (s.side[i].cell_face != f) continue;
      const index_t n = s.side[i].neighbor;
      if (n == NO_CELL || is_free(n) || owner_[n] == ci) return FaceState::Closed;
      return owner_quad(n, s.side[i].neighbor_face) ? FaceState::Conflict : FaceState::Closed;
    }
    return FaceState::Closed;
  }
  behind = tets_behind(s, f);
  const index_t n0 = behind[0], n1 = behind[1];
  if (n0 == NO_CELL && n1 == NO_CELL) return FaceState::Closed;
  if (n0 == NO_CELL || n1 == NO_CELL) return FaceState::Conflict;
  const QuadKey key = face_key(c, f);
  if (!is_free(n0) || !is_free(n1)) {
    return owner_[n0] == owner_[n1] && has_quad(cands_[owner_[n0]], key) ? FaceState::Closed
                                                                         : FaceState::Conflict;
  }
  return closing_pyramid(n0, n1, &key) != NO_INDEX ? FaceState::Closed : FaceState::Open;
}

// The best available hexahedron or prism that takes free tets n0 and n1 with quad face `key`
// and meets nothing chosen badly: hexahedra first, then the fewest open quad faces, then the
// best scaled Jacobian (the first of equals). NO_INDEX when there is none. The prisms are looked
// at only where no hexahedron qualifies, and a candidate's faces only until it can no longer win
// (more open faces than the best, or as many and no better quality): the same partner as
// weighing every candidate in full (which was two thirds of the selection's samples on the
// TetGen-lattice sphere at 100k, most of them in the faces of candidates that lost).
index_t Selector::group_partner(index_t n0, index_t n1, const QuadKey& key) const {
  index_t best = NO_INDEX;
  int best_open = 0;
  for (const CellType type : {CellType::Hex, CellType::Prism}) {
    for (index_t k = offsets_[n0]; k < offsets_[n0 + 1]; ++k) {
      if (types_[k] != type) continue;
      const index_t xi = ids_[k];
      const Candidate& x = cands_[xi];
      if (!contains(x, n1) || !available(xi) || !has_quad(x, key)) continue;
      // Open faces that leave x behind the best: as many when x is no better.
      const int losing = best == NO_INDEX
                             ? descriptor(x.type).nb_faces + 1
                             : (x.quality > cands_[best].quality ? best_open + 1 : best_open);
      const Sides s = sides(xi);
      int open = 0;
      bool out = false;  // a conflict, or no win
      std::array<index_t, 2> behind{};
      for (int f = 0; f < descriptor(x.type).nb_faces && !out; ++f) {
        const FaceState state = face_state(xi, s, f, behind);
        open += state == FaceState::Open;
        out = state == FaceState::Conflict || open >= losing;
      }
      if (out) continue;
      best = xi;
      best_open = open;
    }
    if (best != NO_INDEX) break;
  }
  return best;
}

// Grows the group of `seed` (chosen here, in the journal begun by the caller): every quad face
// of a member must lie on the domain boundary, on the identical quad face of a chosen element
// (a member, or one chosen before), or over a pyramid that no other quad needs (reserved,
// closing_pyramid); an open one gets the best partner (group_partner), which joins the group.
// Members are scanned again until a scan adds none, since a later member's quad can take the
// pyramid an earlier face counted on. Fails on a face that nothing can close, or when a
// partner would make the group larger than group_size (`capped`).
bool Selector::grow_group(index_t seed, std::vector<index_t>& members, bool& capped) {
  members.assign(1, seed);
  choose(seed);
  capped = false;
  for (bool added = true; added;) {
    added = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      const index_t m = members[i];
      const Sides s = sides(m);
      std::array<index_t, 2> behind{};
      for (int f = 0; f < descriptor(cands_[m].type).nb_faces; ++f) {
        const FaceState state = face_state(m, s, f, behind);
        if (state == FaceState::Closed) continue;
        if (state == FaceState::Conflict) return false;
        if (members.size() >= static_cast<std::size_t>(params_.group_size)) {
          capped = true;
          return false;
        }
        const index_t x = group_partner(behind[0], behind[1], face_key(cands_[m], f));
        if (x == NO_INDEX) return false;
        choose(x);
        members.push_back(x);
        added = true;
      }
    }
  }
  return true;
}

// Step 0b: from each hexahedron candidate, then each prism candidate, best scaled Jacobian
// first, a group is grown (grow_group) and kept with the pyramids reserved for its open quads,
// or rolled back. Each candidate seeds once (a failed seed is not tried again; it may still
// join a later group as a partner), so the work is bounded by the candidates times group_size
// partner searches. Letting the members of a failed group seed no other either was measured:
// 0 to 0.7 points of element reduction less, for no time saved (docs/benchmarks.md).
void Selector::select_groups() {
  if (params_.group_size <= 0) return;
  // Sorted with their keys beside them: a comparison reading two records (at 1M lattice tets
  // a few million of 44 bytes, out of cache) was half of the selection's cache misses there.
  struct Seed {
    index_t id;
    float quality;
    bool hex;
  };
  std::vector<Seed> keyed;
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    const Candidate& c = cands_[ci];
    if (c.type == CellType::Hex || c.type == CellType::Prism) {
      keyed.push_back({ci, c.quality, c.type == CellType::Hex});
    }
  }
  std::stable_sort(keyed.begin(), keyed.end(), [](const Seed& a, const Seed& b) {
    if (a.hex != b.hex) return a.hex;
    return a.quality > b.quality;
  });
  std::vector<index_t> seeds(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) seeds[i] = keyed[i].id;
  std::vector<Seed>().swap(keyed);
  std::vector<index_t> members;
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    prefetch_candidates(seeds, i);
    const index_t seed = seeds[i];
    if (!available(seed)) continue;
    ++result_.group_seeds;
    begin_move();
    bool capped = false;
    if (grow_group(seed, members, capped)) {
      commit();
      ++result_.groups;
      for (index_t m : members) {
        if (cands_[m].type == CellType::Hex) ++result_.group_hexahedra;
      }
      continue;
    }
    rollback();
    ++(capped ? result_.groups_capped : result_.groups_failed);
  }
}

}  // namespace hexmerge::select
