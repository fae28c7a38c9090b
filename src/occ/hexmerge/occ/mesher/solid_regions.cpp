#include "hexmerge/occ/mesher/solid_regions.h"

#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/mesher/common.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/occ/regions_by_solid.h"

namespace hexmerge::mesher {
namespace {

index_t find(std::vector<index_t>& parent, index_t t) {
  while (parent[t] != t) t = parent[t] = parent[parent[t]];
  return t;
}

// Per tet, the root of its component: tets joined through every face between two tets that is
// none of the triangles; touch(t, i) for each face of tet t that is triangle i.
template <typename Touch>
std::vector<index_t> components(const TetMesh& mesh,
                                const std::vector<std::array<index_t, 3>>& triangles,
                                Touch&& touch) {
  std::unordered_map<FaceKey, std::size_t, FaceKeyHash> on_face;
  on_face.reserve(triangles.size());
  // Only a face whose three vertices are the triangles' can be one (most faces have a vertex
  // inside: no look-up for them).
  std::vector<char> on_triangle(mesh.nb_vertices(), 0);
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    on_face.emplace(face_key(triangles[i][0], triangles[i][1], triangles[i][2]), i);
    for (const index_t v : triangles[i]) on_triangle[v] = 1;
  }
  const index_t nb_tets = mesh.nb_tets();
  const TetTopology topology(mesh);
  std::vector<index_t> parent(nb_tets);
  std::iota(parent.begin(), parent.end(), index_t{0});
  for (index_t t = 0; t < nb_tets; ++t) {
    const index_t* v = mesh.tet(t);
    for (int f = 0; f < 4; ++f) {
      const index_t a = v[(f + 1) % 4], b = v[(f + 2) % 4], c = v[(f + 3) % 4];
      const auto face = on_triangle[a] && on_triangle[b] && on_triangle[c]
                            ? on_face.find(face_key(a, b, c))
                            : on_face.end();
      if (face != on_face.end()) {
        touch(t, face->second);
      } else if (topology.neighbor(t, f) != NO_CELL) {
        parent[find(parent, t)] = find(parent, topology.neighbor(t, f));
      }
    }
  }
  for (index_t t = 0; t < nb_tets; ++t) parent[t] = find(parent, t);
  return parent;
}

}  // namespace

std::optional<std::vector<std::int32_t>> solid_regions(
    const Shape& shape, const TetMesh& mesh, const std::vector<std::array<index_t, 3>>& triangles,
    const std::vector<int>& markers) {
  const index_t nb_tets = mesh.nb_tets();
  const int nb_faces = shape.faces.Extent();
  // Per face, the solids it bounds (by index into shape.solids; -1: none, one or two).
  std::vector<std::pair<std::int32_t, std::int32_t>> owners(static_cast<std::size_t>(nb_faces),
                                                            {-1, -1});
  for (int s = 1; s <= shape.solids.Extent(); ++s) {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape.solids(s), TopAbs_FACE, faces);
    for (int f = 1; f <= faces.Extent(); ++f) {
      const int i = shape.faces.FindIndex(faces(f));
      if (i <= 0) continue;
      auto& [a, b] = owners[static_cast<std::size_t>(i - 1)];
      (a < 0 ? a : b) = s - 1;
    }
  }
  // The faces' triangles stop the flood; every other face between two tets joins them.
  for (const int marker : markers)
    if (marker < 1 || marker > nb_faces) return std::nullopt;
  std::vector<std::pair<index_t, int>> touching;  // (tet, the face one of its faces lies on)
  std::vector<index_t> parent = components(
      mesh, triangles, [&](index_t t, std::size_t i) { touching.emplace_back(t, markers[i] - 1); });
  // Per component, the solids every face it touches bounds: the first face's owners, less
  // those a later face does not name (-2: no face met yet).
  std::vector<std::pair<std::int32_t, std::int32_t>> common(nb_tets, {-2, -2});
  for (const auto& [t, face] : touching) {
    const auto [a, b] = owners[static_cast<std::size_t>(face)];
    auto& [x, y] = common[find(parent, t)];
    if (x == -2) {
      x = a, y = b;
      continue;
    }
    if (x != a && x != b) x = -1;
    if (y != a && y != b) y = -1;
    if (x < 0) std::swap(x, y);
  }
  std::vector<std::int32_t> region(nb_tets);
  for (index_t t = 0; t < nb_tets; ++t) {
    const auto [x, y] = common[find(parent, t)];
    // One solid: not none, not a component on no face, not two solids bounded by the same faces.
    if (x < 0 || y >= 0) return std::nullopt;
    region[t] = x;
  }
  return region;
}

