#include "hexmerge/recombine/recombine.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/core/phase_timer.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/bound_selection.h"
#include "hexmerge/recombine/find_candidates.h"
#include "hexmerge/recombine/find_candidates_exhaustive.h"
#include "hexmerge/recombine/postmerge/postmerge.h"
#include "hexmerge/recombine/prune_candidates.h"
#include "hexmerge/recombine/rf_graph.h"
#include "hexmerge/recombine/select/select_candidates.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hexmerge {
namespace {

// Gives the memory freed so far back to the system. The search's per-chunk lists and the quad
// pairs' tables are allocated by the worker threads, in their own malloc arenas, and freed
// once the candidates are made; glibc keeps those pages (the arenas are trimmed only from their
// top), so that on two threads the resident set at the pruning, the engine's peak, held them
// on top of what is live: 933 against 788 bytes per tet on box TetGen lattice 100k.
void release_freed_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// The output cells: chosen elements by type (hex, prism, pyramid), then the tets left, in input
// order.
MixedMesh build_output(const TetMesh& input, const Candidates& candidates,
                       const Selection& selection) {
  MixedMesh out;
  out.points = input.points;
  out.offsets.push_back(0);
  out.source_offsets.push_back(0);
  const bool with_regions = !input.regions.empty();
  std::vector<char> merged(input.nb_tets(), 0);
  for (CellType type : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
    for (index_t ci : selection.elements) {
      const Candidate& c = candidates[ci];
      if (c.type != type) continue;
      out.types.push_back(type);
      const int nv = nb_vertices(type);
      out.cell_vertices.insert(out.cell_vertices.end(), c.vertices.begin(),
                               c.vertices.begin() + nv);
      out.offsets.push_back(static_cast<index_t>(out.cell_vertices.size()));
      const TetSpan tets = candidates.tets(c);
      out.source_tets.insert(out.source_tets.end(), tets.begin(), tets.end());
      out.source_offsets.push_back(static_cast<index_t>(out.source_tets.size()));
      if (with_regions) out.regions.push_back(input.region(tets[0]));
      for (const index_t t : tets) merged[t] = 1;
    }
  }
  for (index_t t = 0; t < input.nb_tets(); ++t) {
    if (merged[t]) continue;
    out.types.push_back(CellType::Tet);
    const index_t* q = input.tet(t);
    out.cell_vertices.insert(out.cell_vertices.end(), q, q + 4);
    out.offsets.push_back(static_cast<index_t>(out.cell_vertices.size()));
    out.source_tets.push_back(t);
    out.source_offsets.push_back(static_cast<index_t>(out.source_tets.size()));
    if (with_regions) out.regions.push_back(input.region(t));
  }
  return out;
}

// A boundary triangle is on a curved part of the boundary (PyramidPlacement::NoCurvedBoundaryFace)
// when its normal turns by more than this to one of the boundary triangles beside it (flat:
// round-off) and less than kCurvedMax (a sharp edge), in degrees.
constexpr double kCurvedMin = 1.0;
constexpr double kCurvedMax = 30.0;

// Per tet and face (4 t + f): whether it is a boundary triangle on a curved part of the
// boundary (kCurvedMin to kCurvedMax degrees to a boundary triangle across one of its sides).
std::vector<char> curved_boundary_faces(const TetMesh& mesh, const TetTopology& topology) {
  const CellDescriptor& tet = descriptor(CellType::Tet);  // faces outward (positive tets)
  std::vector<std::size_t> slot;                          // per boundary triangle, 4 t + f
  std::vector<Vec3> normal;                               // per boundary triangle, its unit normal
  struct Side {
    index_t a, b;     // its ends, a < b
    std::size_t tri;  // the boundary triangle (index into slot and normal)
  };
  std::vector<Side> sides;
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    for (int f = 0; f < 4; ++f) {
      if (!topology.on_boundary(t, f)) continue;
      index_t c[3];
      for (int k = 0; k < 3; ++k) c[k] = mesh.tet(t)[tet.face[f][k]];
      const Vec3 p0 = Vec3::of(mesh.point(c[0]));
      const Vec3 n = (Vec3::of(mesh.point(c[1])) - p0).cross(Vec3::of(mesh.point(c[2])) - p0);
      if (n.norm() == 0) continue;
      for (int k = 0; k < 3; ++k)
        sides.push_back(
            {std::min(c[k], c[(k + 1) % 3]), std::max(c[k], c[(k + 1) % 3]), normal.size()});
      slot.push_back(4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(f));
      normal.push_back(n * (1 / n.norm()));
    }
  std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) {
    return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.tri < y.tri;
  });
  std::vector<char> curved(4 * static_cast<std::size_t>(mesh.nb_tets()), 0);
  const double lo = std::cos(kCurvedMin * M_PI / 180), hi = std::cos(kCurvedMax * M_PI / 180);
  for (std::size_t i = 0, j = 0; i < sides.size(); i = j) {
    while (j < sides.size() && sides[j].a == sides[i].a && sides[j].b == sides[i].b) ++j;
    for (std::size_t x = i; x < j; ++x)
      for (std::size_t y = x + 1; y < j; ++y) {
        const double c = normal[sides[x].tri].dot(normal[sides[y].tri]);
        if (c < lo && c > hi) curved[slot[sides[x].tri]] = curved[slot[sides[y].tri]] = 1;
      }
  }
  return curved;
}

