// What the daemon tells the outside world: alarm transitions, driver faults, overruns, reloads.
// The worker thread builds one Event per occurrence and hands it to every EventSink (JSON-lines
// event log, spdlog, and the configured `outputs:` such as a Modbus coil). The sink is the
// output plug-in point, beside the driver interface (io/driver.hpp); header-only, so that
// outputs implement it without linking the daemon.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::io {

enum class EventKind {
  alarm_raised,
  alarm_cleared,
  alarm_acknowledged,
  driver_fault,
  driver_recovered,
  overrun,
  config_reloaded,
  config_rejected,
  // Persistence (state_store.hpp): what was learned came back from the state directory, was
  // set aside (changed configuration, newer format, corrupt file: learning starts afresh), or
  // could not be saved.
  state_restored,
  state_discarded,
  state_save_failed,
  // Lifecycle: the daemon started acquiring / stopped (after its last event was written).
  daemon_started,
  daemon_stopped,
  // A reload changed an option what the detector learned depends on: it learns again, and
  // detects nothing until `protected_from`.
  relearning,
  // A pressure-only detector's rig: the hydraulic mode it sees a leak through hardly shows above
  // the transducers' noise while it learns (pipeline/mode_visibility.hpp), so no leak alarm can
  // come from it. Announced when learning ends and again after a restart.
  detection_blind,
  // The detector has not been judging for longer than the alarm's not_judged_event_seconds
  // (`reason` says why, `not_judged_since` from when): a leak opening now would go unseen. And
  // the end of that.
  not_judged,
  judging_resumed,
  // When learning ends: the feature the detector learned made a step of alarm-worthy size
  // during the learning period (detect/learned_change.hpp), so a leak may have been learned as
  // healthy. `change_t` is when, `channel` and `feature` where, the leak or index fields the size.
  learned_change,
};

constexpr std::string_view to_string(EventKind kind) {
  switch (kind) {
    case EventKind::alarm_raised:
      return "alarm_raised";
    case EventKind::alarm_cleared:
      return "alarm_cleared";
    case EventKind::alarm_acknowledged:
      return "alarm_acknowledged";
    case EventKind::driver_fault:
      return "driver_fault";
    case EventKind::driver_recovered:
      return "driver_recovered";
    case EventKind::overrun:
      return "overrun";
    case EventKind::config_reloaded:
      return "config_reloaded";
    case EventKind::config_rejected:
      return "config_rejected";
    case EventKind::state_restored:
      return "state_restored";
    case EventKind::state_discarded:
      return "state_discarded";
    case EventKind::state_save_failed:
      return "state_save_failed";
    case EventKind::daemon_started:
      return "daemon_started";
    case EventKind::daemon_stopped:
      return "daemon_stopped";
    case EventKind::relearning:
      return "relearning";
    case EventKind::detection_blind:
      return "detection_blind";
    case EventKind::not_judged:
      return "not_judged";
    case EventKind::judging_resumed:
      return "judging_resumed";
    case EventKind::learned_change:
      return "learned_change";
  }
  return "unknown";
}

inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

struct Event {
  EventKind kind = EventKind::alarm_raised;
  // Source time of the sample that completed the deciding window [s] (the capture's t under
  // replay, seconds since the group started otherwise); NaN for events not tied to a sample.
  double t = kNoValue;
  std::string actuator;     // empty for daemon-wide events
  std::string alarm;        // "internal_leakage" for alarm events
  std::string channel;      // the index channel (e.g. "p1"), or the driver name for driver events
  std::string fault;        // sensor_fault alarms: frozen, saturated, spikes or dropout
  double index = kNoValue;  // the index [Pa] that decided
  double score = kNoValue;  // the detector's score
  double baseline = kNoValue;  // learned healthy index [Pa]
  // Leak size when the detector estimates one: C_L [m^3/(s Pa)], the same in l/min/MPa, and the
  // flow in l/min at the current load pressure |p1 - p2|.
  double leak_coefficient = kNoValue;
  double leak_lpm_per_mpa = kNoValue;
  double leak_lpm = kNoValue;
  // 95 % half-widths of the two sizes above (statistics and the valve-gain uncertainty).
  double leak_lpm_per_mpa_ci95 = kNoValue;
  double leak_lpm_ci95 = kNoValue;
  double load_pressure = kNoValue;  // |p1 - p2| [Pa] over the deciding hop
  std::string message;              // human-readable detail (driver error text, counts...)
  double unix_time = kNoValue;  // wall-clock time of publication [s since 1970], set by the worker
  bool latched = false;         // alarm events: the alarm waits for acknowledgement
  // daemon_started / daemon_stopped: the program's version, its configuration file, its pid,
  // and (stopped) why and after how long.
  std::string version;
  std::string config;
  long long pid = 0;   // 0: not set
  std::string reason;  // daemon_stopped: signal, duration, end_of_sources, error; relearning: the
                       // changed options
  double uptime_s = kNoValue;
  // relearning: source times [s] of the group's newest sample when learning began again, and
  // from when the detector decides again (learning done).
  double learning_since = kNoValue;
  double protected_from = kNoValue;
  // not_judged / judging_resumed: source time [s] the detector stopped judging.
  double not_judged_since = kNoValue;
  // learned_change: the estimated source time [s] of the step, and the feature it was seen in
  // ("command_residual" or "index").
  double change_t = kNoValue;
  std::string feature;
};

// One actuator's newest decision as an output may publish it: its feature message, one JSON
// object the daemon formats from the same snapshot as /metrics and /status (views/status_json.hpp
// features_json; fields in docs/daemon.md "Many rigs: MQTT").
struct ActuatorReading {
  std::string actuator;
  std::string message;
};
// Called from the output's own thread; takes the worker's lock briefly, never the real-time
// path's. Empty when the daemon offers none.
using ReadingSource = std::function<std::vector<ActuatorReading>()>;

// A number an output counts, for the daemon's /metrics (`leakmon_` + name, labelled with the
// output's name).
struct SinkMetric {
  std::string_view name;  // e.g. "mqtt_connected"
  std::string_view help;
  bool counter = false;  // else a gauge
  double value = 0.0;
};

// Receives every event, in order, on the worker thread (never the real-time thread). publish()
// must not block for long: a sink that talks to slow devices queues and writes elsewhere.
class EventSink {
 public:
  EventSink() = default;
  virtual ~EventSink() = default;
  EventSink(const EventSink&) = delete;
  EventSink& operator=(const EventSink&) = delete;

  virtual void publish(const Event& event) = 0;
  // Make everything published so far durable (called at least once a second and at shutdown).
  virtual void flush() {}

  // Optional hooks, unused by most sinks. attach_readings: a source of live values the sink may
  // call from its own thread until it is detached (called with an empty source, which waits for
  // a call in progress). metrics: the sink's own counters, read from the metrics thread.
  virtual void attach_readings(ReadingSource source) { (void)source; }
  virtual std::string_view name() const { return {}; }
  virtual std::vector<SinkMetric> metrics() const { return {}; }
};

}  // namespace leakmon::io
