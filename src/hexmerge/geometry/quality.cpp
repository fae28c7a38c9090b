#include "hexmerge/geometry/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hexmerge/geometry/vec3.h"

namespace hexmerge {
namespace {

constexpr double kRadToDeg = 57.29577951308232;
constexpr double kDegToRad = 0.017453292519943295;
// A cosine this far from a bound's cosine decides the comparison of its angle with the bound:
// |d acos / dc| >= 1, so the angles differ by at least 1e-9 rad, far more than the rounding of
// the cosine, of the bound's cosine and of the angle computed from the cosine.
constexpr double kCosineMargin = 1e-9;

// The cosine of the angle between u and v; false when one of them is zero (the angle is then
// taken as 180 degrees).
bool cosine(const Vec3& u, const Vec3& v, double& c) {
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0.0 || nv == 0.0) return false;
  c = std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0);
  return true;
}

double angle_deg(const Vec3& u, const Vec3& v) {
  double c;
  return cosine(u, v, c) ? std::acos(c) * kRadToDeg : 180.0;
}

// angle_deg(u, v) > bound.degrees, the same answer.
bool angle_above(const Vec3& u, const Vec3& v, const AngleBound& bound) {
  // cosine(u, v, c), its products computed once (sqrt(u.u) is 0 exactly when u.u is).
  const double uu = u.dot(u), vv = v.dot(v), uv = u.dot(v);
  if (uu == 0.0 || vv == 0.0) return 180.0 > bound.degrees;
  // An angle of at most 90 degrees (u.v >= 0, so c >= 0, or NaN when |u| |v| is 0 or infinite
  // after rounding, which fails every comparison below) is not above a bound whose cosine is
  // below -kCosineMargin: the answer without the square roots and the division.
  if (uv >= 0.0 && bound.cosine < -kCosineMargin) return false;
  const double c = std::clamp(uv / (std::sqrt(uu) * std::sqrt(vv)), -1.0, 1.0);
  if (c < bound.cosine - kCosineMargin) return true;
  if (c > bound.cosine + kCosineMargin) return false;
  return std::acos(c) * kRadToDeg > bound.degrees;
}

}  // namespace

double tet_volume(const double* a, const double* b, const double* c, const double* d) {
  const Vec3 pa = Vec3::of(a);
  return det3(Vec3::of(b) - pa, Vec3::of(c) - pa, Vec3::of(d) - pa) / 6.0;
}

