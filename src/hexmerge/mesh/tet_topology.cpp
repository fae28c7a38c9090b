#include "hexmerge/mesh/tet_topology.h"

#include <algorithm>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

TetTopology::TetTopology(const TetMesh& mesh) {
  const index_t nt = mesh.nb_tets();
  const index_t nv = mesh.nb_vertices();
  const CellDescriptor& tet = descriptor(CellType::Tet);
  neighbors_.assign(4 * static_cast<std::size_t>(nt), NO_CELL);
  neighbor_faces_.assign(4 * static_cast<std::size_t>(nt), -1);

  // Bucket every face by its smallest vertex (counting sort), then match faces inside a bucket
  // by their two other vertices. Buckets hold a few dozen faces, so this is linear overall.
  struct FaceKey {
    std::uint64_t rest;  // (middle vertex << 32) | largest vertex
    index_t tet_face;    // 4 * tet + local face
  };
  std::vector<index_t> bucket_start(static_cast<std::size_t>(nv) + 1, 0);
  auto sorted_face = [&](index_t t, int f, index_t out[3]) {
    const index_t* q = mesh.tet(t);
    const index_t a = q[tet.face[f][0]], b = q[tet.face[f][1]], c = q[tet.face[f][2]];
    // Branch-free: which vertex is smallest is a coin toss.
    const index_t lo = std::min(a, b), hi = std::max(a, b);
    out[0] = std::min(lo, c);
    out[2] = std::max(hi, c);
    out[1] = std::max(lo, std::min(hi, c));
  };
  // Whether a tet face's vertex cycle, started at its smallest vertex, runs to the smaller of
  // the two others: the two tets of an interior face must see it with opposite cycles.
  auto ascending = [&](index_t tet_face) {
    const index_t* q = mesh.tet(tet_face / 4);
    const index_t a = q[tet.face[tet_face % 4][0]], b = q[tet.face[tet_face % 4][1]],
                  c = q[tet.face[tet_face % 4][2]];
    if (a < b && a < c) return b < c;
    if (b < c) return c < a;
    return a < b;
  };
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      index_t s[3];
      sorted_face(t, f, s);
      ++bucket_start[s[0] + 1];
    }
  }
  for (index_t v = 0; v < nv; ++v) bucket_start[v + 1] += bucket_start[v];
  std::vector<FaceKey> faces(4 * static_cast<std::size_t>(nt));
  std::vector<index_t> fill(bucket_start.begin(), bucket_start.end() - 1);
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      index_t s[3];
      sorted_face(t, f, s);
      faces[fill[s[0]]++] = {(static_cast<std::uint64_t>(s[1]) << 32) | s[2], 4 * t + f};
    }
  }
  for (index_t v = 0; v < nv; ++v) {
    auto begin = faces.begin() + bucket_start[v];
    auto end = faces.begin() + bucket_start[v + 1];
    std::sort(begin, end, [](const FaceKey& a, const FaceKey& b) {
      return a.rest < b.rest || (a.rest == b.rest && a.tet_face < b.tet_face);
    });
    for (auto it = begin; it != end;) {
      auto next = it + 1;
      while (next != end && next->rest == it->rest) ++next;
      const auto count = next - it;
      if (count > 2) {
        const index_t t0 = it->tet_face / 4, t1 = (it + 1)->tet_face / 4,
                      t2 = (it + 2)->tet_face / 4;
        throw InputError("a face is shared by " + std::to_string(count) + " tetrahedra (" +
                             std::to_string(t0) + ", " + std::to_string(t1) + ", " +
                             std::to_string(t2) + (count > 3 ? ", ..." : "") +
                             "): the mesh is not a valid tetrahedralisation",
                         Entity::Element, t2);
      }
      if (count == 2) {
        const index_t a = it->tet_face, b = (it + 1)->tet_face;
        if (ascending(a) == ascending(b)) {
          // Both tets see the face with the same orientation: they lie on the same side of it.
          index_t s[3];
          sorted_face(a / 4, a % 4, s);
          throw InputError("tetrahedra " + std::to_string(a / 4) + " and " + std::to_string(b / 4) +
                               " lie on the same side of their shared face (" + "nodes " +
                               std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " +
                               std::to_string(s[2]) + "): the mesh folds over itself",
                           Entity::Element, b / 4);
        }
        neighbors_[a] = b / 4;
        neighbors_[b] = a / 4;
        neighbor_faces_[a] = static_cast<signed char>(b % 4);
        neighbor_faces_[b] = static_cast<signed char>(a % 4);
      } else {
        ++nb_boundary_faces_;
      }
      it = next;
    }
  }
}

TetTopology TetTopology::reordered(const std::vector<index_t>& order) const {
  std::vector<index_t> position(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) position[order[i]] = static_cast<index_t>(i);
  TetTopology out;
  out.neighbors_.resize(neighbors_.size());
  out.neighbor_faces_.resize(neighbor_faces_.size());
  out.nb_boundary_faces_ = nb_boundary_faces_;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (int f = 0; f < 4; ++f) {
      const index_t n = neighbor(order[i], f);
      out.neighbors_[4 * i + f] = n == NO_CELL ? NO_CELL : position[n];
      out.neighbor_faces_[4 * i + f] = neighbor_faces_[4 * std::size_t(order[i]) + f];
    }
  }
  return out;
}

bool TetTopology::is_boundary_tet(index_t t) const {
  for (int f = 0; f < 4; ++f) {
    if (on_boundary(t, f)) return true;
  }
  return false;
}

}  // namespace hexmerge
