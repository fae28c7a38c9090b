#include "hexmerge/occ/read_shape_file.h"

#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_SequenceOfPrinters.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <algorithm>
#include <cctype>
#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/occ/brep_text.h"

namespace hexmerge {

namespace {

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of("/\\");
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// The length unit a reader's file declares (OpenCASCADE converts to millimetres), "" when none.
std::string declared_length_unit(STEPControl_Reader& reader) {
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.FileUnits(lengths, angles, solid_angles);
  return lengths.IsEmpty() ? std::string() : std::string(lengths.First().ToCString());
}
std::string declared_length_unit(IGESControl_Reader& reader) {
  const Handle(IGESData_IGESModel) model = reader.IGESModel();
  if (model.IsNull()) return "";
  const Handle(TCollection_HAsciiString) name = model->GlobalSection().UnitName();
  return name.IsNull() ? std::string() : std::string(name->ToCString());
}

// OpenCASCADE's readers print through its default messenger (the IGES reader: "Total number of
// loaded entities", in colour, on standard output): another program's text, which the user of
// hexmerge does not get. Its printers are taken away while a file is read, and put back.
class QuietReading {
 public:
  QuietReading() : lock_(mutex()), printers_(Message::DefaultMessenger()->Printers()) {
    Message::DefaultMessenger()->ChangePrinters().Clear();
  }
  ~QuietReading() { Message::DefaultMessenger()->ChangePrinters() = printers_; }
  QuietReading(const QuietReading&) = delete;
  QuietReading& operator=(const QuietReading&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  Message_SequenceOfPrinters printers_;
};

// A file's bytes.
std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The files a STEP file's parts are in, when it refers to others (DOCUMENT_FILE entities: an
// assembly whose parts were exported one file each, as the CAX-IF's s1 test model), in order.
std::vector<std::string> external_files(const std::string& path) {
  const std::string all = file_text(path);
  static const std::regex entity(R"(DOCUMENT_FILE\s*\(\s*'([^']+)')", std::regex::icase);
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (auto it = std::sregex_iterator(all.begin(), all.end(), entity); it != std::sregex_iterator();
       ++it)
    if (seen.insert((*it)[1].str()).second) names.push_back((*it)[1].str());
  return names;
}

// "the STEP file holds no shape", and why where it can be told.
std::string no_shape(const std::string& path, const char* kind) {
  std::string text = path + ": the " + kind + " file holds no shape";
  if (std::string(kind) != "STEP") return text;
  const std::vector<std::string> files = external_files(path);
  if (files.empty()) return text;
  text += ": its parts are in other files (";
  for (std::size_t i = 0; i < files.size(); ++i) text += (i > 0 ? ", " : "") + files[i];
  return text +
         "), which it only names; mesh those, or export the assembly with its parts in one "
         "file";
}

// Reads a STEP or IGES file with an XSControl reader; every root becomes one shape.
template <typename Reader>
TopoDS_Shape read_with(const std::string& path, const char* kind, std::string* length_unit) {
  const QuietReading quiet;
  Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError("cannot read " + path + " as a " + kind + " file");
  if (reader.TransferRoots() == 0) throw InputError(no_shape(path, kind));
  TopoDS_Shape shape = reader.OneShape();
  if (shape.IsNull()) throw InputError(no_shape(path, kind));
  if (length_unit) *length_unit = declared_length_unit(reader);
  return shape;
}

}  // namespace

std::string read_shape_file(const std::string& path, std::string* length_unit) {
  if (length_unit) length_unit->clear();
  if (!std::ifstream(path).good()) throw InputError("cannot open the shape file " + path);
  const std::string ext = lower_extension(path);
  try {
    if (ext == "brep" || ext == "brp") {
      std::string text = file_text(path);
      try {
        read_brep(text);  // fails here, naming the file, rather than later
      } catch (const InputError& e) {
        throw InputError("cannot read " + path + ": " + e.what());
      }
      return text;
    }
    if (ext == "step" || ext == "stp")
      return write_brep(read_with<STEPControl_Reader>(path, "STEP", length_unit));
    if (ext == "iges" || ext == "igs")
      return write_brep(read_with<IGESControl_Reader>(path, "IGES", length_unit));
  } catch (const Standard_Failure& e) {
    throw InputError("cannot read " + path + ": " + e.GetMessageString());
  }
  throw InputError("cannot read " + path +
                   ": the file name must end in .step, .stp, .brep, .brp, "
                   ".iges or .igs");
}

}  // namespace hexmerge
