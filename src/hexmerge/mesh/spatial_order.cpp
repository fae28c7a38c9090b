#include "hexmerge/mesh/spatial_order.h"

#include <algorithm>
#include <cstdint>

namespace hexmerge {
namespace {

// The low 21 bits of v spread to every third bit.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

}  // namespace

std::vector<index_t> spatial_order(const TetMesh& mesh) {
  const index_t nt = mesh.nb_tets();
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = mesh.points.empty() ? 0.0 : mesh.points[k];
  for (index_t v = 0; v < mesh.nb_vertices(); ++v) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], mesh.point(v)[k]);
      hi[k] = std::max(hi[k], mesh.point(v)[k]);
    }
  }
  // Cells of the curve: about four tets per cell, so that one counting sort on the cell is
  // enough (tets within a cell stay in id order; a cell is small enough to be in cache).
  int bits = 1;
  while (bits < 21 && (std::uint64_t{1} << (3 * bits)) < nt / 4) ++bits;
  const double cells = static_cast<double>((1 << bits) - 1);
  // Centroids are compared as sums of four corners: the box scales by four too.
  double scale[3];
  for (int k = 0; k < 3; ++k) scale[k] = hi[k] > lo[k] ? cells / (4.0 * (hi[k] - lo[k])) : 0.0;
  std::vector<std::uint64_t> cell_of(nt);
  for (index_t t = 0; t < nt; ++t) {
    const index_t* q = mesh.tet(t);
    std::uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const double sum =
          mesh.point(q[0])[k] + mesh.point(q[1])[k] + mesh.point(q[2])[k] + mesh.point(q[3])[k];
      const double cell = std::clamp((sum - 4.0 * lo[k]) * scale[k], 0.0, cells);
      key |= spread_bits(static_cast<std::uint64_t>(cell)) << k;
    }
    cell_of[t] = key;
  }
  std::vector<index_t> start((std::size_t{1} << (3 * bits)) + 1, 0);
  for (index_t t = 0; t < nt; ++t) ++start[cell_of[t] + 1];
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<index_t> order(nt);
  for (index_t t = 0; t < nt; ++t) order[start[cell_of[t]]++] = t;
  return order;
}

TetMesh reorder_tets(const TetMesh& mesh, const std::vector<index_t>& order) {
  TetMesh out;
  out.points = mesh.points;
  out.tets.resize(mesh.tets.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    std::copy_n(mesh.tet(order[i]), 4, &out.tets[4 * i]);
  }
  if (!mesh.regions.empty()) {
    out.regions.resize(order.size());
    for (std::size_t i = 0; i < order.size(); ++i) out.regions[i] = mesh.regions[order[i]];
  }
  return out;
}

}  // namespace hexmerge
