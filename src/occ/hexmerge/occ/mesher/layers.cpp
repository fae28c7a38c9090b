#include "hexmerge/occ/mesher/layers.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parameter_table.h"
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
// A wall meets a lattice-face wall "at about a right angle" when their normals are further
// apart than this angle (and nearer than its supplement): its layer is then carried onto the
// lattice face.
constexpr double kOntoPlaneAngle = 70.0;

}  // namespace

std::string faces_text(const std::vector<int>& faces) {
  std::string out;
  for (const int f : faces) out += (out.empty() ? "Face" : ",Face") + std::to_string(f);
  return out;
}

std::vector<FaceLayerSpec> face_layer_specs(const std::vector<FaceLayers>& entries,
                                            const ItemNumbering& faces, double h) {
  std::vector<FaceLayerSpec> out;
  for (const FaceLayers& entry : entries) {
    const std::string what = "boundary layers on " + faces_text(entry.faces);
    if (entry.thickness > h)
      throw InputError("parameter 'face_layers': " + what + ": the first layer's thickness " +
                           parameter_number_text(entry.thickness) + " is larger than the size " +
                           parameter_number_text(h) +
                           ": boundary layers are finer than the mesh, give a thickness of at "
                           "most the size",
                       Entity::Parameter);
    FaceLayerSpec spec{{}, entry.layers, entry.thickness, entry.growth};
    for (const int f : entry.faces)
      for (const int i : faces.items(f, "face_layers", what)) spec.faces.push_back(i);
    out.push_back(spec);
  }
  return out;
}

void check_face_layers_placed(const std::vector<FaceLayers>& entries,
                              const std::vector<FaceLayersApplied>& applied, double h) {
  for (std::size_t e = 0; e < entries.size() && e < applied.size(); ++e) {
    if (applied[e].nb_per_layer.empty() || applied[e].nb_per_layer[0] > 0) continue;
    throw InputError(
        "parameter 'face_layers': boundary layers on " + faces_text(entries[e].faces) +
            (applied[e].nb_nodes == 0
                 ? ": at size " + parameter_number_text(h) +
                       " the face has no surface node off its edges to grow layers from (give "
                       "a smaller size, or a local size on the face)"
                 : ": no room for a first layer " + parameter_number_text(entries[e].thickness) +
                       " deep at any of its " + std::to_string(applied[e].nb_nodes) +
                       " nodes (the shape is thinner there, or the face is shared by two "
                       "solids)"),
        Entity::Parameter);
  }
}

double FaceLayerSpec::depth(int k) const {
  double sum = 0, step = thickness;
  for (int j = 0; j < k; ++j) sum += step, step *= growth;
  return sum;
}

std::size_t clear_face_layers(const std::vector<FaceLayerSpec>& specs,
                              const std::vector<Vec3>& nodes, const Surface& surface,
                              const Lattice& lattice, const Surroundings& around, double margin,
                              KeptPoints& kept) {
  if (specs.empty()) return 0;
  std::vector<double> reach(lattice.lattice_face.size(), 0.0);
  double deepest = 0;
  for (const FaceLayerSpec& spec : specs)
    for (const int f : spec.faces) {
      // The closing pyramids' apexes (and circumspheres) reach half a cell beyond the core.
      const double r = spec.depth(spec.layers) * (1 + kLayerJitter) + margin +
                       0.5 * std::max({lattice.widest(0), lattice.widest(1), lattice.widest(2)});
      reach[static_cast<std::size_t>(f)] = std::max(reach[static_cast<std::size_t>(f)], r);
      deepest = std::max(deepest, r);
    }
  // One set per distinct reach would be exact; one set of every layered face at the deepest
  // reach over-clears only where entries of different depths meet.
  TriangleSet layered(nodes, around.box_lo, around.box_hi, std::max(deepest, 1e-12));
  for (const SurfaceTriangle& t : surface.triangles)
    if (reach[static_cast<std::size_t>(t.face)] > 0) layered.add(t.node);
  const int n0 = lattice.cells[0] + 1, n1 = lattice.cells[1] + 1, n2 = lattice.cells[2] + 1;
  std::size_t dropped = 0;
  for (int k = 0; k < n2; ++k)
    for (int j = 0; j < n1; ++j)
      for (int i = 0; i < n0; ++i) {
        const std::size_t index = lattice.point_index(i, j, k);
        if (!kept.kept[index] || !layered.any_within(lattice.point(i, j, k), deepest)) continue;
        kept.kept[index] = 0;
        ++dropped;
      }
  return dropped;
}

