// The selection's entry (select/select_candidates.cpp): which strategy runs, and what every
// strategy guarantees of the selection it returns.
#include "hexmerge/recombine/select/select_candidates.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fixtures.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/prune_candidates.h"

namespace hexmerge::test {
namespace {

void remove_unclosable_candidates(const TetMesh& mesh, Candidates& candidates) {
  std::size_t removed = 0;
  candidates = prune_unclosable(mesh, TetTopology(mesh), candidates, removed);
}

struct StrategyCase {
  Conformity conformity;
  bool make_pyramids;
  const char* strategy;
};

// Conforming mode with pyramids reserves a closing pyramid for every pending quad face
// ("safe_pyramids"); without pyramids it can only count on some closer ("closable"); the other
// modes name no strategy. Whatever runs, the chosen candidates hold disjoint tets, and in
// conforming mode no quad face is left meeting two triangles.
TEST(select_candidates, names_the_strategy_it_ran_and_keeps_the_selection_disjoint) {
  const TetMesh mesh = kuhn_grid(4);
  const TetTopology topology(mesh);
  const Candidates all = find_candidates(mesh, topology, AcceptanceCriteria{}, 1);
  ASSERT_FALSE(all.empty());
  for (const StrategyCase& c : {StrategyCase{Conformity::Conforming, true, "safe_pyramids"},
                                StrategyCase{Conformity::Conforming, false, "closable"},
                                StrategyCase{Conformity::LastResort, true, ""},
                                StrategyCase{Conformity::Allow, true, ""}}) {
    SCOPED_TRACE(to_string(c.conformity) + (c.make_pyramids ? "" : ", no pyramids"));
    RecombineParameters p;
    p.conformity = c.conformity;
    p.make_pyramids = c.make_pyramids;
    // As recombine offers them: without pyramids when none may be made, and in conforming
    // mode without the candidates no conforming selection can hold.
    Candidates offered;
    for (const Candidate& x : all) {
      if (c.make_pyramids || x.type != CellType::Pyramid) {
        offered.push_back(x, all.tets(x).data(), x.nb_tets);
      }
    }
    if (c.conformity == Conformity::Conforming) remove_unclosable_candidates(mesh, offered);
    const Selection s = select_candidates(mesh, topology, offered, p);
    EXPECT_EQ(s.strategy, c.strategy);
    EXPECT_FALSE(s.elements.empty());
    std::vector<int> owners(mesh.nb_tets(), 0);
    for (index_t ci : s.elements) {
      ASSERT_LT(ci, offered.size());
      for (const index_t t : offered.tets(ci)) ++owners[t];
    }
    for (index_t t = 0; t < mesh.nb_tets(); ++t) EXPECT_LE(owners[t], 1) << "tet " << t;
    if (c.conformity == Conformity::Conforming) {
      EXPECT_EQ(s.nonconforming_quads, 0u);
    }
  }
}

}  // namespace
}  // namespace hexmerge::test
