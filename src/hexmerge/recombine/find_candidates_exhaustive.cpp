#include "hexmerge/recombine/find_candidates_exhaustive.h"

#include <algorithm>
#include <array>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/recombine/quad_pairs.h"

namespace hexmerge {
namespace {

const CellDescriptor& kTet = descriptor(CellType::Tet);

// An oriented quad: its vertex cycle, outward from the tets behind it, rotated to start at its
// smallest vertex; and, per diagonal (0: positions 0-2, 1: positions 1-3), one tet face behind
// it as 4 * tet + face (NO_INDEX when that diagonal's triangles are not an accepted pair).
struct QuadCycle {
  std::array<index_t, 4> v;
  std::array<index_t, 2> seed;
};

// One accepted pair as found, before merging the two diagonals of a cycle.
struct PairRecord {
  std::array<index_t, 4> v;
  index_t seed;
  std::uint8_t diagonal;
};

// Every oriented quad with at least one accepted triangulation, and an index of them by directed
// edge: for vertex a, the (b, quad * 4 + rotation) of every quad whose cycle runs a -> b, sorted
// by b.
class QuadIndex {
 public:
  QuadIndex(const TetMesh& mesh, const QuadPairs& pairs, int threads) {
    const index_t nt = mesh.nb_tets();
    constexpr index_t kChunk = 16384;
    const index_t nb_chunks = (nt + kChunk - 1) / kChunk;
    std::vector<std::vector<PairRecord>> per_chunk(nb_chunks);
    parallel_chunks(nt, kChunk, threads, [&](index_t chunk, index_t begin, index_t end) {
      auto& out = per_chunk[chunk];
      for (index_t t = begin; t < end; ++t) {
        for (int f = 0; f < 4; ++f) {
          for (const QuadPartner* p = pairs.begin(t, f); p != pairs.end(t, f); ++p) {
            std::array<index_t, 4> q;
            if (!quad_from_triangles(tet_face(mesh, t, f), tet_face(mesh, p->face / 4, p->face % 4),
                                     q)) {
              continue;
            }
            const int r = static_cast<int>(std::min_element(q.begin(), q.end()) - q.begin());
            PairRecord rec;
            for (int i = 0; i < 4; ++i) rec.v[i] = q[(r + i) % 4];
            rec.seed = 4 * t + f;
            rec.diagonal = static_cast<std::uint8_t>(r % 2);
            out.push_back(rec);
          }
        }
      }
      std::sort(out.begin(), out.end(), less);
    });

    std::vector<PairRecord> all = concatenate(per_chunk);
    std::sort(all.begin(), all.end(), less);
    for (const PairRecord& r : all) {
      if (quads_.empty() || quads_.back().v != r.v) quads_.push_back({r.v, {NO_INDEX, NO_INDEX}});
      index_t& seed = quads_.back().seed[r.diagonal];
      if (seed == NO_INDEX) seed = r.seed;
    }
    std::vector<PairRecord>().swap(all);

    offsets_.assign(static_cast<std::size_t>(mesh.nb_vertices()) + 1, 0);
    for (const QuadCycle& q : quads_) {
      for (int i = 0; i < 4; ++i) ++offsets_[q.v[i] + 1];
    }
    for (std::size_t i = 0; i + 1 < offsets_.size(); ++i) offsets_[i + 1] += offsets_[i];
    entries_.resize(offsets_.back());
    std::vector<index_t> fill(offsets_.begin(), offsets_.end() - 1);
    for (index_t k = 0; k < quads_.size(); ++k) {
      for (int i = 0; i < 4; ++i) {
        entries_[fill[quads_[k].v[i]]++] = {quads_[k].v[(i + 1) % 4], 4 * k + i};
      }
    }
    for (std::size_t a = 0; a + 1 < offsets_.size(); ++a) {
      std::sort(entries_.begin() + offsets_[a], entries_.begin() + offsets_[a + 1]);
    }
  }

  std::size_t size() const { return quads_.size(); }
  const QuadCycle& quad(index_t k) const { return quads_[k]; }

  // Calls fn(c, d, quad) for every quad whose cycle is a -> b -> c -> d; stops when fn returns
  // false.
  template <class Fn>
  void for_each_on_edge(index_t a, index_t b, Fn&& fn) const {
    auto first = entries_.begin() + offsets_[a], last = entries_.begin() + offsets_[a + 1];
    first = std::lower_bound(first, last, std::make_pair(b, index_t(0)));
    for (; first != last && first->first == b; ++first) {
      const QuadCycle& q = quads_[first->second / 4];
      const int r = static_cast<int>(first->second % 4);
      if (!fn(q.v[(r + 2) % 4], q.v[(r + 3) % 4], q)) return;
    }
  }

