#pragma once
/// @file
/// Mends of the surface OpenCASCADE's mesher (BRepMesh) makes, done in triangulate() (internal
/// header of mesh_shape()): the nodes it leaves out of a face, the sides it gives two faces.

#include <cstddef>

#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

struct Shape;

/// Merges points closer than a tolerance into one node of a surface (triangulate()'s nodes).
class NodeMerger {
 public:
  NodeMerger(Surface& s, double tolerance)
      : s_(s), tol_(tolerance), nodes_(s.nodes, 4 * tolerance) {}
  /// The node within the tolerance of p, or a new one there (of `face`).
  int id(const Vec3& p, int face) {
    const int found = nodes_.find(p, tol_);
    if (found >= 0) return found;
    const int n = static_cast<int>(s_.nodes.size());
    s_.nodes.push_back(p);
    s_.node_face.push_back(face);
    nodes_.add(n);
    return n;
  }

 private:
  Surface& s_;
  double tol_;
  NodeHash nodes_;
};

/// A face's vertices on none of its edges (INTERNAL: where a solid touches another at a point,
/// BooleanFragments puts the point on the other's face) become nodes of the face's triangles:
/// BRepMesh leaves them out, and the face's triangles passed by the other solid's node there (a
/// random part's spike touching a box on top at its tip: "the surface's triangles cross" at every
/// size). Each takes the node at its place (the other solid's), the face's triangle nearest it
/// split in three (one of no area where it lies on a side: remove_flat_triangles() then splits
/// the triangle across), when that lies within twice the chord `deflection` of it. Each such
/// vertex's face goes to Surface::internal_vertex_faces.
void insert_internal_vertices(const Shape& s, double deflection, NodeMerger& merger,
                              Surface& surface);

/// Sides that BRepMesh gave two faces which only come close there (find_overused_sides(), the
/// faces apart along it by faces_meet_along() within `tolerance`): each such face's two triangles
/// on the side are split at a node of its own, the side's middle taken onto that face, so that
/// the faces part there (a random part's torus and cylinder 0.04 mm apart between two curves of
/// intersection, at h 18.7: the same chord in both faces at every chord deflection). How many
/// sides.
std::size_t part_shared_sides(const Shape& s, double tolerance, NodeMerger& merger,
                              Surface& surface);

}  // namespace hexmerge::mesher
