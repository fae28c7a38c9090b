#include "hexmerge/occ/mesher/remove_slivers.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge {
namespace {

using Tet = std::array<index_t, 4>;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

using mesher::face_key;
using mesher::FaceKey;
using mesher::FaceKeyHash;

// Whether (w, x, y, z), four distinct vertices of t, run in t's own (positive) order up to an
// even permutation.
bool same_orientation(const Tet& t, index_t w, index_t x, index_t y, index_t z) {
  auto at = [&](index_t v) {
    return static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
  };
  const int p[4] = {at(w), at(x), at(y), at(z)};
  int inversions = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) inversions += p[i] > p[j];
  return inversions % 2 == 0;
}

// The mesh while it is flipped: tets by slot (dead slots stay), the tets at each vertex.
class FlipMesh {
 public:
  FlipMesh(TetMesh& mesh, const std::vector<char>& fixed,
           const std::vector<std::int32_t>& boundary_patch, const std::vector<char>* settled)
      : points_(mesh.points) {
    // Each vertex's list allocated once, at its number of tets (the flips add a few).
    std::vector<index_t> degree(mesh.nb_vertices(), 0);
    for (const index_t v : mesh.tets) ++degree[v];
    at_vertex_.resize(mesh.nb_vertices());
    for (std::size_t v = 0; v < at_vertex_.size(); ++v) at_vertex_[v].reserve(degree[v]);
    changed_.assign(mesh.nb_vertices(), 0);
    for (auto* list : {&examined_, &tried_}) list->reserve(mesh.nb_tets());
    tets_.reserve(mesh.nb_tets()), region_.reserve(mesh.nb_tets());
    fixed_.reserve(mesh.nb_tets()), alive_.reserve(mesh.nb_tets());
    quality_.reserve(mesh.nb_tets());
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      const index_t* v = mesh.tet(t);
      add(Tet{v[0], v[1], v[2], v[3]}, mesh.region(t), !fixed.empty() && fixed[t]);
    }
    // The tets settled before: examined after every stamp the adds above left.
    clock_ = kBuilt;
    if (settled != nullptr)
      for (std::size_t t = 0; t < settled->size(); ++t)
        if ((*settled)[t]) examined_[t] = clock_;
    if (boundary_patch.empty()) return;
    // The patches of the boundary faces (a face without one reads as -1, as a face not kept).
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      for (int f = 0; f < 4; ++f) {
        const std::int32_t patch = boundary_patch[4 * static_cast<std::size_t>(t) + f];
        if (patch < 0 || across(t, f) != NO_CELL) continue;
        const index_t* v = mesh.tet(t);
        patch_[face_key(v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4])] = patch;
      }
  }

  double quality(const Tet& t) const {
    return scaled_jacobian(CellType::Tet, points_.data(), t.data());
  }
  std::size_t nb_slots() const { return tets_.size(); }
  bool alive(index_t t) const { return alive_[t]; }
  bool fixed(index_t t) const { return fixed_[t]; }
  const Tet& tet(index_t t) const { return tets_[t]; }
  double quality(index_t t) const { return quality_[t]; }
  std::int32_t region(index_t t) const { return region_[t]; }
  // Whether t may be replaced in a flip within region r.
  bool movable(index_t t, std::int32_t r) const {
    return alive_[t] && !fixed_[t] && region_[t] == r;
  }

  void add(const Tet& t, std::int32_t region, bool fixed = false) {
    const auto id = static_cast<index_t>(tets_.size());
    tets_.push_back(t);
    region_.push_back(region);
    fixed_.push_back(fixed);
    alive_.push_back(1);
    quality_.push_back(quality(t));
    examined_.push_back(0);
    tried_.push_back(0);
    for (index_t v : t) at_vertex_[v].push_back(id), changed_[v] = clock_;
  }
  // A new vertex at p, in no tet yet; its position may change (place) until a tet holds it.
  index_t add_vertex(const Vec3& p) {
    points_.insert(points_.end(), {p.x, p.y, p.z});
    at_vertex_.emplace_back();
    changed_.push_back(clock_);
    return static_cast<index_t>(at_vertex_.size() - 1);
  }
  void place(index_t v, const Vec3& p) {
    double* x = &points_[3 * static_cast<std::size_t>(v)];
    x[0] = p.x, x[1] = p.y, x[2] = p.z;
  }
  // The last vertex added, while no tet holds it.
  void remove_last_vertex() {
    points_.resize(points_.size() - 3);
    at_vertex_.pop_back();
    changed_.pop_back();
  }

  // One set of tets at a time (an insertion's cavity): emptied, a tet put in, asked for.
  void clear_set() {
    ++set_clock_;
    set_.resize(tets_.size(), 0);
  }
  void put_in_set(index_t t) { set_[t] = set_clock_; }
  bool in_set(index_t t) const { return set_[t] == set_clock_; }

  void remove(index_t t) {
    alive_[t] = 0;
    for (index_t v : tets_[t]) {
      auto& list = at_vertex_[v];
      list.erase(std::find(list.begin(), list.end(), t));
      changed_[v] = clock_;
    }
  }

  // Whether t's flips may differ from when it was last examined: everything they read (the
  // tets across its faces and around its edges, their qualities, the boundary patches of faces
  // at its edges) lies in tets holding one of its vertices, and every tet added or removed
  // stamps its vertices. A tet never examined has stamp 0, below every clock.
  bool changed_since_examined(index_t t) const {
    const std::uint64_t seen = examined_[t];
    return seen == 0 || std::any_of(tets_[t].begin(), tets_[t].end(),
                                    [&](index_t v) { return changed_[v] >= seen; });
  }
  // Marks t examined now: the changes from now on stamp at least this clock.
  void examine(index_t t) { examined_[t] = ++clock_; }
  // The same for vertex insertion into t: not tried again while the tets at its vertices stay
  // (its larger cavities reach farther, but seldom change alone).
  bool changed_since_tried(index_t t) const {
    const std::uint64_t seen = tried_[t];
    return seen == 0 || std::any_of(tets_[t].begin(), tets_[t].end(),
                                    [&](index_t v) { return changed_[v] >= seen; });
  }
  void try_insertion(index_t t) { tried_[t] = ++clock_; }

  // The tets around edge (a, b), in `around`, and their other vertices in `ring`, so that tet i
  // is (a, b, ring[i], ring[i + 1]) in positive order (ring[n] = ring[0] for a closed ring, an
  // interior edge; an open ring, a boundary edge, has n + 1 vertices). False when the tets do not
  // make one ring or there are more than max_ring.
  bool edge_ring(index_t a, index_t b, int max_ring, std::vector<index_t>& around,
                 std::vector<index_t>& ring, bool& closed) const {
    around.clear();
    for (index_t t : at_vertex_[a])
      if (std::find(tets_[t].begin(), tets_[t].end(), b) != tets_[t].end()) {
        if (static_cast<int>(around.size()) == max_ring) return false;
        around.push_back(t);
      }
    const std::size_t n = around.size();
    if (n == 0) return false;
    // Per tet, its two other vertices (x, y) with (a, b, x, y) positive.
    std::vector<std::pair<index_t, index_t>> sides(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Tet& t = tets_[around[i]];
      index_t other[2], k = 0;
      for (index_t v : t)
        if (v != a && v != b) other[k++] = v;
      sides[i] = same_orientation(t, a, b, other[0], other[1]) ? std::make_pair(other[0], other[1])
                                                               : std::make_pair(other[1], other[0]);
    }
    // An open ring starts at the vertex no tet ends at.
    index_t x = sides[0].first;
    closed = true;
    for (const auto& side : sides)
      if (std::none_of(sides.begin(), sides.end(),
                       [&](const auto& s) { return s.second == side.first; }))
        x = side.first, closed = false;
    ring.clear();
    std::vector<index_t> ordered;
    for (std::size_t step = 0; step < n; ++step) {
      std::size_t i = 0;
      while (i < n && sides[i].first != x) ++i;
      if (i == n) return false;
      ring.push_back(x);
      ordered.push_back(around[i]);
      x = sides[i].second;
    }
    if (closed && x != ring.front()) return false;
    if (!closed) ring.push_back(x);
    around = ordered;
    return closed ? n >= 3 : n >= 1;
  }

  // The patch of boundary face (a, b, c), or -1 (no patch given, or not a boundary face).
  std::int32_t patch(index_t a, index_t b, index_t c) const {
    const auto it = patch_.find(face_key(a, b, c));
    return it == patch_.end() ? -1 : it->second;
  }
  void set_patch(index_t a, index_t b, index_t c, std::int32_t patch) {
    patch_[face_key(a, b, c)] = patch;
  }
  void clear_patch(index_t a, index_t b, index_t c) { patch_.erase(face_key(a, b, c)); }
  const double* point(index_t v) const { return &points_[3 * static_cast<std::size_t>(v)]; }

  // The tet across face `opposite` (local index of the vertex not on it) of t, or NO_CELL.
  index_t across(index_t t, int opposite) const {
    const Tet& v = tets_[t];
    const index_t f0 = v[(opposite + 1) % 4], f1 = v[(opposite + 2) % 4],
                  f2 = v[(opposite + 3) % 4];
    for (index_t u : at_vertex_[f0]) {
      if (u == t) continue;
      const Tet& w = tets_[u];
      if (std::find(w.begin(), w.end(), f1) != w.end() &&
          std::find(w.begin(), w.end(), f2) != w.end())
        return u;
    }
    return NO_CELL;
  }

  // The live tets, renumbered; regions when the input had them.
  // The living tets into `mesh`; into `state` (when not null), whether each was examined and
  // nothing at its vertices changed since, and the vertices at which a tet changed.
  void write(TetMesh& mesh, RemoveSliversState* state) const {
    const bool with_regions = !mesh.regions.empty();
    mesh.tets.clear();
    mesh.regions.clear();
    std::vector<char>* settled = state != nullptr ? &state->settled : nullptr;
    if (settled != nullptr) settled->clear();
    for (std::size_t t = 0; t < tets_.size(); ++t) {
      if (!alive_[t]) continue;
      mesh.tets.insert(mesh.tets.end(), tets_[t].begin(), tets_[t].end());
      if (with_regions) mesh.regions.push_back(region_[t]);
      if (settled != nullptr)
        settled->push_back(examined_[t] != 0 && !changed_since_examined(static_cast<index_t>(t)));
    }
    if (state != nullptr) {
      state->touched.resize(changed_.size());
      for (std::size_t v = 0; v < changed_.size(); ++v) state->touched[v] = changed_[v] >= kBuilt;
    }
  }

 private:
  std::vector<double>& points_;
  std::vector<Tet> tets_;
  std::vector<std::int32_t> region_;
  std::vector<char> fixed_, alive_;
  std::vector<double> quality_;
  std::vector<std::vector<index_t>> at_vertex_;
  // Change stamps: per tet the clock when it was last examined, per vertex when a tet at it was
  // last added or removed (see changed_since_examined).
  std::vector<std::uint64_t> examined_, tried_, changed_;
  // The clock while the mesh is built, and after.
  static constexpr std::uint64_t kBuilding = 1, kBuilt = 2;
  std::uint64_t clock_ = kBuilding;
  std::unordered_map<FaceKey, std::int32_t, FaceKeyHash> patch_;
  // The set's stamps: a tet is in it when its stamp is the set's clock.
  std::vector<std::uint64_t> set_;
  std::uint64_t set_clock_ = 0;
};

