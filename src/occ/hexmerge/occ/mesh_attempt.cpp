#include "hexmerge/occ/mesh_attempt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/core/phase_timer.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/geometry/quality.h"
#include "hexmerge/occ/brep_text.h"
#include "hexmerge/occ/mesher/axis_points.h"
#include "hexmerge/occ/mesher/boundary_distance.h"
#include "hexmerge/occ/mesher/buffer_layer.h"
#include "hexmerge/occ/mesher/core.h"
#include "hexmerge/occ/mesher/corner_strips.h"
#include "hexmerge/occ/mesher/facets.h"
#include "hexmerge/occ/mesher/improve.h"
#include "hexmerge/occ/mesher/lattice.h"
#include "hexmerge/occ/mesher/layers.h"
#include "hexmerge/occ/mesher/local_size.h"
#include "hexmerge/occ/mesher/polish.h"
#include "hexmerge/occ/mesher/pull_core.h"
#include "hexmerge/occ/mesher/second_order.h"
#include "hexmerge/occ/mesher/shape.h"
#include "hexmerge/occ/mesher/sharp_features.h"
#include "hexmerge/occ/mesher/size_estimate.h"
#include "hexmerge/occ/mesher/solid_regions.h"
#include "hexmerge/occ/mesher/spatial.h"
#include "hexmerge/occ/mesher/strategy.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/occ/mesher/surface_check.h"
#include "hexmerge/occ/mesher/surface_path.h"
#include "hexmerge/occ/mesher/surface_repair.h"
#include "hexmerge/occ/mesher/sweep.h"
#include "hexmerge/occ/mesher/thin_walls.h"
#include "hexmerge/occ/mesher/wall_cells.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/tetgen/tetrahedralize.h"
#include "hexmerge/tetgen/triangulate_facets.h"

