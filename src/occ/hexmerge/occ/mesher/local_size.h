#pragma once
/// @file
/// Local sizes (internal header of mesh_shape(); no OpenCASCADE): the size field that faces and
/// edges given a finer size than h set around themselves, graded out to h, and the points of
/// finer lattices that fill the graded zone inside the shape.

#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hexmerge/geometry/vec3.h"
#include "hexmerge/occ/mesh_shape.h"
#include "hexmerge/occ/mesher/lattice.h"
#include "hexmerge/occ/mesher/surface.h"
#include "hexmerge/occ/mesher/sweep.h"

namespace hexmerge::mesher {

/// The size wanted at a point: min(h, size_i + grading * max(0, distance to item i - slack))
/// over the triangles and segments given a local size (world coordinates). The slack is the
/// chord deflection of the triangulation the items come from: points on the curved face itself
/// are that far from its triangles, and get its size.
class SizeField {
 public:
  /// @param[in] h        the target size (the field's largest value)
  /// @param[in] grading  how fast the size grows with the distance (0.5: by half the distance)
  /// @param[in] slack    distances count from this much off the items
  SizeField(double h, double grading, double slack);
  /// A triangle (or a segment: c == b) of size `size` < h.
  void add(const Vec3& a, const Vec3& b, const Vec3& c, double size);
  /// The size wanted at p, in (0, h]; at most `cap` (a caller asking only whether the size is
  /// under `cap` gets the same answer, and the same size where it is, from fewer items). The
  /// first query after add() builds the items' hierarchy (not safe from two threads at once).
  double at(const Vec3& p, double cap = std::numeric_limits<double>::infinity()) const;
  /// No item: the field is h everywhere.
  bool empty() const { return items_.empty(); }
  double h() const { return h_; }
  /// The smallest size of an item (h when none).
  double smallest() const { return smallest_; }
  /// Boxes (lo, hi) outside which the field is at least `size`: per item finer than `size`,
  /// its box grown by (size - its size) / grading plus the slack.
  std::vector<std::array<Vec3, 2>> boxes_below(double size) const;

