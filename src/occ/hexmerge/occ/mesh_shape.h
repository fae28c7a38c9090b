#pragma once
/// @file
/// Hex-friendly tetrahedral meshing of a CAD shape: lattice-seeded tets (OpenCASCADE + TetGen)
/// that the recombination engine merges into mostly hexahedra.
///
/// After Baudouin, Remacle, Marchandise, Henrotte & Geuzaine, "A frontal approach to
/// hex-dominant mesh generation" (AMSES 2014): where a mesh's vertices sit on a cubic lattice,
/// its tets fill the lattice cells and recombine into hexahedra. The steps:
///  1. the shape's faces are triangulated with OpenCASCADE (BRepMesh), then refined by
///     longest-side bisection with Delaunay flips to the target size; every new node is
///     evaluated on the CAD surface or edge;
///  2. a frame is chosen (the normals of the largest planar faces, else the principal axes of
///     inertia) and a cubic lattice of spacing about h laid in it, its planes through the shape's
///     bounding box, so that planar faces on those planes carry lattice points of their own
///     ("lattice faces"; they are not refined but get the lattice points);
///  3. lattice points inside the shape and far enough from the other faces are kept; the cells
///     with all eight corners kept form the hexahedral core; every quad face on the core's
///     boundary gets the centre of the cell beyond it as the apex of a closing pyramid, and core
///     cells whose pyramid would be crowded by the surface are given up (this is what lets the
///     core recombine conformingly);
///  4. layers of points offset from the surface nodes along the inward normal, where the surface
///     is smooth and there is room, so that the boundary becomes prisms;
///  5. TetGen tetrahedralises the surface (kept as it is, `-pY`) with the points as isolated
///     vertices of its input (not `-i`: non-Delaunay lattice tets), through its files; the tets are
///     read back, oriented, and given the solid that holds them as region. The nodes of straight
///     edges across the lattice on lattice faces are put exactly on one line first (TetGen 1.5
///     loops on nearly collinear loop nodes), and TetGen runs under a time limit;
///  6. flips (remove_slivers) alternate with moves of the boundary-layer and Steiner points
///     (smooth_nodes), neither ever lowering the smallest scaled Jacobian. Surface nodes in
///     needle triangles are smoothed on their face after step 1, and the layers' depths vary by
///     up to 10 % per node so that the layers' sides are not cocircular quads.
///
/// A swept shape (one cross-section extruded along a lattice axis, from a planar cap on one
/// lattice plane to one on another: cylinders, plates with holes, profiles, and solids stacked
/// along the axis or side by side, with faces between them on lattice planes or along the axis)
/// is meshed as a sweep instead: the first plane's boundary is split to at most h and repeated
/// on every lattice plane along the axis, the walls are strips of two triangles per side and
/// slab (no refinement), the caps above are copies of the first, the layers are placed on the
/// first plane and repeated (on both sides of a wall between two solids), and no closing
/// pyramids are needed across the axis. Every plane then has the same points, every tet lies
/// between two consecutive planes, and the tets of a slab are prisms over the cross-section's
/// triangles, which the engine's block pairs into hexahedra (cylinder: 95 % hex volume, the rest
/// prisms, no tets).
///
/// The header needs no OpenCASCADE include: shapes come in as BREP text.

