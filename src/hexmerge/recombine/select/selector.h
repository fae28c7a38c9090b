#pragma once
/// @file
/// The selection's internals: one Selector, whose member functions live in one file per stage
/// (the order in which Selector::run calls them):
/// - select_candidates.cpp: the entry (select_candidates, the strategy) and Selector::run;
/// - kernel.cpp: conformity of a candidate against what is chosen (violations, closers), the
///   ranking at a tet, and the move journal (begin_move, rollback); ownership and choose/release
///   are inline here;
/// - block.cpp: the block of near-perfect and planar-quad hexahedra and prisms (step 0);
/// - groups.cpp: hexahedra taken in conforming groups (step 0b);
/// - greedy.cpp: the boundary and interior greedy stages, the closing of quad faces (step 4)
///   and, outside conforming mode, the release of cracks;
/// - local_optimisation.cpp: the paper's local optimisation at unmatched boundary tets (4.2);
/// - local_search.cpp: swaps and exact re-selection in neighbourhoods (step 5).
/// What runs, in which order, is described in select_candidates.h.

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/select/select_candidates.h"

namespace hexmerge::select {

using QuadKey = FaceKey;  // sorted vertices of a quad face

// The quad faces asked of the element that takes two tets: the open quad itself and at most one
// per face of each tet.
struct QuadKeys {
  std::array<QuadKey, 9> key;
  int count = 0;
  void add(const QuadKey& k) {
    for (int i = 0; i < count; ++i) {
      if (key[i] == k) return;
    }
    key[count++] = k;
  }
  const QuadKey* begin() const { return key.data(); }
  const QuadKey* end() const { return key.data() + count; }
};

inline int gain(const Candidate& c) { return c.nb_tets - 1; }  // elements saved by merging

// One boundary triangle of a candidate: the tet face it is, the tet across it, and the face of
// the candidate's cell that it lies in.
struct Side {
  index_t neighbor;   // NO_CELL on the domain boundary
  int neighbor_face;  // local face of the neighbour across it
  int cell_face;
};

struct Sides {
  std::array<Side, 12> side;
  int count = 0;
};

inline bool is_quad(const Candidate& c, int f) { return descriptor(c.type).face_size[f] == 4; }

// A stage of a greedy phase: which element type, and whether non-conforming ones may be taken.
struct Stage {
  CellType type;
  bool allow_nonconforming;
};

// What every selection reads and none changes, built once: tet -> candidates, the cell face
// each tet face of a candidate lies in, the boundary tets.
struct CandidateIndex {
  CandidateIndex(const TetMesh& mesh, const TetTopology& topo, const Candidates& cands,
                 bool respect_regions, int threads);

  std::vector<index_t> offsets, ids;  // tet -> candidates (CSR)
  // Per CSR entry, its candidate's type: the stages that want one type skip the others without
  // reading their records (at 1M tets the records are far out of cache).
  std::vector<CellType> types;
  // Per candidate's tet i and face f, at 4 * (first_tet + i) + f (the candidates' tets are
  // laid out one after the other, Candidates::all_tets): -1 inside the cell, else the cell face
  // it lies in (bits 0-2), the face of the tet across it (bits 3-4; 0 on the domain boundary),
  // so that sides() reads no TetTopology::neighbor_face, and whether the cell face is a quad
  // (bit 5).
  std::vector<signed char> cell_face;
  std::vector<char> is_boundary;
};

class Selector {
 public:
  Selector(const TetMesh& mesh, const TetTopology& topology, const Candidates& candidates,
           const CandidateIndex& index, const RecombineParameters& parameters, bool strict)
      : mesh_(mesh),
        topo_(topology),
        cands_(candidates),
        params_(parameters),
        strict_(strict),
        owner_(mesh.nb_tets(), NO_INDEX),
        taken_((mesh.nb_tets() + 63) / 64, 0),
        owner_faces_(4 * static_cast<std::size_t>(mesh.nb_tets()), -1),
        chosen_(candidates.size(), 0),
        offsets_(index.offsets),
        ids_(index.ids),
        types_(index.types),
        index_(index),
        is_boundary_(index.is_boundary) {}

  // ---- select/select_candidates.cpp
  Selection run(const ProgressCallback& progress);

 private:
  bool is_free(index_t t) const { return !((taken_[t >> 6] >> (t & 63)) & 1); }

  bool available(index_t ci) const {
    for (const index_t t : cands_.tets(ci)) {
      if (!is_free(t)) return false;
    }
    return true;
  }

  bool contains(const Candidate& c, index_t t) const { return cands_.tets(c).contains(t); }

  // ---- select/kernel.cpp
  Sides sides(index_t ci) const;
  void required_quads(index_t t, QuadKeys& keys) const;
  bool has_quad(const Candidate& x, const QuadKey& key) const;
  index_t closer(index_t n1, index_t n2, const QuadKey* extra, const Candidate* exclude) const;
  index_t closing_pyramid(index_t n1, index_t n2, const QuadKey* key) const;
  index_t pyramid_on(index_t n1, index_t n2, const QuadKey& key) const;
  std::size_t violations(index_t ci, bool pending_ok = true, bool count_triangles = true) const;
  std::size_t risky_quads(index_t ci) const;
  index_t best_at(index_t t, const Stage& stage) const;
  void begin_move();
  void rollback();

