#pragma once
/// @file
/// Spatial queries of the mesher (internal header of mesh_shape(); no OpenCASCADE): points and
/// triangles in a uniform grid of cubic buckets, "is there one within r of q"; nodes in a sparse
/// grid, "which node is within r of q".

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "hexmerge/geometry/triangle_distance.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {

/// Nodes (indices into the caller's vector, which may grow) in a sparse grid of cubic cells of
/// side `cell`: "a node within `tolerance` of p", for tolerances up to the cell's side.
class NodeHash {
 public:
  NodeHash(const std::vector<Vec3>& nodes, double cell) : nodes_(nodes), cell_(cell) {}
  void add(int n) {
    const std::array<long long, 3> c = cell_of(nodes_[n]);
    cells_[hash(c[0], c[1], c[2])].push_back(n);
  }
  /// The first node found within `tolerance` (at most the cell's side) of p, or -1.
  int find(const Vec3& p, double tolerance) const {
    return find_if(p, tolerance, [](int) { return true; });
  }
  /// Calls f(n) for every node n within `tolerance` (at most the cell's side) of p.
  template <class F>
  void for_each_within(const Vec3& p, double tolerance, const F& f) const {
    find_if(p, tolerance, [&](int n) {
      f(n);
      return false;
    });
  }
  /// The same, among the nodes n for which `wanted(n)` holds.
  template <class Wanted>
  int find_if(const Vec3& p, double tolerance, const Wanted& wanted) const {
    // The cells around p's that a node within `tolerance` can lie in (the ball's box, widened to
    // twice the tolerance against rounding), in the order of the whole 3 x 3 x 3 block: the same
    // nodes, met in the same order, as over the whole block.
    const std::array<long long, 3> c = cell_of(p);
    const Vec3 reach{2 * tolerance, 2 * tolerance, 2 * tolerance};
    const std::array<long long, 3> lo = cell_of(p - reach), hi = cell_of(p + reach);
    for (long long i = std::max(c[0] - 1, lo[0]); i <= std::min(c[0] + 1, hi[0]); ++i)
      for (long long j = std::max(c[1] - 1, lo[1]); j <= std::min(c[1] + 1, hi[1]); ++j)
        for (long long k = std::max(c[2] - 1, lo[2]); k <= std::min(c[2] + 1, hi[2]); ++k) {
          const auto it = cells_.find(hash(i, j, k));
          if (it == cells_.end()) continue;
          for (int n : it->second)
            if ((nodes_[n] - p).norm() <= tolerance && wanted(n)) return n;
        }
    return -1;
  }

 private:
  std::array<long long, 3> cell_of(const Vec3& p) const {
    return {static_cast<long long>(std::floor(p.x / cell_)),
            static_cast<long long>(std::floor(p.y / cell_)),
            static_cast<long long>(std::floor(p.z / cell_))};
  }
  static std::uint64_t hash(long long i, long long j, long long k) {
    return static_cast<std::uint64_t>(i) * 73856093ULL ^
           static_cast<std::uint64_t>(j) * 19349663ULL ^
           static_cast<std::uint64_t>(k) * 83492791ULL;
  }
  const std::vector<Vec3>& nodes_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

/// Items (ints) filed under every bucket their bounding box overlaps, in a grid of cubic
/// buckets of side `cell` over the box [lo, hi] (points outside go to the nearest bucket).
class BucketGrid {
 public:
  BucketGrid(const Vec3& lo, const Vec3& hi, double cell) : lo_(lo), cell_(cell) {
    for (int a = 0; a < 3; ++a) {
      const double extent = (a == 0 ? hi.x - lo.x : a == 1 ? hi.y - lo.y : hi.z - lo.z);
      n_[a] = std::max(1, static_cast<int>(std::ceil(extent / cell)) + 1);
    }
    slot_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], 0);
  }
  // Adds item to every bucket the box [a, b] overlaps.
  void add(int item, const Vec3& a, const Vec3& b) {
    std::array<int, 3> i0 = coords(a), i1 = coords(b);
    for (int i = i0[0]; i <= i1[0]; ++i)
      for (int j = i0[1]; j <= i1[1]; ++j)
        for (int k = i0[2]; k <= i1[2]; ++k) {
          std::int32_t& slot = slot_[index(i, j, k)];
          if (slot == 0) {
            lists_.emplace_back();
            slot = static_cast<std::int32_t>(lists_.size());
          }
          lists_[static_cast<std::size_t>(slot - 1)].push_back(item);
        }
  }
  // Calls f(item) for the items of the buckets the box [a, b] overlaps (an item may come twice);
  // stops when f returns true, and returns whether it did.
  template <typename F>
  bool any_in(const Vec3& a, const Vec3& b, F&& f) const {
    std::array<int, 3> i0 = coords(a), i1 = coords(b);
    for (int i = i0[0]; i <= i1[0]; ++i)
      for (int j = i0[1]; j <= i1[1]; ++j)
        for (int k = i0[2]; k <= i1[2]; ++k) {
          const std::int32_t slot = slot_[index(i, j, k)];
          if (slot == 0) continue;
          for (int item : lists_[static_cast<std::size_t>(slot - 1)])
            if (f(item)) return true;
        }
    return false;
  }

 private:
  std::array<int, 3> coords(const Vec3& p) const {
    const double c[3] = {(p.x - lo_.x) / cell_, (p.y - lo_.y) / cell_, (p.z - lo_.z) / cell_};
    std::array<int, 3> out{};
    for (int a = 0; a < 3; ++a)
      out[a] = std::clamp(static_cast<int>(std::floor(c[a])), 0, n_[a] - 1);
    return out;
  }
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(i) * n_[1] + j) * n_[2] + k;
  }
  Vec3 lo_;
  double cell_;
  std::array<int, 3> n_{};
  // Per bucket, 1 + the index of its list in lists_, 0 while it is empty: most buckets of a
  // grid over a part's box stay empty, and 4 bytes each cost less to make than an empty list.
  std::vector<std::int32_t> slot_;
  std::vector<std::vector<int>> lists_;
};

