#include "views/status_json.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>

#include "capture/units.hpp"
#include "daemon/daemon.hpp"
#include "io/event_json.hpp"

namespace leakmon::views {
namespace {

using io::json_string;

std::string flag(bool on) { return on ? "true" : "false"; }

}  // namespace

std::string json_number(double value) {
  return std::isfinite(value) ? fmt::format("{}", value) : "null";
}

}  // namespace leakmon::views

// The service's side, until it fills a snapshot the views format.
namespace leakmon::daemon {
using namespace leakmon::views;
std::string Daemon::status_json() const {
  const std::int64_t now = realtime::monotonic_now_ns();
  std::string out = "{";
  out += fmt::format("\"version\":{},\"uptime_s\":{},\"config\":{},", json_string(LEAKMON_VERSION),
                     json_number(static_cast<double>(now - started_ns_) / 1e9),
                     json_string(config_path_));
  out += fmt::format("\"reload\":{{\"ok\":{},\"reloads\":{},\"failures\":{},\"last_unix\":{}}},",
                     flag(last_reload_ok_.load()), reloads_.load(), reload_failures_.load(),
                     last_reload_unix_.load());
  out += "\"groups\":[";
  for (std::size_t i = 0; i < groups_.size(); ++i) {
    const auto& g = *groups_[i];
    const auto& c = g.loop->counters();
    const std::int64_t last = c.last_cycle_ns.load();
    out += fmt::format(
        "{}{{\"name\":{},\"cycles\":{},\"overruns\":{},\"missed_cycles\":{},\"ring_drops\":{},"
        "\"ring_high_water\":{},\"ring_capacity\":{},\"realtime\":{},\"wakeup_latency_us\":{{"
        "\"mean\":{},\"max\":{}}},\"last_cycle_age_s\":{},\"ended\":{}}}",
        i == 0 ? "" : ",", json_string(g.config.name), c.cycles.load(), c.overruns.load(),
        c.missed_cycles.load(), c.ring_drops.load(), c.ring_high_water.load(), g.ring->capacity(),
        flag(g.realtime.fifo),
        json_number(c.cycles.load() == 0 ? NAN : c.wakeup_latency.mean_ns() / 1e3),
        json_number(c.cycles.load() == 0 ? NAN
                                         : static_cast<double>(c.wakeup_latency.max_ns()) / 1e3),
        json_number(last == 0 ? NAN : static_cast<double>(now - last) / 1e9),
        flag(c.end_of_stream.load()));
  }
  out += "],\"drivers\":[";
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    const auto health = drivers_[i]->health();
    out += fmt::format(
        "{}{{\"name\":{},\"status\":{},\"detail\":{},\"last_error\":{},\"errors\":{},"
        "\"reconnects\":{},\"stale_values\":{}}}",
        i == 0 ? "" : ",", json_string(drivers_[i]->name()),
        json_string(io::to_string(health.status)), json_string(health.detail),
        health.last_error.empty() ? "null" : json_string(health.last_error), health.errors,
        health.reconnects, health.stale_values);
  }
  out += "],\"actuators\":[";
  const auto actuators = worker_->status();
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const auto& a = actuators[i];
    const char* state = a.state != pipeline::AlarmState::normal ? "alarm"
                        : a.learning                            ? "learning"
                                                                : "monitoring";
    out += fmt::format(
        "{}{{\"name\":{},\"detector\":{},\"state\":\"{}\",\"learning_seconds_left\":{},"
        "\"t\":{},\"index_pa\":{{\"p1\":{},\"p2\":{}}},\"score\":{},\"threshold\":{{\"raise\":{},"
        "\"clear\":{}}},\"baseline_pa\":{},\"leak_lpm_per_mpa\":{{\"estimate\":{},\"ci95\":{}}},"
        "\"oil_temperature_c\":{},\"alarms\":[{{\"name\":{},\"state\":{}}}],\"suspended\":{},"
        "\"mode_visibility\":{},\"detection_blind\":{},\"decisions\":{},\"gap_samples\":{},"
        "\"sensors\":[",
        i == 0 ? "" : ",", json_string(a.name), json_string(a.detector), state,
        json_number(a.learning ? a.learning_seconds_left : NAN), json_number(a.t),
        json_number(a.index_p1), json_number(a.index_p2), json_number(a.score),
        json_number(a.raise_threshold), json_number(a.clear_threshold), json_number(a.baseline),
        json_number(units::lpm_per_mpa(a.leak_coefficient)),
        json_number(units::lpm_per_mpa(a.leak_coefficient_ci)), json_number(a.oil_temperature),
        json_string(a.alarm), json_string(to_string(a.state)), flag(a.suspended),
        json_number(a.mode_visibility), flag(a.detection_blind), a.decisions, a.gap_samples);
    for (std::size_t k = 0; k < a.channels.size(); ++k) {
      const auto& c = a.channels[k];
      out += fmt::format(
          "{}{{\"channel\":{},\"status\":{},\"fault\":{},\"spikes_rejected\":{}}}",
          k == 0 ? "" : ",", json_string(c.channel), json_string(io::to_string(c.status)),
          c.fault == detect::SensorFault::none ? "null" : json_string(detect::to_string(c.fault)),
          c.spikes_rejected);
    }
    out += "]}";
  }
  out += "]}\n";
  return out;
}
std::string Daemon::status_text() const { return views::status_text_from_json(status_json()); }

}  // namespace leakmon::daemon

