#pragma once
/// @file
/// The candidates' storage: one fixed-size record per candidate, and the tets of all of them in
/// one shared array, each candidate's tets found by an offset and a count in its record.
///
/// A candidate has 2 to 16 tets (3.6 on average on a lattice mesh, 2.6 on a Delaunay one): 16
/// slots in every record made it 104 bytes, of which the tets used 14 on average; the record is
/// now 44 bytes and the tets 4 bytes each (docs/benchmarks.md, the engine's profile).

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/core/index.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

/// Most tets in one candidate: a hexahedron's subdivisions have 5 to 15 tets (Pellerin,
/// Verhetsel & Remacle 2018); the exhaustive finder's groups may add flat tets on its faces.
constexpr int MAX_CANDIDATE_TETS = 16;

/// A possible element: a group of tets and the cell they form. Its tets are held by the
/// Candidates it belongs to (Candidates::tets).
struct Candidate {
  std::array<index_t, 8> vertices;  ///< local order of cell_type.h; unused slots NO_VERTEX
  index_t first_tet;                ///< where its tets begin in its Candidates' tet array
  CellType type;
  std::uint8_t graph;  ///< index into rf_graphs() of the template that found it, or
                       ///< EXHAUSTIVE_GRAPH (find_candidates_exhaustive.h)
  std::uint8_t nb_tets;
  float quality;  ///< scaled Jacobian
};
static_assert(sizeof(Candidate) == 44, "the record's size is the lattice's peak of memory");

/// The tets of one candidate, sorted: a view into its Candidates' tet array, valid until that
/// array changes.
class TetSpan {
 public:
  TetSpan(const index_t* first, int size) : first_(first), size_(size) {}
  const index_t* begin() const { return first_; }
  const index_t* end() const { return first_ + size_; }
  const index_t* data() const { return first_; }
  int size() const { return size_; }
  index_t operator[](int i) const { return first_[i]; }
  /// Whether t is one of them (a linear scan: at most MAX_CANDIDATE_TETS).
  bool contains(index_t t) const {
    for (int i = 0; i < size_; ++i)
      if (first_[i] == t) return true;
    return false;
  }

 private:
  const index_t* first_;
  int size_;
};

/// Candidates: their records, in order, and their tets in one array, in the same order (the
/// tets of candidate i follow those of candidate i - 1: first_tet is the sum of the nb_tets
/// before it).
class Candidates {
 public:
  Candidates() = default;
  /// From records and tets already laid out as above (checked: a broken layout is a
  /// programmer error).
  Candidates(std::vector<Candidate> records, std::vector<index_t> tets)
      : records_(std::move(records)), tets_(std::move(tets)) {
    std::size_t next = 0;
    for (const Candidate& c : records_) {
      HEXMERGE_ASSERT(c.first_tet == next && c.nb_tets >= 1 && c.nb_tets <= MAX_CANDIDATE_TETS,
                      "Candidates: the records' tets are not consecutive");
      next += c.nb_tets;
    }
    HEXMERGE_ASSERT(next == tets_.size(), "Candidates: tets past the last record's");
  }

  std::size_t size() const { return records_.size(); }
  bool empty() const { return records_.empty(); }
  const Candidate& operator[](std::size_t ci) const { return records_[ci]; }
  std::vector<Candidate>::const_iterator begin() const { return records_.begin(); }
  std::vector<Candidate>::const_iterator end() const { return records_.end(); }

  /// A candidate's tets (c one of these records).
  TetSpan tets(const Candidate& c) const { return {tets_.data() + c.first_tet, c.nb_tets}; }
  TetSpan tets(std::size_t ci) const { return tets(records_[ci]); }
  /// The tets of all candidates, in order.
  const std::vector<index_t>& all_tets() const { return tets_; }

  void reserve(std::size_t nb_candidates, std::size_t nb_tets) {
    records_.reserve(nb_candidates);
    tets_.reserve(nb_tets);
  }

  /// Appends a candidate made of `nb` tets (sorted, distinct, 1 to MAX_CANDIDATE_TETS);
  /// c.first_tet and c.nb_tets are set here.
  void push_back(Candidate c, const index_t* tets, int nb) {
    HEXMERGE_ASSERT(nb >= 1 && nb <= MAX_CANDIDATE_TETS,
                    "Candidates: a candidate of no tets or more than MAX_CANDIDATE_TETS");
    if (tets_.size() + nb >= NO_INDEX) {
      throw ResourceError("the candidates hold more than 2^32 - 2 tets in all");
    }
    c.first_tet = static_cast<index_t>(tets_.size());
    c.nb_tets = static_cast<std::uint8_t>(nb);
    tets_.insert(tets_.end(), tets, tets + nb);
    records_.push_back(c);
  }

  /// Removes the last candidate and its tets.
  void pop_back() {
    HEXMERGE_ASSERT(!records_.empty(), "Candidates: pop_back on none");
    tets_.resize(records_.back().first_tet);
    records_.pop_back();
  }

  /// Appends the candidates of `other`, in order.
  void append(const Candidates& other) {
    for (const Candidate& c : other) push_back(c, other.tets(c).data(), c.nb_tets);
  }

  /// Keeps the candidates ci for which keep(ci) is true, in order, with their tets: moved up in
  /// place, no second array. keep is called once per candidate, in order, and may read that
  /// candidate (its record and tets are still in place then).
  template <class Keep>
  void keep_if(Keep&& keep) {
    std::size_t kept = 0, tets_kept = 0;
    for (std::size_t ci = 0; ci < records_.size(); ++ci) {
      if (!keep(static_cast<index_t>(ci))) continue;
      Candidate c = records_[ci];
      for (int i = 0; i < c.nb_tets; ++i) tets_[tets_kept + i] = tets_[c.first_tet + i];
      c.first_tet = static_cast<index_t>(tets_kept);
      tets_kept += c.nb_tets;
      records_[kept++] = c;
    }
    records_.resize(kept);
    tets_.resize(tets_kept);
  }

  /// Lets go of the arrays' spare capacity (a copy of each: call it where that is not the peak).
  void shrink_to_fit() {
    records_.shrink_to_fit();
    tets_.shrink_to_fit();
  }

 private:
  std::vector<Candidate> records_;
  std::vector<index_t> tets_;
};

}  // namespace hexmerge
