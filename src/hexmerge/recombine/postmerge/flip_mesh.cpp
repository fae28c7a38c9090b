#include "hexmerge/recombine/postmerge/flip_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"

namespace hexmerge {
namespace {

bool holds(const index_t* q, index_t v) { return q[0] == v || q[1] == v || q[2] == v || q[3] == v; }

// The face of tet q opposite its corner f.
std::array<index_t, 3> face_opposite(const index_t* q, int f) {
  std::array<index_t, 3> face{};
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    if (i != f) face[n++] = q[i];
  }
  return face;
}

}  // namespace

FlipMesh::FlipMesh(const TetMesh& mesh)
    : points_(mesh.points),
      with_regions_(!mesh.regions.empty()),
      tets_(mesh.tets),
      alive_(mesh.nb_tets(), 1),
      locked_(mesh.nb_tets(), 0),
      incidence_(mesh.nb_vertices()),
      kind_(mesh.nb_vertices(), kUnknown) {
  regions_.resize(mesh.nb_tets());
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    regions_[t] = mesh.region(t);
    for (int i = 0; i < 4; ++i) incidence_[mesh.tet(t)[i]].push_back(t);
  }
  const TetTopology topology(mesh);
  input_neighbors_.resize(4 * static_cast<std::size_t>(mesh.nb_tets()));
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f) input_neighbors_[4 * std::size_t{t} + f] = topology.neighbor(t, f);
}

void FlipMesh::tets_with_edge(index_t a, index_t b, std::vector<index_t>& out) const {
  out.clear();
  for (index_t t : incidence_[a]) {
    if (t < nb_slots() && alive_[t] && holds(tet(t), a) && holds(tet(t), b) &&
        std::find(out.begin(), out.end(), t) == out.end()) {
      out.push_back(t);
    }
  }
}

index_t FlipMesh::tet_with_face(index_t a, index_t b, index_t c, index_t except) const {
  // An input tet alive with the face: its input neighbour across it, when alive (no other tet
  // can hold the face then), or none on the domain's boundary (changes keep each cavity's
  // surface, so nothing comes beyond it).
  if (except != NO_CELL && 4 * std::size_t{except} < input_neighbors_.size() && alive_[except]) {
    const index_t* q = tet(except);
    int off = -1, held = 0;
    for (int i = 0; i < 4; ++i) {
      if (q[i] == a || q[i] == b || q[i] == c) {
        ++held;
      } else {
        off = i;
      }
    }
    if (held == 3) {
      const index_t n = input_neighbors_[4 * std::size_t{except} + off];
      if (n == NO_CELL || alive_[n]) return n;
    }
  }
  for (index_t t : incidence_[a]) {
    if (t != except && t < nb_slots() && alive_[t] && holds(tet(t), a) && holds(tet(t), b) &&
        holds(tet(t), c)) {
      return t;
    }
  }
  return NO_CELL;
}

index_t FlipMesh::opposite(index_t t, index_t a, index_t b, index_t c) const {
  for (int i = 0; i < 4; ++i) {
    const index_t v = tet(t)[i];
    if (v != a && v != b && v != c) return v;
  }
  return NO_VERTEX;
}

bool FlipMesh::replace(const std::vector<index_t>& old_tets,
                       const std::vector<std::array<index_t, 4>>& new_tets, double min_quality,
                       std::uint8_t kind) {
  const std::int32_t region = regions_[old_tets[0]];
  double old_volume = 0.0;
  for (index_t t : old_tets) {
    if (!alive_[t] || locked_[t] || regions_[t] != region) return false;
    const index_t* q = tet(t);
    old_volume += tet_volume(point(q[0]), point(q[1]), point(q[2]), point(q[3]));
  }
  double new_volume = 0.0;
  for (const auto& q : new_tets) {
    const double volume = tet_volume(point(q[0]), point(q[1]), point(q[2]), point(q[3]));
    if (!(volume > 0.0)) return false;
    if (scaled_jacobian(CellType::Tet, points_.data(), q.data()) < min_quality) return false;
    new_volume += volume;
  }
  // The new tets have the old ones' boundary, consistently oriented, so their signed volumes add
  // up to the union's: this only guards the construction against rounding.
  if (std::fabs(new_volume - old_volume) > 1e-9 * old_volume) return false;
  for (index_t t : old_tets) {
    alive_[t] = 0;
    journal_.push_back({t, false, 0});
  }
  for (const auto& q : new_tets) {
    const index_t t = nb_slots();
    tets_.insert(tets_.end(), q.begin(), q.end());
    regions_.push_back(region);
    alive_.push_back(1);
    locked_.push_back(0);
    for (index_t v : q) incidence_[v].push_back(t);
    journal_.push_back({t, true, 0});
  }
  journal_.back().kind = kind;
  if (kind == 23) ++counts_.flips_23;
  if (kind == 32) ++counts_.flips_32;
  if (kind == 44) ++counts_.flips_44;
  if (kind == kContraction) ++counts_.contractions;
  if (kind == kSplit) ++counts_.splits;
  return true;
}

