// Builds detectors by name. "default" picks the best detector for the channels a configuration
// acquires; the evaluation (`leakmon evaluate`, docs/detection.md) is what "best" rests on.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "detect/detector.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::detect {

// Which Observation fields the configuration fills.
struct AvailableSignals {
  bool p1 = false, p2 = false, u = false, x = false;
};

// kind: one of detector_kinds(). hop_seconds: time between observations. options: the
// detector's mapping from the configuration, or null for defaults; unknown keys and
// out-of-range values throw config::ConfigError naming file:line:column. rig: the actuator's
// description (`rig:`), or null for the paper's rig: the base of the detector's supply, tank,
// command full scale, valve, piston area and oil, which the options of detect/rig_options.hpp
// override. Throws std::invalid_argument for an unknown kind or when the signals the kind needs
// are missing.
std::unique_ptr<Detector> make_detector(const std::string& kind, const AvailableSignals& signals,
                                        double hop_seconds, const config::ConfigNode* options,
                                        const sim::RigDescription* rig = nullptr);

std::vector<std::string> detector_kinds();

// The kind "default" resolves to for these signals.
std::string default_detector_kind(const AvailableSignals& signals);

}  // namespace leakmon::detect