namespace hexmerge::mesher {
namespace {

using namespace tetgen;

// Times TetGen is run again, its lattice faces' loops started elsewhere, when it does not finish.
constexpr int kTetgenRestarts = 5;
// The finer lattices' points around a local size stay this fraction of the size wanted there
// from the faces and the other points.
constexpr double kGradedClearance = 0.5;
// Lattice faces' triangles get points inside until none has an angle under kFacetAngle (radians;
// a tet on a triangle is no better than its smallest angle) or a circumradius over kFacetRadius
// h (a lattice face with few lattice points, on an impeller's thin blades, was joined to points
// 2-3 h away across them: 116 elements under 0.2 at 0.6, 210 at 0.8, 265 at 1), the points
// kFacetClearance h clear of the core's and the layers' points.
constexpr double kFacetAngle = 20.0 * M_PI / 180;
constexpr double kFacetRadius = 0.6;
constexpr double kFacetClearance = 0.25;
// Rounds of finer sizes where the triangles of two faces cross (each halves the sizes there).
constexpr int kCrossingRounds = 6;
// The tets' volume against the surface's: their difference at most this fraction of it (the
// nudged points move it by about 1e-7 h times the area).
constexpr double kVolumeTolerance = 1e-5;
// The most the flips and node moves against slivers may change the tets' volume, as a fraction.
constexpr double kVolumeDrift = 0.01;

}  // namespace

TetMesh mesh_attempt(const Shape& shape, const GivenItems& given_items, const Frame& frame,
                     const SharpFeatures& sharp, const std::string& regions_brep,
                     const MeshShapeParameters& parameters, const Strategy& strategy,
                     const std::vector<double>& widths, const std::vector<double>& spans,
                     bool merge_narrow, MeshShapeReport& report, Tet10Mesh* tet10,
                     const ProgressCallback& progress) {
  PhaseTimer clock(report.phase_seconds);
  // Each step's end: its time, and the progress of this way of placing the points ("mesh shape:
  // <step>", the way's name after the first); a callback asking to stop cancels here.
  const std::string way =
      strategy.name == kStrategies[0].name ? "" : std::string(" (") + strategy.name + ")";
  const auto step = [&](const char* name, double fraction) {
    clock.lap(name);
    report_progress(progress, std::string("mesh shape: ") + name + way, fraction);
  };
  report_progress(progress, "mesh shape: surface" + way, 0.0);
  const double h = parameters.size * strategy.size_factor;
  TetrahedralizeParameters tetgen_parameters;
  tetgen_parameters.program = parameters.tetgen;
  tetgen_parameters.work_directory = parameters.work_directory;
  tetgen_parameters.time_limit = parameters.tetgen_time_limit;
  tetgen_parameters.restarts = kTetgenRestarts;
  tetgen_parameters.nudge = 1e-7 * h;
  tetgen_parameters.tolerance = 1e-9 * h;
  tetgen_parameters.quality = !strategy.lattice_points;
  const Tetrahedralizer tetgen(tetgen_parameters);

  // 4. The surface triangulation (on the CAD), and the lattice through its bounding box in the
  // frame.
  const double deflection = parameters.surface_deflection * strategy.deflection_factor * h;
  std::vector<std::string> face_names(static_cast<std::size_t>(shape.faces.Extent()));
  for (std::size_t f = 0; f < face_names.size(); ++f) {
    const int number = given_items.faces.number_of(static_cast<int>(f));
    face_names[f] = number > 0 ? "Face" + std::to_string(number)
                               : "face " + std::to_string(f + 1) + " of the glued solids";
  }
  // Nodes nearer than 1e-5 h, or than TetGen's own tolerance (1e-8 of the input's size), are
  // one node: TetGen would merge the second itself and renumber the points after them, and a
  // face narrower than the first is below any mesh of size h (KiCad's barrel jack has a step
  // of 1e-6 mm along an 8.6 mm edge: at 1e-9 h its face's triangles were flat, 208 boundary
  // triangles under 1 degree, tets down to scaled Jacobian 4.5e-7; merged, 0.150). The
  // boundary then stays within 1e-5 h of the CAD there.
  // Faces BRepMesh leaves without triangles at this deflection fail the way as too coarse: the
  // surface at a finer one is tried.
  Surface surface = [&] {
    try {
      return triangulate(shape, deflection, 1e-5 * h + 2e-8 * shape.diagonal + 1e-12, face_names);
    } catch (const FacesNotTriangulated& e) {
      throw SurfaceTooCoarse(e.what());
    }
  }();
  // Faces narrower than kNarrowFace h (a step 0.001 mm high along a KiCad pin socket's holes,
  // 2.2e-4 h at its 20k size: triangles of 0.2 degrees) are no faces at this size: merged away
  // (the boundary stays within that of the CAD). Where that makes the surface touch itself or
  // leave a gap, not.
  if (merge_narrow)
    report.nb_narrow_faces = merge_narrow_faces(surface, shape, widths, kNarrowFace * h);
  // The volume BRepMesh's triangles enclose: the CAD's within the chord deflection.
  const double triangulated_volume =
      enclosed_volume(surface.nodes, surface.triangles, shape.face_solid_count);
  report.nb_flat_surface_triangles = surface.nb_flat_triangles;
  report.nb_revolution_faces = surface.nb_revolution_faces;
  report.nb_zipped_faces = surface.nb_zipped_faces;
  report.nb_unfolded_patches = surface.nb_unfolded_patches;
  report.nb_internal_vertices = surface.internal_vertex_faces.size();
  report.nb_parted_sides = surface.nb_parted_sides;
  Lattice lattice = lay_lattice(shape, frame, surface.nodes, h, strategy.lattice_faces);
  // Where a solid's boundary passes a side twice, two CAD edges lie at one place (their nodes
  // merged): the solid touches itself there, which TetGen cannot mesh either. Checked on
  // BRepMesh's triangles (before the repairs, which take minutes on such a shape's 825k
  // triangles) and on the surface that goes to TetGen.
  // Where the faces lie apart along such a side (BRepMesh's chord of two faces that come close,
  // left after part_shared_sides()): this way fails as too coarse.
  const auto refuse_touching_itself = [&] {
    const std::vector<OverusedSide> overused =
        find_overused_sides(surface, shape.face_solids, shape.edge_faces);
    if (overused.empty()) return;
    std::vector<OverusedSide> touching;
    for (const OverusedSide& side : overused)
      if (faces_meet_along(shape, surface.nodes, side, 1e-4 * h)) touching.push_back(side);
    if (!touching.empty())
      throw InputError(
          "mesh_shape: the shape is broken: its surface touches itself along a curve, where two "
          "of its edges lie at one place without being one edge: " +
          describe_overused_sides(surface.nodes, touching, face_names) + kRepairTheShape);
    throw SurfaceTooCoarse("the triangles of faces that come close share a side at this size (" +
                           describe_overused_sides(surface.nodes, overused, face_names) +
                           "), which a finer surface keeps apart");
  };
  refuse_touching_itself();
  // BRepMesh can leave part of a face without triangles at some sizes (a random part's
  // cylinder between a cone and another cylinder at h 58.8, meshed at 38.3: the surface had a
  // hole, and TetGen carved the whole solid away, "left out 568 of the points given", in every
  // way): this way fails as too coarse, and the surface at a quarter of the chord deflection is
  // tried.
  if (const std::vector<int> open = faces_with_open_sides(surface); !open.empty())
    throw SurfaceTooCoarse("OpenCASCADE's triangles of the faces leave a gap at this size, at " +
                           face_list(open, face_names));

  // Local sizes (the attempts at other sizes keep them, up to their h): their faces are no
  // lattice faces (refined like curved ones), their edges and those faces' edges no lattice
  // edges; the size field from the surface as BRepMesh made it.
  const std::vector<LocalSize> local_sizes = parse_local_sizes(parameters.local_sizes);
  const LocalSizeItems local_items =
      local_size_items(local_sizes, given_items.faces, given_items.edges,
                       std::max(h, parameters.size));  // checked at the size asked for
  LocalSizeItems items_at_h = local_items;
  for (double& size : items_at_h.face_size) size = std::min(size, h);
  for (double& size : items_at_h.edge_size) size = std::min(size, h);
  // The sweep of the shape as found (its lattice faces before local sizes and face layers take
  // some away). The CAD's short edges and narrow faces get sizes of their own (feature_size),
  // but for an extrusion that will be swept: its cross-section is repeated as it is (where its
  // sweep fails below, they get them then).
  // (Slabs are the lattice's cells along the axis: a sweep along a rectilinear axis, whose cells
  // differ, is not taken; an extrusion has no planar face across its axis between its caps, so
  // its axis is uniform.)
  const auto find_uniform_sweep = [&]() -> std::optional<Sweep> {
    std::optional<Sweep> found =
        find_sweep(shape, lattice.frame, lattice.face_plane, lattice.lattice_face, lattice.cells,
                   lattice.spacing, h);
    if (found && !lattice.uniform(found->axis)) found.reset();
    return found;
  };
  const std::optional<Sweep> sweep_as_found =
      parameters.sweep && strategy.lattice_faces ? find_uniform_sweep() : std::nullopt;
  std::vector<SizedTriangle> thin_walls;
  const auto feature_sizes = [&] {
    std::tie(report.nb_feature_edges, report.nb_feature_faces) =
        add_feature_sizes(shape.edge_length, widths, spans, h, parameters.feature_size, items_at_h);
    UnsizedWalls unsized;
    if (parameters.feature_size > 0) thin_walls = thin_wall_sizes(surface, h, deflection, &unsized);
    report.nb_thin_wall_patches = thin_walls.size();
    report.nb_unsized_wall_patches = unsized.patches;
    report.thinnest_unsized_wall = unsized.thinnest;
    report.thickest_unsized_wall = unsized.thickest;
    if (thin_walls.empty()) return;
    // The thin walls' sizes counted in the estimate of step 2 too.
    report.estimated_tets += estimate_patch_tets(thin_walls, h, kLocalGrading);
    refuse_if_too_large({report.estimated_tets, report.estimated_tets * kBytesPerTet}, shape.shape,
                        shape.volume.Mass(), parameters.size, parameters.surface_deflection,
                        parameters.memory_limit, "with the sizes of its thin walls");
  };
  if (!sweep_as_found) feature_sizes();
  // Face layers (none when this way places no layers): their faces are no lattice faces either.
  const std::vector<FaceLayers> layer_entries = parse_face_layers(parameters.face_layers);
  const std::vector<FaceLayerSpec> layer_specs =
      strategy.layers
          ? face_layer_specs(layer_entries, given_items.faces, std::max(h, parameters.size))
          : std::vector<FaceLayerSpec>{};
  std::vector<char> layered(items_at_h.face_size.size(), 0);
  std::vector<char> internal_vertex(items_at_h.face_size.size(), 0);  // their triangles as they are
  for (const int f : surface.internal_vertex_faces)
    internal_vertex[static_cast<std::size_t>(f)] = 1;
  for (const FaceLayerSpec& spec : layer_specs)
    for (const int f : spec.faces) layered[static_cast<std::size_t>(f)] = 1;
  const std::vector<bool> lattice_faces_as_found = lattice.lattice_face;
  // The sizes on the surface; inside (the finer lattices' points) but the thin walls' (graded, 13
  // tets under 0.2 on gmsh_Zylkopf at 250k, not 3); the thin walls' on lattice faces (facets).
  SizeField field(h, kLocalGrading, deflection), inside = field, walls = field;
  const SizeField* local = nullptr;
  // The faces and edges with sizes or layers taken out of the lattice's, and the size field.
  const auto apply_sizes = [&] {
    for (std::size_t f = 0; f < items_at_h.face_size.size(); ++f)
      if ((items_at_h.face_size[f] < h || layered[f] || internal_vertex[f]) &&
          lattice.lattice_face[f]) {
        lattice.lattice_face[f] = false;
        --lattice.nb_lattice_faces;
      }
    for (std::size_t e = 0; e < lattice.lattice_edge.size(); ++e)
      for (const int f : shape.edge_faces[e])
        if (!lattice.lattice_face[f] || items_at_h.edge_size[e] < h)
          lattice.lattice_edge[e] = false;
    inside = make_size_field(surface, items_at_h, h, kLocalGrading, deflection);
    field = inside, walls = SizeField(h, kLocalGrading, deflection);
    for (const SizedTriangle& p : thin_walls)
      field.add(p.a, p.b, p.c, p.size), walls.add(p.a, p.b, p.c, p.size);
    local = field.empty() ? nullptr : &field;
    report.nb_lattice_faces = lattice.nb_lattice_faces;
  };
  apply_sizes();
  for (int a = 0; a < 3; ++a) {
    report.spacing[a] = lattice.spacing[a];
    report.frame[a] = {lattice.frame.axis[a].x, lattice.frame.axis[a].y, lattice.frame.axis[a].z};
  }

  // 5. The surface at size h: swept when the shape is an extrusion along a lattice axis, else
  // refined and cleaned.
  std::optional<Sweep> sweep;
  std::vector<double> wall_size;  // swept with local sizes on its caps' edges: per wall
  bool carried = false;           // an extrusion whose local sizes and face layers the sweep takes
  if (!local && layer_specs.empty() && surface.internal_vertex_faces.empty())
    sweep = sweep_as_found;  // no lattice face taken away
  // The sweep carries local sizes on its caps' edges only (the walls' sides split to them), and
  // the global layers only: a shape that would be swept without its other local sizes or its
  // face layers is meshed unswept, and says why.
  if (parameters.sweep && strategy.lattice_faces && (local || !layer_specs.empty())) {
    const std::optional<Sweep>& would = sweep_as_found;
    std::string why;
    if (would)
      why = sweep_carries(local_sizes, given_items.edges, *would, shape.edge_faces,
                          lattice_faces_as_found, h, wall_size);
    // Face layers on walls are placed on the first plane and repeated; on caps they are not.
    for (std::size_t e = 0; would && why.empty() && e < layer_specs.size(); ++e)
      for (const int f : layer_specs[e].faces)
        if (would->cap[static_cast<std::size_t>(f)] >= 0 && why.empty())
          why = "the face layers on " + faces_text(layer_entries[e].faces) +
                " lie on a cap, whose nodes the sweep repeats from its first plane (face layers "
                "on its walls are swept)";
    carried = would && why.empty();
    if (carried) {
      // Walls with face layers are no lattice faces now: the sweep over the faces as they are.
      sweep = find_uniform_sweep();
    } else {
      wall_size.clear();
      Surface probe = surface;  // sweep_surface() rebuilds the surface it is given
      if (would &&
          sweep_surface(shape, *would, lattice.frame,
                        lattice.frame.axis[would->axis] * lattice.spacing[would->axis],
                        lattice.cells[would->axis], h, deflection, lattice_faces_as_found, probe))
        report.sweep_skipped = "not swept, though an extrusion: " + why;
    }
  }
  SweptSurface swept;
  if (sweep) {
    const int a = sweep->axis;
    const std::optional<SweptSurface> made = sweep_surface(
        shape, *sweep, lattice.frame, lattice.frame.axis[a] * lattice.spacing[a], lattice.cells[a],
        h, deflection, lattice.lattice_face, surface, wall_size.empty() ? nullptr : &wall_size);
    if (made) {
      swept = *made;
      local = nullptr;  // carried by the split walls: no graded points off the planes
    } else {
      sweep.reset();         // the cross-section changes along the axis
      if (sweep_as_found) {  // not swept after all: the features get their sizes
        feature_sizes();
        apply_sizes();
      }
    }
  }
  if (carried && !sweep)
    report.sweep_skipped =
        "not swept, though an extrusion: its sweep failed with the local sizes and face layers "
        "applied (walls split to a local size, or made no lattice faces for layers)";
  std::vector<Crossing> crossings;
  // The triangles checked: a lattice face's as its loops will be triangulated (facet_triangles).
  std::vector<SurfaceTriangle> checked;
  // Every crossing is of triangles of one face: the repairs folded it.
  const auto only_folds = [&] {
    return std::all_of(crossings.begin(), crossings.end(), [&](const Crossing& c) {
      return checked[c.first].face == checked[c.second].face;
    });
  };
  // Whether two faces whose triangles cross meet on the CAD itself where they share no edge: they
  // cross at every size, and the shape is refused below (pyocc_11752: 8 of its 97 pairs of
  // crossing faces; the crossing rounds refined its 89 others to 564k triangles, 3 minutes).
  const auto faces_meet_on_cad = [&] {
    return any_faces_meet(shape, checked, crossings, 1e-4 * h);
  };
  if (sweep) {
    report.sweep_axis = sweep->axis;
    checked = surface.triangles;
    crossings = find_crossings(surface.nodes, checked);
  } else {
    // The repairs, their triangles as far from their faces as they come; where they then cross
    // (faces far narrower than h: pyocc_11752's tubes, triangles joining nodes across them),
    // again from BRepMesh's triangles with every repair kept within the chord deflection
    // (bounded everywhere, the repairs left more poor triangles elsewhere: 3,263 elements under
    // scaled Jacobian 0.2 against 2,947 on the real parts at 50k).
    const auto repair = [&](double max_gap, const SizeField* sizes,
                            const SizeField* gap_sizes = nullptr) {
      // BRepMesh's caps go first: bisecting their sides makes flat triangles.
      collapse_sides(shape, surface, h, std::numeric_limits<double>::infinity(), max_gap,
                     lattice.lattice_face, sizes, gap_sizes);
      refine(shape, surface, h, max_gap, lattice.lattice_face, lattice.lattice_edge, sizes,
             gap_sizes);
      report.nb_unrefined_faces = surface.unrefined_faces.size();
      collapse_sides(shape, surface, h, h, max_gap, lattice.lattice_face, sizes, gap_sizes);
      report.nb_corner_nodes_removed =
          coarsen_sharp_corners(shape, surface, sharp.corners, h, max_gap, gap_sizes);
      remove_folds(surface, 1e-8 * shape.diagonal);  // TetGen's own coincidence tolerance
    };
    const Surface triangulated = surface;
    repair(std::numeric_limits<double>::infinity(), local);
    checked = facet_triangles(surface, lattice.frame, lattice.lattice_face, lattice.face_plane);
    crossings = find_crossings(surface.nodes, checked);
    if (!crossings.empty()) {
      surface = triangulated;
      repair(deflection, local);
      report.bounded_surface_repairs = true;
      checked = facet_triangles(surface, lattice.frame, lattice.lattice_face, lattice.face_plane);
      crossings = find_crossings(surface.nodes, checked);
    }
    // Triangles of two faces that still cross, where the faces come closer than the triangles'
    // chord deflection (on KiCad's component models, a pad's cylinder 0.025 mm from its body's,
    // a terminal block's cylinders 0.1 mm apart): the surface is made again with the places of the
    // crossing triangles given a size of half their longest side, then a quarter, ... (their
    // sagitta a quarter each time), the sizes of the earlier rounds kept, while fewer triangles
    // cross than the round before (faces that touch where they share no edge cross at every size);
    // the rest of the surface and the points inside are as at h. The repairs' deflection there
    // shrinks with those sizes (a channel 0.03 mm deep between a fillet and a chamfer, KiCad's
    // Molex PicoBlade at h 5 to 10.7: the fillet's arc was collapsed onto the chamfer at each
    // size of the places).
    SizeField finer = field;  // the local sizes, and the crossing places of every round
    // The crossing places alone.
    SizeField places(h, kLocalGrading, deflection);
    std::size_t crossing_before = std::numeric_limits<std::size_t>::max();
    for (int round = 0; round < kCrossingRounds && !crossings.empty(); ++round) {
      if (only_folds()) break;         // folds of one face: no size of these places unfolds them
      if (faces_meet_on_cad()) break;  // refused below
      // find_crossings() gives a pair of triangles per pair of faces: every crossing one here.
      std::vector<std::array<int, 3>> corners_of(checked.size());
      for (std::size_t t = 0; t < checked.size(); ++t) corners_of[t] = checked[t].node;
      const std::vector<char> crossing = crosses_any(surface.nodes, corners_of, corners_of);
      const auto nb_crossing =
          static_cast<std::size_t>(std::count(crossing.begin(), crossing.end(), 1));
      if (nb_crossing >= crossing_before) break;  // finer sizes do not part the faces there
      crossing_before = nb_crossing;
      for (std::size_t t = 0; t < checked.size(); ++t)
        if (crossing[t]) {
          std::array<Vec3, 3> corners;
          double longest = 0;
          for (int k = 0; k < 3; ++k) corners[k] = surface.nodes[checked[t].node[k]];
          for (int k = 0; k < 3; ++k)
            longest = std::max(longest, (corners[(k + 1) % 3] - corners[k]).norm());
          const double size = std::max(0.5 * longest, 1e-3 * h);
          finer.add(corners[0], corners[1], corners[2], size);
          places.add(corners[0], corners[1], corners[2], size);
        }
      surface = triangulated;
      repair(deflection, &finer, &places);
      report.bounded_surface_repairs = true;
      ++report.nb_crossing_refinements;
      checked = facet_triangles(surface, lattice.frame, lattice.lattice_face, lattice.face_plane);
      crossings = find_crossings(surface.nodes, checked);
    }
  }
  const int sweep_axis = report.sweep_axis;
  refuse_touching_itself();
  // A surface whose triangles cross cannot be kept by TetGen (its boundary recovery never
  // ends): refused here, by name, when the CAD's faces themselves meet where they share no edge;
  // else this way fails (another size may not cross).
  if (!crossings.empty()) {
    bool cad_at_fault = false;
    const std::string where = describe_crossings(shape, surface.nodes, checked, crossings, 1e-4 * h,
                                                 face_names, cad_at_fault);
    if (cad_at_fault)
      throw InputError(
          "mesh_shape: the shape is broken: faces meet where they share no edge (an edge of "
          "one lies on the other without being one of its edges, or they touch), so no mesh "
          "can follow them. "
          "The surface's triangles cross at " +
          where + kRepairTheShape);
    // Triangles of one face crossing each other: the repairs folded it (a cone's apex, needles
    // along a half cone's seam), which another size may not; of two faces: they come closer
    // than the chord deflection.
    const bool folds = only_folds();
    throw SurfaceTooCoarse(
        "the surface's triangles at this size cross (" + where +
        (folds ? "): the triangles of a face fold over each other at this size, which another "
                 "size may not do"
               : "): the faces there come closer than their triangles' chord deflection, and a "
                 "smaller size keeps them apart"));
  }
  step("surface", 0.15);

  // 6. Everything below in frame coordinates, the nodes of lattice faces exactly on their planes.
  std::vector<Vec3> nodes = frame_nodes(shape, surface, lattice, sweep_axis, swept);
  auto around = std::make_unique<Surroundings>(nodes, surface, lattice, h);

  // 7. The lattice points kept: inside, lattice_margin from the faces that are not lattice faces
  // (the layers keep out of the core after it, and improve_tets() nudges the closing pyramids'
  // apexes off the faces where that leaves a tet under 0.2). Swept, lattice_margin beyond the
  // layers: the columns recombine into hexahedra up to the layers anyway, and the layers stay
  // whole at their depth (the walls' stress in first order follows that depth, issue 15).
  auto parity = std::make_unique<Parity>(nodes, surface, shape.face_solid_count, *around, h);
  InsertedPoints inserted;
  const int nb_layers = boundary_layers_placed(parameters, strategy, sweep_axis >= 0);
  const double keep_distance =
      (parameters.lattice_margin + (sweep_axis >= 0 ? nb_layers * parameters.layer_thickness : 0)) *
      h;
  KeptPoints kept = keep_lattice_points(lattice, *around, *parity, keep_distance,
                                        parameters.lattice_margin * h, sweep_axis);
  clear_face_layers(layer_specs, nodes, surface, lattice, *around, parameters.lattice_margin * h,
                    kept);
  step("lattice", 0.2);

  // 8. The hexahedral core and its closing pyramids' apexes.
  if (strategy.lattice_points) {
    // Not where boundary layers are asked for: they keep out of the core, which would take
    // their room.
    const bool pull =
        strategy.pull && parameters.pull_core && nb_layers == 0 && layer_specs.empty();
    const CoreLayout layout = lay_core(lattice, *around, *parity, kept, sweep_axis, h, pull);
    // The faces that may take quads (the wall cells', the buffer layer's tops): no lattice face,
    // no face with a local size or face layers, none between two solids.
    std::vector<char> eligible(static_cast<std::size_t>(shape.faces.Extent()), 1);
    for (std::size_t f = 0; f < eligible.size(); ++f)
      eligible[f] = !lattice.lattice_face[f] && shape.face_solid_count[f] == 1 &&
                    !(items_at_h.face_size[f] < h);
    const auto anew = [&] {
      nodes = frame_nodes(shape, surface, lattice, sweep_axis, swept);
      around = std::make_unique<Surroundings>(nodes, surface, lattice, h);
      parity = std::make_unique<Parity>(nodes, surface, shape.face_solid_count, *around, h);
    };
    // 8b, before 8a. Hexahedra across tube walls too thin for the core (clear of its corners and
    // its pyramids' apexes), their quads put into their cylinders' triangles; first, so that a wall
    // the core reaches in places keeps its cylinders for them rather than for the buffer layer's
    // few tops there (flanged_tee at h 3.5: its pipes' walls 1.7 h thick).
    WallCells tube_walls;
    if (pull && strategy.buffer && parameters.buffer_layer) {
      PointSet obstacles(around->box_lo, around->box_hi, h);
      for (std::size_t p = 0; p < layout.core_corner.size(); ++p)
        if (layout.core_corner[p]) obstacles.add(layout.point_at(lattice, p));
      for (std::size_t c = 0; c < layout.apex_cell.size(); ++c)
        if (layout.apex_cell[c]) obstacles.add(layout.apex_at(lattice, c));
      WallReport made;
      tube_walls =
          wall_cells(shape, lattice.frame, eligible, obstacles, h, deflection, surface, made);
      report.nb_wall_hexes = made.nb_hexes;
      report.nb_walls = made.nb_walls;
      report.nb_wall_faces = made.nb_faces;
      for (const int f : made.faces) eligible[static_cast<std::size_t>(f)] = 0;
      if (made.nb_faces > 0) anew();
    }
    // 8a. The buffer layer: hexahedra from the core's closing pyramids' bases to the surface,
    // their tops put into the faces' triangles (the faces above but the walls'); the surface's
    // nodes and what lies near them then anew.
    BufferCells buffer;
    if (pull && strategy.buffer && parameters.buffer_layer) {
      BufferReport made;
      buffer = buffer_layer(shape, lattice, layout, nodes, *around, eligible, h, surface, made);
      report.nb_buffer_hexes = made.nb_hexes;
      report.nb_buffer_pyramids = made.nb_pyramids;
      report.nb_buffer_faces = made.nb_faces;
      report.buffer_bases = made.bases;
      if (made.nb_faces > 0) anew();
    }
    emit_wall_cells(tube_walls, *around, inserted);
    const CoreCounts core = emit_core(lattice, layout, buffer, kept, h, *around, inserted);
    report.nb_core_cells = core.nb_core_cells;
    report.nb_lattice_points = core.nb_lattice_points;
    report.nb_apex_points = core.nb_apex_points;
    report.nb_pulled_points = core.nb_pulled_points;
    report.nb_narrow_pyramids = core.nb_narrow_pyramids;
    report.nb_inner_apexes = core.nb_inner_apexes;
  }
  step("core", 0.25);
  report.nb_surface_nodes = nodes.size();
  report.nb_surface_triangles = surface.triangles.size();
  // The surface's nodes at the CAD's sharp corners and edges (the tets' first nodes).
  for (const int n : nodes_at(sharp, surface))
    report.sharp_nodes.push_back(static_cast<index_t>(n));

  // 9. Boundary layers, inside the shape (by ray parity), clear of the faces and of the core.
  // None where a local size wants finer than h: finer lattices' points fill that zone.
  std::vector<char> no_layers;
  if (local)
    for (const Vec3& p : surface.nodes) no_layers.push_back(field.at(p) < h ? 1 : 0);
  const std::size_t before_layers = inserted.points.size();
  report.nb_layer_points =
      place_layers(nodes, surface, shape.face_solid_count, lattice, sweep_axis, swept, nb_layers,
                   parameters.layer_thickness * h, parameters.lattice_margin * h, *parity, *around,
                   inserted, local ? &no_layers : nullptr, layer_specs, &report.face_layers);
  for (std::size_t e = 0; e < report.face_layers.size(); ++e) {
    FaceLayersApplied& applied = report.face_layers[e];
    applied.faces = layer_entries[e].faces;
    applied.layers = layer_entries[e].layers;
    applied.thickness = layer_entries[e].thickness;
    applied.growth = layer_entries[e].growth;
  }
  check_face_layers_placed(layer_entries, report.face_layers, h);
  if (local)
    report.nb_graded_points =
        place_graded_points(inside, lattice, *parity, *around, kGradedClearance, inserted);
  // (Swept, every point repeats on every plane; the way without points inside has none.)
  if (sweep_axis < 0 && strategy.lattice_points)
    report.nb_axis_points = place_axis_points(shape, lattice, *around, *parity, h, inserted);
  // The face layers' points (the last place_layers() added) stay at their depths: they go first
  // among the isolated points, and improve_tets() leaves every point before them in place (the
  // points on lattice faces too: finer lattices' points there keep their place then).
  std::size_t nb_face_layer_points = 0;
  for (const FaceLayersApplied& applied : report.face_layers)
    nb_face_layer_points += applied.nb_points;
  std::size_t isolated_before = 0;  // isolated points before the face layers' in `inserted`
  for (std::size_t i = 0; i < before_layers + report.nb_layer_points - nb_face_layer_points; ++i)
    isolated_before += inserted.face[i] < 0;
  std::size_t nb_on_faces = face_points_first(inserted);
  // (Swept: nothing moves, and the face layers' points on caps are face points.)
  if (nb_face_layer_points > 0 && sweep_axis < 0) {  // every point in the range is isolated
    const auto first = inserted.points.begin() + static_cast<std::ptrdiff_t>(nb_on_faces);
    std::rotate(first, first + static_cast<std::ptrdiff_t>(isolated_before),
                first + static_cast<std::ptrdiff_t>(isolated_before + nb_face_layer_points));
  }
  step("layers", 0.3);

  // 10. TetGen: the surface kept as it is, the lattice faces with their lattice points, the other
  // points as isolated vertices.
  TetrahedralizeInput input;
  input.facets = make_facets(surface, nodes, lattice.lattice_face, lattice.face_plane);
  input.points = nodes;
  input.points.insert(input.points.end(), inserted.points.begin(),
                      inserted.points.begin() + static_cast<std::ptrdiff_t>(nb_on_faces));
  add_face_points(input.facets, input.points, nodes.size(), lattice.lattice_face,
                  lattice.face_plane, 1e-7 * h);
  // The lattice faces' triangles: a face's lattice points are h apart, the sides of its loops
  // as short as its edges' curvature makes them, and the triangles between them skinny (a tet
  // on one is no better than its smallest angle). Points inside the face, clear of the core
  // (its cells and closing pyramids keep their circumspheres empty) and of the points inside,
  // raise them (not swept: the planes repeat the first one's points), outside the squares of
  // four kept lattice points (gmsh_1385_Laufrad_1000's thin blades at 250k hold 43 % hex volume
  // in such cells, core or not; 8.9 % with points inside their faces).
  InsertedPoints facet_points;  // face points, after the others (their faces in order)
  if (sweep_axis < 0)
    for (Facet& facet : input.facets) {
      const std::size_t face = static_cast<std::size_t>(facet.marker - 1);
      if (!lattice.lattice_face[face]) continue;
      const int axis = lattice.face_plane[face]->axis;
      const std::vector<Vec3> points = tetgen::refine_facet(
          facet, input.points, kFacetAngle,
          [&](const Vec3& q) { return kFacetRadius * walls.at(lattice.frame.to_world(q)); },
          [&](const Vec3& q) {
            return !in_kept_square(lattice, kept, q, axis) && !around->core_balls.holds(q, 0) &&
                   !around->buffer_cells.near(q, kFacetClearance * h) &&
                   !around->core_points.any_within(q, kFacetClearance * h) &&
                   !around->layer_points.any_within(q, kFacetClearance * h);
          },
          input.points.size());
      for (const Vec3& q : points) {
        facet.polygons.push_back({static_cast<int>(input.points.size())});
        input.points.push_back(q);
        facet_points.points.push_back(q);
        facet_points.face.push_back(facet.marker - 1);
      }
    }
  report.nb_facet_points = facet_points.points.size();
  const auto on_faces_end = static_cast<std::ptrdiff_t>(nb_on_faces);
  inserted.points.insert(inserted.points.begin() + on_faces_end, facet_points.points.begin(),
                         facet_points.points.end());
  inserted.face.insert(inserted.face.begin() + on_faces_end, facet_points.face.begin(),
                       facet_points.face.end());
  nb_on_faces += facet_points.points.size();
  input.points.insert(input.points.end(),
                      inserted.points.begin() + static_cast<std::ptrdiff_t>(nb_on_faces),
                      inserted.points.end());
  input.first_isolated = nodes.size() + nb_on_faces;
  const std::size_t given = input.points.size();
  // The core's faces TetGen must keep (emit_core()), as inner facets of their own marker.
  const int constraint_marker = shape.faces.Extent() + 1;
  std::vector<std::array<int, 3>> constraints;
  // The core's points pulled off the lattice (emit_core()), by their place among TetGen's points,
  // with their lattice positions: improve_tets() tells the core's cells and pyramids by those.
  std::vector<std::pair<std::size_t, Vec3>> pulled;
  // The buffer's cells, by their vertices among TetGen's points: improve_tets() keeps them.
  std::vector<std::vector<index_t>> kept_cells;
  if (!inserted.pulled.empty() || !inserted.kept_cells.empty()) {
    NodeHash at(input.points, 1e-3 * h);
    for (std::size_t i = 0; i < given; ++i) at.add(static_cast<int>(i));
    for (const auto& [where, q] : inserted.pulled) {
      const int i = at.find(where, 1e-6 * h);
      if (i >= 0) pulled.emplace_back(static_cast<std::size_t>(i), q);
    }
    for (const std::array<Vec3, 3>& t : inserted.constraints) {
      const int a = at.find(t[0], 1e-6 * h), b = at.find(t[1], 1e-6 * h),
                c = at.find(t[2], 1e-6 * h);
      if (a < 0 || b < 0 || c < 0) continue;  // (every corner is a point given)
      input.facets.push_back(Facet{{{a, b, c}}, {}, constraint_marker});
      constraints.push_back({a, b, c});
    }
    for (const std::vector<Vec3>& cell : inserted.kept_cells) {
      std::vector<index_t> vertices;
      for (const Vec3& q : cell) {
        const int i = at.find(q, 1e-6 * h);
        if (i >= 0) vertices.push_back(static_cast<index_t>(i));
      }
      if (vertices.size() == cell.size()) kept_cells.push_back(std::move(vertices));
    }
  }
  input.to_world = [&](const Vec3& p) { return lattice.frame.to_world(p); };
  // Swept: TetGen on the first slab only, its first plane's triangles extruded (else on the
  // whole volume, the tets rebuilt as columns below).
  std::size_t extruded = 0;
  std::optional<TetrahedralizeOutput> swept_tets;
  if (sweep_axis >= 0)
    swept_tets = tetrahedralize_swept(tetgen, input, swept, nodes.size(), sweep_axis,
                                      lattice.spacing[sweep_axis], extruded);
  TetrahedralizeOutput tets = swept_tets ? std::move(*swept_tets) : tetgen.run(std::move(input));
  // 10a. The pulled cells and pyramids split as the lattice's.
  if (!inserted.splits.empty())
    report.nb_resplit_cells =
        resplit_core(tets.points, tets.tets, constraints, inserted.splits, 1e-6 * h);
  // The core's facets are no boundary.
  if (!inserted.constraints.empty()) {
    std::size_t kept_faces = 0;
    for (std::size_t i = 0; i < tets.boundary.size(); ++i)
      if (tets.boundary_marker[i] != constraint_marker) {
        tets.boundary[kept_faces] = tets.boundary[i];
        tets.boundary_marker[kept_faces++] = tets.boundary_marker[i];
      }
    tets.boundary.resize(kept_faces);
    tets.boundary_marker.resize(kept_faces);
  }
  report.tetgen_command = tets.command;
  report.nb_tetgen_restarts = tets.nb_restarts;
  report.nb_nudged_points = tets.nb_nudged;
  const std::size_t made = tets.points.size() / 3;
  report.nb_steiner_points = made > given ? made - given : 0;
  step("tetgen", 0.6);

  // 10b. Swept: the tets rebuilt as columns over the first plane's triangles.
  if (sweep_axis >= 0 && !swept_tets)
    extruded = extrude_tets(sweep_axis, lattice.spacing[sweep_axis], given, tets);
  report.nb_extruded_triangles = extruded;

  // 10c. The tets TetGen put in voids the solids enclose (it carves from the convex hull only).
  {
    TetMesh in_frame;
    in_frame.points = std::move(tets.points);
    in_frame.tets = std::move(tets.tets);
    report.nb_void_tets = remove_outside_components(
        in_frame, tets.boundary, [&](const Vec3& q) { return parity->inside(q); });
    tets.points = std::move(in_frame.points);
    tets.tets = std::move(in_frame.tets);
  }
  // 10d. The tets fill the surface given, no more and no less (a guard: TetGen carving too little
  // or too much, never seen on the corpora).
  {
    const double enclosed = enclosed_volume(nodes, surface.triangles, shape.face_solid_count);
    const double filled = tets_volume(tets.points, tets.tets);
    if (std::abs(filled - enclosed) > kVolumeTolerance * std::abs(enclosed)) {
      std::ostringstream text;
      text << "TetGen's tets hold a volume of " << filled << " where the surface given encloses "
           << enclosed << " (" << std::showpos << std::setprecision(3)
           << 100 * (filled - enclosed) / enclosed << " %)";
      throw TetrahedralizeFailure(text.str());
    }
  }

  // 11. The tets in the world, regions by solid.
  TetMesh mesh = world_mesh(regions_brep, shape, surface, lattice.frame, tets);
  step("regions", 0.65);

  // 12. Flips and node moves against slivers.
  ImproveParameters improve;
  improve.spacing = lattice.spacing;
  improve.ticks = lattice.ticks;
  improve.sweep_axis = sweep_axis;
  improve.nb_surface_nodes =
      nodes.size() +
      (nb_face_layer_points > 0 && sweep_axis < 0 ? nb_on_faces + nb_face_layer_points : 0);
  improve.max_boundary_shift = deflection;
  // A tet under 0.2 (an element a solver should not get) that no flip improves gets a vertex
  // inside; swept, the columns stay.
  improve.insert_below = sweep_axis < 0 ? 0.2 : 0.0;
  // The closing pyramids stay acceptable to the recombination at its default bound (a nudge
  // that took them to 0.2-0.3 lost gmsh_part's core block at its 250k size: 78.5 % hex volume
  // against 90.8 % kept).
  improve.pyramid_floor = RecombineParameters{}.min_scaled_jacobian;
  improve.kept_cells = std::move(kept_cells);
  std::vector<std::int32_t> boundary_face(tets.boundary_marker.size());
  for (std::size_t i = 0; i < boundary_face.size(); ++i)
    boundary_face[i] = static_cast<std::int32_t>(tets.boundary_marker[i]) - 1;
  // The faces with a local size keep their triangles (a swap lengthens a side past the size).
  std::vector<std::int32_t> swappable = boundary_face;
  for (std::int32_t& face : swappable)
    if (face >= 0 && items_at_h.face_size[static_cast<std::size_t>(face)] < h) face = -1;
  // The path of the boundary nodes but those of faces and edges under h in `sizes` and of
  // face layers.
  const auto path_holding = [&](const LocalSizeItems& sizes) {
    std::vector<bool> kept_face(sizes.face_size.size(), false), kept_edge(sizes.edge_size.size());
    for (std::size_t f = 0; f < kept_face.size(); ++f)
      kept_face[f] = sizes.face_size[f] < h || layered[f];
    for (std::size_t e = 0; e < kept_edge.size(); ++e) kept_edge[e] = sizes.edge_size[e] < h;
    return boundary_path(shape, surface, kept_face, kept_edge, 1e-6 * h);
  };
  // The boundary nodes inside a face or edge move along it (not swept: nothing moves there),
  // but for those of faces and edges with a local size or face layers, and the lattice points
  // (improve_tets() keeps them). Those of lattice faces and of faces between two solids move
  // (their tets on both sides kept positive): held, gmsh_as1-tu-203 at its 50k size kept 206 tets
  // under 0.2, 135 of them on faces between solids; moved, 36.
  const std::unique_ptr<SurfacePath> along_faces =
      sweep_axis < 0 ? path_holding(items_at_h) : nullptr;
  improve.surface = along_faces.get();
  ImproveReport improved;
  std::vector<double> lattice_points = tets.points;
  for (const auto& [i, q] : pulled) {
    lattice_points[3 * i] = q.x, lattice_points[3 * i + 1] = q.y, lattice_points[3 * i + 2] = q.z;
  }
  const double volume_before = tets_volume(mesh.points, mesh.tets);
  improve_tets(mesh, lattice_points, tets.boundary, swappable, improve, improved);
  // The boundary swaps move the surface by up to the chord deflection each: on a wall thinner
  // than that (a tube 0.05 thick at h 40, 0.2 of deflection) they took its bore's side into the
  // bore, 92 % more volume. The volume may not move away from BRepMesh's by more than
  // kVolumeDrift of it. (On the real and random parts the flips and moves change the volume by
  // at most 0.17 %.)
  const double volume_after = tets_volume(mesh.points, mesh.tets);
  if (std::abs(volume_after - triangulated_volume) >
      std::abs(volume_before - triangulated_volume) + kVolumeDrift * triangulated_volume) {
    std::ostringstream text;
    text << "the flips and node moves against slivers changed the volume by " << std::showpos
         << std::setprecision(3) << 100 * (volume_after / volume_before - 1)
         << " % (walls thinner than the chord deflection, " << std::noshowpos << deflection << "?)";
    throw SurfaceTooCoarse(text.str());
  }
  report.shape_volume = shape.volume.Mass();
  report.mesh_volume = volume_after;
  report.min_tet_quality_before = improved.min_quality_before;
  report.nb_face_flips = improved.face_flips;
  report.nb_edge_flips = improved.edge_flips;
  report.nb_boundary_swaps = improved.boundary_swaps;
  report.nb_node_moves = improved.node_moves;
  report.nb_boundary_node_moves = improved.boundary_node_moves;
  report.nb_inserted_points = improved.inserted_vertices;
  report.nb_buffer_cells_released = improved.released_cells;
  report.nb_lattice_face_points_released = improved.released_face_points;
  report.nb_split_open_cells = improved.split_open_cells;
  step("slivers", 0.9);
  // A tet the flips and moves left flat or folded (gmsh_Block at h 1.18: scaled Jacobian
  // 1e-13) fails this way of placing the points, not the whole run: the next way is tried.
  try {
    validate_tet_mesh(mesh);
  } catch (const InputError& e) {
    throw TetrahedralizeFailure(std::string("the tets made are not all valid (") + e.what() + ")");
  }

  // 12b. The tets the recombination leaves, improved: its elements stay, the tets between them
  // get flips and moves, also of the nodes of faces and edges sized for their features (held
  // through step 12: moved there, they broke the prisms and hexahedra across narrow faces, KiCad's
  // Samtec FMC connector 593 -> 119 hexahedra), keeping the elements at the nodes acceptable.
  if (parameters.polish && sweep_axis < 0) {
    const std::unique_ptr<SurfacePath> along = path_holding(local_items);
    std::vector<char> movable(mesh.nb_vertices(), kFree);
    for (const std::array<index_t, 3>& triangle : tets.boundary)
      for (const index_t v : triangle) movable[v] = kFixed;
    for (index_t v = 0; v < improve.nb_surface_nodes; ++v)
      movable[v] = along->dimension(v) > 0 ? kOnSurface : kFixed;
    // The recombination's phases shown (at 1M tets it takes about 10 s), the fraction where the
    // sliver stage left it.
    ProgressCallback recombining;
    if (progress)
      recombining = [&](const std::string& phase, double) {
        return progress("mesh shape: polish, recombining: " + phase + way, 0.9);
      };
    PolishReport polished;
    polish_leftover_tets(mesh, std::move(movable), along.get(), RecombineParameters{}, 0.2,
                         polished, recombining);
    report.polish_tets_below_before = polished.below_before;
    report.polish_tets_below_after = polished.below_after;
    report.nb_polish_flips = polished.flips;
    report.nb_polish_node_moves = polished.node_moves;
    report.nb_polish_boundary_node_moves = polished.boundary_node_moves;
    report.nb_polish_inserted_points = polished.inserted_vertices;
    step("polish", 0.92);
  }

  // 13. How far the boundary nodes are from the CAD faces they lie on.
  std::vector<int> given_face = surface.node_face;
  given_face.insert(given_face.end(), inserted.face.begin(), inserted.face.end());
  given_face.resize(given, -1);
  // The points TetGen added on the boundary (FreeCAD's I22_2_5_16withEPL22_6_16.stp at h 0.812,
  // three, before its lattice edges kept their points) lie on the face of a triangle at them.
  const std::vector<int> vertex_face = point_faces(std::move(given_face), mesh.points.size() / 3,
                                                   tets.boundary, tets.boundary_marker);
  // A node lies on the CAD where it lies on the face of a boundary triangle at it: those faces
  // too (KiCad's heatsink, swept: its fillets' profile nodes took the plane beside them).
  report.max_boundary_distance = max_boundary_distance(
      shape, mesh, vertex_face, 1e-6 * h,
      vertex_faces(mesh.nb_vertices(), vertex_face, tets.boundary, boundary_face));
  report.local_sizes =
      local_sizes_applied(local_sizes, given_items.faces, given_items.edges, surface);
  if (sweep)
    add_swept_segments(report.local_sizes, local_sizes, given_items.edges, *sweep, shape.edge_faces,
                       surface);
  step("check", 0.95);

  // 14. Second order: the boundary mid-edge nodes on the CAD.
  if (tet10) {
    SecondOrderReport second;
    *tet10 =
        second_order_mesh(shape, mesh, vertex_face, tets.boundary, boundary_face, 1e-9 * h, second);
    report.nb_projected_mid_nodes = second.nb_projected;
    report.nb_straight_mid_nodes = second.nb_straight;
    step("second order", 1.0);
  }
  return mesh;
}

}  // namespace hexmerge::mesher
