#include "hexmerge/occ/mesher/local_size.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parameter_table.h"
#include "hexmerge/occ/mesher/common.h"

namespace hexmerge::mesher {
namespace {

// Squared distance from p to segment ab.
double squared_distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = ab.dot(ab);
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  const Vec3 d = p - (a + ab * t);
  return d.dot(d);
}

// Items per leaf of the size field's hierarchy.
constexpr int kLeaf = 8;
// Levels of finer lattices at most (spacing h / 2^10): a local size below h / 1024 is refused
// before (mesh_shape's validation), so this is never reached for a valid one.
constexpr int kMaxLevels = 10;
// The finer lattices are scanned in blocks of kBlock^3 points near the items.
constexpr long kBlock = 8;
// The smallest local size, as a fraction of h (finer lattices down to h / 1024).
constexpr double kSmallestLocalSize = 1e-3;

// Per shape item, whether one of the given numbers names it.
std::vector<char> named(const std::vector<int>& numbers, const ItemNumbering& numbering) {
  std::vector<char> out(numbering.nb_items, 0);
  for (const int n : numbers)
    for (const int i : numbering.to_shape[static_cast<std::size_t>(n - 1)])
      out[static_cast<std::size_t>(i)] = 1;
  return out;
}

// Counts one triangle or segment (`nb` ends, closed when 3) on a local size's items, with its
// longest side.
void tally(LocalSizeApplied& applied, std::size_t& count, const std::vector<Vec3>& nodes,
           const int* ends, int nb) {
  ++count;
  for (int c = 0; c < (nb == 3 ? 3 : 1); ++c)
    applied.max_side =
        std::max(applied.max_side, (nodes[ends[c]] - nodes[ends[(c + 1) % nb]]).norm());
}

}  // namespace

ItemNumbering ItemNumbering::identity(const char* kind, std::size_t count) {
  ItemNumbering out;
  out.kind = kind;
  out.nb_items = count;
  out.to_shape.resize(count);
  for (std::size_t i = 0; i < count; ++i) out.to_shape[i] = {static_cast<int>(i)};
  return out;
}

int ItemNumbering::number_of(int item) const {
  for (std::size_t g = 0; g < to_shape.size(); ++g) {
    const std::vector<int>& to = to_shape[g];
    if (std::find(to.begin(), to.end(), item) != to.end()) return static_cast<int>(g) + 1;
  }
  return 0;
}

const std::vector<int>& ItemNumbering::items(int number, const std::string& parameter,
                                             const std::string& what) const {
  if (number < 1 || static_cast<std::size_t>(number) > to_shape.size()) {
    std::string lower = kind;
    lower[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(lower[0])));
    const std::string count = std::to_string(to_shape.size());
    throw InputError("parameter '" + parameter + "': " + what + ": " + kind +
                         std::to_string(number) + " does not exist (the shape has " + count + " " +
                         lower + "s, " + kind + "1 to " + kind + count + ")",
                     Entity::Parameter);
  }
  const std::vector<int>& out = to_shape[static_cast<std::size_t>(number - 1)];
  if (out.empty())
    throw InputError("parameter '" + parameter + "': " + what + ": " + kind +
                         std::to_string(number) +
                         " of the shape as given is gone from the shape whose touching solids "
                         "were glued (it lay inside another solid?)",
                     Entity::Parameter);
  return out;
}

LocalSizeItems local_size_items(const std::vector<LocalSize>& sizes, const ItemNumbering& faces,
                                const ItemNumbering& edges, double h) {
  LocalSizeItems items;
  items.face_size.assign(faces.nb_items, h);
  items.edge_size.assign(edges.nb_items, h);
  const auto fail = [&](const std::string& why) {
    throw InputError("parameter 'local_sizes': " + why, Entity::Parameter);
  };
  // One kind of item: every number checked, its items given the size.
  const auto apply = [](const std::vector<int>& numbers, const ItemNumbering& numbering,
                        const std::string& what, double size, std::vector<double>& item_size) {
    for (const int n : numbers)
      for (const int i : numbering.items(n, "local_sizes", what))
        item_size[static_cast<std::size_t>(i)] =
            std::min(item_size[static_cast<std::size_t>(i)], size);
  };
  for (const LocalSize& local : sizes) {
    const std::string what = "local size " + parameter_number_text(local.size);
    if (local.size > h)
      fail(what + " is larger than the size " + parameter_number_text(h) +
           ": local sizes refine, give one of at most the size");
    if (local.size < kSmallestLocalSize * h)
      fail(what + " is smaller than the size / 1000 (" +
           parameter_number_text(kSmallestLocalSize * h) + ")");
    apply(local.faces, faces, what, local.size, items.face_size);
    apply(local.edges, edges, what, local.size, items.edge_size);
  }
  return items;
}

