#include "hexmerge/occ/mesher/frame.h"

#include <cmath>

#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {

Frame make_frame(const Vec3& e3, const Vec3* e1_hint, const Vec3 (&fallback)[3]) {
  Frame f;
  f.axis[2] = unit(e3);
  Vec3 e1{0, 0, 0};
  if (e1_hint) e1 = *e1_hint;
  if (e1.norm() < 0.5) {
    // The fallback axis least aligned with e3.
    double best = 2;
    for (const Vec3& a : fallback)
      if (std::abs(a.dot(f.axis[2])) < best) best = std::abs(a.dot(f.axis[2])), e1 = a;
  }
  e1 = e1 - f.axis[2] * e1.dot(f.axis[2]);
  f.axis[0] = unit(e1);
  f.axis[1] = f.axis[2].cross(f.axis[0]);
  return f;
}

}  // namespace hexmerge::mesher
