#include "hexmerge/recombine/select_candidates.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include "hexmerge/core/error.h"
#include "hexmerge/core/work_queue.h"
#include "hexmerge/geometry/vec3.h"

namespace hexmerge {
namespace {

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

const CellDescriptor& kTet = descriptor(CellType::Tet);

// Scaled Jacobian from which a hexahedron may join the block (Selector::select_block). The
// share of hexahedra on lattice-seeded meshes is the same from 0.7 to 0.95.
constexpr float kBlockQuality = 0.9f;

int gain(const Candidate& c) { return c.nb_tets - 1; }  // elements saved by merging

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

// Face of the cell of `c` that contains the three vertices, or -1.
int cell_face_of(const Candidate& c, const std::array<index_t, 3>& tri) {
  const CellDescriptor& d = descriptor(c.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    int hits = 0;
    for (int i = 0; i < d.face_size[f]; ++i) {
      const index_t v = c.vertices[d.face[f][i]];
      hits += (v == tri[0]) + (v == tri[1]) + (v == tri[2]);
    }
    if (hits == 3) return f;
  }
  return -1;
}

bool is_quad(const Candidate& c, int f) { return descriptor(c.type).face_size[f] == 4; }

// A stage of a greedy phase: which element type, and whether non-conforming ones may be taken.
struct Stage {
  CellType type;
  bool allow_nonconforming;
};

// What every selection reads and none changes, built once: tet -> candidates, the cell face
// each tet face of a candidate lies in, the boundary tets.
struct CandidateIndex {
  CandidateIndex(const TetMesh& mesh, const TetTopology& topo, const std::vector<Candidate>& cands,
                 bool respect_regions) {
    const index_t nt = mesh.nb_tets();
    offsets.assign(static_cast<std::size_t>(nt) + 1, 0);
    first_face.assign(cands.size() + 1, 0);
    for (index_t ci = 0; ci < cands.size(); ++ci) {
      const Candidate& c = cands[ci];
      for (int i = 0; i < c.nb_tets; ++i) ++offsets[c.tets[i] + 1];
      first_face[ci + 1] = first_face[ci] + 4 * static_cast<std::size_t>(c.nb_tets);
    }
    for (index_t t = 0; t < nt; ++t) offsets[t + 1] += offsets[t];
    ids.resize(offsets[nt]);
    std::vector<index_t> fill(offsets.begin(), offsets.end() - 1);
    cell_face.assign(first_face.back(), -1);
    for (index_t ci = 0; ci < cands.size(); ++ci) {
      const Candidate& c = cands[ci];
      for (int i = 0; i < c.nb_tets; ++i) {
        const index_t t = c.tets[i];
        ids[fill[t]++] = ci;
        const index_t* q = mesh.tet(t);
        for (int f = 0; f < 4; ++f) {
          const index_t n = topo.neighbor(t, f);
          if (n != NO_CELL && std::find(c.tets.begin(), c.tets.begin() + c.nb_tets, n) !=
                                  c.tets.begin() + c.nb_tets) {
            continue;  // internal face of the candidate
          }
          const std::array<index_t, 3> tri{q[kTet.face[f][0]], q[kTet.face[f][1]],
                                           q[kTet.face[f][2]]};
          const int cf = cell_face_of(c, tri);
          HEXMERGE_ASSERT(cf >= 0, "a candidate's boundary triangle is not on its cell");
          cell_face[first_face[ci] + 4 * i + f] = static_cast<signed char>(cf);
        }
      }
    }
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

  std::vector<index_t> offsets, ids;    // tet -> candidates (CSR)
  std::vector<std::size_t> first_face;  // candidate -> first entry of cell_face
  std::vector<signed char> cell_face;   // per candidate, tet i, face f: its cell face, or -1
  std::vector<char> is_boundary;
};

class Selector {
 public:
  Selector(const TetMesh& mesh, const TetTopology& topology,
           const std::vector<Candidate>& candidates, const CandidateIndex& index,
           const RecombineParameters& parameters, bool strict)
      : mesh_(mesh),
        topo_(topology),
        cands_(candidates),
        params_(parameters),
        strict_(strict),
        owner_(mesh.nb_tets(), NO_INDEX),
        chosen_(candidates.size(), 0),
        offsets_(index.offsets),
        ids_(index.ids),
        index_(index),
        is_boundary_(index.is_boundary) {}