// Removes the pyramid candidates that parameters.pyramid_placement forbids: with a face on the
// domain boundary (one of its two tets has a boundary face), with one on a curved part of it, with
// a vertex on it, or with a vertex on a curved part of it.
void drop_boundary_pyramids(const TetMesh& mesh, const TetTopology& topology,
                            PyramidPlacement placement, Candidates& candidates) {
  if (placement == PyramidPlacement::Anywhere) return;
  std::vector<char> curved;
  if (placement == PyramidPlacement::NoCurvedBoundaryFace ||
      placement == PyramidPlacement::NoCurvedBoundaryNode)
    curved = curved_boundary_faces(mesh, topology);
  // The vertices a pyramid may not have: on the boundary, or on its curved triangles.
  std::vector<char> boundary_vertex;
  if (placement == PyramidPlacement::NoBoundaryNode ||
      placement == PyramidPlacement::NoCurvedBoundaryNode) {
    const bool curved_only = placement == PyramidPlacement::NoCurvedBoundaryNode;
    boundary_vertex.assign(mesh.nb_vertices(), 0);
    for (index_t t = 0; t < mesh.nb_tets(); ++t) {
      for (int f = 0; f < 4; ++f) {
        if (!topology.on_boundary(t, f)) continue;
        if (curved_only && !curved[4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(f)])
          continue;
        for (int v = 0; v < 4; ++v) {
          if (v != f) boundary_vertex[mesh.tet(t)[v]] = 1;
        }
      }
    }
  }
  const auto forbidden = [&](const Candidate& c) {
    if (c.type != CellType::Pyramid) return false;
    if (placement == PyramidPlacement::NoBoundaryFace) {
      const TetSpan tets = candidates.tets(c);
      return std::any_of(tets.begin(), tets.end(),
                         [&](index_t t) { return topology.is_boundary_tet(t); });
    }
    if (placement == PyramidPlacement::NoCurvedBoundaryFace) {
      const TetSpan tets = candidates.tets(c);
      return std::any_of(tets.begin(), tets.end(), [&](index_t t) {
        for (int f = 0; f < 4; ++f)
          if (curved[4 * static_cast<std::size_t>(t) + static_cast<std::size_t>(f)]) return true;
        return false;
      });
    }
    return std::any_of(c.vertices.begin(), c.vertices.begin() + nb_vertices(c.type),
                       [&](index_t v) { return boundary_vertex[v] != 0; });
  };
  candidates.keep_if([&](index_t ci) { return !forbidden(candidates[ci]); });
}

void fill_report(const TetMesh& input, const MixedMesh& out, RecombineReport& report) {
  report.input_tets = input.nb_tets();
  report.output_cells = out.nb_cells();
  report.element_reduction_percent =
      100.0 * (1.0 - static_cast<double>(out.nb_cells()) / static_cast<double>(input.nb_tets()));
  std::vector<double> tet_volume_of(input.nb_tets());
  report.input_volume = 0.0;
  for (index_t t = 0; t < input.nb_tets(); ++t) {
    const index_t* q = input.tet(t);
    tet_volume_of[t] =
        tet_volume(input.point(q[0]), input.point(q[1]), input.point(q[2]), input.point(q[3]));
    report.input_volume += tet_volume_of[t];
  }
  std::array<double, NB_CELL_TYPES> volume{}, sum_sj{};
  report.output_counts.fill(0);
  report.min_scaled_jacobian.fill(0.0);
  for (index_t c = 0; c < out.nb_cells(); ++c) {
    const int type = static_cast<int>(out.types[c]);
    for (index_t k = out.source_offsets[c]; k < out.source_offsets[c + 1]; ++k) {
      volume[type] += tet_volume_of[out.source_tets[k]];
    }
    const double sj = scaled_jacobian(out.types[c], out.points.data(), out.cell(c));
    report.min_scaled_jacobian[type] =
        report.output_counts[type] == 0 ? sj : std::min(report.min_scaled_jacobian[type], sj);
    sum_sj[type] += sj;
    ++report.output_counts[type];
  }
  for (int type = 0; type < NB_CELL_TYPES; ++type) {
    report.volume_fraction[type] = volume[type] / report.input_volume;
    report.mean_scaled_jacobian[type] =
        report.output_counts[type] ? sum_sj[type] / report.output_counts[type] : 0.0;
  }
}

