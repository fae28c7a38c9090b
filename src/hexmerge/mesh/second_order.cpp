#include "hexmerge/mesh/second_order.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {
namespace {

/// Positions of the mid-edge nodes in a Tet10 (VTK): node 4 + k sits on edge k of the tet.
constexpr int kTet10Edge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

std::uint64_t edge_key(index_t a, index_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

struct EdgeMid {
  std::uint64_t edge;
  index_t mid;
  index_t tet;
  bool operator<(const EdgeMid& o) const {
    return edge < o.edge || (edge == o.edge && (mid < o.mid || (mid == o.mid && tet < o.tet)));
  }
};

void check_tet10_sizes(const Tet10Mesh& mesh) {
  if (mesh.points.size() % 3 != 0) {
    throw InputError("the point array must have 3 coordinates per point");
  }
  if (mesh.tets10.size() % 10 != 0) {
    throw InputError("the Tet10 array must have 10 node ids per tetrahedron");
  }
  if (!mesh.regions.empty() && mesh.regions.size() != mesh.nb_tets()) {
    throw InputError("the region array has " + std::to_string(mesh.regions.size()) +
                     " entries for " + std::to_string(mesh.nb_tets()) + " tetrahedra");
  }
}

}  // namespace

TetMesh corner_mesh(const Tet10Mesh& mesh) {
  check_tet10_sizes(mesh);
  TetMesh out;
  out.points = mesh.points;
  out.regions = mesh.regions;
  const index_t nt = mesh.nb_tets();
  out.tets.resize(4 * static_cast<std::size_t>(nt));
  for (index_t t = 0; t < nt; ++t) {
    std::copy_n(&mesh.tets10[10 * static_cast<std::size_t>(t)], 4,
                &out.tets[4 * static_cast<std::size_t>(t)]);
  }
  return out;
}

namespace {

// Edge -> mid node of every edge of a Tet10 mesh, sorted by edge, after checking that the mesh
// agrees with itself: ids in range, one mid node per edge, a mid node on one edge only and never
// a corner, and each mid node near its edge: within the middle half of the edge along it (the
// element's Jacobian vanishes on the edge outside it) and within half the edge's length of its
// midpoint (every circular arc up to a half circle passes, so curved boundary edges do).
std::vector<EdgeMid> mid_nodes(const Tet10Mesh& input) {
  check_tet10_sizes(input);
  const index_t nt = input.nb_tets();
  const index_t nv = static_cast<index_t>(input.points.size() / 3);

  // Edge -> mid node, as a sorted array: one entry per (edge, tet), then checked for agreement.
  std::vector<EdgeMid> edges;
  edges.reserve(6 * static_cast<std::size_t>(nt));
  std::vector<char> is_corner(nv, 0);
  for (index_t t = 0; t < nt; ++t) {
    const index_t* q = &input.tets10[10 * static_cast<std::size_t>(t)];
    for (int k = 0; k < 10; ++k) {
      if (q[k] >= nv) {
        throw InputError("tetrahedron " + std::to_string(t) +
                             (k < 4 ? " refers to corner node " : " refers to mid-edge node ") +
                             std::to_string(q[k]) + ", but the mesh has " + std::to_string(nv) +
                             " nodes",
                         Entity::Element, t);
      }
    }
    for (int i = 0; i < 4; ++i) is_corner[q[i]] = 1;
    for (int k = 0; k < 6; ++k) {
      const index_t mid = q[4 + k];
      for (int i = 0; i < 4; ++i) {
        if (q[i] == mid) {
          throw InputError("tetrahedron " + std::to_string(t) + " has corner node " +
                               std::to_string(mid) + " as the mid node of an edge",
                           Entity::Element, t);
        }
      }
      edges.push_back({edge_key(q[kTet10Edge[k][0]], q[kTet10Edge[k][1]]), mid, t});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::size_t unique = 0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (unique > 0 && edges[unique - 1].edge == edges[i].edge) {
      if (edges[unique - 1].mid != edges[i].mid) {
        const index_t a = static_cast<index_t>(edges[i].edge >> 32);
        const index_t b = static_cast<index_t>(edges[i].edge & 0xffffffffu);
        throw InputError("the edge between nodes " + std::to_string(a) + " and " +
                             std::to_string(b) + " has two different mid nodes (" +
                             std::to_string(edges[unique - 1].mid) + " in tetrahedron " +
                             std::to_string(edges[unique - 1].tet) + ", " +
                             std::to_string(edges[i].mid) + " in tetrahedron " +
                             std::to_string(edges[i].tet) + ")",
                         Entity::Element, edges[i].tet);
      }
      continue;
    }
    edges[unique++] = edges[i];
  }
  edges.resize(unique);

  auto edge_name = [](const EdgeMid& e) {
    return "the edge between nodes " + std::to_string(e.edge >> 32) + " and " +
           std::to_string(e.edge & 0xffffffffu);
  };
  std::vector<index_t> edge_of_mid(nv, NO_INDEX);
  for (index_t i = 0; i < edges.size(); ++i) {
    const EdgeMid& e = edges[i];
    if (is_corner[e.mid]) {
      throw InputError("tetrahedron " + std::to_string(e.tet) + " has node " +
                           std::to_string(e.mid) + " as the mid node of " + edge_name(e) +
                           ", but the node is a corner of another tetrahedron",
                       Entity::Element, e.tet);
    }
    if (edge_of_mid[e.mid] != NO_INDEX) {
      const EdgeMid& other = edges[edge_of_mid[e.mid]];
      throw InputError("node " + std::to_string(e.mid) + " is the mid node of two edges: " +
                           edge_name(other) + " (tetrahedron " + std::to_string(other.tet) +
                           ") and " + edge_name(e) + " (tetrahedron " + std::to_string(e.tet) + ")",
                       Entity::Element, e.tet);
    }
    edge_of_mid[e.mid] = i;
    const double* a = &input.points[3 * (e.edge >> 32)];
    const double* b = &input.points[3 * (e.edge & 0xffffffffu)];
    const double* m = &input.points[3 * std::size_t(e.mid)];
    double off = 0.0, along = 0.0, length = 0.0;  // squared; along: dot with the edge
    for (int c = 0; c < 3; ++c) {
      const double d = m[c] - 0.5 * (a[c] + b[c]);
      off += d * d;
      along += d * (b[c] - a[c]);
      length += (b[c] - a[c]) * (b[c] - a[c]);
    }
    // Along the edge, within its middle half (outside it the element's Jacobian vanishes on the
    // edge); across it, within half its length.
    if (!(off <= 0.25 * length) || !(std::fabs(along) < 0.25 * length)) {  // also refuses NaN
      throw InputError(
          "tetrahedron " + std::to_string(e.tet) + ": mid node " + std::to_string(e.mid) + " of " +
              edge_name(e) + " lies " + std::to_string(std::sqrt(off)) +
              " from the edge's midpoint (edge length " + std::to_string(std::sqrt(length)) +
              "): a mid node must lie within the middle half of its edge and at most "
              "half the edge's length off it",
          Entity::Element, e.tet);
    }
  }
  return edges;
}

}  // namespace

void validate_tet10_mesh(const Tet10Mesh& mesh) { mid_nodes(mesh); }

QuadraticCells quadratic_cells(const MixedMesh& linear, const Tet10Mesh& input) {
  const std::vector<EdgeMid> edges = mid_nodes(input);
  QuadraticCells out;
  const index_t nc = linear.nb_cells();
  out.offsets.reserve(static_cast<std::size_t>(nc) + 1);
  out.offsets.push_back(0);
  for (index_t c = 0; c < nc; ++c) {
    const CellDescriptor& desc = descriptor(linear.types[c]);
    HEXMERGE_ASSERT(linear.cell_size(c) == static_cast<index_t>(desc.nb_vertices),
                    "a linear cell with the wrong number of vertices");
    const index_t* verts = linear.cell(c);
    out.nodes.insert(out.nodes.end(), verts, verts + desc.nb_vertices);
    for (int e = 0; e < desc.nb_edges; ++e) {
      const EdgeMid probe{edge_key(verts[desc.edge[e][0]], verts[desc.edge[e][1]]), 0, 0};
      const auto it = std::lower_bound(edges.begin(), edges.end(), probe);
      if (it == edges.end() || it->edge != probe.edge) {
        throw InputError(std::string(desc.name) + " " + std::to_string(c) +
                             " has an edge between nodes " +
                             std::to_string(verts[desc.edge[e][0]]) + " and " +
                             std::to_string(verts[desc.edge[e][1]]) +
                             " that is no edge of the Tet10 mesh (no mid node)",
                         Entity::Element, c);
      }
      out.nodes.push_back(it->mid);
    }
    out.offsets.push_back(static_cast<index_t>(out.nodes.size()));
  }
  return out;
}

}  // namespace hexmerge