#include <array>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "hexmerge/core/parameter_table.h"
#include "hexmerge/core/phase_timer.h"
#include "hexmerge/core/progress.h"
#include "hexmerge/mesh/second_order.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// How mesh_shape() works. Lengths are in the shape's units. Every field is a row of
/// mesh_shape_parameter_table() with its unit and range.
struct MeshShapeParameters {
  /// Target element size h: the lattice spacing (adjusted per axis so that the bounding box holds
  /// a whole number of cells, at least one) and the surface's longest edge. > 0 and not larger
  /// than the shape's largest extent.
  double size = 0.0;
  /// Layers of points offset from the curved and unaligned faces along the inward normal
  /// (0 to 3; -1: one on swept shapes, none on the others). Each layer is `layer_thickness` h
  /// thick. On a swept shape the layer is a regular ring of prisms and hexahedra along the walls
  /// whose depth sets a first-order element's stress there; unswept, the layer's points add
  /// about 40 % to the tets and no prisms or hexahedra (Delaunay does not join them into
  /// columns), so by default there is none.
  int boundary_layers = -1;
  /// Thickness of one boundary layer, as a fraction of h, in [0.1, 1].
  double layer_thickness = 0.3;
  /// Lattice points nearer than this fraction of h to a face that is not a lattice face (swept
  /// shapes: this beyond their boundary layers) are dropped. In [0.1, 2].
  double lattice_margin = 0.3;
  /// Chord deflection of the surface triangulation on curved faces, as a fraction of h.
  /// In [0.001, 0.5].
  double surface_deflection = 0.02;
  /// Sizes at the CAD's short edges, as a fraction of h: an edge shorter than twice this gets a
  /// local size of its length, at least this (as `local_sizes` on it: the surface and the inside
  /// graded out to h), so that its short segments do not meet nodes h away in needle
  /// triangles and flat tets; with it on, a face from 0.01 h to 0.1 h wide (twice its area over
  /// its perimeter) gets three times its width; 0: none. Not applied to swept shapes (their
  /// cross-section is repeated as it is). In [0, 0.5].
  double feature_size = 0.1;
  /// Lattice orientation: "auto" (normals of the largest planar faces, else principal axes of
  /// inertia), "principal" (principal axes of inertia), "global" (x, y, z).
  std::string frame = "auto";
  /// Where the shape is one cross-section extruded along a lattice axis between two planar caps
  /// on lattice planes (plates with holes, cylinders, profiles; one solid or several, stacked or
  /// side by side), make the tets swept too: the same cross-section on every lattice plane along
  /// the axis, so that they recombine into hexahedra and prisms only, with no pyramids.
  bool sweep = true;
  /// Pull the hexahedral core towards the surface (not swept, not with boundary layers or face
  /// layers, which keep out of the core): the lattice's steps leave the
  /// core's closing pyramids' apexes up to a cell from the faces; the core's boundary nodes
  /// move out along the pyramids' bases, the apexes with them, until the apexes come 0.15 h
  /// from the faces, as far as the cells (scaled Jacobian 0.9) and pyramids (0.4) stay good;
  /// the moved cells and pyramids are kept whole as TetGen constraints. So are the core cells
  /// that would otherwise leave the core: those whose closing pyramid's apex lies in their
  /// circumsphere (a narrow cell beside a wide one on a rectilinear axis), and those where the
  /// centre of the cell across is outside the shape, closed by an apex nearer the face (0.15 h
  /// from every face, 0.25 h from the surface's nodes, the pyramid at 0.4). When TetGen fails on
  /// them, the next way of placing the points is the lattice without it.
  bool pull_core = true;
  /// With the core pulled, a buffer layer of hexahedra between it and the surface (on the real
  /// parts the median hex volume at about 250k tets 78.4 -> 81.6 %, with fewer elements under 0.2;
  /// see docs/benchmarks-real-parts.md): each closing pyramid's base whose apex closes no other
  /// base, its corners projected onto one CAD face (not a lattice face, a face with a local size or
  /// one between two solids) within 35 degrees of its normal, 0.15 h to 1.5 h away and 0.3 h inside
  /// the face's edges, becomes a hexahedron (scaled Jacobian at least 0.3) whose top is two of the
  /// face's triangles: the face is triangulated again with the tops in it. Side faces no other such
  /// hexahedron shares are closed by pyramids to the apexes of the core's pyramids beside them.
  /// With it, the walls between two coaxial cylinders of one solid kThinnestWallCell h to
  /// kThickestWallCell h apart (mesher/wall_cells.h), which the core does not reach, get a grid of
  /// hexahedra across them, their quads put into both cylinders' triangles.
  /// When TetGen fails on them, the next way of placing the points is the pulled core without the
  /// layer.
  bool buffer_layer = true;
  /// After the sliver stage, the tets the recombination (at its default parameters) leaves
  /// are improved: it is run once, its hexahedra, prisms and pyramids stay, and the tets left
  /// under a scaled Jacobian of 0.2 get flips and moves of their nodes (those on faces and edges
  /// sized for their features too, along them) that keep every element at the nodes acceptable
  /// (mesher/polish.h). Not on swept shapes. Costs one more recombination.
  bool polish = true;
  /// Time limit of one TetGen run, in seconds; 0: 30 s plus 1 ms per point (far above TetGen's
  /// own time, about 1 s per 20k points). A run past it (TetGen 1.5 can loop on a lattice face),
  /// or one that leaves no tet, is restarted with the lattice faces' loops started at other
  /// vertices, up to 5 times; then mesh_shape fails, saying so. In [0, 86400].
  double tetgen_time_limit = 0.0;
  /// Memory the meshing and recombination may take, in GB (10^9 bytes); 0: what the system has
  /// available. A size whose estimated tets (from the shape's volume and area) would need more
  /// is refused before any work, with the estimate. In [0, 10^6].
  double memory_limit = 0.0;
  /// The TetGen program: a name looked up on PATH, or a path.
  std::string tetgen = "tetgen";
  /// A directory for TetGen's files, kept afterwards; empty: a temporary one, removed.
  std::string work_directory;
  /// Local sizes, finer than h, on some faces and edges (1-based, as FreeCAD's FaceN and EdgeN
  /// and the report number them): entries "ITEMS:SIZE" separated by ';', ITEMS a comma-separated
  /// list of "N" or "FaceN" (a face), "EdgeN" (an edge); e.g. "5:1.5; Edge3,Edge4:0.5". The
  /// surface there is refined to the size (its neighbours grading out by half the distance),
  /// the lattice and layers keep clear, finer lattices fill the graded zone inside. A swept shape
  /// stays swept for local sizes on its caps' edges only (the walls' sides split to them);
  /// otherwise it is not swept, and MeshShapeReport::sweep_skipped says why. Sizes in (0, h],
  /// at least h / 1000. See parse_local_sizes().
  std::string local_sizes;
  /// Boundary layers on some faces (1-based, as FreeCAD's FaceN): entries
  /// "FACES:LAYERS:THICKNESS[:GROWTH]" separated by ';', FACES a comma-separated list of "N" or
  /// "FaceN"; e.g. "3,Face4:3:0.5:1.5". The surface nodes of those faces get LAYERS points along
  /// the inward normal, the first THICKNESS (a length) deep, each next layer GROWTH times thicker
  /// than the one before (default 1), where there is room (the clearance rules of the global
  /// layers; depths vary by up to 10 % per node); the faces are no lattice faces and the lattice
  /// keeps clear of the layers. A swept shape stays swept for layers on its walls (placed on the
  /// first plane and repeated), not on its caps (MeshShapeReport::sweep_skipped says why). The
  /// other faces' nodes keep `boundary_layers`.
  /// LAYERS in [1, 10], THICKNESS in (0, h], GROWTH in [1, 3]. See parse_face_layers().
  std::string face_layers;
};

