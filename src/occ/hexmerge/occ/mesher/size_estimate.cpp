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
