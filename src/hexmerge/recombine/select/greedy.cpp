// Selection steps 1, 3 and 4: the greedy stages over the boundary and interior tets, the closing
// of pending quad faces, and the release of cracks outside conforming mode.
#include "hexmerge/core/work_queue.h"
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {
// Exhaustive-greedy over the boundary tets, best candidate first: every candidate of this
// stage's type that holds a boundary tet, by decreasing scaled Jacobian.
void Selector::boundary_stage_by_quality(const Stage& stage) {
  // Sorted with the qualities beside them (select_groups says why).
  std::vector<std::pair<float, index_t>> keyed;
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    const Candidate& c = cands_[ci];
    if (c.type != stage.type) continue;
    bool on_boundary = false;
    for (int i = 0; i < c.nb_tets; ++i)
      on_boundary = on_boundary || is_boundary_[cands_.tets(c)[i]];
    if (on_boundary) keyed.push_back({c.quality, ci});
  }
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<index_t> order(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  for (std::size_t i = 0; i < order.size(); ++i) {
    prefetch_candidates(order, i);
    const index_t ci = order[i];
    if (!available(ci)) continue;
    if (!stage.allow_nonconforming && violations(ci) > 0) continue;
    choose(ci);
  }
}

// Exhaustive-greedy over the boundary tets (the paper's order): the tet with the fewest available
// candidates of this stage's type goes first (bucket queue; counts only decrease).
void Selector::boundary_stage(const Stage& stage) {
  const index_t nt = mesh_.nb_tets();
  std::vector<index_t> count(nt, 0);
  std::vector<char> counted(cands_.size(), 0);
  std::vector<std::vector<index_t>> buckets(1);
  for (index_t t = 0; t < nt; ++t) {
    if (!is_boundary_[t] || !is_free(t)) continue;
    for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
      if (types_[k] == stage.type && available(ids_[k])) ++count[t];
    }
    if (count[t] == 0) continue;
    if (buckets.size() <= count[t]) buckets.resize(count[t] + 1);
    buckets[count[t]].push_back(t);
  }
  for (std::size_t b = 1; b < buckets.size();) {
    if (buckets[b].empty()) {
      ++b;
      continue;
    }
    const index_t t = buckets[b].back();
    buckets[b].pop_back();
    if (!is_free(t) || count[t] != b) continue;  // stale entry
    const index_t ci = best_at(t, stage);
    count[t] = 0;
    if (ci == NO_INDEX) continue;
    choose(ci);
    // Candidates that lost a tet are no longer available: their boundary tets move down.
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) {
      const index_t s = cands_.tets(c)[i];
      for (index_t k = offsets_[s]; k < offsets_[s + 1]; ++k) {
        const index_t xi = ids_[k];
        if (xi == ci || types_[k] != stage.type || counted[xi]) continue;
        const Candidate& x = cands_[xi];
        counted[xi] = 1;
        for (int j = 0; j < x.nb_tets; ++j) {
          const index_t u = cands_.tets(x)[j];
          if (!is_boundary_[u] || !is_free(u) || count[u] == 0) continue;
          --count[u];
          if (count[u] > 0) {
            buckets[count[u]].push_back(u);
            b = std::min<std::size_t>(b, count[u]);
          }
        }
      }
    }
  }
}

