// Seeded random-mutation fuzzer of the engine's entry points: validate_tet_mesh, TetTopology,
// recombine (every finder and conformity mode, options drawn inside their documented ranges) and
// check_mesh. Each run takes a seed mesh of the corpus, mutates it (moved, coincident or NaN
// nodes, swapped or out-of-range vertex ids, dropped or doubled tets, flattened tets, scaling by
// 1e-120 .. 1e120, far translations, regions), and asserts what the library promises:
//   - bad input ends in InputError, never another exception or a crash (the sanitizers and
//     -D_GLIBCXX_ASSERTIONS catch undefined behaviour in the build scripts/fuzz.sh makes);
//   - an accepted input gives a mesh check_mesh calls valid, with no cell whose scaled
//     Jacobian is not positive, and (conforming mode) no non-conforming quad left.
// Deterministic: run i uses seed (base seed, i); a failure prints the command that repeats it.
//
// Usage: hexmerge_fuzz CORPUS_DIR [--seconds S] [--runs N] [--seed BASE] [--only RUN]
//                      [--verbose] [--dump FILE]   (--dump: the last run's mutated mesh, in the
//                                                   corpus format, for a closer look)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "hexmerge/check/check_mesh.h"
#include "hexmerge/core/error.h"
#include "hexmerge/mesh/tet_mesh.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/recombine/parameters.h"
#include "hexmerge/recombine/recombine.h"

namespace fs = std::filesystem;
using namespace hexmerge;

namespace {

// A corpus mesh: "points N" then N lines "x y z", "tets M" then M lines "a b c d [region]";
// lines starting with '#' are comments.
TetMesh read_corpus_mesh(const fs::path& path) {
  std::ifstream in(path);
  TetMesh mesh;
  std::string word;
  std::size_t n = 0, m = 0;
  bool with_regions = false;
  while (in >> word) {
    if (word[0] == '#') {
      std::getline(in, word);
    } else if (word == "points") {
      in >> n;
      mesh.points.resize(3 * n);
      for (double& c : mesh.points) in >> c;
    } else if (word == "tets") {
      in >> m >> std::ws;
      std::string line;
      for (std::size_t t = 0; t < m && std::getline(in, line); ++t) {
        std::istringstream row(line);
        index_t q[4];
        row >> q[0] >> q[1] >> q[2] >> q[3];
        mesh.tets.insert(mesh.tets.end(), q, q + 4);
        std::int32_t r = 0;
        if (row >> r) with_regions = true;
        mesh.regions.push_back(r);
      }
    }
  }
  if (!in.eof() || mesh.points.size() != 3 * n || mesh.tets.size() != 4 * m || n == 0 || m == 0) {
    std::fprintf(stderr, "%s: not a corpus mesh\n", path.c_str());
    std::exit(2);
  }
  if (!with_regions) mesh.regions.clear();
  return mesh;
}

void write_corpus_mesh(const std::string& path, const TetMesh& mesh, const std::string& note) {
  std::ofstream out(path);
  out.precision(17);
  out << "# " << note << "\npoints " << mesh.nb_vertices() << "\n";
  for (index_t v = 0; v < mesh.nb_vertices(); ++v) {
    out << mesh.point(v)[0] << " " << mesh.point(v)[1] << " " << mesh.point(v)[2] << "\n";
  }
  out << "tets " << mesh.nb_tets() << "\n";
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    const index_t* q = mesh.tet(t);
    out << q[0] << " " << q[1] << " " << q[2] << " " << q[3];
    if (!mesh.regions.empty()) out << " " << mesh.regions[t];
    out << "\n";
  }
}

struct Fuzzer {
  std::mt19937_64 rng;
  std::vector<std::string> log;  // the mutations and options of this run

