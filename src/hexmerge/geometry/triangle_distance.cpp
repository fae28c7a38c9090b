#include "hexmerge/geometry/triangle_distance.h"

namespace hexmerge {

Vec3 nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double& s,
                         double& t) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return s = 0, t = 0, a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return s = 1, t = 0, b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    s = d1 / (d1 - d3), t = 0;
    return a + ab * s;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return s = 0, t = 1, c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    s = 0, t = d2 / (d2 - d6);
    return a + ac * t;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    s = 1 - w, t = w;
    return b + (c - b) * w;
  }
  const double denom = 1.0 / (va + vb + vc);
  s = vb * denom, t = vc * denom;
  return a + ab * s + ac * t;
}

double squared_distance_to_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  double s = 0, t = 0;
  const Vec3 d = p - nearest_on_triangle(p, a, b, c, s, t);
  return d.dot(d);
}

}  // namespace hexmerge
