// The private module hexmerge._core: numpy arrays in, numpy arrays out, exceptions translated.
//
// Validation with friendly messages lives in the pure-Python package (hexmerge/_validate.py);
// this file only converts data and errors. The GIL is released while the core works.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "hexmerge/check/check_mesh.h"
#include "hexmerge/check/validate_tet_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/cell_type.h"
#include "hexmerge/mesh/mixed_mesh.h"
#include "hexmerge/mesh/second_order.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/recombine.h"
#include "hexmerge/tetgen/tetrahedralize.h"
#ifdef HEXMERGE_WITH_OCC
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/read_shape_file.h"
#include "hexmerge/occ/regions_by_solid.h"
#endif

namespace py = pybind11;
using namespace hexmerge;

namespace {

constexpr auto kIn = py::array::c_style | py::array::forcecast;
using PointsIn = py::array_t<double, kIn>;
using IndexIn = py::array_t<index_t, kIn>;
using RegionsIn = py::array_t<std::int32_t, kIn>;
using TypesIn = py::array_t<std::uint8_t, kIn>;

// The Python type of InputError, created at import and kept for the interpreter's lifetime (a
// raw pointer: a static py::object would be released after the interpreter is gone).
PyObject* g_input_error = nullptr;

const char* entity_name(Entity entity) {
  switch (entity) {
    case Entity::Node:
      return "node";
    case Entity::Element:
      return "element";
    case Entity::Parameter:
      return "parameter";
    case Entity::None:
      break;
  }
  return nullptr;
}

// Copies a numpy array of any shape into a flat vector, checking its shape.
template <class T, int F>
std::vector<T> flat(const py::array_t<T, F>& a, py::ssize_t columns, const char* what) {
  if (columns > 0 ? (a.ndim() != 2 || a.shape(1) != columns) : a.ndim() != 1) {
    throw py::value_error(std::string(what) + ": wrong array shape");
  }
  return std::vector<T>(a.data(), a.data() + a.size());
}

// Moves a vector into a numpy array without copying the data.
template <class T>
py::array_t<T> to_numpy(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(v));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, heap->data(), owner);
}

template <class T>
py::array_t<T> to_numpy(std::vector<T>&& v) {
  const auto n = static_cast<py::ssize_t>(v.size());
  return to_numpy(std::move(v), {n});
}

template <class T, std::size_t N>
py::dict per_type(const std::array<T, N>& values) {
  py::dict d;
  for (int t = 0; t < NB_CELL_TYPES; ++t) {
    d[descriptor(static_cast<CellType>(t)).name] = values[t];
  }
  return d;
}

py::object optional_index(index_t i) {
  return i == NO_INDEX ? py::object(py::none()) : py::object(py::int_(i));
}

// Builds the core's parameters from {name: text}; set_parameter checks names and ranges.
RecombineParameters make_parameters(const std::map<std::string, std::string>& options) {
  RecombineParameters parameters;
  for (const auto& [name, value] : options) set_parameter(parameters, name, value);
  validate_parameters(parameters);
  return parameters;
}

std::vector<std::int32_t> regions_of(const py::object& regions, const char* what) {
  if (regions.is_none()) return {};
  return flat(regions.cast<RegionsIn>(), 0, what);
}

// Wraps the optional Python progress function. The core calls it from the thread that started
// the run (this one), with the GIL released: take it back for the call. Calls are throttled so a
// chatty phase does not spend its time in Python; Ctrl-C (a pending signal) cancels the run.
class Progress {
 public:
  explicit Progress(py::object function) : function_(std::move(function)) {}

  ProgressCallback callback() {
    return [this](const std::string& phase, double fraction) { return call(phase, fraction); };
  }

  // Re-raises what the Python side raised (KeyboardInterrupt, an error in the callback) in place
  // of the core's Cancelled.
  void rethrow_python_error() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  bool call(const std::string& phase, double fraction) {
    const auto now = std::chrono::steady_clock::now();
    const bool due = phase != last_phase_ || fraction >= 1.0 || now - last_call_ > kInterval;
    if (!due) return true;
    last_phase_ = phase;
    last_call_ = now;
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (function_.is_none()) return true;
      const py::object answer = function_(phase, fraction);
      if (answer.is_none()) return true;
      if (!PyBool_Check(answer.ptr()) && !py::isinstance(answer, numpy_bool())) {
        throw InputError(
            "progress must return True, False or None, got " + std::string(py::repr(answer)),
            Entity::Parameter);
      }
      return answer.cast<bool>();
    } catch (...) {
      error_ = std::current_exception();
      return false;
    }
  }

  static py::object numpy_bool() { return py::module_::import("numpy").attr("bool_"); }

  static constexpr std::chrono::milliseconds kInterval{50};
  py::object function_;
  std::string last_phase_;
  std::chrono::steady_clock::time_point last_call_{};
  std::exception_ptr error_;
};

