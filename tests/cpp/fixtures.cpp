#include "fixtures.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/geometry/vec3.h"
#include "hexmerge/tetgen/tetrahedralize.h"

namespace hexmerge::test {
namespace {

Vec3 vec(const Point& p) { return {p[0], p[1], p[2]}; }

double six_volume(const std::vector<Point>& pts, const Tet& t) {
  const Vec3 a = vec(pts[t[0]]);
  return det3(vec(pts[t[1]]) - a, vec(pts[t[2]]) - a, vec(pts[t[3]]) - a);
}

/// The four faces of a tet as vertex triples (any orientation).
std::array<std::array<index_t, 3>, 4> tet_faces(const Tet& t) {
  return {{{t[1], t[2], t[3]}, {t[0], t[2], t[3]}, {t[0], t[1], t[3]}, {t[0], t[1], t[2]}}};
}

std::array<index_t, 3> sorted(std::array<index_t, 3> f) {
  std::sort(f.begin(), f.end());
  return f;
}

/// True when the triangle lies on the boundary of the convex hull of `pts`.
bool on_hull(const std::vector<Point>& pts, const std::array<index_t, 3>& f) {
  const Vec3 a = vec(pts[f[0]]);
  const Vec3 n = (vec(pts[f[1]]) - a).cross(vec(pts[f[2]]) - a);
  bool pos = false, neg = false;
  for (const Point& p : pts) {
    const double s = n.dot(vec(p) - a);
    pos = pos || s > 0.0;
    neg = neg || s < 0.0;
  }
  return !(pos && neg);
}

bool coplanar(const std::vector<Point>& pts, const std::array<index_t, 3>& f,
              const std::array<index_t, 3>& g) {
  const Vec3 a = vec(pts[f[0]]);
  const Vec3 n = (vec(pts[f[1]]) - a).cross(vec(pts[f[2]]) - a);
  for (index_t v : g) {
    if (n.dot(vec(pts[v]) - a) != 0.0) return false;
  }
  return true;
}

/// Exact for small integer coordinates: the interiors of two tets are disjoint iff one of
/// their face normals or one cross product of an edge of each is a separating axis.
bool interiors_disjoint(const std::vector<Point>& pts, const Tet& s, const Tet& t) {
  std::vector<Vec3> axes;
  auto add_normals = [&](const Tet& q) {
    for (const auto& f : tet_faces(q)) {
      const Vec3 a = vec(pts[f[0]]);
      axes.push_back((vec(pts[f[1]]) - a).cross(vec(pts[f[2]]) - a));
    }
  };
  add_normals(s);
  add_normals(t);
  const int edges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (const auto& e : edges) {
    for (const auto& g : edges) {
      const Vec3 u = vec(pts[s[e[1]]]) - vec(pts[s[e[0]]]);
      const Vec3 w = vec(pts[t[g[1]]]) - vec(pts[t[g[0]]]);
      axes.push_back(u.cross(w));
    }
  }
  for (const Vec3& axis : axes) {
    if (axis.dot(axis) == 0.0) continue;
    double smin = 1e300, smax = -1e300, tmin = 1e300, tmax = -1e300;
    for (int i = 0; i < 4; ++i) {
      const double ps = axis.dot(vec(pts[s[i]])), pt = axis.dot(vec(pts[t[i]]));
      smin = std::min(smin, ps);
      smax = std::max(smax, ps);
      tmin = std::min(tmin, pt);
      tmax = std::max(tmax, pt);
    }
    if (smax <= tmin || tmax <= smin) return true;
  }
  return false;
}

/// Every face of the set either on the hull or shared by exactly one other tet of the set.
bool face_to_face(const std::vector<Point>& pts, const std::vector<Tet>& tets) {
  std::map<std::array<index_t, 3>, int> count;
  for (const Tet& t : tets) {
    for (const auto& f : tet_faces(t)) ++count[sorted(f)];
  }
  for (const auto& [face, n] : count) {
    if (on_hull(pts, face) ? n != 1 : n != 2) return false;
  }
  return true;
}

double polytope_six_volume(const Polytope& polytope) {
  if (polytope.name == "cube") return 6.0;
  if (polytope.name == "prism") return 3.0;
  if (polytope.name == "pyramid") return 8.0;
  throw std::logic_error("unknown polytope " + polytope.name);
}

}  // namespace

void add_tet(TetMesh& mesh, index_t a, index_t b, index_t c, index_t d) {
  if (tet_volume(mesh.point(a), mesh.point(b), mesh.point(c), mesh.point(d)) < 0) std::swap(c, d);
  mesh.tets.insert(mesh.tets.end(), {a, b, c, d});
}

double min_quality(const TetMesh& mesh) {
  double q = 1;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    q = std::min(q, scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)));
  }
  return q;
}

