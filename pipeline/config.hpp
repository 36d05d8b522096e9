// The daemon's configuration as plain values (schema: config/README.md): what the pipeline is
// built from. Reading it from YAML and checking it against the machine is the service's
// (daemon/config.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/role.hpp"
#include "config/paths.hpp"
#include "config/yaml_reader.hpp"
#include "detect/factory.hpp"
#include "detect/sensor_plausibility.hpp"
#include "dsp/streaming_features.hpp"
#include "pipeline/alarm.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::pipeline {

// A `drivers:` entry; the mapping is handed whole to the driver's factory.
struct DriverConfig {
  std::string name;
  std::string type;
  std::optional<config::ConfigNode> node;  // absent for drivers built in code (replay_capture)
};

// A `sampling:` group: one real-time thread, one ring buffer.
struct GroupConfig {
  std::string name = "main";
  std::int64_t period_ns = 2'000'000;
  std::vector<std::string> drivers;  // names from `drivers:`
  int priority = 80;                 // SCHED_FIFO priority; 0 keeps normal scheduling
  std::vector<int> cpus;             // CPU affinity; empty = any
  std::size_t ring_capacity = 8192;  // samples (16 s at 500 Hz)
};

// Where one actuator signal comes from: `driver.channel`.
struct ChannelRef {
  std::string driver;
  std::string channel;
  std::optional<config::ConfigNode> where;  // the YAML scalar, for error locations
  bool present() const { return !channel.empty(); }
  std::string text() const { return driver.empty() ? channel : driver + "." + channel; }
};

// The roles whose transducers have a plausibility check (detect/sensor_plausibility.hpp): the
// chamber pressures and the position.
inline constexpr std::array<capture::Role, 3> kCheckedRoles = {capture::Role::p1, capture::Role::p2,
                                                               capture::Role::x};

// MODEL.md's transducers: 0-20.7 MPa 12 bit 5 kPa noise for the pressures, 10 um resolution with
// 5 um noise for the position (the other roles have no check: their entry is unused).
capture::ByRole<detect::TransducerSpec> default_transducers();

struct ActuatorConfig {
  std::string name;
  // Signals by role (capture/role.hpp); p1 is required, the others optional.
  capture::ByRole<ChannelRef> channels;
  dsp::FeatureParams features;
  std::string detector = "default";
  std::optional<config::ConfigNode> detector_options;
  // The rig's description (`rig:`, FORMATS.md): the base of the detector's supply, tank pressure,
  // valve, piston area, command full scale and oil, which detector options of the same values
  // override (detect/rig_options.hpp); the paper's rig when absent. A stated supply also sets
  // the pressure transducers' default range (sim::sensors_for).
  sim::RigDescription rig;
  // Thresholds left NaN take the detector's own.
  AlarmSettings alarm{NAN, NAN, 0.0, 0.0, false};
  std::string alarm_name = "internal_leakage";
  // The transducers behind the checked roles (kCheckedRoles), for their plausibility checks
  // (`transducers:`); the pressures 12 bit over the rig's standard range when `rig:` states the
  // supply.
  capture::ByRole<detect::TransducerSpec> transducers = default_transducers();

  // Which roles the actuator acquires.
  capture::ByRole<bool> acquired() const;
};

// What a detector is told it gets (detect/factory.hpp), from the roles acquired: the one place
// the configuration check, the state fingerprint and the monitor build it.
detect::AvailableSignals available_signals(const capture::ByRole<bool>& acquired);

struct RecordingConfig {
  std::string directory;                    // empty: no recording
  std::optional<config::ConfigNode> where;  // `recording.directory`, for error locations
  double rotate_seconds = 3600.0;           // start a new file after this much source time
  std::size_t keep_files = 24;              // oldest files beyond this are deleted; 0 keeps all
  double flush_seconds = 1.0;
};

// Where what was learned is kept across restarts (state_store.hpp).
struct StateConfig {
  std::string directory;                    // empty: nothing is kept (every start learns afresh)
  double save_seconds = 60.0;               // save at least this often, and at shutdown
  std::optional<config::ConfigNode> where;  // `state.directory` when given
};

struct MetricsConfig {
  std::string address = "127.0.0.1";        // an IPv4 address (names are not resolved)
  int port = 9187;                          // 0 disables the metrics and control endpoint
  std::optional<config::ConfigNode> where;  // `metrics.port` (else `metrics`) when given
  // Required by POST /ack when set; check-config demands one for a non-loopback address.
  std::string ack_token;
  // The live page's in-memory trend (views/trend_history.hpp): how far back, how finely.
  double trend_seconds = 4 * 3600.0;
  double trend_interval_s = 1.0;
};

struct DaemonConfig {
  std::string source;  // file the configuration came from, for messages
  std::vector<DriverConfig> drivers;
  std::vector<GroupConfig> groups;
  std::vector<ActuatorConfig> actuators;
  std::string event_log;  // JSON-lines file; empty: none
  std::optional<config::ConfigNode> event_log_where;
  // Legal but probably wrong (two Modbus channels on the same registers, a value given both in
  // `rig:` and in the detector's options), each `file:line:column: message`; check-config prints
  // them, run logs them at start.
  std::vector<std::string> warnings;
  RecordingConfig recording;
  StateConfig state{config::default_state_directory(), 60.0, std::nullopt};
  MetricsConfig metrics;
  std::vector<config::ConfigNode> outputs;
  // Worker wake-up interval when the rings are empty [ns]: bounds the sample-to-event latency
  // (target p99 < 1 ms) at the cost of 2000 cheap wake-ups a second.
  std::int64_t worker_poll_ns = 500'000;
  // SCHED_FIFO priority of the worker thread (below the loops'), so that decisions and alarm
  // events keep their latency on a loaded machine; 0 keeps normal scheduling.
  int worker_priority = 70;
  // Longest CPU idle-state exit the daemon tolerates [us], requested through
  // /dev/cpu_dma_latency while it runs (0: CPUs never sleep deeper than polling, as cyclictest
  // asks); negative: no request, the power management stays as the system has it.
  int cpu_wakeup_latency_us = 0;
};

// Sets the actuator's rig and what follows from it where nothing else is configured: the
// pressure transducers' range (12 bit over sim::sensors_for's range for a stated supply).
// daemon::parse_config calls it before it reads `transducers:`; `leakmon replay --rig` on the
// built-in defaults, and the evaluation on a told rig.
void apply_rig(ActuatorConfig& actuator, sim::RigDescription rig);

// The group that holds `driver`, or nullptr.
const GroupConfig* group_of_driver(const DaemonConfig& config, const std::string& driver);

}  // namespace leakmon::pipeline
