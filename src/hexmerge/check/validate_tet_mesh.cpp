#include "hexmerge/check/validate_tet_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {

void validate_tet_mesh(const TetMesh& mesh) {
  if (mesh.points.size() % 3 != 0) {
    throw InputError("the point array must have 3 coordinates per point");
  }
  if (mesh.tets.size() % 4 != 0) {
    throw InputError("the tetrahedron array must have 4 vertex ids per tetrahedron");
  }
  const index_t nv = mesh.nb_vertices();
  const index_t nt = mesh.nb_tets();
  if (nt == 0) throw InputError("the mesh has no tetrahedra");
  if (!mesh.regions.empty() && mesh.regions.size() != nt) {
    throw InputError("the region array has " + std::to_string(mesh.regions.size()) +
                     " entries for " + std::to_string(nt) + " tetrahedra");
  }
  for (index_t v = 0; v < nv; ++v) {
    const double* p = mesh.point(v);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw InputError("node " + std::to_string(v) + " has a NaN or infinite coordinate",
                       Entity::Node, v);
    }
  }
  for (index_t t = 0; t < nt; ++t) {
    const index_t* q = mesh.tet(t);
    for (int i = 0; i < 4; ++i) {
      if (q[i] >= nv) {
        throw InputError("tetrahedron " + std::to_string(t) + " refers to node " +
                             std::to_string(q[i]) + ", but the mesh has " + std::to_string(nv) +
                             " nodes",
                         Entity::Element, t);
      }
      for (int j = 0; j < i; ++j) {
        if (q[i] == q[j]) {
          throw InputError(
              "tetrahedron " + std::to_string(t) + " uses node " + std::to_string(q[i]) + " twice",
              Entity::Element, t);
        }
      }
    }
    const double v =
        tet_volume(mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3]));
    if (!(v > 0.0)) {
      throw InputError("tetrahedron " + std::to_string(t) +
                           (v < 0.0 ? " is inverted (negative volume " : " has zero volume (") +
                           std::to_string(v) + ")",
                       Entity::Element, t);
    }
    // Flat to round-off: a positive volume that is noise against the tet's size (the scaled
    // Jacobian does not depend on the scale); its sign could flip in any other computation.
    const double sj = scaled_jacobian(CellType::Tet, mesh.points.data(), q);
    if (!(sj > kMinInputScaledJacobian)) {
      char text[32];
      std::snprintf(text, sizeof text, "%.3g", sj);
      throw InputError("tetrahedron " + std::to_string(t) +
                           " is flat to round-off (scaled Jacobian " + text + ")",
                       Entity::Element, t);
    }
  }
  // Duplicate tets: the sorted vertex quadruples, bucketed by their smallest vertex (a counting
  // sort) and sorted within each bucket; a duplicate is equal to the next one. The first pair in
  // the lexicographic order of the quadruples is reported.
  std::vector<index_t> bucket_start(static_cast<std::size_t>(nv) + 1, 0);
  std::vector<std::array<index_t, 4>> sorted_tets(nt);
  for (index_t t = 0; t < nt; ++t) {
    std::array<index_t, 4>& k = sorted_tets[t];
    std::copy_n(mesh.tet(t), 4, k.begin());
    std::sort(k.begin(), k.end());
    ++bucket_start[k[0] + 1];
  }
  for (index_t v = 0; v < nv; ++v) bucket_start[v + 1] += bucket_start[v];
  std::vector<std::array<index_t, 4>> keys(nt);  // the three larger vertices, then the tet
  {
    std::vector<index_t> fill(bucket_start.begin(), bucket_start.end() - 1);
    for (index_t t = 0; t < nt; ++t) {
      const auto& k = sorted_tets[t];
      keys[fill[k[0]]++] = {k[1], k[2], k[3], t};
    }
  }
  for (index_t v = 0; v < nv; ++v) {
    const auto begin = keys.begin() + bucket_start[v], end = keys.begin() + bucket_start[v + 1];
    std::sort(begin, end);
    for (auto it = begin; it != end && it + 1 != end; ++it) {
      if (std::equal(it->begin(), it->begin() + 3, (it + 1)->begin())) {
        throw InputError("tetrahedra " + std::to_string((*it)[3]) + " and " +
                             std::to_string((*(it + 1))[3]) + " are duplicates (same four nodes)",
                         Entity::Element, (*(it + 1))[3]);
      }
    }
  }
}

}  // namespace hexmerge