// Where quads may meet triangles (allow, last_resort), chosen elements can still leave a
// crack: (1) a quad face half on the domain boundary, half inside (nothing can cover it);
// (2) two elements capping one free tet from its two sides, each with a quad face on two of
// the tet's faces: two quads on the same four corners with the other diagonal, the tet
// sandwiched between; (3) an element capping a free tet whose other two faces are on the
// domain boundary (the quad has the boundary's corners). Releases the element in (1) and (3),
// and in (2) the one that saves fewer tets (the later one on ties): a release only leaves tets,
// so no new crack appears.
void Selector::release_cracks() {
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    if (!chosen_[ci]) continue;
    const Candidate& c = cands_[ci];
    const Sides s = sides(ci);
    const CellDescriptor& d = descriptor(c.type);
    for (int f = 0; f < d.nb_faces && chosen_[ci]; ++f) {
      if (d.face_size[f] != 4) continue;
      const auto n = tets_behind(s, f);
      if ((n[0] == NO_CELL) != (n[1] == NO_CELL)) {
        release(ci);
        ++result_.released_elements;
      }
    }
  }
  auto drop_one = [&](index_t a, index_t b) {
    const int ga = gain(cands_[a]), gb = gain(cands_[b]);
    release(ga > gb || (ga == gb && a < b) ? b : a);
    ++result_.released_elements;
  };
  // The complementary pairs of a tet's faces: faces (p, q) form one quad on the tet's
  // corners, the other two faces the same quad with the other diagonal.
  static constexpr int kPairs[3][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}};
  for (index_t t = 0; t < mesh_.nb_tets(); ++t) {
    if (!is_free(t)) continue;
    std::array<std::pair<index_t, int>, 4> quad_of{};  // per face: (element, its quad face)
    for (int f = 0; f < 4; ++f) {
      quad_of[f] = {NO_INDEX, -1};
      const index_t n = topo_.neighbor(t, f);
      if (n == NO_CELL || is_free(n)) continue;
      const int nf = topo_.neighbor_face(t, f);
      if (owner_quad(n, nf)) quad_of[f] = {owner_[n], owner_face(n, nf)};
    }
    for (const auto& p : kPairs) {
      for (int side = 0; side < 2; ++side) {
        // An element's quad on two faces of t, t's other two faces on the domain boundary: the
        // quad has the boundary's corners, and a face matching takes it for the boundary.
        const int* q = p + 2 * side;
        const int* r = p + 2 - 2 * side;
        const auto a = quad_of[q[0]];
        if (a.first != NO_INDEX && quad_of[q[1]] == a && topo_.on_boundary(t, r[0]) &&
            topo_.on_boundary(t, r[1])) {
          release(a.first);
          ++result_.released_elements;
          quad_of[q[0]] = quad_of[q[1]] = {NO_INDEX, -1};
        }
      }
      const auto a = quad_of[p[0]], b = quad_of[p[2]];
      if (a.first == NO_INDEX || b.first == NO_INDEX || a.first == b.first) continue;
      if (quad_of[p[1]] != a || quad_of[p[3]] != b) continue;
      drop_one(a.first, b.first);
      break;
    }
  }
}

// Tets in breadth-first order from the boundary tets (then any tet not reached, in order).
std::vector<index_t> Selector::breadth_first_order() const {
  const index_t nt = mesh_.nb_tets();
  std::vector<index_t> order;
  order.reserve(nt);
  std::vector<char> seen(nt, 0);
  for (index_t t = 0; t < nt; ++t) {
    if (is_boundary_[t]) {
      seen[t] = 1;
      order.push_back(t);
    }
  }
  for (std::size_t head = 0; head < order.size() || order.size() < nt; ++head) {
    if (head == order.size()) {  // a part with no boundary tet: start anywhere
      index_t s = 0;
      while (seen[s]) ++s;
      seen[s] = 1;
      order.push_back(s);
    }
    const index_t t = order[head];
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo_.neighbor(t, f);
      if (n != NO_CELL && !seen[n]) {
        seen[n] = 1;
        order.push_back(n);
      }
    }
  }
  return order;
}

// Asks the memory for what best_at will read at the free tets ahead of order[i], a step of the
// chain at each distance (each step's address is read from the step before, fetched a few
// tets earlier): the tet's entry of the index, its candidates and their types, the records of
// those of `type`, then their tets and cell faces. At 1M tets in a mesh numbered in no
// spatial order every one of these is a miss; asked for together they overlap. Only reads:
// the selection is the same.
void Selector::prefetch_ahead(const std::vector<index_t>& order, std::size_t i,
                              CellType type) const {
  constexpr std::size_t kOffsets = 16, kIds = 12, kRecords = 8, kTets = 4;
  const std::size_t n = order.size();
  if (i + kOffsets < n) __builtin_prefetch(&offsets_[order[i + kOffsets]]);
  if (i + kIds < n && is_free(order[i + kIds])) {
    // (A tet of no candidate may start at the end of the lists: an address, never read.)
    const index_t k = offsets_[order[i + kIds]];
    __builtin_prefetch(ids_.data() + k);
    __builtin_prefetch(types_.data() + k);
  }
  if (i + kRecords < n && is_free(order[i + kRecords])) {
    const index_t t = order[i + kRecords];
    for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
      if (types_[k] == type) __builtin_prefetch(&cands_[ids_[k]]);
    }
  }
  if (i + kTets < n && is_free(order[i + kTets])) {
    const index_t t = order[i + kTets];
    for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
      if (types_[k] != type) continue;
      prefetch_cell(cands_[ids_[k]]);
    }
  }
}