std::size_t count_below(const TetMesh& mesh, double quality) {
  std::size_t n = 0;
  for (index_t t = 0; t < mesh.nb_tets(); ++t)
    n += scaled_jacobian(CellType::Tet, mesh.points.data(), mesh.tet(t)) < quality;
  return n;
}

TetMesh tetgen_mesh(const std::vector<Point>& points) {
  std::optional<tetgen::Tetrahedralizer> tetgen;
  try {
    tetgen.emplace(tetgen::TetrahedralizeParameters{});  // the tetgen program on the PATH
  } catch (const InputError&) {
    return {};  // not installed: the callers skip
  }
  tetgen::TetrahedralizeInput input;  // no facets: the Delaunay tetrahedralisation
  for (const Point& p : points) input.points.push_back({p[0], p[1], p[2]});
  const tetgen::TetrahedralizeOutput out = tetgen->run(std::move(input));
  if (out.points.size() != 3 * points.size()) throw std::runtime_error("TetGen added points");
  std::vector<Tet> tets(out.tets.size() / 4);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) tets[t][k] = out.tets[4 * t + k];
  }
  TetMesh mesh = make_tet_mesh(points, tets);  // the points exactly as given
  orient_positively(mesh);
  return mesh;
}

TetMesh tetgen_lattice(int n, double jitter, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<Point> points;
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) points.push_back({i + u(rng), j + u(rng), k + u(rng)});
    }
  }
  return tetgen_mesh(points);
}

TetMesh make_tet_mesh(const std::vector<Point>& points, const std::vector<Tet>& tets,
                      const std::vector<std::int32_t>& regions) {
  TetMesh mesh;
  for (const Point& p : points) mesh.points.insert(mesh.points.end(), p.begin(), p.end());
  for (const Tet& t : tets) mesh.tets.insert(mesh.tets.end(), t.begin(), t.end());
  mesh.regions = regions;
  return mesh;
}

void orient_positively(TetMesh& mesh) {
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    index_t* q = &mesh.tets[4 * static_cast<std::size_t>(t)];
    if (tet_volume(mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3])) < 0.0) {
      std::swap(q[2], q[3]);
    }
  }
}

Polytope unit_cube() {
  Polytope cube{"cube", {}};
  for (int i = 0; i < 8; ++i) {
    cube.corners.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  }
  return cube;
}

Polytope unit_prism() {
  return {"prism", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}}};
}

Polytope square_pyramid() {
  return {"pyramid", {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {1, 1, 1}}};
}

std::vector<Tet> candidate_tets(const Polytope& polytope) {
  const auto& pts = polytope.corners;
  const index_t n = static_cast<index_t>(pts.size());
  std::vector<Tet> out;
  for (index_t a = 0; a < n; ++a) {
    for (index_t b = a + 1; b < n; ++b) {
      for (index_t c = b + 1; c < n; ++c) {
        for (index_t d = c + 1; d < n; ++d) {
          Tet t{a, b, c, d};
          const double v = six_volume(pts, t);
          if (v == 0.0) continue;
          if (v < 0.0) std::swap(t[2], t[3]);
          out.push_back(t);
        }
      }
    }
  }
  return out;
}

