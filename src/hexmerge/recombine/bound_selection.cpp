#include "hexmerge/recombine/bound_selection.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>

#include "hexmerge/core/error.h"
#include "hexmerge/geometry/quality.h"

#ifdef HEXMERGE_WITH_GLPK
#include <glpk.h>
#endif

namespace hexmerge {

#ifdef HEXMERGE_WITH_GLPK
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

int saving(const Candidate& c) { return static_cast<int>(c.nb_tets) - 1; }

// A bound that needs no solver: every tet gives at most the best share (n - 1) / n of a
// candidate covering it, so the savings are at most the sum of those shares (a feasible point
// of the LP's dual). Used only when the LP relaxation does not finish in time.
double share_bound(index_t nb_tets, const Candidates& candidates) {
  std::vector<double> share(nb_tets, 0.0);
  for (const Candidate& c : candidates) {
    const double s = static_cast<double>(saving(c)) / c.nb_tets;
    for (const index_t t : candidates.tets(c)) share[t] = std::max(share[t], s);
  }
  double sum = 0.0;
  for (double s : share) sum += s;
  return sum;
}

std::size_t elements_saved(const Candidates& candidates, const std::vector<index_t>& chosen) {
  std::size_t saved = 0;
  for (index_t c : chosen) saved += saving(candidates[c]);
  return saved;
}

// Objective values are whole numbers: a bound b on the savings allows at most floor(b) of them.
// The small tolerance absorbs the simplex's rounding.
std::size_t whole_savings(double bound) {
  return bound <= 0.0 ? 0 : static_cast<std::size_t>(std::floor(bound + 1e-6));
}

// What the branch-and-cut callback needs: the incumbent to offer once, and the best bound seen.
struct SearchState {
  const std::vector<double>* initial = nullptr;  // 1-based column values, or null
  bool offered = false;
  double best_bound = HUGE_VAL;  // on the savings; the global bound only decreases
};

void on_search_event(glp_tree* tree, void* info) {
  auto& state = *static_cast<SearchState*>(info);
  if (glp_ios_reason(tree) == GLP_IHEUR && state.initial != nullptr && !state.offered) {
    state.offered = true;
    glp_ios_heur_sol(tree, state.initial->data());
  }
  // Every open node's bound bounds the savings of the solutions below it; the best open node's
  // bounds them all (GLPK's own relative gap is built on the same value).
  const int node = glp_ios_best_node(tree);
  if (node != 0) state.best_bound = std::min(state.best_bound, glp_ios_node_bound(tree, node));
}

// GLPK's cut generators print even at GLP_MSG_OFF; the core never prints, so terminal output is
// off for the solve (GLPK's switch is per thread) and restored after.
class QuietTerminal {
 public:
  QuietTerminal() : previous_(glp_term_out(GLP_OFF)) {}
  ~QuietTerminal() { glp_term_out(previous_); }
  QuietTerminal(const QuietTerminal&) = delete;
  QuietTerminal& operator=(const QuietTerminal&) = delete;

