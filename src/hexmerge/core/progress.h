#pragma once
/// @file
/// Progress reporting from the core to its callers. The core never prints.

#include <functional>
#include <string>

namespace hexmerge {

/// Called by long-running steps with the phase name and the fraction done in [0, 1].
/// Return false to cancel: the run then throws hexmerge::Cancelled. May be called from the
/// thread that started the run only. An empty function means "no progress wanted".
using ProgressCallback = std::function<bool(const std::string& phase, double fraction)>;

/// Forward a progress report; throws Cancelled when the callback asks to stop.
void report_progress(const ProgressCallback& callback, const std::string& phase, double fraction);

}  // namespace hexmerge
