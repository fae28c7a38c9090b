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

// A face pair that passed the normal filter, as the walk from the face's tet meets it. Each pair
// is tested once, from the face with the smaller code: its entry holds both answers, and the
// other face's entry (kPending) takes its answer from there (QuadPairs' constructor).
// A face around an edge: (tet, local face). (std::pair would zero the walk's arrays, 3 KB per tet.)
struct RingFace {
  index_t tet;
  int face;
};

struct Entry {
  index_t face;     // 4 * t + f
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

  void faces_of_tet(index_t t, std::vector<Entry>& out) const {
    // The faces around each of t's edges q[i]-q[j] (i < j), walked once per edge. t's two faces
    // holding the edge are those opposite its other two vertices.
    struct Ring {
      int others[2];
      int n;
      std::array<RingFace, 64> faces;  // not initialised: the first n are written
    };
    std::array<Ring, 6> rings;
    const index_t* q = mesh_.tet(t);
    for (int i = 0, e = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j, ++e) {
        Ring& r = rings[e];
        int k = 0;
        for (int l = 0; l < 4; ++l) {
          if (l != i && l != j) r.others[k++] = l;
        }
        r.n = tets_around_edge(t, q[i], q[j], r.others, r.faces);
      }
    }
    // Grouped by face for the CSR; per face, in edge order then walk order.
    for (int f = 0; f < 4; ++f) {
      const float* nt = &normals_[12 * std::size_t(t) + 3 * f];
      for (const Ring& r : rings) {
        if (r.others[0] != f && r.others[1] != f) continue;
        for (int a = 0; a < r.n; ++a) {
          const auto [s, g] = r.faces[a];
          const float* ns = &normals_[12 * std::size_t(s) + 3 * g];
          if (nt[0] * ns[0] + nt[1] * ns[1] + nt[2] * ns[2] < min_cos_) continue;
          // (The filter is symmetric: the partner's walk meets this pair too.)
          const index_t face = 4 * t + f, partner = 4 * s + g;
          out.push_back({face, partner, face < partner ? accept_both(t, f, s, g) : kPending});
        }
      }
    }
  }

 private:
  // Faces (tet, local face) holding edge x-y of the tets around it other than t: walk from t
  // across each of its two faces on the edge until the walk returns or leaves the domain.
  int tets_around_edge(index_t t, index_t x, index_t y, const int others[2],
                       std::array<RingFace, 64>& out) const {
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
      if (cur == t) break;  // closed ring: every tet seen from one side
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
  std::vector<std::vector<Entry>> per_chunk((nt + kChunk - 1) / kChunk);
  parallel_chunks(nt, kChunk, threads, [&](index_t chunk, index_t begin, index_t end) {
    for (index_t t = begin; t < end; ++t) builder.faces_of_tet(t, per_chunk[chunk]);
  });
  // Entries come out grouped by tet face, in increasing order: start[c] is the place of face c's
  // first entry in the chunks taken one after the other (chunk k's begin at base[k]). The
  // chunks' lists are not concatenated: each is freed once its partners are placed.
  std::vector<std::size_t> base(per_chunk.size() + 1, 0);
  for (std::size_t k = 0; k < per_chunk.size(); ++k) base[k + 1] = base[k] + per_chunk[k].size();
  std::vector<std::size_t> start(4 * static_cast<std::size_t>(nt) + 1, 0);
  for (const auto& chunk : per_chunk)
    for (const Entry& e : chunk) ++start[e.face + 1];
  for (std::size_t i = 0; i + 1 < start.size(); ++i) start[i + 1] += start[i];
  // The entries of face c: [first, last) in its chunk's list.
  auto entries_of = [&](index_t c) {
    const std::size_t k = c / 4 / kChunk;
    const Entry* data = per_chunk[k].data();
    return std::make_pair(data + (start[c] - base[k]), data + (start[c + 1] - base[k]));
  };
  // A pending entry (face > partner) takes kReverse of the partner's entry for this face. The
  // partner's walk meets the pair unless its ring was cut at its 32 tets: then the pair is
  // tested here, from this side, as it always was.
  parallel_chunks(nt, kChunk, threads, [&](index_t chunk, index_t, index_t) {
    for (Entry& e : per_chunk[chunk]) {
      if (e.state != kPending) continue;
      const auto [first, last] = entries_of(e.partner);
      const Entry* r =
          std::find_if(first, last, [&](const Entry& o) { return o.partner == e.face; });
      e.state = r != last ? (r->state & kReverse ? kForward : 0)
                          : (builder.accept(e.face / 4, static_cast<int>(e.face % 4), e.partner / 4,
                                            static_cast<int>(e.partner % 4))
                                 ? kForward
                                 : 0);
    }
  });
  std::vector<std::size_t>().swap(start);

  offsets_.assign(4 * static_cast<std::size_t>(nt) + 1, 0);
  masks_.assign(nt, 0);
  partner_bits_.assign(nt, 0);
  std::size_t accepted = 0;
  for (const auto& chunk : per_chunk)
    for (const Entry& e : chunk) accepted += (e.state & kForward) != 0;
  partners_.reserve(accepted);
  for (auto& chunk : per_chunk) {
    for (const Entry& e : chunk) {
      if (!(e.state & kForward)) continue;
      ++offsets_[e.face + 1];
      masks_[e.face / 4] |= static_cast<unsigned char>(1u << (e.face % 4));
      partner_bits_[e.face / 4] |= std::uint64_t{1} << (e.partner / 4 & 63u);
      partners_.push_back({e.partner});
    }
    std::vector<Entry>().swap(chunk);
  }
  for (std::size_t i = 0; i + 1 < offsets_.size(); ++i) offsets_[i + 1] += offsets_[i];
}

}  // namespace hexmerge
