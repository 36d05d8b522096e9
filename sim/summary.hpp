// What a simulation run will hold, said before it runs: `leakmon sim` prints this one line, so
// that a run shortened below its preset's leak (paper-fig13 --duration 120 ends before the
// leak at 300 s) does not pass silently.
#pragma once

#include <string>
#include <vector>

#include "sim/scenario.hpp"

namespace leakmon::sim {

// One line: origin, seed, controller, duration and rate, the effects (a leak in l/min/MPa with
// its onset), drifting conditions and sensor faults with their start times.
std::string summary_line(const Scenario& scenario);

// Each effect, condition change or sensor fault that starts at or after the end of the run,
// as a sentence naming it, its start and the end ("internal_leakage starts at t = 300 s, after
// the run ends at t = 120 s: the capture holds no leak"). Empty when everything starts in time.
std::vector<std::string> starts_after_end(const Scenario& scenario);

}  // namespace leakmon::sim