// Asks for a candidate's tets and the cell faces of its tets.
void Selector::prefetch_cell(const Candidate& c) const {
  __builtin_prefetch(cands_.tets(c).data());
  __builtin_prefetch(&index_.cell_face[4 * static_cast<std::size_t>(c.first_tet)]);
}

// As prefetch_ahead, for a list of candidates visited in order (by quality: in no order in memory):
// the records ahead of list[i], then the tets and cell faces of those a little nearer.
void Selector::prefetch_candidates(const std::vector<index_t>& list, std::size_t i) const {
  constexpr std::size_t kRecords = 8, kTets = 4;
  if (i + kRecords < list.size()) __builtin_prefetch(&cands_[list[i + kRecords]]);
  if (i + kTets < list.size()) {
    prefetch_cell(cands_[list[i + kTets]]);
  }
}

void Selector::interior_stage(const Stage& stage, const std::vector<index_t>& order) {
  for (std::size_t i = 0; i < order.size(); ++i) {
    prefetch_ahead(order, i, stage.type);
    const index_t t = order[i];
    if (!is_free(t)) continue;
    const index_t ci = best_at(t, stage);
    if (ci != NO_INDEX) choose(ci);
  }
}

// Step 4: quad faces facing free tets get the element that closes them. In conforming mode
// an element whose quad still cannot conform is then released (its tets stay tets) and its
// neighbours get one more chance to close what the release opened. Termination: the queue
// holds an element once at a time, and a candidate can be chosen as a closer only once, so
// every choice and every release happens a bounded number of times.
void Selector::close_quads() {
  std::vector<index_t> chosen_now;
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    if (chosen_[ci]) chosen_now.push_back(ci);
  }
  for (index_t ci : chosen_now) {
    if (chosen_[ci]) close_pending<void (*)(index_t)>(ci, nullptr);
  }
  if (params_.conformity != Conformity::Conforming) return;
  WorkQueue work(cands_.size());
  auto enqueue = [&](index_t ci) {
    if (chosen_[ci]) work.push(ci);
  };
  // Whatever owns a tet next to a changed element must be looked at again.
  auto touch = [&](index_t ci) {
    enqueue(ci);
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(cands_.tets(c)[i], f);
        if (n != NO_CELL && !is_free(n)) enqueue(owner_[n]);
      }
    }
  };
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    if (chosen_[ci] && violations(ci, false) > 0) enqueue(ci);
  }
  while (!work.empty()) {
    const index_t ci = work.pop();
    if (!chosen_[ci]) continue;
    close_pending(ci, &touch);
    if (violations(ci, false) == 0) continue;
    release(ci);
    ++result_.released_elements;
    touch(ci);
  }
}

template <class Touch>
void Selector::close_pending(index_t ci, Touch* touch) {
  const Candidate& c = cands_[ci];
  const Sides s = sides(ci);
  const CellDescriptor& d = descriptor(c.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] != 4) continue;
    const auto n = tets_behind(s, f);
    if (n[0] == NO_CELL || n[1] == NO_CELL || !is_free(n[0]) || !is_free(n[1])) continue;
    const index_t x = closer(n[0], n[1], nullptr, nullptr);
    if (x == NO_INDEX || was_closer_[x]) continue;
    was_closer_[x] = 1;
    choose(x);
    if (touch) (*touch)(x);
    if (cands_[x].type == CellType::Pyramid) ++result_.closing_pyramids;
  }
}

}  // namespace hexmerge::select
