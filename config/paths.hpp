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

// Where a secret named in a configuration (`password_file:`) is: an absolute path as it is; a
// relative name in $CREDENTIALS_DIRECTORY when the service runs with systemd credentials
// (LoadCredential=NAME:/etc/leakmon/NAME), else relative to the configuration file, so that
// the service and `leakmon check-config` run by hand read the same secret.
std::string secret_path(const ConfigNode& field);

// The secret in that file: its content without one trailing newline. Fails at `field` when the
// file cannot be read, is empty, or is larger than 64 KiB (not a password).
std::string read_secret(const ConfigNode& field);

// $STATE_DIRECTORY (set by systemd for StateDirectory=leakmon; its first entry when the unit
// names several), else /var/lib/leakmon.
std::string default_state_directory();

}  // namespace leakmon::config
