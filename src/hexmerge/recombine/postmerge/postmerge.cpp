#include "hexmerge/recombine/postmerge/postmerge.h"

#include <algorithm>
#include <array>
#include <functional>
#include <set>
#include <utility>

#include "hexmerge/geometry/quality.h"
#include "hexmerge/mesh/cell_type.h"

namespace hexmerge {
namespace {

bool holds(const index_t* q, index_t v) { return q[0] == v || q[1] == v || q[2] == v || q[3] == v; }

bool holds3(const index_t* q, index_t a, index_t b, index_t c) {
  return holds(q, a) && holds(q, b) && holds(q, c);
}

/// One quad face of a candidate, split by its tets on diagonal a-c into (a, b, c) and (a, c, d),
/// with the candidate's tets behind the two triangles.
struct QuadFace {
  index_t a, b, c, d;
  index_t inner_abc, inner_acd;
};

/// A candidate's scaled Jacobian is stored as a float: a moved candidate is compared with it
/// less this.
constexpr double kQualityRounding = 1e-6;

/// Degrees a lifted candidate's quad angles are kept inside the bounds.
constexpr double kAngleSpare = 1e-6;

/// With move_nodes, apexes whose pyramid reaches this share of the acceptance are tried.
constexpr double kMovableApexShare = 0.5;

/// A vertex split's new edge, as a share of the prism's sides it runs along (longest first).
constexpr std::array<double, 3> kSplitLengths = {1.0, 0.7, 0.4};

class Stage {
 public:
  /// candidates: those whose Candidate records the member functions are given
  Stage(FlipMesh& mesh, const Candidates& candidates, const PostMergeOptions& options)
      : m_(mesh),
        cands_(candidates),
        options_(options),
        min_dihedral_(options.min_dihedral_angle),
        max_corner_(options.max_face_angle) {
    if (options.placement == PyramidPlacement::NoBoundaryNode ||
        options.placement == PyramidPlacement::NoCurvedBoundaryNode) {
      boundary_vertex_.assign(mesh.nb_slots() == 0 ? 0 : max_vertex() + 1, 0);
      for (index_t t = 0; t < m_.nb_slots(); ++t) {
        for (int f = 0; f < 4; ++f) {
          if (!face_on_boundary(t, f)) continue;
          for (int i = 0; i < 4; ++i) {
            if (i != f) boundary_vertex_[m_.tet(t)[i]] = 1;
          }
        }
      }
    }
  }

  /// A move may not make candidate `i` of `list` fail the acceptance while its tets are alive
  /// (still_accepted()); the first call turns the move guard on.
  void protect(const Candidates& list, index_t i) {
    const Candidate& c = list[i];
    for (int k = 0; k < descriptor(c.type).nb_vertices; ++k) {
      const index_t v = c.vertices[k];
      if (v >= at_node_.size()) at_node_.resize(v + 1);
      at_node_[v].push_back({&list, i});
    }
    if (!guarded_) {
      m_.set_move_guard([this](index_t v, const std::vector<index_t>& leaving) {
        return still_accepted(v, leaving);
      });
      guarded_ = true;
    }
  }

  /// The candidate's quad faces with their diagonals; false when a face's split is not found
  /// among its tets (cannot happen for a candidate of the finders).
  bool quad_faces(const Candidate& cand, std::vector<QuadFace>& faces) const {
    return quad_faces(cands_, cand, faces);
  }
  bool quad_faces(const Candidates& list, const Candidate& cand,
                  std::vector<QuadFace>& faces) const {
    faces.clear();
    const CellDescriptor& desc = descriptor(cand.type);
    for (int f = 0; f < desc.nb_faces; ++f) {
      if (desc.face_size[f] != 4) continue;
      std::array<index_t, 4> v{};
      for (int i = 0; i < 4; ++i) v[i] = cand.vertices[desc.face[f][i]];
      bool found = false;
      for (int s = 0; s < 2 && !found; ++s) {
        const index_t a = v[s], b = v[s + 1], c = v[s + 2], d = v[(s + 3) % 4];
        const index_t abc = inner_tet(list, cand, a, b, c), acd = inner_tet(list, cand, a, c, d);
        if (abc != NO_CELL && acd != NO_CELL) {
          faces.push_back({a, b, c, d, abc, acd});
          found = true;
        }
      }
      if (!found) return false;
    }
    return true;
  }