 private:
  int previous_;
};

struct ProblemDeleter {
  void operator()(glp_prob* p) const { glp_delete_prob(p); }
};

// Milliseconds left of `time_limit` seconds from `start`; at least 1 (GLPK reads 0 as none).
int milliseconds_left(Clock::time_point start, double time_limit) {
  return std::max(1, static_cast<int>(1000.0 * (time_limit - seconds_since(start))));
}

// GLPK's simplex, quiet (the core never prints).
glp_smcp simplex_parameters(int time_limit_ms) {
  glp_smcp simplex;
  glp_init_smcp(&simplex);
  simplex.msg_lev = GLP_MSG_OFF;
  simplex.tm_lim = time_limit_ms;
  return simplex;
}

// GLPK's branch and cut, quiet, from the LP relaxation already solved, with clique cuts (tets
// shared by many candidates are cliques of conflicts), reporting to `state`.
glp_iocp search_parameters(int time_limit_ms, SearchState& state) {
  glp_iocp search;
  glp_init_iocp(&search);
  search.msg_lev = GLP_MSG_OFF;
  search.tm_lim = time_limit_ms;
  search.presolve = GLP_OFF;
  search.clq_cuts = GLP_ON;
  search.cb_func = on_search_event;
  search.cb_info = &state;
  return search;
}

// The set-packing program, to be maximised: one binary column per candidate with its weight, one
// row per tet that two or more of them share (a tet of one candidate constrains nothing). A
// column is given by its candidate's tets.
void load_packing(glp_prob* lp, index_t nb_tets, const std::vector<TetSpan>& columns,
                  const std::vector<double>& weights) {
  std::vector<int> covering(nb_tets, 0);
  for (const TetSpan& c : columns) {
    for (const index_t t : c) ++covering[t];
  }
  std::vector<int> row_of(nb_tets, 0);
  int nb_rows = 0;
  for (index_t t = 0; t < nb_tets; ++t) {
    if (covering[t] >= 2) row_of[t] = ++nb_rows;
  }
  glp_set_obj_dir(lp, GLP_MAX);
  if (nb_rows > 0) glp_add_rows(lp, nb_rows);
  for (int r = 1; r <= nb_rows; ++r) glp_set_row_bnds(lp, r, GLP_UP, 0.0, 1.0);
  // GLPK's arrays are 1-based: entry 0 is unused.
  std::vector<int> ia(1, 0), ja(1, 0);
  std::vector<double> ar(1, 0.0);
  if (!columns.empty()) glp_add_cols(lp, static_cast<int>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const int j = static_cast<int>(k) + 1;
    glp_set_col_kind(lp, j, GLP_BV);
    glp_set_obj_coef(lp, j, weights[k]);
    for (const index_t t : columns[k]) {
      if (row_of[t] == 0) continue;
      ia.push_back(row_of[t]);
      ja.push_back(j);
      ar.push_back(1.0);
    }
  }
  glp_load_matrix(lp, static_cast<int>(ia.size()) - 1, ia.data(), ja.data(), ar.data());
}

}  // namespace
#endif

std::vector<ConformityRow> conformity_rows(const TetMesh& mesh, const TetTopology& topology,
                                           const Candidates& candidates) {
  // Every quad face of every candidate, keyed by its sorted vertices.
  struct Quad {
    std::array<index_t, 4> key;
    index_t candidate;
    bool constrained;
  };
  std::vector<Quad> quads;
  for (index_t ci = 0; ci < candidates.size(); ++ci) {
    const Candidate& c = candidates[ci];
    const CellDescriptor& d = descriptor(c.type);
    for (int f = 0; f < d.nb_faces; ++f) {
      if (d.face_size[f] != 4) continue;
      Quad q{{}, ci, false};
      for (int i = 0; i < 4; ++i) q.key[i] = c.vertices[d.face[f][i]];
      std::sort(q.key.begin(), q.key.end());
      // The candidate's tet faces lying on the quad, and whether each has a tet beyond it.
      int on_quad = 0, beyond = 0;
      for (const index_t t : candidates.tets(c)) {
        const index_t* v = mesh.tet(t);
        for (int tf = 0; tf < 4; ++tf) {
          bool inside = true;
          for (int i = 0; i < 4 && inside; ++i) {
            if (i != tf) inside = std::binary_search(q.key.begin(), q.key.end(), v[i]);
          }
          if (!inside) continue;
          ++on_quad;
          if (topology.neighbor(t, tf) != NO_CELL) ++beyond;
        }
      }
      q.constrained = on_quad == 2 && beyond == 2;
      quads.push_back(q);
    }
  }
  std::sort(quads.begin(), quads.end(), [](const Quad& a, const Quad& b) {
    return a.key != b.key ? a.key < b.key : a.candidate < b.candidate;
  });
  std::vector<ConformityRow> rows;
  for (std::size_t begin = 0, end; begin < quads.size(); begin = end) {
    end = begin + 1;
    while (end < quads.size() && quads[end].key == quads[begin].key) ++end;
    for (std::size_t i = begin; i < end; ++i) {
      if (!quads[i].constrained) continue;
      ConformityRow row{quads[i].candidate, {}};
      for (std::size_t j = begin; j < end; ++j) {
        if (quads[j].candidate != row.candidate) row.partners.push_back(quads[j].candidate);
      }
      row.partners.erase(std::unique(row.partners.begin(), row.partners.end()), row.partners.end());
      rows.push_back(std::move(row));
    }
  }
  return rows;
}

