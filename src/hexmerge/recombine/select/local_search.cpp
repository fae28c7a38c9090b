// Selection step 5: local search, swaps and exact re-selection in neighbourhoods (branch and
// bound).
#include "hexmerge/core/error.h"
#include "hexmerge/core/work_queue.h"
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {
// Cell face xf of candidate x against face nf of the tet n across it, which is not free (its
// owner's cell face there): they conform when both are triangles, or both the same quad.
bool Selector::faces_match(index_t x, int xf, index_t n, int nf) const {
  const bool xq = is_quad(cands_[x], xf), yq = owner_quad(n, nf);
  if (xq != yq) return false;
  return !xq || face_key(cands_[x], xf) == face_key(cands_[owner_[n]], owner_face(n, nf));
}

// Whether candidate ci (inside the neighbourhood) conforms with everything outside it, which
// the move does not change: elements (matching faces), free tets (no quad face against them)
// and the domain boundary (a quad wholly on it, or not at all).
bool Selector::fits_outside(index_t ci) const {
  const Candidate& c = cands_[ci];
  const Sides s = sides(ci);
  const CellDescriptor& d = descriptor(c.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] != 4) continue;
    const auto n = tets_behind(s, f);
    if ((n[0] == NO_CELL) != (n[1] == NO_CELL)) return false;
  }
  for (int i = 0; i < c.nb_tets; ++i) {
    for (int f = 0; f < 4; ++f) {
      const int cf = face_in_cell(c, i, f);
      if (cf < 0) continue;
      const index_t n = topo_.neighbor(cands_.tets(c)[i], f);
      if (n == NO_CELL || local_[n] >= 0) continue;
      if (is_free(n)) {
        if (is_quad(c, cf)) return false;
      } else if (!faces_match(ci, cf, n, face_across(c, i, f))) {
        return false;
      }
    }
  }
  return true;
}

// Whether candidate ci conforms with what the search has decided inside the neighbourhood.
bool Selector::fits_inside(const Hood& h, index_t ci) const {
  const Candidate& c = cands_[ci];
  for (int i = 0; i < c.nb_tets; ++i) {
    for (int f = 0; f < 4; ++f) {
      const int cf = face_in_cell(c, i, f);
      if (cf < 0) continue;
      const index_t n = topo_.neighbor(cands_.tets(c)[i], f);
      if (n == NO_CELL || local_[n] < 0) continue;
      const int st = h.state[local_[n]];
      if (st == UNDECIDED) continue;
      if (st == LEFT_FREE) {
        if (is_quad(c, cf)) return false;
      } else if (!faces_match(ci, cf, n, face_across(c, i, f))) {
        return false;
      }
    }
  }
  return true;
}

// Whether tet t may stay a tet given what the search has decided: no quad face against it.
bool Selector::may_stay_free(const Hood& h, index_t t) const {
  for (int f = 0; f < 4; ++f) {
    const index_t n = topo_.neighbor(t, f);
    if (n == NO_CELL || local_[n] < 0 || h.state[local_[n]] < 0) continue;
    if (owner_quad(n, topo_.neighbor_face(t, f))) return false;
  }
  return true;
}

