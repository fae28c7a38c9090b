#pragma once
/// @file
/// Wall time per phase of a run: the one timer and the one report shape of every report
/// (RecombineReport, MeshShapeReport, RegionsBySolidReport).

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace hexmerge {

/// Wall time per phase, in seconds, in the order the phases first ran.
using PhaseSeconds = std::vector<std::pair<std::string, double>>;

/// Adds `seconds` to `phase`: a new entry the first time, summed into the entry after.
inline void add_phase_seconds(PhaseSeconds& phases, const std::string& phase, double seconds) {
  for (auto& [name, total] : phases) {
    if (name == phase) {
      total += seconds;
      return;
    }
  }
  phases.emplace_back(phase, seconds);
}

/// Times consecutive phases into a PhaseSeconds: each lap() records the time since the timer
/// was made or since the previous lap.
class PhaseTimer {
 public:
  using Clock = std::chrono::steady_clock;

  explicit PhaseTimer(PhaseSeconds& out) : out_(out), start_(Clock::now()) {}

  /// Records the time since the start or the previous lap under `phase`, and restarts.
  void lap(const std::string& phase) {
    const auto now = Clock::now();
    add_phase_seconds(out_, phase, std::chrono::duration<double>(now - start_).count());
    start_ = now;
  }

  /// Seconds since `start` (a Clock::now() taken earlier).
  static double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
  }

 private:
  PhaseSeconds& out_;
  Clock::time_point start_;
};

}  // namespace hexmerge
