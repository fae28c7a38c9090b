// Selection step 2: the local optimisation of Meshkat & Talmor, section 4.2.
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {
// Section 4.2: at each unmatched boundary tet, try each of its candidates in place of the
// elements in its way; refill the freed tets greedily; keep the move only when it saves
// elements and leaves every quad face as conforming as before.
void Selector::local_optimisation() {
  const index_t nt = mesh_.nb_tets();
  for (index_t t = 0; t < nt; ++t) {
    if (!is_boundary_[t] || !is_free(t)) continue;
    for (index_t k = offsets_[t]; k < offsets_[t + 1] && is_free(t); ++k) {
      if (types_[k] == CellType::Pyramid) continue;
      try_move(ids_[k]);
    }
  }
}

void Selector::try_move(index_t ci) {
  const Candidate& c = cands_[ci];
  std::vector<index_t> in_way;
  for (int i = 0; i < c.nb_tets; ++i) {
    const index_t o = owner_[cands_.tets(c)[i]];
    if (o != NO_INDEX && std::find(in_way.begin(), in_way.end(), o) == in_way.end()) {
      in_way.push_back(o);
    }
  }
  if (in_way.empty() || in_way.size() > 3) return;
  int old_gain = 0;
  for (index_t o : in_way) old_gain += gain(cands_[o]);
  const bool allow = params_.conformity == Conformity::Allow;
  begin_move();
  for (index_t o : in_way) release(o);
  if (!allow && violations(ci) > 0) {
    rollback();
    return;
  }
  choose(ci);
  int new_gain = gain(c);
  std::vector<index_t> freed;
  for (index_t o : in_way) {
    const Candidate& e = cands_[o];
    for (int i = 0; i < e.nb_tets; ++i) {
      if (is_free(cands_.tets(e)[i])) freed.push_back(cands_.tets(e)[i]);
    }
  }
  for (CellType type : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
    for (index_t f : freed) {
      if (!is_free(f)) continue;
      const index_t x = best_at(f, {type, allow});
      if (x != NO_INDEX) {
        choose(x);
        new_gain += gain(cands_[x]);
      }
    }
  }
  if (new_gain <= old_gain || !neighbourhood_conforms(ci, freed)) {
    rollback();
    return;
  }
  commit();
  ++result_.local_moves;
}

// After a move: the new element and every chosen element next to the freed tets must have
// no quad face that cannot conform.
bool Selector::neighbourhood_conforms(index_t ci, const std::vector<index_t>& freed) const {
  if (params_.conformity == Conformity::Allow) return true;
  std::vector<index_t> check{ci};
  for (index_t f : freed) {
    if (!is_free(f)) check.push_back(owner_[f]);
    for (int k = 0; k < 4; ++k) {
      const index_t n = topo_.neighbor(f, k);
      if (n != NO_CELL && !is_free(n)) check.push_back(owner_[n]);
    }
  }
  std::sort(check.begin(), check.end());
  check.erase(std::unique(check.begin(), check.end()), check.end());
  for (index_t e : check) {
    if (violations(e) > 0) return false;
  }
  return true;
}

}  // namespace hexmerge::select