  /// Every candidate at node v whose tets are alive and not in `leaving` still passes the
  /// acceptance with the node where it is (PostMergeOptions::min_dihedral_angle).
  bool still_accepted(index_t v, const std::vector<index_t>& leaving) const {
    if (v >= at_node_.size()) return true;
    for (const auto& [list, i] : at_node_[v]) {
      const Candidate& c = (*list)[i];
      const TetSpan tets = list->tets(c);
      const bool gone = std::any_of(tets.begin(), tets.end(), [&](index_t t) {
        return !m_.alive(t) || std::find(leaving.begin(), leaving.end(), t) != leaving.end();
      });
      if (gone) continue;
      const double need =
          std::min(options_.min_pyramid_quality, double{c.quality} - kQualityRounding);
      if (!accepted(*list, c, v, need)) return false;
    }
    return true;
  }

  /// Candidate c of `list` has a scaled Jacobian of at least `need` and its quad faces at node
  /// `at` (every quad face when `at` is NO_VERTEX) pass the angle bounds across their diagonal.
  bool accepted(const Candidates& list, const Candidate& c, index_t at, double need) const {
    const double sj = scaled_jacobian(c.type, m_.point(0), c.vertices.data());
    if (!(sj >= need)) return false;
    std::vector<QuadFace> faces;
    if (!quad_faces(list, c, faces)) return false;
    for (const QuadFace& q : faces) {
      if (at != NO_VERTEX && q.a != at && q.b != at && q.c != at && q.d != at) continue;
      if (!quad_accepted(q)) return false;
    }
    return true;
  }

  bool quad_accepted(const QuadFace& q) const {
    const double *a = m_.point(q.a), *b = m_.point(q.b), *c = m_.point(q.c), *d = m_.point(q.d);
    if (quad_dihedral_angle_below(a, b, c, d, min_dihedral_) &&
        quad_dihedral_angle_below(c, d, a, b, min_dihedral_)) {
      return false;
    }
    return !quad_max_corner_angle_above(a, b, c, d, max_corner_);
  }

  /// The candidate passes the acceptance with the nodes where they are.
  bool passes(const Candidate& cand) const {
    return accepted(cands_, cand, NO_VERTEX, options_.min_pyramid_quality);
  }

  /// A hexahedron candidate that fails the acceptance (a liftable one) made to pass it by
  /// moving one of its nodes (each quad face that fails holds it): the paper's smoothing. True
  /// when it passes (moved or not); on false nothing is changed.
  bool lift(const Candidate& cand) {
    const double need = options_.min_pyramid_quality;
    if (accepted(cands_, cand, NO_VERTEX, need)) return true;
    std::vector<QuadFace> faces;
    if (!quad_faces(cand, faces)) return false;
    for (int k = 0; k < 8; ++k) {
      const index_t v = cand.vertices[k];
      const bool holds_failing = std::all_of(faces.begin(), faces.end(), [&](const QuadFace& q) {
        return q.a == v || q.b == v || q.c == v || q.d == v || quad_accepted(q);
      });
      if (!holds_failing || !m_.movable(v)) continue;
      std::vector<FlipMesh::Goal> goals = {{[this, &cand]() {
                                              return scaled_jacobian(CellType::Hex, m_.point(0),
                                                                     cand.vertices.data());
                                            },
                                            need}};
      for (const QuadFace& q : faces) {
        if (q.a != v && q.b != v && q.c != v && q.d != v) continue;
        // Angles in right angles, so that a degree weighs about as much as 0.01 of scaled
        // Jacobian.
        goals.push_back({[this, q]() {
                           return quad_dihedral_angle(m_.point(q.a), m_.point(q.b), m_.point(q.c),
                                                      m_.point(q.d)) /
                                  90.0;
                         },
                         (options_.min_dihedral_angle + kAngleSpare) / 90.0});
        goals.push_back({[this, q]() {
                           return -quad_max_corner_angle(m_.point(q.a), m_.point(q.b),
                                                         m_.point(q.c), m_.point(q.d)) /
                                  90.0;
                         },
                         -(options_.max_face_angle - kAngleSpare) / 90.0});
      }
      const std::size_t start = m_.mark();
      if (m_.smooth(v, goals, {}, options_.min_tet_quality) &&
          accepted(cands_, cand, NO_VERTEX, need)) {
        return true;
      }
      m_.undo(start);
    }
    return false;
  }

  /// Both triangles on the domain boundary.
  bool on_boundary(const QuadFace& q) const {
    return m_.tet_with_face(q.a, q.b, q.c, q.inner_abc) == NO_CELL &&
           m_.tet_with_face(q.a, q.c, q.d, q.inner_acd) == NO_CELL;
  }

