#include "hexmerge/geometry/quality.h"

#include <algorithm>
#include <cmath>

#include "hexmerge/geometry/vec3.h"

namespace hexmerge {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

double angle_deg(const Vec3& u, const Vec3& v) {
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0.0 || nv == 0.0) return 180.0;
  const double c = std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0);
  return std::acos(c) * kRadToDeg;
}

}  // namespace

double tet_volume(const double* a, const double* b, const double* c, const double* d) {
  const Vec3 pa = Vec3::of(a);
  return det3(Vec3::of(b) - pa, Vec3::of(c) - pa, Vec3::of(d) - pa) / 6.0;
}

double cell_volume(CellType type, const double* points, const index_t* vertices) {
  const CellDescriptor& d = descriptor(type);
  auto p = [&](int local) { return Vec3::of(points + 3 * static_cast<std::size_t>(vertices[local])); };
  // Volumes of the cones from a reference point to the outward faces; the reference is the
  // first vertex, which keeps the arithmetic well conditioned.
  const Vec3 o = p(0);
  double six_volume = 0.0;
  for (int f = 0; f < d.nb_faces; ++f) {
    const auto& fv = d.face[f];
    const Vec3 a = p(fv[0]) - o, b = p(fv[1]) - o, c = p(fv[2]) - o;
    if (d.face_size[f] == 3) {
      six_volume += det3(a, b, c);
    } else {
      const Vec3 e = p(fv[3]) - o;
      six_volume += 0.5 * (det3(a, b, c) + det3(a, c, e) + det3(a, b, e) + det3(b, c, e));
    }
  }
  return six_volume / 6.0;
}

double scaled_jacobian(CellType type, const double* points, const index_t* vertices) {
  const CellDescriptor& d = descriptor(type);
  auto p = [&](int local) { return Vec3::of(points + 3 * static_cast<std::size_t>(vertices[local])); };
  double worst = 1e300;
  for (int k = 0; k < d.nb_corners; ++k) {
    const auto& c = d.corner[k];
    const Vec3 v = p(c[0]);
    const Vec3 e1 = p(c[1]) - v, e2 = p(c[2]) - v, e3 = p(c[3]) - v;
    const double l = e1.norm() * e2.norm() * e3.norm();
    const double j = l > 0.0 ? det3(e1, e2, e3) / l : 0.0;
    worst = std::min(worst, j);
  }
  return std::min(1.0, worst * d.jacobian_scale);
}

double quad_dihedral_angle(const double* a, const double* b, const double* c, const double* d) {
  const Vec3 pa = Vec3::of(a), pb = Vec3::of(b), pc = Vec3::of(c), pd = Vec3::of(d);
  const Vec3 n1 = (pb - pa).cross(pc - pa);
  const Vec3 n2 = (pc - pa).cross(pd - pa);
  // Flat quad: both normals agree, the angle between them is 0 and the dihedral angle 180.
  return 180.0 - angle_deg(n1, n2);
}

double quad_max_corner_angle(const double* a, const double* b, const double* c, const double* d) {
  const Vec3 q[4] = {Vec3::of(a), Vec3::of(b), Vec3::of(c), Vec3::of(d)};
  double worst = 0.0;
  for (int i = 0; i < 4; ++i) {
    const Vec3& prev = q[(i + 3) % 4];
    const Vec3& next = q[(i + 1) % 4];
    worst = std::max(worst, angle_deg(prev - q[i], next - q[i]));
  }
  return worst;
}

}  // namespace hexmerge