// Wall time per phase as a dict, in the order the phases ran.
py::dict phases_dict(const PhaseSeconds& phases) {
  py::dict d;
  for (const auto& [name, seconds] : phases) d[name.c_str()] = seconds;
  return d;
}

py::dict report_to_dict(const RecombineReport& r) {
  py::dict d;
  d["input_tets"] = r.input_tets;
  d["output_cells"] = r.output_cells;
  d["output_counts"] = per_type(r.output_counts);
  d["element_reduction_percent"] = r.element_reduction_percent;
  d["input_volume"] = r.input_volume;
  d["volume_fraction"] = per_type(r.volume_fraction);
  d["nonconforming_quads"] = r.nonconforming_quads;
  d["block_hexahedra"] = r.block_hexahedra;
  d["group_seeds"] = r.group_seeds;
  d["groups"] = r.groups;
  d["group_hexahedra"] = r.group_hexahedra;
  d["groups_failed"] = r.groups_failed;
  d["groups_capped"] = r.groups_capped;
  d["closing_pyramids"] = r.closing_pyramids;
  d["released_elements"] = r.released_elements;
  d["local_moves"] = r.local_moves;
  d["swap_moves"] = r.swap_moves;
  d["reselection_moves"] = r.reselection_moves;
  d["local_search_saved"] = r.local_search_saved;
  d["selection_strategy"] = r.selection_strategy;
  d["min_scaled_jacobian"] = per_type(r.min_scaled_jacobian);
  d["mean_scaled_jacobian"] = per_type(r.mean_scaled_jacobian);
  py::dict templates;
  for (const auto& [name, count] : r.candidates_per_template) templates[name.c_str()] = count;
  d["candidates_per_template"] = templates;
  d["candidates_total"] = r.candidates_total;
  d["candidates_unclosable"] = r.candidates_unclosable;
  d["post_merge"] = r.post_merge;
  d["census_hex_candidates"] = r.census_hex_candidates;
  d["census_closable"] = r.census_closable;
  d["census_hex_candidates_after"] = r.census_hex_candidates_after;
  d["census_closable_after"] = r.census_closable_after;
  d["post_merge_attempted"] = r.post_merge_attempted;
  d["post_merge_rounds"] = r.post_merge_rounds;
  d["post_merge_closed"] = r.post_merge_closed;
  d["contractions"] = r.contractions;
  d["node_moves"] = r.node_moves;
  d["vertex_splits"] = r.vertex_splits;
  d["post_merge_lifted"] = r.post_merge_lifted;
  d["flips_23"] = r.flips_23;
  d["flips_32"] = r.flips_32;
  d["flips_44"] = r.flips_44;
  d["phase_seconds"] = phases_dict(r.phase_seconds);
  // None unless the optimality bound ran (parameter optimality_bound).
  const auto bound_field = [&](auto value) {
    return r.bound_computed ? py::cast(value) : py::object(py::none());
  };
  d["bound_elements"] = bound_field(r.bound_elements);
  d["bound_best_elements"] = bound_field(r.bound_best_elements);
  d["bound_proved"] = bound_field(r.bound_proved);
  d["bound_conforming"] = bound_field(r.bound_conforming);
  d["gap_percent"] = bound_field(r.gap_percent);
  d["hex_volume_bound"] = bound_field(r.hex_volume_bound);
  d["hex_volume_bound_proved"] = bound_field(r.hex_volume_bound_proved);
  return d;
}

py::dict check_report_to_dict(const CheckReport& r) {
  py::dict d;
  d["valid"] = r.valid();
  d["nb_cells"] = r.nb_cells;
  d["counts"] = per_type(r.counts);
  d["inverted_cells"] = r.inverted_cells;
  d["min_scaled_jacobian"] = r.min_scaled_jacobian;
  d["worst_cell"] = optional_index(r.worst_cell);
  d["nonconforming_quads"] = r.nonconforming_quads;
  d["cracks"] = r.cracks;
  d["overshared_faces"] = r.overshared_faces;
  d["unused_input_nodes"] = r.unused_input_nodes;
  d["moved_nodes"] = r.moved_nodes;
  d["declared_changed_nodes"] = r.declared_changed_nodes;
  d["off_boundary_nodes"] = r.off_boundary_nodes;
  d["volume_not_kept"] = r.volume_not_kept;
  d["linear_volume_difference"] = r.linear_volume_difference;
  d["region_mismatches"] = r.region_mismatches;
  d["input_volume"] = r.input_volume;
  d["output_volume"] = r.output_volume;
  d["relative_volume_difference"] = r.relative_volume_difference;
  d["max_region_volume_difference"] = r.max_region_volume_difference;
  d["worst_region"] =
      r.worst_region < 0 ? py::object(py::none()) : py::object(py::int_(r.worst_region));
  d["problems"] = r.problems;
  return d;
}

