// Candidates: the records and their tets in one shared array.
#include "hexmerge/recombine/candidates.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "fixtures.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/prune_candidates.h"

namespace hexmerge {
namespace {

std::vector<index_t> as_vector(TetSpan tets) { return {tets.begin(), tets.end()}; }

// Random sorted, distinct tet lists of 1 to MAX_CANDIDATE_TETS tets, each with its record.
struct Reference {
  std::vector<Candidate> records;
  std::vector<std::vector<index_t>> tets;
};

Reference random_candidates(std::mt19937& rng, int count) {
  Reference r;
  std::uniform_int_distribution<int> size(1, MAX_CANDIDATE_TETS);
  std::uniform_int_distribution<index_t> tet(0, 999);
  for (int i = 0; i < count; ++i) {
    std::vector<index_t> t;
    const int n = size(rng);
    while (static_cast<int>(t.size()) < n) {
      const index_t x = tet(rng);
      if (std::find(t.begin(), t.end(), x) == t.end()) t.push_back(x);
    }
    std::sort(t.begin(), t.end());
    Candidate c{};
    c.vertices.fill(NO_VERTEX);
    c.vertices[0] = static_cast<index_t>(i);
    c.type = static_cast<CellType>(1 + i % 3);
    c.graph = static_cast<std::uint8_t>(i % 7);
    c.quality = 0.5f + 0.001f * static_cast<float>(i);
    r.records.push_back(c);
    r.tets.push_back(t);
  }
  return r;
}

// What the container holds is what was put in, record by record, and its tet array is the lists
// one after the other (the layout every reader relies on).
void expect_holds(const Candidates& cs, const Reference& r, const std::vector<char>& kept) {
  std::vector<index_t> all;
  std::size_t i = 0;
  for (std::size_t k = 0; k < r.records.size(); ++k) {
    if (!kept[k]) continue;
    ASSERT_LT(i, cs.size());
    const Candidate& c = cs[i];
    EXPECT_EQ(c.vertices, r.records[k].vertices) << k;
    EXPECT_EQ(c.type, r.records[k].type);
    EXPECT_EQ(c.graph, r.records[k].graph);
    EXPECT_EQ(c.quality, r.records[k].quality);
    EXPECT_EQ(c.nb_tets, r.tets[k].size());
    EXPECT_EQ(c.first_tet, all.size());
    EXPECT_EQ(as_vector(cs.tets(i)), r.tets[k]) << k;
    EXPECT_EQ(as_vector(cs.tets(c)), r.tets[k]) << k;
    for (index_t t : r.tets[k]) EXPECT_TRUE(cs.tets(i).contains(t));
    all.insert(all.end(), r.tets[k].begin(), r.tets[k].end());
    ++i;
  }
  EXPECT_EQ(i, cs.size());
  EXPECT_EQ(cs.all_tets(), all);
}

TEST(Candidates, TetListsRoundTripThroughPushBackAppendAndKeepIf) {
  std::mt19937 rng(18);
  const Reference r = random_candidates(rng, 300);
  Candidates cs;
  for (std::size_t k = 0; k < 200; ++k) {
    cs.push_back(r.records[k], r.tets[k].data(), static_cast<int>(r.tets[k].size()));
  }
  Candidates rest;
  for (std::size_t k = 200; k < r.records.size(); ++k) {
    rest.push_back(r.records[k], r.tets[k].data(), static_cast<int>(r.tets[k].size()));
  }
  cs.append(rest);
  std::vector<char> kept(r.records.size(), 1);
  expect_holds(cs, r, kept);
  // The same records and tets given as arrays make the same container.
  const Candidates copy(std::vector<Candidate>(cs.begin(), cs.end()), cs.all_tets());
  expect_holds(copy, r, kept);

  // keep_if: the kept ones in order, their tets moved up with them; the predicate may read the
  // candidate it is asked about.
  std::bernoulli_distribution coin(0.4);
  for (char& k : kept) k = coin(rng);
  std::size_t asked = 0;
  cs.keep_if([&](index_t ci) {
    EXPECT_EQ(ci, asked++);
    EXPECT_EQ(as_vector(cs.tets(ci)), r.tets[ci]);
    return kept[ci] != 0;
  });
  EXPECT_EQ(asked, r.records.size());
  expect_holds(cs, r, kept);
  cs.keep_if([](index_t) { return false; });
  EXPECT_TRUE(cs.empty());
  EXPECT_TRUE(cs.all_tets().empty());
}

TEST(Candidates, ABrokenLayoutIsRefused) {
  Candidate c{};
  c.nb_tets = 2;
  c.first_tet = 1;  // not where the array begins
  EXPECT_THROW(Candidates({c}, {4, 5, 6}), InternalError);
  c.first_tet = 0;  // tets past the last record's
  EXPECT_THROW(Candidates({c}, {4, 5, 6}), InternalError);
  EXPECT_NO_THROW(Candidates({c}, {4, 5}));
  Candidates cs;
  const std::vector<index_t> many(MAX_CANDIDATE_TETS + 1, 0);
  EXPECT_THROW(cs.push_back(c, many.data(), MAX_CANDIDATE_TETS + 1), InternalError);
  EXPECT_THROW(cs.push_back(c, many.data(), 0), InternalError);
}

// The finder's and the pruning's results keep the layout (the constructor checks it again) and
// every candidate's tets are sorted, distinct tets of the mesh.
TEST(Candidates, TheFinderAndThePruningKeepTheLayout) {
  TetMesh mesh = test::kuhn_grid(3);
  std::mt19937 rng(3);
  test::random_perturbation(mesh, rng, 0.1);
  const TetTopology topology(mesh);
  AcceptanceCriteria criteria;
  criteria.min_scaled_jacobian = 0.05;
  const Candidates found = find_candidates(mesh, topology, criteria, 2);
  std::size_t removed = 0;
  const Candidates kept = prune_unclosable(mesh, topology, found, removed, 2);
  ASSERT_FALSE(kept.empty());
  for (const Candidates* cs : {&found, &kept}) {
    EXPECT_NO_THROW(Candidates(std::vector<Candidate>(cs->begin(), cs->end()), cs->all_tets()));
    for (const Candidate& c : *cs) {
      const TetSpan tets = cs->tets(c);
      EXPECT_EQ(tets.size(), c.nb_tets);
      EXPECT_TRUE(std::is_sorted(tets.begin(), tets.end()));
      EXPECT_EQ(std::adjacent_find(tets.begin(), tets.end()), tets.end());
      for (index_t t : tets) EXPECT_LT(t, mesh.nb_tets());
    }
  }
  EXPECT_EQ(kept.size() + removed, found.size());
}

}  // namespace
}  // namespace hexmerge