  /// The fan of tets behind the face around its diagonal: vertices b, x1, ..., xk, d and the
  /// k + 1 tets between them. False when the fan leaves the mesh, runs into the candidate, or is
  /// longer than max_fan tets.
  bool fan(const QuadFace& q, const Candidate& cand, std::vector<index_t>& vertices,
           std::vector<index_t>& tets) const {
    vertices.assign(1, q.b);
    tets.clear();
    index_t cur = m_.tet_with_face(q.a, q.b, q.c, q.inner_abc);
    index_t prev = q.b;
    while (true) {
      if (cur == NO_CELL || in_candidate(cand, cur)) return false;
      const index_t x = m_.opposite(cur, q.a, q.c, prev);
      vertices.push_back(x);
      tets.push_back(cur);
      if (x == q.d) return true;
      if (static_cast<int>(tets.size()) >= options_.max_fan) return false;
      const index_t next = m_.tet_with_face(q.a, q.c, x, cur);
      prev = x;
      cur = next;
    }
  }

  /// The pyramid on the face with apex `apex` made of tets t0 (holding b) and t1 (holding d)
  /// passes the acceptance.
  bool pyramid_ok(const QuadFace& q, index_t apex, index_t t0, index_t t1) const {
    return pyramid_quality(q, apex) >= options_.min_pyramid_quality &&
           pyramid_allowed(q, apex, t0, t1);
  }

  /// pyramid_ok(), or (move_nodes) made so by moving the apex (its tets all kept positive and
  /// at the floor, or not worse where they were below it).
  bool pyramid_ok_or_moved(const QuadFace& q, index_t apex, index_t t0, index_t t1) {
    if (pyramid_ok(q, apex, t0, t1)) return true;
    if (!options_.move_nodes || !pyramid_allowed(q, apex, t0, t1)) return false;
    const std::vector<FlipMesh::Goal> goals = {
        {[this, &q, apex]() { return pyramid_quality(q, apex); }, options_.min_pyramid_quality}};
    return m_.smooth(apex, goals, {}, options_.min_tet_quality);
  }

  /// The pyramid's region and placement pass the acceptance (its shape aside).
  bool pyramid_allowed(const QuadFace& q, index_t apex, index_t t0, index_t t1) const {
    if (m_.region(t0) != m_.region(t1)) return false;
    if (options_.placement == PyramidPlacement::NoBoundaryFace ||
        options_.placement == PyramidPlacement::NoCurvedBoundaryFace) {
      for (index_t t : {t0, t1}) {
        for (int f = 0; f < 4; ++f) {
          if (face_on_boundary(t, f)) return false;
        }
      }
    } else if (options_.placement == PyramidPlacement::NoBoundaryNode ||
               options_.placement == PyramidPlacement::NoCurvedBoundaryNode) {
      for (index_t v : {q.a, q.b, q.c, q.d, apex}) {
        // Nodes a split added are past the array and inside the domain.
        if (v < boundary_vertex_.size() && boundary_vertex_[v]) return false;
      }
    }
    return true;
  }

  double pyramid_quality(const QuadFace& q, index_t apex) const {
    const std::array<index_t, 5> up{{q.a, q.b, q.c, q.d, apex}};
    const std::array<index_t, 5> down{{q.a, q.d, q.c, q.b, apex}};
    const double* points = m_.point(0);
    return std::max(scaled_jacobian(CellType::Pyramid, points, up.data()),
                    scaled_jacobian(CellType::Pyramid, points, down.data()));
  }

  /// The face is closed by the tets as they are; on success, the pyramid's tets.
  bool closed(const QuadFace& q, const Candidate& cand, std::array<index_t, 2>& pyramid) const {
    std::vector<index_t> vertices, tets;
    if (!fan(q, cand, vertices, tets) || tets.size() != 2) return false;
    pyramid = {tets[0], tets[1]};
    return pyramid_ok(q, vertices[1], tets[0], tets[1]);
  }

