// prune_unclosable: the candidates no conforming selection can hold.
#include "hexmerge/recombine/prune_candidates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "fixtures.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/recombine/find_candidates_exhaustive.h"
#include "hexmerge/recombine/recombine.h"

namespace hexmerge {
namespace {

using test::five_tet_grid;
using test::kuhn_grid;
using test::orient_positively;

std::size_t count_type(const Candidates& candidates, CellType type) {
  std::size_t n = 0;
  for (const Candidate& c : candidates) n += c.type == type;
  return n;
}

// A Kuhn cube with one tet on each triangle of its top face (z = 1), whose apexes are `apex0`
// and `apex1`: the cube's top quad is closed by a pyramid when they are one point, by nothing
// when they are two.
TetMesh cube_with_cap(const std::array<double, 3>& apex0, const std::array<double, 3>& apex1) {
  TetMesh mesh = kuhn_grid(1);
  std::vector<std::array<index_t, 3>> top;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* v = mesh.tet(t);
    for (int f = 0; f < 4; ++f) {
      std::array<index_t, 3> tri{};
      int k = 0;
      for (int i = 0; i < 4; ++i)
        if (i != f) tri[k++] = v[i];
      if (mesh.point(tri[0])[2] == 1 && mesh.point(tri[1])[2] == 1 && mesh.point(tri[2])[2] == 1)
        top.push_back(tri);
    }
  }
  EXPECT_EQ(top.size(), 2u);
  const index_t a0 = mesh.nb_vertices();
  mesh.points.insert(mesh.points.end(), apex0.begin(), apex0.end());
  index_t a1 = a0;
  if (apex1 != apex0) {
    a1 = a0 + 1;
    mesh.points.insert(mesh.points.end(), apex1.begin(), apex1.end());
  }
  mesh.tets.insert(mesh.tets.end(), {top[0][0], top[0][1], top[0][2], a0});
  mesh.tets.insert(mesh.tets.end(), {top[1][0], top[1][1], top[1][2], a1});
  orient_positively(mesh);
  validate_tet_mesh(mesh);
  return mesh;
}

Candidates candidates_of(const TetMesh& mesh) {
  const TetTopology topology(mesh);
  AcceptanceCriteria criteria;
  criteria.min_scaled_jacobian = 0.05;
  return find_candidates(mesh, topology, criteria, 1);
}

// The definition, read literally: sweep over the candidates, dropping every one with a quad face
// that is neither on the boundary nor the face of a candidate still kept on its other side (one
// that holds the tets behind the face's triangles), until a sweep drops nothing.
std::vector<char> unclosable_by_sweeps(const TetMesh& mesh, const TetTopology& topology,
                                       const Candidates& all) {
  auto holds = [&](const Candidate& c, index_t t) { return all.tets(c).contains(t); };
  std::vector<std::vector<FaceKey>> faces(all.size());
  for (std::size_t ci = 0; ci < all.size(); ++ci)
    for (int f = 0; f < descriptor(all[ci].type).nb_faces; ++f)
      faces[ci].push_back(face_key(all[ci], f));
  std::vector<char> dropped(all.size(), 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t ci = 0; ci < all.size(); ++ci) {
      const Candidate& c = all[ci];
      const CellDescriptor& d = descriptor(c.type);
      bool ok = !dropped[ci];
      for (int f = 0; f < d.nb_faces && ok; ++f) {
        if (d.face_size[f] != 4) continue;
        const FaceKey key = face_key(c, f);
        // The triangles of the candidate's boundary on this face, and the tets behind them.
        std::vector<index_t> behind;
        bool open = false;
        for (const index_t t : all.tets(c)) {
          const index_t* v = mesh.tet(t);
          for (int lf = 0; lf < 4; ++lf) {
            bool on_face = true;
            for (int k = 0; k < 4; ++k)
              if (k != lf) on_face = on_face && std::count(key.begin(), key.end(), v[k]) > 0;
            const index_t n = topology.neighbor(t, lf);
            if (!on_face || (n != NO_CELL && holds(c, n))) continue;
            if (n == NO_CELL)
              open = true;
            else
              behind.push_back(n);
          }
        }
        if (open) {
          ok = behind.empty();
          continue;
        }
        if (behind.size() > 2) behind.resize(2);
        bool closed = false;
        for (std::size_t p = 0; p < all.size() && !closed; ++p) {
          if (p == ci || dropped[p]) continue;
          const bool same_face = std::count(faces[p].begin(), faces[p].end(), key) > 0;
          closed = same_face && std::all_of(behind.begin(), behind.end(),
                                            [&](index_t t) { return holds(all[p], t); });
        }
        ok = closed;
      }
      if (!ok && !dropped[ci]) {
        dropped[ci] = 1;
        changed = true;
      }
    }
  }
  return dropped;
}

// prune_unclosable keeps exactly the candidates the sweeps keep, in their order, on any number of
// threads.
void expect_same_as_sweeps(const TetMesh& mesh, const Candidates& all) {
  const TetTopology topology(mesh);
  const std::vector<char> dropped = unclosable_by_sweeps(mesh, topology, all);
  Candidates expected;
  for (std::size_t ci = 0; ci < all.size(); ++ci)
    if (!dropped[ci]) expected.push_back(all[ci], all.tets(ci).data(), all[ci].nb_tets);
  for (int threads : {1, 2}) {
    std::size_t removed = 0;
    const Candidates kept = prune_unclosable(mesh, topology, all, removed, threads);
    EXPECT_EQ(removed, all.size() - expected.size());
    ASSERT_EQ(kept.size(), expected.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
      EXPECT_TRUE(std::equal(kept.tets(i).begin(), kept.tets(i).end(), expected.tets(i).begin(),
                             expected.tets(i).end()));
      EXPECT_EQ(kept[i].type, expected[i].type);
      EXPECT_EQ(kept[i].vertices, expected[i].vertices);
    }
  }
}