std::vector<std::vector<Tet>> enumerate_triangulations(const Polytope& polytope) {
  const auto& pts = polytope.corners;
  const std::vector<Tet> cand = candidate_tets(polytope);
  const std::size_t n = cand.size();
  std::vector<std::vector<char>> disjoint(n, std::vector<char>(n, 0));
  std::vector<double> vol(n);
  for (std::size_t i = 0; i < n; ++i) {
    vol[i] = six_volume(pts, cand[i]);
    for (std::size_t j = 0; j < i; ++j) {
      disjoint[i][j] = disjoint[j][i] = interiors_disjoint(pts, cand[i], cand[j]);
    }
  }
  const double target = polytope_six_volume(polytope);
  std::vector<std::vector<Tet>> out;
  std::vector<std::size_t> chosen;
  // Depth-first over sets of pairwise interior-disjoint tets in increasing index order; the
  // volumes are small integers (times 1/6), so the sums are exact.
  auto search = [&](auto&& self, std::size_t start, double volume) -> void {
    if (volume == target) {
      std::vector<Tet> tets;
      for (std::size_t i : chosen) tets.push_back(cand[i]);
      if (face_to_face(pts, tets)) out.push_back(tets);
      return;
    }
    for (std::size_t i = start; i < n; ++i) {
      if (volume + vol[i] > target) continue;
      bool ok = true;
      for (std::size_t j : chosen) ok = ok && disjoint[i][j];
      if (!ok) continue;
      chosen.push_back(i);
      self(self, i + 1, volume + vol[i]);
      chosen.pop_back();
    }
  };
  search(search, 0, 0.0);
  return out;
}

int RFGraph::degree(int node) const {
  int d = 0;
  for (int j = 0; j < nb_nodes; ++j) d += (adjacency[node][j] & 1) ? 1 : 0;
  return d;
}

RFGraph rf_graph(const Polytope& polytope, const std::vector<Tet>& tets) {
  const auto& pts = polytope.corners;
  RFGraph g;
  g.nb_nodes = static_cast<int>(tets.size());
  g.adjacency.assign(g.nb_nodes, std::vector<int>(g.nb_nodes, 0));
  for (int i = 0; i < g.nb_nodes; ++i) {
    for (int j = 0; j < g.nb_nodes; ++j) {
      if (i == j) continue;
      for (const auto& f : tet_faces(tets[i])) {
        for (const auto& h : tet_faces(tets[j])) {
          if (sorted(f) == sorted(h)) g.adjacency[i][j] |= 1;
          if (on_hull(pts, f) && on_hull(pts, h) && coplanar(pts, f, h)) g.adjacency[i][j] |= 2;
        }
      }
    }
  }
  return g;
}

std::string canonical_form(const RFGraph& graph) {
  std::vector<int> perm(graph.nb_nodes);
  std::iota(perm.begin(), perm.end(), 0);
  std::string best;
  do {
    std::string code;
    for (int i = 0; i < graph.nb_nodes; ++i) {
      for (int j = i + 1; j < graph.nb_nodes; ++j) {
        code += static_cast<char>('0' + graph.adjacency[perm[i]][perm[j]]);
      }
    }
    if (best.empty() || code < best) best = code;
  } while (std::next_permutation(perm.begin(), perm.end()));
  return std::to_string(graph.nb_nodes) + ":" + best;
}

int solid_cycle_length(const RFGraph& graph) {
  std::vector<int> degree(graph.nb_nodes);
  std::vector<char> alive(graph.nb_nodes, 1);
  for (int i = 0; i < graph.nb_nodes; ++i) degree[i] = graph.degree(i);
  for (bool pruned = true; pruned;) {
    pruned = false;
    for (int i = 0; i < graph.nb_nodes; ++i) {
      if (!alive[i] || degree[i] > 1) continue;
      alive[i] = 0;
      pruned = true;
      for (int j = 0; j < graph.nb_nodes; ++j) {
        if (alive[j] && (graph.adjacency[i][j] & 1)) --degree[j];
      }
    }
  }
  return static_cast<int>(std::count(alive.begin(), alive.end(), 1));
}

std::vector<int> classes_of(const std::vector<std::string>& keys, std::vector<int>& sizes) {
  std::map<std::string, int> id;
  std::vector<int> out;
  sizes.clear();
  for (const std::string& k : keys) {
    const auto [it, inserted] = id.emplace(k, static_cast<int>(sizes.size()));
    if (inserted) sizes.push_back(0);
    ++sizes[it->second];
    out.push_back(it->second);
  }
  return out;
}

TetMesh polytope_mesh(const Polytope& polytope, const std::vector<Tet>& tets) {
  return make_tet_mesh(polytope.corners, tets);
}