  std::size_t pick(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

  // Whether vertex id v of a tet names a node (an earlier mutation may have put any id there).
  static bool names_a_node(const TetMesh& mesh, index_t v) { return v < mesh.nb_vertices(); }

  // The length of tet 0's first edge (mutate() calls it with a tet left); NaN where an earlier
  // mutation gave that edge a vertex id out of range (reading that node overran the points, run
  // 15619 of seed 20261203).
  double edge_scale(const TetMesh& mesh) {
    const index_t* q = mesh.tet(0);
    if (!names_a_node(mesh, q[0]) || !names_a_node(mesh, q[1])) return std::nan("");
    double d = 0.0;
    for (int c = 0; c < 3; ++c) d += std::pow(mesh.point(q[1])[c] - mesh.point(q[0])[c], 2);
    return std::sqrt(d);
  }

  void mutate(TetMesh& mesh) {
    const index_t nv = mesh.nb_vertices();
    const index_t nt = mesh.nb_tets();
    if (nt == 0 || nv == 0) return;  // nothing left to pick from
    double h = edge_scale(mesh);
    if (!(std::isfinite(h) && h > 0.0)) h = 1.0;  // after a non-finite or coincident node
    switch (pick(13)) {
      case 0: {  // small or large move of one node
        const index_t v = pick(nv);
        const double amp = h * std::pow(10.0, uniform(-6.0, 0.0));
        for (int c = 0; c < 3; ++c) mesh.points[3 * v + c] += uniform(-amp, amp);
        log.push_back("move node " + std::to_string(v) + " by up to " + std::to_string(amp));
        break;
      }
      case 1: {  // uniform scale, any magnitude a double holds
        const double s = std::pow(10.0, std::round(uniform(-120.0, 120.0)));
        for (double& c : mesh.points) c *= s;
        log.push_back("scale by " + std::to_string(std::log10(s)) + " decades");
        break;
      }
      case 2: {  // far translation
        const double o = std::pow(10.0, uniform(0.0, 9.0)) * h;
        for (std::size_t i = 0; i < mesh.points.size(); i += 3) mesh.points[i] += o;
        log.push_back("translate by " + std::to_string(o));
        break;
      }
      case 3: {  // inverted tet
        const index_t t = pick(nt);
        std::swap(mesh.tets[4 * t], mesh.tets[4 * t + 1]);
        log.push_back("invert tet " + std::to_string(t));
        break;
      }
      case 4: {  // vertex id anywhere, in range or not
        const index_t t = pick(nt);
        const index_t v = static_cast<index_t>(pick(nv + 3));
        mesh.tets[4 * t + pick(4)] = v;
        log.push_back("tet " + std::to_string(t) + " gets node " + std::to_string(v));
        break;
      }
      case 5: {  // drop a tet (a hole, maybe a non-manifold boundary)
        if (nt < 2) break;
        const index_t t = pick(nt);
        mesh.tets.erase(mesh.tets.begin() + 4 * t, mesh.tets.begin() + 4 * t + 4);
        if (!mesh.regions.empty()) mesh.regions.erase(mesh.regions.begin() + t);
        log.push_back("drop tet " + std::to_string(t));
        break;
      }
      case 6: {  // doubled tet, vertices rotated (same orientation)
        const index_t t = pick(nt);
        const index_t* q = mesh.tet(t);
        const index_t rotated[4] = {q[1], q[2], q[0], q[3]};
        mesh.tets.insert(mesh.tets.end(), rotated, rotated + 4);
        if (!mesh.regions.empty()) mesh.regions.push_back(mesh.regions[t]);
        log.push_back("double tet " + std::to_string(t));
        break;
      }
      case 7: {  // a node onto another
        const index_t a = pick(nv), b = pick(nv);
        for (int c = 0; c < 3; ++c) mesh.points[3 * a + c] = mesh.points[3 * b + c];
        log.push_back("node " + std::to_string(a) + " onto node " + std::to_string(b));
        break;
      }
      case 8: {  // flatten a tet: its last vertex onto the plane of the other three (to round-off)
        const index_t t = pick(nt);
        const index_t* q = mesh.tet(t);
        if (!std::all_of(q, q + 4, [&](index_t v) { return names_a_node(mesh, v); })) break;
        double p[3][3], *d = &mesh.points[3 * q[3]];
        for (int i = 0; i < 3; ++i)
          for (int c = 0; c < 3; ++c) p[i][c] = mesh.point(q[i])[c];
        const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const double w[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                       u[0] * w[1] - u[1] * w[0]};
        const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (!(nn > 0.0)) break;
        const double k =
            ((d[0] - p[0][0]) * n[0] + (d[1] - p[0][1]) * n[1] + (d[2] - p[0][2]) * n[2]) / nn;
        for (int c = 0; c < 3; ++c) d[c] -= k * n[c];
        log.push_back("flatten tet " + std::to_string(t));
        break;
      }
      case 9: {  // regions
        mesh.regions.assign(mesh.nb_tets(), 0);
        const int nr = 1 + static_cast<int>(pick(3));
        const int axis = static_cast<int>(pick(3));
        for (index_t t = 0; t < mesh.nb_tets(); ++t) {
          const index_t v = mesh.tet(t)[0];
          const double x = names_a_node(mesh, v) ? mesh.point(v)[axis] : NAN;
          const double slab = std::fmod(std::fabs(x / h), nr);  // NaN for a NaN node
          mesh.regions[t] = std::isfinite(slab) ? static_cast<std::int32_t>(slab) : 0;
        }
        log.push_back("regions: " + std::to_string(nr) + " slabs along axis " +
                      std::to_string(axis));
        break;
      }
      case 10: {  // NaN or infinite coordinate
        const index_t v = pick(nv);
        mesh.points[3 * v + pick(3)] = pick(2) ? NAN : INFINITY;
        log.push_back("non-finite node " + std::to_string(v));
        break;
      }
      case 11: {  // one axis stretched
        const int axis = static_cast<int>(pick(3));
        const double s = std::pow(10.0, uniform(-8.0, 8.0));
        for (std::size_t i = axis; i < mesh.points.size(); i += 3) mesh.points[i] *= s;
        log.push_back("stretch axis " + std::to_string(axis) + " by " + std::to_string(s));
        break;
      }
      default: {  // small random jitter of every node (stays valid most of the time)
        const double amp = h * 0.05;
        for (double& c : mesh.points) c += uniform(-amp, amp);
        log.push_back("jitter every node by 5 %");
        break;
      }
    }
  }

  RecombineParameters parameters() {
    RecombineParameters p;
    auto set = [&](const std::string& name, const std::string& value) {
      set_parameter(p, name, value);
      log.push_back(name + "=" + value);
    };
    if (pick(3) == 0) return p;  // the defaults, often
    const char* conformity[] = {"conforming", "last_resort", "allow"};
    set("conformity", conformity[pick(3)]);
    set("finder", pick(2) ? "programs" : "exhaustive");
    if (pick(2)) set("min_dihedral_angle", std::to_string(uniform(90.0, 180.0)));
    if (pick(2)) set("min_boundary_dihedral_angle", std::to_string(uniform(90.0, 180.0)));
    if (pick(2)) set("max_face_angle", std::to_string(uniform(90.0, 180.0)));
    if (pick(2)) set("min_scaled_jacobian", std::to_string(uniform(-1.0, 1.0)));
    if (pick(4) == 0) set("make_pyramids", "false");
    if (pick(4) == 0) set("make_prisms", "false");
    if (pick(4) == 0) set("respect_regions", "false");
    if (pick(4) == 0) set("local_search_radius", std::to_string(pick(3)));
    set("threads", std::to_string(1 + pick(3)));
    return p;
  }
};

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : "; ") + i;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s CORPUS_DIR [--seconds S] [--runs N] [--seed BASE] [--only RUN] "
                 "[--verbose]\n",
                 argv[0]);
    return 2;
  }
  double seconds = 60.0;
  long runs = -1, only = -1;
  unsigned long long base = 1;
  bool verbose = false;
  std::string dump;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else if (a == "--runs" && i + 1 < argc)
      runs = std::atol(argv[++i]);
    else if (a == "--seed" && i + 1 < argc)
      base = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--only" && i + 1 < argc)
      only = std::atol(argv[++i]);
    else if (a == "--verbose")
      verbose = true;
    else if (a == "--dump" && i + 1 < argc)
      dump = argv[++i];
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(argv[1])) {
    if (entry.path().extension() == ".tets") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::fprintf(stderr, "%s: no .tets file\n", argv[1]);
    return 2;
  }
  std::vector<TetMesh> corpus;
  for (const auto& f : files) corpus.push_back(read_corpus_mesh(f));

  const auto start = std::chrono::steady_clock::now();
  long done = 0, refused = 0, failures = 0;
  for (long run = only >= 0 ? only : 0;; ++run) {
    if (only >= 0 && run > only) break;
    if (only < 0) {
      if (runs >= 0 && done >= runs) break;
      if (runs < 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
              seconds) {
        break;
      }
    }
    Fuzzer fz{std::mt19937_64(base * 1000003ull + static_cast<unsigned long long>(run)), {}};
    const std::size_t which = fz.pick(corpus.size());
    TetMesh mesh = corpus[which];
    fz.log.push_back(files[which].filename().string());
    const int nb_mutations = static_cast<int>(fz.pick(3));
    for (int i = 0; i < nb_mutations; ++i) fz.mutate(mesh);
    const RecombineParameters parameters = fz.parameters();
    if (!dump.empty()) write_corpus_mesh(dump, mesh, joined(fz.log));
    ++done;
    std::string failure;
    try {
      RecombineReport report;
      const MixedMesh out = recombine(mesh, parameters, report);
      CheckReport check = check_mesh(out, mesh);
      if (!parameters.respect_regions) check.region_mismatches = 0;  // merging across is asked
      if (!check.valid()) {
        failure = "the output is invalid: " + (check.problems.empty() ? "" : check.problems[0]);
      } else if (parameters.conformity == Conformity::Conforming && check.nonconforming_quads) {
        failure =
            std::to_string(check.nonconforming_quads) + " non-conforming quads in conforming mode";
      }
      if (verbose) std::printf("run %ld: %u cells\n", run, static_cast<unsigned>(out.nb_cells()));
    } catch (const InputError& e) {
      ++refused;
      if (verbose) std::printf("run %ld: refused: %s\n", run, e.what());
    } catch (const std::exception& e) {
      failure = std::string("exception: ") + e.what();
    }
    if (!failure.empty()) {
      ++failures;
      std::printf("FAIL run %ld (%s): %s\n  repeat: %s %s --seed %llu --only %ld --verbose\n", run,
                  joined(fz.log).c_str(), failure.c_str(), argv[0], argv[1], base, run);
      std::fflush(stdout);
      if (failures >= 5) break;
    }
  }
  std::printf("hexmerge_fuzz: %ld runs (%ld refused as bad input), %ld failures, %.0f s\n", done,
              refused, failures,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return failures ? 1 : 0;
}
