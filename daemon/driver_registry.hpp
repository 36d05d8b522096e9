// Which driver `type:` names exist and how each is built from its YAML mapping (every driver
// library is always built and linked).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "config/yaml_reader.hpp"
#include "daemon/plugin_registry.hpp"
#include "io/driver.hpp"

namespace leakmon::daemon {

// Builds a driver from its mapping under `drivers:` (including `name:` and `type:`). Validates
// every field and fails with ConfigNode::fail (file:line:column) on bad input; does not open
// devices (that is Driver::start()).
using DriverType = PluginType<io::Driver>;
using DriverFactory = DriverType::Factory;

std::span<const DriverType> driver_types();

// The factory for `node.type`, failing at the `type:` field when no driver has that name.
std::unique_ptr<io::Driver> make_driver(const config::ConfigNode& node);

}  // namespace leakmon::daemon