bool FlipMesh::flip_23(index_t t0, index_t t1, double min_quality) {
  if (t0 == t1 || !alive_[t0] || !alive_[t1]) return false;
  // The shared face (a, b, c), ordered so that (a, b, c, p) is positive, p the apex in t0.
  std::array<index_t, 3> face{};
  int n = 0;
  index_t p = NO_VERTEX;
  for (int i = 0; i < 4; ++i) {
    const index_t v = tet(t0)[i];
    if (holds(tet(t1), v)) {
      if (n == 3) return false;
      face[n++] = v;
    } else {
      p = v;
    }
  }
  if (n != 3) return false;
  const index_t q = opposite(t1, face[0], face[1], face[2]);
  const index_t a = face[0];
  index_t b = face[1], c = face[2];
  if (tet_volume(point(a), point(b), point(c), point(p)) < 0.0) std::swap(b, c);
  return change({t0, t1}, {{{a, b, q, p}}, {{b, c, q, p}}, {{c, a, q, p}}}, min_quality, 23);
}

bool FlipMesh::remove_edge(index_t u, index_t v, int diagonal, double min_quality) {
  std::vector<index_t> around;
  tets_with_edge(u, v, around);
  if (around.size() != 3 && around.size() != 4) return false;
  // The ring: the other two vertices of each tet, chained into one cycle.
  std::vector<std::array<index_t, 2>> pairs;
  for (index_t t : around) {
    std::array<index_t, 2> pair{};
    int n = 0;
    for (int i = 0; i < 4; ++i) {
      const index_t w = tet(t)[i];
      if (w != u && w != v) pair[n++] = w;
    }
    pairs.push_back(pair);
  }
  std::vector<index_t> ring = {pairs[0][0], pairs[0][1]};
  std::vector<char> used(pairs.size(), 0);
  used[0] = 1;
  while (ring.size() < pairs.size()) {
    bool grown = false;
    for (std::size_t k = 0; k < pairs.size() && !grown; ++k) {
      if (used[k]) continue;
      for (int s = 0; s < 2; ++s) {
        if (pairs[k][s] == ring.back()) {
          ring.push_back(pairs[k][1 - s]);
          used[k] = 1;
          grown = true;
          break;
        }
      }
    }
    if (!grown) return false;  // an open ring: (u, v) is on the boundary
  }
  // Closed: the last unused pair joins the ends.
  const auto last = std::find(used.begin(), used.end(), 0) - used.begin();
  const auto& closing = pairs[static_cast<std::size_t>(last)];
  const bool closes = (closing[0] == ring.back() && closing[1] == ring.front()) ||
                      (closing[1] == ring.back() && closing[0] == ring.front());
  if (!closes) return false;
  if (tet_volume(point(u), point(v), point(ring[0]), point(ring[1])) < 0.0) {
    std::reverse(ring.begin(), ring.end());
  }
  std::vector<std::array<index_t, 4>> made;
  if (ring.size() == 3) {
    made = {{{ring[0], ring[1], ring[2], v}}, {{ring[0], ring[2], ring[1], u}}};
  } else {
    const int s = diagonal == 0 ? 0 : 1;
    const index_t r0 = ring[s], r1 = ring[s + 1], r2 = ring[s + 2], r3 = ring[(s + 3) % 4];
    made = {{{r0, r1, r2, v}}, {{r0, r2, r3, v}}, {{r0, r2, r1, u}}, {{r0, r3, r2, u}}};
  }
  return change(around, made, min_quality, ring.size() == 3 ? 32 : 44);
}

