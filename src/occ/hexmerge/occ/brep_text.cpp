#include "hexmerge/occ/brep_text.h"

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Standard_Failure.hxx>
#include <sstream>

#include "hexmerge/core/error.h"

namespace hexmerge {

TopoDS_Shape read_brep(const std::string& text) {
  TopoDS_Shape shape;
  try {
    std::istringstream in(text);
    BRep_Builder builder;
    BRepTools::Read(shape, in, builder);
  } catch (const Standard_Failure& e) {
    throw InputError(std::string("the shape's BREP text cannot be read: ") + e.GetMessageString());
  }
  if (shape.IsNull()) throw InputError("the shape's BREP text cannot be read (no shape in it)");
  return shape;
}

std::string write_brep(const TopoDS_Shape& shape) {
  std::ostringstream out;
  BRepTools::Write(shape, out);
  return out.str();
}

}  // namespace hexmerge