std::size_t add_short_edge_sizes(const std::vector<double>& edge_length, double h, double fraction,
                                 std::vector<double>& edge_size) {
  std::size_t added = 0;
  for (std::size_t e = 0; e < edge_length.size(); ++e) {
    const double length = edge_length[e];
    if (length <= 0 || length >= 2 * fraction * h) continue;
    const double size = std::max(length, fraction * h);
    if (size < edge_size[e]) {
      edge_size[e] = size;
      ++added;
    }
  }
  return added;
}

std::size_t add_narrow_face_sizes(const std::vector<double>& face_width,
                                  const std::vector<double>& face_span, double h,
                                  std::vector<double>& face_size) {
  std::size_t added = 0;
  for (std::size_t f = 0; f < face_width.size(); ++f) {
    const double width = face_width[f];
    if (!(width >= kNarrowestSizedFace * h) || width >= kNarrowFaceWidth * h) continue;
    if (!(face_span[f] >= kNarrowestSizedFace * h)) continue;
    const double size = kNarrowFaceSizeFactor * width;
    if (size < face_size[f]) {
      face_size[f] = size;
      ++added;
    }
  }
  return added;
}

std::pair<std::size_t, std::size_t> add_feature_sizes(const std::vector<double>& edge_length,
                                                      const std::vector<double>& face_width,
                                                      const std::vector<double>& face_span,
                                                      double h, double fraction,
                                                      LocalSizeItems& items) {
  const std::size_t edges = add_short_edge_sizes(edge_length, h, fraction, items.edge_size);
  return {edges,
          fraction > 0 ? add_narrow_face_sizes(face_width, face_span, h, items.face_size) : 0};
}

std::vector<LocalSizeApplied> local_sizes_applied(const std::vector<LocalSize>& sizes,
                                                  const ItemNumbering& faces,
                                                  const ItemNumbering& edges,
                                                  const Surface& surface) {
  std::vector<LocalSizeApplied> out;
  for (const LocalSize& local : sizes) {
    LocalSizeApplied applied{local.faces, local.edges, local.size, 0, 0, 0.0};
    const std::vector<char> on_face = named(local.faces, faces);
    const std::vector<char> on_edge = named(local.edges, edges);
    for (const SurfaceTriangle& t : surface.triangles)
      if (on_face[static_cast<std::size_t>(t.face)])
        tally(applied, applied.nb_triangles, surface.nodes, t.node.data(), 3);
    for (const auto& [key, segment] : surface.segments)
      if (on_edge[static_cast<std::size_t>(segment.edge)]) {
        const int ends[2] = {pair_lo(key), pair_hi(key)};
        tally(applied, applied.nb_segments, surface.nodes, ends, 2);
      }
    out.push_back(applied);
  }
  return out;
}

SizeField::SizeField(double h, double grading, double slack)
    : h_(h), grading_(grading), slack_(slack), smallest_(h) {}

void SizeField::add(const Vec3& a, const Vec3& b, const Vec3& c, double size) {
  const Vec3 lo = vmin(a, vmin(b, c)), hi = vmax(a, vmax(b, c));
  const Vec3 centre = (lo + hi) * 0.5;
  items_.push_back({a, b, c, size, centre, (hi - centre).norm(), lo, hi});
  smallest_ = std::min(smallest_, size);
  tree_.clear();
}