  /// Closes the face by flips (none when it is closed already); on failure nothing is changed.
  bool close(const QuadFace& q, const Candidate& cand, std::array<index_t, 2>& pyramid) {
    std::vector<index_t> vertices, tets;
    if (!fan(q, cand, vertices, tets)) return false;
    if (tets.size() == 2) {
      pyramid = {tets[0], tets[1]};
      return pyramid_ok_or_moved(q, vertices[1], tets[0], tets[1]);
    }
    // Apexes by the quality of their pyramid, best first (with move_nodes also those at half
    // the acceptance or more, which a move of the apex may lift).
    const double least =
        options_.min_pyramid_quality * (options_.move_nodes ? kMovableApexShare : 1.0);
    std::vector<std::pair<double, index_t>> apexes;
    for (std::size_t i = 1; i + 1 < vertices.size(); ++i) {
      const double quality = pyramid_quality(q, vertices[i]);
      if (quality >= least) apexes.emplace_back(-quality, vertices[i]);
    }
    std::sort(apexes.begin(), apexes.end());
    for (const auto& [unused, apex] : apexes) {
      const std::size_t start = m_.mark();
      if (reduce_fan(q, cand, apex, vertices.size()) && fan(q, cand, vertices, tets) &&
          tets.size() == 2 && vertices[1] == apex &&
          pyramid_ok_or_moved(q, apex, tets[0], tets[1])) {
        pyramid = {tets[0], tets[1]};
        return true;
      }
      m_.undo(start);
      fan(q, cand, vertices, tets);
    }
    return false;
  }

  /// The paper's vertex split (4.3.2) making a hexahedron: prism `ci` of `list` (the stage's
  /// candidates) and the pyramid closing its quad face q (the two tets behind it, apex p) become
  /// one hexahedron when p is split into an edge p-n parallel to the face's sides that run
  /// between the prism's triangles: the pyramid's tets, one with p and one with n, and the ring
  /// tet on the face's diagonal are a second prism on q. The new edge is tried as long as those
  /// sides, then kSplitLengths of them, centred on p, where the hexahedron reaches the acceptance's
  /// scaled Jacobian; p's star is cut as star_sides() gives. Each hexahedron made that passes the
  /// acceptance is appended to `list` and given to `closes` (its index), which closes its faces
  /// or changes nothing: true at the first it keeps; otherwise nothing is changed.
  bool split_into_hex(Candidates& list, index_t ci, const QuadFace& q,
                      const std::function<bool(index_t)>& closes) {
    const Candidate prism = list[ci];  // a copy: the list grows
    if (prism.nb_tets != 3) return false;
    std::vector<index_t> fan_vertices, fan_tets;
    if (!fan(q, prism, fan_vertices, fan_tets) || fan_tets.size() != 2) return false;
    const index_t p = fan_vertices[1];
    if (!m_.movable(p)) return false;
    // The prism's corner off the face on its bottom triangle (u) and its twin on the top (w);
    // the bottom's other corners x1, y1 and their twins x2, y2: the face's sides x1-x2, y1-y2.
    const auto& v = prism.vertices;
    int k = 0;
    while (k < 3 && (v[k] == q.a || v[k] == q.b || v[k] == q.c || v[k] == q.d)) ++k;
    if (k == 3) return false;
    const index_t x1 = v[(k + 1) % 3], y1 = v[(k + 2) % 3];
    // The pyramid's tet whose base triangle holds x1-y1 keeps p; the other takes n.
    const bool keep_abc =
        (x1 == q.a || x1 == q.b || x1 == q.c) && (y1 == q.a || y1 == q.b || y1 == q.c);
    const index_t keep = keep_abc ? fan_tets[0] : fan_tets[1];
    const index_t moving = keep_abc ? fan_tets[1] : fan_tets[0];
    std::array<double, 3> dir{}, at{};
    for (int i = 0; i < 3; ++i) {
      dir[i] = 0.5 * (m_.point(v[(k + 1) % 3 + 3])[i] + m_.point(v[(k + 2) % 3 + 3])[i] -
                      m_.point(x1)[i] - m_.point(y1)[i]);
      at[i] = m_.point(p)[i];
    }
    const std::vector<std::vector<index_t>> sides = star_sides(p, q, keep, moving, at, dir);
    const index_t next = m_.nb_nodes();
    // Hexahedron corners: the bottom u, x1, p, y1 (p across x1-y1 from u) and their twins on the
    // top; index `next` stands for n until it exists. Either way round, the better.
    const std::array<index_t, 8> up{
        {v[k], x1, p, y1, v[k + 3], v[(k + 1) % 3 + 3], next, v[(k + 2) % 3 + 3]}};
    const std::array<index_t, 8> down{
        {v[k], y1, p, x1, v[k + 3], v[(k + 2) % 3 + 3], next, v[(k + 1) % 3 + 3]}};
    for (double share : kSplitLengths) {
      std::array<double, 3> at_p{}, at_n{};
      for (int i = 0; i < 3; ++i) {
        at_p[i] = at[i] - 0.5 * share * dir[i];
        at_n[i] = at[i] + 0.5 * share * dir[i];
      }
      // The hexahedron's shape at these places, before any split is tried.
      const auto shape = [&](const std::array<index_t, 8>& order) {
        std::array<double, 24> corners{};
        for (int c = 0; c < 8; ++c) {
          const index_t w = order[c];
          const double* x = w == p ? at_p.data() : w == next ? at_n.data() : m_.point(w);
          std::copy(x, x + 3, &corners[3 * c]);
        }
        const std::array<index_t, 8> local{{0, 1, 2, 3, 4, 5, 6, 7}};
        return scaled_jacobian(CellType::Hex, corners.data(), local.data());
      };
      if (std::max(shape(up), shape(down)) < options_.min_pyramid_quality) continue;
      for (const auto& side : sides) {
        const std::size_t start = m_.mark();
        const index_t n = m_.split(p, side, at_p, at_n, options_.min_tet_quality);
        if (n == NO_VERTEX) continue;
        HEXMERGE_ASSERT(n == next, "a split adds the next node");
        // The second prism's tets: the pyramid's two, remade, and the ring tet on the diagonal.
        std::array<index_t, 6> tets{};
        std::copy(list.tets(prism).begin(), list.tets(prism).end(), tets.begin());
        tets[3] = m_.tet_with_face(q.a, q.b, q.c, q.inner_abc);
        tets[4] = m_.tet_with_face(q.a, q.c, q.d, q.inner_acd);
        std::vector<index_t> ring;
        m_.tets_with_edge(p, n, ring);
        tets[5] = NO_CELL;
        for (index_t t : ring) {
          if (holds(m_.tet(t), q.a) && holds(m_.tet(t), q.c)) tets[5] = t;
        }
        if (tets[3] != NO_CELL && tets[4] != NO_CELL && tets[5] != NO_CELL) {
          std::sort(tets.begin(), tets.end());
          Candidate hex = prism;  // graph: not read by the stage
          hex.type = CellType::Hex;
          const double* points = m_.point(0);
          const double made_up = scaled_jacobian(CellType::Hex, points, up.data());
          const double made_down = scaled_jacobian(CellType::Hex, points, down.data());
          hex.vertices = made_up >= made_down ? up : down;
          hex.quality = static_cast<float>(std::max(made_up, made_down));
          list.push_back(hex, tets.data(), 6);
          const Candidate& made = list[list.size() - 1];
          if (accepted(list, made, NO_VERTEX, options_.min_pyramid_quality) &&
              closes(static_cast<index_t>(list.size() - 1))) {
            return true;
          }
          list.pop_back();
        }
        m_.undo(start);
      }
    }
    return false;
  }

