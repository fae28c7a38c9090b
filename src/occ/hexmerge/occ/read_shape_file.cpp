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
#include <sstream>

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

// Reads a STEP or IGES file with an XSControl reader; every root becomes one shape.
template <typename Reader>
TopoDS_Shape read_with(const std::string& path, const char* kind, std::string* length_unit) {
  const QuietReading quiet;
  Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError("cannot read " + path + " as a " + kind + " file");
  if (reader.TransferRoots() == 0)
    throw InputError(path + ": the " + kind + " file holds no shape");
  TopoDS_Shape shape = reader.OneShape();
  if (shape.IsNull()) throw InputError(path + ": the " + kind + " file holds no shape");
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
      std::ifstream in(path, std::ios::binary);
      std::ostringstream text;
      text << in.rdbuf();
      try {
        read_brep(text.str());  // fails here, naming the file, rather than later
      } catch (const InputError& e) {
        throw InputError("cannot read " + path + ": " + e.what());
      }
      return text.str();
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