// Release `released`, and re-select the tets of `tets` (which holds every tet of the released
// elements) exactly. Keeps the result when it saves more elements; returns whether it did.
bool Selector::reselect(Hood& h) {
  const bool check = checks_conformity();
  for (std::size_t i = 0; i < h.tets.size(); ++i) local_[h.tets[i]] = static_cast<int>(i);
  int old_saved = 0;
  for (index_t e : h.released) {
    old_saved += gain(cands_[e]);
    release(e);
  }
  const std::size_t nl = h.tets.size();
  // Pool: candidates wholly inside; in the checked modes only those that fit the outside.
  h.pool.clear();
  ++stamp_;
  for (index_t t : h.tets) {
    for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
      const index_t ci = ids_[k];
      if (stamp_of_[ci] == stamp_) continue;
      stamp_of_[ci] = stamp_;
      const Candidate& c = cands_[ci];
      bool inside = true;
      for (int i = 0; i < c.nb_tets && inside; ++i) inside = local_[cands_.tets(c)[i]] >= 0;
      if (inside && (!check || fits_outside(ci))) h.pool.push_back(ci);
    }
  }
  // Per local tet, its pool entries, best first (bigger, then better quality).
  std::sort(h.pool.begin(), h.pool.end(), [&](index_t a, index_t b) {
    const Candidate& x = cands_[a];
    const Candidate& y = cands_[b];
    if (x.nb_tets != y.nb_tets) return x.nb_tets > y.nb_tets;
    if (x.quality != y.quality) return x.quality > y.quality;
    return a < b;
  });
  h.at_offsets.assign(nl + 1, 0);
  h.open_sizes.assign(nl * (MAX_CANDIDATE_TETS + 1), 0);
  h.sizes.assign(nl, 0);
  for (index_t ci : h.pool) {
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) {
      const int l = local_[cands_.tets(c)[i]];
      ++h.at_offsets[l + 1];
      ++h.open_sizes[l * (MAX_CANDIDATE_TETS + 1) + c.nb_tets];
      h.sizes[l] |= 1u << c.nb_tets;
    }
  }
  h.closed.assign(h.pool.size(), 0);
  for (std::size_t l = 0; l < nl; ++l) h.at_offsets[l + 1] += h.at_offsets[l];
  h.at.assign(h.at_offsets[nl], 0);
  {
    std::vector<int> fill(h.at_offsets.begin(), h.at_offsets.end() - 1);
    for (std::size_t p = 0; p < h.pool.size(); ++p) {
      const Candidate& c = cands_[h.pool[p]];
      for (int i = 0; i < c.nb_tets; ++i)
        h.at[fill[local_[cands_.tets(c)[i]]]++] = static_cast<int>(p);
    }
  }
  // Tets an outside element's quad face ends on cannot stay tets.
  h.must_cover.assign(nl, 0);
  if (check) {
    for (std::size_t l = 0; l < nl; ++l) {
      const index_t t = h.tets[l];
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(t, f);
        if (n == NO_CELL || local_[n] >= 0 || is_free(n)) continue;
        if (owner_quad(n, topo_.neighbor_face(t, f))) h.must_cover[l] = 1;
      }
    }
  }
  long long rest = 0;
  for (std::size_t l = 0; l < nl; ++l) rest += share_of(h, static_cast<int>(l));
  h.state.assign(nl, UNDECIDED);
  h.current.clear();
  h.best.clear();
  h.best_saved = old_saved;
  h.nodes = 0;
  h.stopped = false;
  branch(h, 0, 0, rest);
  result_.local_search_nodes += static_cast<std::size_t>(h.nodes);
  const bool improved = h.best_saved > old_saved;
  if (improved) {
    for (int p : h.best) choose(h.pool[p]);
    result_.local_search_saved += static_cast<std::size_t>(h.best_saved - old_saved);
  } else {
    for (index_t e : h.released) choose(e);
  }
  if (improved && params_.conformity == Conformity::Conforming) {
    // The search keeps every face conforming; the selection's own rule must agree.
    for (int p : h.best) {
      HEXMERGE_ASSERT(violations(h.pool[p], false, false) == 0,
                      "local search: a re-selected element does not conform");
    }
  }
  for (index_t t : h.tets) local_[t] = -1;
  return improved;
}

long long Selector::share_of(const Hood& h, int l) {
  const std::uint32_t m = h.sizes[l];
  return m == 0 ? 0 : share_units(31 - __builtin_clz(m));
}

// Marks the local tets `ls` decided (their state already set) and closes the pool entries
// that take them; returns by how much the bound on the undecided tets drops (the decided tets'
// own shares, `before`, included).
long long Selector::close_entries(Hood& h, const int* ls, int k, long long before) {
  long long drop = before;
  for (int a = 0; a < k; ++a) {
    for (int q = h.at_offsets[ls[a]]; q < h.at_offsets[ls[a] + 1]; ++q) {
      const int p = h.at[q];
      if (h.closed[p]++ != 0) continue;
      const Candidate& c = cands_[h.pool[p]];
      for (int i = 0; i < c.nb_tets; ++i) {
        const int u = local_[cands_.tets(c)[i]];
        const bool undecided = h.state[u] == UNDECIDED;
        const long long old = undecided ? share_of(h, u) : 0;
        if (--h.open_sizes[u * (MAX_CANDIDATE_TETS + 1) + c.nb_tets] == 0) {
          h.sizes[u] &= ~(1u << c.nb_tets);
        }
        if (undecided) drop += old - share_of(h, u);
      }
    }
  }
  return drop;
}