py::dict mesh_to_dict(MixedMesh&& m) {
  py::dict d;
  const auto nb_points = static_cast<py::ssize_t>(m.nb_vertices());
  std::vector<std::uint8_t> types(m.types.size());
  for (std::size_t c = 0; c < m.types.size(); ++c) types[c] = static_cast<std::uint8_t>(m.types[c]);
  d["points"] = to_numpy(std::move(m.points), {nb_points, 3});
  d["types"] = to_numpy(std::move(types));
  d["offsets"] = to_numpy(std::move(m.offsets));
  d["cell_vertices"] = to_numpy(std::move(m.cell_vertices));
  d["regions"] =
      m.regions.empty() ? py::object(py::none()) : py::object(to_numpy(std::move(m.regions)));
  d["source_offsets"] = to_numpy(std::move(m.source_offsets));
  d["source_tets"] = to_numpy(std::move(m.source_tets));
  d["changed_nodes"] = to_numpy(std::move(m.changed_nodes));
  return d;
}

MixedMesh mesh_from_arrays(const PointsIn& points, const TypesIn& types, const IndexIn& offsets,
                           const IndexIn& cell_vertices, const py::object& regions,
                           const py::object& source_offsets, const py::object& source_tets) {
  MixedMesh m;
  m.points = flat(points, 3, "points");
  const auto raw_types = flat(types, 0, "types");
  m.types.resize(raw_types.size());
  for (std::size_t c = 0; c < raw_types.size(); ++c) {
    if (raw_types[c] >= NB_CELL_TYPES) throw py::value_error("types: unknown cell type");
    m.types[c] = static_cast<CellType>(raw_types[c]);
  }
  m.offsets = flat(offsets, 0, "offsets");
  m.cell_vertices = flat(cell_vertices, 0, "cell_vertices");
  m.regions = regions_of(regions, "regions");
  if (!source_offsets.is_none()) {
    m.source_offsets = flat(source_offsets.cast<IndexIn>(), 0, "source_offsets");
    m.source_tets = flat(source_tets.cast<IndexIn>(), 0, "source_tets");
  }
  return m;
}

py::tuple run_recombine(const PointsIn& points, const IndexIn& cells, const py::object& regions,
                        const std::map<std::string, std::string>& options,
                        const py::object& progress) {
  const bool quadratic = cells.ndim() == 2 && cells.shape(1) == 10;
  Tet10Mesh tet10;
  TetMesh input;
  if (quadratic) {
    tet10.points = flat(points, 3, "points");
    tet10.tets10 = flat(cells, 10, "cells");
    tet10.regions = regions_of(regions, "regions");
  } else {
    input.points = flat(points, 3, "points");
    input.tets = flat(cells, 4, "cells");
    input.regions = regions_of(regions, "regions");
  }
  const RecombineParameters parameters = make_parameters(options);
  Progress watcher(progress);
  RecombineReport report;
  QuadraticMixedMesh mesh;
  try {
    py::gil_scoped_release released;
    if (quadratic) {
      mesh = recombine(tet10, parameters, report, watcher.callback());
    } else {
      mesh.linear = recombine(input, parameters, report, watcher.callback());
    }
  } catch (const Cancelled&) {
    watcher.rethrow_python_error();
    throw;
  }
  py::dict out = mesh_to_dict(std::move(mesh.linear));
  if (quadratic) {
    out["quadratic_offsets"] = to_numpy(std::move(mesh.quadratic.offsets));
    out["quadratic_nodes"] = to_numpy(std::move(mesh.quadratic.nodes));
  }
  return py::make_tuple(out, report_to_dict(report));
}

py::dict run_check(const PointsIn& points, const TypesIn& types, const IndexIn& offsets,
                   const IndexIn& cell_vertices, const py::object& regions,
                   const py::object& source_offsets, const py::object& source_tets,
                   const PointsIn& input_points, const IndexIn& input_tets,
                   const py::object& input_regions, const py::object& changed_nodes) {
  MixedMesh mesh =
      mesh_from_arrays(points, types, offsets, cell_vertices, regions, source_offsets, source_tets);
  if (!changed_nodes.is_none()) {
    mesh.changed_nodes = flat(changed_nodes.cast<IndexIn>(), 0, "changed_nodes");
  }
  TetMesh input;
  input.points = flat(input_points, 3, "input_points");
  input.tets = flat(input_tets, 4, "input_tets");
  input.regions = regions_of(input_regions, "input_regions");
  CheckReport report;
  {
    py::gil_scoped_release released;
    report = check_mesh(mesh, input);
  }
  return check_report_to_dict(report);
}