std::size_t remove_outside_components(TetMesh& mesh,
                                      const std::vector<std::array<index_t, 3>>& triangles,
                                      const std::function<bool(const Vec3&)>& inside) {
  const index_t nb_tets = mesh.nb_tets();
  const std::vector<index_t> root = components(mesh, triangles, [](index_t, std::size_t) {});
  const auto corner = [&](index_t t, int k) { return Vec3::of(&mesh.points[3 * mesh.tet(t)[k]]); };
  // Per component (by its root tet), its largest tet (whose centroid lies furthest inside it,
  // near no face).
  std::vector<double> most(nb_tets, -1.0);
  std::vector<index_t> largest(nb_tets, 0);
  for (index_t t = 0; t < nb_tets; ++t) {
    const Vec3 a = corner(t, 0);
    const double volume = std::abs(det3(corner(t, 1) - a, corner(t, 2) - a, corner(t, 3) - a));
    if (volume > most[root[t]]) most[root[t]] = volume, largest[root[t]] = t;
  }
  std::vector<char> keep(nb_tets, 0);
  for (index_t r = 0; r < nb_tets; ++r) {
    if (root[r] != r) continue;
    const index_t t = largest[r];
    keep[r] = inside((corner(t, 0) + corner(t, 1) + corner(t, 2) + corner(t, 3)) * 0.25);
  }
  index_t kept = 0;
  for (index_t t = 0; t < nb_tets; ++t) {
    if (!keep[root[t]]) continue;
    if (kept != t)
      std::copy_n(mesh.tet(t), 4, mesh.tets.begin() + 4 * static_cast<std::ptrdiff_t>(kept));
    if (!mesh.regions.empty()) mesh.regions[kept] = mesh.regions[t];
    ++kept;
  }
  mesh.tets.resize(4 * kept);
  if (!mesh.regions.empty()) mesh.regions.resize(kept);
  return nb_tets - kept;
}

TetMesh world_mesh(const std::string& brep, const Shape& shape, const Surface& surface,
                   const Frame& frame, const tetgen::TetrahedralizeOutput& tets) {
  const std::vector<double>& frame_points = tets.points;
  const std::size_t made = frame_points.size() / 3;
  TetMesh mesh;
  mesh.tets = tets.tets;
  // Orientation: positive volume in frame coordinates is positive in the world (proper frame).
  for (std::size_t t = 0; t < mesh.tets.size() / 4; ++t) {
    index_t* v = &mesh.tets[4 * t];
    const Vec3 p0 = Vec3::of(&frame_points[3 * v[0]]);
    const double d =
        det3(Vec3::of(&frame_points[3 * v[1]]) - p0, Vec3::of(&frame_points[3 * v[2]]) - p0,
             Vec3::of(&frame_points[3 * v[3]]) - p0);
    if (d < 0) std::swap(v[1], v[2]);
  }
  mesh.points.resize(frame_points.size());
  for (std::size_t i = 0; i < made; ++i) {
    const Vec3 p = frame.to_world(Vec3::of(&frame_points[3 * i]));
    mesh.points[3 * i] = p.x, mesh.points[3 * i + 1] = p.y, mesh.points[3 * i + 2] = p.z;
  }
  // The surface nodes keep their exact CAD positions.
  for (std::size_t i = 0; i < surface.nodes.size() && i < made; ++i) {
    mesh.points[3 * i] = surface.nodes[i].x, mesh.points[3 * i + 1] = surface.nodes[i].y,
                    mesh.points[3 * i + 2] = surface.nodes[i].z;
  }
  if (shape.solids.Extent() > 1) {
    // From the triangles TetGen kept on the faces; by geometry where they do not separate the
    // solids (they always do when TetGen recovered every face).
    std::optional<std::vector<std::int32_t>> regions =
        solid_regions(shape, mesh, tets.boundary, tets.boundary_marker);
    mesh.regions = regions ? std::move(*regions) : regions_by_solid(brep, mesh);
  } else
    mesh.regions.assign(mesh.tets.size() / 4, 0);
  return mesh;
}

double tets_volume(const std::vector<double>& points, const std::vector<index_t>& tets) {
  double volume = 0;
  for (std::size_t k = 0; k < tets.size(); k += 4)
    volume += std::abs(
        tet_volume(&points[3 * std::size_t{tets[k]}], &points[3 * std::size_t{tets[k + 1]}],
                   &points[3 * std::size_t{tets[k + 2]}], &points[3 * std::size_t{tets[k + 3]}]));
  return volume;
}

}  // namespace hexmerge::mesher