  Selection run(const ProgressCallback& progress) {
    std::vector<Stage> conforming, relaxed;
    const bool allow = params_.conformity == Conformity::Allow;
    for (CellType type : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
      conforming.push_back({type, allow});
      if (params_.conformity == Conformity::LastResort) relaxed.push_back({type, true});
    }
    report_progress(progress, "selection", 0.0);
    if (params_.conformity == Conformity::Conforming) select_block();
    for (const Stage& stage : conforming) {
      if (params_.boundary_order == BoundaryOrder::Quality) {
        boundary_stage_by_quality(stage);
      } else {
        boundary_stage(stage);
      }
    }
    report_progress(progress, "selection", 0.25);
    if (params_.local_optimisation) local_optimisation();
    report_progress(progress, "selection", 0.5);
    const std::vector<index_t> order = breadth_first_order();
    for (const Stage& stage : conforming) interior_stage(stage, order);
    for (const Stage& stage : relaxed) interior_stage(stage, order);
    report_progress(progress, "selection", 0.75);
    close_quads();
    if (params_.local_search) local_search();
    if (params_.conformity != Conformity::Conforming) release_cracks();
    report_progress(progress, "selection", 1.0);
    for (index_t ci = 0; ci < cands_.size(); ++ci) {
      if (chosen_[ci]) result_.elements.push_back(ci);
    }
    result_.nonconforming_quads = 0;
    for (index_t ci : result_.elements) {
      result_.nonconforming_quads += violations(ci, false, false);
    }
    return result_;
  }

 private:
  bool is_free(index_t t) const { return owner_[t] == NO_INDEX; }

  bool available(index_t ci) const {
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) {
      if (!is_free(c.tets[i])) return false;
    }
    return true;
  }

  bool contains(const Candidate& c, index_t t) const {
    return std::find(c.tets.begin(), c.tets.begin() + c.nb_tets, t) != c.tets.begin() + c.nb_tets;
  }

  Sides sides(index_t ci) const {
    const Candidate& c = cands_[ci];
    Sides s;
    for (int i = 0; i < c.nb_tets; ++i) {
      for (int f = 0; f < 4; ++f) {
        const int cf = index_.cell_face[index_.first_face[ci] + 4 * i + f];
        if (cf < 0) continue;
        const index_t n = topo_.neighbor(c.tets[i], f);
        s.side[s.count++] = {n, n == NO_CELL ? -1 : topo_.neighbor_face(c.tets[i], f), cf};
      }
    }
    return s;
  }

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
    const Candidate& e = cands_[ei];
    const int i =
        static_cast<int>(std::find(e.tets.begin(), e.tets.begin() + e.nb_tets, t) - e.tets.begin());
    return index_.cell_face[index_.first_face[ei] + 4 * i + f];
  }

  // Quad faces of chosen elements that touch free tet t through one of its faces: their keys
  // must all be quad faces of whatever element takes t.
  void required_quads(index_t t, QuadKeys& keys) const {
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo_.neighbor(t, f);
      if (n == NO_CELL || is_free(n)) continue;
      const Candidate& e = cands_[owner_[n]];
      const int ef = cell_face_at(owner_[n], n, topo_.neighbor_face(t, f));
      if (ef >= 0 && is_quad(e, ef)) keys.add(face_key(e, ef));
    }
  }