void run_validate(const PointsIn& points, const IndexIn& cells, const py::object& regions) {
  TetMesh input;
  input.points = flat(points, 3, "points");
  input.tets = flat(cells, 4, "cells");
  input.regions = regions_of(regions, "regions");
  py::gil_scoped_release released;
  validate_tet_mesh(input);
  const TetTopology topology(input);  // faces shared by three tets, folded tets
}

// TetGen through the library's one interface (tetgen/tetrahedralize.h), for the benchmarks'
// mesh generator: surface triangles (each a facet) and isolated points in, tets out.
py::tuple run_tetrahedralize(const PointsIn& points, const IndexIn& triangles,
                             py::ssize_t first_isolated, const std::string& program,
                             double time_limit, int restarts) {
  const std::vector<double> xyz = flat(points, 3, "points");
  const std::vector<index_t> corners = flat(triangles, 3, "triangles");
  const std::size_t nb_points = xyz.size() / 3;
  if (first_isolated < 0 || static_cast<std::size_t>(first_isolated) > nb_points) {
    throw InputError("first_isolated must be between 0 and the number of points",
                     Entity::Parameter);
  }
  tetgen::TetrahedralizeInput input;
  for (std::size_t i = 0; i < nb_points; ++i) {
    input.points.push_back({xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]});
  }
  for (std::size_t f = 0; f < corners.size() / 3; ++f) {
    tetgen::Facet facet;
    facet.polygons.push_back({});
    for (int k = 0; k < 3; ++k) {
      const index_t v = corners[3 * f + k];
      if (v >= nb_points) {
        throw InputError("triangle " + std::to_string(f) + " refers to point " + std::to_string(v) +
                             ", but there are " + std::to_string(nb_points) + " points",
                         Entity::Element, static_cast<index_t>(f));
      }
      facet.polygons.back().push_back(static_cast<int>(v));
    }
    facet.marker = 1;
    input.facets.push_back(std::move(facet));
  }
  input.first_isolated = static_cast<std::size_t>(first_isolated);
  tetgen::TetrahedralizeParameters parameters;
  parameters.program = program;
  parameters.time_limit = time_limit;
  parameters.restarts = restarts;
  tetgen::TetrahedralizeOutput out;
  {
    py::gil_scoped_release released;
    try {
      const tetgen::Tetrahedralizer tetgen(parameters);
      out = tetgen.run(std::move(input));
    } catch (const tetgen::TetrahedralizeFailure& e) {
      throw InputError(e.what());
    }
  }
  const auto nb_out = static_cast<py::ssize_t>(out.points.size() / 3);
  const auto nb_tets = static_cast<py::ssize_t>(out.tets.size() / 4);
  return py::make_tuple(to_numpy(std::move(out.points), {nb_out, 3}),
                        to_numpy(std::move(out.tets), {nb_tets, 4}), out.command);
}

#ifdef HEXMERGE_WITH_OCC
py::tuple run_regions_by_solid(const std::string& brep, const PointsIn& points,
                               const IndexIn& cells, double tolerance, int samples_per_piece,
                               bool classify_every_tet, int nb_threads) {
  TetMesh mesh;
  mesh.points = flat(points, 3, "points");
  mesh.tets = flat(cells, 4, "cells");
  RegionsBySolidParameters parameters;
  parameters.tolerance = tolerance;
  parameters.samples_per_piece = samples_per_piece;
  parameters.classify_every_tet = classify_every_tet;
  parameters.nb_threads = nb_threads;
  RegionsBySolidReport report;
  std::vector<std::int32_t> regions;
  {
    py::gil_scoped_release released;
    regions = regions_by_solid(brep, mesh, parameters, report);
  }
  py::dict d;
  d["nb_solids"] = report.nb_solids;
  d["nb_shared_faces"] = report.nb_shared_faces;
  d["nb_interface_nodes"] = report.nb_interface_nodes;
  d["nb_pieces"] = report.nb_pieces;
  d["nb_split_pieces"] = report.nb_split_pieces;
  d["nb_classified_points"] = report.nb_classified_points;
  d["nb_unassigned_tets"] = report.nb_unassigned_tets;
  d["phase_seconds"] = phases_dict(report.phase_seconds);
  return py::make_tuple(to_numpy(std::move(regions)), d);
}

