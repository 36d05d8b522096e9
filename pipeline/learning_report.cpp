#include "pipeline/learning_report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <vector>

namespace leakmon::pipeline {

std::string detector_line(const ActuatorConfig& actuator, const ActuatorStatus& status) {
  std::vector<std::string> signals{"p1"};
  for (const capture::Role role : {capture::Role::p2, capture::Role::u, capture::Role::x}) {
    if (actuator.channels[role].present()) signals.emplace_back(capture::to_string(role));
  }
  const std::string chosen = actuator.detector == "default"
                                 ? fmt::format(" (default for {})", fmt::join(signals, ", "))
                                 : std::string();
  if (!status.learning && !std::isfinite(status.learning_ended_t)) {
    return fmt::format("{}: detector {}{}; resumes what it learned before (state directory)",
                       status.name, status.detector, chosen);
  }
  return fmt::format(
      "{}: detector {}{}; learns the healthy rig during its first {:.1f} s of data (a leak "
      "present then is learned as healthy) and detects from then on",
      status.name, status.detector, chosen, status.learning_seconds);
}

std::string learning_line(const ActuatorStatus& status) {
  if (std::isfinite(status.learning_ended_t)) {
    return fmt::format("{}: learned the healthy rig until t = {:.1f} s; detecting since",
                       status.name, status.learning_ended_t);
  }
  if (!status.learning || std::isnan(status.t)) return "";
  return fmt::format(
      "{}: still learning at t = {:.1f} s (learning takes {:.1f} s of data): nothing could be "
      "detected yet",
      status.name, status.t, status.learning_seconds);
}

}  // namespace leakmon::pipeline