bool selection_bound_available() {
#ifdef HEXMERGE_WITH_GLPK
  return true;
#else
  return false;
#endif
}

void require_selection_bound() {
  if (selection_bound_available()) return;
  throw InputError(
      "parameter 'optimality_bound': this build of HexMerge has no GLPK (install libglpk-dev "
      "and rebuild with HEXMERGE_WITH_GLPK=ON)",
      Entity::Parameter);
}

SelectionBound bound_selection(index_t nb_tets, const Candidates& candidates,
                               const std::vector<index_t>& initial, double time_limit,
                               const std::vector<ConformityRow>& conformity) {
  HEXMERGE_ASSERT(time_limit > 0.0, "bound_selection: the time limit must be positive");
  std::vector<char> used(nb_tets, 0);
  for (index_t ci : initial) {
    for (const index_t t : candidates.tets(ci)) {
      HEXMERGE_ASSERT(!used[t], "bound_selection: the initial selection overlaps");
      used[t] = 1;
    }
  }
#ifndef HEXMERGE_WITH_GLPK
  static_cast<void>(conformity);
  require_selection_bound();
  return {};
#else
  const auto start = Clock::now();
  const QuietTerminal quiet;
  SelectionBound result;
  result.best = initial;

  const int nb_cols = static_cast<int>(candidates.size());
  // Conformity rows the initial selection keeps (x_c - sum x_partners <= 0).
  std::vector<char> chosen(candidates.size(), 0);
  for (index_t ci : initial) chosen[ci] = 1;
  std::vector<const ConformityRow*> kept;
  for (const ConformityRow& row : conformity) {
    const bool broken =
        chosen[row.candidate] && std::none_of(row.partners.begin(), row.partners.end(),
                                              [&](index_t p) { return chosen[p] != 0; });
    if (broken) {
      ++result.dropped_rows;
    } else {
      kept.push_back(&row);
    }
  }
  result.conformity_rows = kept.size();

  std::unique_ptr<glp_prob, ProblemDeleter> problem(glp_create_prob());
  glp_prob* lp = problem.get();
  std::vector<TetSpan> columns;
  std::vector<double> weights;
  for (const Candidate& c : candidates) {
    columns.push_back(candidates.tets(c));
    weights.push_back(saving(c));
  }
  load_packing(lp, nb_tets, columns, weights);

  const std::size_t initial_saved = elements_saved(candidates, initial);
  const auto finish = [&](double saved_bound, std::size_t best_saved) {
    result.bound_elements = nb_tets - std::min<std::size_t>(whole_savings(saved_bound), nb_tets);
    result.best_elements = nb_tets - best_saved;
    result.seconds = seconds_since(start);
    return result;
  };

  glp_smcp simplex = simplex_parameters(milliseconds_left(start, time_limit));
  if (nb_cols == 0) {
    result.proved = true;
    return finish(0.0, 0);
  }
  // The packing LP first: quick, and its bound holds whatever happens next.
  if (glp_simplex(lp, &simplex) != 0 || glp_get_status(lp) != GLP_OPT) {
    return finish(share_bound(nb_tets, candidates), initial_saved);
  }
  double lp_bound = glp_get_obj_val(lp);
  if (!kept.empty()) {
    // Then the conformity rows (x_c - sum x_partners <= 0), re-solved from the packing basis by
    // the dual simplex: cold, this LP is far slower (degenerate).
    const int first = glp_add_rows(lp, static_cast<int>(kept.size()));
    std::vector<int> index(1, 0);
    std::vector<double> value(1, 0.0);
    for (std::size_t k = 0; k < kept.size(); ++k) {
      index.assign(1, 0);
      value.assign(1, 0.0);
      index.push_back(static_cast<int>(kept[k]->candidate) + 1);
      value.push_back(1.0);
      for (index_t p : kept[k]->partners) {
        index.push_back(static_cast<int>(p) + 1);
        value.push_back(-1.0);
      }
      const int r = first + static_cast<int>(k);
      glp_set_row_bnds(lp, r, GLP_UP, 0.0, 0.0);
      glp_set_mat_row(lp, r, static_cast<int>(index.size()) - 1, index.data(), value.data());
    }
    simplex.meth = GLP_DUALP;
    simplex.tm_lim = milliseconds_left(start, time_limit);
    if (glp_simplex(lp, &simplex) != 0 || glp_get_status(lp) != GLP_OPT) {
      return finish(lp_bound, initial_saved);
    }
    lp_bound = glp_get_obj_val(lp);
  }

  std::vector<double> start_values;
  SearchState state;
  if (!initial.empty()) {
    start_values.assign(nb_cols + 1, 0.0);
    for (index_t ci : initial) start_values[ci + 1] = 1.0;
    state.initial = &start_values;
  }
  glp_iocp search = search_parameters(milliseconds_left(start, time_limit), state);
  const int status = glp_intopt(lp, &search);
  const int mip = glp_mip_status(lp);

  std::size_t best_saved = initial_saved;
  if (mip == GLP_OPT || mip == GLP_FEAS) {
    const std::size_t found = whole_savings(glp_mip_obj_val(lp) + 0.5);
    if (found > best_saved) {
      best_saved = found;
      result.best.clear();
      for (int j = 1; j <= nb_cols; ++j) {
        if (glp_mip_col_val(lp, j) > 0.5) result.best.push_back(static_cast<index_t>(j - 1));
      }
    }
  }
  if (status == 0 && mip == GLP_OPT) {
    result.proved = true;
    return finish(static_cast<double>(best_saved), best_saved);
  }
  return finish(std::min(lp_bound, state.best_bound), best_saved);
#endif
}

