#include "hexmerge/check/check_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/triangle_distance.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/mesh/cell_type.h"

// The checker deliberately shares nothing with the engine beyond the descriptor tables and the
// geometric measures: faces are rebuilt here from the cells alone, so a bug in the engine's
// topology cannot hide itself from the check.

namespace hexmerge {
namespace {

/// Kinds of fault, each with its own budget of problem lines.
enum Kind {
  kMalformed,
  kInverted,
  kOvershared,
  kMismatched,
  kCrack,
  kUnused,
  kMoved,
  kRegion,
  kSource,
  kChanged,
  kNbKinds
};

class ProblemLog {
 public:
  explicit ProblemLog(std::vector<std::string>& lines) : lines_(lines) {}
  void add(Kind kind, const std::string& line) {
    if (counts_[kind]++ < kMaxProblemsPerKind) lines_.push_back(line);
  }
  /// Adds one closing line per kind whose lines were cut.
  void finish() {
    for (int k = 0; k < kNbKinds; ++k) {
      if (counts_[k] > kMaxProblemsPerKind) {
        lines_.push_back("... and " + std::to_string(counts_[k] - kMaxProblemsPerKind) +
                         " more of the same kind");
      }
    }
  }

 private:
  std::vector<std::string>& lines_;
  std::size_t counts_[kNbKinds] = {};
};

/// Sorts the 3 or 4 vertex ids of a face (insertion sort: std::sort on a 4-array trips GCC 12's
/// -Warray-bounds false positive, and this is faster anyway).
void sort_face(index_t* key, int n) {
  for (int i = 1; i < n; ++i) {
    for (int j = i; j > 0 && key[j - 1] > key[j]; --j) std::swap(key[j - 1], key[j]);
  }
}

/// One face of one cell, filed under its smallest vertex; the other vertices sorted, d =
/// NO_VERTEX for a triangle.
struct FaceRecord {
  index_t b, c, d;
  index_t cell;
  std::uint8_t local_face;
  bool operator<(const FaceRecord& o) const {
    if (b != o.b) return b < o.b;
    if (c != o.c) return c < o.c;
    if (d != o.d) return d < o.d;
    return cell < o.cell;
  }
  bool same_key(const FaceRecord& o) const { return b == o.b && c == o.c && d == o.d; }
};

/// All faces of a set of cells, bucketed by smallest vertex (counting sort) and sorted inside
/// each bucket: linear to build, a binary search within one small bucket to query.
class FaceTable {
 public:
  /// `cell_ok(c)` tells which cells to include; `cell_type(c)`, `cell_vertices(c)` describe them.
  template <class Ok, class Type, class Verts>
  FaceTable(index_t nb_vertices, index_t nb_cells, Ok cell_ok, Type cell_type, Verts cell_vertices)
      : start_(static_cast<std::size_t>(nb_vertices) + 1, 0) {
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<index_t> fill;
      if (pass == 1) {
        for (index_t v = 0; v < nb_vertices; ++v) start_[v + 1] += start_[v];
        records_.resize(start_[nb_vertices]);
        fill.assign(start_.begin(), start_.end() - 1);
      }
      for (index_t cell = 0; cell < nb_cells; ++cell) {
        if (!cell_ok(cell)) continue;
        const CellDescriptor& desc = descriptor(cell_type(cell));
        const index_t* verts = cell_vertices(cell);
        for (int f = 0; f < desc.nb_faces; ++f) {
          index_t key[4] = {0, 0, 0, NO_VERTEX};
          const int n = desc.face_size[f];
          for (int i = 0; i < n; ++i) key[i] = verts[desc.face[f][i]];
          sort_face(key, n);
          if (pass == 0) {
            ++start_[key[0] + 1];
          } else {
            records_[fill[key[0]]++] = {key[1], key[2], key[3], cell, static_cast<std::uint8_t>(f)};
          }
        }
      }
    }
    for (index_t v = 0; v < nb_vertices; ++v) {
      std::sort(records_.begin() + start_[v], records_.begin() + start_[v + 1]);
    }
  }

  std::size_t size() const { return records_.size(); }
  const FaceRecord& record(std::size_t i) const { return records_[i]; }
  std::size_t bucket_begin(index_t v) const { return start_[v]; }
  std::size_t bucket_end(index_t v) const { return start_[v + 1]; }

