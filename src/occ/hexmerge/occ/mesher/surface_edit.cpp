#include "hexmerge/occ/mesher/surface_edit.h"

#include <BRep_Tool.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Pnt2d.hxx>

#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/shape.h"

namespace hexmerge::mesher {

FaceGaps::FaceGaps(const Shape& s, double deflection, double target, const SizeField* field)
    : s_(s), deflection_(deflection), target_(target), field_(field), surfaces_(s.faces.Extent()) {}

FaceGaps::~FaceGaps() = default;

double FaceGaps::of(int face, const std::array<Vec3, 3>& p, const std::array<UV, 3>& uv) {
  if (!surfaces_[face])
    surfaces_[face] = std::make_unique<ShapeAnalysis_Surface>(
        BRep_Tool::Surface(TopoDS::Face(s_.faces(face + 1))));
  ShapeAnalysis_Surface& surface = *surfaces_[face];
  const Vec3 c = (p[0] + p[1] + p[2]) * (1.0 / 3);
  const gp_Pnt2d middle((uv[0].u + uv[1].u + uv[2].u) / 3, (uv[0].v + uv[1].v + uv[2].v) / 3);
  surface.NextValueOfUV(middle, gp_Pnt(c.x, c.y, c.z), 1e-3 * deflection_);
  // (The gap over the local share of the deflection; unbounded, no field is asked.)
  if (field_ == nullptr || !bounded()) return surface.Gap();
  return surface.Gap() / std::min(1.0, field_->at(c) / target_);
}

// Node r's segments to a and b (both on one CAD edge) become the one segment from a to b, with
// the edge's parameters at a and b.
void join_segments(Surface& surface, int r, int a, int b) {
  const auto ra = surface.segments.find(pair_key(r, a)), rb = surface.segments.find(pair_key(r, b));
  const auto t_at = [](const std::pair<const std::uint64_t, EdgeSegment>& segment, int n) {
    return pair_lo(segment.first) == n ? segment.second.t_lo : segment.second.t_hi;
  };
  const double ta = t_at(*ra, a), tb = t_at(*rb, b);
  const int edge = ra->second.edge;
  surface.segments.erase(ra);
  surface.segments.erase(rb);
  surface.segments[pair_key(a, b)] = a < b ? EdgeSegment{edge, ta, tb} : EdgeSegment{edge, tb, ta};
}

// The triangles in `slots` (a node's, taken out) replaced by `made` (as many or fewer: the
// slots left over die), the nodes' lists of their triangles (`around`) kept up to date.
void replace_triangles(std::vector<SurfaceTriangle>& tris, std::vector<std::vector<int>>& around,
                       std::vector<char>& dead, const std::vector<int>& slots,
                       const std::vector<SurfaceTriangle>& made) {
  for (int ti : slots)
    for (int n : tris[ti].node)
      around[n].erase(std::remove(around[n].begin(), around[n].end(), ti), around[n].end());
  for (std::size_t k = 0; k < slots.size(); ++k) {
    const int ti = slots[k];
    if (k >= made.size()) {
      dead[ti] = 1;
      continue;
    }
    tris[ti] = made[k];
    for (int n : made[k].node) around[n].push_back(ti);
  }
}

// The surface without its `removed` nodes and `dead` triangles, the rest renumbered in their
// order, with their segments; Surface::seed gives each node's index in `surface` or, with
// `keep_seeds`, the seed it had there.
void drop_removed(Surface& surface, const std::vector<char>& removed, const std::vector<char>& dead,
                  bool keep_seeds) {
  const int nb_nodes = static_cast<int>(surface.nodes.size());
  std::vector<int> renumber(nb_nodes, -1);
  Surface out;
  for (int n = 0; n < nb_nodes; ++n)
    if (!removed[n]) {
      renumber[n] = static_cast<int>(out.nodes.size());
      out.nodes.push_back(surface.nodes[n]);
      out.node_face.push_back(surface.node_face[n]);
      out.seed.push_back(keep_seeds && !surface.seed.empty() ? surface.seed[n] : n);
    }
  for (std::size_t ti = 0; ti < surface.triangles.size(); ++ti) {
    if (dead[ti]) continue;
    SurfaceTriangle t = surface.triangles[ti];
    for (int& n : t.node) n = renumber[n];
    out.triangles.push_back(t);
  }
  out.unrefined_faces = surface.unrefined_faces;
  for (const auto& [key, segment] : surface.segments)
    out.segments[pair_key(renumber[pair_lo(key)], renumber[pair_hi(key)])] = segment;
  surface = std::move(out);
}

}  // namespace hexmerge::mesher