 private:
  /// Ways to cut node p's star in two for a split (split_into_hex): each the tets that take the
  /// new node, holding `moving` and not `keep`. First, for each link vertex y joined to both
  /// ends of q's diagonal a-c, the tets reached from `moving` across faces at p without crossing
  /// the cycle a-c-y of link edges (a ring of three tets); then the tets whose base triangle's
  /// centroid lies ahead of p (at `at`) along `dir`. Distinct sets only.
  std::vector<std::vector<index_t>> star_sides(index_t p, const QuadFace& q, index_t keep,
                                               index_t moving, const std::array<double, 3>& at,
                                               const std::array<double, 3>& dir) const {
    std::vector<index_t> around;
    m_.tets_with_edge(p, p, around);
    // The triangle of tet t opposite p (its side of p's link).
    const auto base_of = [this, p](index_t t) {
      std::array<index_t, 3> base{};
      int n = 0;
      for (int i = 0; i < 4; ++i) {
        if (m_.tet(t)[i] != p) base[n++] = m_.tet(t)[i];
      }
      return base;
    };
    std::vector<std::vector<index_t>> sides;
    const auto add = [&sides](std::vector<index_t> side) {
      std::sort(side.begin(), side.end());
      if (std::find(sides.begin(), sides.end(), side) == sides.end()) sides.push_back(side);
    };
    const auto edge = [](index_t x, index_t y) {
      return std::make_pair(std::min(x, y), std::max(x, y));
    };
    std::vector<index_t> ahead;
    std::set<std::pair<index_t, index_t>> link_edges;
    for (index_t t : around) {
      const std::array<index_t, 3> base = base_of(t);
      double along = 0.0;
      for (int i = 0; i < 3; ++i) {
        const double centroid =
            (m_.point(base[0])[i] + m_.point(base[1])[i] + m_.point(base[2])[i]) / 3.0;
        along += (centroid - at[i]) * dir[i];
      }
      if (t == moving || (t != keep && along > 0.0)) ahead.push_back(t);
      for (int i = 0; i < 3; ++i) {
        link_edges.insert(edge(base[i], base[(i + 1) % 3]));
      }
    }
    std::set<index_t> tried;
    for (const auto& [e0, e1] : link_edges) {
      for (index_t y : {e0, e1}) {
        if (y == q.a || y == q.c || !tried.insert(y).second) continue;
        if (!link_edges.count(edge(q.a, y)) || !link_edges.count(edge(q.c, y))) continue;
        const std::set<std::pair<index_t, index_t>> cycle = {edge(q.a, q.c), edge(q.a, y),
                                                             edge(q.c, y)};
        std::vector<index_t> reached = {moving};
        for (std::size_t r = 0; r < reached.size(); ++r) {
          const index_t t = reached[r];
          const std::array<index_t, 3> base = base_of(t);
          for (int i = 0; i < 3; ++i) {
            const index_t f0 = base[i], f1 = base[(i + 1) % 3];
            if (cycle.count(edge(f0, f1))) continue;
            const index_t across = m_.tet_with_face(p, f0, f1, t);
            if (across != NO_CELL &&
                std::find(reached.begin(), reached.end(), across) == reached.end()) {
              reached.push_back(across);
            }
          }
        }
        if (std::find(reached.begin(), reached.end(), keep) == reached.end()) add(reached);
      }
    }
    add(ahead);
    return sides;
  }

