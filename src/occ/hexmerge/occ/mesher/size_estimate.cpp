#include "hexmerge/occ/mesher/size_estimate.h"

#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace hexmerge::mesher {

SizeEstimate estimate_size(const TopoDS_Shape& shape, double size) {
  GProp_GProps volume, area;
  BRepGProp::VolumeProperties(shape, volume);
  BRepGProp::SurfaceProperties(shape, area);
  SizeEstimate e;
  e.tets = 11 * std::abs(volume.Mass()) / (size * size * size) + 10 * area.Mass() / (size * size);
  e.bytes = e.tets * kBytesPerTet;
  return e;
}

double estimate_local_tets(const TopTools_IndexedMapOfShape& faces,
                           const TopTools_IndexedMapOfShape& edges,
                           const std::vector<double>& face_size,
                           const std::vector<double>& edge_size, double h, double grading) {
  double tets = 0;
  for (int f = 1; f <= faces.Extent(); ++f) {
    const double s = face_size[f - 1];
    if (s >= h) continue;
    GProp_GProps area;
    BRepGProp::SurfaceProperties(faces(f), area);
    tets += area.Mass() *
            (10 / (s * s) + 11 / (2 * grading) * (1 / (s * s) - 1 / (h * h)) - 10 / (h * h));
  }
  for (int e = 1; e <= edges.Extent(); ++e) {
    const double s = edge_size[e - 1];
    if (s >= h) continue;
    GProp_GProps length;
    BRepGProp::LinearProperties(edges(e), length);
    tets += 11 * M_PI * length.Mass() / (grading * grading * s);
  }
  return tets;
}

std::uint64_t available_memory() {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream fields(line.substr(13));
      std::uint64_t kib = 0;
      if (fields >> kib) return kib * 1024;
    }
  return 0;
}

}  // namespace hexmerge::mesher