VolumeBound bound_hex_volume(const TetMesh& mesh, const Candidates& candidates, double time_limit) {
  HEXMERGE_ASSERT(time_limit > 0.0, "bound_hex_volume: the time limit must be positive");
#ifndef HEXMERGE_WITH_GLPK
  static_cast<void>(mesh);
  static_cast<void>(candidates);
  require_selection_bound();
  return {};
#else
  const auto start = Clock::now();
  const QuietTerminal quiet;
  std::vector<double> volume_of(mesh.nb_tets());
  double mesh_volume = 0.0;
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* v = mesh.tet(t);
    volume_of[t] =
        tet_volume(mesh.point(v[0]), mesh.point(v[1]), mesh.point(v[2]), mesh.point(v[3]));
    mesh_volume += volume_of[t];
  }
  std::vector<TetSpan> columns;
  std::vector<double> weights;
  for (const Candidate& c : candidates) {
    if (c.type != CellType::Hex) continue;
    double volume = 0.0;
    for (const index_t t : candidates.tets(c)) volume += volume_of[t];
    columns.push_back(candidates.tets(c));
    weights.push_back(volume / mesh_volume);
  }
  VolumeBound result;
  result.hexahedra = columns.size();
  const auto finish = [&] {
    result.seconds = seconds_since(start);
    return result;
  };
  if (columns.empty()) {
    result.proved = true;
    return finish();
  }
  std::unique_ptr<glp_prob, ProblemDeleter> problem(glp_create_prob());
  glp_prob* lp = problem.get();
  load_packing(lp, mesh.nb_tets(), columns, weights);
  const glp_smcp simplex = simplex_parameters(milliseconds_left(start, time_limit));
  if (glp_simplex(lp, &simplex) != 0 || glp_get_status(lp) != GLP_OPT) {
    // No LP optimum in time: every hexahedron at once still bounds it.
    result.bound = 0.0;
    for (double w : weights) result.bound += w;
    result.bound = std::min(result.bound, 1.0);
    return finish();
  }
  result.bound = glp_get_obj_val(lp);
  SearchState state;
  glp_iocp search = search_parameters(milliseconds_left(start, time_limit), state);
  const int status = glp_intopt(lp, &search);
  const int mip = glp_mip_status(lp);
  if (mip == GLP_OPT || mip == GLP_FEAS) result.best = glp_mip_obj_val(lp);
  if (status == 0 && mip == GLP_OPT) {
    result.proved = true;
    result.bound = result.best;
  } else {
    result.bound = std::min(result.bound, state.best_bound);
  }
  return finish();
#endif
}

}  // namespace hexmerge