 private:
  /// Takes every fan vertex but `apex` out of the fan, one flip at a time.
  bool reduce_fan(const QuadFace& q, const Candidate& cand, index_t apex, std::size_t length) {
    std::vector<index_t> vertices, tets;
    while (true) {
      if (!fan(q, cand, vertices, tets)) return false;
      if (tets.size() == 2) return true;
      bool progress = false;
      for (std::size_t i = 1; i + 1 < vertices.size() && !progress; ++i) {
        if (vertices[i] == apex) continue;
        progress = remove_from_fan(q, cand, apex, vertices, tets, i);
      }
      if (!progress) return false;
      if (vertices.size() >= length) return false;  // guards against a cycle of flips
      length = vertices.size();
    }
  }

  /// One flip that takes vertices[i] out of the fan (kept only if the fan gets shorter and still
  /// holds the apex).
  bool remove_from_fan(const QuadFace& q, const Candidate& cand, index_t apex,
                       std::vector<index_t>& vertices, std::vector<index_t>& tets, std::size_t i) {
    const std::size_t before = vertices.size();
    const index_t x = vertices[i];
    const auto kept = [&]() {
      std::vector<index_t> v2, t2;
      if (fan(q, cand, v2, t2) && v2.size() < before &&
          std::find(v2.begin(), v2.end(), apex) != v2.end()) {
        vertices.swap(v2);
        tets.swap(t2);
        return true;
      }
      return false;
    };
    const double floor = options_.min_tet_quality;
    const std::size_t start = m_.mark();
    if (m_.flip_23(tets[i - 1], tets[i], floor)) {
      if (kept()) return true;
      m_.undo(start);
    }
    for (index_t end : {q.a, q.c}) {
      for (int diagonal = 0; diagonal < 2; ++diagonal) {
        if (!m_.remove_edge(end, x, diagonal, floor)) continue;
        if (kept()) return true;
        m_.undo(start);
      }
    }
    // No flip takes it out: contract it into a neighbour along the fan (the tets between them
    // go, the fan loses it).
    if (options_.contract_edges) {
      for (index_t onto : {vertices[i - 1], vertices[i + 1]}) {
        if (!m_.contract(x, onto, floor)) continue;
        if (kept()) return true;
        m_.undo(start);
      }
    }
    return false;
  }

  index_t inner_tet(const Candidates& list, const Candidate& cand, index_t a, index_t b,
                    index_t c) const {
    for (const index_t t : list.tets(cand)) {
      if (m_.alive(t) && holds3(m_.tet(t), a, b, c)) return t;
    }
    return NO_CELL;
  }

  bool in_candidate(const Candidate& cand, index_t t) const {
    return cands_.tets(cand).contains(t);
  }

  bool face_on_boundary(index_t t, int f) const {
    std::array<index_t, 3> v{};
    int n = 0;
    for (int i = 0; i < 4; ++i) {
      if (i != f) v[n++] = m_.tet(t)[i];
    }
    return m_.tet_with_face(v[0], v[1], v[2], t) == NO_CELL;
  }

