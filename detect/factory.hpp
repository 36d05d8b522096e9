// Builds detectors by name from one registry: each kind states what it needs, its options (one
// table: key, range, default, meaning; option_table.hpp) and how it is built. "default" picks
// the best detector for the channels a configuration acquires; the evaluation (`leakmon
// evaluate`, docs/detection.md) is what "best" rests on.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"
#include "detect/detector.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::detect {

// Which Observation fields the configuration fills.
struct AvailableSignals {
  bool p1 = false, p2 = false, u = false, x = false;
};

// One kind of detector. A new kind is an options struct, its option rows (shared groups in
// factory.cpp: learning, false alarms, supply, drift, oil) and one entry here.
struct DetectorKind {
  std::string_view name;
  std::string_view needs;  // the signals it needs, in words (for errors and the docs)
  bool (*runs_on)(const AvailableSignals&);
  std::vector<std::string> (*option_keys)();
  // Options read (and checked) from `options` (null: defaults), the detector built.
  std::unique_ptr<Detector> (*build)(const AvailableSignals&, double hop_seconds,
                                     const config::ConfigNode* options,
                                     const sim::RigDescription& rig);
  std::string (*options_reference)();  // Markdown, for docs/detection.md
};

// Every kind, in the order the docs and `detector_kinds()` list them.
std::vector<DetectorKind> detector_registry();

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

// Every kind's options as Markdown (the reference in docs/detection.md, checked by a test).
std::string detector_options_reference();

}  // namespace leakmon::detect
