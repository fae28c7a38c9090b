#include "hexmerge/core/error.h"

#include <sstream>

namespace hexmerge {

void assertion_failed(const char* condition, const char* message, const char* file, int line) {
  std::ostringstream out;
  out << "internal error (please report): " << message << " [" << condition << " at " << file << ":"
      << line << "]";
  throw InternalError(out.str());
}

}  // namespace hexmerge
