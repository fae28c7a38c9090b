#include "hexmerge/occ/mesher/layers.h"

#include <cmath>
#include <utility>

#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {
namespace {

// Largest relative change of a boundary layer's depth from one node to the next.
constexpr double kLayerJitter = 0.1;
// A boundary-layer point stays at least this fraction of its depth from every face.
constexpr double kLayerClearance = 0.5;
// A boundary-layer point stays out of the core's circumspheres grown by this fraction of a
// layer's depth.
constexpr double kCoreSlack = 0.05;

}  // namespace

std::size_t place_layers(const std::vector<Vec3>& nodes, const Surface& surface,
                         const std::vector<int>& face_solid_count, const Lattice& lattice,
                         int sweep_axis, const SweptSurface& swept, int layers, double thickness,
                         double core_margin, const Parity& parity, Surroundings& around,
                         InsertedPoints& inserted, const std::vector<char>* no_layers) {
  // Boundary layers: surface nodes of the other faces where the surface is smooth, moved along
  // the inward normal, where there is room.
  std::vector<Vec3> normal(nodes.size(), Vec3{0, 0, 0});
  std::vector<bool> smooth(nodes.size(), true);
  auto triangle_normal = [&](const SurfaceTriangle& t) {
    return (nodes[t.node[1]] - nodes[t.node[0]]).cross(nodes[t.node[2]] - nodes[t.node[0]]);
  };
  for (const SurfaceTriangle& t : surface.triangles) {
    const Vec3 n = triangle_normal(t);
    for (int c : t.node) {
      normal[c] = normal[c] + n;
      if (lattice.lattice_face[t.face] || face_solid_count[t.face] > 1) smooth[c] = false;
    }
  }
  if (no_layers)
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if ((*no_layers)[i]) smooth[i] = false;
  for (auto& n : normal)
    if (n.norm() > 0) n = unit(n);
  for (const SurfaceTriangle& t : surface.triangles) {
    const Vec3 n = triangle_normal(t);
    if (n.norm() == 0) continue;
    for (int c : t.node)
      if (unit(n).dot(normal[c]) < std::cos(25.0 * M_PI / 180)) smooth[c] = false;
  }
  // Swept: the nodes repeating a node of the bottom caps' boundary take its normal across the
  // walls (its sides' normals weighted by length), on the caps' planes too, and are smooth where
  // the walls are; the depths, the room and the caps' faces are found on the bottom plane, so
  // that every plane gets the same layer points. A wall between two solids gets layers on both
  // sides (without them, a cylinder through boxes had triangles of 14 degrees between its fine
  // stations and the lattice, prisms below the quality floor, and the block unravelled).
  std::vector<std::vector<int>> column;  // swept: per bottom node, its repeats plane by plane
  std::vector<char> two_sided(nodes.size(), 0);
  if (sweep_axis >= 0) {
    const int a = sweep_axis;
    Vec3 along{0, 0, 0};
    set_coord(along, a, 1.0);
    std::vector<Vec3> side_normal(swept.sides.size()), sum(nodes.size(), Vec3{0, 0, 0});
    for (std::size_t k = 0; k < swept.sides.size(); ++k) {
      const auto& side = swept.sides[k];
      side_normal[k] = (nodes[side[0]] - nodes[side[1]]).cross(along);  // the wall's, outward
      for (int end : side) sum[end] = sum[end] + side_normal[k];
    }
    std::vector<char> station(nodes.size(), 0), bent(nodes.size(), 0), outer(nodes.size(), 0);
    for (std::size_t k = 0; k < swept.sides.size(); ++k) {
      const auto& side = swept.sides[k];
      const Vec3 n = unit(side_normal[k]);
      for (int end : side) {
        station[end] = 1;
        if (n.dot(unit(sum[end])) < std::cos(25.0 * M_PI / 180)) bent[end] = 1;
        if (swept.shared[k])
          two_sided[end] = 1;
        else
          outer[end] = 1;
        // Lattice faces have no layers: one ending at a station beside one (where a fillet meets
        // a lattice face) left triangles of 11 degrees there, prisms below the quality floor.
        if (swept.on_lattice_face[k]) bent[end] = 1;
      }
    }
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (two_sided[i] && outer[i]) bent[i] = 1, two_sided[i] = 0;  // where solids meet a wall
    column.resize(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const int b = swept.base[i];
      column[b].push_back(static_cast<int>(i));
      two_sided[i] = two_sided[b];
      smooth[i] = station[b] && !bent[b];
      normal[i] = station[b] ? unit(sum[b]) : Vec3{0, 0, 0};
    }
  }
  const double layer = thickness;
  // Out of the core's circumspheres (by a little more than round-off: a point on one makes its
  // cell or pyramid cospherical with it) and its points' margin.
  const auto clear_of_core = [&](const Vec3& q) {
    return !around.core_balls.holds(q, kCoreSlack * layer) &&
           !around.core_points.any_within(q, core_margin);
  };
  std::size_t placed = 0;
  for (int k = 1; k <= layers; ++k)
    for (std::size_t i = 0; i < nodes.size(); ++i)
      for (const double sign : {1.0, -1.0}) {
        if (sign < 0 && !two_sided[i]) continue;
        if (!smooth[i] || normal[i].norm() == 0) continue;
        if (sweep_axis >= 0 && swept.base[i] != static_cast<int>(i))
          continue;  // placed with its base
        // Depths vary by up to kLayerJitter (a fixed pseudo-random fraction per node): the sides
        // of equally deep layers are cocircular quads (rectangles, isosceles trapezoids), which
        // TetGen cuts with flat tets where the prisms on either side disagree on the diagonal.
        const double spread =
            static_cast<double>((static_cast<std::size_t>(surface.seed[i]) * 2654435761u) % 1000) /
                500.0 -
            1;
        const double depth = k * layer * (1 + kLayerJitter * spread);
        const Vec3 q = nodes[i] - normal[i] * (sign * depth);
        // Room: no other part of the surface nearer than the depth, no other point too near.
        if (around.curved.any_within(q, 0.9 * depth)) continue;
        if (around.layer_points.any_within(q, 0.3 * layer) ||
            around.surface_points.any_within(q, 0.5 * depth))
          continue;
        if (sweep_axis >= 0) {
          const int a = sweep_axis;
          std::vector<std::pair<Vec3, int>> repeats;  // the point on every plane, and its cap face
          for (int j : column[i]) {
            Vec3 r = q;
            set_coord(r, a, coord(nodes[j], a));
            const int level = static_cast<int>(std::lround(coord(r, a) / lattice.spacing[a]));
            int index[3] = {-1, -1, -1};
            index[a] = level;
            const int face = around.on_lattice_face(r, index);  // a cap it lies in, on any plane
            if (face < 0 && (level == 0 || level == lattice.cells[a]))
              break;  // outside: none anywhere
            if (!clear_of_core(r)) break;
            repeats.emplace_back(r, face);
          }
          if (repeats.size() != column[i].size()) continue;
          for (const auto& [r, face] : repeats) {
            around.layer_points.add(r);
            inserted.points.push_back(r);
            inserted.face.push_back(face);
            ++placed;
          }
          continue;
        }
        // Inside the shape and clear of every face, lattice faces too: points offset from a
        // curved face next to a planar one went through the planar one, and TetGen left them out.
        if (!parity.inside(q) || around.every_face.any_within(q, kLayerClearance * depth)) continue;
        if (!clear_of_core(q)) continue;
        around.layer_points.add(q);
        inserted.points.push_back(q);
        inserted.face.push_back(-1);
        ++placed;
      }
  return placed;
}

}  // namespace hexmerge::mesher
