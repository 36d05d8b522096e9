// Which `outputs:` types exist: event sinks beyond the built-in event log and journal, e.g. a
// Modbus coil that follows an alarm. Same shape as the driver registry.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "config/yaml_reader.hpp"
#include "daemon/plugin_registry.hpp"
#include "io/event.hpp"

namespace leakmon::daemon {

// Builds an output from its mapping under `outputs:` (including `name:` and `type:`); validates
// with ConfigNode::fail. Must not block on devices here: connect lazily or in a thread.
using OutputType = PluginType<io::EventSink>;
using OutputFactory = OutputType::Factory;

std::span<const OutputType> output_types();

std::unique_ptr<io::EventSink> make_output(const config::ConfigNode& node);

}  // namespace leakmon::daemon