py::tuple run_mesh_shape(const std::string& brep, const std::map<std::string, std::string>& options,
                         bool second_order, const py::object& progress) {
  MeshShapeParameters parameters;
  for (const auto& [name, value] : options) {
    mesh_shape_parameter_table().set(parameters, name, value);
  }
  MeshShapeReport report;
  TetMesh mesh;
  Tet10Mesh tet10;
  Progress watcher(progress);
  try {
    py::gil_scoped_release released;
    if (second_order)
      tet10 = mesh_shape_tet10(brep, parameters, report, watcher.callback());
    else
      mesh = mesh_shape(brep, parameters, report, watcher.callback());
  } catch (const Cancelled&) {
    watcher.rethrow_python_error();
    throw;
  }
  py::dict d;
  d["nb_solids"] = report.nb_solids;
  d["nb_faces"] = report.nb_faces;
  d["nb_lattice_faces"] = report.nb_lattice_faces;
  d["nb_surface_nodes"] = report.nb_surface_nodes;
  d["nb_surface_triangles"] = report.nb_surface_triangles;
  d["nb_lattice_points"] = report.nb_lattice_points;
  d["nb_core_cells"] = report.nb_core_cells;
  d["nb_apex_points"] = report.nb_apex_points;
  d["nb_pulled_points"] = report.nb_pulled_points;
  d["nb_narrow_pyramids"] = report.nb_narrow_pyramids;
  d["nb_inner_apexes"] = report.nb_inner_apexes;
  d["nb_buffer_hexes"] = report.nb_buffer_hexes;
  d["nb_buffer_pyramids"] = report.nb_buffer_pyramids;
  d["nb_buffer_faces"] = report.nb_buffer_faces;
  d["nb_wall_hexes"] = report.nb_wall_hexes;
  d["nb_walls"] = report.nb_walls;
  d["nb_wall_faces"] = report.nb_wall_faces;
  d["nb_buffer_cells_released"] = report.nb_buffer_cells_released;
  d["nb_lattice_face_points_released"] = report.nb_lattice_face_points_released;
  d["polish_tets_below_before"] = report.polish_tets_below_before;
  d["polish_tets_below_after"] = report.polish_tets_below_after;
  d["nb_polish_flips"] = report.nb_polish_flips;
  d["nb_polish_node_moves"] = report.nb_polish_node_moves;
  d["nb_polish_boundary_node_moves"] = report.nb_polish_boundary_node_moves;
  d["nb_polish_inserted_points"] = report.nb_polish_inserted_points;
  d["nb_split_open_cells"] = report.nb_split_open_cells;
  {
    py::dict bases;
    for (const auto& [name, member] : kBufferBaseCounts) bases[name] = report.buffer_bases.*member;
    d["buffer_bases"] = bases;
  }
  d["nb_resplit_cells"] = report.nb_resplit_cells;
  d["nb_layer_points"] = report.nb_layer_points;
  d["nb_steiner_points"] = report.nb_steiner_points;
  d["nb_nudged_points"] = report.nb_nudged_points;
  d["nb_tetgen_restarts"] = report.nb_tetgen_restarts;
  d["min_tet_quality_before"] = report.min_tet_quality_before;
  d["nb_face_flips"] = report.nb_face_flips;
  d["nb_edge_flips"] = report.nb_edge_flips;
  d["nb_boundary_swaps"] = report.nb_boundary_swaps;
  d["nb_node_moves"] = report.nb_node_moves;
  d["nb_boundary_node_moves"] = report.nb_boundary_node_moves;
  d["nb_inserted_points"] = report.nb_inserted_points;
  py::list sharp;
  for (const SharpFeatureReport& f : report.sharp_features) {
    py::dict e;
    e["kind"] = f.kind, e["faces"] = f.faces, e["edges"] = f.edges, e["angle"] = f.angle;
    e["point"] = py::make_tuple(f.point[0], f.point[1], f.point[2]);
    sharp.append(e);
  }
  d["sharp_features"] = sharp;
  py::list sharp_nodes;
  for (const index_t n : report.sharp_nodes) sharp_nodes.append(n);
  d["sharp_nodes"] = sharp_nodes;
  d["sweep_axis"] = report.sweep_axis;
  py::list axes;
  for (const auto& axis : report.frame) axes.append(py::make_tuple(axis[0], axis[1], axis[2]));
  d["frame"] = axes;
  d["spacing"] = py::make_tuple(report.spacing[0], report.spacing[1], report.spacing[2]);
  d["max_boundary_distance"] = report.max_boundary_distance;
  d["shape_volume"] = report.shape_volume;
  d["mesh_volume"] = report.mesh_volume;
  d["estimated_tets"] = report.estimated_tets;
  d["nb_unrefined_faces"] = report.nb_unrefined_faces;
  d["nb_corner_nodes_removed"] = report.nb_corner_nodes_removed;
  d["nb_flat_surface_triangles"] = report.nb_flat_surface_triangles;
  d["nb_revolution_faces"] = report.nb_revolution_faces;
  d["nb_zipped_faces"] = report.nb_zipped_faces;
  d["nb_unfolded_patches"] = report.nb_unfolded_patches;
  d["nb_internal_vertices"] = report.nb_internal_vertices;
  d["nb_parted_sides"] = report.nb_parted_sides;
  d["nb_narrow_faces"] = report.nb_narrow_faces;
  d["glue_fuzzy"] = report.glue_fuzzy;
  d["nb_axis_points"] = report.nb_axis_points;
  d["nb_crossing_refinements"] = report.nb_crossing_refinements;
  d["bounded_surface_repairs"] = report.bounded_surface_repairs;
  d["nb_extruded_triangles"] = report.nb_extruded_triangles;
  d["nb_void_tets"] = report.nb_void_tets;
  d["nb_shared_faces"] = report.nb_shared_faces;
  d["nb_sewn_solids"] = report.nb_sewn_solids;
  d["nb_split_lens_edges"] = report.nb_split_lens_edges;
  py::list local_sizes;
  for (const LocalSizeApplied& l : report.local_sizes) {
    py::dict e;
    e["faces"] = l.faces, e["edges"] = l.edges, e["size"] = l.size;
    e["nb_triangles"] = l.nb_triangles, e["nb_segments"] = l.nb_segments;
    e["max_side"] = l.max_side;
    local_sizes.append(e);
  }
  d["local_sizes"] = local_sizes;
  py::list face_layers;
  for (const FaceLayersApplied& l : report.face_layers) {
    py::dict e;
    e["faces"] = l.faces, e["layers"] = l.layers, e["thickness"] = l.thickness;
    e["growth"] = l.growth, e["nb_nodes"] = l.nb_nodes, e["nb_points"] = l.nb_points;
    e["nb_per_layer"] = l.nb_per_layer;
    face_layers.append(e);
  }
  d["face_layers"] = face_layers;
  d["sweep_skipped"] = report.sweep_skipped;
  d["nb_graded_points"] = report.nb_graded_points;
  d["nb_facet_points"] = report.nb_facet_points;
  d["nb_feature_edges"] = report.nb_feature_edges;
  d["nb_feature_faces"] = report.nb_feature_faces;
  d["nb_thin_wall_patches"] = report.nb_thin_wall_patches;
  d["nb_unsized_wall_patches"] = report.nb_unsized_wall_patches;
  d["thinnest_unsized_wall"] = report.thinnest_unsized_wall;
  d["thickest_unsized_wall"] = report.thickest_unsized_wall;
  if (second_order) {
    d["nb_projected_mid_nodes"] = report.nb_projected_mid_nodes;
    d["nb_straight_mid_nodes"] = report.nb_straight_mid_nodes;
  }
  d["strategy"] = report.strategy;
  py::list failed;
  for (const std::string& f : report.failed_strategies) failed.append(f);
  d["failed_strategies"] = failed;
  d["tetgen_command"] = report.tetgen_command;
  d["phase_seconds"] = phases_dict(report.phase_seconds);
  if (second_order) {
    const auto nb_points = static_cast<py::ssize_t>(tet10.points.size() / 3);
    const auto nb_tets = static_cast<py::ssize_t>(tet10.tets10.size() / 10);
    return py::make_tuple(to_numpy(std::move(tet10.points), {nb_points, 3}),
                          to_numpy(std::move(tet10.tets10), {nb_tets, 10}),
                          to_numpy(std::move(tet10.regions)), d);
  }
  const auto nb_points = static_cast<py::ssize_t>(mesh.points.size() / 3);
  const auto nb_tets = static_cast<py::ssize_t>(mesh.tets.size() / 4);
  return py::make_tuple(to_numpy(std::move(mesh.points), {nb_points, 3}),
                        to_numpy(std::move(mesh.tets), {nb_tets, 4}),
                        to_numpy(std::move(mesh.regions)), d);
}
#endif

