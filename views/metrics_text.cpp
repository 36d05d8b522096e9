#include "views/metrics_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <type_traits>

#include "capture/units.hpp"
#include "pipeline/alarm.hpp"

namespace leakmon::views {
namespace {

using pipeline::ActuatorStatus;
using Type = MetricType;

// Every family /metrics exports, declared once (docs/daemon.md lists them). The outputs' own
// counters (io::EventSink::metrics) are declared by each output.
constexpr MetricFamily kBuildInfo{"leakmon_build_info", "leakmon version", Type::gauge};
constexpr MetricFamily kLoopWakeupLatency{"leakmon_loop_wakeup_latency_seconds",
                                          "acquisition loop wake-up minus schedule",
                                          Type::histogram};
constexpr MetricFamily kLoopCycles{"leakmon_loop_cycles_total", "acquisition cycles run",
                                   Type::counter};
constexpr MetricFamily kLoopOverruns{"leakmon_loop_overruns_total",
                                     "late wake-ups that skipped a period", Type::counter};
constexpr MetricFamily kLoopMissedCycles{"leakmon_loop_missed_cycles_total",
                                         "periods skipped by overruns", Type::counter};
constexpr MetricFamily kRingDrops{"leakmon_ring_drops_total",
                                  "samples dropped because the ring was full", Type::counter};
constexpr MetricFamily kRingHighWater{"leakmon_ring_high_water",
                                      "most samples ever queued in the ring", Type::gauge};
constexpr MetricFamily kRingCapacity{"leakmon_ring_capacity", "ring capacity in samples",
                                     Type::gauge};
constexpr MetricFamily kLoopRealtime{"leakmon_loop_realtime", "1 when the loop runs SCHED_FIFO",
                                     Type::gauge};
constexpr MetricFamily kCpuLatencyRequestHeld{
    "leakmon_cpu_wakeup_latency_request_held",
    "1 while the CPU wake-up latency request (/dev/cpu_dma_latency) is held", Type::gauge};
constexpr MetricFamily kSamplesProcessed{"leakmon_samples_processed_total",
                                         "samples the worker consumed", Type::counter};
constexpr MetricFamily kEvents{"leakmon_events_total", "events published", Type::counter};
constexpr MetricFamily kDecisionLatency{"leakmon_decision_latency_seconds",
                                        "sample acquisition to decision and events",
                                        Type::histogram};
constexpr MetricFamily kIndex{"leakmon_index_pascal",
                              "newest wavelet index (db8 level-2 detail RMS)", Type::gauge};
constexpr MetricFamily kDetectorScore{"leakmon_detector_score", "newest detector score",
                                      Type::gauge};
constexpr MetricFamily kDetectorLearning{
    "leakmon_detector_learning", "1 while the detector learns the healthy baseline", Type::gauge};
constexpr MetricFamily kLearningRemaining{
    "leakmon_learning_remaining_seconds",
    "source time until the detector decides (0: it decides; after a reload that invalidated what "
    "it learned, until it has learned again)",
    Type::gauge};
constexpr MetricFamily kRelearn{
    "leakmon_relearn_total",
    "reloads that changed an option the learned state depends on (learning started over)",
    Type::counter};
constexpr MetricFamily kAlarmActive{"leakmon_alarm_active", "1 while the alarm is annunciated",
                                    Type::gauge};
// FORMATS.md "Operator view and fleet": the leak size in l/min/MPa (at 40 degC where the oil
// temperature is acquired), NaN until the detector has one; its 95 % half-width beside it.
constexpr MetricFamily kLeak{"leakmon_leak_lpm_per_mpa",
                             "estimated internal leakage [l/min/MPa], at 40 degC with a temp "
                             "channel",
                             Type::gauge};
constexpr MetricFamily kLeakCi95{"leakmon_leak_lpm_per_mpa_ci95",
                                 "95 % half-width of the leak size [l/min/MPa]", Type::gauge};
constexpr MetricFamily kOilTemperature{"leakmon_oil_temperature_celsius",
                                       "oil temperature (hop mean of the temp channel)",
                                       Type::gauge};
constexpr MetricFamily kSensorStatus{"leakmon_sensor_status",
                                     "NAMUR NE 107 status of each transducer channel (1: current)",
                                     Type::gauge};
constexpr MetricFamily kSpikesRejected{"leakmon_sensor_spikes_rejected_total",
                                       "isolated spikes replaced before the index", Type::counter};
constexpr MetricFamily kDetectorSuspended{
    "leakmon_detector_suspended", "1 while a faulty channel holds the leak decision", Type::gauge};
constexpr MetricFamily kRepeatedSamples{
    "leakmon_acquisition_repeated_samples",
    "samples of the last second that repeat the one before exactly (100 of 500: the acquisition "
    "is slower than its sampling, and the leak decision is held)",
    Type::gauge};
constexpr MetricFamily kModeVisibility{
    "leakmon_hydraulic_mode_visibility",
    "pressure-only detectors: median index while learning over the transducer's noise floor, "
    "best chamber (below 2.5 the rig is blind to a leak: detection_blind)",
    Type::gauge};
constexpr MetricFamily kDetectionBlind{
    "leakmon_detection_blind",
    "1 when a pressure-only detector's rig showed no hydraulic mode to see a leak by while it "
    "learned",
    Type::gauge};
// Judging (detect::NotJudgedReason): whether the newest decision could have revealed a leak, and
// why not as a state set over every reason; two counters whose ratio is the judged share.
constexpr MetricFamily kJudged{
    "leakmon_judged",
    "1 while the detector judges (its decisions could reveal a leak), 0 while it does not",
    Type::gauge};
constexpr MetricFamily kNotJudgedReason{"leakmon_not_judged_reason",
                                        "why the detector does not judge (1: current reason)",
                                        Type::gauge};
constexpr MetricFamily kJudgedSeconds{"leakmon_judged_seconds_total",
                                      "source seconds of decisions that judged", Type::counter};
constexpr MetricFamily kDecidedSeconds{
    "leakmon_decided_seconds_total",
    "source seconds of decisions (judged or not, held back by a sensor fault included)",
    Type::counter};
constexpr MetricFamily kLearnedStateAge{
    "leakmon_learned_state_age_seconds",
    "seconds since the learned state kept in the state directory was saved", Type::gauge};
constexpr MetricFamily kDriverErrors{"leakmon_driver_errors_total", "driver communication errors",
                                     Type::counter};
constexpr MetricFamily kDriverUp{"leakmon_driver_up", "1 when the driver reports NE 107 status ok",
                                 Type::gauge};
constexpr MetricFamily kDriverStatus{"leakmon_driver_status",
                                     "driver health as NAMUR NE 107 category", Type::gauge};
constexpr MetricFamily kDriverReconnects{"leakmon_driver_reconnects_total", "driver reconnects",
                                         Type::counter};
constexpr MetricFamily kDriverStaleValues{"leakmon_driver_stale_values_total",
                                          "reads that gave a gap because the value was too old",
                                          Type::counter};
constexpr MetricFamily kReloadSuccess{"leakmon_config_reload_success",
                                      "1 when the last reload (or start) succeeded", Type::gauge};
constexpr MetricFamily kReloads{"leakmon_config_reloads_total", "reloads applied", Type::counter};
constexpr MetricFamily kReloadFailures{"leakmon_config_reload_failures_total", "reloads rejected",
                                       Type::counter};
constexpr MetricFamily kLastReload{"leakmon_config_last_reload_timestamp_seconds",
                                   "unix time of the last reload attempt", Type::gauge};
constexpr MetricFamily kHttpRequests{"leakmon_http_requests_total",
                                     "HTTP requests whose head was read", Type::counter};
constexpr MetricFamily kHttpRejected{
    "leakmon_http_rejected_total",
    "HTTP requests refused before routing (400 target, 413 body, 431 headers)", Type::counter};
constexpr MetricFamily kHttpDeadlineCloses{
    "leakmon_http_deadline_closes_total",
    "HTTP connections closed because their request outlived the deadline", Type::counter};
constexpr MetricFamily kHttpConnections{"leakmon_http_connections", "open HTTP connections",
                                        Type::gauge};

std::uint64_t flag(bool on) { return on ? 1 : 0; }

void latency_histogram(PrometheusText& out, const MetricFamily& family, std::string_view labels,
                       const LatencySummary& h) {
  out.histogram(family.name, labels, kLatencyBucketsSeconds, h.below, h.count,
                static_cast<double>(h.sum_ns) / 1e9);
}

// A gauge family with one sample per actuator, `value(actuator)`. With `skip_missing`, an
// actuator whose value is not finite gets no sample: the quantity does not exist there (no
// temperature transducer, a detector that is not judged), which NaN would misstate.
template <typename ValueOf>
void per_actuator_gauge(PrometheusText& out, std::span<const ActuatorStatus> actuators,
                        const MetricFamily& family, ValueOf value, bool skip_missing = false) {
  out.family(family);
  for (const auto& a : actuators) {
    const auto v = value(a);
    if constexpr (std::is_floating_point_v<decltype(v)>) {
      if (skip_missing && !std::isfinite(v)) continue;
    }
    out.sample(family, label("actuator", a.name), v);
  }
}

// A family with one sample per sampling group, `value(group)` as a count.
template <typename ValueOf>
void per_group(PrometheusText& out, std::span<const GroupSnapshot> groups,
               const MetricFamily& family, ValueOf value) {
  out.family(family);
  for (const auto& g : groups) {
    out.sample(family, label("group", g.name), static_cast<std::uint64_t>(value(g)));
  }
}

}  // namespace

std::string escape_label_value(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

std::string metric_number(double value) {
  return std::isfinite(value) ? fmt::format("{}", value) : "NaN";
}

std::string label(std::string_view name, std::string_view value) {
  return fmt::format("{}=\"{}\"", name, escape_label_value(value));
}

std::string_view to_string(MetricType type) {
  switch (type) {
    case MetricType::counter:
      return "counter";
    case MetricType::gauge:
      return "gauge";
    case MetricType::histogram:
      return "histogram";
  }
  return "untyped";
}

void PrometheusText::family(const MetricFamily& family) {
  this->family(family.name, family.help, to_string(family.type));
}

void PrometheusText::family(std::string_view name, std::string_view help, std::string_view type) {
  out_ += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
}

void PrometheusText::sample(std::string_view name, std::string_view labels, std::uint64_t value) {
  if (labels.empty()) {
    out_ += fmt::format("{} {}\n", name, value);
  } else {
    out_ += fmt::format("{}{{{}}} {}\n", name, labels, value);
  }
}

void PrometheusText::sample(std::string_view name, std::string_view labels, std::int64_t value) {
  if (labels.empty()) {
    out_ += fmt::format("{} {}\n", name, value);
  } else {
    out_ += fmt::format("{}{{{}}} {}\n", name, labels, value);
  }
}

void PrometheusText::sample(std::string_view name, std::string_view labels, double value) {
  if (labels.empty()) {
    out_ += fmt::format("{} {}\n", name, metric_number(value));
  } else {
    out_ += fmt::format("{}{{{}}} {}\n", name, labels, metric_number(value));
  }
}

void PrometheusText::histogram(std::string_view name, std::string_view labels,
                               std::span<const double> upper_bounds,
                               std::span<const std::uint64_t> cumulative, std::uint64_t count,
                               double sum) {
  if (upper_bounds.size() != cumulative.size()) {
    throw std::invalid_argument(fmt::format("histogram {}: {} bounds but {} counts", name,
                                            upper_bounds.size(), cumulative.size()));
  }
  const std::string_view sep = labels.empty() ? "" : ",";
  for (std::size_t i = 0; i < upper_bounds.size(); ++i) {
    out_ += fmt::format("{}_bucket{{{}{}le=\"{}\"}} {}\n", name, labels, sep, upper_bounds[i],
                        cumulative[i]);
  }
  out_ += fmt::format("{}_bucket{{{}{}le=\"+Inf\"}} {}\n", name, labels, sep, count);
  // An empty label set is still written as `{}` here, as the daemon always has.
  out_ += fmt::format("{}_sum{{{}}} {}\n", name, labels, sum);
  out_ += fmt::format("{}_count{{{}}} {}\n", name, labels, count);
}

void state_set(PrometheusText& out, std::string_view name, std::string_view labels,
               io::DeviceStatus current) {
  const std::string_view sep = labels.empty() ? "" : ",";
  for (const io::DeviceStatus status :
       {io::DeviceStatus::ok, io::DeviceStatus::failure, io::DeviceStatus::function_check,
        io::DeviceStatus::out_of_specification, io::DeviceStatus::maintenance_required}) {
    out.sample(name, fmt::format("{}{}{}", labels, sep, label("status", io::to_string(status))),
               flag(current == status));
  }
}

void actuator_metrics(PrometheusText& out, std::span<const ActuatorStatus> actuators,
                      double now_unix) {
  out.family(kIndex);
  for (const auto& a : actuators) {
    out.sample(kIndex, label("actuator", a.name) + "," + label("channel", "p1"), a.index_p1);
    if (std::isfinite(a.index_p2)) {
      out.sample(kIndex, label("actuator", a.name) + "," + label("channel", "p2"), a.index_p2);
    }
  }
  out.family(kDetectorScore);
  for (const auto& a : actuators) {
    out.sample(kDetectorScore, label("actuator", a.name) + "," + label("detector", a.detector),
               a.score);
  }
  per_actuator_gauge(out, actuators, kDetectorLearning,
                     [](const ActuatorStatus& a) { return flag(a.learning); });
  per_actuator_gauge(out, actuators, kLearningRemaining,
                     [](const ActuatorStatus& a) { return a.learning_seconds_left; });
  out.family(kRelearn);
  for (const auto& a : actuators) out.sample(kRelearn, label("actuator", a.name), a.relearns);
  out.family(kAlarmActive);
  for (const auto& a : actuators) {
    // `alarm_state` is the alarm's ISA-18.2 state; `state`, the same value, is its name before
    // the one vocabulary (views/vocabulary.hpp), kept for one release.
    const std::string_view alarm_state = pipeline::to_string(a.state);
    out.sample(kAlarmActive,
               label("actuator", a.name) + "," + label("alarm", a.alarm) + "," +
                   label("alarm_state", alarm_state) + "," + label("state", alarm_state),
               flag(a.state != pipeline::AlarmState::normal));
  }
  per_actuator_gauge(out, actuators, kLeak, [](const ActuatorStatus& a) {
    return units::lpm_per_mpa(a.leak_coefficient);
  });
  per_actuator_gauge(out, actuators, kLeakCi95, [](const ActuatorStatus& a) {
    return units::lpm_per_mpa(a.leak_coefficient_ci);
  });
  per_actuator_gauge(
      out, actuators, kOilTemperature, [](const ActuatorStatus& a) { return a.oil_temperature; },
      true);
  out.family(kSensorStatus);
  for (const auto& a : actuators) {
    for (const auto& c : a.channels) {
      state_set(out, kSensorStatus.name,
                label("actuator", a.name) + "," + label("channel", c.channel), c.status);
    }
  }
  out.family(kSpikesRejected);
  for (const auto& a : actuators) {
    for (const auto& c : a.channels) {
      out.sample(kSpikesRejected, label("actuator", a.name) + "," + label("channel", c.channel),
                 c.spikes_rejected);
    }
  }
  per_actuator_gauge(out, actuators, kDetectorSuspended,
                     [](const ActuatorStatus& a) { return flag(a.suspended); });
  per_actuator_gauge(out, actuators, kRepeatedSamples, [](const ActuatorStatus& a) {
    return static_cast<double>(a.repeated_samples);
  });
  per_actuator_gauge(
      out, actuators, kModeVisibility, [](const ActuatorStatus& a) { return a.mode_visibility; },
      true);
  per_actuator_gauge(out, actuators, kDetectionBlind,
                     [](const ActuatorStatus& a) { return flag(a.detection_blind); });
  per_actuator_gauge(out, actuators, kJudged,
                     [](const ActuatorStatus& a) { return flag(a.judged); });
  out.family(kNotJudgedReason);
  for (const auto& a : actuators) {
    for (std::size_t r = 1; r < detect::kNotJudgedReasonNames.size(); ++r) {
      out.sample(
          kNotJudgedReason,
          label("actuator", a.name) + "," + label("reason", detect::kNotJudgedReasonNames[r]),
          flag(!a.judged && static_cast<std::size_t>(a.not_judged_reason) == r));
    }
  }
  out.family(kJudgedSeconds);
  for (const auto& a : actuators) {
    out.sample(kJudgedSeconds, label("actuator", a.name), a.judged_seconds);
  }
  out.family(kDecidedSeconds);
  for (const auto& a : actuators) {
    out.sample(kDecidedSeconds, label("actuator", a.name), a.decided_seconds);
  }
  out.family(kLearnedStateAge);
  for (const auto& a : actuators) {
    if (std::isfinite(a.learned_state_saved_unix)) {
      out.sample(kLearnedStateAge, label("actuator", a.name),
                 std::max(0.0, now_unix - a.learned_state_saved_unix));
    }
  }
}

std::string metrics_text(const ServiceSnapshot& s) {
  PrometheusText out;
  out.family(kBuildInfo);
  out.sample(kBuildInfo, label("version", s.version), std::uint64_t{1});

  out.family(kLoopWakeupLatency);
  for (const auto& g : s.groups) {
    latency_histogram(out, kLoopWakeupLatency, label("group", g.name), g.wakeup_latency);
  }
  per_group(out, s.groups, kLoopCycles, [](const GroupSnapshot& g) { return g.cycles; });
  per_group(out, s.groups, kLoopOverruns, [](const GroupSnapshot& g) { return g.overruns; });
  per_group(out, s.groups, kLoopMissedCycles,
            [](const GroupSnapshot& g) { return g.missed_cycles; });
  per_group(out, s.groups, kRingDrops, [](const GroupSnapshot& g) { return g.ring_drops; });
  per_group(out, s.groups, kRingHighWater,
            [](const GroupSnapshot& g) { return g.ring_high_water; });
  per_group(out, s.groups, kRingCapacity, [](const GroupSnapshot& g) { return g.ring_capacity; });
  per_group(out, s.groups, kLoopRealtime, [](const GroupSnapshot& g) { return flag(g.realtime); });

  out.family(kCpuLatencyRequestHeld);
  out.sample(kCpuLatencyRequestHeld, "", flag(s.cpu_latency_request_held));
  out.family(kSamplesProcessed);
  out.sample(kSamplesProcessed, "", s.samples_processed);
  out.family(kEvents);
  out.sample(kEvents, "", s.events);
  out.family(kDecisionLatency);
  latency_histogram(out, kDecisionLatency, "", s.decision_latency);

  actuator_metrics(out, s.actuators, s.unix_time);

  out.family(kDriverErrors);
  for (const auto& d : s.drivers) {
    out.sample(kDriverErrors, label("driver", d.name), d.health.errors);
  }
  out.family(kDriverUp);
  for (const auto& d : s.drivers) {
    // `detail` is the driver's own word for its condition; `state`, the same value, is its name
    // before the one vocabulary (views/vocabulary.hpp), kept for one release.
    out.sample(kDriverUp,
               label("driver", d.name) + "," + label("detail", d.health.detail) + "," +
                   label("state", d.health.detail),
               flag(d.health.status == io::DeviceStatus::ok));
  }
  out.family(kDriverStatus);
  for (const auto& d : s.drivers) {
    state_set(out, kDriverStatus.name, label("driver", d.name), d.health.status);
  }
  out.family(kDriverReconnects);
  for (const auto& d : s.drivers) {
    out.sample(kDriverReconnects, label("driver", d.name), d.health.reconnects);
  }
  out.family(kDriverStaleValues);
  for (const auto& d : s.drivers) {
    out.sample(kDriverStaleValues, label("driver", d.name), d.health.stale_values);
  }

  out.family(kReloadSuccess);
  out.sample(kReloadSuccess, "", flag(s.reload.ok));
  out.family(kReloads);
  out.sample(kReloads, "", s.reload.reloads);
  out.family(kReloadFailures);
  out.sample(kReloadFailures, "", s.reload.failures);
  out.family(kLastReload);
  out.sample(kLastReload, "", s.reload.last_unix);

  // Outputs' own counters (io::EventSink::metrics), one family per name across outputs; the
  // snapshot holds them sorted by name.
  for (std::size_t i = 0; i < s.output_metrics.size(); ++i) {
    const auto& [output, metric] = s.output_metrics[i];
    const std::string name = fmt::format("leakmon_{}", metric.name);
    if (i == 0 || s.output_metrics[i - 1].metric.name != metric.name)
      out.family(name, metric.help, metric.counter ? "counter" : "gauge");
    out.sample(name, label("output", output), metric.value);
  }
  out.family(kHttpRequests);
  out.sample(kHttpRequests, "", s.http.requests);
  out.family(kHttpRejected);
  out.sample(kHttpRejected, "", s.http.rejected);
  out.family(kHttpDeadlineCloses);
  out.sample(kHttpDeadlineCloses, "", s.http.deadline_closes);
  out.family(kHttpConnections);
  out.sample(kHttpConnections, "", s.http.open_connections);
  return out.take();
}

}  // namespace leakmon::views
