#include "hexmerge/recombine/recombine.h"

namespace hexmerge {

QuadraticMixedMesh recombine(const Tet10Mesh& input, const RecombineParameters& parameters,
                             RecombineReport& report, const ProgressCallback& progress) {
  const TetMesh corners = corner_mesh(input);  // checks the array sizes first
  validate_tet10_mesh(input);                  // before the run, not after it
  // The post-merge stage's flips make edges that have no mid-edge node in a Tet10 mesh: it is
  // off for quadratic input, and the report says so.
  RecombineParameters linear = parameters;
  linear.same_nodes = true;
  QuadraticMixedMesh out;
  out.linear = recombine(corners, linear, report, progress);
  if (!parameters.same_nodes) report.post_merge = "off: Tet10 input";
  out.quadratic = quadratic_cells(out.linear, input);
  return out;
}

}  // namespace hexmerge
