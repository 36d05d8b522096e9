// What `leakmon run` and `leakmon replay` say about each actuator's detector: which one runs
// (and, for `default`, which signals chose it), how long it learns the healthy rig before it
// can raise an alarm, and when that learning ended. A leak that opens while the detector still
// learns is learned as healthy: these lines make the learning period visible.
#pragma once

#include <string>

#include "pipeline/actuator_monitor.hpp"
#include "pipeline/config.hpp"

namespace leakmon::pipeline {

// "cylinder: detector flow_balance (default for p1, p2, u, x); learns the healthy rig during
// its first 92.8 s of data, detects from then on", or "...; resumes what it learned before".
std::string detector_line(const ActuatorConfig& actuator, const ActuatorStatus& status);

// After the actuator has data: "cylinder: learned the healthy rig until t = 92.8 s, detecting
// since", or "cylinder: still learning at t = 60.0 s (learning takes 92.8 s from the first
// sample): nothing can be detected before it ends". Empty while it has no decision yet.
std::string learning_line(const ActuatorStatus& status);

}  // namespace leakmon::pipeline
