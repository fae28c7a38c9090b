#pragma once
/// @file
/// Shapes as BREP text, the form in which they cross HexMerge's public headers (internal header:
/// it includes OpenCASCADE).

#include <TopoDS_Shape.hxx>
#include <string>

namespace hexmerge {

/// The shape in BREP text. @throws InputError when the text cannot be read or holds no shape
TopoDS_Shape read_brep(const std::string& text);

/// The BREP text of a shape.
std::string write_brep(const TopoDS_Shape& shape);

}  // namespace hexmerge