  index_t max_vertex() const {
    index_t most = 0;
    for (index_t t = 0; t < m_.nb_slots(); ++t) {
      for (int i = 0; i < 4; ++i) most = std::max(most, m_.tet(t)[i]);
    }
    return most;
  }

  FlipMesh& m_;
  const Candidates& cands_;
  const PostMergeOptions& options_;
  std::vector<char> boundary_vertex_;
  AngleBound min_dihedral_, max_corner_;
  /// The candidates at each node (move_nodes only).
  std::vector<std::vector<std::pair<const Candidates*, index_t>>> at_node_;
  bool guarded_ = false;
};

bool all_alive(const FlipMesh& m, TetSpan tets) {
  for (const index_t t : tets) {
    if (!m.alive(t) || m.locked(t)) return false;
  }
  return true;
}

/// Locks the candidate's tets and closes its quad faces one by one (pass 0: only those closed as
/// the tets are; else by flips), locking each closing pyramid; every tet this call locks is added
/// to `locked` (not one locked before: a closing pyramid's tets may be those of an element the
/// selection keeps, which give_up() must leave locked).
bool close_faces(Stage& stage, FlipMesh& m, const Candidate& cand, TetSpan tets,
                 const std::vector<QuadFace>& faces, int pass, std::vector<index_t>& locked) {
  const auto lock = [&](index_t t) {
    if (m.locked(t)) return;
    m.set_locked(t, true);
    locked.push_back(t);
  };
  for (const index_t t : tets) lock(t);
  for (const QuadFace& q : faces) {
    if (stage.on_boundary(q)) continue;
    std::array<index_t, 2> pyramid{};
    if (!(pass == 0 ? stage.closed(q, cand, pyramid) : stage.close(q, cand, pyramid))) {
      return false;
    }
    for (index_t t : pyramid) lock(t);
  }
  return true;
}

/// Unlocks the tets close_faces() locked and undoes every change since `start`.
void give_up(FlipMesh& m, const std::vector<index_t>& locked, std::size_t start) {
  for (index_t t : locked) {
    if (t < m.nb_slots()) m.set_locked(t, false);
  }
  m.undo(start);
}

}  // namespace

QuadCensus quad_census(const TetMesh& mesh, const Candidates& candidates,
                       const PostMergeOptions& options) {
  FlipMesh m(mesh);
  Stage stage(m, candidates, options);
  QuadCensus census;
  std::vector<QuadFace> faces;
  std::array<index_t, 2> pyramid{};
  for (const Candidate& cand : candidates) {
    if (cand.type != CellType::Hex) continue;
    ++census.hex_candidates;
    if (!stage.quad_faces(cand, faces)) continue;
    const bool closable = std::all_of(faces.begin(), faces.end(), [&](const QuadFace& q) {
      return stage.on_boundary(q) || stage.closed(q, cand, pyramid);
    });
    if (closable) ++census.closable;
  }
  return census;
}

PostMergeResult close_open_quads(const TetMesh& mesh, const Candidates& found,
                                 const Candidates& selected_from, const Selection& selection,
                                 const PostMergeOptions& options, const Candidates& liftable) {
  FlipMesh m(mesh);
  m.set_smoothing(options.move_nodes);
  m.set_slide_on_faces(options.move_nodes);
  // The candidates worked on: those found, then (move_nodes) the liftable hexahedra.
  Candidates candidates;
  const Candidates* all = &found;
  const index_t nb_found = static_cast<index_t>(found.size());
  const bool lifts = options.move_nodes && !liftable.empty();
  // Splits append the hexahedra they make to the stage's list.
  if (lifts || options.split_nodes) {
    candidates = found;
    if (lifts) {
      for (const Candidate& c : liftable) {
        if (c.type == CellType::Hex) candidates.push_back(c, liftable.tets(c).data(), c.nb_tets);
      }
    }
    all = &candidates;
  }
  Stage stage(m, *all, options);
  const Candidates& cands = *all;
  PostMergeResult result;
  // The selection's hexahedra and the elements on their quad faces stay as they are.
  std::set<FaceKey> hex_quads;
  for (index_t e : selection.elements) {
    const Candidate& c = selected_from[e];
    if (c.type != CellType::Hex) continue;
    for (int f = 0; f < 6; ++f) hex_quads.insert(face_key(c, f));
  }
  for (index_t e : selection.elements) {
    const Candidate& c = selected_from[e];
    bool keep = c.type == CellType::Hex;
    for (int f = 0; f < descriptor(c.type).nb_faces && !keep; ++f) {
      keep = descriptor(c.type).face_size[f] == 4 && hex_quads.count(face_key(c, f)) != 0;
    }
    if (!keep) continue;
    for (const index_t t : selected_from.tets(c)) m.set_locked(t, true);
  }
  // Hexahedron candidates: first those whose faces are closed as the tets are, then the others,
  // best scaled Jacobian first (ties by index: deterministic).
  std::vector<index_t> order;
  for (index_t i = 0; i < static_cast<index_t>(cands.size()); ++i) {
    if (cands[i].type == CellType::Hex) order.push_back(i);
  }
  // Fewest flips first (the fan lengths beyond two tets, summed over the faces; a face whose
  // fan cannot be followed counts max_fan), then best scaled Jacobian.
  std::vector<int> effort(cands.size(), 0);
  std::vector<QuadFace> faces;
  std::vector<index_t> fan_vertices, fan_tets;
  for (index_t i : order) {
    if (!stage.quad_faces(cands[i], faces)) continue;
    for (const QuadFace& q : faces) {
      if (stage.on_boundary(q)) continue;
      effort[i] += stage.fan(q, cands[i], fan_vertices, fan_tets)
                       ? static_cast<int>(fan_tets.size()) - 2
                       : options.max_fan;
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](index_t x, index_t y) {
    if (effort[x] != effort[y]) return effort[x] < effort[y];
    return cands[x].quality > cands[y].quality;
  });
  if (options.move_nodes) {
    // Moves keep the hexahedron candidates found and the selection's elements passing the
    // acceptance (every candidate found would leave few moves: docs/recombine.md).
    for (index_t i : order) {
      if (i < nb_found) stage.protect(cands, i);
    }
    for (index_t e : selection.elements) stage.protect(selected_from, e);
  }
  std::vector<index_t> locked_here;
  for (int pass = 0; pass < 2; ++pass) {
    for (index_t i : order) {
      const Candidate& cand = cands[i];
      if (!all_alive(m, cands.tets(cand)) || !stage.quad_faces(cand, faces)) continue;
      // A liftable candidate: made acceptable by a node move first (flips' pass only).
      const bool lifting = i >= nb_found;
      if (lifting && (pass == 0 || stage.passes(cand))) continue;  // passing: one of `found`
      if (pass == 1) ++result.attempted;
      const std::size_t start = m.mark();
      if (lifting) {
        // A move changes no tet's vertices: a face whose fan cannot be followed now (it leaves
        // the mesh, runs into the candidate or is longer than max_fan) will not close.
        const bool followed = std::all_of(faces.begin(), faces.end(), [&](const QuadFace& q) {
          return stage.on_boundary(q) || stage.fan(q, cand, fan_vertices, fan_tets);
        });
        if (!followed || !stage.lift(cand)) continue;
        if (!stage.quad_faces(cand, faces)) {
          m.undo(start);
          continue;
        }
      }
      locked_here.clear();
      if (close_faces(stage, m, cand, cands.tets(cand), faces, pass, locked_here)) {
        if (lifting) ++result.lifted;
        if (pass == 0) {
          ++result.already_closed;
        } else {
          ++result.closed;
        }
        continue;
      }
      give_up(m, locked_here, start);
    }
  }
  if (options.split_nodes) {
    // Vertex splits: prisms found whose tets are all free, best scaled Jacobian first.
    std::vector<index_t> prisms;
    for (index_t i = 0; i < nb_found; ++i) {
      if (cands[i].type == CellType::Prism) prisms.push_back(i);
    }
    std::stable_sort(prisms.begin(), prisms.end(),
                     [&](index_t x, index_t y) { return cands[x].quality > cands[y].quality; });
    std::vector<QuadFace> prism_faces;
    for (index_t i : prisms) {
      if (!all_alive(m, cands.tets(i)) || !stage.quad_faces(cands[i], prism_faces)) continue;
      for (const QuadFace& q : prism_faces) {
        if (stage.on_boundary(q)) continue;
        const auto closes = [&](index_t h) {
          const std::size_t start = m.mark();
          locked_here.clear();
          if (stage.quad_faces(cands[h], faces) &&
              close_faces(stage, m, cands[h], cands.tets(h), faces, 1, locked_here)) {
            return true;
          }
          give_up(m, locked_here, start);
          return false;
        };
        if (stage.split_into_hex(candidates, i, q, closes)) {
          ++result.split_hexes;
          break;
        }
      }
    }
  }
  result.flips = m.counts();
  result.tets = m.compact();
  return result;
}

}  // namespace hexmerge