  // True when the cycle a -> b -> c -> d is an accepted quad.
  bool has(index_t a, index_t b, index_t c, index_t d) const {
    bool found = false;
    for_each_on_edge(a, b, [&](index_t qc, index_t qd, const QuadCycle&) {
      found = qc == c && qd == d;
      return !found;
    });
    return found;
  }

 private:
  static bool less(const PairRecord& a, const PairRecord& b) {
    if (a.v != b.v) return a.v < b.v;
    if (a.diagonal != b.diagonal) return a.diagonal < b.diagonal;
    return a.seed < b.seed;
  }

  std::vector<QuadCycle> quads_;
  std::vector<index_t> offsets_;
  std::vector<std::pair<index_t, index_t>> entries_;
};

constexpr int kMaxGroup = MAX_CANDIDATE_TETS;
// Caps up to which every subset is a candidate (2^3 = 8 candidates at most per cell).
constexpr int kMaxCapSubsets = 3;

// Verifies cells and turns them into candidates.
class CellBuilder {
 public:
  CellBuilder(const TetMesh& mesh, const TetTopology& topology, const QuadPairs& pairs,
              const AcceptanceCriteria& criteria, Candidates& out)
      : mesh_(mesh), topo_(topology), pairs_(pairs), criteria_(criteria), out_(out) {}

  // The cell of `type` on `vertices` (local order), grown from tet face `seed` (4 * tet + face,
  // a face lying on the cell's face 0... or any face of the cell): adds its candidates (none, one,
  // or two with caps) when it is filled and accepted. Returns whether it was filled.
  bool build(CellType type, const std::array<index_t, 8>& vertices, index_t seed) {
    type_ = type;
    d_ = &descriptor(type);
    v_ = vertices;
    for (int f = 0; f < d_->nb_faces; ++f) {
      unsigned m = 0;
      for (int i = 0; i < d_->face_size[f]; ++i) m |= 1u << d_->face[f][i];
      face_mask_[f] = m;
    }
    if (!grow(seed / 4)) return false;
    if (!match_boundary()) return false;
    emit();
    return true;
  }

 private:
  int local(index_t v) const {
    for (int i = 0; i < d_->nb_vertices; ++i) {
      if (v_[i] == v) return i;
    }
    return -1;
  }

  // The cell face holding all vertices of local mask m, or -1.
  int face_holding(unsigned m) const {
    for (int f = 0; f < d_->nb_faces; ++f) {
      if ((m & ~face_mask_[f]) == 0) return f;
    }
    return -1;
  }

  bool inside(index_t t) const {
    const index_t* q = mesh_.tet(t);
    for (int i = 0; i < 4; ++i) {
      if (local(q[i]) < 0) return false;
    }
    return true;
  }

  bool in_group(index_t t) const { return std::find(group_, group_ + nb_, t) != group_ + nb_; }

  // The group: every tet reached from `start` across faces not on the cell's faces.
  bool grow(index_t start) {
    nb_ = 0;
    nb_boundary_ = 0;
    if (!inside(start)) return false;
    const std::int32_t region = mesh_.region(start);
    group_[nb_++] = start;
    for (int i = 0; i < nb_; ++i) {
      const index_t t = group_[i];
      const index_t* q = mesh_.tet(t);
      for (int f = 0; f < 4; ++f) {
        unsigned m = 0;
        for (int k = 0; k < 3; ++k) m |= 1u << local(q[kTet.face[f][k]]);
        const int g = face_holding(m);
        if (g >= 0) {
          // A triangle of the cell's surface: the group's boundary (a cell has at most 12).
          if (nb_boundary_ == 12) return false;
          boundary_[nb_boundary_++] = {4 * t + f, static_cast<index_t>(g)};
          continue;
        }
        const index_t n = topo_.neighbor(t, f);
        if (n == NO_CELL) return false;
        if (in_group(n)) continue;
        if (local(mesh_.tet(n)[topo_.neighbor_face(t, f)]) < 0) return false;
        if (criteria_.respect_regions && mesh_.region(n) != region) return false;
        if (nb_ == kMaxGroup) return false;
        group_[nb_++] = n;
      }
    }
    return true;
  }