/// One entry of MeshShapeParameters::local_sizes.
struct LocalSize {
  std::vector<int> faces;  ///< 1-based face numbers
  std::vector<int> edges;  ///< 1-based edge numbers
  double size = 0.0;
};

/// The entries of a local_sizes text ("" : none).
/// @throws InputError (Entity::Parameter) naming the entry that is not "ITEMS:SIZE", an item
///         that is not N, FaceN or EdgeN (N >= 1), or a size that is not a number > 0
std::vector<LocalSize> parse_local_sizes(const std::string& text);

/// One entry of MeshShapeParameters::face_layers.
struct FaceLayers {
  std::vector<int> faces;  ///< 1-based face numbers
  int layers = 0;          ///< layers of points, 1 to 10
  double thickness = 0.0;  ///< the first layer's depth (a length)
  double growth = 1.0;     ///< each layer's depth over the one before, 1 to 3
};

/// The entries of a face_layers text ("": none).
/// @throws InputError (Entity::Parameter) naming the entry that is not
///         FACES:LAYERS:THICKNESS[:GROWTH], a face that is not N or FaceN (N >= 1), a number of
///         layers outside [1, 10], a thickness not > 0, or a growth outside [1, 3]
std::vector<FaceLayers> parse_face_layers(const std::string& text);

