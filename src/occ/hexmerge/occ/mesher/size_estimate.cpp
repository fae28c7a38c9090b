#include "hexmerge/occ/mesher/size_estimate.h"

#include <sys/resource.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {

SizeEstimate estimate_size(const TopoDS_Shape& shape, double volume, double size,
                           double deflection) {
  GProp_GProps area;
  BRepGProp::SurfaceProperties(shape, area);
  SizeEstimate e;
  e.tets = 11 * std::abs(volume) / (size * size * size) + 10 * area.Mass() / (size * size);
  // Curved faces of small radius r: BRepMesh cuts them into strips (one per kSurfaceAngle or per
  // chord of sagitta `deflection`, the shorter), which refine() splits to h along: 2 A / (r a h)
  // triangles (a the strip's angle) where A / (0.433 h²) are at size h, that many times more.
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face& face = TopoDS::Face(ex.Current());
    const BRepAdaptor_Surface surface(face, false);
    double radius = 0;
    switch (surface.GetType()) {
      case GeomAbs_Cylinder:
        radius = surface.Cylinder().Radius();
        break;
      case GeomAbs_Sphere:
        radius = surface.Sphere().Radius();
        break;
      case GeomAbs_Torus:
        radius = surface.Torus().MinorRadius();
        break;
      default:
        continue;
    }
    const double strip =
        std::min(kSurfaceAngle, 2 * std::acos(std::max(-1.0, 1 - deflection / radius)));
    const double finer = 0.866 * size / (radius * strip);
    if (finer <= 1) continue;
    GProp_GProps face_area;
    BRepGProp::SurfaceProperties(face, face_area);
    e.tets += 10 * face_area.Mass() / (size * size) * (finer - 1);
  }
  e.bytes = e.tets * kBytesPerTet;
  return e;
}

double size_that_fits(const TopoDS_Shape& shape, double volume, double size,
                      double deflection_ratio, double bytes) {
  auto fits = [&](double h) {
    return estimate_size(shape, volume, h, deflection_ratio * h).bytes <= bytes;
  };
  double lo = size, hi = size;
  // Grown by the cube root of the excess (exact for the volume's term; the surface's grow
  // slower), then bisected to 1 %.
  for (int i = 0; i < 60 && !fits(hi); ++i) {
    lo = hi;
    hi *= std::max(
        1.01, std::cbrt(estimate_size(shape, volume, hi, deflection_ratio * hi).bytes / bytes));
  }
  while (hi > 1.01 * lo) {
    const double mid = std::sqrt(lo * hi);
    (fits(mid) ? hi : lo) = mid;
  }
  // Rounded up to three significant digits, as messages print it.
  const double unit = std::pow(10.0, std::floor(std::log10(hi)) - 2);
  return std::ceil(hi / unit) * unit;
}

namespace {

// The tets an area of local size s < h adds: 10 / s² on it, 11 / (2 g) (1 / s² - 1 / h²) in the
// zone graded by g inside, less its 10 / h² at h.
double graded_area_tets(double area, double s, double h, double grading) {
  return area * (10 / (s * s) + 11 / (2 * grading) * (1 / (s * s) - 1 / (h * h)) - 10 / (h * h));
}

}  // namespace

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
    tets += graded_area_tets(area.Mass(), s, h, grading);
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

double estimate_patch_tets(const std::vector<SizedTriangle>& patches, double h, double grading) {
  double tets = 0;
  for (const SizedTriangle& p : patches) {
    if (p.size < h)
      tets += graded_area_tets(0.5 * (p.b - p.a).cross(p.c - p.a).norm(), p.size, h, grading);
  }
  return tets;
}

void refuse_if_too_large(const SizeEstimate& estimate, const TopoDS_Shape& shape, double volume,
                         double size, double deflection_ratio, double memory_limit,
                         const std::string& why) {
  const double limit =
      memory_limit > 0 ? memory_limit * 1e9 : static_cast<double>(available_memory());
  if (!(limit > 0) || estimate.bytes <= limit) return;
  std::ostringstream text;
  text.precision(3);
  text << "mesh_shape: size " << size << " would make about " << estimate.tets / 1e6
       << " million tets" << (why.empty() ? "" : " (" + why + ")") << ", which need about "
       << estimate.bytes / 1e9 << " GB to mesh and recombine; "
       << (memory_limit > 0 ? "memory_limit is " : "the system has ") << limit / 1e9 << " GB"
       << (memory_limit > 0 ? "" : " available") << ": give a size of at least "
       << std::max(size * std::cbrt(estimate.bytes / limit),
                   size_that_fits(shape, volume, size, deflection_ratio, limit))
       << " (or raise memory_limit)";
  throw InputError(text.str(), Entity::Parameter);
}

namespace {

// The value in kiB of the line of a /proc file that starts with `key`, in bytes; 0 when absent.
std::uint64_t proc_bytes(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) {
      std::istringstream fields(line.substr(key.size()));
      std::uint64_t kib = 0;
      if (fields >> kib) return kib * 1024;
    }
  return 0;
}

}  // namespace

std::uint64_t available_memory() {
  std::uint64_t available = proc_bytes("/proc/meminfo", "MemAvailable:");
  // A limit on the process's address space (ulimit -v; the benchmark's runs have 8 GB) leaves
  // it what the limit has above the space it holds now.
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    const std::uint64_t held = proc_bytes("/proc/self/status", "VmSize:");
    const std::uint64_t left = limit.rlim_cur > held ? limit.rlim_cur - held : 1;
    available = available > 0 ? std::min(available, left) : left;
  }
  return available;
}

}  // namespace hexmerge::mesher
