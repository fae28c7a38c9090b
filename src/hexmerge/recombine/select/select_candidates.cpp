// The selection's entry: the strategy, and the order of the stages (Selector::run).
#include "hexmerge/recombine/select/select_candidates.h"

#include "hexmerge/core/parallel.h"
#include "hexmerge/recombine/select/selector.h"

namespace hexmerge {
namespace select {

Selection Selector::run(const ProgressCallback& progress) {
  std::vector<Stage> conforming, relaxed;
  const bool allow = params_.conformity == Conformity::Allow;
  for (CellType type : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
    conforming.push_back({type, allow});
    if (params_.conformity == Conformity::LastResort) relaxed.push_back({type, true});
  }
  report_progress(progress, "selection", 0.0);
  if (params_.conformity == Conformity::Conforming) select_block();
  if (strict_) select_groups();
  for (const Stage& stage : conforming) {
    if (params_.boundary_order == BoundaryOrder::Quality) {
      boundary_stage_by_quality(stage);
    } else {
      boundary_stage(stage);
    }
  }
  report_progress(progress, "selection", 0.25);
  if (params_.local_optimisation) local_optimisation();
  report_progress(progress, "selection", 0.5);
  const std::vector<index_t> order = breadth_first_order();
  for (const Stage& stage : conforming) interior_stage(stage, order);
  for (const Stage& stage : relaxed) interior_stage(stage, order);
  report_progress(progress, "selection", 0.75);
  close_quads();
  if (params_.local_search) local_search();
  if (params_.conformity != Conformity::Conforming) release_cracks();
  report_progress(progress, "selection", 1.0);
  for (index_t ci = 0; ci < cands_.size(); ++ci) {
    if (chosen_[ci]) result_.elements.push_back(ci);
  }
  result_.nonconforming_quads = 0;
  for (index_t ci : result_.elements) {
    result_.nonconforming_quads += violations(ci, false, false);
  }
  return result_;
}

}  // namespace select

Selection select_candidates(const TetMesh& mesh, const TetTopology& topology,
                            const Candidates& candidates, const RecombineParameters& parameters,
                            const ProgressCallback& progress) {
  // Conforming mode with pyramids: "safe pyramids" (a pending quad face only where a closing
  // pyramid is reserved for it; never releases). Without pyramids, and in the other modes:
  // "closable" (a pending quad needs only some candidate that could close it; in conforming mode
  // the elements that end up unclosed are released). Until issue 18 both ran in conforming mode
  // and the better was kept: "closable" never won on a benchmark mesh (docs/benchmarks.md).
  const select::CandidateIndex index(mesh, topology, candidates, parameters.respect_regions,
                                     thread_count(parameters.threads));
  const bool conforming = parameters.conformity == Conformity::Conforming;
  const bool safe_pyramids = conforming && parameters.make_pyramids;
  Selection selection =
      select::Selector(mesh, topology, candidates, index, parameters, safe_pyramids).run(progress);
  selection.strategy = safe_pyramids ? "safe_pyramids" : conforming ? "closable" : "";
  return selection;
}

}  // namespace hexmerge