void Selector::reopen_entries(Hood& h, const int* ls, int k) {
  for (int a = k - 1; a >= 0; --a) {
    for (int q = h.at_offsets[ls[a] + 1] - 1; q >= h.at_offsets[ls[a]]; --q) {
      const int p = h.at[q];
      if (--h.closed[p] != 0) continue;
      const Candidate& c = cands_[h.pool[p]];
      for (int i = 0; i < c.nb_tets; ++i) {
        const int u = local_[cands_.tets(c)[i]];
        if (h.open_sizes[u * (MAX_CANDIDATE_TETS + 1) + c.nb_tets]++ == 0) {
          h.sizes[u] |= 1u << c.nb_tets;
        }
      }
    }
  }
}

// Depth-first over the neighbourhood's tets in local order: the first undecided tet is taken
// by one of its open pool entries (best first), or stays a tet. `rest` bounds what the
// undecided tets can still save.
void Selector::branch(Hood& h, std::size_t pos, int saved, long long rest) {
  if (h.stopped) return;
  if (++h.nodes > params_.local_search_nodes) {
    h.stopped = true;
    return;
  }
  const std::size_t nl = h.tets.size();
  while (pos < nl && h.state[pos] != UNDECIDED) ++pos;
  if (pos == nl) {
    if (saved > h.best_saved) {
      h.best_saved = saved;
      h.best = h.current;
    }
    return;
  }
  // Savings are whole numbers: a branch must be able to save one more than the best.
  if (saved * UNIT + rest < (h.best_saved + 1) * UNIT) return;
  const bool check = checks_conformity();
  int ls[MAX_CANDIDATE_TETS];
  for (int k = h.at_offsets[pos]; k < h.at_offsets[pos + 1]; ++k) {
    const int p = h.at[k];
    if (h.closed[p] != 0) continue;
    const index_t ci = h.pool[p];
    const Candidate& c = cands_[ci];
    if (check && !fits_inside(h, ci)) continue;
    long long before = 0;
    for (int i = 0; i < c.nb_tets; ++i) {
      ls[i] = local_[cands_.tets(c)[i]];
      before += share_of(h, ls[i]);
    }
    for (int i = 0; i < c.nb_tets; ++i) {
      h.state[ls[i]] = p;
      put_owner(cands_.tets(c)[i], ci, i);
    }
    const long long drop = close_entries(h, ls, c.nb_tets, before);
    h.current.push_back(p);
    branch(h, pos + 1, saved + gain(c), rest - drop);
    h.current.pop_back();
    reopen_entries(h, ls, c.nb_tets);
    for (int i = 0; i < c.nb_tets; ++i) {
      h.state[ls[i]] = UNDECIDED;
      put_owner(cands_.tets(c)[i], NO_INDEX, 0);
    }
    if (h.stopped) return;
  }
  if (h.must_cover[pos] || (check && !may_stay_free(h, h.tets[pos]))) return;
  const int l = static_cast<int>(pos);
  const long long before = share_of(h, l);
  h.state[pos] = LEFT_FREE;
  const long long drop = close_entries(h, &l, 1, before);
  branch(h, pos + 1, saved, rest - drop);
  reopen_entries(h, &l, 1);
  h.state[pos] = UNDECIDED;
}

// Adds t to the neighbourhood once.
void Selector::hood_add(Hood& h, index_t t) {
  if (local_[t] != -1) return;
  local_[t] = -2;  // marked while the neighbourhood is gathered
  h.tets.push_back(t);
}

void Selector::hood_add_element(Hood& h, index_t e) {
  if (std::find(h.released.begin(), h.released.end(), e) != h.released.end()) return;
  h.released.push_back(e);
  const Candidate& c = cands_[e];
  for (int i = 0; i < c.nb_tets; ++i) hood_add(h, cands_.tets(c)[i]);
}

void Selector::hood_clear_marks(Hood& h) {
  for (index_t t : h.tets) local_[t] = -1;
}

