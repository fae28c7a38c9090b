#include "hexmerge/occ/mesher/surface_unfold.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hexmerge/occ/mesher/outline_cdt.h"
#include "hexmerge/occ/mesher/surface_check.h"

namespace hexmerge::mesher {
namespace {

using cgal2::Cdt;
using cgal2::Kernel;
using cgal2::mark_inside;

// A new triangle may turn from the patch's normal by less than this (degrees): the patch lies on
// one side of its plane, as a graph over it.
constexpr double kMostTurn = 80.0;
// And its smallest angle is at least this (degrees): not flat.
constexpr double kLeastAngle = 1e-3;

// Two triangles of one face fold on their common side when their normals are further apart
// than this (degrees): they lie almost on each other. (A face's triangles turn by at most
// about 90 degrees where the face is smooth: BRepMesh's angular deflection.)
constexpr double kFoldTurn = 150.0;

// Whether triangles with normals a and b fold on a common side.
bool folds(const Vec3& a, const Vec3& b) {
  return a.dot(b) < std::cos(kFoldTurn * M_PI / 180) * a.norm() * b.norm();
}

// The pairs of triangles of one face that fold on their common side (which the crossing test
// takes for no crossing); `face` < 0: every face's.
std::vector<std::array<int, 2>> folded_sides(const Surface& surface, int face) {
  const std::vector<SurfaceTriangle>& tris = surface.triangles;
  std::unordered_map<std::uint64_t, std::vector<int>> at_side;
  for (std::size_t ti = 0; ti < tris.size(); ++ti)
    if (face < 0 || tris[ti].face == face)
      for (int c = 0; c < 3; ++c) at_side[side_key(tris[ti], c)].push_back(static_cast<int>(ti));
  std::vector<std::array<int, 2>> out;
  for (const auto& [key, two] : at_side) {
    (void)key;
    if (two.size() != 2) continue;
    const SurfaceTriangle& a = tris[static_cast<std::size_t>(two[0])];
    const SurfaceTriangle& b = tris[static_cast<std::size_t>(two[1])];
    if (a.face == b.face && folds(normal_of(surface.nodes, a.node[0], a.node[1], a.node[2]),
                                  normal_of(surface.nodes, b.node[0], b.node[1], b.node[2])))
      out.push_back({two[0], two[1]});
  }
  return out;
}

// Per triangle of the surface, whether it is folded: a triangle of `face` that crosses another
// of its face, or one of a pair of folded_sides().
std::vector<char> folded_triangles(const Surface& surface, int face) {
  const std::vector<SurfaceTriangle>& tris = surface.triangles;
  std::vector<char> folded(tris.size(), 0);
  for (const auto& pair : folded_sides(surface, face))
    folded[static_cast<std::size_t>(pair[0])] = folded[static_cast<std::size_t>(pair[1])] = 1;
  std::vector<int> own;
  std::vector<std::array<int, 3>> corners;
  for (std::size_t ti = 0; ti < tris.size(); ++ti)
    if (tris[ti].face == face)
      own.push_back(static_cast<int>(ti)), corners.push_back(tris[ti].node);
  const std::vector<char> crossing = crosses_any(surface.nodes, corners, corners);
  for (std::size_t i = 0; i < own.size(); ++i)
    if (crossing[i]) folded[static_cast<std::size_t>(own[i])] = 1;
  return folded;
}

// The triangles replacing the patch `region` (triangle indices, all of one face), or none (see
// unfold_faces()). `folded`: per triangle of the surface, folded_triangles()' answer.
std::optional<std::vector<SurfaceTriangle>> triangulate_patch(const Surface& surface,
                                                              const std::vector<int>& region,
                                                              const std::vector<char>& folded) {
  const std::vector<SurfaceTriangle>& tris = surface.triangles;
  const int face = tris[static_cast<std::size_t>(region.front())].face;
  // Sides by their nodes: how often the patch uses each, and the first use's direction.
  std::map<std::pair<int, int>, std::pair<int, std::pair<int, int>>> sides;
  std::unordered_map<int, UV> uv;
  Vec3 normal{0, 0, 0};
  for (const int ti : region) {
    const SurfaceTriangle& t = tris[static_cast<std::size_t>(ti)];
    for (int c = 0; c < 3; ++c) {
      const int a = t.node[c], b = t.node[(c + 1) % 3];
      auto& entry = sides[std::minmax(a, b)];
      if (entry.first++ == 0) entry.second = {a, b};
      uv.emplace(t.node[c], t.uv[c]);
    }
    if (!folded[static_cast<std::size_t>(ti)])
      normal = normal + normal_of(surface.nodes, t.node[0], t.node[1], t.node[2]);
  }
  const double length = normal.norm();
  if (!(length > 0)) return std::nullopt;
  normal = normal * (1 / length);
  // The outline (sides used once) as one loop; sides used twice inside; none more often.
  std::unordered_map<int, int> next;
  std::vector<std::pair<int, int>> inner_segments;  // CAD edges' segments inside: kept
  for (const auto& [key, entry] : sides) {
    if (entry.first > 2) return std::nullopt;
    if (entry.first == 2) {
      if (surface.segments.count(pair_key(key.first, key.second))) inner_segments.push_back(key);
      continue;
    }
    if (!next.emplace(entry.second.first, entry.second.second).second) return std::nullopt;
  }
  if (next.size() < 3) return std::nullopt;
  std::vector<int> loop{next.begin()->first};
  while (true) {
    const auto it = next.find(loop.back());
    if (it == next.end()) return std::nullopt;
    if (it->second == loop.front()) break;
    if (loop.size() > next.size()) return std::nullopt;
    loop.push_back(it->second);
  }
  if (loop.size() != next.size()) return std::nullopt;  // more than one loop: not a disk
  // The plane across the normal: the loop must be simple there, turning counter-clockwise.
  Vec3 e1 = std::abs(normal.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  e1 = e1 - normal * e1.dot(normal);
  e1 = e1 * (1 / e1.norm());
  const Vec3 e2 = normal.cross(e1);
  const auto flat = [&](int n) {
    const Vec3& p = surface.nodes[static_cast<std::size_t>(n)];
    return Kernel::Point_2(p.dot(e1), p.dot(e2));
  };
  double area = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Kernel::Point_2 p = flat(loop[i]), q = flat(loop[(i + 1) % loop.size()]);
    area += p.x() * q.y() - q.x() * p.y();
  }
  if (!(area > 0)) return std::nullopt;
  // Every node of the patch stays: its triangles are made again on them.
  std::vector<int> kept = loop;
  for (const auto& [n, at] : uv) {
    (void)at;
    if (!next.count(n)) kept.push_back(n);
  }
  Cdt cdt;
  std::unordered_map<int, Cdt::Vertex_handle> handle;
  for (const int n : kept) {
    if (handle.count(n)) continue;  // an inner segment's node on the loop
    handle[n] = cdt.insert(flat(n));
    handle[n]->info() = n;
  }
  if (cdt.number_of_vertices() != handle.size()) return std::nullopt;  // two at one place
  std::set<std::pair<int, int>> outline;
  try {
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      cdt.insert_constraint(handle[a], handle[b]);
      outline.insert(std::minmax(a, b));
    }
    for (const auto& [a, b] : inner_segments) cdt.insert_constraint(handle[a], handle[b]);
  } catch (const Cdt::Intersection_of_constraints_exception&) {
    return std::nullopt;  // the loop crosses itself there, or a segment crosses it
  }
  if (cdt.number_of_vertices() != handle.size()) return std::nullopt;
  // Inside: reached from outside across an odd number of the outline's sides.
  if (!mark_inside(cdt, outline)) return std::nullopt;  // the outline bounds no region
  std::vector<SurfaceTriangle> patch;
  const double most_turn = std::cos(kMostTurn * M_PI / 180);
  for (Cdt::Face_handle f : cdt.finite_face_handles()) {
    if (f->info() != 1) continue;
    SurfaceTriangle t;
    t.face = face;
    for (int k = 0; k < 3; ++k) {
      t.node[k] = f->vertex(k)->info();
      t.uv[k] = uv.at(t.node[k]);
    }
    const Vec3 n = normal_of(surface.nodes, t.node[0], t.node[1], t.node[2]);
    if (!(n.dot(normal) > most_turn * n.norm()) ||
        smallest_angle(surface.nodes, t.node) < kLeastAngle * M_PI / 180)
      return std::nullopt;
    patch.push_back(t);
  }
  if (patch.empty()) return std::nullopt;
  // No fold on a side of the new triangles, among them or with the face's triangles around.
  std::unordered_map<std::uint64_t, std::vector<Vec3>> normals_at;
  const auto add_normals = [&](const SurfaceTriangle& t) {
    for (int c = 0; c < 3; ++c)
      normals_at[side_key(t, c)].push_back(
          normal_of(surface.nodes, t.node[0], t.node[1], t.node[2]));
  };
  for (const SurfaceTriangle& t : patch) add_normals(t);
  std::set<int> in_patch(region.begin(), region.end());
  for (std::size_t ti = 0; ti < tris.size(); ++ti)
    if (tris[ti].face == face && !in_patch.count(static_cast<int>(ti)))
      for (int c = 0; c < 3; ++c)
        if (outline.count(std::minmax(tris[ti].node[c], tris[ti].node[(c + 1) % 3])))
          add_normals(tris[ti]);
  for (const auto& [key, normals] : normals_at) {
    (void)key;
    if (normals.size() == 2 && folds(normals[0], normals[1])) return std::nullopt;
  }
  // No new triangle crosses the surface outside the patch (the triangles whose boxes meet the
  // patch's: one scan, then the exact test on those only).
  std::vector<char> in_region(tris.size(), 0);
  for (const int ti : region) in_region[static_cast<std::size_t>(ti)] = 1;
  std::vector<std::array<int, 3>> others, made;
  Vec3 lo = surface.nodes[static_cast<std::size_t>(loop.front())], hi = lo;
  for (const SurfaceTriangle& t : patch) {
    made.push_back(t.node);
    for (const int n : t.node)
      lo = vmin(lo, surface.nodes[static_cast<std::size_t>(n)]),
      hi = vmax(hi, surface.nodes[static_cast<std::size_t>(n)]);
  }
  for (std::size_t ti = 0; ti < tris.size(); ++ti) {
    if (in_region[ti]) continue;
    Vec3 a = surface.nodes[static_cast<std::size_t>(tris[ti].node[0])], b = a;
    for (const int n : tris[ti].node)
      a = vmin(a, surface.nodes[static_cast<std::size_t>(n)]),
      b = vmax(b, surface.nodes[static_cast<std::size_t>(n)]);
    if (a.x <= hi.x && a.y <= hi.y && a.z <= hi.z && lo.x <= b.x && lo.y <= b.y && lo.z <= b.z)
      others.push_back(tris[ti].node);
  }
  const std::vector<char> crossing =
      others.empty() ? std::vector<char>() : crosses_any(surface.nodes, others, made);
  if (std::any_of(crossing.begin(), crossing.end(), [](char c) { return c != 0; }))
    return std::nullopt;
  return patch;
}

}  // namespace