/// What mesh_shape() did with one entry of face_layers.
struct FaceLayersApplied {
  std::vector<int> faces;  ///< 1-based, as given
  int layers = 0;
  double thickness = 0.0;
  double growth = 1.0;
  /// the surface nodes of its faces where the surface is smooth (the others, on sharp edges
  /// and corners, take no layers)
  std::size_t nb_nodes = 0;
  std::size_t nb_points = 0;  ///< layer points placed from those nodes
  /// per layer (first = nearest the face), the nodes that got a point in it
  std::vector<std::size_t> nb_per_layer;
};

/// What mesh_shape() did with one local size.
struct LocalSizeApplied {
  std::vector<int> faces;  ///< 1-based
  std::vector<int> edges;  ///< 1-based
  double size = 0.0;
  std::size_t nb_triangles = 0;  ///< surface triangles on its faces
  std::size_t nb_segments = 0;   ///< surface segments on its edges
  double max_side = 0.0;  ///< the longest side of those triangles and segments, after meshing
};

/// The table of MeshShapeParameters' fields (core/parameter_table.h), in display order, with
/// MeshShapeParameters{}'s defaults; the Python module, the CLI and the FreeCAD add-on build the
/// mesher's options from it.
const ParameterTable<MeshShapeParameters>& mesh_shape_parameter_table();

/// Checks every field against its row of mesh_shape_parameter_table(), and that `tetgen` names a
/// program. @throws InputError (Entity::Parameter) naming the first bad one
void validate_mesh_shape_parameters(const MeshShapeParameters& parameters);

/// What mesh_shape() did.
/// A CAD feature sharper than usable elements can follow: a face corner or an edge whose angle
/// inside the solid is under 8.13 degrees (a tet with a corner there has a scaled Jacobian of at
/// most sqrt(2) sin(angle) < 0.2, a boundary triangle in a corner at most its angle).
struct SharpFeatureReport {
  std::string kind;               ///< "corner" (of a face) or "edge" (the solid's dihedral angle)
  std::vector<int> faces;         ///< 1-based, as given: the corner's face, the edge's two faces
  std::vector<int> edges;         ///< 1-based, as given: the corner's two edges, or the edge
  double angle = 0.0;             ///< degrees
  std::array<double, 3> point{};  ///< the corner, or where the edge's angle is smallest
};