  bool has_quad(const Candidate& x, const QuadKey& key) const {
    const CellDescriptor& d = descriptor(x.type);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] == 4 && face_key(x, f) == key) return true;
    }
    return false;
  }

  // The best available candidate that takes free tets n1 and n2, avoids the tets of `exclude`
  // (may be null) and has every quad face the chosen elements and `extra` ask of n1 and n2 —
  // the element that would close a pending quad face. NO_INDEX when there is none.
  index_t closer(index_t n1, index_t n2, const QuadKey* extra, const Candidate* exclude) const {
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
        for (int i = 0; i < x.nb_tets && !overlap; ++i) overlap = contains(*exclude, x.tets[i]);
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
  index_t closing_pyramid(index_t n1, index_t n2, const QuadKey* key) const {
    QuadKeys keys;
    if (key) keys.add(*key);
    required_quads(n1, keys);
    required_quads(n2, keys);
    return keys.count == 1 ? pyramid_on(n1, n2, keys.key[0]) : NO_INDEX;
  }

  // An available pyramid of tets n1 and n2 with base `key`, or NO_INDEX.
  index_t pyramid_on(index_t n1, index_t n2, const QuadKey& key) const {
    for (index_t k = offsets_[n1]; k < offsets_[n1 + 1]; ++k) {
      const index_t xi = ids_[k];
      const Candidate& x = cands_[xi];
      if (x.type == CellType::Pyramid && contains(x, n2) && available(xi) &&
          face_key(x, 0) == key) {
        return xi;
      }
    }
    return NO_INDEX;
  }

  // Quad faces of candidate ci that would not conform if it were (or, when it is, as it is)
  // chosen now. A quad facing two free tets conforms while some available candidate can close
  // it; with `pending_ok` false (the final count) it does not.
  std::size_t violations(index_t ci, bool pending_ok = true, bool count_triangles = true) const {
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
        if (n != NO_CELL && !is_free(n)) {
          const Candidate& e = cands_[owner_[n]];
          if (is_quad(e, cell_face_at(owner_[n], n, half[0]->neighbor_face))) ++bad;
        }
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
        const Candidate& e = cands_[owner_[n1]];
        const int ef = cell_face_at(owner_[n1], n1, half[0]->neighbor_face);
        if (!is_quad(e, ef) || face_key(e, ef) != face_key(c, f)) ++bad;
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
  std::size_t risky_quads(index_t ci) const {
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

  // Ranking at one tet: element type, then fewer non-conformities (in conforming mode: fewer
  // pending quads without a safe closing pyramid), then quality.
  static bool better(const Candidate& a, std::size_t va, const Candidate& b, std::size_t vb) {
    if (a.type != b.type) return static_cast<int>(a.type) > static_cast<int>(b.type);
    if (va != vb) return va < vb;
    return a.quality > b.quality;
  }

  // The best available candidate of `stage` that takes tet t, or NO_INDEX.
  index_t best_at(index_t t, const Stage& stage) const {
    index_t best = NO_INDEX;
    std::size_t best_v = 0;
    for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
      const index_t ci = ids_[k];
      const Candidate& c = cands_[ci];
      if (c.type != stage.type || !available(ci)) continue;
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

  void set_owner(index_t t, index_t ci) {
    if (journaling_) journal_.push_back({t, owner_[t]});
    owner_[t] = ci;
  }

  void choose(index_t ci) {
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) set_owner(c.tets[i], ci);
    if (journaling_) chosen_journal_.push_back({ci, chosen_[ci]});
    chosen_[ci] = 1;
  }

  void release(index_t ci) {
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) set_owner(c.tets[i], NO_INDEX);
    if (journaling_) chosen_journal_.push_back({ci, chosen_[ci]});
    chosen_[ci] = 0;
  }

  void begin_move() {
    journaling_ = true;
    journal_.clear();
    chosen_journal_.clear();
  }

  void rollback() {
    for (auto it = journal_.rbegin(); it != journal_.rend(); ++it) owner_[it->first] = it->second;
    for (auto it = chosen_journal_.rbegin(); it != chosen_journal_.rend(); ++it) {
      chosen_[it->first] = it->second;
    }
    journaling_ = false;
  }

  void commit() { journaling_ = false; }

  // Whether every quad face of c is planar (to round-off): the hexahedra and prisms of swept
  // meshes (a cross-section repeated from plane to plane) and of lattices.
  bool planar_quads(const Candidate& c) const {
    const CellDescriptor& d = descriptor(c.type);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      Vec3 p[4];
      for (int i = 0; i < 4; ++i) p[i] = Vec3::of(mesh_.point(c.vertices[d.face[f][i]]));
      const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
      const double scale = (p[1] - p[0]).norm() * (p[2] - p[0]).norm() * (p[3] - p[0]).norm();
      if (std::abs(n.dot(p[3] - p[0])) > 1e-9 * scale) return false;
    }
    return true;
  }

  // The block, before anything else: the near-perfect hexahedra (structured regions, as a
  // lattice core) and the hexahedra and prisms with planar quads (swept regions) that can all be
  // kept together. Disjoint ones are taken, hexahedra first, by decreasing quality, ties by
  // their centroids along a fixed direction: on a swept mesh the copies of one element on every
  // plane then come in the same order against their rivals (two pairings of the same triangles),
  // and every plane pairs its triangles alike (by candidate index, symmetric cross-sections
  // paired differently from plane to plane and the block unravelled: 97 -> 40 % hex volume).
  // Then, until nothing changes, a member leaves the block when one of its quad faces is not on
  // the domain boundary, not shared with a member, and not closable by a pyramid of the two tets
  // behind it that no other block quad touches (of two members whose quads touch the same tet,
  // or whose quad meets the other's triangles, the one with fewer faces shared with the block
  // leaves, then the lesser; by quality alone, all 1 in a lattice, the hole that one missing
  // closer leaves grew through the core: bracket h 1.38, 97 -> 33 % hex volume). What stays is
  // chosen at once, a transaction that the greedy stages (one element at a time, and a block
  // lost to one missing closer) cannot break up. Its open quads are left to them: each has a
  // closing pyramid that no other quad needs, so both strategies keep it closable; a prism
  // sharing it may close it instead.
  void select_block() {
    std::vector<double> along(cands_.size(), 0.0);  // centroid . direction, for the members
    const Vec3 direction = Vec3{1.0, std::sqrt(2.0), std::sqrt(3.0)} * 0.5;
    auto rank = [&](std::vector<index_t>& list) {
      for (index_t ci : list) {
        const Candidate& c = cands_[ci];
        const int n = descriptor(c.type).nb_vertices;
        for (int i = 0; i < n; ++i)
          along[ci] += Vec3::of(mesh_.point(c.vertices[i])).dot(direction);
        along[ci] /= n;
      }
      std::sort(list.begin(), list.end(), [&](index_t a, index_t b) {
        if (cands_[a].type != cands_[b].type) return cands_[a].type == CellType::Hex;
        if (cands_[a].quality != cands_[b].quality) return cands_[a].quality > cands_[b].quality;
        if (along[a] != along[b]) return along[a] < along[b];
        return a < b;
      });
    };
    std::vector<index_t> block_of(mesh_.nb_tets(), NO_INDEX);
    std::vector<char> in_block(cands_.size(), 0);
    auto unclaimed = [&](const Candidate& c) {
      for (int i = 0; i < c.nb_tets; ++i) {
        if (block_of[c.tets[i]] != NO_INDEX) return false;
      }
      return true;
    };
    auto take_disjoint = [&](const std::vector<index_t>& list) {
      for (index_t ci : list) {
        const Candidate& c = cands_[ci];
        if (!unclaimed(c)) continue;
        for (int i = 0; i < c.nb_tets; ++i) block_of[c.tets[i]] = ci;
        in_block[ci] = 1;
      }
    };
    // The near-perfect hexahedra, then the planar-quad ones on the tets they leave (all ranked
    // below them: by type, then quality), so that only those are tested for planarity.
    std::vector<index_t> order, planar;
    for (index_t ci = 0; ci < cands_.size(); ++ci) {
      const Candidate& c = cands_[ci];
      if (c.type == CellType::Hex && c.quality >= kBlockQuality) order.push_back(ci);
    }
    rank(order);
    take_disjoint(order);
    for (index_t ci = 0; ci < cands_.size(); ++ci) {
      const Candidate& c = cands_[ci];
      if ((c.type == CellType::Prism || (c.type == CellType::Hex && c.quality < kBlockQuality)) &&
          unclaimed(c) && planar_quads(c))
        planar.push_back(ci);
    }
    rank(planar);
    take_disjoint(planar);
    order.insert(order.end(), planar.begin(), planar.end());
    // The block hexahedron other than `except` whose quad face meets tet t (not in the block),
    // or NO_INDEX.
    auto other_quad_at = [&](index_t t, index_t except) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(t, f);
        if (n == NO_CELL || block_of[n] == NO_INDEX || block_of[n] == except) continue;
        const index_t e = block_of[n];
        if (is_quad(cands_[e], cell_face_at(e, n, topo_.neighbor_face(t, f)))) return e;
      }
      return NO_INDEX;
    };
    // Faces of block hexahedron h shared with another block hexahedron.
    auto block_faces = [&](index_t h) {
      const Candidate& c = cands_[h];
      const Sides s = sides(h);
      int shared = 0;
      for (int f = 0; f < descriptor(c.type).nb_faces; ++f) {
        const auto n = tets_behind(s, f);
        if (n[0] == NO_CELL || n[1] == NO_CELL) continue;
        const index_t b = block_of[n[0]];
        if (b != NO_INDEX && b == block_of[n[1]] && has_quad(cands_[b], face_key(c, f))) ++shared;
      }
      return shared;
    };
    auto lesser = [&](index_t a, index_t b) {
      const int fa = block_faces(a), fb = block_faces(b);
      if (fa != fb) return fa < fb;
      if (cands_[a].quality != cands_[b].quality) return cands_[a].quality < cands_[b].quality;
      return a > b;
    };
    // The hexahedron of the block that must leave because of h's faces, or NO_INDEX.
    auto leaving = [&](index_t h) {
      const Candidate& c = cands_[h];
      const Sides s = sides(h);
      for (int f = 0; f < descriptor(c.type).nb_faces; ++f) {
        if (!is_quad(c, f)) continue;  // a triangle meets whatever is across it conformingly
        const auto n = tets_behind(s, f);
        if (n[0] == NO_CELL && n[1] == NO_CELL) continue;
        if (n[0] == NO_CELL || n[1] == NO_CELL) return h;
        const QuadKey key = face_key(c, f);
        const index_t b0 = block_of[n[0]], b1 = block_of[n[1]];
        if (b0 != NO_INDEX || b1 != NO_INDEX) {
          if (b0 == b1 && has_quad(cands_[b0], key)) continue;
          // The quad meets another member's triangles or another quad: the lesser goes.
          const index_t e = b1 == NO_INDEX || (b0 != NO_INDEX && lesser(b0, b1)) ? b0 : b1;
          return lesser(h, e) ? h : e;
        }
        if (pyramid_on(n[0], n[1], key) == NO_INDEX) return h;
        for (index_t t : n) {
          const index_t e = other_quad_at(t, h);
          if (e != NO_INDEX) return lesser(h, e) ? h : e;
        }
      }
      return NO_INDEX;
    };
    WorkQueue work(cands_.size());
    auto enqueue = [&](index_t h) {
      if (h != NO_INDEX && in_block[h]) work.push(h);
    };
    for (index_t ci : order) enqueue(ci);
    while (!work.empty()) {
      const index_t h = work.pop();
      if (!in_block[h]) continue;
      const index_t gone = leaving(h);
      if (gone == NO_INDEX) continue;
      in_block[gone] = 0;
      const Candidate& c = cands_[gone];
      for (int i = 0; i < c.nb_tets; ++i) block_of[c.tets[i]] = NO_INDEX;
      // Who may have counted on it: block hexahedra next to its tets, and those whose quads
      // meet the tets next to them (a conflict may be gone).
      for (int i = 0; i < c.nb_tets; ++i) {
        for (int f = 0; f < 4; ++f) {
          const index_t n = topo_.neighbor(c.tets[i], f);
          if (n == NO_CELL) continue;
          enqueue(block_of[n]);
          if (block_of[n] == NO_INDEX) enqueue(other_quad_at(n, NO_INDEX));
        }
      }
      enqueue(h);
    }
    for (index_t ci : order) {
      if (!in_block[ci]) continue;
      choose(ci);
      if (cands_[ci].type == CellType::Hex) ++result_.block_hexahedra;
    }
  }

  // Exhaustive-greedy over the boundary tets, best candidate first: every candidate of this
  // stage's type that holds a boundary tet, by decreasing scaled Jacobian.
  void boundary_stage_by_quality(const Stage& stage) {
    std::vector<index_t> order;
    for (index_t ci = 0; ci < cands_.size(); ++ci) {
      const Candidate& c = cands_[ci];
      if (c.type != stage.type) continue;
      bool on_boundary = false;
      for (int i = 0; i < c.nb_tets; ++i) on_boundary = on_boundary || is_boundary_[c.tets[i]];
      if (on_boundary) order.push_back(ci);
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](index_t a, index_t b) { return cands_[a].quality > cands_[b].quality; });
    for (index_t ci : order) {
      if (!available(ci)) continue;
      if (!stage.allow_nonconforming && violations(ci) > 0) continue;
      choose(ci);
    }
  }

  // Exhaustive-greedy over the boundary tets (the paper's order): the tet with the fewest available
  // candidates of this stage's type goes first (bucket queue; counts only decrease).
  void boundary_stage(const Stage& stage) {
    const index_t nt = mesh_.nb_tets();
    std::vector<index_t> count(nt, 0);
    std::vector<char> counted(cands_.size(), 0);
    std::vector<std::vector<index_t>> buckets(1);
    for (index_t t = 0; t < nt; ++t) {
      if (!is_boundary_[t] || !is_free(t)) continue;
      for (index_t k = offsets_[t]; k < offsets_[t + 1]; ++k) {
        const index_t ci = ids_[k];
        if (cands_[ci].type == stage.type && available(ci)) ++count[t];
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
        const index_t s = c.tets[i];
        for (index_t k = offsets_[s]; k < offsets_[s + 1]; ++k) {
          const index_t xi = ids_[k];
          const Candidate& x = cands_[xi];
          if (xi == ci || x.type != stage.type || counted[xi]) continue;
          counted[xi] = 1;
          for (int j = 0; j < x.nb_tets; ++j) {
            const index_t u = x.tets[j];
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

  // Section 4.2: at each unmatched boundary tet, try each of its candidates in place of the
  // elements in its way; refill the freed tets greedily; keep the move only when it saves
  // elements and leaves every quad face as conforming as before.
  void local_optimisation() {
    const index_t nt = mesh_.nb_tets();
    for (index_t t = 0; t < nt; ++t) {
      if (!is_boundary_[t] || !is_free(t)) continue;
      for (index_t k = offsets_[t]; k < offsets_[t + 1] && is_free(t); ++k) {
        const index_t ci = ids_[k];
        if (cands_[ci].type == CellType::Pyramid) continue;
        try_move(ci);
      }
    }
  }

  void try_move(index_t ci) {
    const Candidate& c = cands_[ci];
    std::vector<index_t> in_way;
    for (int i = 0; i < c.nb_tets; ++i) {
      const index_t o = owner_[c.tets[i]];
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
        if (is_free(e.tets[i])) freed.push_back(e.tets[i]);
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
  bool neighbourhood_conforms(index_t ci, const std::vector<index_t>& freed) const {
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

  // Where quads may meet triangles (allow, last_resort), chosen elements can still leave a
  // crack: (1) a quad face half on the domain boundary, half inside (nothing can cover it);
  // (2) two elements capping one free tet from its two sides, each with a quad face on two of
  // the tet's faces: two quads on the same four corners with the other diagonal, the tet
  // sandwiched between; (3) an element capping a free tet whose other two faces are on the
  // domain boundary (the quad has the boundary's corners). Releases the element in (1) and (3),
  // and in (2) the one that saves fewer tets (the later one on ties): a release only leaves tets,
  // so no new crack appears.
  void release_cracks() {
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
        const int ef = cell_face_at(owner_[n], n, topo_.neighbor_face(t, f));
        if (ef >= 0 && is_quad(cands_[owner_[n]], ef)) quad_of[f] = {owner_[n], ef};
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
  std::vector<index_t> breadth_first_order() const {
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

  void interior_stage(const Stage& stage, const std::vector<index_t>& order) {
    for (index_t t : order) {
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
  void close_quads() {
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
          const index_t n = topo_.neighbor(c.tets[i], f);
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
  void close_pending(index_t ci, Touch* touch) {
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

  // The cell faces of candidates x and y meeting across face f of x's tet t (y's tet n beyond):
  // they conform when both are triangles, or both the same quad.
  bool faces_match(index_t x, int xf, index_t y, index_t n, int nf) const {
    const int yf = cell_face_at(y, n, nf);
    const bool xq = is_quad(cands_[x], xf), yq = is_quad(cands_[y], yf);
    if (xq != yq) return false;
    return !xq || face_key(cands_[x], xf) == face_key(cands_[y], yf);
  }

  // Whether candidate ci (inside the neighbourhood) conforms with everything outside it, which
  // the move does not change: elements (matching faces), free tets (no quad face against them)
  // and the domain boundary (a quad wholly on it, or not at all).
  bool fits_outside(index_t ci) const {
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
        const int cf = index_.cell_face[index_.first_face[ci] + 4 * i + f];
        if (cf < 0) continue;
        const index_t n = topo_.neighbor(c.tets[i], f);
        if (n == NO_CELL || local_[n] >= 0) continue;
        if (is_free(n)) {
          if (is_quad(c, cf)) return false;
        } else if (!faces_match(ci, cf, owner_[n], n, topo_.neighbor_face(c.tets[i], f))) {
          return false;
        }
      }
    }
    return true;
  }

  // Whether candidate ci conforms with what the search has decided inside the neighbourhood.
  bool fits_inside(const Hood& h, index_t ci) const {
    const Candidate& c = cands_[ci];
    for (int i = 0; i < c.nb_tets; ++i) {
      for (int f = 0; f < 4; ++f) {
        const int cf = index_.cell_face[index_.first_face[ci] + 4 * i + f];
        if (cf < 0) continue;
        const index_t n = topo_.neighbor(c.tets[i], f);
        if (n == NO_CELL || local_[n] < 0) continue;
        const int st = h.state[local_[n]];
        if (st == UNDECIDED) continue;
        if (st == LEFT_FREE) {
          if (is_quad(c, cf)) return false;
        } else if (!faces_match(ci, cf, owner_[n], n, topo_.neighbor_face(c.tets[i], f))) {
          return false;
        }
      }
    }
    return true;
  }

  // Whether tet t may stay a tet given what the search has decided: no quad face against it.
  bool may_stay_free(const Hood& h, index_t t) const {
    for (int f = 0; f < 4; ++f) {
      const index_t n = topo_.neighbor(t, f);
      if (n == NO_CELL || local_[n] < 0 || h.state[local_[n]] < 0) continue;
      const index_t y = owner_[n];
      if (is_quad(cands_[y], cell_face_at(y, n, topo_.neighbor_face(t, f)))) return false;
    }
    return true;
  }

  // Release `released`, and re-select the tets of `tets` (which holds every tet of the released
  // elements) exactly. Keeps the result when it saves more elements; returns whether it did.
  bool reselect(Hood& h) {
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
        for (int i = 0; i < c.nb_tets && inside; ++i) inside = local_[c.tets[i]] >= 0;
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
        const int l = local_[c.tets[i]];
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
        for (int i = 0; i < c.nb_tets; ++i) h.at[fill[local_[c.tets[i]]]++] = static_cast<int>(p);
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
          const index_t o = owner_[n];
          if (is_quad(cands_[o], cell_face_at(o, n, topo_.neighbor_face(t, f))))
            h.must_cover[l] = 1;
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

  // Savings per tet in units of 1 / 720720 (the least common multiple of 2..16), so that the
  // bound is exact in integers: a tet in an element of n tets saves (n - 1) / n.
  static constexpr long long UNIT = 720720;
  static long long share_units(int n) { return (n - 1) * UNIT / n; }

  static long long share_of(const Hood& h, int l) {
    const std::uint32_t m = h.sizes[l];
    return m == 0 ? 0 : share_units(31 - __builtin_clz(m));
  }

  // Marks the local tets `ls` decided (their state already set) and closes the pool entries
  // that take them; returns by how much the bound on the undecided tets drops (the decided tets'
  // own shares, `before`, included).
  long long close_entries(Hood& h, const int* ls, int k, long long before) {
    long long drop = before;
    for (int a = 0; a < k; ++a) {
      for (int q = h.at_offsets[ls[a]]; q < h.at_offsets[ls[a] + 1]; ++q) {
        const int p = h.at[q];
        if (h.closed[p]++ != 0) continue;
        const Candidate& c = cands_[h.pool[p]];
        for (int i = 0; i < c.nb_tets; ++i) {
          const int u = local_[c.tets[i]];
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

  void reopen_entries(Hood& h, const int* ls, int k) {
    for (int a = k - 1; a >= 0; --a) {
      for (int q = h.at_offsets[ls[a] + 1] - 1; q >= h.at_offsets[ls[a]]; --q) {
        const int p = h.at[q];
        if (--h.closed[p] != 0) continue;
        const Candidate& c = cands_[h.pool[p]];
        for (int i = 0; i < c.nb_tets; ++i) {
          const int u = local_[c.tets[i]];
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
  void branch(Hood& h, std::size_t pos, int saved, long long rest) {
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
        ls[i] = local_[c.tets[i]];
        before += share_of(h, ls[i]);
      }
      for (int i = 0; i < c.nb_tets; ++i) {
        h.state[ls[i]] = p;
        owner_[c.tets[i]] = ci;
      }
      const long long drop = close_entries(h, ls, c.nb_tets, before);
      h.current.push_back(p);
      branch(h, pos + 1, saved + gain(c), rest - drop);
      h.current.pop_back();
      reopen_entries(h, ls, c.nb_tets);
      for (int i = 0; i < c.nb_tets; ++i) {
        h.state[ls[i]] = UNDECIDED;
        owner_[c.tets[i]] = NO_INDEX;
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
  void hood_add(Hood& h, index_t t) {
    if (local_[t] != -1) return;
    local_[t] = -2;  // marked while the neighbourhood is gathered
    h.tets.push_back(t);
  }

  void hood_add_element(Hood& h, index_t e) {
    if (std::find(h.released.begin(), h.released.end(), e) != h.released.end()) return;
    h.released.push_back(e);
    const Candidate& c = cands_[e];
    for (int i = 0; i < c.nb_tets; ++i) hood_add(h, c.tets[i]);
  }

  void hood_clear_marks(Hood& h) {
    for (index_t t : h.tets) local_[t] = -1;
  }

  // Swap: element e and the free tets next to it.
  bool try_swap(Hood& h, index_t e) {
    h.tets.clear();
    h.released.clear();
    hood_add_element(h, e);
    const Candidate& c = cands_[e];
    bool any_free = false;
    for (int i = 0; i < c.nb_tets; ++i) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(c.tets[i], f);
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
          for (int i = 0; i < x.nb_tets && inside; ++i) inside = local_[x.tets[i]] >= 0;
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
  bool try_reselection(Hood& h, index_t s) {
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

  void local_search() {
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

  const TetMesh& mesh_;
  const TetTopology& topo_;
  const std::vector<Candidate>& cands_;
  const RecombineParameters& params_;
  const bool strict_;  // pending quads only where a safe closing pyramid waits (closing_pyramid)
  std::vector<index_t> owner_;           // per tet: the chosen candidate that holds it, or NO_INDEX
  std::vector<char> chosen_;             // per candidate
  const std::vector<index_t>& offsets_;  // tet -> candidates
  const std::vector<index_t>& ids_;
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

}  // namespace

Selection select_candidates(const TetMesh& mesh, const TetTopology& topology,
                            const std::vector<Candidate>& candidates,
                            const RecombineParameters& parameters,
                            const ProgressCallback& progress) {
  // Conforming mode with pyramids: "safe pyramids" (a pending quad face only where a closing
  // pyramid is reserved for it; never releases). Without pyramids, and in the other modes:
  // "closable" (a pending quad needs only some candidate that could close it; in conforming mode
  // the elements that end up unclosed are released). Until issue 18 both ran in conforming mode
  // and the better was kept: "closable" never won on a benchmark mesh (docs/benchmarks.md).
  const CandidateIndex index(mesh, topology, candidates, parameters.respect_regions);
  const bool conforming = parameters.conformity == Conformity::Conforming;
  const bool safe_pyramids = conforming && parameters.make_pyramids;
  Selection selection =
      Selector(mesh, topology, candidates, index, parameters, safe_pyramids).run(progress);
  selection.strategy = safe_pyramids ? "safe_pyramids" : conforming ? "closable" : "";
  return selection;
}

}  // namespace hexmerge
