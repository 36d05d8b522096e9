// The Modbus alarm output: a coil or holding register on a PLC that follows the alarm state
// (raised_value while any matching alarm is raised, cleared_value otherwise), configured as an
// `outputs:` entry with `type: modbus` (see README.md beside this file).
#pragma once

#include <memory>

#include "config/yaml_reader.hpp"
#include "io/event.hpp"

namespace leakmon::io {

// `node` is the output's YAML mapping, including `name:` and `type: modbus`. Validates every
// field (file:line:column errors); opens no connection until the first event or flush.
std::unique_ptr<EventSink> make_modbus_output(const config::ConfigNode& node);

}  // namespace leakmon::io
