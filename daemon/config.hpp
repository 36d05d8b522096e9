// Reading the daemon's configuration (schema: config/README.md) from YAML, with errors that
// name file, line and column, and checking it against this machine. Everything is validated
// when loaded, so that `check-config`, start-up and SIGHUP reload reject the same mistakes
// before anything runs. The values themselves are pipeline/config.hpp's.
#pragma once

#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "pipeline/config.hpp"

namespace leakmon::daemon {

using pipeline::DaemonConfig;

// 127.0.0.0/8, ::1 or localhost: reachable from this machine only.
bool is_loopback_address(const std::string& address);

// Parses and validates; throws config::ConfigError with `file:line:column: path: message`.
// Does not construct drivers (check_config() does that too, without starting them).
DaemonConfig parse_config(const config::ConfigNode& root);
DaemonConfig load_config(const std::string& path);

// What check_config() looks at on this machine besides the file itself.
struct Preflight {
  // Devices the drivers name: CAN interfaces exist, serial ports are character devices.
  bool devices = true;
  // The metrics address and port can be bound now (nothing else listens there). A running
  // daemon's reload leaves this out: it holds the port itself.
  bool port = true;
  // Network peers (Modbus TCP devices, MQTT brokers) accept a TCP connection now. Only
  // `leakmon check-config`: the daemon starts without them and reconnects when they come.
  bool peers = false;
};

// Full validation, the one `leakmon check-config` and `leakmon run` (and SIGHUP) share, so that
// systemd's ExecStartPre and the start never disagree: parse, build (not start) every driver,
// output and detector so their own option checks run, check that every actuator channel
// exists, that the event log, recording and state paths can be written, and what `preflight`
// asks for. Throws ConfigError with `file:line:column: message`.
DaemonConfig check_config(const std::string& path, const Preflight& preflight = {});

// The machine-dependent part of check_config() on a parsed configuration. Throws ConfigError.
void check_paths(const DaemonConfig& config);
void check_port(const DaemonConfig& config);
void check_devices(const DaemonConfig& config);
void check_peers(const DaemonConfig& config);

// Checks actuator channel references and group sizes against the channels the built drivers
// offer (`driver_channels[i]` belongs to `config.drivers[i]`). Throws ConfigError.
void check_channels(const DaemonConfig& config,
                    const std::vector<std::vector<std::string>>& driver_channels);

}  // namespace leakmon::daemon