// Swap: element e and the free tets next to it.
bool Selector::try_swap(Hood& h, index_t e) {
  h.tets.clear();
  h.released.clear();
  hood_add_element(h, e);
  const Candidate& c = cands_[e];
  bool any_free = false;
  for (int i = 0; i < c.nb_tets; ++i) {
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo_.neighbor(cands_.tets(c)[i], f);
      if (n != NO_CELL && is_free(n)) {
        hood_add(h, n);
        any_free = true;
      }
    }
  }
  // Only a candidate that takes a free tet can do better than e itself (two or more
  // candidates within e's tets save fewer elements): look for one before anything else.
  bool useful = false;
  if (any_free) {
    for (index_t t : h.tets) local_[t] = 0;
    for (std::size_t k = c.nb_tets; k < h.tets.size() && !useful; ++k) {
      const index_t t = h.tets[k];
      for (index_t j = offsets_[t]; j < offsets_[t + 1] && !useful; ++j) {
        const Candidate& x = cands_[ids_[j]];
        bool inside = true;
        for (int i = 0; i < x.nb_tets && inside; ++i) inside = local_[cands_.tets(x)[i]] >= 0;
        useful = inside;
      }
    }
  }
  hood_clear_marks(h);
  if (!useful) return false;
  std::sort(h.tets.begin(), h.tets.end());
  return reselect(h);
}

// Re-selection: every tet within `radius` face hops of free tet s, with the whole of the
// elements holding them.
bool Selector::try_reselection(Hood& h, index_t s) {
  h.tets.clear();
  h.released.clear();
  hood_add(h, s);
  std::size_t layer_begin = 0;
  for (int hop = 0; hop < params_.local_search_radius; ++hop) {
    const std::size_t layer_end = h.tets.size();
    for (std::size_t k = layer_begin; k < layer_end; ++k) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(h.tets[k], f);
        if (n != NO_CELL) hood_add(h, n);
      }
    }
    layer_begin = layer_end;
  }
  const std::size_t reached = h.tets.size();
  for (std::size_t k = 0; k < reached; ++k) {
    if (!is_free(h.tets[k])) hood_add_element(h, owner_[h.tets[k]]);
  }
  hood_clear_marks(h);
  // Nothing to re-select: no element, or one element and no free tet (it is its own best).
  bool any_free = false;
  for (index_t t : h.tets) any_free = any_free || is_free(t);
  if (h.released.empty() || (h.released.size() == 1 && !any_free)) return false;
  std::sort(h.tets.begin(), h.tets.end());
  return reselect(h);
}

void Selector::local_search() {
  const index_t nt = mesh_.nb_tets();
  local_.assign(nt, -1);
  stamp_of_.assign(cands_.size(), 0);
  Hood h;
  // Swaps, at every element next to a free tet, in candidate order; an accepted swap puts the
  // elements around it back in the queue.
  WorkQueue work(cands_.size());
  auto enqueue = [&](index_t ci) {
    if (chosen_[ci]) work.push(ci);
  };
  for (index_t ci = 0; ci < cands_.size(); ++ci) enqueue(ci);
  while (!work.empty()) {
    const index_t e = work.pop();
    if (!chosen_[e] || !try_swap(h, e)) continue;
    ++result_.swap_moves;
    for (index_t t : h.tets) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(t, f);
        if (n != NO_CELL && !is_free(n)) enqueue(owner_[n]);
      }
    }
  }
  // Re-selection around every free tet (every tet with local_search_seeds = all), in tet
  // order; an accepted one puts the seeds whose neighbourhood reaches what changed back in the
  // queue.
  const bool all = params_.local_search_seeds == LocalSearchSeeds::All;
  WorkQueue seeds(nt);
  auto seed = [&](index_t t) {
    if (all || is_free(t)) seeds.push(t);
  };
  if (params_.local_search_radius > 0) {
    for (index_t t = 0; t < nt; ++t) seed(t);
  }
  while (!seeds.empty()) {
    const index_t s = seeds.pop();
    if (!try_reselection(h, s)) continue;
    ++result_.reselection_moves;
    // Every seed whose neighbourhood reaches the changed tets is worth another look.
    std::vector<index_t> ring(h.tets.begin(), h.tets.end());
    for (index_t t : ring) local_[t] = -2;
    for (std::size_t begin = 0, hop = 0; hop < std::size_t(params_.local_search_radius); ++hop) {
      const std::size_t end = ring.size();
      for (std::size_t k = begin; k < end; ++k) {
        for (int f = 0; f < 4; ++f) {
          const index_t n = topo_.neighbor(ring[k], f);
          if (n != NO_CELL && local_[n] == -1) {
            local_[n] = -2;
            ring.push_back(n);
          }
        }
      }
      begin = end;
    }
    for (index_t t : ring) {
      local_[t] = -1;
      seed(t);
    }
  }
}

}  // namespace hexmerge::select
