// The Prometheus writer, and the daemon's metrics and status texts built with it.
#include "views/metrics_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <stdexcept>
#include <type_traits>

#include "capture/units.hpp"
#include "daemon/daemon.hpp"

namespace leakmon::views {

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

namespace {

void latency_histogram(PrometheusText& out, std::string_view name, std::string_view labels,
                       const realtime::LatencyHistogram& h) {
  static constexpr double kBucketsSeconds[] = {10e-6, 20e-6, 50e-6, 100e-6, 200e-6, 500e-6,
                                               1e-3,  2e-3,  5e-3,  10e-3,  20e-3};
  std::uint64_t cumulative[std::size(kBucketsSeconds)];
  for (std::size_t i = 0; i < std::size(kBucketsSeconds); ++i) {
    cumulative[i] =
        h.count_below(static_cast<std::int64_t>(std::llround(kBucketsSeconds[i] * 1e9)));
  }
  out.histogram(name, labels, kBucketsSeconds, cumulative, h.count(),
                static_cast<double>(h.sum_ns()) / 1e9);
}

std::uint64_t flag(bool on) { return on ? 1 : 0; }

// A gauge family with one sample per actuator, `value(actuator)`. With `skip_missing`, an
// actuator whose value is not finite gets no sample: the quantity does not exist there (no
// temperature transducer, a detector that is not judged), which NaN would misstate.
template <typename ValueOf>
void per_actuator_gauge(PrometheusText& out, std::span<const pipeline::ActuatorStatus> actuators,
                        std::string_view name, std::string_view help, ValueOf value,
                        bool skip_missing = false) {
  out.family(name, help, "gauge");
  for (const auto& a : actuators) {
    const auto v = value(a);
    if constexpr (std::is_floating_point_v<decltype(v)>) {
      if (skip_missing && !std::isfinite(v)) continue;
    }
    out.sample(name, label("actuator", a.name), v);
  }
}

}  // namespace

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

void actuator_metrics(PrometheusText& out, std::span<const pipeline::ActuatorStatus> actuators,
                      const std::map<std::string, double>& state_saved_unix, double now_unix) {
  out.family("leakmon_index_pascal", "newest wavelet index (db8 level-2 detail RMS)", "gauge");
  for (const auto& a : actuators) {
    out.sample("leakmon_index_pascal", label("actuator", a.name) + "," + label("channel", "p1"),
               a.index_p1);
    if (std::isfinite(a.index_p2)) {
      out.sample("leakmon_index_pascal", label("actuator", a.name) + "," + label("channel", "p2"),
                 a.index_p2);
    }
  }
  out.family("leakmon_detector_score", "newest detector score", "gauge");
  for (const auto& a : actuators) {
    out.sample("leakmon_detector_score",
               label("actuator", a.name) + "," + label("detector", a.detector), a.score);
  }
  per_actuator_gauge(out, actuators, "leakmon_detector_learning",
                     "1 while the detector learns the healthy baseline",
                     [](const pipeline::ActuatorStatus& a) { return flag(a.learning); });
  per_actuator_gauge(out, actuators, "leakmon_learning_remaining_seconds",
                     "source time until the detector decides (0: it decides; after a reload that "
                     "invalidated what it learned, until it has learned again)",
                     [](const pipeline::ActuatorStatus& a) { return a.learning_seconds_left; });
  out.family("leakmon_relearn_total",
             "reloads that changed an option the learned state depends on (learning started over)",
             "counter");
  for (const auto& a : actuators) {
    out.sample("leakmon_relearn_total", label("actuator", a.name), a.relearns);
  }
  out.family("leakmon_alarm_active", "1 while the alarm is annunciated", "gauge");
  for (const auto& a : actuators) {
    out.sample("leakmon_alarm_active",
               label("actuator", a.name) + "," + label("alarm", a.alarm) + "," +
                   label("state", to_string(a.state)),
               flag(a.state != pipeline::AlarmState::normal));
  }
  // FORMATS.md "Operator view and fleet": the leak size in l/min/MPa (at 40 degC where the oil
  // temperature is acquired), NaN until the detector has one; its 95 % half-width beside it.
  per_actuator_gauge(
      out, actuators, "leakmon_leak_lpm_per_mpa",
      "estimated internal leakage [l/min/MPa], at 40 degC with a temp channel",
      [](const pipeline::ActuatorStatus& a) { return units::lpm_per_mpa(a.leak_coefficient); });
  per_actuator_gauge(
      out, actuators, "leakmon_leak_lpm_per_mpa_ci95",
      "95 % half-width of the leak size [l/min/MPa]",
      [](const pipeline::ActuatorStatus& a) { return units::lpm_per_mpa(a.leak_coefficient_ci); });
  per_actuator_gauge(
      out, actuators, "leakmon_oil_temperature_celsius",
      "oil temperature (hop mean of the temp channel)",
      [](const pipeline::ActuatorStatus& a) { return a.oil_temperature; }, true);
  out.family("leakmon_sensor_status", "NAMUR NE 107 status of each transducer channel (1: current)",
             "gauge");
  for (const auto& a : actuators) {
    for (const auto& c : a.channels) {
      state_set(out, "leakmon_sensor_status",
                label("actuator", a.name) + "," + label("channel", c.channel), c.status);
    }
  }
  out.family("leakmon_sensor_spikes_rejected_total", "isolated spikes replaced before the index",
             "counter");
  for (const auto& a : actuators) {
    for (const auto& c : a.channels) {
      out.sample("leakmon_sensor_spikes_rejected_total",
                 label("actuator", a.name) + "," + label("channel", c.channel), c.spikes_rejected);
    }
  }
  per_actuator_gauge(out, actuators, "leakmon_detector_suspended",
                     "1 while a faulty channel holds the leak decision",
                     [](const pipeline::ActuatorStatus& a) { return flag(a.suspended); });
  per_actuator_gauge(
      out, actuators, "leakmon_acquisition_repeated_samples",
      "samples of the last second that repeat the one before exactly (100 of 500: the "
      "acquisition is slower than its sampling, and the leak decision is held)",
      [](const pipeline::ActuatorStatus& a) { return static_cast<double>(a.repeated_samples); });
  per_actuator_gauge(
      out, actuators, "leakmon_hydraulic_mode_visibility",
      "pressure-only detectors: median index while learning over the transducer's noise floor, "
      "best chamber (below 2.5 the rig is blind to a leak: detection_blind)",
      [](const pipeline::ActuatorStatus& a) { return a.mode_visibility; }, true);
  per_actuator_gauge(out, actuators, "leakmon_detection_blind",
                     "1 when a pressure-only detector's rig showed no hydraulic mode to see a "
                     "leak by while it learned",
                     [](const pipeline::ActuatorStatus& a) { return flag(a.detection_blind); });
  out.family("leakmon_learned_state_age_seconds",
             "seconds since the learned state kept in the state directory was saved", "gauge");
  for (const auto& a : actuators) {
    const auto saved = state_saved_unix.find(a.name);
    if (saved != state_saved_unix.end()) {
      out.sample("leakmon_learned_state_age_seconds", label("actuator", a.name),
                 std::max(0.0, now_unix - saved->second));
    }
  }
}

}  // namespace leakmon::views