// The hierarchy: the items split at the median of their centres along the longest side of the
// centres' box, down to kLeaf items per leaf.
void SizeField::build() const {
  order_.resize(items_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  tree_.reserve(2 * items_.size() / kLeaf + 1);
  build(0, static_cast<int>(items_.size()));
}

int SizeField::build(int begin, int end) const {
  const int at = static_cast<int>(tree_.size());
  tree_.push_back({});
  const Item& first = items_[static_cast<std::size_t>(order_[static_cast<std::size_t>(begin)])];
  Node node{first.lo, first.hi, h_, begin, end - begin, -1};
  Vec3 centre_lo = first.centre, centre_hi = first.centre;
  for (int k = begin; k < end; ++k) {
    const Item& it = items_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])];
    node.lo = vmin(node.lo, it.lo), node.hi = vmax(node.hi, it.hi);
    node.least = std::min(node.least, it.size);
    centre_lo = vmin(centre_lo, it.centre), centre_hi = vmax(centre_hi, it.centre);
  }
  if (end - begin > kLeaf) {
    const Vec3 extent = centre_hi - centre_lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                     : extent.y >= extent.z                       ? 1
                                                                  : 2;
    const int middle = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                     [&](int a, int b) {
                       return coord(items_[static_cast<std::size_t>(a)].centre, axis) <
                              coord(items_[static_cast<std::size_t>(b)].centre, axis);
                     });
    node.count = 0;
    node.first = build(begin, middle);
    node.right = build(middle, end);
  }
  tree_[static_cast<std::size_t>(at)] = node;
  return at;
}

double SizeField::at(const Vec3& p, double cap) const {
  double best = std::min(h_, cap);
  if (items_.empty() || best <= smallest_) return best;
  if (tree_.empty()) build();
  // No item below a node can give less than its smallest size plus the grading times the
  // distance to its box (less the slack), nor an item less than its size plus the grading times
  // the distance to its ball: such nodes and items are not measured (a margin of 1e-9 of h
  // against rounding in the bound). The nearer child first.
  const auto bound = [&](const Node& n) {
    const Vec3 d = vmax(vmax(n.lo - p, p - n.hi), Vec3{0, 0, 0});
    return n.least + grading_ * std::max(0.0, d.norm() - slack_);
  };
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = tree_[static_cast<std::size_t>(stack[--top])];
    if (bound(n) > best + 1e-9 * h_) continue;
    if (n.count == 0) {
      const double left = bound(tree_[static_cast<std::size_t>(n.first)]);
      const double right = bound(tree_[static_cast<std::size_t>(n.right)]);
      if (left <= right) {
        stack[top++] = n.right, stack[top++] = n.first;
      } else {
        stack[top++] = n.first, stack[top++] = n.right;
      }
      continue;
    }
    for (int k = n.first; k < n.first + n.count; ++k) {
      const Item& it = items_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])];
      const double least = std::max(0.0, (p - it.centre).norm() - it.radius - slack_);
      if (it.size + grading_ * least > best + 1e-9 * h_) continue;
      const double d2 = it.b.x == it.c.x && it.b.y == it.c.y && it.b.z == it.c.z
                            ? squared_distance_to_segment(p, it.a, it.b)
                            : squared_distance_to_triangle(p, it.a, it.b, it.c);
      best = std::min(best, it.size + grading_ * std::max(0.0, std::sqrt(d2) - slack_));
    }
  }
  return best;
}

std::vector<std::array<Vec3, 2>> SizeField::boxes_below(double size) const {
  std::vector<std::array<Vec3, 2>> boxes;
  for (const Item& it : items_) {
    if (it.size >= size) continue;
    const double reach = (size - it.size) / grading_ + slack_;
    const Vec3 r{reach, reach, reach};
    boxes.push_back({vmin(it.a, vmin(it.b, it.c)) - r, vmax(it.a, vmax(it.b, it.c)) + r});
  }
  return boxes;
}

std::string sweep_carries(const std::vector<LocalSize>& sizes, const ItemNumbering& edges,
                          const Sweep& sweep, const std::vector<std::vector<int>>& edge_faces,
                          const std::vector<bool>& lattice_face, double h,
                          std::vector<double>& wall_size) {
  wall_size.assign(lattice_face.size(), h);
  for (const LocalSize& local : sizes) {
    if (local.size >= h) continue;
    const std::string what = "the local size " + parameter_number_text(local.size) + " on ";
    if (!local.faces.empty())
      return what + "Face" + std::to_string(local.faces[0]) +
             " (a face) needs a graded surface, which the sweep's slabs (h thick along its axis) "
             "and repeated cross-section cannot carry (local sizes on its caps' edges are swept)";
    for (const int number : local.edges)
      for (const int e : edges.items(number, "local_sizes", what)) {
        bool on_cap = false;
        for (const int f : edge_faces[static_cast<std::size_t>(e)])
          on_cap = on_cap || sweep.cap[static_cast<std::size_t>(f)] >= 0;
        const std::string edge = what + "Edge" + std::to_string(number);
        if (!on_cap) return edge + " (an edge along the sweep's axis) needs slabs thinner than h";
        for (const int f : edge_faces[static_cast<std::size_t>(e)]) {
          if (sweep.cap[static_cast<std::size_t>(f)] >= 0) continue;
          if (lattice_face[static_cast<std::size_t>(f)])
            return edge +
                   " lies on a wall on a lattice plane, whose lattice points the sweep keeps";
          wall_size[static_cast<std::size_t>(f)] =
              std::min(wall_size[static_cast<std::size_t>(f)], local.size);
        }
      }
  }
  return "";
}

