#pragma once
/// @file
/// Reading a CAD file into BREP text, the form in which shapes cross HexMerge's public headers
/// (mesh_shape(), regions_by_solid()). The header needs no OpenCASCADE include.

#include <string>

namespace hexmerge {

/// The shape in a STEP (.step, .stp), BREP (.brep, .brp) or IGES (.iges, .igs) file, as BREP text.
/// OpenCASCADE gives STEP and IGES shapes in millimetres whatever their file's unit; when
/// `length_unit` is given, it is set to the length unit the file declares (as the file names it,
/// e.g. "INCH"; "" for BREP files, which have none).
/// @throws InputError when the file is missing, of another kind, or unreadable
std::string read_shape_file(const std::string& path, std::string* length_unit = nullptr);

}  // namespace hexmerge