double cell_volume(CellType type, const double* points, const index_t* vertices) {
  const CellDescriptor& d = descriptor(type);
  auto p = [&](int local) {
    return Vec3::of(points + 3 * static_cast<std::size_t>(vertices[local]));
  };
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

namespace {

// scaled_jacobian() of a tet, to the last bit: the same corners and arithmetic as the general
// loop (cell_type.cpp's tet corners {0,1,2,3}, {1,2,0,3}, {2,0,1,3}, {3,0,2,1}). The mesher's flips
// and node moves evaluate tets by the million: with SSE2 (every x86-64) two corners go in each
// register, each lane doing exactly the scalar operations in the same order (IEEE addition,
// subtraction, multiplication, division and square root round the same in a lane as alone; no
// fused multiply-add), so the result is the same double.
#if defined(__SSE2__)
struct Lanes {  // a vector per lane: lane 0 and lane 1 are two corners
  __m128d x, y, z;
};
inline Lanes lanes(const Vec3& low, const Vec3& high) {
  return {_mm_set_pd(high.x, low.x), _mm_set_pd(high.y, low.y), _mm_set_pd(high.z, low.z)};
}
inline Lanes operator-(const Lanes& a, const Lanes& b) {
  return {_mm_sub_pd(a.x, b.x), _mm_sub_pd(a.y, b.y), _mm_sub_pd(a.z, b.z)};
}
inline __m128d dot(const Lanes& a, const Lanes& b) {  // Vec3::dot's order
  return _mm_add_pd(_mm_add_pd(_mm_mul_pd(a.x, b.x), _mm_mul_pd(a.y, b.y)), _mm_mul_pd(a.z, b.z));
}
inline Lanes cross(const Lanes& a, const Lanes& b) {  // Vec3::cross's order
  return {_mm_sub_pd(_mm_mul_pd(a.y, b.z), _mm_mul_pd(a.z, b.y)),
          _mm_sub_pd(_mm_mul_pd(a.z, b.x), _mm_mul_pd(a.x, b.z)),
          _mm_sub_pd(_mm_mul_pd(a.x, b.y), _mm_mul_pd(a.y, b.x))};
}
// The corners' ratios det3(a, b, c) / (|a| |b| |c|) (0 where the product is not positive), for
// the corners at q with edges a, b, c in each lane. |p - q| and |q - p| are the same double.
inline __m128d corner_ratios(const Lanes& q, const Lanes& a_end, const Lanes& b_end,
                             const Lanes& c_end) {
  const Lanes a = a_end - q, b = b_end - q, c = c_end - q;
  const __m128d la = _mm_sqrt_pd(dot(a, a)), lb = _mm_sqrt_pd(dot(b, b)),
                lc = _mm_sqrt_pd(dot(c, c));
  const __m128d l = _mm_mul_pd(_mm_mul_pd(la, lb), lc);
  const __m128d ratio = _mm_div_pd(dot(cross(a, b), c), l);
  return _mm_and_pd(_mm_cmpgt_pd(l, _mm_setzero_pd()), ratio);
}
#endif

double tet_scaled_jacobian(const double* points, const index_t* vertices, double scale) {
  const Vec3 p0 = Vec3::of(points + 3 * static_cast<std::size_t>(vertices[0]));
  const Vec3 p1 = Vec3::of(points + 3 * static_cast<std::size_t>(vertices[1]));
  const Vec3 p2 = Vec3::of(points + 3 * static_cast<std::size_t>(vertices[2]));
  const Vec3 p3 = Vec3::of(points + 3 * static_cast<std::size_t>(vertices[3]));
  double ratio[4];
#if defined(__SSE2__)
  // Corners 0 and 1, then 2 and 3.
  _mm_storeu_pd(ratio, corner_ratios(lanes(p0, p1), lanes(p1, p2), lanes(p2, p0), lanes(p3, p3)));
  _mm_storeu_pd(ratio + 2,
                corner_ratios(lanes(p2, p3), lanes(p0, p0), lanes(p1, p2), lanes(p3, p1)));
#else
  const Vec3 e01 = p1 - p0, e02 = p2 - p0, e03 = p3 - p0;
  const Vec3 e12 = p2 - p1, e10 = p0 - p1, e13 = p3 - p1;
  const Vec3 e20 = p0 - p2, e21 = p1 - p2, e23 = p3 - p2;
  const Vec3 e30 = p0 - p3, e32 = p2 - p3, e31 = p1 - p3;
  const double l01 = e01.norm(), l02 = e02.norm(), l03 = e03.norm();
  const double l12 = e12.norm(), l13 = e13.norm(), l23 = e23.norm();
  auto corner = [](const Vec3& a, const Vec3& b, const Vec3& c, double la, double lb, double lc) {
    const double l = la * lb * lc;
    return l > 0.0 ? det3(a, b, c) / l : 0.0;
  };
  ratio[0] = corner(e01, e02, e03, l01, l02, l03);
  ratio[1] = corner(e12, e10, e13, l12, l01, l13);
  ratio[2] = corner(e20, e21, e23, l02, l12, l23);
  ratio[3] = corner(e30, e32, e31, l03, l23, l13);
#endif
  double worst = 1e300;  // as the general loop starts (a NaN corner then leaves it)
  for (const double r : ratio) worst = std::min(worst, r);
  return std::min(1.0, worst * scale);
}

}  // namespace

double scaled_jacobian(CellType type, const double* points, const index_t* vertices) {
  const CellDescriptor& d = descriptor(type);
  if (type == CellType::Tet) return tet_scaled_jacobian(points, vertices, d.jacobian_scale);
  auto p = [&](int local) {
    return Vec3::of(points + 3 * static_cast<std::size_t>(vertices[local]));
  };
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

// Outside [0, 180] degrees the cosine is no monotone image of the angle: NaN then fails both
// shortcut comparisons, and every comparison takes the arccosine.
AngleBound::AngleBound(double bound)
    : degrees(bound),
      cosine(bound >= 0.0 && bound <= 180.0 ? std::cos(bound * kDegToRad)
                                            : std::numeric_limits<double>::quiet_NaN()) {}

bool quad_dihedral_angle_below(const double* a, const double* b, const double* c, const double* d,
                               const AngleBound& min_angle) {
  const Vec3 pa = Vec3::of(a), pb = Vec3::of(b), pc = Vec3::of(c), pd = Vec3::of(d);
  const Vec3 n1 = (pb - pa).cross(pc - pa);
  const Vec3 n2 = (pc - pa).cross(pd - pa);
  // 180 - angle(n1, n2) < min: the normals' angle is above 180 - min, whose cosine is -cos(min).
  double cn;
  if (!cosine(n1, n2, cn)) return 180.0 - 180.0 < min_angle.degrees;
  if (cn < -min_angle.cosine - kCosineMargin) return true;
  if (cn > -min_angle.cosine + kCosineMargin) return false;
  return 180.0 - std::acos(cn) * kRadToDeg < min_angle.degrees;
}

bool quad_max_corner_angle_above(const double* a, const double* b, const double* c, const double* d,
                                 const AngleBound& max_angle) {
  const Vec3 q[4] = {Vec3::of(a), Vec3::of(b), Vec3::of(c), Vec3::of(d)};
  if (0.0 > max_angle.degrees) return true;  // quad_max_corner_angle starts from 0
  for (int i = 0; i < 4; ++i) {
    if (angle_above(q[(i + 3) % 4] - q[i], q[(i + 1) % 4] - q[i], max_angle)) return true;
  }
  return false;
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

bool quad_is_planar(const double* a, const double* b, const double* c, const double* d) {
  const Vec3 p0 = Vec3::of(a), p1 = Vec3::of(b), p2 = Vec3::of(c), p3 = Vec3::of(d);
  const Vec3 n = (p1 - p0).cross(p2 - p0);
  const double scale = (p1 - p0).norm() * (p2 - p0).norm() * (p3 - p0).norm();
  return !(std::abs(n.dot(p3 - p0)) > 1e-9 * scale);
}

}  // namespace hexmerge