  // The tets across the two triangles of quad face f (NO_CELL on the domain boundary).
  static std::array<index_t, 2> tets_behind(const Sides& s, int f) {
    std::array<index_t, 2> n{NO_CELL, NO_CELL};
    int nh = 0;
    for (int i = 0; i < s.count; ++i) {
      if (s.side[i].cell_face == f && nh < 2) n[nh++] = s.side[i].neighbor;
    }
    return n;
  }

  // The cell face of candidate ei that face f of its tet t lies in (-1: inside the cell).
  int cell_face_at(index_t ei, index_t t, int f) const {
    const TetSpan e = cands_.tets(ei);
    const int i = static_cast<int>(std::find(e.begin(), e.end(), t) - e.begin());
    return face_in_cell(cands_[ei], i, f);
  }

  // CandidateIndex::cell_face of face f of candidate c's i-th tet.
  int face_entry(const Candidate& c, int i, int f) const {
    return index_.cell_face[4 * (static_cast<std::size_t>(c.first_tet) + i) + f];
  }

  // The cell face of candidate c that face f of its i-th tet lies in (-1: inside the cell).
  int face_in_cell(const Candidate& c, int i, int f) const {
    const int packed = face_entry(c, i, f);
    return packed < 0 ? -1 : packed & 7;
  }

  // The face, in the tet across it, of face f of candidate c's i-th tet (that face not inside
  // the cell nor on the domain boundary): TetTopology::neighbor_face, from the same entry.
  int face_across(const Candidate& c, int i, int f) const { return (face_entry(c, i, f) >> 3) & 3; }

  // Of a tet n that is not free, face f (not inside its owner's cell): the face of the owner's
  // cell it lies in, and whether that is a quad. From owner_faces_, without the owner's record.
  int owner_face(index_t n, int f) const {
    return owner_faces_[4 * static_cast<std::size_t>(n) + f] & 7;
  }
  bool owner_quad(index_t n, int f) const {
    const int entry = owner_faces_[4 * static_cast<std::size_t>(n) + f];
    return entry >= 0 && (entry & 32) != 0;
  }

  // Ranking at one tet: element type, then fewer non-conformities (in conforming mode: fewer
  // pending quads without a safe closing pyramid), then quality.
  static bool better(const Candidate& a, std::size_t va, const Candidate& b, std::size_t vb) {
    if (a.type != b.type) return static_cast<int>(a.type) > static_cast<int>(b.type);
    if (va != vb) return va < vb;
    return a.quality > b.quality;
  }

  // Every write of owner_ goes through here, so that the bits of is_free and owner_faces_
  // follow it; t is the i-th tet of ci (any i when ci is NO_INDEX).
  void put_owner(index_t t, index_t ci, int i) {
    owner_[t] = ci;
    const std::uint64_t bit = std::uint64_t{1} << (t & 63);
    if (ci == NO_INDEX) {
      taken_[t >> 6] &= ~bit;
    } else {
      taken_[t >> 6] |= bit;
      const std::size_t from = 4 * (static_cast<std::size_t>(cands_[ci].first_tet) + i);
      std::copy_n(&index_.cell_face[from], 4, &owner_faces_[4 * static_cast<std::size_t>(t)]);
    }
  }

  void set_owner(index_t t, index_t ci, int i) {
    if (journaling_) journal_.push_back({t, owner_[t]});
    put_owner(t, ci, i);
  }

  void choose(index_t ci) {
    const TetSpan ct = cands_.tets(ci);
    for (int i = 0; i < ct.size(); ++i) set_owner(ct[i], ci, i);
    if (journaling_) chosen_journal_.push_back({ci, chosen_[ci]});
    chosen_[ci] = 1;
  }

  void release(index_t ci) {
    for (const index_t t : cands_.tets(ci)) set_owner(t, NO_INDEX, 0);
    if (journaling_) chosen_journal_.push_back({ci, chosen_[ci]});
    chosen_[ci] = 0;
  }

  void commit() { journaling_ = false; }

  // ---- select/block.cpp
  bool planar_quads(const Candidate& c) const;
  void select_block();

  // ---- select/groups.cpp
  // A face of a candidate against what is chosen: on the boundary, shared or closed by a
  // reserved pyramid (a triangle: meeting no chosen quad); open (a quad over two free tets that
  // no reserved pyramid closes); or in conflict (nothing can make it conform).
  enum class FaceState { Closed, Open, Conflict };
  FaceState face_state(index_t ci, const Sides& s, int f, std::array<index_t, 2>& behind) const;
  index_t group_partner(index_t n0, index_t n1, const QuadKey& key) const;
  bool grow_group(index_t seed, std::vector<index_t>& members, bool& capped);
  void select_groups();