  // Positions, in cell face g's cycle, of the triangle's vertices run in the same cyclic order.
  bool same_orientation(int g, const std::array<index_t, 3>& tri, int& missing) const {
    const int n = d_->face_size[g];
    int pos[3];
    for (int k = 0; k < 3; ++k) {
      pos[k] = -1;
      for (int i = 0; i < n; ++i) {
        if (v_[d_->face[g][i]] == tri[k]) pos[k] = i;
      }
    }
    int turns = 0;
    for (int k = 0; k < 3; ++k) turns += (pos[(k + 1) % 3] - pos[k] + n) % n;
    missing = n * (n - 1) / 2 - pos[0] - pos[1] - pos[2];  // 0+1+2+3 minus the three
    return turns == n;
  }

  // The group's boundary is exactly the cell's faces, outward: one triangle per triangular face,
  // two triangles on one diagonal per quad face.
  bool match_boundary() {
    const int expected = 2 * d_->nb_quad_faces + (d_->nb_faces - d_->nb_quad_faces);
    if (nb_boundary_ != expected) return false;
    std::array<int, 6> count{};
    std::array<int, 6> missing{};
    for (int b = 0; b < nb_boundary_; ++b) {
      const index_t code = boundary_[b][0];
      const int g = static_cast<int>(boundary_[b][1]);
      int m = 0;
      if (!same_orientation(g, tet_face(mesh_, code / 4, code % 4), m)) return false;
      if (count[g] == 0) {
        missing[g] = m;
        face_tris_[g][0] = code;
      } else {
        if (d_->face_size[g] != 4 || count[g] > 1 || (missing[g] - m + 4) % 4 != 2) return false;
        face_tris_[g][1] = code;
      }
      ++count[g];
    }
    for (int g = 0; g < d_->nb_faces; ++g) {
      if (count[g] != (d_->face_size[g] == 4 ? 2 : 1)) return false;
    }
    return true;
  }

  // Whether (a, b) is an accepted pair of tet faces, from either side.
  bool accepted_pair(index_t a, index_t b) const {
    for (int side = 0; side < 2; ++side) {
      for (const QuadPartner* p = pairs_.begin(a / 4, a % 4); p != pairs_.end(a / 4, a % 4); ++p) {
        if (p->face == b) return true;
      }
      std::swap(a, b);
    }
    return false;
  }

  // Face f of tet t on the domain's boundary, or on a region interface when regions are kept
  // apart (then the interface is each region's boundary and takes the boundary's dangle).
  bool boundary_face(index_t t, int f) const {
    if (topo_.on_boundary(t, f)) return true;
    return criteria_.respect_regions && mesh_.region(t) != mesh_.region(topo_.neighbor(t, f));
  }

  // Whether the quad made of two outward faces of one tet (a flat cap) passes the angles.
  bool cap_accepted(index_t t, int f1, int f2) const {
    std::array<index_t, 4> q;
    if (!quad_from_triangles(tet_face(mesh_, t, f1), tet_face(mesh_, t, f2), q)) return false;
    const double dh = quad_dihedral_angle(mesh_.point(q[0]), mesh_.point(q[1]), mesh_.point(q[2]),
                                          mesh_.point(q[3]));
    const double cr = quad_max_corner_angle(mesh_.point(q[0]), mesh_.point(q[1]), mesh_.point(q[2]),
                                            mesh_.point(q[3]));
    const bool on_boundary = boundary_face(t, f1) && boundary_face(t, f2);
    const double min_dihedral =
        on_boundary ? criteria_.min_boundary_dihedral_angle : criteria_.min_dihedral_angle;
    return dh >= min_dihedral && cr <= criteria_.max_face_angle;
  }