bool FlipMesh::contract(index_t from, index_t onto, double min_quality) {
  std::vector<index_t> star;
  tets_with_edge(from, from, star);
  bool joined = false;
  // The faces at `from` with no tet on their other side: on the domain boundary.
  std::vector<std::array<index_t, 3>> boundary;
  for (index_t t : star) {
    const index_t* q = tet(t);
    joined = joined || holds(q, onto);
    for (int f = 0; f < 4; ++f) {
      if (q[f] == from) continue;
      const std::array<index_t, 3> face = face_opposite(q, f);
      if (tet_with_face(face[0], face[1], face[2], t) == NO_CELL) boundary.push_back(face);
    }
  }
  if (!joined) return false;
  if (!boundary.empty() && !flat_boundary(boundary, onto)) return false;
  // The star of `from` is a ball and `onto` lies on its boundary; the cone from `onto` over the
  // star's faces away from `from` and `onto` tiles it exactly when every cone tet is positive
  // (the winding number argument), which replace() checks with the quality floor. On the
  // domain boundary the star's faces at `from` there are one plane with `onto` in it, so the
  // cone's faces in that plane tile the same polygon: the boundary surface is kept.
  std::vector<std::array<index_t, 4>> made;
  for (index_t t : star) {
    const index_t* q = tet(t);
    if (holds(q, onto)) continue;
    std::array<index_t, 4> cone{{q[0], q[1], q[2], q[3]}};
    std::replace(cone.begin(), cone.end(), from, onto);
    made.push_back(cone);
  }
  return change(star, made, min_quality, kContraction);
}

index_t FlipMesh::split(index_t v, const std::vector<index_t>& to_new,
                        const std::array<double, 3>& at_v, const std::array<double, 3>& at_new,
                        double min_quality) {
  // movable() finds whether v is inner (and its tets of one region and unlocked).
  if (!movable(v) || kind_[v] != kInner) return NO_VERTEX;
  std::vector<index_t> around;
  star(v, around);
  const auto moving = [&to_new](index_t t) {
    return std::find(to_new.begin(), to_new.end(), t) != to_new.end();
  };
  const auto nb_moving =
      static_cast<std::size_t>(std::count_if(around.begin(), around.end(), moving));
  if (nb_moving == 0 || nb_moving != to_new.size() || nb_moving == around.size()) {
    return NO_VERTEX;
  }
  const index_t n = nb_nodes();
  std::vector<std::array<index_t, 4>> made;
  for (index_t t : around) {
    const std::array<index_t, 4> q{{tet(t)[0], tet(t)[1], tet(t)[2], tet(t)[3]}};
    if (!moving(t)) {
      made.push_back(q);
      continue;
    }
    std::array<index_t, 4> moved = q;
    std::replace(moved.begin(), moved.end(), v, n);
    made.push_back(moved);
    // A face at v shared with a tet that keeps v: the ring tet is t with its corner across the
    // face replaced by n. It holds the face as t does, so it lies on t's side of it, between the
    // tet keeping v and t with n; its other faces cancel along the ring.
    for (int f = 0; f < 4; ++f) {
      if (q[f] == v) continue;
      const std::array<index_t, 3> face = face_opposite(q.data(), f);
      const index_t other = tet_with_face(face[0], face[1], face[2], t);
      if (other == NO_CELL || moving(other)) continue;
      std::array<index_t, 4> ring = q;
      ring[f] = n;
      made.push_back(ring);
    }
  }
  // The node added and v's move are journalled first, so that undo takes the tets back before
  // the points.
  const std::size_t start = mark();
  double* p = &points_[3 * std::size_t{v}];
  journal_.push_back({static_cast<index_t>(split_nodes_.size()), false, kSplitNode});
  split_nodes_.push_back({v, {{p[0], p[1], p[2]}}});
  std::copy(at_v.begin(), at_v.end(), p);
  points_.insert(points_.end(), at_new.begin(), at_new.end());
  incidence_.emplace_back();
  kind_.push_back(kInner);
  // The old tets' signed volumes, v moved, still add up to the star's (a cone over its surface):
  // replace()'s volume guard holds.
  if (!replace(around, made, min_quality, kSplit)) {
    undo(start);
    return NO_VERTEX;
  }
  return n;
}