  /// Records [first, last) whose face has exactly the vertices of `key` (unsorted, n = 3 or 4).
  std::pair<std::size_t, std::size_t> find(const index_t* key, int n) const {
    index_t s[4] = {0, 0, 0, NO_VERTEX};
    std::copy(key, key + n, s);
    sort_face(s, n);
    if (s[0] + 1 >= start_.size()) return {0, 0};
    const FaceRecord probe{s[1], s[2], s[3], 0, 0};
    const auto begin = records_.begin() + start_[s[0]];
    const auto end = records_.begin() + start_[s[0] + 1];
    const auto lo = std::lower_bound(begin, end, probe);
    auto hi = lo;
    while (hi != end && hi->same_key(probe)) ++hi;
    return {static_cast<std::size_t>(lo - records_.begin()),
            static_cast<std::size_t>(hi - records_.begin())};
  }

 private:
  std::vector<std::size_t> start_;
  std::vector<FaceRecord> records_;
};

/// Parity of the permutation that sorts a triangle's vertices: the orientation of a triangle
/// as a cyclic sequence, independent of where the cycle starts.
int triangle_parity(const index_t t[3]) {
  return ((t[0] > t[1]) + (t[0] > t[2]) + (t[1] > t[2])) & 1;
}

std::string cell_name(const MixedMesh& mesh, index_t c) {
  return std::string(descriptor(mesh.types[c]).name) + " " + std::to_string(c);
}

std::string join_cells(const MixedMesh& mesh, const FaceTable& table, std::size_t first,
                       std::size_t last) {
  std::string out;
  for (std::size_t i = first; i < last; ++i) {
    out += (i == first ? "" : ", ") + cell_name(mesh, table.record(i).cell);
  }
  return out;
}

std::string face_text(const index_t* f, int n) {
  std::string out = "(";
  for (int i = 0; i < n; ++i) out += (i ? " " : "") + std::to_string(f[i]);
  return out + ")";
}

/// The input's boundary triangles in a uniform grid, each filed in every grid cell its bounding
/// box (grown by `margin`) meets: the distance from a point to the surface, where it is at most
/// `margin`, is found among the triangles of the point's grid cell.
class SurfaceGrid {
 public:
  SurfaceGrid(const TetMesh& input, std::vector<std::array<index_t, 3>> triangles)
      : input_(input), triangles_(std::move(triangles)) {
    if (triangles_.empty()) return;
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const auto& t : triangles_) {
      for (index_t v : t) {
        const double* p = input.point(v);
        lo = {std::min(lo.x, p[0]), std::min(lo.y, p[1]), std::min(lo.z, p[2])};
        hi = {std::max(hi.x, p[0]), std::max(hi.y, p[1]), std::max(hi.z, p[2])};
      }
    }
    margin_ = kBoundaryNodeTolerance * (hi - lo).norm();
    lo_ = lo - Vec3{margin_, margin_, margin_};
    const Vec3 size = hi - lo + Vec3{2 * margin_, 2 * margin_, 2 * margin_};
    // About one triangle per grid cell on a closed surface: n^(2/3) cells along the longest side.
    const double longest = std::max({size.x, size.y, size.z});
    const double per_side = std::max(1.0, std::cbrt(static_cast<double>(triangles_.size())) * 2);
    cell_ = longest > 0 ? longest / per_side : 1.0;
    for (int k = 0; k < 3; ++k) {
      dims_[k] = std::max(1, static_cast<int>(std::ceil((&size.x)[k] / cell_)));
    }
    start_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2] + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::size_t> fill;
      if (pass == 1) {
        for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
        items_.resize(start_.back());
        fill.assign(start_.begin(), start_.end() - 1);
      }
      for (std::size_t t = 0; t < triangles_.size(); ++t) {
        std::array<int, 3> a{}, b{};
        box(t, a, b);
        for (int i = a[0]; i <= b[0]; ++i) {
          for (int j = a[1]; j <= b[1]; ++j) {
            for (int k = a[2]; k <= b[2]; ++k) {
              const std::size_t c = index(i, j, k);
              if (pass == 0) {
                ++start_[c + 1];
              } else {
                items_[fill[c]++] = static_cast<index_t>(t);
              }
            }
          }
        }
      }
    }
  }

  /// Distance from p to the nearest boundary triangle when it is at most the grid's margin
  /// (a fraction kBoundaryNodeTolerance of the surface's bounding-box diagonal), else a larger
  /// value.
  double distance(const Vec3& p) const {
    double best = 1e300;
    if (triangles_.empty()) return best;
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const double x = ((&p.x)[k] - (&lo_.x)[k]) / cell_;
      if (x < 0 || x >= dims_[k]) return best;
      c[k] = std::min(dims_[k] - 1, static_cast<int>(x));
    }
    const std::size_t cell = index(c[0], c[1], c[2]);
    for (std::size_t i = start_[cell]; i < start_[cell + 1]; ++i) {
      const auto& t = triangles_[items_[i]];
      best = std::min(best, squared_distance_to_triangle(p, Vec3::of(input_.point(t[0])),
                                                         Vec3::of(input_.point(t[1])),
                                                         Vec3::of(input_.point(t[2]))));
    }
    return std::sqrt(best);
  }

 private:
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * dims_[1] + j) * dims_[0] + i;
  }
  void box(std::size_t t, std::array<int, 3>& a, std::array<int, 3>& b) const {
    for (int k = 0; k < 3; ++k) {
      double lo = 1e300, hi = -1e300;
      for (index_t v : triangles_[t]) {
        lo = std::min(lo, input_.point(v)[k]);
        hi = std::max(hi, input_.point(v)[k]);
      }
      const auto at = [&](double x) {
        return std::clamp(static_cast<int>((x - (&lo_.x)[k]) / cell_), 0, dims_[k] - 1);
      };
      a[k] = at(lo - margin_);
      b[k] = at(hi + margin_);
    }
  }

  const TetMesh& input_;
  std::vector<std::array<index_t, 3>> triangles_;
  Vec3 lo_{0, 0, 0};
  double margin_ = 0.0, cell_ = 1.0;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::size_t> start_;
  std::vector<index_t> items_;
};
}  // namespace

