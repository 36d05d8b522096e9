// The detector options that restate a value of the rig's description (sim/rig_description.hpp,
// an actuator's `rig:`): a detector takes its supply, tank pressure, command full scale, valve,
// piston area and oil from the rig, and these options, where given, override it. One table, so
// that `check-config` can say when a value is given in both places.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::detect {

struct RigOption {
  std::string_view option;                 // the detector option's key
  std::span<const std::string_view> keys;  // the rig keys that state the same value
};

// supply_pressure, tank_pressure, command_full_scale, valve_coefficient (the rig's
// valve_coefficient or valve_rated_flow), piston_area (the rig's bore and rod), oil_grade and
// oil_viscosity_40/_100 (the rig's oil keys).
std::span<const RigOption> rig_options();

// One option of `options` that restates what `rig` states: the option and the rig's keys.
struct RigRestatement {
  config::ConfigNode option;
  std::vector<std::string> rig_keys;  // those the rig states, in the table's order
};

// Every option in `options` (a detector's mapping) whose value the rig states too.
std::vector<RigRestatement> restated_rig_values(const config::ConfigNode& options,
                                                const sim::RigDescription& rig);

}  // namespace leakmon::detect