/// The buffer layer's census of the core's closing pyramids' bases (MeshShapeReport::buffer_bases):
/// each base at the first of these tests it fails, or kept. The tops are the bases' corners
/// projected onto the surface.
struct BufferBaseCounts {
  std::size_t considered = 0;   ///< closing pyramids' bases
  std::size_t apex_shared = 0;  ///< at the core's concave edges and corners (apex shared)
  std::size_t no_top_far = 0;   ///< a corner with no surface within 1.5 h
  /// a corner nearest a face that takes no tops (a lattice face, a face with a local size or
  /// face layers, a face between two solids)
  std::size_t no_top_face = 0;
  std::size_t no_top_projection = 0;  ///< a corner whose projection onto its face went elsewhere
  std::size_t no_top_clearance = 0;   ///< a corner's top within 0.3 h of another face
  std::size_t two_faces = 0;          ///< corners whose tops lie on different faces
  std::size_t height_or_tilt = 0;     ///< a top nearer than 0.15 h, beyond 1.5 h or past 35 degrees
  std::size_t hex_quality = 0;        ///< the hexahedron under scaled Jacobian 0.3
  std::size_t split_quality = 0;      ///< one of its six tets under 0.2
  std::size_t folds = 0;  ///< its top or a side folds, or a quad corner opens, past the limits
  /// passed those, then dropped: its face's chart, the quads side by side, the side pyramids,
  /// the face's new triangles, crossings
  std::size_t dropped_later = 0;
  std::size_t kept = 0;  ///< buffer hexahedra (nb_buffer_hexes)
};

/// BufferBaseCounts' members by name (the report's keys), in the order of the tests.
inline constexpr std::pair<const char*, std::size_t BufferBaseCounts::*> kBufferBaseCounts[] = {
    {"considered", &BufferBaseCounts::considered},
    {"apex_shared", &BufferBaseCounts::apex_shared},
    {"no_top_far", &BufferBaseCounts::no_top_far},
    {"no_top_face", &BufferBaseCounts::no_top_face},
    {"no_top_projection", &BufferBaseCounts::no_top_projection},
    {"no_top_clearance", &BufferBaseCounts::no_top_clearance},
    {"two_faces", &BufferBaseCounts::two_faces},
    {"height_or_tilt", &BufferBaseCounts::height_or_tilt},
    {"hex_quality", &BufferBaseCounts::hex_quality},
    {"split_quality", &BufferBaseCounts::split_quality},
    {"folds", &BufferBaseCounts::folds},
    {"dropped_later", &BufferBaseCounts::dropped_later},
    {"kept", &BufferBaseCounts::kept}};

