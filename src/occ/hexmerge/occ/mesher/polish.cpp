#include "hexmerge/occ/mesher/polish.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/mixed_mesh.h"
#include "hexmerge/occ/mesher/remove_slivers.h"
#include "hexmerge/recombine/recombine.h"

namespace hexmerge::mesher {
namespace {

/// Rounds of flips and node moves (gmsh_Block at its 50k size: the fourth moves 240 nodes of
/// the first's 1,468, and changes no count under 0.2).
constexpr int kPolishRounds = 4;

/// How far an element's scaled Jacobian may fall for a better tet beside it (above the
/// recombination's acceptance either way).
constexpr double kPolishDrop = 0.1;

using TetKey = std::array<index_t, 4>;

TetKey tet_key(const TetMesh& mesh, index_t t) {
  TetKey key{mesh.tet(t)[0], mesh.tet(t)[1], mesh.tet(t)[2], mesh.tet(t)[3]};
  std::sort(key.begin(), key.end());
  return key;
}

/// An element the recombination made, and what a move of its nodes must keep of it.
struct Element {
  CellType type = CellType::Tet;
  std::array<index_t, 8> vertices{};
  double least_quality = 0.0;             ///< its scaled Jacobian, at least
  std::array<double, 6> least_fold{};     ///< per quad face: its dihedral angle, at least
  std::array<double, 6> widest_corner{};  ///< per quad face: its widest corner, at most
};

/// Quad face f of element e, its corners' coordinates.
std::array<const double*, 4> quad(const double* points, const Element& e, int f) {
  const std::array<int, 4>& face = descriptor(e.type).face[f];
  std::array<const double*, 4> p{};
  for (int i = 0; i < 4; ++i) p[i] = points + 3 * static_cast<std::size_t>(e.vertices[face[i]]);
  return p;
}

/// The fold of a quad: the smaller dihedral angle across either diagonal.
double fold(const std::array<const double*, 4>& p) {
  return std::min(quad_dihedral_angle(p[0], p[1], p[2], p[3]),
                  quad_dihedral_angle(p[1], p[2], p[3], p[0]));
}

}  // namespace

void polish_leftover_tets(TetMesh& mesh, std::vector<char> movable, SurfacePath* surface,
                          const RecombineParameters& recombination, double floor,
                          PolishReport& report, const ProgressCallback& progress) {
  report = PolishReport{};
  // No tet under the floor: nothing left under it (not recombined).
  bool any = false;
  for (index_t t = 0; t < mesh.nb_tets() && !any; ++t)
    any = scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)) < floor;
  if (!any) return;
  RecombineReport recombined;
  const MixedMesh mixed = recombine(mesh, recombination, recombined, progress);
  // The elements' tets, which stay; per quad face (corners sorted), how many elements have it
  // and their region (-1: two regions, a face the recombination treats as the boundary).
  std::vector<TetKey> kept;
  std::map<std::array<index_t, 4>, std::pair<int, std::int32_t>> quads;
  std::vector<Element> elements;
  for (index_t c = 0; c < mixed.nb_cells(); ++c) {
    if (mixed.types[c] == CellType::Tet) continue;
    for (index_t k = mixed.source_offsets[c]; k < mixed.source_offsets[c + 1]; ++k)
      kept.push_back(tet_key(mesh, mixed.source_tets[k]));
    Element e;
    e.type = mixed.types[c];
    std::copy(mixed.cell(c), mixed.cell(c) + mixed.cell_size(c), e.vertices.begin());
    const CellDescriptor& d = descriptor(e.type);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      std::array<index_t, 4> corners;
      for (int i = 0; i < 4; ++i) corners[i] = e.vertices[d.face[f][i]];
      std::sort(corners.begin(), corners.end());
      const auto [it, added] = quads.emplace(corners, std::make_pair(1, mixed.region(c)));
      if (!added) {
        ++it->second.first;
        if (it->second.second != mixed.region(c)) it->second.second = -1;
      }
    }
    elements.push_back(e);
  }
  std::sort(kept.begin(), kept.end());
  report.elements = elements.size();
  const auto leftover_below = [&]() {
    std::size_t below = 0;
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      below += scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)) < floor &&
               !std::binary_search(kept.begin(), kept.end(), tet_key(mesh, t));
    return below;
  };
  report.below_before = report.below_after = leftover_below();
  if (report.below_before == 0) return;

  // What each element must keep; the nodes of the block's elements stay.
  const double* points = mesh.points.data();
  std::vector<std::vector<std::size_t>> elements_at(mesh.nb_vertices());
  for (std::size_t i = 0; i < elements.size(); ++i) {
    Element& e = elements[i];
    const CellDescriptor& d = descriptor(e.type);
    const double quality = scaled_jacobian(e.type, points, e.vertices.data());
    bool block = e.type == CellType::Hex && quality >= kBlockHexQuality;
    bool all_planar = true;
    e.least_quality =
        std::min(quality, std::max(recombination.min_scaled_jacobian, quality - kPolishDrop));
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      const std::array<const double*, 4> p = quad(points, e, f);
      std::array<index_t, 4> corners;
      for (int k = 0; k < 4; ++k) corners[k] = e.vertices[d.face[f][k]];
      std::sort(corners.begin(), corners.end());
      const auto& [count, region] = quads.at(corners);
      const double bound = count == 1 || region < 0 ? recombination.min_boundary_dihedral_angle
                                                    : recombination.min_dihedral_angle;
      e.least_fold[f] = std::min(bound, fold(p));
      e.widest_corner[f] =
          std::max(recombination.max_face_angle, quad_max_corner_angle(p[0], p[1], p[2], p[3]));
      all_planar = all_planar && quad_is_planar(p[0], p[1], p[2], p[3]);
    }
    block = block || (e.type != CellType::Pyramid && all_planar);
    for (int k = 0; k < d.nb_vertices; ++k) {
      if (block) movable[e.vertices[k]] = kFixed;
      elements_at[e.vertices[k]].push_back(i);
    }
  }
  const auto keeps = [&](index_t v) {
    const double* at = mesh.points.data();
    for (const std::size_t i : elements_at[v]) {
      const Element& e = elements[i];
      if (!(scaled_jacobian(e.type, at, e.vertices.data()) >= e.least_quality)) return false;
      const CellDescriptor& d = descriptor(e.type);
      for (int f = 0; f < d.nb_faces; ++f) {
        if (d.face_size[f] != 4) continue;
        const std::array<const double*, 4> p = quad(at, e, f);
        if (!(fold(p) >= e.least_fold[f]) ||
            !(quad_max_corner_angle(p[0], p[1], p[2], p[3]) <= e.widest_corner[f]))
          return false;
      }
    }
    return true;
  };

  for (int round = 0; round < kPolishRounds; ++round) {
    std::vector<char> fixed(mesh.nb_tets());
    for (index_t t = 0; t < mesh.nb_tets(); ++t)
      fixed[t] = std::binary_search(kept.begin(), kept.end(), tet_key(mesh, t));
    RemoveSliversParameters flip_parameters;
    flip_parameters.target = floor;
    flip_parameters.insert_below = floor;
    RemoveSliversReport flips;
    remove_slivers(mesh, fixed, {}, flip_parameters, flips);
    // The inserted vertices: inside, free, in no element.
    movable.resize(mesh.nb_vertices(), kFree);
    elements_at.resize(mesh.nb_vertices());
    SmoothNodesParameters move_parameters;
    move_parameters.target = floor;
    move_parameters.floor = floor;
    SmoothNodesReport moves;
    smooth_nodes(mesh, movable, move_parameters, moves, surface, {}, nullptr, keeps);
    report.flips += flips.face_removals + flips.edge_removals;
    report.inserted_vertices += flips.insertions;
    report.node_moves += moves.moves;
    report.boundary_node_moves += moves.surface_moves;
    if (flips.face_removals + flips.edge_removals + flips.insertions + moves.moves == 0) break;
  }
  report.below_after = leftover_below();
}

}  // namespace hexmerge::mesher
