// Where the files a configuration names live: relative to the configuration, or in the
// service's state directory.
#pragma once

#include <string>

#include "config/yaml_reader.hpp"

namespace leakmon::config {

// Relative paths in a configuration are relative to the file `node` came from, so that a
// configuration and its data can move together (and a service's working directory does not
// matter). Empty and absolute paths are returned as they are.
std::string resolve_path(const ConfigNode& node, const std::string& path);

// $STATE_DIRECTORY (set by systemd for StateDirectory=leakmon; its first entry when the unit
// names several), else /var/lib/leakmon.
std::string default_state_directory();

}  // namespace leakmon::config