  // The group's candidate, and with caps: flat tets lying on its quad faces, outside the group,
  // that may join it (on a face between two cells, either may take the cap). Every subset of the
  // caps when there are at most kMaxCapSubsets of them, otherwise none and all.
  void emit() {
    const double sj = scaled_jacobian(type_, mesh_.points.data(), v_.data());
    if (!good_enough(criteria_, mesh_, type_, sj, group_, nb_)) return;
    std::array<int, 6> cap_of_quad;  // per quad face: index into caps, or -1
    std::array<index_t, 6> caps;
    int nb_caps = 0, nb_quads = 0;
    for (int g = 0; g < d_->nb_faces; ++g) {
      if (d_->face_size[g] != 4) continue;
      int& cap = cap_of_quad[nb_quads++];
      cap = -1;
      const index_t a = face_tris_[g][0], b = face_tris_[g][1];
      if (!accepted_pair(a, b)) return;
      const index_t na = topo_.neighbor(a / 4, a % 4), nb = topo_.neighbor(b / 4, b % 4);
      if (na != NO_CELL && na == nb && nb_ + nb_caps < kMaxGroup &&
          (!criteria_.respect_regions || mesh_.region(na) == mesh_.region(group_[0])) &&
          cap_on_face(na, g) && cap_accepted(na, other_face(a, b, 0), other_face(a, b, 1))) {
        cap = nb_caps;
        caps[nb_caps++] = na;
      }
    }
    Candidate c;
    c.vertices = v_;
    c.type = type_;
    c.graph = EXHAUSTIVE_GRAPH;
    c.quality = static_cast<float>(sj);
    const unsigned all = (1u << nb_caps) - 1;
    index_t tets[kMaxGroup];
    for (unsigned subset = 0; subset <= all; ++subset) {
      if (nb_caps > kMaxCapSubsets && subset != 0 && subset != all) continue;
      std::copy(group_, group_ + nb_, tets);
      int n = nb_;
      for (int q = 0; q < nb_quads; ++q) {
        const int cap = cap_of_quad[q];
        if (cap >= 0 && (subset & (1u << cap))) tets[n++] = caps[cap];
      }
      std::sort(tets, tets + n);
      out_.push_back(c, tets, n);
    }
  }

  // Tet t has its four vertices on the cell's face g.
  bool cap_on_face(index_t t, int g) const {
    const index_t* q = mesh_.tet(t);
    unsigned m = 0;
    for (int i = 0; i < 4; ++i) {
      const int l = local(q[i]);
      if (l < 0) return false;
      m |= 1u << l;
    }
    return m == face_mask_[g];
  }

  // The k-th face of the cap behind the group's faces a and b, other than those two.
  int other_face(index_t a, index_t b, int k) const {
    const int fa = topo_.neighbor_face(a / 4, a % 4), fb = topo_.neighbor_face(b / 4, b % 4);
    for (int f = 0; f < 4; ++f) {
      if (f == fa || f == fb) continue;
      if (k-- == 0) return f;
    }
    return 0;
  }

  const TetMesh& mesh_;
  const TetTopology& topo_;
  const QuadPairs& pairs_;
  const AcceptanceCriteria& criteria_;
  Candidates& out_;
  CellType type_ = CellType::Hex;
  const CellDescriptor* d_ = nullptr;
  std::array<index_t, 8> v_{};
  std::array<unsigned, 6> face_mask_{};
  index_t group_[kMaxGroup];
  int nb_ = 0;
  std::array<std::array<index_t, 2>, 12> boundary_;  // (4 * tet + face, cell face)
  int nb_boundary_ = 0;
  std::array<std::array<index_t, 2>, 6> face_tris_;  // per quad face: its two triangles
};

// The searches from one quad taken as a base (hex, pyramid) or a side (prism).
class Searcher {
 public:
  Searcher(const TetMesh& mesh, const QuadIndex& index, const AcceptanceCriteria& criteria,
           CellBuilder& builder)
      : mesh_(mesh), index_(index), criteria_(criteria), builder_(builder) {}

  void run(const QuadCycle& q) {
    if (criteria_.types[static_cast<int>(CellType::Hex)]) hexes(q);
    if (criteria_.types[static_cast<int>(CellType::Prism)]) prisms(q);
    if (criteria_.types[static_cast<int>(CellType::Pyramid)]) pyramids(q);
  }

 private:
  // Builds from either diagonal's seed until one fills the cell.
  void build(CellType type, const std::array<index_t, 8>& v, const QuadCycle& q) {
    for (const index_t seed : q.seed) {
      if (seed != NO_INDEX && builder_.build(type, v, seed)) return;
    }
  }

  // Hexahedra with q as the base 0-1-2-3 and v0 = q.v[0] their smallest vertex. Of the three
  // quads at v0, the base is the one without v0's largest neighbour (v4): each hex once.
  void hexes(const QuadCycle& q) {
    // Outward base cycle (0, 3, 2, 1).
    const index_t v0 = q.v[0], v3 = q.v[1], v2 = q.v[2], v1 = q.v[3];
    auto in_base = [&](index_t u) { return u == v0 || u == v1 || u == v2 || u == v3; };
    // Side (0, 1, 5, 4).
    index_t& u0 = top_[0];
    index_t& u1 = top_[1];
    index_t& u2 = top_[2];
    index_t& u3 = top_[3];
    index_.for_each_on_edge(v0, v1, [&](index_t c5, index_t c4, const QuadCycle&) {
      u1 = c5;
      u0 = c4;
      if (u0 < v1 || u0 < v3 || u1 < v0 || in_base(u0) || in_base(u1)) return true;
      // Side (1, 2, 6, 5).
      index_.for_each_on_edge(v1, v2, [&](index_t c6, index_t c5b, const QuadCycle&) {
        if (c5b != u1) return true;
        u2 = c6;
        if (u2 < v0 || in_base(u2) || u2 == u0) return true;
        // Side (2, 3, 7, 6).
        index_.for_each_on_edge(v2, v3, [&](index_t c7, index_t c6b, const QuadCycle&) {
          if (c6b != u2) return true;
          u3 = c7;
          if (u3 < v0 || in_base(u3) || u3 == u0 || u3 == u1) return true;
          // Side (3, 0, 4, 7) and top (4, 5, 6, 7).
          if (!index_.has(v3, v0, u0, u3) || !index_.has(u0, u1, u2, u3)) return true;
          build(CellType::Hex, {v0, v1, v2, v3, u0, u1, u2, u3}, q);
          return true;
        });
        return true;
      });
      return true;
    });
  }

