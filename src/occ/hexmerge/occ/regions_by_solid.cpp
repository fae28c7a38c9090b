#include "hexmerge/occ/regions_by_solid.h"

#include <BRepBndLib.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepGProp.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <gp_Pnt.hxx>
#include <map>
#include <memory>
#include <numeric>
#include <thread>

#include "hexmerge/core/error.h"
#include "hexmerge/core/parallel.h"
#include "hexmerge/mesh/tet_topology.h"
#include "hexmerge/occ/brep_text.h"

namespace hexmerge {
namespace {

using Clock = PhaseTimer::Clock;
const auto seconds_since = PhaseTimer::seconds_since;

// Runs body(begin, end, chunk) over [0, n) in contiguous chunks, at most one per thread, with
// the project's thread helper (core/parallel.h). OpenCASCADE reads one shape from several threads
// safely as long as each thread owns its algorithms (classifiers, projectors): the bodies below
// keep theirs per chunk, and a chunk runs on one thread.
template <class Body>
void parallel_for(std::size_t n, int nb_threads, Body body) {
  const std::size_t threads =
      std::max<std::size_t>(1, std::min<std::size_t>(nb_threads, n / 64 + 1));
  if (threads == 1 || n == 0) {
    body(std::size_t{0}, n, 0);
    return;
  }
  const index_t chunk = static_cast<index_t>((n + threads - 1) / threads);
  parallel_chunks(static_cast<index_t>(n), chunk, static_cast<int>(threads),
                  [&](index_t c, index_t begin, index_t end) {
                    body(std::size_t{begin}, std::size_t{end}, static_cast<int>(c));
                  });
}

Bnd_Box bounding_box(const TopoDS_Shape& shape, double enlarge) {
  Bnd_Box box;
  // Exact geometry, not the stored triangulation: a triangulation of a curved face can lie
  // inside the face's true extent.
  BRepBndLib::Add(shape, box, false);
  box.Enlarge(enlarge);
  return box;
}

// A face of the shape lying between two solids, with what finding mesh nodes on it needs.
struct SharedFace {
  TopoDS_Face face;
  Bnd_Box box;       // enlarged by `tolerance`
  double tolerance;  // distance under which a point lies on the face
};

double area_of(const TopoDS_Face& face, gp_Pnt& centre) {
  GProp_GProps props;
  BRepGProp::SurfaceProperties(face, props);
  centre = props.CentreOfMass();
  return props.Mass();
}

// Faces that two solids share (the same TopoDS face, as BooleanFragments or a CompSolid make
// them) and pairs of coincident faces of different solids (touching solids of a plain compound).
std::vector<SharedFace> shared_faces(const TopTools_IndexedMapOfShape& solids, double tolerance) {
  TopTools_IndexedMapOfShape faces;
  std::vector<std::vector<int>> owners;
  for (int s = 1; s <= solids.Extent(); ++s) {
    TopTools_IndexedMapOfShape of_solid;
    TopExp::MapShapes(solids(s), TopAbs_FACE, of_solid);
    for (int f = 1; f <= of_solid.Extent(); ++f) {
      const int i = faces.Add(of_solid(f));
      if (static_cast<int>(owners.size()) < i) owners.resize(i);
      if (owners[i - 1].empty() || owners[i - 1].back() != s) owners[i - 1].push_back(s);
    }
  }
  const int nb_faces = faces.Extent();
  std::vector<char> shared(nb_faces, 0);
  std::vector<Bnd_Box> boxes(nb_faces);
  for (int f = 0; f < nb_faces; ++f) {
    shared[f] = owners[f].size() >= 2;
    boxes[f] = bounding_box(faces(f + 1), tolerance);
  }
  // Coincident faces: the same bounding box, area and centre of area, different solids.
  std::vector<double> area(nb_faces, -1.0);
  std::vector<gp_Pnt> centre(nb_faces);
  auto measure = [&](int f) {
    if (area[f] < 0) area[f] = area_of(TopoDS::Face(faces(f + 1)), centre[f]);
  };
  for (int a = 0; a < nb_faces; ++a) {
    if (shared[a] || owners[a].size() != 1) continue;
    for (int b = a + 1; b < nb_faces; ++b) {
      if (owners[b].size() != 1 || owners[b][0] == owners[a][0] || boxes[a].IsOut(boxes[b]))
        continue;
      double a0[6], b0[6];
      boxes[a].Get(a0[0], a0[1], a0[2], a0[3], a0[4], a0[5]);
      boxes[b].Get(b0[0], b0[1], b0[2], b0[3], b0[4], b0[5]);
      bool same_box = true;
      for (int k = 0; k < 6; ++k) same_box = same_box && std::abs(a0[k] - b0[k]) <= 2 * tolerance;
      if (!same_box) continue;
      measure(a);
      measure(b);
      if (std::abs(area[a] - area[b]) <= 1e-9 * std::max(area[a], 1.0) &&
          centre[a].Distance(centre[b]) <= 2 * tolerance) {
        shared[a] = shared[b] = 1;
      }
    }
  }
  std::vector<SharedFace> out;
  for (int f = 0; f < nb_faces; ++f) {
    if (!shared[f]) continue;
    const TopoDS_Face face = TopoDS::Face(faces(f + 1));
    const double face_tolerance = tolerance + BRep_Tool::Tolerance(face);
    out.push_back({face, bounding_box(face, face_tolerance), face_tolerance});
  }
  return out;
}

// Marks the mesh nodes lying on a shared face: a bounding-box test, then the projection onto
// the face's surface and the position of the projection in the face's parameter domain.
std::vector<char> interface_nodes(const TetMesh& mesh, const std::vector<SharedFace>& faces,
                                  int nb_threads) {
  std::vector<char> on(mesh.nb_vertices(), 0);
  if (faces.empty()) return on;
  parallel_for(mesh.nb_vertices(), nb_threads, [&](std::size_t begin, std::size_t end, int) {
    // Per thread, built on first use: a face whose box holds none of this thread's nodes costs
    // nothing.
    std::vector<Handle(ShapeAnalysis_Surface)> surfaces(faces.size());
    std::vector<std::unique_ptr<BRepTopAdaptor_FClass2d>> domains(faces.size());
    for (std::size_t v = begin; v < end; ++v) {
      const double* p = mesh.point(static_cast<index_t>(v));
      const gp_Pnt point(p[0], p[1], p[2]);
      for (std::size_t f = 0; f < faces.size() && !on[v]; ++f) {
        if (faces[f].box.IsOut(point)) continue;
        if (surfaces[f].IsNull()) {
          surfaces[f] = new ShapeAnalysis_Surface(BRep_Tool::Surface(faces[f].face));
          domains[f] = std::make_unique<BRepTopAdaptor_FClass2d>(faces[f].face, faces[f].tolerance);
        }
        const gp_Pnt2d uv = surfaces[f]->ValueOfUV(point, faces[f].tolerance);
        if (surfaces[f]->Gap() > faces[f].tolerance) continue;
        on[v] = domains[f]->Perform(uv) != TopAbs_OUT;
      }
    }
  });
  return on;
}

// Connected pieces of tets through the faces that do not lie on the interface: piece[t] in
// [0, nb_pieces).
std::vector<index_t> pieces_of(const TetMesh& mesh, const std::vector<char>& interface,
                               std::size_t& nb_pieces) {
  const TetTopology topology(mesh);
  const index_t m = mesh.nb_tets();
  std::vector<index_t> parent(m);
  std::iota(parent.begin(), parent.end(), index_t{0});
  auto find = [&](index_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (index_t t = 0; t < m; ++t) {
    const index_t* v = mesh.tet(t);
    for (int f = 0; f < 4; ++f) {
      const index_t n = topology.neighbor(t, f);
      if (n == NO_CELL || n < t) continue;
      // Face f is opposite local vertex f: it lies on the interface when its three nodes do.
      bool cut = true;
      for (int k = 0; k < 4 && cut; ++k) cut = k == f || interface[v[k]];
      if (cut) continue;
      const index_t a = find(t), b = find(n);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<index_t> piece(m);
  nb_pieces = 0;
  for (index_t t = 0; t < m; ++t) {
    const index_t r = find(t);
    piece[t] = r == t ? static_cast<index_t>(nb_pieces++) : piece[r];
  }
  return piece;
}

// Point-in-solid queries by tet centroid, with one classifier per solid and thread.
class Classifier {
 public:
  Classifier(const TopTools_IndexedMapOfShape& solids, double tolerance, int nb_threads)
      : tolerance_(tolerance), nb_threads_(nb_threads) {
    for (int s = 1; s <= solids.Extent(); ++s) {
      solids_.push_back(solids(s));
      boxes_.push_back(bounding_box(solids(s), tolerance));
    }
  }

  // solid[i] = the solid holding the centroid of tets[i], or NO_SOLID.
  std::vector<std::int32_t> classify(const TetMesh& mesh, const std::vector<index_t>& tets) {
    std::vector<std::int32_t> solid(tets.size(), NO_SOLID);
    parallel_for(tets.size(), nb_threads_, [&](std::size_t begin, std::size_t end, int) {
      std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>> classifiers(solids_.size());
      for (std::size_t i = begin; i < end; ++i) solid[i] = classify(mesh, tets[i], classifiers);
    });
    queries_ += tets.size();
    return solid;
  }

  std::size_t nb_queries() const { return queries_; }

 private:
  std::int32_t classify(
      const TetMesh& mesh, index_t t,
      std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>>& classifiers) const {
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      const double* p = mesh.point(mesh.tet(t)[k]);
      for (int d = 0; d < 3; ++d) c[d] += 0.25 * p[d];
    }
    const gp_Pnt point(c[0], c[1], c[2]);
    std::int32_t on = NO_SOLID;
    for (std::size_t s = 0; s < solids_.size(); ++s) {
      if (boxes_[s].IsOut(point)) continue;
      if (!classifiers[s])
        classifiers[s] = std::make_unique<BRepClass3d_SolidClassifier>(solids_[s]);
      classifiers[s]->Perform(point, tolerance_);
      const TopAbs_State state = classifiers[s]->State();
      if (state == TopAbs_IN) return static_cast<std::int32_t>(s);
      if (state == TopAbs_ON && on == NO_SOLID) on = static_cast<std::int32_t>(s);
    }
    return on;
  }

  std::vector<TopoDS_Shape> solids_;
  std::vector<Bnd_Box> boxes_;
  double tolerance_;
  int nb_threads_;
  std::size_t queries_ = 0;
};

void check_mesh_arrays(const TetMesh& mesh) {
  if (mesh.points.size() % 3 != 0 || mesh.tets.size() % 4 != 0) {
    throw InputError(
        "the mesh arrays have a size that is not a multiple of 3 (points) or 4 (tets)");
  }
  const index_t n = mesh.nb_vertices();
  for (index_t t = 0; t < mesh.nb_tets(); ++t) {
    for (int k = 0; k < 4; ++k) {
      if (mesh.tet(t)[k] >= n) {
        throw InputError("element " + std::to_string(t) + " refers to node " +
                             std::to_string(mesh.tet(t)[k]) + ", which does not exist",
                         Entity::Element, t);
      }
    }
  }
}

std::vector<std::int32_t> classify_mesh(const std::string& brep, const TetMesh& mesh,
                                        const RegionsBySolidParameters& parameters,
                                        RegionsBySolidReport& report) {
  if (!(parameters.tolerance > 0 && parameters.tolerance <= 0.01)) {
    throw InputError("regions_by_solid: tolerance must be in (0, 0.01]", Entity::Parameter);
  }
  if (parameters.samples_per_piece < 1 || parameters.samples_per_piece > 1000) {
    throw InputError("regions_by_solid: samples_per_piece must be in [1, 1000]", Entity::Parameter);
  }
  check_mesh_arrays(mesh);
  report = RegionsBySolidReport{};
  const int nb_threads = parameters.nb_threads > 0
                             ? parameters.nb_threads
                             : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  auto start = Clock::now();
  const TopoDS_Shape shape = read_brep(brep);
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  if (solids.IsEmpty()) throw InputError("the shape has no solid: regions by solid need solids");
  report.nb_solids = static_cast<std::size_t>(solids.Extent());
  Bnd_Box whole = bounding_box(shape, 0.0);
  const double diagonal = whole.IsVoid() ? 1.0 : std::sqrt(whole.SquareExtent());
  const double tolerance = parameters.tolerance * diagonal;
  add_phase_seconds(report.phase_seconds, "read shape", seconds_since(start));

  const index_t m = mesh.nb_tets();
  std::vector<std::int32_t> region(m, NO_SOLID);
  Classifier classifier(solids, tolerance, nb_threads);
  std::vector<index_t> per_tet;  // the tets classified one by one

  if (parameters.classify_every_tet) {
    per_tet.resize(m);
    std::iota(per_tet.begin(), per_tet.end(), index_t{0});
  } else {
    start = Clock::now();
    const std::vector<SharedFace> faces = shared_faces(solids, tolerance);
    report.nb_shared_faces = faces.size();
    add_phase_seconds(report.phase_seconds, "shared faces", seconds_since(start));

    start = Clock::now();
    const std::vector<char> interface = interface_nodes(mesh, faces, nb_threads);
    report.nb_interface_nodes =
        static_cast<std::size_t>(std::count(interface.begin(), interface.end(), 1));
    add_phase_seconds(report.phase_seconds, "interface nodes", seconds_since(start));

    start = Clock::now();
    const std::vector<index_t> piece = pieces_of(mesh, interface, report.nb_pieces);
    // Members of each piece, by counting sort.
    std::vector<index_t> first(report.nb_pieces + 1, 0);
    for (index_t t = 0; t < m; ++t) ++first[piece[t] + 1];
    std::partial_sum(first.begin(), first.end(), first.begin());
    std::vector<index_t> members(m);
    {
      std::vector<index_t> next(first.begin(), first.end() - 1);
      for (index_t t = 0; t < m; ++t) members[next[piece[t]]++] = t;
    }
    // Samples spread over each piece's members (in tet order, so over its extent).
    std::vector<index_t> samples, sample_first(1, 0);
    for (std::size_t p = 0; p < report.nb_pieces; ++p) {
      const index_t size = first[p + 1] - first[p];
      const index_t k = std::min<index_t>(size, static_cast<index_t>(parameters.samples_per_piece));
      for (index_t i = 0; i < k; ++i) {
        samples.push_back(members[first[p] + static_cast<index_t>(std::uint64_t{i} * size / k)]);
      }
      sample_first.push_back(static_cast<index_t>(samples.size()));
    }
    add_phase_seconds(report.phase_seconds, "pieces", seconds_since(start));

    start = Clock::now();
    const std::vector<std::int32_t> sample_solid = classifier.classify(mesh, samples);
    for (std::size_t p = 0; p < report.nb_pieces; ++p) {
      std::map<std::int32_t, int> votes;
      for (index_t i = sample_first[p]; i < sample_first[p + 1]; ++i) {
        if (sample_solid[i] != NO_SOLID) ++votes[sample_solid[i]];
      }
      if (votes.size() == 1) {
        for (index_t i = first[p]; i < first[p + 1]; ++i) region[members[i]] = votes.begin()->first;
      } else {
        // Samples in two solids (the cut missed part of an interface) or in none: per tet.
        if (votes.size() > 1) ++report.nb_split_pieces;
        per_tet.insert(per_tet.end(), members.begin() + first[p], members.begin() + first[p + 1]);
      }
    }
    add_phase_seconds(report.phase_seconds, "classify samples", seconds_since(start));
  }

  if (!per_tet.empty()) {
    start = Clock::now();
    const std::vector<std::int32_t> solid = classifier.classify(mesh, per_tet);
    for (std::size_t i = 0; i < per_tet.size(); ++i) region[per_tet[i]] = solid[i];
    add_phase_seconds(report.phase_seconds, "classify tets", seconds_since(start));
  }
  report.nb_classified_points = classifier.nb_queries();
  report.nb_unassigned_tets =
      static_cast<std::size_t>(std::count(region.begin(), region.end(), NO_SOLID));
  return region;
}

}  // namespace

std::vector<std::int32_t> regions_by_solid(const std::string& brep, const TetMesh& mesh,
                                           const RegionsBySolidParameters& parameters,
                                           RegionsBySolidReport& report) {
  try {
    return classify_mesh(brep, mesh, parameters, report);
  } catch (const Standard_Failure& e) {
    // OCCT's own exceptions stop at this boundary: callers know only the project's types.
    throw InputError(std::string("OpenCASCADE failed on the shape: ") + e.DynamicType()->Name() +
                     ": " + e.GetMessageString());
  }
}

std::vector<std::int32_t> regions_by_solid(const std::string& brep, const TetMesh& mesh,
                                           const RegionsBySolidParameters& parameters) {
  RegionsBySolidReport report;
  return regions_by_solid(brep, mesh, parameters, report);
}

}  // namespace hexmerge