// A parameter table's rows as dicts (the front ends' format, see parameter_table's doc).
py::list table_rows(const std::vector<ParameterInfo>& table) {
  py::list rows;
  for (const ParameterInfo& p : table) {
    py::dict row;
    row["name"] = p.name;
    row["type"] = p.type;
    row["default"] = p.default_value;
    row["unit"] = p.unit;
    row["min"] = p.min;
    row["max"] = p.max;
    row["min_exclusive"] = p.min_exclusive;
    row["choices"] = p.choices;
    row["label"] = p.label;
    row["doc"] = p.doc;
    row["cli_flag"] = p.cli_flag;
    row["freecad_property"] = p.freecad_property;
    rows.append(row);
  }
  return rows;
}

py::list cell_types() {
  py::list rows;
  for (int t = 0; t < NB_CELL_TYPES; ++t) {
    const CellDescriptor& d = descriptor(static_cast<CellType>(t));
    py::list faces;
    for (int f = 0; f < d.nb_faces; ++f) {
      py::list face;
      for (int k = 0; k < d.face_size[f]; ++k) face.append(d.face[f][k]);
      faces.append(py::tuple(face));
    }
    py::list edges;
    for (int e = 0; e < d.nb_edges; ++e) edges.append(py::make_tuple(d.edge[e][0], d.edge[e][1]));
    py::dict row;
    row["value"] = t;
    row["name"] = d.name;
    row["nb_vertices"] = d.nb_vertices;
    row["nb_edges"] = d.nb_edges;
    row["nb_faces"] = d.nb_faces;
    row["faces"] = faces;
    row["edges"] = edges;
    row["vtk_id"] = d.vtk_id;
    row["nb_quad_faces"] = d.nb_quad_faces;
    rows.append(row);
  }
  return rows;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = R"doc(HexMerge's compiled core (private: use the package `hexmerge`).

Arrays in, arrays out. Bad input raises InputError (a ValueError) naming the node or element
at fault; a run cancelled from the progress callback raises Cancelled; a broken internal
invariant raises RuntimeError.)doc";

  // InputError is a ValueError carrying `entity` ("node", "element", "parameter" or None) and
  // `index` (0-based, or None).
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<Cancelled> cancelled(m, "Cancelled", PyExc_Exception);
  // ResourceError: the machine lacks what the run needs (threads); a MemoryError.
  static py::exception<ResourceError> resource_error(m, "ResourceError", PyExc_MemoryError);
  g_input_error = input_error.ptr();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::object error = py::reinterpret_borrow<py::object>(g_input_error)(e.what());
      const char* entity = entity_name(e.entity());
      error.attr("entity") = entity ? py::object(py::str(entity)) : py::object(py::none());
      error.attr("index") = optional_index(e.id());
      PyErr_SetObject(g_input_error, error.ptr());
    } catch (const Cancelled& e) {
      cancelled(e.what());
    } catch (const ResourceError& e) {
      resource_error(e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError,
                      "out of memory: the run needs more memory than the system gives it (a "
                      "smaller mesh, fewer threads or more memory)");
    } catch (const InternalError& e) {
      PyErr_SetString(PyExc_RuntimeError, (std::string("HexMerge internal error: ") + e.what() +
                                           " (please report this bug)")
                                              .c_str());
    }
  });

  m.def("recombine", &run_recombine, py::arg("points"), py::arg("cells"),
        py::arg("regions") = py::none(), py::arg("options") = std::map<std::string, std::string>{},
        py::arg("progress") = py::none(),
        R"doc(Merges the tets of a Tet4 or Tet10 mesh into hexahedra, prisms and pyramids.

points   float64 (N, 3).
cells    (M, 4) linear tets or (M, 10) quadratic tets, VTK node order, uint32-compatible ids.
regions  int32 (M,) region id per tet, or None (one region).
options  {parameter name: value as text}; see parameter_table().
progress callable(phase: str, fraction: float) -> bool | None, called from this thread with
         the GIL held; returning False cancels the run (raises Cancelled).

Returns (mesh, report): mesh is a dict of arrays points (N, 3), types uint8 (C,) (CellType
values), offsets (C+1,), cell_vertices, regions (C,) or None, source_offsets (C+1,),
source_tets, changed_nodes (sorted ids of the nodes the engine moved, removed or added); for
Tet10 input also quadratic_offsets (C+1,) and quadratic_nodes (corners then
mid-edge nodes in VTK quadratic order, ids of the input's points). report is a dict.)doc");

  m.def("check_mesh", &run_check, py::arg("points"), py::arg("types"), py::arg("offsets"),
        py::arg("cell_vertices"), py::arg("regions"), py::arg("source_offsets"),
        py::arg("source_tets"), py::arg("input_points"), py::arg("input_tets"),
        py::arg("input_regions"), py::arg("changed_nodes") = py::none(),
        R"doc(Checks a linear mixed mesh against the tet mesh it came from.

The mixed mesh is given by the arrays of recombine()'s result (source_offsets and source_tets
may be None: regions are then not traced). The input is a linear tet mesh (input_tets (M, 4)).
changed_nodes (sorted ids, or None) are the nodes the mesh declares moved, removed or added.
Returns the CheckReport as a dict; `valid` is True when the mesh passes.)doc");

  m.def("validate_tet_mesh", &run_validate, py::arg("points"), py::arg("cells"),
        py::arg("regions") = py::none(),
        R"doc(Raises InputError naming the first node or element that the engine cannot process.

points float64 (N, 3); cells (M, 4); regions int32 (M,) or None.)doc");

  m.def("tetrahedralize", &run_tetrahedralize, py::arg("points"), py::arg("triangles"),
        py::arg("first_isolated") = 0, py::arg("tetgen") = "tetgen", py::arg("time_limit") = 0.0,
        py::arg("restarts") = 5,
        R"doc(Tets of a closed triangulated surface with TetGen (tetgen -pY: the surface kept).

points          float64 (N, 3): the surface's nodes, then isolated points inside.
triangles       (F, 3) ids into points: the surface (an empty (0, 3) array: the Delaunay
                tetrahedralisation of the points).
first_isolated  points from this index on are isolated interior vertices.
tetgen          the TetGen program; time_limit seconds per run (0: 30 s + 1 ms per point);
                restarts: runs made again after one that does not finish.
Returns (points float64 (P, 3): the input's, then TetGen's own; tets (M, 4), orientation as
TetGen makes them; the command run). TetGen's failures raise InputError.)doc");

#ifdef HEXMERGE_WITH_OCC
  m.attr("with_opencascade") = true;
  m.def("regions_by_solid", &run_regions_by_solid, py::arg("brep"), py::arg("points"),
        py::arg("cells"), py::arg("tolerance") = 1e-6, py::arg("samples_per_piece") = 5,
        py::arg("classify_every_tet") = false, py::arg("nb_threads") = 0,
        R"doc(The solid of a shape (BREP text) holding each tet; OpenCASCADE.

brep      the shape as BREP text (FreeCAD: Shape.exportBrepToString()).
points    float64 (N, 3).
cells     (M, 4) linear tets (corners only), uint32-compatible ids.
tolerance distance to a face shared by two solids, as a fraction of the shape's diagonal.
samples_per_piece, classify_every_tet, nb_threads: see RegionsBySolidParameters.

Returns (solids, report): solids int32 (M,), 0-based solid index in TopExp::MapShapes order
(FreeCAD's Shape.Solids) or -1; report a dict of counts and phase_seconds.)doc");
  m.def("mesh_shape", &run_mesh_shape, py::arg("brep"), py::arg("options"),
        py::arg("second_order") = false, py::arg("progress") = py::none(),
        R"doc(Lattice-seeded tets of a solid shape (BREP text) with OpenCASCADE and TetGen.

options  {parameter name: value as text}; see mesh_parameter_table() ("size" is required).
Returns (points float64 (N, 3), tets (M, 4), regions int32 (M,), report dict); with
second_order, tets (M, 10) in VTK's Tet10 order, the boundary mid-edge nodes on the CAD
(mesh_shape_tet10), and report["nb_projected_mid_nodes"], report["nb_straight_mid_nodes"].
progress  as for recombine(): called with ("mesh shape: <step>", fraction) after each step;
returning False cancels between steps (hexmerge.Cancelled).)doc");
  m.def(
      "mesh_parameter_table", [] { return table_rows(mesh_shape_parameter_table().info()); },
      R"doc(The mesher's parameters (MeshShapeParameters), in parameter_table()'s format.)doc");
  m.def(
      "read_shape_file",
      [](const std::string& path, bool with_unit) -> py::object {
        std::string unit, brep;
        {
          py::gil_scoped_release released;
          brep = read_shape_file(path, &unit);
        }
        if (with_unit) return py::make_tuple(brep, unit);
        return py::str(brep);
      },
      py::arg("path"), py::arg("with_unit") = false,
      R"doc(The shape in a STEP, BREP or IGES file, as BREP text (in millimetres for STEP and IGES);
with_unit=True: (BREP text, the length unit the file declares, "" when none).)doc");
#else
  m.attr("with_opencascade") = false;
#endif

  m.def(
      "parameter_table", [] { return table_rows(parameter_table()); },
      R"doc(The engine's parameters, in display order: a list of dicts with name, type ("float",
"int", "bool", "choice", "text"), default (text), unit, min, max, min_exclusive (the range is
(min, max]), choices, label, doc, cli_flag (the command-line option) and freecad_property (the
FreeCAD property; "" when the add-on does not show it).)doc");

  m.def("cell_types", &cell_types,
        R"doc(The linear cell types, by value: a list of dicts with value, name, nb_vertices,
nb_edges, nb_faces, faces (outward, VTK order), edges (VTK quadratic mid-edge order), vtk_id and
nb_quad_faces.)doc");
}