std::size_t place_layers(const std::vector<Vec3>& nodes, const Surface& surface,
                         const std::vector<int>& face_solid_count, const Lattice& lattice,
                         int sweep_axis, const SweptSurface& swept, int layers, double thickness,
                         double core_margin, const Parity& parity, Surroundings& around,
                         InsertedPoints& inserted, const std::vector<char>* no_layers,
                         const std::vector<FaceLayerSpec>& face_layers,
                         std::vector<FaceLayersApplied>* applied) {
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
  // Per node, the face-layer spec it takes (-1: the global layers).
  std::vector<int> spec_of(nodes.size(), -1);
  if (!face_layers.empty()) {
    std::vector<int> face_spec(lattice.lattice_face.size(), -1);
    for (std::size_t e = face_layers.size(); e-- > 0;)
      for (const int f : face_layers[e].faces)
        face_spec[static_cast<std::size_t>(f)] = static_cast<int>(e);
    for (const SurfaceTriangle& t : surface.triangles) {
      const int e = face_spec[static_cast<std::size_t>(t.face)];
      if (e < 0) continue;
      for (const int c : t.node)
        if (spec_of[c] < 0 || e < spec_of[c]) spec_of[c] = e;
    }
  }
  if (no_layers)
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if ((*no_layers)[i] && spec_of[i] < 0) smooth[i] = false;
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
  // Swept: per node, the side of the first plane on a lattice-face wall its layer points lie on
  // (-1: none), where a wall of one solid meets that lattice face at about a right angle.
  std::vector<int> onto_side(nodes.size(), -1);
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
    // Where a wall of one solid meets a lattice-face wall at about a right angle (a bore and a
    // symmetry plane), the layer goes on in that plane: the station's layer points lie on the
    // lattice face, along the wall's normal made parallel to the plane. A layer ending before the
    // plane left a wedge there and a hexahedron of the full depth on the plane, and the first-order
    // stress at the bore peaked two nodes from it (docs/fem-accuracy.md). Where the wall meets the
    // lattice face at a shallow angle (a fillet), the station stays without layers; face layers
    // end at their walls' edges. (Not swept, the same carried onto lattice faces lowered the
    // tets' smallest scaled Jacobian: cylinder h 2.7 0.227 to 0.181, bracket-4 with two layers
    // recombined 0.112 to 0.062; not done.)
    // Per station, its side on a lattice-face wall (-2: two), and its other sides.
    std::vector<int> lattice_side(nodes.size(), -1), other_sides(nodes.size(), 0);
    for (std::size_t k = 0; k < swept.sides.size(); ++k)
      for (int end : swept.sides[k]) {
        if (swept.on_lattice_face[k])
          lattice_side[end] = lattice_side[end] == -1 ? static_cast<int>(k) : -2;
        else
          ++other_sides[end];
      }
    for (std::size_t k = 0; k < swept.sides.size(); ++k) {
      if (swept.on_lattice_face[k] || swept.shared[k]) continue;
      const Vec3 n = unit(side_normal[k]);
      for (int end : swept.sides[k]) {
        const int l = lattice_side[end];
        if (l < 0 || other_sides[end] != 1 || two_sided[end] || spec_of[end] >= 0) continue;
        const Vec3 plane = unit(side_normal[static_cast<std::size_t>(l)]);
        if (std::abs(n.dot(plane)) > std::cos(kOntoPlaneAngle * M_PI / 180)) continue;
        const Vec3 in_plane = n - plane * n.dot(plane);
        const auto& side = swept.sides[static_cast<std::size_t>(l)];
        const Vec3 along_side = nodes[side[0] == end ? side[1] : side[0]] - nodes[end];
        if (in_plane.norm() == 0 || in_plane.dot(along_side) >= 0) continue;  // not inward
        onto_side[end] = l;
        bent[end] = 0;
        sum[end] = in_plane;
      }
    }
    column.resize(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const int b = swept.base[i];
      column[b].push_back(static_cast<int>(i));
      two_sided[i] = two_sided[b];
      onto_side[i] = onto_side[b];
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
  int deepest = 0;
  for (const FaceLayerSpec& spec : face_layers) deepest = std::max(deepest, spec.layers);
  if (applied) {
    applied->assign(face_layers.size(), FaceLayersApplied{});
    for (std::size_t e = 0; e < face_layers.size(); ++e)
      (*applied)[e].nb_per_layer.assign(static_cast<std::size_t>(face_layers[e].layers), 0);
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (spec_of[i] >= 0 && smooth[i] && normal[i].norm() > 0 &&
          (sweep_axis < 0 || swept.base[i] == static_cast<int>(i)))  // swept: the first plane's
        ++(*applied)[static_cast<std::size_t>(spec_of[i])].nb_nodes;
  }
  std::vector<int> reached(nodes.size(), 0);  // face-layer nodes: the layers placed so far
  // A face-layer node got layer k, `points` points (swept: one per plane).
  const auto reach = [&](std::size_t i, int k, std::size_t points) {
    reached[i] = k;
    if (!applied) return;
    FaceLayersApplied& counts = (*applied)[static_cast<std::size_t>(spec_of[i])];
    counts.nb_points += points;
    ++counts.nb_per_layer[static_cast<std::size_t>(k - 1)];
  };
  // The global layers first, then the face layers: these come last in `inserted`, together.
  for (const bool face_pass : {false, true})
    for (int k = 1; k <= (face_pass ? deepest : layers); ++k)
      for (std::size_t i = 0; i < nodes.size(); ++i)
        for (const double sign : {1.0, -1.0}) {
          if (sign < 0 && !two_sided[i]) continue;
          if (!smooth[i] || normal[i].norm() == 0 || (spec_of[i] >= 0) != face_pass) continue;
          const FaceLayerSpec* spec =
              spec_of[i] >= 0 ? &face_layers[static_cast<std::size_t>(spec_of[i])] : nullptr;
          if (spec && (k > spec->layers || reached[i] < k - 1)) continue;
          if (sweep_axis >= 0 && swept.base[i] != static_cast<int>(i))
            continue;  // placed with its base
          // Depths vary by up to kLayerJitter (a fixed pseudo-random fraction per node): the sides
          // of equally deep layers are cocircular quads (rectangles, isosceles trapezoids), which
          // TetGen cuts with flat tets where the prisms on either side disagree on the diagonal.
          const double spread =
              static_cast<double>((static_cast<std::size_t>(surface.seed[i]) * 2654435761u) %
                                  1000) /
                  500.0 -
              1;
          const double depth = spec ? spec->depth(k) * (1 + kLayerJitter * spread)
                                    : k * layer * (1 + kLayerJitter * spread);
          // This layer's own thickness: points of other layers keep 0.3 of it away.
          const double own = spec ? spec->depth(k) - spec->depth(k - 1) : layer;
          Vec3 q = nodes[i] - normal[i] * (sign * depth);
          // Carried onto a lattice-face wall: exactly on its plane, within its side.
          int plane_axis = -1;
          if (onto_side[i] >= 0) {
            const auto& side = swept.sides[static_cast<std::size_t>(onto_side[i])];
            const AxisPlane& plane = *lattice.face_plane[static_cast<std::size_t>(
                swept.wall[static_cast<std::size_t>(onto_side[i])][0])];
            plane_axis = plane.axis;
            set_coord(q, plane_axis, coord(nodes[i], plane_axis));
            const Vec3 along = nodes[side[0] == static_cast<int>(i) ? side[1] : side[0]] - nodes[i];
            if ((q - nodes[i]).dot(along) >= along.dot(along)) continue;  // past its other end
          }
          // Room: no other part of the surface nearer than the depth, no other point too near.
          if (around.curved.any_within(q, 0.9 * depth)) continue;
          // Swept: clear of the walls on lattice faces (the points lie on the first plane, so not
          // of the caps), but the one it is carried onto. A point offset from a bore beside a
          // lattice wall landed 0.037 from it, its column of tets flat (FreeCAD's
          // PathTests/test_holes00: holes 0.5 mm from a side, h 6.3, scaled Jacobian 1.4e-4).
          if (sweep_axis >= 0 &&
              around.every_face.any_within(q, kLayerClearance * depth, [&](int t) {
                const int f = surface.triangles[static_cast<std::size_t>(t)].face;
                const auto& plane = lattice.face_plane[static_cast<std::size_t>(f)];
                return plane && plane->axis != sweep_axis &&
                       (onto_side[i] < 0 ||
                        f != swept.wall[static_cast<std::size_t>(onto_side[i])][0]);
              }))
            continue;
          if (around.layer_points.any_within(q, 0.3 * own) ||
              around.surface_points.any_within(q, 0.5 * depth))
            continue;
          if (sweep_axis >= 0) {
            const int a = sweep_axis;
            std::vector<std::pair<Vec3, int>>
                repeats;  // the point on every plane, and its cap face
            for (int j : column[i]) {
              Vec3 r = q;
              set_coord(r, a, coord(nodes[j], a));
              const int level = static_cast<int>(std::lround(lattice.cells_at(a, coord(r, a))));
              int index[3] = {-1, -1, -1};
              index[a] = level;
              int face = around.on_lattice_face(r, index);  // a cap it lies in, on any plane
              if (face < 0 && (level == 0 || level == lattice.cells[a]))
                break;  // outside: none anywhere
              // Carried onto a lattice-face wall: on that face (between the caps too).
              if (plane_axis >= 0 && face < 0) {
                int on_wall[3] = {-1, -1, -1};
                on_wall[plane_axis] = static_cast<int>(
                    std::lround(lattice.cells_at(plane_axis, coord(r, plane_axis))));
                face = around.on_lattice_face(r, on_wall);
                if (face < 0) break;
              }
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
            if (spec) reach(i, k, repeats.size());
            continue;
          }
          // Inside the shape and clear of every face, lattice faces too: points offset from a
          // curved face next to a planar one went through the planar one, and TetGen left them out.
          if (!parity.inside(q) || around.every_face.any_within(q, kLayerClearance * depth))
            continue;
          if (!clear_of_core(q)) continue;
          around.layer_points.add(q);
          inserted.points.push_back(q);
          inserted.face.push_back(-1);
          ++placed;
          if (spec) reach(i, k, 1);
        }
  return placed;
}

}  // namespace hexmerge::mesher
