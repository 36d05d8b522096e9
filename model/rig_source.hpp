// Where `leakmon model check` takes the rig's description from (FORMATS.md "The rig's
// description"): a file whose top-level key is `rig:` (sim::load_rig_file), or one actuator's
// `rig:` in the daemon's configuration. The configuration is read only as far as the
// `actuators:` list's names and rigs (daemon/config.cpp validates the rest when the daemon
// loads it): the model check needs no driver, detector or alarm to judge a capture.
#pragma once

#include <string>

#include "sim/rig_description.hpp"

namespace leakmon::model {

// The `rig:` of the actuator named `actuator` in the daemon configuration `config_path`; the
// paper's rig when that actuator has none (as the daemon assumes). Throws config::ConfigError
// at file:line:column for a missing `actuators:` list, an unknown actuator (naming the known
// ones) and any error in the rig's description.
sim::RigDescription load_actuator_rig(const std::string& config_path, const std::string& actuator);

}  // namespace leakmon::model