namespace leakmon::views {

namespace {

// A number from the document, NaN for null (or absent).
double number(const YAML::Node& node) {
  if (!node || node.IsNull()) return NAN;
  return node.as<double>();
}

std::string text(const YAML::Node& node) {
  if (!node || node.IsNull()) return {};
  return node.as<std::string>();
}

// `format` applied to the value, or "n/a" when the value is not known.
std::string maybe(double value, std::string_view unit, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  return fmt::format("{:.{}f}{}", value, decimals, unit);
}

std::string significant(double value) {
  if (!std::isfinite(value)) return "n/a";
  return fmt::format("{:.3g}", value);
}

}  // namespace

std::string status_text_from_json(std::string_view json) {
  YAML::Node doc;
  try {
    doc = YAML::Load(std::string(json));
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("status is not JSON: {}", e.what()));
  }
  if (!doc.IsMap() || !doc["actuators"] || !doc["groups"]) {
    throw std::runtime_error("status has no 'actuators' or 'groups': not a leakmon /status answer");
  }
  try {
    std::string out =
        fmt::format("leakmon {} running {} s, configuration {}\n", text(doc["version"]),
                    maybe(number(doc["uptime_s"]), "", 0), text(doc["config"]));
    out += fmt::format("last reload: {}\n",
                       doc["reload"]["ok"].as<bool>() ? "ok" : "REJECTED (see log)");
    for (const auto& g : doc["groups"]) {
      out += fmt::format(
          "group {}: {} cycles, wake-up latency avg {} max {}, {} overruns, {} missed, {} ring "
          "drops (high water {}/{}), {}{}\n",
          text(g["name"]), text(g["cycles"]),
          maybe(number(g["wakeup_latency_us"]["mean"]), " us", 1),
          maybe(number(g["wakeup_latency_us"]["max"]), " us", 1), text(g["overruns"]),
          text(g["missed_cycles"]), text(g["ring_drops"]), text(g["ring_high_water"]),
          text(g["ring_capacity"]), g["realtime"].as<bool>() ? "SCHED_FIFO" : "normal scheduling",
          g["ended"].as<bool>() ? ", source ended" : "");
    }
    for (const auto& d : doc["drivers"]) {
      const std::string error = text(d["last_error"]);
      out += fmt::format("driver {}: {} (NE 107 {}){}{} ({} errors)\n", text(d["name"]),
                         text(d["detail"]), text(d["status"]), error.empty() ? "" : ": ", error,
                         text(d["errors"]));
    }
    for (const auto& a : doc["actuators"]) {
      const std::string state = text(a["state"]);
      std::string what = state;
      if (state == "learning") {
        const double left = number(a["learning_seconds_left"]);
        what = std::isfinite(left) ? fmt::format("learning, {:.0f} s left", std::ceil(left))
                                   : "learning (no decision yet)";
      } else if (state == "alarm") {
        what = "ALARM";
      }
      out += fmt::format("actuator {}: {}, detector {}, t {}\n", text(a["name"]), what,
                         text(a["detector"]), maybe(number(a["t"]), " s", 2));
      for (const auto& alarm : a["alarms"]) {
        out += fmt::format("  alarm {}: {}\n", text(alarm["name"]), text(alarm["state"]));
      }
      out +=
          fmt::format("  index p1 {}, p2 {}; score {} (raises at {}, clears at {}); baseline {}\n",
                      maybe(number(a["index_pa"]["p1"]) / 1e3, " kPa", 2),
                      maybe(number(a["index_pa"]["p2"]) / 1e3, " kPa", 2),
                      significant(number(a["score"])), significant(number(a["threshold"]["raise"])),
                      significant(number(a["threshold"]["clear"])),
                      maybe(number(a["baseline_pa"]) / 1e3, " kPa", 2));
      const double leak = number(a["leak_lpm_per_mpa"]["estimate"]);
      const double ci = number(a["leak_lpm_per_mpa"]["ci95"]);
      out += fmt::format("  leak estimate {}\n",
                         !std::isfinite(leak) ? std::string("n/a")
                         : std::isfinite(ci)  ? fmt::format("{:.3f} +/- {:.3f} l/min/MPa", leak, ci)
                                              : fmt::format("{:.3f} l/min/MPa", leak));
      const double temperature = number(a["oil_temperature_c"]);
      if (std::isfinite(temperature)) {
        out += fmt::format("  oil temperature {:.1f} degC\n", temperature);
      }
      for (const auto& c : a["sensors"]) {
        const std::string fault = text(c["fault"]);
        out += fmt::format("  channel {}: {}{}{}, {} spikes rejected\n", text(c["channel"]),
                           text(c["status"]), fault.empty() ? "" : " ", fault,
                           text(c["spikes_rejected"]));
      }
      if (a["suspended"].as<bool>()) out += "  leak decision suspended (sensor fault)\n";
      if (a["detection_blind"] && a["detection_blind"].as<bool>()) {
        out += fmt::format(
            "  BLIND: the hydraulic mode hardly showed while learning (median index {:.1f} x "
            "the transducer noise); no leak alarm can come from this detector\n",
            number(a["mode_visibility"]));
      }
    }
    return out;
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("status JSON lacks a field: {}", e.what()));
  }
}

}  // namespace leakmon::views
