#include "hexmerge/recombine/quad_pairs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "hexmerge/core/parallel.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

std::array<index_t, 3> tet_face(const TetMesh& mesh, index_t t, int f) {
  const CellDescriptor& tet = descriptor(CellType::Tet);
  const index_t* q = mesh.tet(t);
  return {q[tet.face[f][0]], q[tet.face[f][1]], q[tet.face[f][2]]};
}

bool quad_from_triangles(const std::array<index_t, 3>& t1, const std::array<index_t, 3>& t2,
                         std::array<index_t, 4>& quad) {
  for (int i = 0; i < 3; ++i) {
    const index_t x = t1[i], y = t1[(i + 1) % 3], z = t1[(i + 2) % 3];
    for (int j = 0; j < 3; ++j) {
      // t2 must run along the shared edge in the opposite direction: (y, x, w).
      if (t2[j] == y && t2[(j + 1) % 3] == x) {
        const index_t w = t2[(j + 2) % 3];
        if (w == z) return false;
        quad = {x, w, y, z};
        return true;
      }
    }
  }
  return false;
}

namespace {

const CellDescriptor& kTet = descriptor(CellType::Tet);
constexpr double kDegToRad = 0.017453292519943295;

// A face around an edge: (tet, local face). (std::pair would zero the walk's arrays, 3 KB per tet.)
struct RingFace {
  index_t tet;
  int face;
};

// A face pair that passed the normal filter, as the walk from the face's tet meets it, in its
// face's run of entries (QuadPairs' constructor). Each pair is tested once, from the face with
// the smaller code: its entry holds both answers (kept only when one of them is yes), and the
// other face's entry (kPending) takes its answer from there.
struct Entry {
  index_t partner;  // 4 * s + g
  std::uint8_t state;
};
constexpr std::uint8_t kForward = 1;  // face -> partner accepted
constexpr std::uint8_t kReverse = 2;  // partner -> face accepted (the test made from face)
constexpr std::uint8_t kPending = 4;  // tested from the partner's entry

class Builder {
 public:
  Builder(const TetMesh& mesh, const TetTopology& topology, const std::vector<float>& normals,
          double min_dihedral, double min_boundary_dihedral, double max_corner,
          bool region_interfaces_are_boundary)
      : mesh_(mesh),
        topo_(topology),
        regions_(region_interfaces_are_boundary && !mesh.regions.empty()),
        normals_(normals),
        min_dihedral_(min_dihedral),
        min_boundary_dihedral_(min_boundary_dihedral),
        max_corner_(max_corner),
        // Two outward normals of a flat quad agree; a dihedral angle of at least dangle means
        // they are at most 180 - dangle apart.
        // (Single-precision normals: the filter lets through a little more, the exact test
        // in accept() decides.)
        min_cos_(std::cos((180.0 - std::min(min_dihedral, min_boundary_dihedral)) * kDegToRad) -
                 1e-5) {}