TEST(PruneUnclosable, KeepsEveryCellOfAGrid) {
  // Every quad face of a grid cell is on the boundary or shared with the next cell.
  const TetMesh mesh = kuhn_grid(3);
  const TetTopology topology(mesh);
  const Candidates all = candidates_of(mesh);
  std::size_t removed = 0;
  const Candidates kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(kept.size() + removed, all.size());
  std::size_t cubes = 0;
  for (const Candidate& c : kept) cubes += c.type == CellType::Hex && c.quality > 0.999f;
  EXPECT_EQ(cubes, 27u);
}

TEST(PruneUnclosable, KeepsAHexWhoseQuadAPyramidCloses) {
  const TetMesh mesh = cube_with_cap({0.5, 0.5, 1.5}, {0.5, 0.5, 1.5});
  const TetTopology topology(mesh);
  const Candidates all = candidates_of(mesh);
  ASSERT_EQ(count_type(all, CellType::Hex), 1u);
  ASSERT_GE(count_type(all, CellType::Pyramid), 1u);
  std::size_t removed = 0;
  const Candidates kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(count_type(kept, CellType::Hex), 1u);
  // And the selection makes the pair: one hex, one pyramid, conforming.
  RecombineReport report;
  RecombineParameters parameters;
  parameters.min_scaled_jacobian = 0.05;
  const MixedMesh out = recombine(mesh, parameters, report);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Hex)], 1u);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Pyramid)], 1u);
  EXPECT_EQ(report.nonconforming_quads, 0u);
}

TEST(PruneUnclosable, RemovesAHexWhoseQuadNothingCloses) {
  // Two tets with different apexes on the top quad: no pyramid, no hex across.
  const TetMesh mesh = cube_with_cap({0.3, 0.6, 1.4}, {0.7, 0.4, 1.4});
  const TetTopology topology(mesh);
  const Candidates all = candidates_of(mesh);
  ASSERT_EQ(count_type(all, CellType::Hex), 1u);
  std::size_t removed = 0;
  const Candidates kept = prune_unclosable(mesh, topology, all, removed);
  EXPECT_EQ(count_type(kept, CellType::Hex), 0u);
  // So do the pyramids and prisms of the cube that have the top quad as a face.
  EXPECT_GT(removed, 1u);
  EXPECT_EQ(kept.size() + removed, all.size());
  // The selection then leaves the cube's top quad to no element: conforming.
  RecombineReport report;
  RecombineParameters parameters;
  parameters.min_scaled_jacobian = 0.05;
  recombine(mesh, parameters, report);
  EXPECT_EQ(report.output_counts[static_cast<int>(CellType::Hex)], 0u);
  EXPECT_EQ(report.nonconforming_quads, 0u);
  EXPECT_EQ(report.candidates_unclosable, removed);
}

TEST(PruneUnclosable, KeepsWhatTheDefinitionKeepsOnPerturbedGrids) {
  // Perturbed grids leave some quads to no closer, and removals chain through shared quads.
  std::mt19937 rng(11);
  std::size_t removed_total = 0, kept_total = 0;
  for (int kind = 0; kind < 2; ++kind) {
    for (int trial = 0; trial < 3; ++trial) {
      TetMesh mesh = kind == 0 ? kuhn_grid(3) : five_tet_grid(3);
      test::random_perturbation(mesh, rng, 0.12);
      const TetTopology topology(mesh);
      for (bool exhaustive : {false, true}) {
        SCOPED_TRACE(testing::Message() << "kind " << kind << " trial " << trial
                                        << (exhaustive ? " exhaustive" : " programs"));
        const Candidates all =
            exhaustive ? find_candidates_exhaustive(mesh, topology, test::permissive_criteria(), 1)
                       : find_candidates(mesh, topology, test::permissive_criteria(), 1);
        expect_same_as_sweeps(mesh, all);
        std::size_t removed = 0;
        kept_total += prune_unclosable(mesh, topology, all, removed).size();
        removed_total += removed;
      }
    }
  }
  // Both outcomes occur, so the comparison says something.
  EXPECT_GT(removed_total, 0u);
  EXPECT_GT(kept_total, 0u);
}

TEST(PruneUnclosable, KeepsWhatTheDefinitionKeepsWithAFlatTetOnAQuad) {
  // A cube split on the bottom diagonal 1-2 and the flat tet (0, 1, 2, 3) under it, corner 0
  // lowered: the hexahedron that takes the flat tet in has triangles of its bottom quad inside.
  const auto triangulations = test::enumerate_triangulations(test::unit_cube());
  int tried = 0;
  for (const auto& tets : triangulations) {
    const bool uses_12 = std::any_of(tets.begin(), tets.end(), [](const test::Tet& t) {
      return std::count(t.begin(), t.end(), 1u) && std::count(t.begin(), t.end(), 2u);
    });
    if (!uses_12 || tried == 4) continue;
    ++tried;
    std::vector<test::Point> p = test::unit_cube().corners;
    p[0][2] = -0.01;
    std::vector<test::Tet> with_cap = tets;
    with_cap.push_back({0, 1, 2, 3});
    TetMesh mesh = test::make_tet_mesh(p, with_cap);
    orient_positively(mesh);
    const TetTopology topology(mesh);
    const Candidates all =
        find_candidates_exhaustive(mesh, topology, test::permissive_criteria(), 1);
    ASSERT_GE(count_type(all, CellType::Hex), 2u);  // with and without the flat tet
    expect_same_as_sweeps(mesh, all);
  }
  EXPECT_GT(tried, 0);
}

}  // namespace
}  // namespace hexmerge
