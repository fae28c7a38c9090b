// Selection step 0 (conforming mode): the block of hexahedra and prisms kept together.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include "hexmerge/core/work_queue.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge::select {
namespace {
// Per face of a hexahedron (cell_type.h's order: bottom, top, then the sides around), the face
// opposite it.
constexpr int kOppositeHexFace[6] = {1, 0, 4, 5, 2, 3};

}  // namespace

// Whether every quad face of c is planar (to round-off): the hexahedra and prisms of swept
// meshes (a cross-section repeated from plane to plane) and of lattices.
bool Selector::planar_quads(const Candidate& c) const {
  const CellDescriptor& d = descriptor(c.type);
  for (int f = 0; f < d.nb_faces; ++f) {
    if (d.face_size[f] != 4) continue;
    const auto corner = [&](int i) { return mesh_.point(c.vertices[d.face[f][i]]); };
    if (!quad_is_planar(corner(0), corner(1), corner(2), corner(3))) return false;
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
// or whose quad meets the other's triangles, a planar-quad member leaves before a near-perfect
// hexahedron, then the one with fewer faces shared with the block, then the lesser; by quality
// alone, all 1 in a lattice, the hole that one missing closer leaves grew through the core:
// bracket h 1.38, 97 -> 33 % hex volume; by shared faces first, a lattice cell with four lost
// to a planar-quad hexahedron of scaled Jacobian 0.65 with five, and the cells beside it left
// after it: gmsh_as1-tu-203 at h 6.709, 2,360 of 2,965 core cells in the block). What stays is
// chosen at once, a transaction that the greedy stages (one element at a time, and a block
// lost to one missing closer) cannot break up. Its open quads are left to them: each has a
// closing pyramid that no other quad needs, so both strategies keep it closable; a prism
// sharing it may close it instead.
void Selector::select_block() {
  std::vector<double> along(cands_.size(), 0.0);  // centroid . direction, for the members
  const Vec3 direction = Vec3{1.0, std::sqrt(2.0), std::sqrt(3.0)} * 0.5;
  auto rank = [&](std::vector<index_t>& list) {
    for (index_t ci : list) {
      const Candidate& c = cands_[ci];
      const int n = descriptor(c.type).nb_vertices;
      for (int i = 0; i < n; ++i) along[ci] += Vec3::of(mesh_.point(c.vertices[i])).dot(direction);
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
      if (block_of[cands_.tets(c)[i]] != NO_INDEX) return false;
    }
    return true;
  };
  auto take_disjoint = [&](const std::vector<index_t>& list) {
    for (index_t ci : list) {
      const Candidate& c = cands_[ci];
      if (!unclaimed(c)) continue;
      for (int i = 0; i < c.nb_tets; ++i) block_of[cands_.tets(c)[i]] = ci;
      in_block[ci] = 1;
    }
  };
  // The near-perfect hexahedra, then the planar-quad ones on the tets they leave (all ranked
  // below them: by type, then quality), so that only those are tested for planarity.
  auto near_perfect = [&](index_t h) {
    return cands_[h].type == CellType::Hex && cands_[h].quality >= kBlockHexQuality;
  };
  std::vector<index_t> order, planar;
  for (index_t ci = 0; ci < cands_.size(); ++ci)
    if (near_perfect(ci)) order.push_back(ci);
  rank(order);
  take_disjoint(order);
  // Then the hexahedra on the tets left that share a quad face with a near-perfect member and
  // have the opposite face on the domain boundary (a core's buffer layer reaching the surface:
  // taken one at a time, or lost to the planar-quad prisms on their tets, the member leaves the
  // block, and the cells beside it after it). Also where a pyramid of their tets would close the
  // member's face: left out for it, that pyramid's tets met the quad of the buffer hexahedron
  // beside, which left the block, and the cells beside it after it (gmsh_Kurbelwelle at h 0.4177:
  // the block kept 14,702 of the 15,875 core and buffer hexahedra, 15,878 hexahedra now).
  std::vector<index_t> fringe;
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    const Candidate& c = cands_[ci];
    if (c.type != CellType::Hex || in_block[ci] || !unclaimed(c)) continue;
    const Sides s = sides(ci);
    bool beside = false;
    for (int f = 0; f < descriptor(c.type).nb_faces && !beside; ++f) {
      const auto n = tets_behind(s, f);
      const auto across = tets_behind(s, kOppositeHexFace[f]);
      if (n[0] == NO_CELL || n[1] == NO_CELL || across[0] != NO_CELL || across[1] != NO_CELL)
        continue;
      const index_t b = block_of[n[0]];
      const QuadKey key = face_key(c, f);
      beside = b != NO_INDEX && b == block_of[n[1]] && near_perfect(b) && has_quad(cands_[b], key);
    }
    if (beside) fringe.push_back(ci);
  }
  rank(fringe);
  take_disjoint(fringe);
  order.insert(order.end(), fringe.begin(), fringe.end());
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    const Candidate& c = cands_[ci];
    if ((c.type == CellType::Prism || (c.type == CellType::Hex && !near_perfect(ci))) &&
        unclaimed(c) && planar_quads(c))
      planar.push_back(ci);
  }
  // In a region that the near-perfect hexahedra and the planar-quad candidates do not cover
  // whole (not a swept region, where every tet is in a column), only the planar-quad prisms
  // beside the hexahedra taken so far: elsewhere their points lie in planes by chance, and taken
  // first they keep the hexahedra out (Gmsh's frontal points on the benchmark's bracket: 57.5 %
  // of the volume in prisms, 3.6 % in hexahedra).
  {
    std::vector<char> covered(mesh_.nb_tets(), 0);
    for (index_t t = 0; t < mesh_.nb_tets(); ++t) covered[t] = block_of[t] != NO_INDEX;
    for (index_t ci : planar)
      for (index_t t : cands_.tets(cands_[ci])) covered[t] = 1;
    std::unordered_set<std::int32_t> partial;
    for (index_t t = 0; t < mesh_.nb_tets(); ++t)
      if (!covered[t]) partial.insert(mesh_.region(t));
    const auto beside_block = [&](index_t ci) {
      const Sides s = sides(ci);
      for (int f = 0; f < descriptor(cands_[ci].type).nb_faces; ++f) {
        if (!is_quad(cands_[ci], f)) continue;
        const auto n = tets_behind(s, f);
        if (n[0] != NO_CELL && block_of[n[0]] != NO_INDEX) return true;
      }
      return false;
    };
    if (!partial.empty())
      planar.erase(std::remove_if(planar.begin(), planar.end(),
                                  [&](index_t ci) {
                                    const Candidate& c = cands_[ci];
                                    return c.type == CellType::Prism &&
                                           partial.count(mesh_.region(cands_.tets(c)[0])) &&
                                           !beside_block(ci);
                                  }),
                   planar.end());
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
    if (near_perfect(a) != near_perfect(b)) return near_perfect(b);
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
    for (int i = 0; i < c.nb_tets; ++i) block_of[cands_.tets(c)[i]] = NO_INDEX;
    // Who may have counted on it: block hexahedra next to its tets, and those whose quads
    // meet the tets next to them (a conflict may be gone).
    for (int i = 0; i < c.nb_tets; ++i) {
      for (int f = 0; f < 4; ++f) {
        const index_t n = topo_.neighbor(cands_.tets(c)[i], f);
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

}  // namespace hexmerge::select
