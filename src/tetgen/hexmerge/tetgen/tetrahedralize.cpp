#include "hexmerge/tetgen/tetrahedralize.h"

#include <sys/wait.h>

#include <algorithm>
#include <charconv>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <type_traits>
#include <unordered_set>

#include "hexmerge/core/error.h"
#include "hexmerge/tetgen/triangulate_facets.h"

namespace hexmerge::tetgen {
namespace {

namespace fs = std::filesystem;

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string find_program(const std::string& name) {
  if (name.find('/') != std::string::npos) return fs::exists(name) ? name : std::string();
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  return std::string();
}

// Why a TetGen run failed, in a sentence: how it ended (exit code or signal), the reason it
// printed (its progress lines and crash text, such as "terminate called", left out) and the
// facets' markers (the shape's faces + 1) of the points it names in brackets.
std::string failure_text(int status, const fs::path& log, const std::vector<Facet>& facets) {
  // std::system runs a shell, which reports a child killed by signal N as exit code 128 + N.
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : code > 128 ? code - 128 : 0;
  std::string how;
  if (signal == SIGSEGV)
    how = "TetGen crashed (segmentation fault)";
  else if (signal == SIGABRT)
    how = "TetGen stopped on an internal error";
  else if (signal == SIGKILL)
    how = "TetGen was killed (out of memory?)";
  else if (signal != 0)
    how = "TetGen ended on signal " + std::to_string(signal);
  else if (code != 0)
    how = "TetGen failed with exit code " + std::to_string(code);
  else
    how = "TetGen wrote no tets";
  std::ifstream in(log);
  std::string line, reason;
  while (std::getline(in, line) && reason.size() < 300) {
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    line = line.substr(first);
    const bool progress = line.find("seconds:") != std::string::npos ||
                          (line.size() >= 3 && line.compare(line.size() - 3, 3, "...") == 0);
    if (progress) line.clear();
    for (const char* noise : {"Opening ", "terminate called", "Aborted", "Segmentation fault",
                              "Killed", "timeout:", "stdbuf:"})
      if (line.rfind(noise, 0) == 0) line.clear();
    // An assertion names TetGen's source file and function: it is said in our words.
    if (line.find("Assertion") != std::string::npos) line = "an internal consistency check failed";
    if (line.rfind("Error:", 0) == 0)
      line = line.substr(std::min(line.size(), line.find_first_not_of(' ', 6)));
    if (!line.empty()) reason += (reason.empty() ? "" : " ") + line;
  }
  if (reason.empty()) return how;
  // The faces (markers - 1) that hold all the points of each bracketed group.
  std::vector<std::vector<int>> markers_of;
  for (const Facet& f : facets)
    for (const auto& polygon : f.polygons)
      for (int v : polygon) {
        if (v < 0) continue;
        if (static_cast<std::size_t>(v) >= markers_of.size()) markers_of.resize(v + 1);
        auto& list = markers_of[v];
        if (std::find(list.begin(), list.end(), f.marker) == list.end()) list.push_back(f.marker);
      }
  std::vector<int> faces;
  for (std::size_t open = reason.find('['); open != std::string::npos;
       open = reason.find('[', open + 1)) {
    const std::size_t close = reason.find(']', open);
    if (close == std::string::npos) break;
    std::string group = reason.substr(open + 1, close - open - 1);
    std::replace(group.begin(), group.end(), ',', ' ');
    std::istringstream ids(group);
    std::vector<int> common;
    bool first = true;
    for (long v; ids >> v;) {
      if (v < 0 || static_cast<std::size_t>(v) >= markers_of.size()) {
        common.clear();
        break;
      }
      std::vector<int> next;
      for (int m : markers_of[v])
        if (first || std::find(common.begin(), common.end(), m) != common.end()) next.push_back(m);
      common = next;
      first = false;
    }
    for (int m : common)
      if (std::find(faces.begin(), faces.end(), m - 1) == faces.end()) faces.push_back(m - 1);
  }
  std::string where;
  for (std::size_t k = 0; k < faces.size(); ++k)
    where += (k == 0 ? "" : k + 1 == faces.size() ? " and " : ", ") + std::to_string(faces[k]);
  return how + " (it reports: " + reason + ")" +
         (faces.empty()
              ? ""
              : std::string(faces.size() > 1 ? "; faces " : "; face ") + where + " of the shape");
}

// Whether TetGen's log ends in its surface meshing stage (the last progress line is "Creating
// surface mesh ..."): where TetGen 1.5.0 triangulates the lattice faces from their loops.
bool failed_in_surface_mesh(const fs::path& log) {
  std::ifstream in(log);
  std::string line, stage;
  while (std::getline(in, line)) {
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos || first > 0) continue;  // stages start in column 0
    if (line.size() >= 3 && line.compare(line.size() - 3, 3, "...") == 0) stage = line;
  }
  return stage.rfind("Creating surface mesh", 0) == 0;
}

// Reads a TetGen output table (.node, .ele or .face, 0-based with -z): a header "count header
// ...", then per line an id and `columns` values; '#' starts a comment. The header's second
// number is `header`: the values per row of .node (3) and .ele (4), the marker flag of .face
// (1: three vertices and a marker per row). Returns count * columns values.
template <typename T>
std::vector<T> read_tetgen_table(const fs::path& path, int header, int columns) {
  // The whole file at once, then its lines parsed in place (std::from_chars: the same values as
  // a stream's, correctly rounded, and ten times faster on a million tets).
  std::ifstream in(path, std::ios::binary);
  const std::string name = path.filename().string();
  if (!in) throw InputError("TetGen wrote no " + name);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  long long n = -1, width = 0;
  std::vector<T> values;
  const char* const end = text.data() + text.size();
  for (const char* line = text.data(); line < end;) {
    const char* line_end = static_cast<const char*>(std::memchr(line, '\n', end - line));
    if (!line_end) line_end = end;
    const char* stop = static_cast<const char*>(std::memchr(line, '#', line_end - line));
    if (!stop) stop = line_end;
    const char* at = line;
    // The next number of the line into x; false when there is none.
    const auto next = [&](auto& x) {
      while (at < stop && (*at == ' ' || *at == '\t' || *at == '\r')) ++at;
      if (at < stop && *at == '+') ++at;
      const auto [ptr, ec] = std::from_chars(at, stop, x);
      if (ec != std::errc() || (ptr < stop && *ptr != ' ' && *ptr != '\t' && *ptr != '\r'))
        return false;
      at = ptr;
      return true;
    };
    const std::string_view row(line, static_cast<std::size_t>(line_end - line));
    line = line_end + 1;
    if (n < 0) {
      if (!next(n) || !next(width)) {
        n = -1;
        continue;
      }
      if (width != header)
        throw InputError("TetGen's " + name + " has " + std::to_string(width) +
                         " in its header, not " + std::to_string(header));
      values.reserve(static_cast<std::size_t>(n) * columns);
      continue;
    }
    long long id;
    if (!next(id)) continue;
    for (int k = 0; k < columns; ++k) {
      T x;
      if (!next(x)) throw InputError("TetGen's " + name + " has a short row: " + std::string(row));
      values.push_back(x);
    }
  }
  if (n < 0 || static_cast<long long>(values.size()) != columns * n)
    throw InputError("TetGen's " + name + " is truncated");
  return values;
}

// A temporary directory removed on destruction (unless kept).
class WorkDirectory {
 public:
  explicit WorkDirectory(const std::string& requested) {
    if (!requested.empty()) {
      path_ = requested;
      fs::create_directories(path_);
      keep_ = true;
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "hexmerge-mesh-XXXXXX").string();
    if (!mkdtemp(pattern.data()))
      throw InputError("cannot create a temporary directory for TetGen");
    path_ = pattern;
  }
  ~WorkDirectory() {
    std::error_code ec;
    if (!keep_) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool keep_ = false;
};

}  // namespace

Tetrahedralizer::Tetrahedralizer(const TetrahedralizeParameters& parameters)
    : parameters_(parameters), program_(find_program(parameters.program)) {
  if (program_.empty())
    throw InputError("TetGen is needed: \"" + parameters.program +
                         "\" is not found (Debian: apt install tetgen)",
                     Entity::Parameter);
}

// TetGen: the surface kept as it is (-pY), the facets' single points with it, the isolated
// points as isolated vertices of the PLC, 0-based (-z), quiet (-Q). Given to -i instead, TetGen
// 1.5 inserted them after the boundary recovery and left non-Delaunay tets in the degenerate
// (cospherical) lattice: a closing pyramid's apex joined to the far corner of the core cell
// behind it (bracket h 1.40: two core faces without closer, 89.5 % hex volume).
TetrahedralizeOutput Tetrahedralizer::run(TetrahedralizeInput input) const {
  std::vector<Vec3>& points = input.points;
  std::vector<Facet>& facets = input.facets;
  const auto to_world = [&](const Vec3& p) { return input.to_world ? input.to_world(p) : p; };
  TetrahedralizeOutput output;
  WorkDirectory work(parameters_.work_directory);
  // No facets: the points alone, in a .node file (TetGen's Delaunay tetrahedralisation).
  const bool delaunay = facets.empty();
  // The facets with loops go to TetGen as triangles (triangulate_facets.h: its own flips on
  // them did not end), cocircular points joined as in TetGen's Delaunay tetrahedralisation of
  // the points (a run of its own, about a tenth of the whole); one it cannot take stays a loop,
  // for the restarts below.
  if (std::any_of(facets.begin(), facets.end(), has_loop)) {
    TetrahedralizeParameters alone = parameters_;
    alone.work_directory.clear();
    TetrahedralizeInput points_alone;
    points_alone.points = points;
    const TetrahedralizeOutput tets = Tetrahedralizer(alone).run(std::move(points_alone));
    // Only sides between points of those facets are asked about.
    std::vector<char> on_loop(points.size(), 0);
    for (const Facet& f : facets)
      if (has_loop(f))
        for (const auto& polygon : f.polygons)
          for (const int v : polygon) on_loop[static_cast<std::size_t>(v)] = 1;
    std::unordered_set<std::uint64_t> sides;
    for (std::size_t t = 0; t < tets.tets.size(); t += 4)
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) {
          const auto u = static_cast<int>(tets.tets[t + a]), w = static_cast<int>(tets.tets[t + b]);
          if (on_loop[static_cast<std::size_t>(u)] && on_loop[static_cast<std::size_t>(w)])
            sides.insert(side_key(u, w));
        }
    triangulate_facets(facets, points, &sides);
  }
  const fs::path poly = work.path() / (delaunay ? "shape.node" : "shape.poly");
  auto write_poly = [&] {
    // Formatted into one buffer (std::to_chars: the text of a stream at precision 17, "%.17g").
    std::string text;
    text.reserve(points.size() * 64 + facets.size() * 32);
    char number[64];
    const auto put = [&](auto x) {
      std::to_chars_result r;
      if constexpr (std::is_floating_point_v<decltype(x)>)
        r = std::to_chars(number, number + sizeof number, x, std::chars_format::general, 17);
      else
        r = std::to_chars(number, number + sizeof number, x);
      text.append(number, r.ptr);
    };
    put(points.size());
    text += " 3 0 0\n";
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3& p = points[i];
      put(i), text += ' ', put(p.x), text += ' ', put(p.y), text += ' ', put(p.z), text += '\n';
    }
    if (!delaunay) {
      put(facets.size());
      text += " 1\n";
      for (const Facet& f : facets) {
        put(f.polygons.size()), text += ' ', put(f.holes.size()), text += ' ', put(f.marker);
        text += '\n';
        for (const auto& polygon : f.polygons) {
          put(polygon.size());
          for (int v : polygon) text += ' ', put(v);
          text += '\n';
        }
        for (std::size_t i = 0; i < f.holes.size(); ++i) {
          put(i + 1), text += ' ', put(f.holes[i].x), text += ' ', put(f.holes[i].y);
          text += ' ', put(f.holes[i].z), text += '\n';
        }
      }
      text += "0\n0\n";
    }
    std::ofstream out(poly, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out) throw InputError("cannot write TetGen's input in " + work.path().string());
  };

  write_poly();
  const fs::path log = work.path() / "tetgen.log";
  // Not quiet: on failure, its last lines say why (read by failure_text()).
  const std::string switches =
      std::string(delaunay ? " -z" : " -pYz") + (parameters_.quality ? "q1.5 " : " ");
  output.command = shell_quote(program_) + switches + shell_quote(poly.string());
  const std::size_t given = points.size();
  std::vector<double> frame_points;
  // TetGen 1.5 can fail to triangulate a lattice face from its loops: it never ends, or leaves
  // the face with a gap and every tet counted as outside, or stops in its surface meshing
  // ("Invalid PLC. Two segments ... intersect" or a failed assertion on a valid face: thin
  // bracket at h 0.6, a base face with a slot, fails or not with the loop's first vertex). Nearly
  // collinear loop nodes did it (align_straight_edges() now prevents that), and whether it
  // happened depended on the vertex the loop started at; cocircular nodes on straight sides
  // too (its flips never end), which triangulate_facets() now takes away. So TetGen runs under
  // a time limit, far above its own time (about 1 s per 20k points), and after such a failure
  // the loops left start elsewhere.
  const double time_limit = parameters_.time_limit > 0
                                ? parameters_.time_limit
                                : 30 + 1e-3 * static_cast<double>(points.size());
  std::ostringstream limit_text;
  limit_text << time_limit;
  // TetGen's output line-buffered, so that its reason survives an abort.
  const std::string limited = "timeout -k 5 " + limit_text.str() + " stdbuf -oL ";
  const bool has_loops = std::any_of(facets.begin(), facets.end(), has_loop);
  int restarts = 0;
  const auto start_loops_elsewhere = [&] {
    for (Facet& facet : facets)
      for (auto& polygon : facet.polygons)
        if (polygon.size() > 3)
          std::rotate(
              polygon.begin(),
              polygon.begin() + static_cast<std::ptrdiff_t>(
                                    (7919u * static_cast<unsigned>(restarts)) % polygon.size()),
              polygon.end());
    ++output.nb_restarts;
    write_poly();
  };
  std::vector<long long> ele;  // TetGen's tets, 4 per tet
  for (bool nudged = false;;) {
    const int status = std::system(
        (limited + output.command + " > " + shell_quote(log.string()) + " 2>&1").c_str());
    const bool timed_out = WIFEXITED(status) && WEXITSTATUS(status) == 124;
    if (timed_out || (status == 0 && !fs::exists(work.path() / "shape.1.ele"))) {
      // With no loop left, the same input would fail in the same way.
      if (!has_loops || ++restarts > parameters_.restarts)
        throw TetrahedralizeFailure(
            std::string("TetGen ") +
            (timed_out ? "did not finish within " + limit_text.str() + " s"
                       : "lost the shape's surface (no tets inside)") +
            (has_loops ? ", " + std::to_string(restarts) +
                             " times with the lattice faces' loops started at other vertices"
                       : std::string()));
      start_loops_elsewhere();
      continue;
    }
    if (status != 0 && has_loops && restarts < parameters_.restarts &&
        failed_in_surface_mesh(log)) {
      ++restarts;
      start_loops_elsewhere();
      continue;
    }
    if (status != 0 || !fs::exists(work.path() / "shape.1.ele"))
      throw TetrahedralizeFailure(failure_text(status, log, facets));
    frame_points = read_tetgen_table<double>(work.path() / "shape.1.node", 3, 3);
    // TetGen now and then leaves a point of the regular lattice out (degenerate: all
    // cospherical): missing from its .node (which breaks the numbering) or in no tet. The points
    // left out move by 1e-7 h (they stay on the lattice for everything below) and TetGen runs
    // once more.
    std::vector<std::size_t> dropped;
    // TetGen keeps the points' order, but merges points within its tolerance and leaves out
    // points it cannot insert, which shifts the numbering after them.
    bool same_numbering = frame_points.size() / 3 >= given;
    for (std::size_t i = 0; i < given && same_numbering; ++i)
      same_numbering = (Vec3::of(&frame_points[3 * i]) - points[i]).norm() <= parameters_.tolerance;
    if (same_numbering) {
      std::vector<char> used(given, 0);
      ele = read_tetgen_table<long long>(work.path() / "shape.1.ele", 4, 4);
      for (long long v : ele)
        if (v >= 0 && v < static_cast<long long>(given)) used[v] = 1;
      for (std::size_t i = 0; i < given; ++i)
        if (!used[i]) dropped.push_back(i);
      if (dropped.empty()) break;
    } else {
      // Found by their coordinates: TetGen keeps the others in order.
      for (std::size_t i = 0, j = 0; i < given; ++i) {
        const Vec3 p = points[i];
        if (j < frame_points.size() / 3 &&
            (Vec3::of(&frame_points[3 * j]) - p).norm() <= parameters_.tolerance)
          ++j;
        else
          dropped.push_back(i);
      }
    }
    std::string which;
    for (std::size_t i : dropped) {
      const Vec3 p = to_world(points[i]);
      which += " " + std::to_string(i) + " at (" + std::to_string(p.x) + ", " +
               std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
    }
    if (nudged || dropped.empty() || dropped.front() < input.first_isolated || delaunay)
      throw TetrahedralizeFailure(
          "TetGen left out " + std::to_string(dropped.size()) +
          " of the points given (too close together or to a face):" + which);
    for (std::size_t i : dropped) points[i] = points[i] + Vec3{1.0, 0.7, 0.3} * parameters_.nudge;
    output.nb_nudged += dropped.size();
    nudged = true;
    write_poly();
  }

  // (The loop leaves only where the numbering held, with the run's tets read.)
  for (long long v : ele) {
    if (v < 0 || v >= static_cast<long long>(frame_points.size() / 3))
      throw TetrahedralizeFailure("TetGen's tets refer to a node it did not write");
    output.tets.push_back(static_cast<index_t>(v));
  }
  // The boundary faces and the facets' markers they carry.
  // (With no facets: the convex hull's triangles, marker 0.)
  const int per_face = delaunay ? 3 : 4;
  const std::vector<long long> faces =
      read_tetgen_table<long long>(work.path() / "shape.1.face", delaunay ? 0 : 1, per_face);
  for (std::size_t i = 0; i + per_face - 1 < faces.size(); i += per_face) {
    output.boundary.push_back({static_cast<index_t>(faces[i]), static_cast<index_t>(faces[i + 1]),
                               static_cast<index_t>(faces[i + 2])});
    output.boundary_marker.push_back(delaunay ? 0 : static_cast<int>(faces[i + 3]));
  }
  output.points = std::move(frame_points);
  return output;
}

}  // namespace hexmerge::tetgen
