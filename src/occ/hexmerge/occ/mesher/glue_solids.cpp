#include "hexmerge/occ/mesher/glue_solids.h"

#include <BRepAlgoAPI_BuilderAlgo.hxx>
#include <BRepGProp.hxx>
#include <BRep_Builder.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "hexmerge/core/error.h"

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

}  // namespace hexmerge::mesher