bool FlipMesh::flat_boundary(const std::vector<std::array<index_t, 3>>& faces, index_t onto) const {
  const bool holds_onto = std::any_of(faces.begin(), faces.end(), [onto](const auto& f) {
    return f[0] == onto || f[1] == onto || f[2] == onto;
  });
  std::array<double, 3> normal{};
  return holds_onto && plane_of(faces, normal);
}

bool FlipMesh::plane_of(const std::vector<std::array<index_t, 3>>& faces,
                        std::array<double, 3>& n) const {
  double longest = 0.0;
  for (const auto& f : faces) {
    for (int i = 0; i < 3; ++i) {
      const double* p = point(f[i]);
      const double* q = point(f[(i + 1) % 3]);
      longest = std::max(longest,
                         std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                   (p[2] - q[2]) * (p[2] - q[2])));
    }
  }
  // Every corner of every face within a tiny distance of the first face's plane (so the node is
  // on no edge or corner of the geometry).
  const double* a = point(faces[0][0]);
  const double* b = point(faces[0][1]);
  const double* c = point(faces[0][2]);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(norm > 0.0)) return false;
  for (double& x : n) x /= norm;
  for (const auto& f : faces) {
    for (index_t w : f) {
      const double* p = point(w);
      const double distance = n[0] * (p[0] - a[0]) + n[1] * (p[1] - a[1]) + n[2] * (p[2] - a[2]);
      if (std::fabs(distance) > kFlatTolerance * longest) return false;
    }
  }
  return true;
}

void FlipMesh::undo(std::size_t mark) {
  HEXMERGE_ASSERT(mark <= journal_.size(), "undo past the journal");
  while (journal_.size() > mark) {
    const Entry e = journal_.back();
    journal_.pop_back();
    if (e.kind == kMove) {
      HEXMERGE_ASSERT(e.tet + 1 == moves_.size(), "journal out of order");
      const Move& move = moves_.back();
      std::copy(move.from.begin(), move.from.end(), &points_[3 * std::size_t{move.node}]);
      moves_.pop_back();
      --counts_.moves;
      continue;
    }
    if (e.kind == kSplitNode) {
      HEXMERGE_ASSERT(e.tet + 1 == split_nodes_.size(), "journal out of order");
      const Move& split = split_nodes_.back();
      std::copy(split.from.begin(), split.from.end(), &points_[3 * std::size_t{split.node}]);
      points_.resize(points_.size() - 3);
      incidence_.pop_back();
      kind_.pop_back();
      split_nodes_.pop_back();
      continue;
    }
    if (e.kind == 23) --counts_.flips_23;
    if (e.kind == 32) --counts_.flips_32;
    if (e.kind == 44) --counts_.flips_44;
    if (e.kind == kContraction) --counts_.contractions;
    if (e.kind == kSplit) --counts_.splits;
    if (e.created) {
      // Created last, so it is the last slot: drop it (its incidence entries go stale).
      HEXMERGE_ASSERT(e.tet + 1 == nb_slots(), "journal out of order");
      alive_.pop_back();
      locked_.pop_back();
      regions_.pop_back();
      tets_.resize(tets_.size() - 4);
    } else {
      alive_[e.tet] = 1;
    }
  }
}

bool FlipMesh::change(const std::vector<index_t>& old_tets,
                      const std::vector<std::array<index_t, 4>>& new_tets, double min_quality,
                      std::uint8_t kind) {
  if (replace(old_tets, new_tets, min_quality, kind)) return true;
  if (!smoothing_) return false;
  for (index_t t : old_tets) {
    if (!alive_[t] || locked_[t] || regions_[t] != regions_[old_tets[0]]) return false;
  }
  const auto quality = [this](const std::array<index_t, 4>& q) {
    return scaled_jacobian(CellType::Tet, points_.data(), q.data());
  };
  // The refused tets: a node they all hold is moved (no other node changes them).
  std::vector<const std::array<index_t, 4>*> refused;
  for (const auto& q : new_tets) {
    if (!(quality(q) >= min_quality)) refused.push_back(&q);
  }
  if (refused.empty()) return false;  // refused for the volume guard
  for (index_t v : *refused[0]) {
    const bool in_all = std::all_of(refused.begin(), refused.end(), [v](const auto* q) {
      return std::find(q->begin(), q->end(), v) != q->end();
    });
    if (!in_all) continue;
    std::vector<Goal> goals;
    for (const auto& q : new_tets) {
      if (std::find(q.begin(), q.end(), v) != q.end()) {
        goals.push_back({[&quality, &q]() { return quality(q); }, min_quality});
      }
    }
    const std::size_t start = mark();
    if (smooth(v, goals, old_tets, min_quality) && replace(old_tets, new_tets, min_quality, kind)) {
      return true;
    }
    undo(start);
  }
  return false;
}

