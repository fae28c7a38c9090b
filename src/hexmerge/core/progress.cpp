#include "hexmerge/core/progress.h"

#include "hexmerge/core/error.h"

namespace hexmerge {

void report_progress(const ProgressCallback& callback, const std::string& phase, double fraction) {
  if (callback && !callback(phase, fraction)) throw Cancelled();
}

}  // namespace hexmerge
