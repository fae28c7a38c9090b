// The descriptor tables on their own (fTetWild's test_table.cpp habit): every face outward,
// every edge on exactly two faces, face edges in the edge table, corner frames right-handed,
// ideal cells scoring a scaled Jacobian of 1 with their known volumes.
#include "hexmerge/mesh/cell_type.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"

namespace hexmerge {
namespace {

const CellType kTypes[] = {CellType::Tet, CellType::Pyramid, CellType::Prism, CellType::Hex};

/// The ideal cell of each type in local (VTK) order, and its volume.
struct ReferenceCell {
  std::vector<double> points;
  double volume;
};

ReferenceCell ideal_cell(CellType type) {
  const double s3 = std::sqrt(3.0), s2 = std::sqrt(2.0);
  switch (type) {
    case CellType::Tet:  // regular, edge 1
      return {{0, 0, 0, 1, 0, 0, 0.5, s3 / 2, 0, 0.5, s3 / 6, std::sqrt(2.0 / 3.0)}, s2 / 12};
    case CellType::Pyramid:  // square base, all edges 1
      return {{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1 / s2}, s2 / 6};
    case CellType::Prism:  // equilateral triangles, square sides
      return {{0, 0, 0, 1, 0, 0, 0.5, s3 / 2, 0, 0, 0, 1, 1, 0, 1, 0.5, s3 / 2, 1}, s3 / 4};
    case CellType::Hex:  // unit cube
      return {{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1}, 1.0};
  }
  return {};
}

std::vector<index_t> identity(int n) {
  std::vector<index_t> v(n);
  for (int i = 0; i < n; ++i) v[i] = static_cast<index_t>(i);
  return v;
}

Vec3 point(const ReferenceCell& cell, int i) { return Vec3::of(&cell.points[3 * i]); }

Vec3 centroid(const ReferenceCell& cell, const int* ids, int n) {
  Vec3 c{0, 0, 0};
  for (int i = 0; i < n; ++i) c = c + point(cell, ids[i]);
  return c * (1.0 / n);
}

/// Newell's normal of a polygon (exact for planar ones, any size).
Vec3 polygon_normal(const ReferenceCell& cell, const int* ids, int n) {
  Vec3 normal{0, 0, 0};
  for (int i = 0; i < n; ++i)
    normal = normal + point(cell, ids[i]).cross(point(cell, ids[(i + 1) % n]));
  return normal;
}

std::pair<int, int> undirected(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

TEST(descriptor, counts_match_the_types) {
  const int vertices[] = {4, 5, 6, 8}, faces[] = {4, 5, 5, 6}, edges[] = {6, 8, 9, 12};
  const int quads[] = {0, 1, 3, 6}, vtk[] = {10, 14, 13, 12};
  for (CellType type : kTypes) {
    const int k = static_cast<int>(type);
    const CellDescriptor& d = descriptor(type);
    EXPECT_EQ(d.nb_vertices, vertices[k]);
    EXPECT_EQ(nb_vertices(type), vertices[k]);
    EXPECT_EQ(d.nb_faces, faces[k]);
    EXPECT_EQ(d.nb_edges, edges[k]);
    EXPECT_EQ(nb_edges(type), edges[k]);
    EXPECT_EQ(d.vtk_id, vtk[k]);
    int nb_quads = 0;
    for (int f = 0; f < d.nb_faces; ++f) nb_quads += d.face_size[f] == 4;
    EXPECT_EQ(d.nb_quad_faces, quads[k]);
    EXPECT_EQ(nb_quads, quads[k]);
    // Euler: V - E + F = 2 for the boundary of a convex cell.
    EXPECT_EQ(d.nb_vertices - d.nb_edges + d.nb_faces, 2) << d.name;
  }
}

TEST(descriptor, every_face_points_outward) {
  for (CellType type : kTypes) {
    const CellDescriptor& d = descriptor(type);
    const ReferenceCell cell = ideal_cell(type);
    std::vector<int> all(d.nb_vertices);
    for (int i = 0; i < d.nb_vertices; ++i) all[i] = i;
    const Vec3 center = centroid(cell, all.data(), d.nb_vertices);
    for (int f = 0; f < d.nb_faces; ++f) {
      const int n = d.face_size[f];
      ASSERT_TRUE(n == 3 || n == 4);
      for (int i = 0; i < n; ++i) ASSERT_TRUE(d.face[f][i] >= 0 && d.face[f][i] < d.nb_vertices);
      const Vec3 normal = polygon_normal(cell, d.face[f].data(), n);
      const Vec3 out = centroid(cell, d.face[f].data(), n) - center;
      EXPECT_GT(normal.dot(out), 0.0) << d.name << " face " << f;
    }
  }
}

TEST(descriptor, base_in_local_order_points_into_the_cell) {
  // The header's convention: vertices 0-1-2(-3), by the right-hand rule, point into the cell.
  for (CellType type : kTypes) {
    const CellDescriptor& d = descriptor(type);
    const ReferenceCell cell = ideal_cell(type);
    const int base_size = d.face_size[0];
    const int base[4] = {0, 1, 2, 3};
    std::vector<int> all(d.nb_vertices);
    for (int i = 0; i < d.nb_vertices; ++i) all[i] = i;
    const Vec3 inward = centroid(cell, all.data(), d.nb_vertices) - centroid(cell, base, base_size);
    EXPECT_GT(polygon_normal(cell, base, base_size).dot(inward), 0.0) << d.name;
    // The base is face 0 of the table, except for the tet, whose face i is opposite vertex i
    // (so its base 0-1-2 is face 3).
    const int base_face = type == CellType::Tet ? 3 : 0;
    std::set<int> listed(d.face[base_face].begin(), d.face[base_face].begin() + base_size);
    EXPECT_EQ(listed, std::set<int>(base, base + base_size)) << d.name;
  }
}

TEST(descriptor, tet_face_i_is_opposite_vertex_i) {
  const CellDescriptor& d = descriptor(CellType::Tet);
  for (int f = 0; f < 4; ++f) {
    EXPECT_EQ(std::count(d.face[f].begin(), d.face[f].begin() + 3, f), 0) << "face " << f;
  }
}

TEST(descriptor, every_edge_belongs_to_exactly_two_faces) {
  for (CellType type : kTypes) {
    const CellDescriptor& d = descriptor(type);
    std::set<std::pair<int, int>> edges;
    for (int e = 0; e < d.nb_edges; ++e) {
      ASSERT_NE(d.edge[e][0], d.edge[e][1]);
      edges.insert(undirected(d.edge[e][0], d.edge[e][1]));
    }
    EXPECT_EQ(edges.size(), std::size_t(d.nb_edges)) << d.name << ": repeated edge";
    std::set<std::pair<int, int>> face_edges;
    for (const auto& e : edges) {
      int faces = 0;
      for (int f = 0; f < d.nb_faces; ++f) {
        const int n = d.face_size[f];
        for (int i = 0; i < n; ++i) {
          faces += undirected(d.face[f][i], d.face[f][(i + 1) % n]) == e;
        }
      }
      EXPECT_EQ(faces, 2) << d.name << " edge " << e.first << "-" << e.second;
    }
    for (int f = 0; f < d.nb_faces; ++f) {
      const int n = d.face_size[f];
      for (int i = 0; i < n; ++i) {
        const auto e = undirected(d.face[f][i], d.face[f][(i + 1) % n]);
        EXPECT_TRUE(edges.count(e)) << d.name << " face " << f << " has an edge not in the table";
        face_edges.insert(e);
      }
    }
    EXPECT_EQ(face_edges, edges) << d.name;
  }
}

TEST(descriptor, edges_follow_vtk_quadratic_order) {
  // VTK's Tet10, Pyramid13, Wedge15 and Hexahedron20 mid-edge node order.
  const std::vector<std::vector<std::pair<int, int>>> vtk = {
      {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
      {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
      {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
      {{0, 1},
       {1, 2},
       {2, 3},
       {3, 0},
       {4, 5},
       {5, 6},
       {6, 7},
       {7, 4},
       {0, 4},
       {1, 5},
       {2, 6},
       {3, 7}}};
  for (CellType type : kTypes) {
    const CellDescriptor& d = descriptor(type);
    const auto& expected = vtk[static_cast<int>(type)];
    ASSERT_EQ(std::size_t(d.nb_edges), expected.size());
    for (int e = 0; e < d.nb_edges; ++e) {
      EXPECT_EQ(undirected(d.edge[e][0], d.edge[e][1]),
                undirected(expected[e].first, expected[e].second))
          << d.name << " edge " << e;
    }
  }
}

TEST(descriptor, corner_frames_are_right_handed_cell_edges) {
  for (CellType type : kTypes) {
    const CellDescriptor& d = descriptor(type);
    const ReferenceCell cell = ideal_cell(type);
    std::set<std::pair<int, int>> edges;
    for (int e = 0; e < d.nb_edges; ++e) edges.insert(undirected(d.edge[e][0], d.edge[e][1]));
    EXPECT_EQ(d.nb_corners, type == CellType::Pyramid ? 4 : d.nb_vertices);
    std::set<int> apexes;
    for (int k = 0; k < d.nb_corners; ++k) {
      const auto& c = d.corner[k];
      apexes.insert(c[0]);
      for (int i = 1; i < 4; ++i) {
        EXPECT_TRUE(edges.count(undirected(c[0], c[i])))
            << d.name << " corner " << k << ": frame vector not along an edge";
      }
      const Vec3 v = point(cell, c[0]);
      EXPECT_GT(det3(point(cell, c[1]) - v, point(cell, c[2]) - v, point(cell, c[3]) - v), 0.0)
          << d.name << " corner " << k;
    }
    EXPECT_EQ(apexes.size(), std::size_t(d.nb_corners)) << d.name << ": a corner listed twice";
  }
}

TEST(descriptor, ideal_cells_score_one_and_have_their_volume) {
  for (CellType type : kTypes) {
    const ReferenceCell cell = ideal_cell(type);
    const auto ids = identity(descriptor(type).nb_vertices);
    EXPECT_NEAR(scaled_jacobian(type, cell.points.data(), ids.data()), 1.0, 1e-12)
        << descriptor(type).name;
    EXPECT_NEAR(cell_volume(type, cell.points.data(), ids.data()), cell.volume, 1e-14)
        << descriptor(type).name;
  }
}

TEST(descriptor, mirrored_cells_are_inverted) {
  for (CellType type : kTypes) {
    ReferenceCell cell = ideal_cell(type);
    for (std::size_t i = 2; i < cell.points.size(); i += 3) cell.points[i] = -cell.points[i];
    const auto ids = identity(descriptor(type).nb_vertices);
    EXPECT_LT(scaled_jacobian(type, cell.points.data(), ids.data()), 0.0) << descriptor(type).name;
    EXPECT_NEAR(cell_volume(type, cell.points.data(), ids.data()), -cell.volume, 1e-14);
  }
}

}  // namespace
}  // namespace hexmerge