void FlipMesh::star(index_t v, std::vector<index_t>& out) const { tets_with_edge(v, v, out); }

bool FlipMesh::boundary_face(index_t t, int f) const {
  std::array<index_t, 3> face{};
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    if (i != f) face[n++] = tet(t)[i];
  }
  return tet_with_face(face[0], face[1], face[2], t) == NO_CELL;
}

bool FlipMesh::movable(index_t v) const {
  std::vector<index_t> around;
  star(v, around);
  if (around.empty()) return false;
  for (index_t t : around) {
    if (locked_[t]) return false;
  }
  // Inside one region, or inside a flat face of the domain: no change alters it (flips and
  // contractions keep the boundary and the regions, and a contracted node is used no more), so
  // it is found once per node.
  if (kind_[v] == kUnknown) {
    bool one_region = true;
    std::vector<std::array<index_t, 3>> boundary;
    for (index_t t : around) {
      one_region = one_region && regions_[t] == regions_[around[0]];
      for (int f = 0; f < 4; ++f) {
        if (tet(t)[f] == v || !boundary_face(t, f)) continue;
        std::array<index_t, 3> face{};
        int n = 0;
        for (int i = 0; i < 4; ++i) {
          if (i != f) face[n++] = tet(t)[i];
        }
        boundary.push_back(face);
      }
    }
    std::array<double, 3> normal{};
    if (!one_region) {
      kind_[v] = kFixed;
    } else if (boundary.empty()) {
      kind_[v] = kInner;
    } else if (plane_of(boundary, normal)) {
      kind_[v] = kOnFlatFace;
      face_normal_[v] = normal;
    } else {
      kind_[v] = kFixed;
    }
  }
  return kind_[v] == kInner || (kind_[v] == kOnFlatFace && slide_on_faces_);
}