  /// Appends the entries of t's faces, face by face, to `out`; counts[f]: face f's number of
  /// entries. True when a walk around one of t's edges stopped at its 32 tets (its ring was cut).
  bool faces_of_tet(index_t t, std::vector<Entry>& out, index_t* counts) const {
    bool cut = false;
    // The faces around each of t's edges q[i]-q[j] (i < j), walked once per edge. t's two faces
    // holding the edge are those opposite its other two vertices.
    struct Ring {
      int others[2];
      int n;
      std::array<RingFace, 64> faces;  // not initialised: the first n are written
    };
    std::array<Ring, 6> rings;
    const index_t* q = mesh_.tet(t);
    // Edge e's two vertices, and the other two (the faces opposite them hold the edge).
    static constexpr int kEnds[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    static constexpr int kOthers[6][2] = {{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}};
    for (int e = 0; e < 6; ++e) {
      Ring& r = rings[e];
      r.others[0] = kOthers[e][0];
      r.others[1] = kOthers[e][1];
      r.n = tets_around_edge(t, q[kEnds[e][0]], q[kEnds[e][1]], r.others, r.faces, cut);
    }
    // Grouped by face for the CSR; per face, in edge order then walk order. Each ring is read
    // once for both of t's faces on its edge, their entries kept apart until the end.
    std::array<std::array<Entry, 3 * 64>, 4> entries;  // not initialised: the first n[f] are
    int n[4] = {0, 0, 0, 0};
    for (const Ring& r : rings) {
      const int f0 = r.others[0], f1 = r.others[1];
      const float* n0 = &normals_[12 * std::size_t(t) + 3 * f0];
      const float* n1 = &normals_[12 * std::size_t(t) + 3 * f1];
      for (int a = 0; a < r.n; ++a) {
        const auto [s, g] = r.faces[a];
        const float* ns = &normals_[12 * std::size_t(s) + 3 * g];
        const bool pass0 = !(n0[0] * ns[0] + n0[1] * ns[1] + n0[2] * ns[2] < min_cos_);
        const bool pass1 = !(n1[0] * ns[0] + n1[1] * ns[1] + n1[2] * ns[2] < min_cos_);
        if (!pass0 && !pass1) continue;
        // (The filter is symmetric: the partner's walk meets this pair too.)
        const index_t partner = 4 * s + g;
        if (pass0) add(t, f0, s, g, partner, entries[f0], n[f0]);
        if (pass1) add(t, f1, s, g, partner, entries[f1], n[f1]);
      }
    }
    for (int f = 0; f < 4; ++f) {
      out.insert(out.end(), entries[f].begin(), entries[f].begin() + n[f]);
      counts[f] = static_cast<index_t>(n[f]);
    }
    return cut;
  }

 private:
  // The entry of face f of tet t for face g of tet s (partner: its code), when it has one.
  void add(index_t t, int f, index_t s, int g, index_t partner, std::array<Entry, 3 * 64>& list,
           int& n) const {
    const index_t face = 4 * t + f;
    const std::uint8_t state = face < partner ? accept_both(t, f, s, g) : kPending;
    if (state != 0) list[n++] = {partner, state};
  }

  // Faces (tet, local face) holding edge x-y of the tets around it other than t: walk from t
  // across each of its two faces on the edge until the walk returns or leaves the domain.
  int tets_around_edge(index_t t, index_t x, index_t y, const int others[2],
                       std::array<RingFace, 64>& out, bool& cut) const {
    int n = 0;
    for (int dir = 0; dir < 2; ++dir) {
      index_t prev = t, cur = topo_.neighbor(t, others[dir]);
      while (cur != NO_CELL && cur != t && n + 2 <= static_cast<int>(out.size())) {
        const index_t* q = mesh_.tet(cur);
        // Its two local vertices off the edge (a bit mask, then its lowest and highest bit).
        unsigned off = 0;
        for (int l = 0; l < 4; ++l) off |= static_cast<unsigned>((q[l] != x) & (q[l] != y)) << l;
        static constexpr signed char kLow[16] = {-1, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0};
        static constexpr signed char kHigh[16] = {-1, 0, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3};
        const int o[2] = {kLow[off], kHigh[off]};
        out[n++] = {cur, o[0]};
        out[n++] = {cur, o[1]};
        const index_t next = topo_.neighbor(cur, o[0]) == prev ? topo_.neighbor(cur, o[1])
                                                               : topo_.neighbor(cur, o[0]);
        prev = cur;
        cur = next;
      }
      if (cur != NO_CELL && cur != t) cut = true;  // stopped at the array's end
      if (cur == t) break;                         // closed ring: every tet seen from one side
    }
    return n;
  }

 public:
  /// accept(t, f, s, g) alone: face f of tet t takes face g of tet s as partner.
  bool accept(index_t t, int f, index_t s, int g) const {
    return (accept_both(t, f, s, g) & kForward) != 0;
  }

  /// kForward when face f of tet t takes face g of tet s as partner, kReverse when s's face takes
  /// t's: the quad is the same, seen from either side (x, w, y, z) or (y, z, x, w), and so are
  /// its corner angles (the same edge vectors at each corner), which are tested once; the
  /// dihedral angle is measured across the diagonal from the first vertex of each, as each side
  /// alone would (its rounding differs).
  std::uint8_t accept_both(index_t t, int f, index_t s, int g) const {
    std::array<index_t, 4> q;
    if (!quad_from_triangles(tet_face(mesh_, t, f), tet_face(mesh_, s, g), q)) return 0;
    const double* a = mesh_.point(q[0]);
    const double* b = mesh_.point(q[1]);
    const double* c = mesh_.point(q[2]);
    const double* d = mesh_.point(q[3]);
    const bool on_boundary = is_boundary(t, f) && is_boundary(s, g);
    const AngleBound& dihedral = on_boundary ? min_boundary_dihedral_ : min_dihedral_;
    const std::uint8_t sides = (quad_dihedral_angle_below(a, b, c, d, dihedral) ? 0 : kForward) |
                               (quad_dihedral_angle_below(c, d, a, b, dihedral) ? 0 : kReverse);
    if (sides == 0 || quad_max_corner_angle_above(a, b, c, d, max_corner_)) return 0;
    return sides;
  }

 private:
  // Face f of tet t on the domain's boundary, or on a region interface when those count.
  bool is_boundary(index_t t, int f) const {
    if (topo_.on_boundary(t, f)) return true;
    return regions_ && mesh_.region(t) != mesh_.region(topo_.neighbor(t, f));
  }

  const TetMesh& mesh_;
  const TetTopology& topo_;
  bool regions_;
  const std::vector<float>& normals_;  // 4 outward unit normals per tet
  AngleBound min_dihedral_, min_boundary_dihedral_, max_corner_;
  double min_cos_;
};

std::vector<float> unit_normals(const TetMesh& mesh, int threads) {
  std::vector<float> normals(12 * static_cast<std::size_t>(mesh.nb_tets()));
  parallel_chunks(mesh.nb_tets(), 65536, threads, [&](index_t, index_t begin, index_t end) {
    for (index_t t = begin; t < end; ++t) {
      const index_t* q = mesh.tet(t);
      for (int f = 0; f < 4; ++f) {
        const Vec3 a = Vec3::of(mesh.point(q[kTet.face[f][0]]));
        const Vec3 n = (Vec3::of(mesh.point(q[kTet.face[f][1]])) - a)
                           .cross(Vec3::of(mesh.point(q[kTet.face[f][2]])) - a);
        const double len = n.norm();
        const Vec3 u = len > 0.0 ? n * (1.0 / len) : n;
        float* out = &normals[12 * std::size_t(t) + 3 * f];
        out[0] = static_cast<float>(u.x);
        out[1] = static_cast<float>(u.y);
        out[2] = static_cast<float>(u.z);
      }
    }
  });
  return normals;
}

}  // namespace

QuadPairs::QuadPairs(const TetMesh& mesh, const TetTopology& topology, double min_dihedral_angle,
                     double min_boundary_dihedral_angle, double max_face_angle, int threads,
                     bool region_interfaces_are_boundary) {
  const index_t nt = mesh.nb_tets();
  const std::vector<float> normals = unit_normals(mesh, threads);
  const Builder builder(mesh, topology, normals, min_dihedral_angle, min_boundary_dihedral_angle,
                        max_face_angle, region_interfaces_are_boundary);
  constexpr index_t kChunk = 4096;  // small enough for the threads to finish together
  // Each chunk's entries, face by face; first offsets_[c + 1] = the number of face c's entries,
  // then offsets_[c] = the place of its first in its chunk's list.
  std::vector<std::vector<Entry>> per_chunk((nt + kChunk - 1) / kChunk);
  offsets_.assign(4 * static_cast<std::size_t>(nt) + 1, 0);
  std::vector<char> cut(nt, 0);  // some ring of the tet cut at its 32 tets
  parallel_chunks(nt, kChunk, threads, [&](index_t chunk, index_t begin, index_t end) {
    for (index_t t = begin; t < end; ++t)
      cut[t] = builder.faces_of_tet(t, per_chunk[chunk], &offsets_[4 * std::size_t(t) + 1]);
  });
  for (std::size_t c = 0, n = 0; c < 4 * static_cast<std::size_t>(nt); ++c) {
    if (c % (4 * std::size_t(kChunk)) == 0) n = 0;  // a chunk's first face
    const index_t count = offsets_[c + 1];
    offsets_[c] = static_cast<index_t>(n);
    n += count;
  }
  // The entries of face c: [first, last) in its chunk's list.
  auto entries_of = [&](std::size_t c) {
    std::vector<Entry>& list = per_chunk[c / 4 / kChunk];
    const std::size_t end = (c + 1) % (4 * std::size_t(kChunk)) == 0 || c + 1 == 4 * std::size_t(nt)
                                ? list.size()
                                : offsets_[c + 1];
    return std::make_pair(list.data() + offsets_[c], list.data() + end);
  };
  // A pending entry (face > partner) takes kReverse of the partner's entry for this face; no
  // entry there: the pair was refused both ways. (The partner's walk meets the pair unless one
  // of its rings was cut at its 32 tets: then the pair is tested here, from this side, as it
  // always was.)
  parallel_chunks(nt, kChunk, threads, [&](index_t, index_t begin, index_t end) {
    for (std::size_t c = 4 * std::size_t(begin); c < 4 * std::size_t(end); ++c) {
      const auto [first, last] = entries_of(c);
      for (Entry* e = first; e != last; ++e) {
        if (e->state != kPending) continue;
        const auto [pf, pl] = entries_of(e->partner);
        const Entry* r = std::find_if(pf, pl, [&](const Entry& o) { return o.partner == c; });
        if (r != pl)
          e->state = r->state & kReverse ? kForward : 0;
        else if (cut[e->partner / 4])
          e->state = builder.accept(static_cast<index_t>(c / 4), static_cast<int>(c % 4),
                                    e->partner / 4, static_cast<int>(e->partner % 4))
                         ? kForward
                         : 0;
        else
          e->state = 0;
      }
    }
  });
  std::vector<char>().swap(cut);

  masks_.assign(nt, 0);
  partner_bits_.assign(nt, 0);
  std::size_t accepted = 0;
  for (const auto& chunk : per_chunk)
    for (const Entry& e : chunk) accepted += (e.state & kForward) != 0;
  partners_.reserve(accepted);
  // offsets_ becomes the CSR: face c's place is read before it is overwritten, face c + 1's
  // after.
  for (std::size_t c = 0; c < 4 * static_cast<std::size_t>(nt); ++c) {
    const auto [first, last] = entries_of(c);
    offsets_[c] = static_cast<index_t>(partners_.size());
    const index_t t = static_cast<index_t>(c / 4);
    for (const Entry* e = first; e != last; ++e) {
      if (!(e->state & kForward)) continue;
      masks_[t] |= static_cast<unsigned char>(1u << (c % 4));
      partner_bits_[t] |= std::uint64_t{1} << (e->partner / 4 & 63u);
      partners_.push_back({e->partner});
    }
    if ((c + 1) % (4 * std::size_t(kChunk)) == 0)
      std::vector<Entry>().swap(per_chunk[c / 4 / kChunk]);
  }
  offsets_[4 * static_cast<std::size_t>(nt)] = static_cast<index_t>(partners_.size());
}

}  // namespace hexmerge
