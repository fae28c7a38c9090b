#include "hexmerge/occ/mesh_shape.h"

#include <Standard_Failure.hxx>
#include <algorithm>
#include <utility>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/core/phase_timer.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/occ/brep_text.h"
#include "hexmerge/occ/mesh_attempt.h"
#include "hexmerge/occ/mesher/layers.h"
#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/sharp_features.h"
#include "hexmerge/occ/mesher/size_estimate.h"
#include "hexmerge/occ/mesher/strategy.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge {
namespace {

using namespace mesher;
using namespace tetgen;

// OpenCASCADE's exceptions are no std::exception: one that escapes the ways of placing the points
// (reading the shape, its features) becomes an InputError in our words, naming its kind, rather
// than a caller's "unknown exception".
std::string occ_failure(const Standard_Failure& e) {
  return std::string("OpenCASCADE failed on the shape's geometry (") + e.DynamicType()->Name() +
         ")";
}

// mesh_shape() and, with `tet10`, mesh_shape_tet10().
TetMesh mesh_shape_impl(const std::string& brep, const MeshShapeParameters& parameters,
                        MeshShapeReport& report, Tet10Mesh* tet10,
                        const ProgressCallback& progress) {
  validate_mesh_shape_parameters(parameters);
  report = MeshShapeReport{};
  const auto start = PhaseTimer::Clock::now();
  const auto seconds_since = PhaseTimer::seconds_since;
  {
    TetrahedralizeParameters program;
    program.program = parameters.tetgen;
    const Tetrahedralizer check(program);  // fails now when TetGen is missing
  }

  // 1. The shape, its solids glued where they touch, and its frame.
  GlueSolidsReport glue;
  const Shape shape = load_shape(brep, 1e-7 * parameters.size, glue);
  report.nb_solids = static_cast<std::size_t>(shape.solids.Extent());
  report.nb_faces = static_cast<std::size_t>(shape.faces.Extent());
  report.nb_shared_faces = glue.nb_shared_faces;
  report.glue_fuzzy = glue.fuzzy;
  report.nb_sewn_solids = glue.nb_sewn_solids;
  report.nb_split_lens_edges = glue.nb_split_lens_edges;
  // A shape of faces sewn into solids has faces of its own: FaceN of the shape given names none.
  if (glue.nb_sewn_solids > 0 &&
      (!parameters.local_sizes.empty() || !parameters.face_layers.empty()))
    throw InputError(
        "mesh_shape: the shape holds faces, not solids, which were sewn into " +
            std::to_string(glue.nb_sewn_solids) +
            " solid(s) with faces of their own: local sizes and face layers name faces of a "
            "solid; make the solids first (FreeCAD: Part > Shape builder, solid from shell)",
        Entity::Parameter);
  const Frame frame = choose_frame(shape, parameters.frame);
  // Local sizes naming faces or edges the shape does not have, or coarser than h, fail now.
  const std::vector<LocalSize> local_sizes = parse_local_sizes(parameters.local_sizes);
  // The faces and edges as numbered in the shape given (FreeCAD's FaceN, EdgeN), through the
  // gluing of touching solids, which splits and merges faces and edges.
  GivenItems given_items{
      ItemNumbering::identity("Face", static_cast<std::size_t>(shape.faces.Extent())),
      ItemNumbering::identity("Edge", static_cast<std::size_t>(shape.edges.Extent()))};
  const bool remade = glue.glued || glue.nb_split_lens_edges > 0;
  if (remade) {
    given_items.faces.to_shape = glue.face_images;
    given_items.edges.to_shape = glue.edge_images;
  }
  const LocalSizeItems local_items =
      local_size_items(local_sizes, given_items.faces, given_items.edges, parameters.size);
  // Face layers on faces the shape has not, or thicker than h, fail now too.
  face_layer_specs(parse_face_layers(parameters.face_layers), given_items.faces, parameters.size);
  const std::string regions_brep = remade ? write_brep(shape.shape) : brep;
  // The CAD's sharp corners and edges, named as in the shape given.
  const SharpFeatures sharp = sharp_features(shape, kSharpAngle);
  report.sharp_features = sharp_feature_reports(sharp, given_items.faces, given_items.edges);

  // The faces' widths (2 area / perimeter), and the spans of those a way may size (its size is
  // at most 1.1 times the one asked for).
  const std::vector<double>& widths = shape.face_width;
  const double sized_below = kNarrowFaceWidth * 1.1 * parameters.size;
  const std::vector<double> spans = face_spans(shape, widths, sized_below);

  // 2. A size whose mesh would not fit in memory is refused before any work.
  SizeEstimate estimate = estimate_size(shape.shape, shape.volume.Mass(), parameters.size,
                                        parameters.surface_deflection * parameters.size);
  // The sizes at short edges and narrow faces counted too (swept shapes, which go without them,
  // overestimated).
  LocalSizeItems estimated = local_items;
  const auto [feature_edges, feature_faces] = add_feature_sizes(
      shape.edge_length, widths, spans, parameters.size, parameters.feature_size, estimated);
  if (!local_sizes.empty() || feature_edges + feature_faces > 0) {
    const double extra = estimate_local_tets(shape.faces, shape.edges, estimated.face_size,
                                             estimated.edge_size, parameters.size, kLocalGrading);
    estimate.tets += extra;
    estimate.bytes += extra * kBytesPerTet;
  }
  report.estimated_tets = estimate.tets;
  refuse_if_too_large(estimate, shape.shape, shape.volume.Mass(), parameters.size,
                      parameters.surface_deflection, parameters.memory_limit, "");
  const double shape_seconds = seconds_since(start);

  // 3. The attempts, simplest input last; what failed is reported. Faces narrower than
  // kNarrowFace h are merged away first (merge_narrow_faces); where every way fails so, or the
  // shape is refused as broken (a merge can bring two faces' triangles across each other), all
  // the ways run again without (and what they say is what the user gets).
  const MeshShapeReport before_attempts = report;
  // `merge_narrow`: whether faces narrower than kNarrowFace h are merged away.
  const auto run_ways = [&](bool merge_narrow) {
    report = before_attempts;
    std::string failures;
    double failed_seconds = 0;
    int nb_tried = 0;
    bool first_pulled = false;    // whether the first way (which failed) pulled the core
    bool first_buffered = false;  // whether it made a buffer layer
    // The finest chord deflection tried (a factor of the one asked for), and whether a way on it
    // failed on a surface too coarse (SurfaceTooCoarse): a finer one is tried only then.
    double finest = 1.0;
    bool finest_too_coarse = false;
    for (const Strategy& strategy : kStrategies) {
      // The way without layers repeats the way before it (lattice points, no lattice faces, so
      // no sweep) when that one places no layers either.
      if (&strategy != kStrategies && !strategy.layers && !strategy.lattice_faces &&
          strategy.lattice_points &&
          boundary_layers_placed(parameters, *(&strategy - 1), false) == 0)
        continue;
      // The lattice without the buffer layer repeats the first way when that one made none; the
      // lattice without the core pulled when that one pulled nothing.
      if (&strategy == kStrategies + 1 && !first_buffered) continue;
      if (&strategy == kStrategies + 2 && !first_pulled) continue;
      // A finer surface only where the finest so far was too coarse.
      if (strategy.deflection_factor != 1.0 &&
          !(finest_too_coarse && strategy.deflection_factor < finest))
        continue;
      if (strategy.deflection_factor < finest) {
        finest = strategy.deflection_factor;
        finest_too_coarse = false;
      }
      ++nb_tried;
      MeshShapeReport attempt = report;
      const auto attempt_start = PhaseTimer::Clock::now();
      const auto failed = [&](const std::string& why) {
        report.failed_strategies.push_back(std::string(strategy.name) + ": " + why);
        failures += std::string(failures.empty() ? "" : "; ") + strategy.name + ": " + why;
        failed_seconds += seconds_since(attempt_start);
      };
      try {
        TetMesh mesh =
            mesh_attempt(shape, given_items, frame, sharp, regions_brep, parameters, strategy,
                         widths, spans, merge_narrow, attempt, tet10, progress);
        attempt.strategy = strategy.name;
        add_phase_seconds(attempt.phase_seconds, "shape", shape_seconds);
        if (failed_seconds > 0)
          add_phase_seconds(attempt.phase_seconds, "failed attempts", failed_seconds);
        report = std::move(attempt);
        return mesh;
      } catch (const TetrahedralizeFailure& e) {
        if (strategy.deflection_factor == finest && dynamic_cast<const SurfaceTooCoarse*>(&e))
          finest_too_coarse = true;
        if (&strategy == kStrategies) {
          first_pulled =
              attempt.nb_pulled_points + attempt.nb_narrow_pyramids + attempt.nb_inner_apexes > 0;
          first_buffered = attempt.nb_buffer_faces > 0;
        }
        failed(e.what());
      } catch (const Standard_Failure& e) {  // this way's geometry: the next may not need it
        failed(occ_failure(e));
      }
    }
    throw InputError("mesh_shape: could not tetrahedralise the shape at size " +
                     std::to_string(parameters.size) + " in any of " + std::to_string(nb_tried) +
                     " ways of placing the points (" + failures + ")");
  };
  // (The ways' sizes are at most 1.1 times the size asked for.)
  if (std::any_of(widths.begin(), widths.end(),
                  [&](double w) { return w < kNarrowFace * 1.1 * parameters.size; })) {
    try {
      return run_ways(true);
    } catch (const InputError& e) {
      // A parameter's refusal (the thin walls' sizes would not fit in memory) holds without the
      // merge too.
      if (e.entity() == Entity::Parameter) throw;
    }
  }
  return run_ways(false);
}

TetMesh mesh_shape_guarded(const std::string& brep, const MeshShapeParameters& parameters,
                           MeshShapeReport& report, Tet10Mesh* tet10,
                           const ProgressCallback& progress) {
  try {
    return mesh_shape_impl(brep, parameters, report, tet10, progress);
  } catch (const Standard_Failure& e) {
    throw InputError("mesh_shape: " + occ_failure(e));
  }
}

}  // namespace

TetMesh mesh_shape(const std::string& brep, const MeshShapeParameters& parameters,
                   MeshShapeReport& report, const ProgressCallback& progress) {
  return mesh_shape_guarded(brep, parameters, report, nullptr, progress);
}

Tet10Mesh mesh_shape_tet10(const std::string& brep, const MeshShapeParameters& parameters,
                           MeshShapeReport& report, const ProgressCallback& progress) {
  Tet10Mesh tet10;
  mesh_shape_guarded(brep, parameters, report, &tet10, progress);
  return tet10;
}

}  // namespace hexmerge
