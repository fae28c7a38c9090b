#pragma once
/// @file
/// CGAL's constrained Delaunay triangulation in a plane, each vertex carrying an index and each
/// face a mark, and which of its faces lie inside an outline (internal header of the mesher:
/// face_chart.cpp's faces triangulated again with quads, surface_unfold.cpp's patches). CGAL's
/// headers come before any of OpenCASCADE's in a source: OCCT's Handle() macro breaks them.

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <set>
#include <utility>

namespace hexmerge::mesher::cgal2 {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
using FaceInfo = CGAL::Triangulation_face_base_with_info_2<signed char, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceInfo>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::No_constraint_intersection_tag>;

/// Marks every face of `cdt` 1 inside `outline` (its sides as sorted pairs of the vertices'
/// indices, constraints of `cdt`): reached from outside across an odd number of its sides; 0
/// outside. False when the outline bounds no region (a face reached both ways; the marks are
/// then partial).
bool mark_inside(Cdt& cdt, const std::set<std::pair<int, int>>& outline);

}  // namespace hexmerge::mesher::cgal2