 private:
  struct Item {
    Vec3 a, b, c;
    double size;
    Vec3 centre;    ///< of a ball holding the item (its box's centre)
    double radius;  ///< of that ball
    Vec3 lo, hi;    ///< its box
  };
  /// A node of the items' bounding-volume hierarchy: the box of its items and their smallest
  /// size, then two children (`first` the left one's index; the right one follows the left's
  /// subtree), or a leaf of `count` items from `first` in order_.
  struct Node {
    Vec3 lo, hi;
    double least;
    int first, count, right;
  };
  void build() const;
  int build(int begin, int end) const;
  double h_, grading_, slack_, smallest_;
  std::vector<Item> items_;
  mutable std::vector<Node> tree_;  // empty: to be built
  mutable std::vector<int> order_;
};

/// The faces and edges given local sizes (0-based), as mesh_shape() applies them.
struct LocalSizeItems {
  std::vector<double> face_size;  ///< per face, its local size (h: none)
  std::vector<double> edge_size;  ///< per edge, its local size (h: none)
};

/// How the face or edge numbers a user gives (1-based, FreeCAD's FaceN and EdgeN of the shape as
/// given) name the shape's items (0-based): each given item may have become several (gluing
/// touching solids splits faces) or one shared with another.
struct ItemNumbering {
  const char* kind = "Face";  ///< "Face" or "Edge", for messages
  std::size_t nb_items = 0;   ///< the shape's items of this kind
  /// per given item (0-based), the shape's items it names
  std::vector<std::vector<int>> to_shape;
  /// The numbering of a shape of `count` items, each given item being itself.
  static ItemNumbering identity(const char* kind, std::size_t count);
  /// The shape's items that given number `number` (1-based) names.
  /// @throws InputError (Entity::Parameter) for a number the shape as given has not, the message
  ///         starting with `parameter` and `what` ("parameter 'local_sizes': local size 0.5:
  ///         Face9 does not exist (the shape has 6 faces, Face1 to Face6)")
  const std::vector<int>& items(int number, const std::string& parameter,
                                const std::string& what) const;
  /// The number (1-based) the shape as given has for the shape's item `item` (gluing touching
  /// solids splits and merges items: the first given item naming it); 0 for none.
  int number_of(int item) const;
};

/// The faces and edges given local sizes (0-based, sizes above h lowered to h: none), checked.
/// @param[in] sizes  the local sizes (numbers as given)
/// @throws InputError (Entity::Parameter) naming the face or edge that does not exist, or a size
///         larger than h or smaller than h / 1000
LocalSizeItems local_size_items(const std::vector<LocalSize>& sizes, const ItemNumbering& faces,
                                const ItemNumbering& edges, double h);

/// Sizes at the CAD's short edges (MeshShapeParameters::feature_size): every edge shorter than
/// 2 `fraction` h gets a local size of its length, at least `fraction` h, where `edge_size` has
/// none finer. Degenerated edges (length 0) get none.
/// @param[in]     edge_length  per edge, its length (0: degenerated)
/// @param[in,out] edge_size    per edge, its local size (h: none)
/// @return the edges given a size
std::size_t add_short_edge_sizes(const std::vector<double>& edge_length, double h, double fraction,
                                 std::vector<double>& edge_size);

/// Sizes at the CAD's narrow faces (with MeshShapeParameters::feature_size on): every face of
/// width w (twice its area over its perimeter) from kNarrowestSizedFace h to kNarrowFaceWidth h
/// gets a local size of kNarrowFaceSizeFactor w, where `face_size` has none finer: its triangles
/// then cross it at about 18 degrees, not as needles of w over h, and the tets on it have no
/// edge of w beside edges of h. Narrower faces lie within half the chord deflection of their
/// neighbours: sized, the boundary left the CAD (a random part's cone sliver 0.003 h wide at
/// h 68: nodes 0.44 mm off it).
/// A face that spans less than kNarrowestSizedFace h across in space is none of them either,
/// whatever its width (KiCad's Valve_Mini_Pentode_Linear: a whole cylinder 0.006 mm across, 3.1
/// mm long, at h 0.94 0.016 mm wide; sized at 0.047, its triangles folded over each other in
/// every way).
/// @param[in]     face_width  per face, its width (Shape::face_width)
/// @param[in]     face_span   per face, how far it spans across (face_spans())
/// @param[in,out] face_size   per face, its local size (h: none)
/// @return the faces given a size
inline constexpr double kNarrowFaceWidth = 0.1;
inline constexpr double kNarrowestSizedFace = 0.01;
inline constexpr double kNarrowFaceSizeFactor = 3;
std::size_t add_narrow_face_sizes(const std::vector<double>& face_width,
                                  const std::vector<double>& face_span, double h,
                                  std::vector<double>& face_size);

/// The feature sizes (MeshShapeParameters::feature_size, `fraction`; 0: none):
/// add_short_edge_sizes() and add_narrow_face_sizes() on `items`.
/// @return the edges and the faces given a size
std::pair<std::size_t, std::size_t> add_feature_sizes(const std::vector<double>& edge_length,
                                                      const std::vector<double>& face_width,
                                                      const std::vector<double>& face_span,
                                                      double h, double fraction,
                                                      LocalSizeItems& items);

/// What the local sizes gave: per entry, the surface's triangles on its faces and segments on its
/// edges, and their longest side (the entries' numbers as given).
std::vector<LocalSizeApplied> local_sizes_applied(const std::vector<LocalSize>& sizes,
                                                  const ItemNumbering& faces,
                                                  const ItemNumbering& edges,
                                                  const Surface& surface);

/// Whether a sweep carries the local sizes: only those on edges of its caps whose walls are no
/// lattice faces (the first plane's sides on those walls are split to the size and repeated on
/// every plane); a face, an edge along the axis or on a lattice wall would need slabs thinner
/// than h or a graded cross-section.
/// @param[in]  edge_faces    per edge of the shape, the faces it bounds
/// @param[in]  lattice_face  per face, whether it is a lattice face (as found, before the local
///                           sizes)
/// @param[out] wall_size     carried: per face, the size its sides are split to (h: none)
/// @return "" when carried, else why not, in one line naming the first item that cannot be
std::string sweep_carries(const std::vector<LocalSize>& sizes, const ItemNumbering& edges,
                          const Sweep& sweep, const std::vector<std::vector<int>>& edge_faces,
                          const std::vector<bool>& lattice_face, double h,
                          std::vector<double>& wall_size);

/// Swept: the first plane's segments are the only ones the surface keeps; an edge of a cap on
/// another plane has copies of those of the first plane's edges on the same walls. Adds them to
/// the entries (of local_sizes_applied()) whose edges have no segment of their own.
void add_swept_segments(std::vector<LocalSizeApplied>& applied, const std::vector<LocalSize>& sizes,
                        const ItemNumbering& edges, const Sweep& sweep,
                        const std::vector<std::vector<int>>& edge_faces, const Surface& surface);

/// The size field of the triangles (world coordinates) of the faces, and the segments of the
/// edges, with a local size below h.
/// @param[in] deflection  the chord deflection of `surface` (the field's slack)
SizeField make_size_field(const Surface& surface, const LocalSizeItems& items, double h,
                          double grading, double deflection);

/// Points of the lattices of spacing lattice.spacing / 2^l (l = 1, 2, ...) filling the graded
/// zone inside the shape (frame coordinates): a point first on level l is placed where the size
/// wanted is below the spacing of level l - 1, at least `clearance` times that size from every
/// face (lattice faces excepted for points on them: those go into the face as face points, with
/// its index in `inserted.face`), from the surface's nodes, the boundary-layer points and the
/// core's points, and out of the core's circumspheres. Appended to `inserted`.
/// @return the number of points placed
std::size_t place_graded_points(const SizeField& field, const Lattice& lattice,
                                const Parity& parity, const Surroundings& around, double clearance,
                                InsertedPoints& inserted);

}  // namespace hexmerge::mesher