index_t grid_node(int n, int i, int j, int k) {
  return static_cast<index_t>(i + (n + 1) * (j + (n + 1) * k));
}

namespace {

template <class Split>
TetMesh grid(int n, Split split) {
  TetMesh mesh;
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        mesh.points.insert(mesh.points.end(), {double(i), double(j), double(k)});
      }
    }
  }
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        auto corner = [&](int b) {
          return grid_node(n, i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        };
        for (const std::array<int, 4>& t : split(i, j, k)) {
          mesh.tets.insert(mesh.tets.end(),
                           {corner(t[0]), corner(t[1]), corner(t[2]), corner(t[3])});
        }
      }
    }
  }
  orient_positively(mesh);
  return mesh;
}

}  // namespace

TetMesh kuhn_grid(int n) {
  return grid(n, [](int, int, int) {
    std::vector<std::array<int, 4>> tets;
    std::array<int, 3> axes{0, 1, 2};
    do {
      const int v1 = 1 << axes[0];
      tets.push_back({0, v1, v1 | (1 << axes[1]), 7});
    } while (std::next_permutation(axes.begin(), axes.end()));
    return tets;
  });
}

TetMesh five_tet_grid(int n) {
  return grid(n, [](int i, int j, int k) {
    // The central tet takes the corners of one parity, a corner tet cuts off each of the
    // others; alternating the parity keeps every face diagonal shared with the next cube.
    const int parity = (i + j + k) & 1;
    std::vector<std::array<int, 4>> tets;
    std::array<int, 4> central{};
    int m = 0;
    for (int b = 0; b < 8; ++b) {
      const int bits = (b & 1) + ((b >> 1) & 1) + ((b >> 2) & 1);
      if ((bits & 1) == parity) {
        central[m++] = b;
      } else {
        tets.push_back({b, b ^ 1, b ^ 2, b ^ 4});
      }
    }
    tets.push_back(central);
    return tets;
  });
}

void random_affine_map(TetMesh& mesh, std::mt19937& rng, double spread) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double a[3][3];
  for (;;) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a[r][c] = (r == c ? 1.0 : 0.0) + spread * u(rng);
    }
    const double det =
        det3({a[0][0], a[1][0], a[2][0]}, {a[0][1], a[1][1], a[2][1]}, {a[0][2], a[1][2], a[2][2]});
    if (det >= 0.2) break;
  }
  const double b[3] = {u(rng), u(rng), u(rng)};
  for (std::size_t v = 0; v < mesh.points.size(); v += 3) {
    const double x[3] = {mesh.points[v], mesh.points[v + 1], mesh.points[v + 2]};
    for (int r = 0; r < 3; ++r) {
      mesh.points[v + r] = a[r][0] * x[0] + a[r][1] * x[1] + a[r][2] * x[2] + b[r];
    }
  }
}

void random_perturbation(TetMesh& mesh, std::mt19937& rng, double amplitude) {
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  const std::vector<double> original = mesh.points;
  for (int attempt = 0; attempt < 100; ++attempt) {
    for (std::size_t i = 0; i < mesh.points.size(); ++i) mesh.points[i] = original[i] + u(rng);
    bool valid = true;
    for (index_t t = 0; t < mesh.nb_tets() && valid; ++t) {
      const index_t* q = mesh.tet(t);
      valid =
          tet_volume(mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3])) > 0;
    }
    if (valid) return;
  }
  throw std::logic_error("random_perturbation: amplitude too large, every attempt inverted a tet");
}

double total_volume(const TetMesh& mesh) {
  double v = 0.0;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* q = mesh.tet(t);
    v += tet_volume(mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3]));
  }
  return v;
}

namespace {

// AcceptanceCriteria and RecombineParameters name the thresholds alike.
template <class Thresholds>
Thresholds permissive_thresholds() {
  Thresholds t;
  t.min_scaled_jacobian = 0.05;
  t.min_dihedral_angle = 120.0;
  t.min_boundary_dihedral_angle = 120.0;
  t.max_face_angle = 175.0;
  return t;
}

}  // namespace

AcceptanceCriteria permissive_criteria() { return permissive_thresholds<AcceptanceCriteria>(); }

RecombineParameters permissive_parameters() { return permissive_thresholds<RecombineParameters>(); }

}  // namespace hexmerge::test