  // Prisms with q as side (0, 1, 4, 3) and v0 = q.v[0] their smallest vertex: each prism once.
  void prisms(const QuadCycle& q) {
    const index_t v0 = q.v[0], v1 = q.v[1], v4 = q.v[2], v3 = q.v[3];
    // Side (1, 2, 5, 4), as the cycle 4 -> 1 -> 2 -> 5.
    index_.for_each_on_edge(v4, v1, [&](index_t v2, index_t v5, const QuadCycle&) {
      if (v2 < v0 || v5 < v0 || v2 == v3 || v5 == v0 || v2 == v5) return true;
      if (v2 == v0 || v2 == v4 || v5 == v1 || v5 == v3) return true;
      // Side (2, 0, 3, 5), as the cycle 0 -> 3 -> 5 -> 2.
      if (!index_.has(v0, v3, v5, v2)) return true;
      build(CellType::Prism, {v0, v1, v2, v3, v4, v5, NO_VERTEX, NO_VERTEX}, q);
      return true;
    });
  }

  // Pyramids on base q (outward cycle (0, 3, 2, 1), v0 its smallest vertex); the apex is the
  // fourth vertex of the tet behind the base.
  void pyramids(const QuadCycle& q) {
    index_t apex_tried = NO_VERTEX;
    for (const index_t seed : q.seed) {
      if (seed == NO_INDEX) continue;
      const index_t apex = mesh_.tet(seed / 4)[seed % 4];
      if (apex == apex_tried) continue;
      apex_tried = apex;
      if (apex == q.v[0] || apex == q.v[1] || apex == q.v[2] || apex == q.v[3]) continue;
      builder_.build(CellType::Pyramid,
                     {q.v[0], q.v[3], q.v[2], q.v[1], apex, NO_VERTEX, NO_VERTEX, NO_VERTEX}, seed);
    }
  }

  const TetMesh& mesh_;
  const QuadIndex& index_;
  const AcceptanceCriteria& criteria_;
  CellBuilder& builder_;
  std::array<index_t, 4> top_{};
};

}  // namespace

Candidates find_candidates_exhaustive(const TetMesh& mesh, const TetTopology& topology,
                                      const AcceptanceCriteria& criteria, int threads,
                                      const ProgressCallback& progress) {
  threads = std::max(1, threads);
  const QuadPairs pairs(mesh, topology, criteria.min_dihedral_angle,
                        criteria.min_boundary_dihedral_angle, criteria.max_face_angle, threads,
                        criteria.respect_regions);
  const QuadIndex index(mesh, pairs, threads);

  const index_t nq = static_cast<index_t>(index.size());
  constexpr index_t kChunk = 8192;
  std::vector<Candidates> per_chunk((nq + kChunk - 1) / kChunk);
  parallel_chunks(
      nq, kChunk, threads,
      [&](index_t chunk, index_t begin, index_t end) {
        CellBuilder builder(mesh, topology, pairs, criteria, per_chunk[chunk]);
        Searcher searcher(mesh, index, criteria, builder);
        for (index_t k = begin; k < end; ++k) searcher.run(index.quad(k));
      },
      [&](double fraction) { return !progress || progress("candidates", fraction); });
  Candidates all;
  std::size_t nb = 0, nb_tets = 0;
  for (const Candidates& chunk : per_chunk) {
    nb += chunk.size();
    nb_tets += chunk.all_tets().size();
  }
  all.reserve(nb, nb_tets);
  for (Candidates& chunk : per_chunk) {
    all.append(chunk);
    chunk = Candidates();
  }
  return all;
}

}  // namespace hexmerge