using hexmerge::squared_distance_to_triangle;  // geometry/triangle_distance.h

/// Points, with "is there one within r of q" queries.
class PointSet {
 public:
  PointSet(const Vec3& lo, const Vec3& hi, double cell) : grid_(lo, hi, cell) {}
  void add(const Vec3& p) {
    grid_.add(static_cast<int>(points_.size()), p, p);
    points_.push_back(p);
  }
  bool any_within(const Vec3& q, double r) const {
    const Vec3 d{r, r, r};
    return grid_.any_in(q - d, q + d, [&](int i) { return (points_[i] - q).norm() < r; });
  }
  /// Whether one for which `counts(point)` holds is within r of q.
  template <typename Counts>
  bool any_within(const Vec3& q, double r, Counts&& counts) const {
    const Vec3 d{r, r, r};
    return grid_.any_in(q - d, q + d,
                        [&](int i) { return (points_[i] - q).norm() < r && counts(points_[i]); });
  }

 private:
  BucketGrid grid_;
  std::vector<Vec3> points_;
};

/// Whether q lies in tet abcd: each of its barycentric coordinates at least `least` (negative:
/// on and a little beyond its faces too); never in a flat tet.
inline bool in_tet(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                   double least) {
  const double whole = det3(b - a, c - a, d - a);
  if (whole == 0) return false;
  const double l[4] = {det3(b - q, c - q, d - q) / whole, det3(q - a, c - a, d - a) / whole,
                       det3(b - a, q - a, d - a) / whole, det3(b - a, c - a, q - a) / whole};
  return l[0] >= least && l[1] >= least && l[2] >= least && l[3] >= least;
}

/// Tets (by their corners), with "does one hold q or lie near it" queries.
class TetSet {
 public:
  TetSet(const Vec3& lo, const Vec3& hi, double cell) : grid_(lo, hi, cell) {}
  void add(const std::array<Vec3, 4>& t) {
    grid_.add(static_cast<int>(tets_.size()), vmin(vmin(t[0], t[1]), vmin(t[2], t[3])),
              vmax(vmax(t[0], t[1]), vmax(t[2], t[3])));
    tets_.push_back(t);
  }
  /// Whether q lies in one or nearer than r to one.
  bool near(const Vec3& q, double r) const {
    const Vec3 d{r, r, r};
    return grid_.any_in(q - d, q + d, [&](int i) {
      const std::array<Vec3, 4>& t = tets_[static_cast<std::size_t>(i)];
      if (in_tet(q, t[0], t[1], t[2], t[3], 0)) return true;
      for (int k = 0; k < 4; ++k)
        if (squared_distance_to_triangle(q, t[(k + 1) % 4], t[(k + 2) % 4], t[(k + 3) % 4]) < r * r)
          return true;
      return false;
    });
  }

 private:
  BucketGrid grid_;
  std::vector<std::array<Vec3, 4>> tets_;
};

/// Triangles (of nodes the caller keeps alive), with "is one nearer than r to q" queries.
class TriangleSet {
 public:
  TriangleSet(const std::vector<Vec3>& nodes, const Vec3& lo, const Vec3& hi, double cell)
      : nodes_(nodes), grid_(lo, hi, cell) {}
  void add(const std::array<int, 3>& t) {
    const Vec3 &a = nodes_[t[0]], &b = nodes_[t[1]], &c = nodes_[t[2]];
    const Vec3 lo = vmin(a, vmin(b, c)), hi = vmax(a, vmax(b, c));
    grid_.add(static_cast<int>(tris_.size()), lo, hi);
    tris_.push_back(t);
    boxes_.push_back({lo, hi});
  }
  bool any_within(const Vec3& q, double r) const {
    return any_within(q, r, [](int) { return true; });
  }
  /// Whether one for which `counts(index)` holds (its index in the order added) is within r of q.
  template <typename Counts>
  bool any_within(const Vec3& q, double r, Counts&& counts) const {
    const Vec3 d{r, r, r};
    // A triangle's box farther than r from q (by more than the distance's rounding, 1e-9 of the
    // coordinates' size) holds no point within r: the distance to the triangle is not computed.
    const double reach =
        r + 1e-9 * (std::max({std::abs(q.x), std::abs(q.y), std::abs(q.z)}) + std::abs(r));
    return grid_.any_in(q - d, q + d, [&](int i) {
      const auto& t = tris_[i];
      if (!counts(i)) return false;
      const std::array<Vec3, 2>& box = boxes_[i];
      const Vec3 out = vmax(vmax(box[0] - q, q - box[1]), Vec3{0, 0, 0});
      return out.dot(out) <= reach * reach &&
             squared_distance_to_triangle(q, nodes_[t[0]], nodes_[t[1]], nodes_[t[2]]) < r * r;
    });
  }

 private:
  const std::vector<Vec3>& nodes_;
  BucketGrid grid_;
  std::vector<std::array<int, 3>> tris_;
  std::vector<std::array<Vec3, 2>> boxes_;  // per triangle, its bounding box
};

}  // namespace hexmerge::mesher