void add_swept_segments(std::vector<LocalSizeApplied>& applied, const std::vector<LocalSize>& sizes,
                        const ItemNumbering& edges, const Sweep& sweep,
                        const std::vector<std::vector<int>>& edge_faces, const Surface& surface) {
  std::vector<char> has_segments(edges.nb_items, 0);
  for (const auto& [key, segment] : surface.segments)
    has_segments[static_cast<std::size_t>(segment.edge)] = 1;
  const auto is_wall_of = [&](int e, int wall) {
    const std::vector<int>& faces = edge_faces[static_cast<std::size_t>(e)];
    return std::find(faces.begin(), faces.end(), wall) != faces.end();
  };
  for (std::size_t k = 0; k < sizes.size() && k < applied.size(); ++k)
    for (const int number : sizes[k].edges)
      for (const int e : edges.to_shape[static_cast<std::size_t>(number - 1)]) {
        if (has_segments[static_cast<std::size_t>(e)]) continue;
        for (const int wall : edge_faces[static_cast<std::size_t>(e)]) {
          if (sweep.cap[static_cast<std::size_t>(wall)] >= 0) continue;
          for (const auto& [key, segment] : surface.segments)
            if (is_wall_of(segment.edge, wall)) {
              const int ends[2] = {pair_lo(key), pair_hi(key)};
              tally(applied[k], applied[k].nb_segments, surface.nodes, ends, 2);
            }
        }
      }
}

SizeField make_size_field(const Surface& surface, const LocalSizeItems& items, double h,
                          double grading, double deflection) {
  SizeField field(h, grading, deflection);
  for (const SurfaceTriangle& t : surface.triangles) {
    const double size = items.face_size[t.face];
    if (size < h)
      field.add(surface.nodes[t.node[0]], surface.nodes[t.node[1]], surface.nodes[t.node[2]], size);
  }
  for (const auto& [key, segment] : surface.segments) {
    const double size = items.edge_size[segment.edge];
    if (size >= h) continue;
    const Vec3& a = surface.nodes[pair_lo(key)];
    const Vec3& b = surface.nodes[pair_hi(key)];
    field.add(a, b, b, size);
  }
  return field;
}