bool FlipMesh::smooth(index_t v, const std::vector<Goal>& goals,
                      const std::vector<index_t>& leaving, double min_quality) {
  if (!movable(v)) return false;
  std::vector<index_t> around;
  star(v, around);
  // The tets that stay, each with the scaled Jacobian it must keep.
  std::vector<std::pair<index_t, double>> staying;
  double length = 0.0;
  std::array<double, 3> centroid{};
  int edges = 0;
  double* p = &points_[3 * std::size_t{v}];
  for (index_t t : around) {
    if (std::find(leaving.begin(), leaving.end(), t) == leaving.end()) {
      staying.emplace_back(
          t, std::min(min_quality, scaled_jacobian(CellType::Tet, points_.data(), tet(t))));
    }
    for (int i = 0; i < 4; ++i) {
      const index_t w = tet(t)[i];
      if (w == v) continue;
      const double* q = point(w);
      length += std::sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                          (q[2] - p[2]) * (q[2] - p[2]));
      for (int k = 0; k < 3; ++k) centroid[k] += q[k];
      ++edges;
    }
  }
  length /= edges;
  for (double& x : centroid) x /= edges;
  // A node inside a flat face moves in its plane: the centroid projected, the directions in it.
  const bool on_face = kind_[v] == kOnFlatFace;
  const std::array<double, 3> n = on_face ? face_normal_.at(v) : std::array<double, 3>{};
  if (on_face) {
    const double off =
        (centroid[0] - p[0]) * n[0] + (centroid[1] - p[1]) * n[1] + (centroid[2] - p[2]) * n[2];
    for (int k = 0; k < 3; ++k) centroid[k] -= off * n[k];
  }
  // The least margin over the goals and the staying tets (a staying tet that falls below its
  // bound rules the position out).
  const auto margin = [&]() {
    double least = std::numeric_limits<double>::infinity();
    for (const auto& [t, need] : staying) {
      const double m = scaled_jacobian(CellType::Tet, points_.data(), tet(t)) - need;
      if (!(m >= 0.0)) return -std::numeric_limits<double>::infinity();
      least = std::min(least, m);
    }
    for (const Goal& goal : goals) least = std::min(least, goal.quality() - goal.need);
    if (least >= 0.0 && guard_ && !guard_(v, leaving)) {
      return -std::numeric_limits<double>::infinity();
    }
    return least;
  };
  const std::array<double, 3> start{{p[0], p[1], p[2]}};
  const auto at = [&](const std::array<double, 3>& x) {
    std::copy(x.begin(), x.end(), p);
    return margin();
  };
  std::array<double, 3> best = start;
  double best_margin = at(start);
  const double from_centroid = at(centroid);
  if (from_centroid > best_margin) {
    best = centroid;
    best_margin = from_centroid;
  }
  // Pattern search: the 6 axis and 8 diagonal directions, the best step kept, the step halved
  // when none improves; stops once every bound is met with kEnough to spare.
  static constexpr double kEnough = 0.02;
  static const double kDiagonal = 1.0 / std::sqrt(3.0);
  std::vector<std::array<double, 3>> directions;
  if (on_face) {
    // Two unit vectors spanning the plane, their sums and differences (8 directions).
    const int k = std::fabs(n[0]) < 0.6 ? 0 : (std::fabs(n[1]) < 0.6 ? 1 : 2);
    std::array<double, 3> e{};
    e[k] = 1.0;
    std::array<double, 3> a{{e[0] - n[k] * n[0], e[1] - n[k] * n[1], e[2] - n[k] * n[2]}};
    const double norm = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (double& x : a) x /= norm;
    const std::array<double, 3> b{
        {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]}};
    const double h = std::sqrt(0.5);
    for (double s : {-1.0, 1.0}) {
      directions.push_back({{s * a[0], s * a[1], s * a[2]}});
      directions.push_back({{s * b[0], s * b[1], s * b[2]}});
      for (double t : {-1.0, 1.0}) {
        directions.push_back(
            {{h * (s * a[0] + t * b[0]), h * (s * a[1] + t * b[1]), h * (s * a[2] + t * b[2])}});
      }
    }
  } else {
    for (int k = 0; k < 3; ++k) {
      for (double s : {-1.0, 1.0}) {
        std::array<double, 3> d{};
        d[k] = s;
        directions.push_back(d);
      }
    }
    for (double x : {-kDiagonal, kDiagonal}) {
      for (double y : {-kDiagonal, kDiagonal}) {
        for (double z : {-kDiagonal, kDiagonal}) directions.push_back({{x, y, z}});
      }
    }
  }
  int trials = 2;
  for (double step = length / 3.0; step > length * kSmallestStep && trials < kMaxTrials;) {
    if (best_margin >= kEnough) break;
    std::array<double, 3> next = best;
    double next_margin = best_margin;
    for (const auto& d : directions) {
      const std::array<double, 3> x{
          {best[0] + step * d[0], best[1] + step * d[1], best[2] + step * d[2]}};
      const double m = at(x);
      ++trials;
      if (m > next_margin) {
        next = x;
        next_margin = m;
      }
    }
    if (next_margin > best_margin) {
      best = next;
      best_margin = next_margin;
    } else {
      step /= 2.0;
    }
  }
  if (!(best_margin >= 0.0) || best == start) {
    std::copy(start.begin(), start.end(), p);
    return best_margin >= 0.0;  // met where it is: nothing to move
  }
  std::copy(best.begin(), best.end(), p);
  journal_.push_back({static_cast<index_t>(moves_.size()), false, kMove});
  moves_.push_back({v, start});
  ++counts_.moves;
  return true;
}

TetMesh FlipMesh::compact() const {
  TetMesh out;
  out.points = points_;
  for (index_t t = 0; t < nb_slots(); ++t) {
    if (!alive_[t]) continue;
    out.tets.insert(out.tets.end(), tet(t), tet(t) + 4);
    if (with_regions_) out.regions.push_back(regions_[t]);
  }
  return out;
}

}  // namespace hexmerge