struct MeshShapeReport {
  std::size_t nb_solids = 0;
  std::size_t nb_faces = 0;
  std::size_t nb_lattice_faces = 0;      ///< planar faces on lattice planes
  std::size_t nb_surface_nodes = 0;      ///< nodes of the refined surface triangulation
  std::size_t nb_surface_triangles = 0;  ///< its triangles (lattice faces: BRepMesh's own)
  std::size_t nb_lattice_points = 0;     ///< lattice points inserted (inside and on lattice faces)
  std::size_t nb_core_cells = 0;         ///< lattice cells with all corners kept (hex core)
  std::size_t nb_apex_points = 0;        ///< closing-pyramid apexes inserted
  std::size_t nb_pulled_points = 0;      ///< core points moved off the lattice towards the surface
  /// Closing pyramids whose apex lies in their cell's circumsphere (narrow cells on a rectilinear
  /// axis), kept as constraints with the pulled core
  std::size_t nb_narrow_pyramids = 0;
  /// Closing pyramids' apexes placed inside, nearer their face, where the centre of the cell across
  /// is outside the shape (constrained, as the pulled core)
  std::size_t nb_inner_apexes = 0;
  /// The buffer layer (MeshShapeParameters::buffer_layer): hexahedra between the core and the
  /// surface, the pyramids closing their side faces, the CAD faces triangulated again with their
  /// tops
  std::size_t nb_buffer_hexes = 0;
  std::size_t nb_buffer_pyramids = 0;
  std::size_t nb_buffer_faces = 0;
  /// Hexahedra across tube walls (between two coaxial cylinders too close for the core), the
  /// walls that have them, and the CAD faces triangulated again with their quads
  std::size_t nb_wall_hexes = 0;
  std::size_t nb_walls = 0;
  std::size_t nb_wall_faces = 0;
  /// Buffer hexahedra and pyramids given up after TetGen: a tet under 0.2 beside them that the
  /// flips left (their tets and corners then improved as the others)
  std::size_t nb_buffer_cells_released = 0;
  /// Lattice points inside a lattice face, corners of no core cell, at a tet under 0.2 that the
  /// flips left: released with the buffer's cells to move along the face's plane
  std::size_t nb_lattice_face_points_released = 0;
  /// The polish (MeshShapeParameters::polish): the tets the recombination left under 0.2
  /// before and after it (with the same elements), and what it did
  std::size_t polish_tets_below_before = 0;
  std::size_t polish_tets_below_after = 0;
  std::size_t nb_polish_flips = 0;
  std::size_t nb_polish_node_moves = 0;
  std::size_t nb_polish_boundary_node_moves = 0;
  std::size_t nb_polish_inserted_points = 0;
  /// Lattice cells and buffer hexahedra one of whose faces nothing closed after the tet
  /// improvement, split into six pyramids to a vertex at their centre (else the recombination's
  /// block loses them and cells beside them after them).
  std::size_t nb_split_open_cells = 0;
  /// Why the core's closing pyramids' bases got a buffer hexahedron or not (each base counted
  /// once, at the first test it fails, in this order; docs/mesher.md, step 8a)
  BufferBaseCounts buffer_bases;
  std::size_t nb_resplit_cells = 0;   ///< pulled cells and pyramids TetGen split otherwise, resplit
  std::size_t nb_layer_points = 0;    ///< boundary-layer points inserted
  std::size_t nb_steiner_points = 0;  ///< points TetGen added
  std::size_t nb_nudged_points = 0;  ///< lattice points TetGen left out, moved by 1e-7 h, run again
  std::size_t nb_tetgen_restarts = 0;   ///< TetGen runs that failed on a lattice face, restarted
  double min_tet_quality_before = 0.0;  ///< smallest scaled Jacobian of TetGen's tets
  std::size_t nb_face_flips = 0;        ///< 2-3 flips taking out slivers (remove_slivers)
  std::size_t nb_edge_flips = 0;        ///< edge removals (3-2, 4-4, ...) taking out slivers
  std::size_t nb_boundary_swaps = 0;    ///< of which on the boundary, inside one planar face
  std::size_t nb_node_moves = 0;  ///< moves of boundary-layer and Steiner points (smooth_nodes)
  /// of those, moves of boundary nodes along their CAD face or edge
  std::size_t nb_boundary_node_moves = 0;
  std::size_t nb_inserted_points = 0;  ///< points inserted into tets under 0.2 no flip improved
  std::vector<SharpFeatureReport> sharp_features;  ///< the CAD's, see SharpFeatureReport
  /// The mesh's nodes at them: the corners' vertices and the sharp edges' nodes (a tet under a
  /// scaled Jacobian of 0.2 at one of them may be forced so by the CAD).
  std::vector<index_t> sharp_nodes;
  int sweep_axis = -1;  ///< the lattice axis the tets are swept along (0..2), -1: not swept
  /// Swept: the cross-section's triangles whose columns of prisms make the tets (0: TetGen's
  /// tets kept, see mesher::extrude_tets()).
  std::size_t nb_extruded_triangles = 0;
  /// Tets the tetrahedraliser put in voids the solids enclose, removed.
  std::size_t nb_void_tets = 0;
  std::array<std::array<double, 3>, 3> frame{};  ///< lattice axes (rows), unit vectors
  std::array<double, 3> spacing{};               ///< lattice spacing along each axis
  double max_boundary_distance = 0.0;  ///< largest distance of a boundary node to the shape
  double shape_volume = 0.0;           ///< the shape's volume (OpenCASCADE's, its solids')
  /// The tets' volume: the shape's within the chords of its curved faces (a torus of tube radius
  /// 6.9 at h 20: 7.4 % less)
  double mesh_volume = 0.0;
  double estimated_tets = 0;  ///< tets expected from the shape's volume and area, before any work
  /// Faces whose surface refinement to h did not converge and was given up (sides longer
  /// than h remain on them)
  std::size_t nb_unrefined_faces = 0;
  /// Surface nodes taken off the edges of sharp corners, where the face between them is
  /// narrower than 0.3 h up to 4 h from the vertex (coarsen_sharp_corners)
  std::size_t nb_corner_nodes_removed = 0;
  /// BRepMesh's surface triangles whose three nodes lay on one line (a face whose outline runs
  /// along one line and back), taken out: the triangle across split at the third node
  std::size_t nb_flat_surface_triangles = 0;
  /// Faces triangulated as surfaces of revolution, because BRepMesh left a face of the shape
  /// as it is without triangles (the same geometry); 0 when it did not
  std::size_t nb_revolution_faces = 0;
  /// Faces OpenCASCADE's surface mesher left without triangles that lie between two edges with
  /// the same ends, narrower than the chord deflection (slivers): no triangle on them, the
  /// faces across joined along one chain of segments
  std::size_t nb_zipped_faces = 0;
  /// Patches where OpenCASCADE's surface mesher folded a face's triangles over each other (near
  /// a sphere's pole or a cone's apex), triangulated anew on their outline
  std::size_t nb_unfolded_patches = 0;
  /// Vertices inside faces, on none of their edges (where solids touch at a point), made nodes of
  /// the faces' triangles
  std::size_t nb_internal_vertices = 0;
  /// Sides OpenCASCADE's surface mesher gave two faces that only come close there, each face's
  /// triangles split apart at a node of its own
  std::size_t nb_parted_sides = 0;
  /// faces narrower than 9e-4 h (twice their area over their perimeter) merged away, their nodes
  /// and those within that of them one node (none where that made the surface touch itself or
  /// leave a gap, or where every way failed or the shape was refused so: then the ways ran again)
  std::size_t nb_narrow_faces = 0;
  /// whether the surface repairs ran again from BRepMesh's triangles, each kept within the chord
  /// deflection of its face, because the surface they made first crossed itself
  bool bounded_surface_repairs = false;
  /// Times the surface was made again with finer sizes where the triangles of two faces crossed
  /// (faces closer than the chord deflection there), each round halving the sizes there
  std::size_t nb_crossing_refinements = 0;
  std::size_t nb_shared_faces = 0;  ///< faces between two solids (touching solids glued)
  /// The General Fuse's fuzzy value that glued the solids: 1e-7 h, or 1e-5 or 1e-4 of the
  /// shape's diagonal where a smaller one left a solid open; 0 when not glued
  double glue_fuzzy = 0.0;
  /// Solids made of a shape that held faces or shells only (an IGES file, a STEP file of
  /// surfaces): its faces sewn, each closed shell a solid; 0 when it held solids
  std::size_t nb_sewn_solids = 0;
  /// Edges split at their middle before meshing: one of the two edges of each hole (or face)
  /// bounded by two nearly straight edges between the same two vertices, which BRepMesh would
  /// divide into one segment each, leaving the hole no area (split_lens_edges())
  std::size_t nb_split_lens_edges = 0;
  /// The local sizes (MeshShapeParameters::local_sizes) as applied, in their order
  std::vector<LocalSizeApplied> local_sizes;
  std::size_t nb_graded_points = 0;  ///< points of the finer lattices around local sizes
  /// Points on the axes of tubes thinner than about h (wires, leads, pins; place_axis_points())
  std::size_t nb_axis_points = 0;
  std::size_t nb_facet_points = 0;   ///< points added inside lattice faces (refine_facet)
  std::size_t nb_feature_edges = 0;  ///< short CAD edges given a size by `feature_size`
  std::size_t nb_feature_faces = 0;  ///< narrow CAD faces given a size (with `feature_size` on)
  /// patches of the surface across walls from the chord deflection to 0.2 h thick given a size
  /// (with `feature_size` on; thin_walls.h)
  std::size_t nb_thin_wall_patches = 0;
  /// patches across walls thinner than the chord deflection, of even thickness, left without a
  /// size (their tets are flat), and those walls' thinnest and thickest (0: none)
  std::size_t nb_unsized_wall_patches = 0;
  double thinnest_unsized_wall = 0, thickest_unsized_wall = 0;
  /// The face layers (MeshShapeParameters::face_layers) as applied, in their order
  std::vector<FaceLayersApplied> face_layers;
  /// Why the shape was not swept where sweep is on (empty: swept, or not an extrusion)
  std::string sweep_skipped;
  /// mesh_shape_tet10(): boundary mid-edge nodes projected onto their CAD face or edge (on a
  /// plane: the midpoint itself)
  std::size_t nb_projected_mid_nodes = 0;
  /// mesh_shape_tet10(): boundary mid-edge nodes kept at their edge's midpoint, because on the
  /// CAD they would have made a Tet10's Jacobian at a corner non-positive or left the middle
  /// half of their edge
  std::size_t nb_straight_mid_nodes = 0;
  /// How the points were placed: "lattice" (lattice points, lattice faces, boundary layers),
  /// then, where TetGen failed on that, "lattice at 0.95 of the size", "lattice at 1.1 of the
  /// size", "lattice without lattice
  /// faces", "lattice without boundary layers" or "surface only" (TetGen's own points inside:
  /// few hexahedra).
  std::string strategy;
  std::vector<std::string> failed_strategies;  ///< the ways tried before, each with its failure
  std::string tetgen_command;                  ///< the command line run
  PhaseSeconds phase_seconds;                  ///< wall time per phase, in order
};

