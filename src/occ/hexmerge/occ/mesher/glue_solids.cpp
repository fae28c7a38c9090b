#include "hexmerge/occ/mesher/glue_solids.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_BuilderAlgo.hxx>
#include <BRepAlgoAPI_Splitter.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Iterator.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/mesher/surface.h"

namespace hexmerge::mesher {
namespace {

// Per item of `kind` of the shape as given, the items of the glued shape it became.
std::vector<std::vector<int>> images_of(BRepAlgoAPI_BuilderAlgo& fuse, const TopoDS_Shape& given,
                                        const TopoDS_Shape& glued, TopAbs_ShapeEnum kind) {
  TopTools_IndexedMapOfShape before, after;
  TopExp::MapShapes(given, kind, before);
  TopExp::MapShapes(glued, kind, after);
  std::vector<std::vector<int>> out(static_cast<std::size_t>(before.Extent()));
  for (int i = 1; i <= before.Extent(); ++i) {
    std::vector<int>& images = out[static_cast<std::size_t>(i - 1)];
    const auto add = [&](const TopoDS_Shape& s) {
      const int index = after.FindIndex(s);
      if (index > 0 && std::find(images.begin(), images.end(), index - 1) == images.end())
        images.push_back(index - 1);
    };
    for (const TopoDS_Shape& s : fuse.Modified(before(i))) add(s);
    if (images.empty() && !fuse.IsDeleted(before(i))) add(before(i));
  }
  return out;
}

// The angle an edge's tangent turns through along it (radians), from 32 steps.
double turning(const TopoDS_Edge& edge) {
  const BRepAdaptor_Curve curve(edge);
  const double t0 = curve.FirstParameter(), t1 = curve.LastParameter();
  constexpr int kSteps = 32;
  double total = 0;
  gp_Vec before;
  for (int i = 0; i <= kSteps; ++i) {
    gp_Pnt p;
    gp_Vec d;
    curve.D1(t0 + (t1 - t0) * i / kSteps, p, d);
    if (i > 0 && before.Magnitude() > 0 && d.Magnitude() > 0) total += before.Angle(d);
    before = d;
  }
  return total;
}

double volume_of(const TopoDS_Shape& solid) {
  GProp_GProps props;
  BRepGProp::VolumeProperties(solid, props);
  return std::abs(props.Mass());
}

}  // namespace

TopoDS_Shape glue_solids(const TopoDS_Shape& shape, double tolerance, GlueSolidsReport& report) {
  report = GlueSolidsReport{};
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  report.nb_solids = static_cast<std::size_t>(solids.Extent());
  if (solids.Extent() < 2) return shape;

  TopTools_ListOfShape arguments;
  for (int i = 1; i <= solids.Extent(); ++i) arguments.Append(solids(i));
  BRepAlgoAPI_BuilderAlgo fuse;
  fuse.SetArguments(arguments);
  fuse.SetNonDestructive(true);  // the caller's shape stays as it is
  fuse.SetFuzzyValue(tolerance);
  // OpenCASCADE's own threads (its results do not depend on them): gmsh_as1-tu-203's 18 solids
  // in 1.8 s instead of 2.8 on two cores (the same tets). Oriented boxes (SetUseOBB) were slower.
  fuse.SetRunParallel(true);
  try {
    fuse.Build();
  } catch (const Standard_Failure& e) {
    throw InputError(std::string("OpenCASCADE could not intersect the shape's ") +
                     std::to_string(solids.Extent()) +
                     " solids with each other to find where they touch: " + e.GetMessageString());
  }
  if (fuse.HasErrors()) {
    std::ostringstream why;
    fuse.DumpErrors(why);
    std::string text = why.str();
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    throw InputError("OpenCASCADE could not intersect the shape's " +
                     std::to_string(solids.Extent()) +
                     " solids with each other to find where they touch (faces that intersect "
                     "themselves or each other?)" +
                     (text.empty() ? std::string() : ": " + text));
  }
  report.glued = true;
  report.fuzzy = tolerance;

  // The pieces of each solid; a piece in two solids' images is volume they share.
  TopTools_IndexedMapOfShape pieces;
  std::vector<std::vector<int>> owners;
  std::vector<std::vector<int>> images(static_cast<std::size_t>(solids.Extent()));
  for (int i = 1; i <= solids.Extent(); ++i) {
    TopTools_ListOfShape found;
    const TopTools_ListOfShape& modified = fuse.Modified(solids(i));
    for (const TopoDS_Shape& s : modified) {
      TopTools_IndexedMapOfShape in_s;
      TopExp::MapShapes(s, TopAbs_SOLID, in_s);
      for (int k = 1; k <= in_s.Extent(); ++k) found.Append(in_s(k));
    }
    if (found.IsEmpty() && !fuse.IsDeleted(solids(i))) found.Append(solids(i));
    if (found.IsEmpty())
      throw InputError("Solid" + std::to_string(i) +
                       " of the shape vanished when OpenCASCADE intersected the solids (a solid "
                       "of no volume?)");
    for (const TopoDS_Shape& piece : found) {
      const int index = pieces.Add(piece) - 1;
      if (static_cast<std::size_t>(index) >= owners.size()) owners.resize(index + 1);
      owners[index].push_back(i - 1);
      images[i - 1].push_back(index);
    }
  }
  for (std::size_t p = 0; p < owners.size(); ++p)
    if (owners[p].size() > 1) {
      std::ostringstream text;
      text << "Solid" << owners[p][0] + 1 << " and Solid" << owners[p][1] + 1
           << " of the shape overlap (common volume " << volume_of(pieces(static_cast<int>(p) + 1))
           << "): a mesh cannot give that volume to both; make them touch without overlapping "
              "(in FreeCAD: Part BooleanFragments, or Cut one by the other)";
      throw InputError(text.str());
    }

  for (std::size_t i = 0; i < images.size(); ++i)
    if (images[i].size() != 1)
      throw InputError("Solid" + std::to_string(i + 1) + " of the shape is cut into " +
                       std::to_string(images[i].size()) +
                       " pieces by the faces of the other solids: give solids that touch only "
                       "on their boundaries");

  TopoDS_Compound glued;
  BRep_Builder builder;
  builder.MakeCompound(glued);
  for (const auto& image : images)
    for (int p : image) builder.Add(glued, pieces(p + 1));

  TopTools_IndexedDataMapOfShapeListOfShape face_solids;
  TopExp::MapShapesAndAncestors(glued, TopAbs_FACE, TopAbs_SOLID, face_solids);
  for (int f = 1; f <= face_solids.Extent(); ++f) {
    TopTools_IndexedMapOfShape around;
    for (const TopoDS_Shape& s : face_solids(f)) around.Add(s);
    report.nb_shared_faces += around.Extent() > 1;
  }
  report.face_images = images_of(fuse, shape, glued, TopAbs_FACE);
  report.edge_images = images_of(fuse, shape, glued, TopAbs_EDGE);
  return glued;
}

double edge_length(const TopoDS_Edge& edge) {
  GProp_GProps props;
  BRepGProp::LinearProperties(edge, props);
  return props.Mass();
}

bool lens_edges(const TopoDS_Edge& a, const TopoDS_Edge& b) {
  if (a.IsSame(b) || BRep_Tool::Degenerated(a) || BRep_Tool::Degenerated(b)) return false;
  TopoDS_Vertex a0, a1, b0, b1;
  TopExp::Vertices(a, a0, a1);
  TopExp::Vertices(b, b0, b1);
  if (a0.IsNull() || a1.IsNull() || b0.IsNull() || b1.IsNull() || a0.IsSame(a1)) return false;
  return (a0.IsSame(b0) && a1.IsSame(b1)) || (a0.IsSame(b1) && a1.IsSame(b0));
}

TopoDS_Shape split_lens_edges(const TopoDS_Shape& shape, GlueSolidsReport& report) {
  TopTools_IndexedMapOfShape to_split;
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  for (int f = 1; f <= faces.Extent(); ++f) {
    // A face whose outline is a lens (not a hole in it) is zipped shut after BRepMesh instead
    // (surface.cpp, zip_lens_faces()).
    const TopoDS_Face& face = TopoDS::Face(faces(f));
    const TopoDS_Wire outer = BRepTools::OuterWire(face);
    for (TopoDS_Iterator wire(face); wire.More(); wire.Next()) {
      if (wire.Value().ShapeType() != TopAbs_WIRE || wire.Value().IsSame(outer)) continue;
      std::vector<TopoDS_Edge> edges;
      for (TopoDS_Iterator it(wire.Value()); it.More() && edges.size() <= 2; it.Next())
        if (!BRep_Tool::Degenerated(TopoDS::Edge(it.Value())))
          edges.push_back(TopoDS::Edge(it.Value()));
      if (edges.size() != 2 || !lens_edges(edges[0], edges[1])) continue;
      if (!(turning(edges[0]) < kSurfaceAngle) || !(turning(edges[1]) < kSurfaceAngle)) continue;
      to_split.Add(edge_length(edges[0]) >= edge_length(edges[1]) ? edges[0] : edges[1]);
    }
  }
  if (to_split.IsEmpty()) return shape;
  TopTools_ListOfShape arguments, tools;
  arguments.Append(shape);
  for (int i = 1; i <= to_split.Extent(); ++i) {
    const BRepAdaptor_Curve curve(TopoDS::Edge(to_split(i)));
    tools.Append(BRepBuilderAPI_MakeVertex(
        curve.Value(0.5 * (curve.FirstParameter() + curve.LastParameter()))));
  }
  BRepAlgoAPI_Splitter splitter;
  splitter.SetArguments(arguments);
  splitter.SetTools(tools);
  splitter.SetNonDestructive(true);
  // Where OpenCASCADE cannot split them, the edges stay as they are, as before this step (the
  // surface at a finer deflection may still give the hole area; nb_split_lens_edges says 0).
  try {
    splitter.Build();
  } catch (const Standard_Failure&) {
    return shape;
  }
  if (splitter.HasErrors() || !splitter.IsDone()) return shape;
  const TopoDS_Shape split = splitter.Shape();
  TopTools_IndexedMapOfShape faces_after;
  TopExp::MapShapes(split, TopAbs_FACE, faces_after);
  if (faces_after.Extent() != faces.Extent()) return shape;
  // Through the split: per item of `shape`, its items in `split`; then composed with the gluing.
  const auto compose = [&](TopAbs_ShapeEnum kind, std::vector<std::vector<int>>& images) {
    const std::vector<std::vector<int>> step = images_of(splitter, shape, split, kind);
    if (images.empty()) {  // not glued: the shape as given is `shape`
      images = step;
      return;
    }
    for (std::vector<int>& image : images) {
      std::vector<int> composed;
      for (const int i : image)
        for (const int j : step[static_cast<std::size_t>(i)])
          if (std::find(composed.begin(), composed.end(), j) == composed.end())
            composed.push_back(j);
      image = std::move(composed);
    }
  };
  compose(TopAbs_FACE, report.face_images);
  compose(TopAbs_EDGE, report.edge_images);
  report.nb_split_lens_edges = static_cast<std::size_t>(to_split.Extent());
  return split;
}

}  // namespace hexmerge::mesher
