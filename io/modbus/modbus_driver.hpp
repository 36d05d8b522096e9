// The Modbus field driver: a DAQ module or PLC on Modbus TCP or RTU delivers the rig's
// transducer values. A poller thread talks to the device; read() only copies out the latest
// values, turning any older than the channel's max_age_ms into gaps (NaN), so a slow or dead
// link shows as missing data and never as a frozen pressure that looks like a damped actuator.
#pragma once

#include <memory>

#include "config/yaml_reader.hpp"
#include "io/driver.hpp"

namespace leakmon::io {

// `node` is the driver's YAML mapping, including `name:` and `type: modbus`. Every field is
// validated; errors are config::ConfigError naming file:line:column and the field.
std::unique_ptr<Driver> make_modbus_driver(const config::ConfigNode& node);

}  // namespace leakmon::io