/// Tetrahedralises a solid shape with lattice-seeded points, ready for recombine().
///
/// @param[in]  brep        the shape as BREP text (one or more solids; FreeCAD:
///                         `Shape.exportBrepToString()`, files: read_shape_file.h)
/// @param[in]  parameters  see MeshShapeParameters
/// @param[out] report      counts, the frame, timings
/// @return a valid tet mesh (validate_tet_mesh), regions = the index of the solid holding each
///         tet, in the order TopExp::MapShapes(shape, TopAbs_SOLID) gives (FreeCAD's
///         `Shape.Solids`)
/// @param[in] progress  called at the end of each step of each way of placing the points, phase
///                      "mesh shape: <step>" (then the way's name in brackets after the first),
///                      fraction of that way done; returning false cancels (throws Cancelled)
///                      between steps
/// @throws InputError for BREP text that cannot be read, a shape without solids, an open shell
///         (naming the free edge), a size that is not positive or larger than the shape, a
///         surface refinement that does not converge, bad parameters (a local size naming a
///         face or edge the shape does not have, or larger than the size), or TetGen missing or
///         failing (with its output)
TetMesh mesh_shape(const std::string& brep, const MeshShapeParameters& parameters,
                   MeshShapeReport& report, const ProgressCallback& progress = {});

/// As mesh_shape(), in second order: a Tet10 mesh (VTK order) with a mid node on every edge,
/// numbered after the corners by edge (smaller node first, in increasing order). Mid nodes inside
/// are their edges' midpoints; on the boundary they are projected from the midpoint onto the CAD
/// face the edge lies on, or onto the CAD edge where the edge lies on one, so that curved faces
/// stay on the CAD (loads applied to a face find its nodes) -- except where that would make a
/// tet's Jacobian at a corner non-positive or put the node outside the middle half of its edge:
/// those stay at the midpoint, counted in report.nb_straight_mid_nodes. The corners and tets are
/// mesh_shape()'s.
Tet10Mesh mesh_shape_tet10(const std::string& brep, const MeshShapeParameters& parameters,
                           MeshShapeReport& report, const ProgressCallback& progress = {});

}  // namespace hexmerge