  // ---- select/greedy.cpp
  void boundary_stage_by_quality(const Stage& stage);
  void boundary_stage(const Stage& stage);
  void release_cracks();
  std::vector<index_t> breadth_first_order() const;
  void interior_stage(const Stage& stage, const std::vector<index_t>& order);
  void prefetch_ahead(const std::vector<index_t>& order, std::size_t i, CellType type) const;
  void prefetch_candidates(const std::vector<index_t>& list, std::size_t i) const;
  void prefetch_cell(const Candidate& c) const;
  void close_quads();
  template <class Touch>
  void close_pending(index_t ci, Touch* touch);

  // ---- select/local_optimisation.cpp
  void local_optimisation();
  void try_move(index_t ci);
  bool neighbourhood_conforms(index_t ci, const std::vector<index_t>& freed) const;

  // ---- Local search (step 5): swaps and exact re-selection in neighbourhoods -----------------

  // Local state of one neighbourhood's branch and bound. Tets of the neighbourhood get local
  // numbers (local_[t]); `state` is UNDECIDED, LEFT_FREE or the pool entry that covers the tet.
  static constexpr int UNDECIDED = -1;
  static constexpr int LEFT_FREE = -2;

  struct Hood {
    std::vector<index_t> tets;        // the neighbourhood, local order
    std::vector<index_t> released;    // the elements it held
    std::vector<index_t> pool;        // candidates wholly inside it that fit the outside
    std::vector<int> at_offsets, at;  // local tet -> pool entries that take it (best first)
    std::vector<char> must_cover;     // local tet: an outside element's quad face ends on it
    std::vector<int> state;
    // The bound: each undecided tet can save at most (n - 1) / n, n the size of the largest
    // open pool entry (no tet of it decided) that takes it. `closed` counts the decided tets of
    // each entry; `open_sizes` counts, per local tet and size n, its open entries; bit n of
    // `sizes` is set while that count is not zero.
    std::vector<int> closed;
    std::vector<std::uint16_t> open_sizes;
    std::vector<std::uint32_t> sizes;
    std::vector<int> current, best;  // pool entries chosen
    int best_saved = 0;
    long long nodes = 0;
    bool stopped = false;
  };

  bool checks_conformity() const { return params_.conformity != Conformity::Allow; }

  // ---- select/local_search.cpp
  bool faces_match(index_t x, int xf, index_t n, int nf) const;
  bool fits_outside(index_t ci) const;
  bool fits_inside(const Hood& h, index_t ci) const;
  bool may_stay_free(const Hood& h, index_t t) const;
  bool reselect(Hood& h);
  static long long share_of(const Hood& h, int l);
  long long close_entries(Hood& h, const int* ls, int k, long long before);
  void reopen_entries(Hood& h, const int* ls, int k);
  void branch(Hood& h, std::size_t pos, int saved, long long rest);
  void hood_add(Hood& h, index_t t);
  void hood_add_element(Hood& h, index_t e);
  void hood_clear_marks(Hood& h);
  bool try_swap(Hood& h, index_t e);
  bool try_reselection(Hood& h, index_t s);
  void local_search();

  // Savings per tet in units of 1 / 720720 (the least common multiple of 2..16), so that the
  // bound is exact in integers: a tet in an element of n tets saves (n - 1) / n.
  static constexpr long long UNIT = 720720;
  static long long share_units(int n) { return (n - 1) * UNIT / n; }

  const TetMesh& mesh_;
  const TetTopology& topo_;
  const Candidates& cands_;
  const RecombineParameters& params_;
  const bool strict_;  // pending quads only where a safe closing pyramid waits (closing_pyramid)
  std::vector<index_t> owner_;  // per tet: the chosen candidate that holds it, or NO_INDEX
  // Per tet, one bit: owner_ is not NO_INDEX. is_free reads these (128 KB at 1M tets, in the
  // second-level cache) rather than owner_ (4 MB).
  std::vector<std::uint64_t> taken_;
  // Per tet not free, its owner's 4 entries of CandidateIndex::cell_face for it (in the tet's
  // face order), copied when the owner is set: conformity against a chosen neighbour reads these
  // (1 MB per 250k tets, next to nothing else) rather than the owner's record, tets and entries
  // (three misses at 1M tets); the record only for a quad face's vertices.
  std::vector<signed char> owner_faces_;
  std::vector<char> chosen_;             // per candidate
  const std::vector<index_t>& offsets_;  // tet -> candidates
  const std::vector<index_t>& ids_;
  const std::vector<CellType>& types_;  // per entry of ids_
  const CandidateIndex& index_;
  const std::vector<char>& is_boundary_;
  std::vector<char> was_closer_ = std::vector<char>(cands_.size(), 0);

  bool journaling_ = false;
  std::vector<std::pair<index_t, index_t>> journal_;      // (tet, previous owner)
  std::vector<std::pair<index_t, char>> chosen_journal_;  // (candidate, previous flag)
  std::vector<int> local_;          // local search: per tet, its number in the neighbourhood
  std::vector<unsigned> stamp_of_;  // local search: per candidate, last neighbourhood seen
  unsigned stamp_ = 0;
  Selection result_;
};

}  // namespace hexmerge::select