UnfoldReport unfold_faces(Surface& surface) {
  UnfoldReport report;
  std::vector<SurfaceTriangle>& tris = surface.triangles;
  // The faces whose own triangles cross (find_crossings() gives one pair per pair of faces) or
  // fold on a common side.
  std::set<int> faces;
  for (const Crossing& c : find_crossings(surface.nodes, tris))
    if (tris[static_cast<std::size_t>(c.first)].face ==
        tris[static_cast<std::size_t>(c.second)].face)
      faces.insert(tris[static_cast<std::size_t>(c.first)].face);
  for (const auto& pair : folded_sides(surface, -1))
    faces.insert(tris[static_cast<std::size_t>(pair[0])].face);
  if (faces.empty()) return report;
  for (const int face : faces) {
    // One fold at a time, its face's crossings found again after each: a patch may take in
    // another fold.
    // Folds left as they are, by their crossing triangles' sorted nodes (the triangles are
    // renumbered as patches replace theirs; the nodes stay until the end).
    std::set<std::array<int, 3>> given_up;
    // Each patch taken leaves fewer folded triangles (none of its own folds or crosses); a
    // bound all the same.
    std::size_t rounds = 0;
    const auto key = [&](int ti) {
      std::array<int, 3> n = tris[static_cast<std::size_t>(ti)].node;
      std::sort(n.begin(), n.end());
      return n;
    };
    while (true) {
      std::vector<int> own;
      for (std::size_t ti = 0; ti < tris.size(); ++ti)
        if (tris[ti].face == face) own.push_back(static_cast<int>(ti));
      const std::vector<char> folded = folded_triangles(surface, face);
      // The fold: the first folded triangle not given up, and the folded triangles joined to it
      // by their nodes.
      int seed = -1;
      for (const int ti : own)
        if (seed < 0 && folded[static_cast<std::size_t>(ti)] && !given_up.count(key(ti))) seed = ti;
      if (seed < 0 || ++rounds > tris.size()) break;
      std::vector<int> region{seed};
      std::set<int> members{seed};
      std::set<int> nodes(tris[static_cast<std::size_t>(seed)].node.begin(),
                          tris[static_cast<std::size_t>(seed)].node.end());
      const auto grow = [&](bool only_folded) {
        bool added = true;
        while (added) {
          added = false;
          for (const int ti : own) {
            if (members.count(ti) || (only_folded && !folded[static_cast<std::size_t>(ti)]))
              continue;
            const auto& n = tris[static_cast<std::size_t>(ti)].node;
            if (!nodes.count(n[0]) && !nodes.count(n[1]) && !nodes.count(n[2])) continue;
            members.insert(ti), region.push_back(ti);
            nodes.insert(n.begin(), n.end());
            // The folded ones to a fixed point; else one pass over the face's triangles (those
            // touching a node taken in during the pass come in too: a ring or a little more).
            added = only_folded;
          }
        }
      };
      grow(true);
      std::optional<std::vector<SurfaceTriangle>> patch;
      for (int ring = 1; ring <= kUnfoldRings && !patch; ++ring) {
        grow(false);
        patch = triangulate_patch(surface, region, folded);
      }
      if (!patch) {
        for (const int ti : region)
          if (folded[static_cast<std::size_t>(ti)]) given_up.insert(key(ti));
        ++report.failed;
        continue;
      }
      // The patch's triangles replaced (in place, then appended; the dead ones taken out).
      std::sort(region.begin(), region.end());
      std::vector<char> dead(tris.size(), 0);
      std::size_t k = 0;
      for (const int ti : region) {
        if (k < (*patch).size()) {
          tris[static_cast<std::size_t>(ti)] = (*patch)[k++];
        } else {
          dead[static_cast<std::size_t>(ti)] = 1;
        }
      }
      for (; k < (*patch).size(); ++k) tris.push_back((*patch)[k]);
      dead.resize(tris.size(), 0);
      std::size_t w = 0;
      for (std::size_t ti = 0; ti < tris.size(); ++ti)
        if (!dead[ti]) tris[w++] = tris[ti];
      tris.resize(w);
      ++report.patches;
    }
  }
  return report;
}

}  // namespace hexmerge::mesher
