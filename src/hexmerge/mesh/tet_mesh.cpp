#include "hexmerge/mesh/tet_mesh.h"

#include <algorithm>
#include <cmath>

namespace hexmerge {

int normalising_exponent(const std::vector<double>& points) {
  double largest = 0.0;
  for (const double c : points) {
    if (std::isfinite(c)) largest = std::max(largest, std::fabs(c));
  }
  if (largest == 0.0 || (largest >= std::ldexp(1.0, -32) && largest <= std::ldexp(1.0, 32))) {
    return 0;
  }
  int e = 0;
  std::frexp(largest, &e);  // largest = m 2^e, m in [0.5, 1)
  return 1 - e;
}

}  // namespace hexmerge