// Cells of the output of a selection on nb_tets tets.
std::size_t output_cells(index_t nb_tets, const Candidates& candidates,
                         const Selection& selection) {
  std::size_t cells = nb_tets;
  for (index_t e : selection.elements) cells -= candidates[e].nb_tets - 1;
  return cells;
}

void copy_selection_report(const Selection& selection, RecombineReport& report) {
  report.nonconforming_quads = selection.nonconforming_quads;
  report.block_hexahedra = selection.block_hexahedra;
  report.group_seeds = selection.group_seeds;
  report.groups = selection.groups;
  report.group_hexahedra = selection.group_hexahedra;
  report.groups_failed = selection.groups_failed;
  report.groups_capped = selection.groups_capped;
  report.closing_pyramids = selection.closing_pyramids;
  report.released_elements = selection.released_elements;
  report.local_moves = selection.local_moves;
  report.swap_moves = selection.swap_moves;
  report.reselection_moves = selection.reselection_moves;
  report.local_search_saved = selection.local_search_saved;
  report.selection_strategy = selection.strategy;
}

}  // namespace

MixedMesh recombine(const TetMesh& input, const RecombineParameters& parameters,
                    RecombineReport& report, const ProgressCallback& progress) {
  report = RecombineReport{};
  PhaseTimer timer(report.phase_seconds);
  validate_parameters(parameters);
  if (parameters.optimality_bound) require_selection_bound();
  // Scale-free: far from 1, every geometric test runs on the points scaled by a power of two
  // (exact: each product and quotient rounds as before, none under- or overflows); the output
  // keeps the input's points, and the report's volumes are scaled back.
  const int exponent = normalising_exponent(input.points);
  TetMesh scaled;
  if (exponent != 0) {
    scaled = input;
    for (double& c : scaled.points) c = std::ldexp(c, exponent);
  }
  const TetMesh& mesh = exponent != 0 ? scaled : input;
  validate_tet_mesh(mesh);
  report_progress(progress, "topology", 0.0);
  const TetTopology topology(mesh);
  timer.lap("topology");

  AcceptanceCriteria criteria;
  criteria.min_dihedral_angle = parameters.min_dihedral_angle;
  criteria.min_boundary_dihedral_angle = parameters.min_boundary_dihedral_angle;
  criteria.max_face_angle = parameters.max_face_angle;
  // A hard floor under the option: whatever it says (down to -1), no element is made flat or
  // inverted.
  criteria.min_scaled_jacobian =
      std::max(parameters.min_scaled_jacobian, kMinElementScaledJacobian);
  criteria.lowest_scaled_jacobian = parameters.lowest_scaled_jacobian;
  criteria.respect_regions = parameters.respect_regions;
  criteria.types[static_cast<int>(CellType::Hex)] = parameters.make_hexahedra;
  criteria.types[static_cast<int>(CellType::Prism)] = parameters.make_prisms;
  criteria.types[static_cast<int>(CellType::Pyramid)] = parameters.make_pyramids;
  const int threads = thread_count(parameters.threads);
  const auto find = [&](const TetMesh& tets, const TetTopology& faces) {
    Candidates found = parameters.finder == Finder::Exhaustive
                           ? find_candidates_exhaustive(tets, faces, criteria, threads, progress)
                           : find_candidates(tets, faces, criteria, threads, progress);
    drop_boundary_pyramids(tets, faces, parameters.pyramid_placement, found);
    release_freed_memory();
    return found;
  };
  Candidates candidates = find(mesh, topology);
  timer.lap("candidates");
  // Templates by name; the exhaustive finder's candidates count as "exhaustive_<type>".
  std::vector<std::array<std::size_t, NB_CELL_TYPES>> counts(256);
  for (const Candidate& c : candidates) ++counts[c.graph][static_cast<int>(c.type)];
  if (parameters.finder == Finder::Exhaustive) {
    for (CellType type : {CellType::Hex, CellType::Prism, CellType::Pyramid}) {
      report.candidates_per_template[std::string("exhaustive_") + descriptor(type).name] =
          counts[EXHAUSTIVE_GRAPH][static_cast<int>(type)];
    }
  } else {
    const auto& graphs = rf_graphs();
    for (std::size_t g = 0; g < graphs.size(); ++g) {
      report.candidates_per_template[graphs[g].name] = counts[g][static_cast<int>(graphs[g].type)];
    }
  }
  report.candidates_total = candidates.size();
  const bool conforming = parameters.conformity == Conformity::Conforming;
  const bool post_merge = !parameters.same_nodes && conforming;
  Candidates found;  // before the pruning, for the post-merge stage
  if (conforming) {
    if (post_merge) found = candidates;
    candidates = prune_unclosable(mesh, topology, std::move(candidates),
                                  report.candidates_unclosable, threads);
    timer.lap("pruning");
  }

  Selection selection = select_candidates(mesh, topology, candidates, parameters, progress);
  timer.lap("selection");

  // 6. Post-merge stage: flips that close the open quads of hexahedron candidates, then the
  // selection again on the new tets, kept when it has fewer elements; repeated on the kept
  // result (the new selection's hexahedra stay) for at most post_merge_rounds rounds.
  TetMesh flipped;
  if (!parameters.same_nodes) report.post_merge = conforming ? "not kept" : "off: conformity mode";
  if (post_merge) {
    report_progress(progress, "post_merge", 0.0);
    PostMergeOptions options;
    options.min_pyramid_quality = criteria.min_scaled_jacobian;
    options.min_tet_quality = criteria.min_scaled_jacobian;
    options.placement = parameters.pyramid_placement;
    options.contract_edges = parameters.post_merge_contractions;
    options.move_nodes = parameters.post_merge_moves;
    options.split_nodes = parameters.post_merge_splits;
    options.min_dihedral_angle = criteria.min_dihedral_angle;
    options.max_face_angle = criteria.max_face_angle;
    const QuadCensus before = quad_census(mesh, found, options);
    report.census_hex_candidates = report.census_hex_candidates_after = before.hex_candidates;
    report.census_closable = report.census_closable_after = before.closable;
    timer.lap("census_before");
    for (int round = 0; round < parameters.post_merge_rounds; ++round) {
      const TetMesh& current = report.post_merge == "kept" ? flipped : mesh;
      const std::string suffix = "_" + std::to_string(round + 1);
      // Node moves: hexahedron candidates under looser bounds, which a move may lift.
      Candidates liftable;
      if (options.move_nodes) {
        AcceptanceCriteria loose = criteria;
        loose.min_dihedral_angle -= kLiftAngle;
        loose.max_face_angle += kLiftAngle;
        loose.min_scaled_jacobian = std::min(loose.min_scaled_jacobian, kLiftScaledJacobian);
        loose.lowest_scaled_jacobian = loose.min_scaled_jacobian;
        loose.types = {};
        loose.types[static_cast<int>(CellType::Hex)] = true;
        std::unique_ptr<TetTopology> current_topology;
        if (&current != &mesh) current_topology = std::make_unique<TetTopology>(current);
        liftable = find_candidates(current, current_topology ? *current_topology : topology, loose,
                                   threads);
        timer.lap("post_merge_liftable" + suffix);
      }
      PostMergeResult stage =
          close_open_quads(current, found, candidates, selection, options, liftable);
      report.post_merge_attempted += stage.attempted;
      timer.lap("post_merge_flips" + suffix);
      if (stage.closed == 0 && stage.split_hexes == 0) break;
      const TetTopology new_topology(stage.tets);
      Candidates new_found = find(stage.tets, new_topology);
      std::size_t unclosable = 0;
      Candidates new_candidates =
          prune_unclosable(stage.tets, new_topology, new_found, unclosable, threads);
      Selection new_selection =
          select_candidates(stage.tets, new_topology, new_candidates, parameters, progress);
      timer.lap("post_merge_selection" + suffix);
      if (output_cells(stage.tets.nb_tets(), new_candidates, new_selection) >=
          output_cells(current.nb_tets(), candidates, selection)) {
        break;
      }
      report.post_merge = "kept";
      ++report.post_merge_rounds;
      report.post_merge_closed += stage.closed;
      report.flips_23 += stage.flips.flips_23;
      report.flips_32 += stage.flips.flips_32;
      report.flips_44 += stage.flips.flips_44;
      report.contractions += stage.flips.contractions;
      report.node_moves += stage.flips.moves;
      report.vertex_splits += stage.flips.splits;
      report.post_merge_lifted += stage.lifted;
      report.candidates_unclosable = unclosable;
      flipped = std::move(stage.tets);
      found = std::move(new_found);
      candidates = std::move(new_candidates);
      selection = std::move(new_selection);
    }
    if (report.post_merge == "kept") {
      const QuadCensus after = quad_census(flipped, found, options);
      report.census_hex_candidates_after = after.hex_candidates;
      report.census_closable_after = after.closable;
      timer.lap("census_after");
    }
  }
  copy_selection_report(selection, report);
  const bool kept = report.post_merge == "kept";
  const TetMesh& tets = kept ? flipped : mesh;
  const TetTopology* bound_topology = &topology;
  std::unique_ptr<TetTopology> kept_topology;

  MixedMesh out = build_output(tets, candidates, selection);
  fill_report(tets, out, report);
  report.input_volume = std::ldexp(report.input_volume, -3 * exponent);
  // Scaled back by the same power of two (exact): a node the stage did not move is the input's
  // bit for bit.
  if (exponent != 0 && !kept) out.points = input.points;
  if (exponent != 0 && kept) {
    for (double& c : out.points) c = std::ldexp(c, -exponent);
  }
  if (kept) {
    // The cells are unions of the stage's tets, not of the input's: no source tets. The nodes
    // contractions took out are used by no cell, the nodes moves took elsewhere and the nodes
    // splits added (ids past the input's): all are declared changed.
    out.source_offsets.clear();
    out.source_tets.clear();
    std::vector<char> used(tets.nb_vertices(), 0);
    for (index_t v : tets.tets) used[v] = 1;
    for (index_t v = 0; v < input.nb_vertices(); ++v) {
      if (used[v] && !std::equal(input.point(v), input.point(v) + 3, &out.points[3 * v])) {
        out.changed_nodes.push_back(v);
      }
    }
    for (index_t v : input.tets) {
      if (!used[v]) {
        used[v] = 1;
        out.changed_nodes.push_back(v);
      }
    }
    for (index_t v = input.nb_vertices(); v < tets.nb_vertices(); ++v) {
      out.changed_nodes.push_back(v);
    }
    std::sort(out.changed_nodes.begin(), out.changed_nodes.end());
    // The output's tets are the stage's: the report counts the input's.
    report.input_tets = input.nb_tets();
    report.element_reduction_percent =
        100.0 * (1.0 - static_cast<double>(out.nb_cells()) / static_cast<double>(input.nb_tets()));
  }
  timer.lap("output");

  if (parameters.optimality_bound) {
    report_progress(progress, "bound", 0.0);
    // In conforming mode the program gets the conformity rows too: a bound on the conforming
    // selections, which is what this mode's output is measured against.
    if (kept) {
      kept_topology = std::make_unique<TetTopology>(tets);
      bound_topology = kept_topology.get();
    }
    const SelectionBound bound =
        bound_selection(tets.nb_tets(), candidates, selection.elements, parameters.bound_time_limit,
                        conforming ? conformity_rows(tets, *bound_topology, candidates)
                                   : std::vector<ConformityRow>{});
    report.bound_computed = true;
    report.bound_conforming = conforming;
    report.bound_elements = bound.bound_elements;
    report.bound_best_elements = bound.best_elements;
    report.bound_proved = bound.proved;
    report.gap_percent =
        100.0 *
        (static_cast<double>(report.output_cells) - static_cast<double>(bound.bound_elements)) /
        static_cast<double>(bound.bound_elements);
    // The candidates are pruned in conforming mode, so this bounds the conforming selections.
    const VolumeBound hex_bound = bound_hex_volume(tets, candidates, parameters.bound_time_limit);
    report.hex_volume_bound = std::ldexp(hex_bound.bound, -3 * exponent);
    report.hex_volume_bound_proved = hex_bound.proved;
    timer.lap("bound");
  }
  report_progress(progress, "done", 1.0);
  return out;
}

}  // namespace hexmerge
