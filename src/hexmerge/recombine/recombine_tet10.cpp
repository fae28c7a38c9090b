#include "hexmerge/recombine/recombine.h"

namespace hexmerge {

QuadraticMixedMesh recombine(const Tet10Mesh& input, const RecombineParameters& parameters,
                             RecombineReport& report, const ProgressCallback& progress) {
  const TetMesh corners = corner_mesh(input);  // checks the array sizes first
  validate_tet10_mesh(input);                  // before the run, not after it
  QuadraticMixedMesh out;
  out.linear = recombine(corners, parameters, report, progress);
  out.quadratic = quadratic_cells(out.linear, input);
  return out;
}

}  // namespace hexmerge
