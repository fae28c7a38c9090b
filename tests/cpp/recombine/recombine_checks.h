#pragma once
/// @file
/// What the engine's tests share: recombine and check the output independently (check_mesh),
/// and the capped Kuhn grid of the block tests.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "fixtures.h"
#include "hexmerge/check/check_mesh.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/recombine/recombine.h"
#include "hexmerge/recombine/select/select_candidates.h"

namespace hexmerge::test {

inline std::string describe(const CheckReport& r) {
  std::string out = "check_mesh: " + std::to_string(r.counts[0]) + " tets, " +
                    std::to_string(r.counts[1]) + " pyramids, " + std::to_string(r.counts[2]) +
                    " prisms, " + std::to_string(r.counts[3]) + " hexes; " +
                    std::to_string(r.nonconforming_quads) + " non-conforming quads, " +
                    std::to_string(r.cracks) + " cracks";
  for (const auto& line : r.problems) out += "\n  " + line;
  return out;
}

/// Largest volume change that non-planar quads can explain: a bilinear quad a-b-c-d encloses
/// the mean of its two triangulations, which differ by the tet (a, b, c, d); so each quad face
/// moves the volume by at most half that tet's volume from its tets' triangles.
inline double quad_volume_bound(const MixedMesh& mesh) {
  double bound = 0.0;
  for (index_t c = 0; c < mesh.nb_cells(); ++c) {
    const CellDescriptor& d = descriptor(mesh.types[c]);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      const auto p = [&](int i) {
        return &mesh.points[3 * std::size_t(mesh.cell(c)[d.face[f][i]])];
      };
      bound += 0.5 * std::abs(tet_volume(p(0), p(1), p(2), p(3)));
    }
  }
  return bound;
}

struct Outcome {
  MixedMesh mesh;
  RecombineReport report;
  CheckReport check;
};

/// Recombines, checks the output independently, and expects it valid; `flat` when every quad
/// face is planar, so that the volume must be kept to round-off; `conforming` when no quad may
/// meet two triangles; `regions_kept` unless cells may span regions.
inline Outcome recombine_and_check(const TetMesh& input, const RecombineParameters& parameters,
                                   bool flat = true, bool conforming = true,
                                   bool regions_kept = true) {
  Outcome run;
  run.mesh = recombine(input, parameters, run.report);
  run.check = check_mesh(run.mesh, input);
  if (regions_kept) {
    EXPECT_TRUE(run.check.valid()) << describe(run.check);
  } else {
    CheckReport without_regions = run.check;
    without_regions.region_mismatches = 0;
    EXPECT_TRUE(without_regions.valid()) << describe(run.check);
  }
  if (conforming) {
    EXPECT_EQ(run.check.nonconforming_quads, 0u) << describe(run.check);
  }
  if (flat) {
    EXPECT_LT(std::abs(run.check.relative_volume_difference), 1e-12);
  } else {
    EXPECT_LE(std::abs(run.check.output_volume - run.check.input_volume),
              quad_volume_bound(run.mesh) + 1e-12);
  }
  // The report and the checker agree on what was made.
  EXPECT_EQ(run.report.output_cells, run.mesh.nb_cells());
  for (int t = 0; t < NB_CELL_TYPES; ++t)
    EXPECT_EQ(run.report.output_counts[t], run.check.counts[t]);
  EXPECT_EQ(run.report.input_tets, input.nb_tets());
  return run;
}

// The cells a selection makes (its elements and the tets it leaves); owners gets, per tet, how
// many chosen elements hold it.
inline std::size_t selection_cells(const TetMesh& mesh, const Candidates& candidates,
                                   const Selection& s, std::vector<int>& owners) {
  owners.assign(mesh.nb_tets(), 0);
  std::size_t taken = 0;
  for (index_t ci : s.elements) {
    for (const index_t t : candidates.tets(ci)) ++owners[t];
    taken += static_cast<std::size_t>(candidates[ci].nb_tets);
  }
  return s.elements.size() + (mesh.nb_tets() - taken);
}

inline std::size_t hexes(const Outcome& run) {
  return run.check.counts[static_cast<int>(CellType::Hex)];
}

/// A Kuhn grid capped on its x = n side: over each boundary square, the two tets from its
/// triangles to an apex half a cube out (a closing pyramid), except over square (j, k) = `open`,
/// whose two tets get apexes of their own over their triangles' centroids (no pyramid).
inline TetMesh capped_kuhn_grid(int n, std::array<int, 2> open = {-1, -1}) {
  TetMesh mesh = kuhn_grid(n);
  const index_t nt = mesh.nb_tets();
  for (index_t t = 0; t < nt; ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<index_t, 3> tri;
      int m = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != f) tri[m++] = mesh.tet(t)[i];
      }
      bool on_cap = true;
      double c[3] = {0, 0, 0};
      for (index_t v : tri) {
        on_cap = on_cap && mesh.point(v)[0] == n;
        for (int a = 0; a < 3; ++a) c[a] += mesh.point(v)[a] / 3;
      }
      if (!on_cap) continue;
      const int j = int(std::floor(c[1])), k = int(std::floor(c[2]));
      const bool own_apex = j == open[0] && k == open[1];
      const double apex[3] = {n + 0.5, own_apex ? c[1] : j + 0.5, own_apex ? c[2] : k + 0.5};
      index_t a = NO_INDEX;
      for (index_t v = 0; v < mesh.nb_vertices() && a == NO_INDEX; ++v) {
        const double* p = mesh.point(v);
        if (p[0] == apex[0] && p[1] == apex[1] && p[2] == apex[2]) a = v;
      }
      if (a == NO_INDEX) {
        a = mesh.nb_vertices();
        mesh.points.insert(mesh.points.end(), apex, apex + 3);
      }
      mesh.tets.insert(mesh.tets.end(), {tri[0], tri[1], tri[2], a});
    }
  }
  orient_positively(mesh);
  return mesh;
}

}  // namespace hexmerge::test