std::size_t place_graded_points(const SizeField& field, const Lattice& lattice,
                                const Parity& parity, const Surroundings& around, double clearance,
                                InsertedPoints& inserted) {
  if (field.empty()) return 0;
  const double h = field.h();
  const int levels =
      std::min(kMaxLevels, static_cast<int>(std::ceil(std::log2(h / field.smallest() - 1e-9))));
  std::size_t placed = 0;
  PointSet graded(around.box_lo, around.box_hi, h);
  for (int level = 1; level <= levels; ++level) {
    const long scale = 1L << level;
    // The size below which a point of this level is wanted: the spacing of the level before.
    const double wanted_below = h / static_cast<double>(scale / 2);
    // Only the level's points near the items finer than that can be wanted: the blocks of
    // kBlock^3 points that their boxes touch, scanned in the order of a scan of the whole box
    // (z, then y, then x), since each point placed keeps later ones away.
    long last[3];
    for (int a = 0; a < 3; ++a) last[a] = static_cast<long>(lattice.cells[a]) * scale;
    std::vector<std::array<long, 3>> blocks;  // (z, y, x) block indices
    for (const std::array<Vec3, 2>& box : field.boxes_below(wanted_below)) {
      Vec3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
              std::numeric_limits<double>::max()};
      Vec3 hi = lo * -1.0;
      for (int corner = 0; corner < 8; ++corner) {
        const Vec3 q = lattice.frame.to_frame({corner & 1 ? box[1].x : box[0].x,
                                               corner & 2 ? box[1].y : box[0].y,
                                               corner & 4 ? box[1].z : box[0].z});
        lo = vmin(lo, q), hi = vmax(hi, q);
      }
      long from[3], to[3];
      for (int a = 0; a < 3; ++a) {
        // The level's points: each cell of the lattice cut into `scale` along each axis.
        from[a] = std::max(0L, static_cast<long>(std::floor(lattice.cells_at(a, coord(lo, a)) *
                                                            static_cast<double>(scale))));
        to[a] = std::min(last[a], static_cast<long>(std::ceil(lattice.cells_at(a, coord(hi, a)) *
                                                              static_cast<double>(scale))));
      }
      if (from[0] > to[0] || from[1] > to[1] || from[2] > to[2]) continue;
      for (long kb = from[2] / kBlock; kb <= to[2] / kBlock; ++kb)
        for (long jb = from[1] / kBlock; jb <= to[1] / kBlock; ++jb)
          for (long ib = from[0] / kBlock; ib <= to[0] / kBlock; ++ib)
            blocks.push_back({kb, jb, ib});
    }
    std::sort(blocks.begin(), blocks.end());
    blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
    // The surface's crossings of the line through the last row asked (j, k): the points of a
    // row share it, and the scan goes row by row.
    long row_j = -1, row_k = -1;
    std::vector<double> row_crossings;
    const auto inside = [&](const Vec3& q, long j, long k) {
      if (j != row_j || k != row_k)
        row_crossings = parity.crossings(q.y, q.z), row_j = j, row_k = k;
      return Parity::inside_given(row_crossings, q.x);
    };
    const auto visit = [&](long i, long j, long k) {
      if (i % 2 == 0 && j % 2 == 0 && k % 2 == 0) return;  // a coarser level's point
      const long ijk[3] = {i, j, k};
      Vec3 q{};
      for (int a = 0; a < 3; ++a)
        set_coord(q, a, lattice.at(a, static_cast<double>(ijk[a]) / static_cast<double>(scale)));
      const double size = field.at(lattice.frame.to_world(q), wanted_below);
      if (size >= wanted_below) return;
      const double room = clearance * size;
      // On a lattice plane, it may lie in a lattice face: then it is one of its points.
      int index[3] = {-1, -1, -1};
      for (int a = 0; a < 3; ++a)
        if (ijk[a] % scale == 0) index[a] = static_cast<int>(ijk[a] / scale);
      const int face = around.on_lattice_face(q, index);
      // (The curved faces' triangles are some of every face's: clear of these, clear of those.)
      if (face < 0 ? around.every_face.any_within(q, room) : around.curved.any_within(q, room))
        return;
      if (around.surface_points.any_within(q, room) || around.layer_points.any_within(q, room) ||
          around.core_points.any_within(q, room) || around.core_balls.holds(q, 0.05 * size) ||
          around.buffer_cells.near(q, room) || graded.any_within(q, 0.5 * room))
        return;
      if (face < 0 && !inside(q, j, k)) return;  // the costliest test last
      graded.add(q);
      inserted.points.push_back(q);
      inserted.face.push_back(face);
      ++placed;
    };
    // Per block layer (same z block), per point layer k; per block row (same y block) in it,
    // per point row j; the row's blocks in x order.
    for (std::size_t layer = 0; layer < blocks.size();) {
      std::size_t layer_end = layer;
      while (layer_end < blocks.size() && blocks[layer_end][0] == blocks[layer][0]) ++layer_end;
      const long kb = blocks[layer][0];
      for (long k = kb * kBlock; k < (kb + 1) * kBlock && k <= last[2]; ++k)
        for (std::size_t row = layer; row < layer_end;) {
          std::size_t row_end = row;
          while (row_end < layer_end && blocks[row_end][1] == blocks[row][1]) ++row_end;
          const long jb = blocks[row][1];
          for (long j = jb * kBlock; j < (jb + 1) * kBlock && j <= last[1]; ++j)
            for (std::size_t b = row; b < row_end; ++b)
              for (long i = blocks[b][2] * kBlock; i < (blocks[b][2] + 1) * kBlock && i <= last[0];
                   ++i)
                visit(i, j, k);
          row = row_end;
        }
      layer = layer_end;
    }
  }
  return placed;
}

}  // namespace hexmerge::mesher