// A flip: the tets it replaces, the tets it makes and the smallest quality among these.
struct Flip {
  std::vector<index_t> old_tets;
  std::vector<Tet> new_tets;
  double quality = -kInfinity;
  // A boundary edge (a, b) between boundary faces (a, b, c) and (a, b, d) becomes (c, d).
  std::array<index_t, 4> boundary_swap{NO_VERTEX, NO_VERTEX, NO_VERTEX, NO_VERTEX};
};

// Edge removal of (a, b): the best triangulation of the ring polygon, each triangle joined to
// a and to b (Klincsek's dynamic programming, maximising the smallest quality). For a boundary
// edge the polygon is closed by the new boundary edge (ring.front(), ring.back()).
void best_edge_removal(const FlipMesh& m, index_t a, index_t b, const std::vector<index_t>& around,
                       const std::vector<index_t>& ring, Flip& best) {
  const int n = static_cast<int>(ring.size());
  std::vector<double> value(n * n, kInfinity);
  std::vector<int> split(n * n, -1);
  for (int gap = 2; gap < n; ++gap)
    for (int i = 0; i + gap < n; ++i) {
      const int j = i + gap;
      double& v = value[i * n + j];
      v = -kInfinity;
      for (int k = i + 1; k < j; ++k) {
        double q = std::min(value[i * n + k], value[k * n + j]);
        if (q <= v) continue;
        q = std::min(q, m.quality(Tet{ring[i], ring[k], ring[j], b}));
        if (q <= v) continue;
        q = std::min(q, m.quality(Tet{ring[i], ring[j], ring[k], a}));
        if (q > v) v = q, split[i * n + j] = k;
      }
    }
  if (value[n - 1] <= best.quality) return;
  best.quality = value[n - 1];
  best.old_tets = around;
  best.new_tets.clear();
  best.boundary_swap = {NO_VERTEX, NO_VERTEX, NO_VERTEX, NO_VERTEX};
  std::vector<std::pair<int, int>> stack{{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[i * n + j];
    best.new_tets.push_back(Tet{ring[i], ring[k], ring[j], b});
    best.new_tets.push_back(Tet{ring[i], ring[j], ring[k], a});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
}

// A boundary swap may make a triangle with a smaller angle than this (radians, 5 degrees) only
// where the triangles it replaces had one as small.
constexpr double kSmallBoundaryAngle = 5.0 * M_PI / 180;

// Whether boundary edge (a, b) may be swapped to (c, d), its boundary faces being (a, b, c) and
// (a, b, d): both on one patch, in one plane (max_shift 0) or with the lines ab and cd at most
// max_shift apart, so that the boundary stays where it is or within max_shift of it.
bool swappable(const FlipMesh& m, index_t a, index_t b, index_t c, index_t d, double max_shift) {
  const std::int32_t patch = m.patch(a, b, c);
  if (patch < 0 || m.patch(a, b, d) != patch) return false;
  const Vec3 pa = Vec3::of(m.point(a)), ab = Vec3::of(m.point(b)) - pa;
  const Vec3 ac = Vec3::of(m.point(c)) - pa, ad = Vec3::of(m.point(d)) - pa;
  const Vec3 n = ab.cross(ac), cd = ad - ac;
  if (max_shift > 0) {
    const Vec3 both = ab.cross(cd);
    if (std::abs(ac.dot(both)) > max_shift * both.norm()) return false;
  } else if (std::abs(det3(ab, ac, ad)) > 1e-9 * ab.norm() * ac.norm() * ad.norm()) {
    return false;
  }
  // The quad a, c, b, d convex: its diagonals ab and cd cross (seen along n).
  if (!(ab.cross(ac).dot(n) * ab.cross(ad).dot(n) < 0 &&
        cd.cross(ac * -1.0).dot(n) * cd.cross(ab - ac).dot(n) < 0))
    return false;
  // No boundary triangle under kSmallBoundaryAngle made worse: a swap whose quad has a corner
  // of nearly 180 degrees would make a flat boundary triangle, and the tet on it a sliver.
  const Vec3 pb = pa + ab, pc = pa + ac, pd = pa + ad;
  using mesher::smallest_angle;
  const double after = std::min(smallest_angle(pc, pd, pa), smallest_angle(pc, pd, pb));
  return after >= kSmallBoundaryAngle ||
         after >= std::min(smallest_angle(pa, pb, pc), smallest_angle(pa, pb, pd));
}

// Face removal across face `opposite` of t: t = (f, p) and its neighbour (f, q) become three
// tets around the edge (q, p).
void best_face_removal(const FlipMesh& m, index_t t, int opposite, Flip& best) {
  const index_t u = m.across(t, opposite);
  if (u == NO_CELL || !m.movable(u, m.region(t))) return;
  const Tet& v = m.tet(t);
  const index_t p = v[opposite];
  index_t f[3] = {v[(opposite + 1) % 4], v[(opposite + 2) % 4], v[(opposite + 3) % 4]};
  if (!same_orientation(v, f[0], f[1], f[2], p)) std::swap(f[1], f[2]);
  index_t q = NO_VERTEX;
  for (index_t w : m.tet(u))
    if (w != f[0] && w != f[1] && w != f[2]) q = w;
  Flip flip;
  flip.old_tets = {t, u};
  flip.quality = kInfinity;
  for (int i = 0; i < 3; ++i) {
    flip.new_tets.push_back(Tet{q, p, f[i], f[(i + 1) % 3]});
    flip.quality = std::min(flip.quality, m.quality(flip.new_tets.back()));
  }
  if (flip.quality > best.quality) best = std::move(flip);
}

// Vertex insertion: the tets of a cavity around a tet are replaced by the tets joining its
// boundary faces to a new vertex, placed where the worst of them is best.
struct Insertion {
  std::vector<index_t> old_tets;
  std::vector<Tet> new_tets;  // holding the new vertex, the index add_vertex() gives it next
  Vec3 point{0, 0, 0};
  double deficit = kInfinity;  // the sum of floor - quality over the new tets below the floor
};

// The tets joining the boundary faces of `cavity` (tets of a valid mesh, the mesh's set) to
// vertex p, each the
// cavity's tet with the vertex opposite the face replaced by p (so positive where p lies inside
// the face's half-space). False when the cavity is no ball with every vertex on its boundary:
// its boundary must be a closed surface of two faces at every side and Euler characteristic 2
// (then, by the kernel theorem, p sees every face positively only inside the cavity's kernel
// and the tets tile the cavity).
bool star_of_cavity(const FlipMesh& m, const std::vector<index_t>& cavity, index_t p,
                    std::vector<Tet>& made) {
  made.clear();
  std::vector<index_t> vertices, on_boundary;
  std::vector<std::pair<index_t, index_t>> sides;
  for (index_t u : cavity)
    for (int k = 0; k < 4; ++k) {
      vertices.push_back(m.tet(u)[k]);
      const index_t w = m.across(u, k);
      if (w != NO_CELL && m.in_set(w)) continue;
      Tet n = m.tet(u);
      n[k] = p;
      made.push_back(n);
      const index_t f[3] = {n[(k + 1) % 4], n[(k + 2) % 4], n[(k + 3) % 4]};
      for (int i = 0; i < 3; ++i) {
        on_boundary.push_back(f[i]);
        sides.emplace_back(std::min(f[i], f[(i + 1) % 3]), std::max(f[i], f[(i + 1) % 3]));
      }
    }
  for (auto* list : {&vertices, &on_boundary}) {
    std::sort(list->begin(), list->end());
    list->erase(std::unique(list->begin(), list->end()), list->end());
  }
  if (vertices != on_boundary) return false;
  std::sort(sides.begin(), sides.end());
  for (std::size_t i = 0; i < sides.size(); i += 2)
    if (i + 1 >= sides.size() || sides[i] != sides[i + 1] ||
        (i + 2 < sides.size() && sides[i + 2] == sides[i]))
      return false;
  const auto v = static_cast<long>(on_boundary.size()), e = static_cast<long>(sides.size() / 2),
             f = static_cast<long>(made.size());
  return v - e + f == 2;
}

// The centre and squared radius of tet t's circumsphere (radius infinite for a flat tet).
void circumsphere(const FlipMesh& m, const Tet& t, Vec3& centre, double& radius2) {
  const Vec3 a = Vec3::of(m.point(t[0]));
  const Vec3 u = Vec3::of(m.point(t[1])) - a, v = Vec3::of(m.point(t[2])) - a,
             w = Vec3::of(m.point(t[3])) - a;
  const double det = 2 * det3(u, v, w);
  const Vec3 offset =
      (v.cross(w) * u.dot(u) + w.cross(u) * v.dot(v) + u.cross(v) * w.dot(w)) * (1 / det);
  centre = a + offset;
  radius2 = det != 0 ? offset.dot(offset) : kInfinity;
}

// The insertion's search directions, in the order tried: the axes, then the cube's diagonals.
const double kDiagonal = 1 / std::sqrt(3.0);
const Vec3 kCompassDirections[14] = {{1, 0, 0},
                                     {-1, 0, 0},
                                     {0, 1, 0},
                                     {0, -1, 0},
                                     {0, 0, 1},
                                     {0, 0, -1},
                                     {-kDiagonal, -kDiagonal, -kDiagonal},
                                     {kDiagonal, -kDiagonal, -kDiagonal},
                                     {-kDiagonal, kDiagonal, -kDiagonal},
                                     {kDiagonal, kDiagonal, -kDiagonal},
                                     {-kDiagonal, -kDiagonal, kDiagonal},
                                     {kDiagonal, -kDiagonal, kDiagonal},
                                     {-kDiagonal, kDiagonal, kDiagonal},
                                     {kDiagonal, kDiagonal, kDiagonal}};

// The best insertion at t, into one of three cavities (tets within t's region, none fixed):
// the tets whose circumspheres hold t's circumcentre, reached from t across faces (Bowyer and
// Watson's cavity, star-shaped from the centre where the tets are Delaunay); t and the tets
// across its faces; those and the tets across theirs. The new vertex moves by a compass search
// (the axes and the cube's diagonals, steps from a quarter of its distance to the nearest cavity
// vertex down to a hundredth) from the best of the circumcentre, t's centroid and the cavity's
// vertices' centroid, raising the worst new tet; then the same search lowers the new tets'
// deficit (the sum of `floor` - quality over those below `floor`), the worst kept above the
// cavity's. An insertion counts where it raises the worst and lowers the deficit or leaves at
// most one more tet below `floor`; the least deficit wins.
void best_insertion(FlipMesh& m, index_t t, double floor, Insertion& best) {
  const std::int32_t region = m.region(t);
  Vec3 t_centroid{0, 0, 0}, centre;
  for (index_t v : m.tet(t)) t_centroid = t_centroid + Vec3::of(m.point(v)) * 0.25;
  double radius2 = 0;
  circumsphere(m, m.tet(t), centre, radius2);
  const index_t p = m.add_vertex(t_centroid);
  std::vector<index_t> cavity;
  std::vector<Tet> made;
  for (int kind = 0; kind < 3; ++kind) {
    if (kind < 2) {  // the cavity anew (kind 2 grows kind 1's)
      m.clear_set();
      cavity = {t};
      m.put_in_set(t);
    }
    if (kind == 0) {
      if (!(radius2 < kInfinity)) continue;
      for (std::size_t i = 0; i < cavity.size(); ++i)
        for (int k = 0; k < 4; ++k) {
          const index_t w = m.across(cavity[i], k);
          if (w == NO_CELL || !m.movable(w, region) || m.in_set(w)) continue;
          Vec3 c;
          double r2 = 0;
          circumsphere(m, m.tet(w), c, r2);
          if ((centre - c).dot(centre - c) < r2) cavity.push_back(w), m.put_in_set(w);
        }
    } else {
      const std::size_t grown = cavity.size();
      for (std::size_t i = 0; i < grown; ++i)
        for (int k = 0; k < 4; ++k) {
          const index_t w = m.across(cavity[i], k);
          if (w != NO_CELL && m.movable(w, region) && !m.in_set(w))
            cavity.push_back(w), m.put_in_set(w);
        }
      if (cavity.size() == grown) continue;
    }
    if (!star_of_cavity(m, cavity, p, made)) continue;
    // The cavity's worst tet and its deficit.
    double before = kInfinity, deficit_before = 0;
    for (index_t u : cavity)
      before = std::min(before, m.quality(u)),
      deficit_before += std::max(0.0, floor - m.quality(u));
    // The search's tries mostly fail, most on the new tet that failed the try before: that tet
    // is asked first (`failed`). The values returned do not depend on it.
    std::size_t failed = 0;
    // The worst new tet with the vertex at q, or some value <= bound as soon as one is.
    const auto worst_at = [&](const Vec3& q, double bound) {
      m.place(p, q);
      if (const double first = m.quality(made[failed]); first <= bound) return first;
      double worst = kInfinity;
      for (std::size_t i = 0; i < made.size(); ++i)
        if ((worst = std::min(worst, m.quality(made[i]))) <= bound) {
          failed = i;
          break;
        }
      return worst;
    };
    // The new tets' deficit with the vertex at q, infinite where one is not above `before`
    // (or some value >= bound as soon as the sum reaches it; summed in the new tets' order).
    const auto deficit_at = [&](const Vec3& q, double bound) {
      m.place(p, q);
      if (!(m.quality(made[failed]) > before + 1e-12)) return kInfinity;
      double deficit = 0;
      for (std::size_t i = 0; i < made.size(); ++i) {
        const double value = m.quality(made[i]);
        if (!(value > before + 1e-12)) {
          failed = i;
          return kInfinity;
        }
        if ((deficit += std::max(0.0, floor - value)) >= bound) break;
      }
      return deficit;
    };
    Vec3 centroid{0, 0, 0};
    std::vector<index_t> corners;
    for (const Tet& n : made)
      for (index_t v : n)
        if (v != p) corners.push_back(v);
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    for (index_t v : corners) centroid = centroid + Vec3::of(m.point(v));
    centroid = centroid * (1.0 / static_cast<double>(corners.size()));
    Vec3 here = t_centroid;
    double quality = -kInfinity;
    for (const Vec3& start : {centre, t_centroid, centroid})
      if (const double q = worst_at(start, quality); q > quality) quality = q, here = start;
    // None of them in the cavity's kernel (a new tet turned over from each): not searched (it
    // found 4-6 % of the insertions on gmsh_as1-tu-203 and gmsh_918_pump at 50k, in 40-50 % of
    // the searches that failed).
    if (!(quality > 0)) continue;
    double nearest = kInfinity;
    for (index_t v : corners) nearest = std::min(nearest, (Vec3::of(m.point(v)) - here).norm());
    // A compass search that raises `value` (the worst tet, then minus the deficit).
    const auto search = [&](const auto& value, double& best_value) {
      for (double step = 0.25 * nearest; step > 1e-2 * nearest;) {
        bool better = false;
        for (const Vec3& direction : kCompassDirections) {
          const Vec3 q = here + direction * step;
          const double v = value(q, best_value + 1e-12);
          if (v > best_value + 1e-12) best_value = v, here = q, better = true;
        }
        if (!better) step *= 0.5;
      }
    };
    search(worst_at, quality);
    if (!(quality > std::max(before, 0.0) + 1e-12)) continue;
    double minus_deficit = -deficit_at(here, kInfinity);
    search([&](const Vec3& q, double bound) { return -deficit_at(q, -bound); }, minus_deficit);
    std::ptrdiff_t below = 0;
    for (index_t u : cavity) below += m.quality(u) < floor;
    m.place(p, here);
    for (const Tet& n : made) below -= m.quality(n) < floor;
    if (!(-minus_deficit < deficit_before - 1e-12) && below < -1) continue;
    // (Every new tet stays above the cavity's worst: deficit_at() has it.)
    if (-minus_deficit < best.deficit)
      best.deficit = -minus_deficit, best.point = here, best.old_tets = cavity,
      best.new_tets = made;
    if (best.deficit == 0) break;  // every new tet above the floor: no other cavity needed
  }
  m.remove_last_vertex();
}
}  // namespace

void remove_slivers(TetMesh& mesh, const std::vector<char>& fixed,
                    const std::vector<std::int32_t>& boundary_patch,
                    const RemoveSliversParameters& parameters, RemoveSliversReport& report,
                    RemoveSliversState* state) {
  if (!(parameters.target > 0 && parameters.target <= 1) || parameters.max_passes < 1 ||
      parameters.max_ring < 3 || parameters.max_ring > 10 ||
      !(parameters.max_boundary_shift >= 0) ||
      !(parameters.insert_below >= 0 && parameters.insert_below <= 1))
    throw InputError(
        "remove_slivers: target must be in (0, 1], max_passes >= 1, max_ring in [3, 10], "
        "max_boundary_shift >= 0, insert_below in [0, 1]",
        Entity::Parameter);
  if (!fixed.empty() && fixed.size() != mesh.nb_tets())
    throw InputError("remove_slivers: one fixed flag per tet", Entity::Parameter);
  if (!boundary_patch.empty() && boundary_patch.size() != 4 * std::size_t{mesh.nb_tets()})
    throw InputError("remove_slivers: four boundary patches per tet", Entity::Parameter);
  if (state != nullptr && !state->settled.empty() && state->settled.size() != mesh.nb_tets())
    throw InputError("remove_slivers: one settled flag per tet", Entity::Parameter);
  report = RemoveSliversReport{};
  FlipMesh m(mesh, fixed, boundary_patch, state != nullptr ? &state->settled : nullptr);
  auto summarise = [&](double& min, std::size_t& below) {
    min = kInfinity;
    for (index_t t = 0; t < m.nb_slots(); ++t)
      if (m.alive(t)) min = std::min(min, m.quality(t)), below += m.quality(t) < parameters.target;
  };
  summarise(report.min_before, report.below_before);

  std::vector<index_t> around, ring, work;
  bool closed = false;
  for (int pass = 0; pass < parameters.max_passes; ++pass) {
    work.clear();
    for (index_t t = 0; t < m.nb_slots(); ++t)
      if (m.alive(t) && !m.fixed(t) && m.quality(t) < parameters.target) work.push_back(t);
    // Worst first; ties by slot, so that the order depends on nothing but the tets in the list.
    std::sort(work.begin(), work.end(), [&](index_t a, index_t b) {
      return m.quality(a) < m.quality(b) || (m.quality(a) == m.quality(b) && a < b);
    });
    std::size_t flips = 0;
    for (index_t t : work) {
      // A tet whose surroundings did not change since it was last examined has no flip now
      // either (it may change before its turn: hence the test here, not in the list).
      if (!m.alive(t) || !m.changed_since_examined(t)) continue;
      m.examine(t);
      // The best flip that replaces t, better than the tets it replaces.
      Flip best;
      for (int i = 0; i < 4; ++i) best_face_removal(m, t, i, best);
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          const index_t a = m.tet(t)[i], b = m.tet(t)[j];
          if (!m.edge_ring(a, b, parameters.max_ring, around, ring, closed)) continue;
          if (!std::all_of(around.begin(), around.end(),
                           [&](index_t u) { return m.movable(u, m.region(t)); }))
            continue;
          if (!closed &&
              !swappable(m, a, b, ring.front(), ring.back(), parameters.max_boundary_shift))
            continue;
          // A lone tet on a boundary edge goes, its faces (c, d, a) and (c, d, b) becoming the
          // boundary: they must have tets across (else a node could be left in no tet).
          if (around.size() == 1 &&
              (m.across(around[0], i) == NO_CELL || m.across(around[0], j) == NO_CELL))
            continue;
          const double before = best.quality;
          best_edge_removal(m, a, b, around, ring, best);
          if (!closed && best.quality > before)
            best.boundary_swap = {a, b, ring.front(), ring.back()};
        }
      double replaced = kInfinity;
      for (index_t u : best.old_tets) replaced = std::min(replaced, m.quality(u));
      // Never an inverted or flat tet, even in place of one.
      if (best.old_tets.empty() || !(best.quality > std::max(replaced, 0.0) + 1e-12)) continue;
      const std::int32_t region = m.region(t);
      for (index_t u : best.old_tets) m.remove(u);
      for (const Tet& n : best.new_tets) m.add(n, region);
      const auto [a, b, c, d] = best.boundary_swap;
      if (a != NO_VERTEX) {
        const std::int32_t patch = m.patch(a, b, c);
        m.clear_patch(a, b, c);
        m.clear_patch(a, b, d);
        m.set_patch(c, d, a, patch);
        m.set_patch(c, d, b, patch);
        ++report.boundary_swaps;
      }
      // Face removal replaces two tets by three; edge removal n by 2n - 4 (2n - 2 on the boundary).
      ++(best.new_tets.size() == 3 && best.old_tets.size() == 2 ? report.face_removals
                                                                : report.edge_removals);
      ++flips;
    }
    // Once the flips are done (or on the last pass), the tets no flip improved get a vertex
    // each where that helps (insert_below), and the flips go on around the new vertices.
    if (flips > 0 && pass + 1 < parameters.max_passes) continue;
    std::size_t inserted = 0;
    for (index_t t : work) {  // worst first
      if (!m.alive(t) || !(m.quality(t) < parameters.insert_below) || !m.changed_since_tried(t))
        continue;
      m.try_insertion(t);
      Insertion insertion;
      best_insertion(m, t, parameters.insert_below, insertion);
      if (insertion.old_tets.empty()) continue;  // none raises the cavity's worst
      const std::int32_t region = m.region(t);
      m.add_vertex(insertion.point);
      for (index_t u : insertion.old_tets) m.remove(u);
      for (const Tet& n : insertion.new_tets) m.add(n, region);
      ++inserted;
    }
    report.insertions += inserted;
    if (inserted == 0) break;
  }
  summarise(report.min_after, report.below_after);
  m.write(mesh, state);
}

}  // namespace hexmerge