namespace {

CheckReport check_at_scale(const MixedMesh& mesh, const TetMesh& input) {
  CheckReport report;
  ProblemLog log(report.problems);
  const index_t nc = mesh.nb_cells();
  const index_t nv_out = mesh.nb_vertices();
  const index_t nv_in = input.nb_vertices();
  const index_t nt = input.nb_tets();
  report.nb_cells = nc;

  // --- Cell arrays and per-cell geometry -------------------------------------------------------
  const bool offsets_ok = [&] {
    if (mesh.offsets.size() != static_cast<std::size_t>(nc) + 1 || mesh.offsets[0] != 0) {
      return false;
    }
    for (index_t c = 0; c < nc; ++c) {
      if (mesh.offsets[c + 1] < mesh.offsets[c]) return false;
    }
    return mesh.offsets[nc] == mesh.cell_vertices.size();
  }();
  if (!offsets_ok) {
    report.malformed_cells = nc;
    log.add(kMalformed, "the cell offsets do not describe the cell vertex array (" +
                            std::to_string(mesh.offsets.size()) + " offsets for " +
                            std::to_string(nc) + " cells): nothing else was checked");
    log.finish();
    return report;
  }
  std::vector<char> cell_ok(nc, 0);
  for (index_t c = 0; c < nc; ++c) {
    const int type = static_cast<int>(mesh.types[c]);
    if (type < 0 || type >= NB_CELL_TYPES) {
      ++report.malformed_cells;
      log.add(kMalformed,
              "cell " + std::to_string(c) + " has unknown type " + std::to_string(type));
      continue;
    }
    const CellDescriptor& desc = descriptor(mesh.types[c]);
    const index_t* verts = mesh.cell(c);
    std::string why;
    if (mesh.cell_size(c) != static_cast<index_t>(desc.nb_vertices)) {
      why = "has " + std::to_string(mesh.cell_size(c)) + " vertices instead of " +
            std::to_string(desc.nb_vertices);
    } else {
      for (int i = 0; i < desc.nb_vertices && why.empty(); ++i) {
        if (verts[i] >= nv_out) {
          why = "refers to node " + std::to_string(verts[i]) + ", past the " +
                std::to_string(nv_out) + " nodes";
        }
        for (int j = 0; j < i && why.empty(); ++j) {
          if (verts[i] == verts[j]) why = "uses node " + std::to_string(verts[i]) + " twice";
        }
      }
    }
    if (!why.empty()) {
      ++report.malformed_cells;
      log.add(kMalformed, cell_name(mesh, c) + " " + why);
      continue;
    }
    cell_ok[c] = 1;
    ++report.counts[type];
    const double sj = scaled_jacobian(mesh.types[c], mesh.points.data(), verts);
    if (!(sj > 0.0)) {
      ++report.inverted_cells;
      log.add(kInverted, cell_name(mesh, c) + " is inverted or flat (scaled Jacobian " +
                             std::to_string(sj) + ")");
    }
    if (report.worst_cell == NO_INDEX || sj < report.min_scaled_jacobian) {
      report.min_scaled_jacobian = sj;
      report.worst_cell = c;
    }
    report.output_volume += cell_volume(mesh.types[c], mesh.points.data(), verts);
  }
  if (report.worst_cell == NO_INDEX) report.min_scaled_jacobian = 0.0;

  // --- Declared node changes -------------------------------------------------------------------
  const std::vector<index_t>& declared = mesh.changed_nodes;
  const bool with_changes = !declared.empty();
  report.declared_changed_nodes = declared.size();
  std::vector<char> changed(std::max(nv_out, nv_in), 0);
  for (std::size_t i = 0; i < declared.size(); ++i) {
    const index_t v = declared[i];
    if (v >= changed.size() || (i > 0 && declared[i - 1] >= v)) {
      ++report.off_boundary_nodes;
      log.add(kChanged, "the changed-node list names node " + std::to_string(v) +
                            (v >= changed.size() ? ", past the nodes" : " out of order"));
      continue;
    }
    changed[v] = 1;
  }

  // --- Volumes ---------------------------------------------------------------------------------
  for (index_t t = 0; t < nt; ++t) {
    const index_t* q = input.tet(t);
    if (q[0] < nv_in && q[1] < nv_in && q[2] < nv_in && q[3] < nv_in) {
      report.input_volume +=
          tet_volume(input.point(q[0]), input.point(q[1]), input.point(q[2]), input.point(q[3]));
    }
  }
  if (report.input_volume != 0.0) {
    report.relative_volume_difference =
        (report.output_volume - report.input_volume) / report.input_volume;
  }

  // Per region: a bent quad on a region interface moves volume between materials and leaves
  // the total as it was.
  if (!mesh.regions.empty() && mesh.regions.size() == nc && !input.regions.empty()) {
    std::map<std::int32_t, std::array<double, 2>> volumes;  // region -> (input, output)
    for (index_t t = 0; t < nt; ++t) {
      const index_t* q = input.tet(t);
      if (q[0] < nv_in && q[1] < nv_in && q[2] < nv_in && q[3] < nv_in) {
        volumes[input.region(t)][0] +=
            tet_volume(input.point(q[0]), input.point(q[1]), input.point(q[2]), input.point(q[3]));
      }
    }
    for (index_t c = 0; c < nc; ++c) {
      if (cell_ok[c]) {
        volumes[mesh.region(c)][1] += cell_volume(mesh.types[c], mesh.points.data(), mesh.cell(c));
      }
    }
    for (const auto& [region, v] : volumes) {
      const double difference = v[0] != 0.0 ? std::fabs(v[1] - v[0]) / std::fabs(v[0]) : 1.0;
      if (report.worst_region < 0 || difference > report.max_region_volume_difference) {
        report.max_region_volume_difference = difference;
        report.worst_region = region;
      }
    }
  }

  // --- Nodes -----------------------------------------------------------------------------------
  // Nodes past the input's are allowed when every one of them is declared added.
  const bool added_declared =
      nv_out > nv_in &&
      std::all_of(changed.begin() + nv_in, changed.begin() + nv_out, [](char c) { return c != 0; });
  if (nv_out != nv_in && !added_declared) {
    const index_t diff = nv_out > nv_in ? nv_out - nv_in : nv_in - nv_out;
    report.moved_nodes += diff;
    log.add(kMoved, "the output has " + std::to_string(nv_out) + " nodes, the input " +
                        std::to_string(nv_in));
  }
  for (index_t v = 0; v < std::min(nv_out, nv_in); ++v) {
    if (changed[v]) continue;
    // Bitwise: the output must carry the input's coordinates untouched (even -0.0 vs 0.0).
    if (std::memcmp(&mesh.points[3 * static_cast<std::size_t>(v)], input.point(v),
                    3 * sizeof(double)) != 0) {
      ++report.moved_nodes;
      log.add(kMoved, "node " + std::to_string(v) + " is not at its input coordinates");
    }
  }
  {
    std::vector<char> used_in(nv_in, 0), used_out(nv_out, 0);
    for (index_t t = 0; t < nt; ++t) {
      for (int i = 0; i < 4; ++i) {
        if (input.tet(t)[i] < nv_in) used_in[input.tet(t)[i]] = 1;
      }
    }
    for (index_t c = 0; c < nc; ++c) {
      if (!cell_ok[c]) continue;
      for (index_t i = 0; i < mesh.cell_size(c); ++i) used_out[mesh.cell(c)[i]] = 1;
    }
    for (index_t v = 0; v < nv_in; ++v) {
      if (used_in[v] && !changed[v] && (v >= nv_out || !used_out[v])) {
        ++report.unused_input_nodes;
        log.add(kUnused, "input node " + std::to_string(v) + " is used by no output cell");
      }
    }
  }

  // --- Regions and source tets -----------------------------------------------------------------
  const bool regions_ok = mesh.regions.empty() || mesh.regions.size() == nc;
  if (!regions_ok) {
    ++report.region_mismatches;
    log.add(kRegion, "the region array has " + std::to_string(mesh.regions.size()) +
                         " entries for " + std::to_string(nc) + " cells");
  }
  if (!mesh.source_offsets.empty()) {
    const bool sources_ok = mesh.source_offsets.size() == static_cast<std::size_t>(nc) + 1 &&
                            mesh.source_offsets[0] == 0 &&
                            mesh.source_offsets[nc] == mesh.source_tets.size() &&
                            std::is_sorted(mesh.source_offsets.begin(), mesh.source_offsets.end());
    if (!sources_ok) {
      ++report.source_errors;
      log.add(kSource, "the source offsets do not describe the source tet array");
    } else {
      std::vector<index_t> uses(nt, 0);
      std::vector<index_t> corners;
      for (index_t c = 0; c < nc; ++c) {
        corners.clear();
        bool region_differs = false, ids_ok = true;
        for (index_t k = mesh.source_offsets[c]; k < mesh.source_offsets[c + 1]; ++k) {
          const index_t t = mesh.source_tets[k];
          if (t >= nt) {
            ids_ok = false;
            continue;
          }
          ++uses[t];
          corners.insert(corners.end(), input.tet(t), input.tet(t) + 4);
          if (regions_ok && mesh.region(c) != input.region(t)) region_differs = true;
        }
        if (region_differs) {
          ++report.region_mismatches;
          log.add(kRegion, "cell " + std::to_string(c) + " (region " +
                               std::to_string(mesh.region(c)) +
                               ") is made of tets of another region");
        }
        if (!ids_ok) {
          ++report.source_errors;
          log.add(kSource, "cell " + std::to_string(c) + " names a source tet past the " +
                               std::to_string(nt) + " input tets");
          continue;
        }
        if (!cell_ok[c]) continue;
        std::sort(corners.begin(), corners.end());
        corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
        std::vector<index_t> own(mesh.cell(c), mesh.cell(c) + mesh.cell_size(c));
        std::sort(own.begin(), own.end());
        if (own != corners) {
          ++report.source_errors;
          log.add(kSource, cell_name(mesh, c) + ": its corners are not the corners of its " +
                               std::to_string(mesh.source_offsets[c + 1] - mesh.source_offsets[c]) +
                               " source tets");
        }
      }
      for (index_t t = 0; t < nt; ++t) {
        if (uses[t] != 1) {
          ++report.source_errors;
          log.add(kSource, "input tet " + std::to_string(t) + " is the source of " +
                               std::to_string(uses[t]) + " cells (expected 1)");
        }
      }
    }
  }

  // --- Faces -----------------------------------------------------------------------------------
  const FaceTable faces(
      nv_out, nc, [&](index_t c) { return cell_ok[c] != 0; },
      [&](index_t c) { return mesh.types[c]; }, [&](index_t c) { return mesh.cell(c); });
  const FaceTable input_faces(
      nv_in, nt,
      [&](index_t t) {
        const index_t* q = input.tet(t);
        return q[0] < nv_in && q[1] < nv_in && q[2] < nv_in && q[3] < nv_in;
      },
      [](index_t) { return CellType::Tet; }, [&](index_t t) { return input.tet(t); });
  // With declared changes: the input's boundary surface, and the longest output edge at each node
  // (the scale of the tolerance on a changed node's distance to it).
  std::unique_ptr<SurfaceGrid> surface;
  std::vector<double> longest_edge;
  std::vector<char> on_output_boundary;
  // Nodes next to a declared one in the input (its tets' corners): a face there may be new.
  std::vector<char> near_changed(changed.size(), 0);
  if (with_changes) {
    for (index_t t = 0; t < nt; ++t) {
      const index_t* q = input.tet(t);
      if (!(q[0] < nv_in && q[1] < nv_in && q[2] < nv_in && q[3] < nv_in)) continue;
      if (changed[q[0]] || changed[q[1]] || changed[q[2]] || changed[q[3]]) {
        for (int i = 0; i < 4; ++i) near_changed[q[i]] = 1;
      }
    }
    for (index_t v = nv_in; v < changed.size(); ++v) near_changed[v] = changed[v];
    std::vector<std::array<index_t, 3>> triangles;
    for (index_t v = 0; v < nv_in; ++v) {
      for (std::size_t i = input_faces.bucket_begin(v); i < input_faces.bucket_end(v);) {
        std::size_t j = i + 1;
        while (j < input_faces.bucket_end(v) &&
               input_faces.record(j).same_key(input_faces.record(i))) {
          ++j;
        }
        if (j - i == 1) triangles.push_back({v, input_faces.record(i).b, input_faces.record(i).c});
        i = j;
      }
    }
    surface = std::make_unique<SurfaceGrid>(input, std::move(triangles));
    longest_edge.assign(nv_out, 0.0);
    on_output_boundary.assign(nv_out, 0);
    for (index_t c = 0; c < nc; ++c) {
      if (!cell_ok[c]) continue;
      const CellDescriptor& desc = descriptor(mesh.types[c]);
      for (int e = 0; e < desc.nb_edges; ++e) {
        const index_t u = mesh.cell(c)[desc.edge[e][0]], w = mesh.cell(c)[desc.edge[e][1]];
        const double length = (Vec3::of(&mesh.points[3 * static_cast<std::size_t>(u)]) -
                               Vec3::of(&mesh.points[3 * static_cast<std::size_t>(w)]))
                                  .norm();
        longest_edge[u] = std::max(longest_edge[u], length);
        longest_edge[w] = std::max(longest_edge[w], length);
      }
    }
  }
  auto output_point = [&](index_t v) {
    return Vec3::of(&mesh.points[3 * static_cast<std::size_t>(v)]);
  };
  // An unpaired triangle is on the domain boundary when it is one of the input's boundary
  // triangles, or, when it has a declared node or a node next to one, when its corners and
  // centroid lie on them.
  auto on_domain_boundary = [&](const index_t* tri) {
    if (tri[0] < nv_in && tri[1] < nv_in && tri[2] < nv_in) {
      const auto range = input_faces.find(tri, 3);
      if (range.second - range.first == 1) return true;
    }
    if (!with_changes || !(near_changed[tri[0]] || near_changed[tri[1]] || near_changed[tri[2]])) {
      return false;
    }
    const Vec3 a = output_point(tri[0]), b = output_point(tri[1]), c = output_point(tri[2]);
    const double tolerance =
        kBoundaryNodeTolerance * std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    for (const Vec3& p : {a, b, c, (a + b + c) * (1.0 / 3.0)}) {
      if (surface->distance(p) > tolerance) return false;
    }
    return true;
  };
  auto mark_boundary = [&](const index_t* f, int n) {
    if (!with_changes) return;
    for (int i = 0; i < n; ++i) on_output_boundary[f[i]] = 1;
  };
  // The face's vertices in the cell's outward order.
  auto face_vertices = [&](const FaceRecord& r, index_t out[4]) {
    const CellDescriptor& desc = descriptor(mesh.types[r.cell]);
    for (int i = 0; i < desc.face_size[r.local_face]; ++i) {
      out[i] = mesh.cell(r.cell)[desc.face[r.local_face][i]];
    }
    return desc.face_size[r.local_face];
  };

  enum State : char { kPaired = 0, kOpen = 1, kCovered = 2 };
  std::vector<char> state(faces.size(), kPaired);
  // The diagonal of an unpaired quad on which the domain boundary or other cells' faces cover it
  // (0: corners 0-2, 1: corners 1-3), -1 when none.
  std::vector<signed char> quad_diagonal(faces.size(), -1);
  std::vector<std::size_t> open_quads;
  for (index_t v = 0; v < nv_out; ++v) {
    for (std::size_t i = faces.bucket_begin(v); i < faces.bucket_end(v);) {
      std::size_t j = i + 1;
      while (j < faces.bucket_end(v) && faces.record(j).same_key(faces.record(i))) ++j;
      const FaceRecord& r = faces.record(i);
      const bool quad = r.d != NO_VERTEX;
      if (j - i >= 3) {
        ++report.overshared_faces;
        log.add(kOvershared, "a face is shared by " + std::to_string(j - i) +
                                 " cells: " + join_cells(mesh, faces, i, j));
      } else if (j - i == 2) {
        index_t f0[4], f1[4];
        face_vertices(faces.record(i), f0);
        face_vertices(faces.record(i + 1), f1);
        bool opposite;
        if (quad) {
          // The second quad, walked backwards, must be the first one up to rotation.
          const int k = static_cast<int>(std::find(f1, f1 + 4, f0[0]) - f1);
          opposite = true;
          for (int m = 0; m < 4; ++m) opposite = opposite && f1[(k - m + 4) % 4] == f0[m];
        } else {
          opposite = triangle_parity(f0) != triangle_parity(f1);
        }
        if (!opposite) {
          ++report.mismatched_faces;
          log.add(kMismatched, (quad ? "quad " + face_text(f0, 4) + " of "
                                     : "triangle " + face_text(f0, 3) + " of ") +
                                   join_cells(mesh, faces, i, j) +
                                   (quad ? ": the two cells disagree on the quad or lie on one side"
                                         : ": both cells lie on the same side"));
        }
      } else {
        state[i] = kOpen;
        if (quad) open_quads.push_back(i);
      }
      i = j;
    }
  }
  // Unpaired quads: on the domain boundary, against other cells' faces that cover both of its
  // halves on one diagonal (non-conforming: two triangles, or a triangle and half of another
  // quad, or halves of two quads), or a crack.
  struct Half {
    std::array<index_t, 3> key;
    index_t cell;
    bool operator<(const Half& o) const { return key < o.key; }
  };
  auto sorted_triangle = [](index_t a, index_t b, index_t c) {
    std::array<index_t, 3> k = {a, b, c};
    sort_face(k.data(), 3);
    return k;
  };
  std::vector<Half> halves;  // both triangulations of every unpaired quad
  halves.reserve(4 * open_quads.size());
  for (std::size_t i : open_quads) {
    index_t q[4];
    face_vertices(faces.record(i), q);
    const index_t cell = faces.record(i).cell;
    halves.push_back({sorted_triangle(q[0], q[1], q[2]), cell});
    halves.push_back({sorted_triangle(q[0], q[2], q[3]), cell});
    halves.push_back({sorted_triangle(q[0], q[1], q[3]), cell});
    halves.push_back({sorted_triangle(q[1], q[2], q[3]), cell});
  }
  std::sort(halves.begin(), halves.end());
  // The record of an unpaired triangle of another cell equal to `tri`, faces.size() when the
  // triangle is half of another cell's unpaired quad instead, NO_INDEX-like npos when neither.
  const std::size_t npos = static_cast<std::size_t>(-1);
  auto cover = [&](const index_t* tri, index_t own_cell) -> std::size_t {
    const auto range = faces.find(tri, 3);
    if (range.second - range.first == 1 && state[range.first] != kPaired &&
        faces.record(range.first).cell != own_cell) {
      return range.first;
    }
    const Half probe{sorted_triangle(tri[0], tri[1], tri[2]), 0};
    for (auto it = std::lower_bound(halves.begin(), halves.end(), probe);
         it != halves.end() && it->key == probe.key; ++it) {
      if (it->cell != own_cell) return faces.size();
    }
    return npos;
  };
  for (std::size_t i : open_quads) {
    const FaceRecord& r = faces.record(i);
    index_t q[4];
    face_vertices(r, q);
    bool boundary = false, covered = false;
    // Both diagonals are looked at: when a tet caps the quad, all four of its faces are on the
    // quad's corners and may be unpaired (its far faces halves of other quads); the quad's own
    // cover is then either pair, and neither pair is left open.
    for (int diag = 0; diag < 2 && !boundary; ++diag) {
      const index_t t0[3] = {q[diag], q[diag + 1], q[(diag + 2) % 4]};
      const index_t t1[3] = {q[diag], q[(diag + 2) % 4], q[(diag + 3) % 4]};
      if (on_domain_boundary(t0) && on_domain_boundary(t1)) {
        boundary = !covered;
        if (boundary) {
          mark_boundary(q, 4);
          quad_diagonal[i] = static_cast<signed char>(diag);
        }
        break;
      }
      const std::size_t c0 = cover(t0, r.cell), c1 = cover(t1, r.cell);
      if (c0 != npos && c1 != npos) {
        if (!covered) quad_diagonal[i] = static_cast<signed char>(diag);
        covered = true;
        if (c0 < faces.size()) state[c0] = kCovered;
        if (c1 < faces.size()) state[c1] = kCovered;
      }
    }
    if (covered) {
      ++report.nonconforming_quads;
    } else if (!boundary) {
      ++report.cracks;
      log.add(kCrack, "quad " + face_text(q, 4) + " of " + cell_name(mesh, r.cell) +
                          " has no neighbour and is not on the domain boundary (crack)");
    }
  }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceRecord& r = faces.record(i);
    if (state[i] != kOpen || r.d != NO_VERTEX) continue;
    index_t t[4];
    face_vertices(r, t);
    if (!on_domain_boundary(t)) {
      ++report.cracks;
      log.add(kCrack, "triangle " + face_text(t, 3) + " of " + cell_name(mesh, r.cell) +
                          " has no neighbour and is not on the domain boundary (crack)");
    } else {
      mark_boundary(t, 3);
    }
  }
  // Every declared node on the output's boundary lies on the input's boundary surface.
  for (index_t v : declared) {
    if (v >= nv_out || !on_output_boundary[v]) continue;
    const double distance = surface->distance(output_point(v));
    if (distance > kBoundaryNodeTolerance * longest_edge[v]) {
      ++report.off_boundary_nodes;
      log.add(kChanged, "changed node " + std::to_string(v) +
                            " is on the boundary but off the input's boundary surface");
    }
  }
  // With declared changes: every region's volume with every quad face split into two triangles
  // (a shared quad on the same diagonal for both cells, an unpaired one on the triangles that
  // cover it), by the divergence theorem over the faces. The bending of quads, which is the
  // same with or without changed nodes, then does not count: what is measured is whether the
  // cells still tile the input's domain, region by region.
  if (with_changes) {
    const bool by_region =
        !mesh.regions.empty() && mesh.regions.size() == nc && !input.regions.empty();
    std::map<std::int32_t, std::array<double, 2>> volumes;  // region -> (input, output)
    for (index_t t = 0; t < nt; ++t) {
      const index_t* q = input.tet(t);
      if (q[0] < nv_in && q[1] < nv_in && q[2] < nv_in && q[3] < nv_in) {
        volumes[by_region ? input.region(t) : 0][0] +=
            tet_volume(input.point(q[0]), input.point(q[1]), input.point(q[2]), input.point(q[3]));
      }
    }
    const Vec3 origin = nv_in > 0 ? Vec3::of(input.point(0)) : Vec3{0.0, 0.0, 0.0};
    const auto six_volume = [&](index_t a, index_t b, index_t c) {
      return det3(output_point(a) - origin, output_point(b) - origin, output_point(c) - origin);
    };
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const FaceRecord& r = faces.record(i);
      index_t f[4];
      double six = 0.0;
      if (face_vertices(r, f) == 3) {
        six = six_volume(f[0], f[1], f[2]);
      } else {
        int d = quad_diagonal[i];
        if (d < 0) {
          // A quad two cells share: split as the input's tets are, where both triangles of one
          // diagonal are faces of them (no flip or contraction changes a face between two
          // regions, and a bent quad there, split the other way, moved its bend's volume from
          // one region to the other: a glued assembly's interfaces), else through its least
          // corner (the same for both cells).
          const auto input_split = [&](int k) {
            const index_t t0[3] = {f[k], f[k + 1], f[(k + 2) % 4]};
            const index_t t1[3] = {f[k], f[(k + 2) % 4], f[(k + 3) % 4]};
            for (const index_t* t : {t0, t1}) {
              if (t[0] >= nv_in || t[1] >= nv_in || t[2] >= nv_in) return false;
              const auto range = input_faces.find(t, 3);
              if (range.first == range.second) return false;
            }
            return true;
          };
          const bool first = input_split(0), second = input_split(1);
          d = first != second ? (first ? 0 : 1)
                              : static_cast<int>(std::min_element(f, f + 4) - f) % 2;
        }
        six = six_volume(f[d], f[d + 1], f[(d + 2) % 4]) +
              six_volume(f[d], f[(d + 2) % 4], f[(d + 3) % 4]);
      }
      volumes[by_region ? mesh.region(r.cell) : 0][1] += six / 6.0;
    }
    std::int32_t worst = 0;
    for (const auto& [region, v] : volumes) {
      const double difference =
          v[0] != 0.0 ? std::fabs(v[1] - v[0]) / std::fabs(v[0]) : (v[1] != 0.0 ? 1.0 : 0.0);
      if (difference >= report.linear_volume_difference) {
        report.linear_volume_difference = difference;
        worst = region;
      }
    }
    if (report.linear_volume_difference > kChangedVolumeTolerance) {
      report.volume_not_kept = 1;
      log.add(kChanged, "with changed nodes the volume is not kept: " +
                            (by_region ? "region " + std::to_string(worst) + " " : std::string()) +
                            "differs by " + std::to_string(report.linear_volume_difference) +
                            " of its volume (allowed " + std::to_string(kChangedVolumeTolerance) +
                            ")");
    }
  }
  log.finish();
  return report;
}

}  // namespace

CheckReport check_mesh(const MixedMesh& mesh, const TetMesh& input) {
  const int exponent = normalising_exponent(input.points);
  if (exponent == 0) return check_at_scale(mesh, input);
  // Both meshes scaled by the same power of two: exact, so equal coordinates stay equal.
  MixedMesh scaled_mesh = mesh;
  TetMesh scaled_input = input;
  for (double& c : scaled_mesh.points) c = std::ldexp(c, exponent);
  for (double& c : scaled_input.points) c = std::ldexp(c, exponent);
  CheckReport report = check_at_scale(scaled_mesh, scaled_input);
  report.input_volume = std::ldexp(report.input_volume, -3 * exponent);
  report.output_volume = std::ldexp(report.output_volume, -3 * exponent);
  return report;
}

}  // namespace hexmerge