// The service's side, until it fills a snapshot the views format.
namespace leakmon::daemon {
using namespace leakmon::views;
std::string Daemon::metrics_text() const {
  PrometheusText out;
  out.family("leakmon_build_info", "leakmon version", "gauge");
  out.sample("leakmon_build_info", label("version", LEAKMON_VERSION), std::uint64_t{1});

  out.family("leakmon_loop_wakeup_latency_seconds", "acquisition loop wake-up minus schedule",
             "histogram");
  for (const auto& g : groups_) {
    latency_histogram(out, "leakmon_loop_wakeup_latency_seconds", label("group", g->config.name),
                      g->loop->counters().wakeup_latency);
  }
  auto per_group = [&](std::string_view name, std::string_view help, std::string_view type,
                       auto value_of) {
    out.family(name, help, type);
    for (const auto& g : groups_) {
      out.sample(name, label("group", g->config.name), static_cast<std::uint64_t>(value_of(*g)));
    }
  };
  per_group("leakmon_loop_cycles_total", "acquisition cycles run", "counter",
            [](const Group& g) { return g.loop->counters().cycles.load(); });
  per_group("leakmon_loop_overruns_total", "late wake-ups that skipped a period", "counter",
            [](const Group& g) { return g.loop->counters().overruns.load(); });
  per_group("leakmon_loop_missed_cycles_total", "periods skipped by overruns", "counter",
            [](const Group& g) { return g.loop->counters().missed_cycles.load(); });
  per_group("leakmon_ring_drops_total", "samples dropped because the ring was full", "counter",
            [](const Group& g) { return g.loop->counters().ring_drops.load(); });
  per_group("leakmon_ring_high_water", "most samples ever queued in the ring", "gauge",
            [](const Group& g) { return g.loop->counters().ring_high_water.load(); });
  per_group("leakmon_ring_capacity", "ring capacity in samples", "gauge",
            [](const Group& g) { return g.ring->capacity(); });
  per_group("leakmon_loop_realtime", "1 when the loop runs SCHED_FIFO", "gauge",
            [](const Group& g) { return flag(g.realtime.fifo); });

  out.family("leakmon_cpu_wakeup_latency_request_held",
             "1 while the CPU wake-up latency request (/dev/cpu_dma_latency) is held", "gauge");
  out.sample("leakmon_cpu_wakeup_latency_request_held", "", flag(cpu_latency_.held()));
  out.family("leakmon_samples_processed_total", "samples the worker consumed", "counter");
  out.sample("leakmon_samples_processed_total", "", worker_->samples_processed());
  out.family("leakmon_events_total", "events published", "counter");
  out.sample("leakmon_events_total", "", worker_->events_published());
  out.family("leakmon_decision_latency_seconds", "sample acquisition to decision and events",
             "histogram");
  latency_histogram(out, "leakmon_decision_latency_seconds", "", worker_->decision_latency());

  actuator_metrics(
      out, worker_->status(), state_saved_unix(),
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count());

  std::vector<io::DriverHealth> health;
  for (const auto& d : drivers_) health.push_back(d->health());
  out.family("leakmon_driver_errors_total", "driver communication errors", "counter");
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    out.sample("leakmon_driver_errors_total", label("driver", drivers_[i]->name()),
               health[i].errors);
  }
  out.family("leakmon_driver_up", "1 when the driver reports NE 107 status ok", "gauge");
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    out.sample("leakmon_driver_up",
               label("driver", drivers_[i]->name()) + "," + label("state", health[i].detail),
               flag(health[i].status == io::DeviceStatus::ok));
  }
  out.family("leakmon_driver_status", "driver health as NAMUR NE 107 category", "gauge");
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    state_set(out, "leakmon_driver_status", label("driver", drivers_[i]->name()), health[i].status);
  }
  out.family("leakmon_driver_reconnects_total", "driver reconnects", "counter");
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    out.sample("leakmon_driver_reconnects_total", label("driver", drivers_[i]->name()),
               health[i].reconnects);
  }
  out.family("leakmon_driver_stale_values_total",
             "reads that gave a gap because the value was too old", "counter");
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    out.sample("leakmon_driver_stale_values_total", label("driver", drivers_[i]->name()),
               health[i].stale_values);
  }

  out.family("leakmon_config_reload_success", "1 when the last reload (or start) succeeded",
             "gauge");
  out.sample("leakmon_config_reload_success", "", flag(last_reload_ok_.load()));
  out.family("leakmon_config_reloads_total", "reloads applied", "counter");
  out.sample("leakmon_config_reloads_total", "", reloads_.load());
  out.family("leakmon_config_reload_failures_total", "reloads rejected", "counter");
  out.sample("leakmon_config_reload_failures_total", "", reload_failures_.load());
  out.family("leakmon_config_last_reload_timestamp_seconds", "unix time of the last reload attempt",
             "gauge");
  out.sample("leakmon_config_last_reload_timestamp_seconds", "", last_reload_unix_.load());

  // Outputs' own counters (io::EventSink::metrics), one family per name across outputs.
  std::vector<std::pair<std::string, io::SinkMetric>> sink_metrics;
  {
    std::lock_guard lock(sinks_mutex_);
    for (const auto& sink : sinks_) {
      for (const auto& metric : sink->metrics())
        sink_metrics.emplace_back(std::string(sink->name()), metric);
    }
  }
  std::stable_sort(sink_metrics.begin(), sink_metrics.end(),
                   [](const auto& a, const auto& b) { return a.second.name < b.second.name; });
  for (std::size_t i = 0; i < sink_metrics.size(); ++i) {
    const auto& [output, metric] = sink_metrics[i];
    const std::string name = fmt::format("leakmon_{}", metric.name);
    if (i == 0 || sink_metrics[i - 1].second.name != metric.name)
      out.family(name, metric.help, metric.counter ? "counter" : "gauge");
    out.sample(name, label("output", output), metric.value);
  }
  out.family("leakmon_http_requests_total", "HTTP requests whose head was read", "counter");
  out.sample("leakmon_http_requests_total", "", http_counters_.requests.load());
  out.family("leakmon_http_rejected_total",
             "HTTP requests refused before routing (400 target, 413 body, 431 headers)", "counter");
  out.sample("leakmon_http_rejected_total", "", http_counters_.rejected.load());
  out.family("leakmon_http_deadline_closes_total",
             "HTTP connections closed because their request outlived the deadline", "counter");
  out.sample("leakmon_http_deadline_closes_total", "", http_counters_.deadline_closes.load());
  out.family("leakmon_http_connections", "open HTTP connections", "gauge");
  out.sample("leakmon_http_connections", "", http_counters_.open_connections.load());
  return out.take();
}
}  // namespace leakmon::daemon

namespace leakmon::views {}  // namespace leakmon::views
