#include "views/status_json.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>

#include "views/json_writer.hpp"
#include "views/vocabulary.hpp"

namespace leakmon::views {

std::string status_json(const ServiceSnapshot& snapshot) {
  std::string out;
  out.reserve(2048);
  JsonWriter json(out);
  json.begin_object();
  write_service(json, snapshot);
  json.begin_array("groups");
  for (const auto& group : snapshot.groups) {
    json.begin_object();
    write_group(json, group);
    // Renamed; kept for one release (views/vocabulary.cpp renamed_fields()).
    json.begin_object("wakeup_latency_us");
    json.number("mean", group.wakeup_latency.mean_us());
    json.number("max", group.wakeup_latency.max_us());
    json.end_object();
    json.end_object();
  }
  json.end_array();
  json.begin_array("drivers");
  for (const auto& driver : snapshot.drivers) {
    json.begin_object();
    write_driver(json, driver);
    json.end_object();
  }
  json.end_array();
  json.begin_array("actuators");
  for (const auto& actuator : snapshot.actuators) {
    json.begin_object();
    write_actuator(json, actuator);
    // Renamed; kept for one release (views/vocabulary.cpp renamed_fields()).
    json.begin_object("index_pa");
    json.number("p1", actuator.index_p1);
    json.number("p2", actuator.index_p2);
    json.end_object();
    json.begin_object("threshold");
    json.number("raise", actuator.raise_threshold);
    json.number("clear", actuator.clear_threshold);
    json.end_object();
    json.begin_array("alarms");
    json.begin_object();
    json.string("name", actuator.alarm);
    json.string("state", pipeline::to_string(actuator.state));
    json.end_object();
    json.end_array();
    json.end_object();
  }
  json.end_array();
  json.end_object();
  out += '\n';
  return out;
}

std::string features_json(const ServiceSnapshot& snapshot,
                          const pipeline::ActuatorStatus& actuator) {
  std::string out;
  JsonWriter json(out, JsonWriter::Style::message);
  json.begin_object();
  write_fields(json, actuator_fields(), actuator, {"t"});
  json.string("actuator", actuator.name);
  write_fields(json, actuator_fields(), actuator,
               {"index_p1_pa", "score", "leak_lpm_per_mpa", "leak_lpm_per_mpa_ci95", "alarm_state",
                "learning", "judged", "not_judged_reason"});
  // Renamed; kept for one release: the p1 index in kPa (views/vocabulary.cpp renamed_fields()).
  json.number("index", actuator.index_p1 / 1e3);
  json.number("unix_time", snapshot.unix_time);
  json.end_object();
  return out;
}

namespace {

// The member `name` of `node`, or the member the previous release called it.
YAML::Node member(const YAML::Node& node, const char* name, const char* old_name = nullptr,
                  const char* old_member = nullptr) {
  if (node[name]) return node[name];
  if (old_name != nullptr && node[old_name]) {
    return old_member != nullptr ? node[old_name][old_member] : node[old_name];
  }
  return YAML::Node();
}

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
          maybe(number(member(g, "wakeup_latency_mean_us", "wakeup_latency_us", "mean")), " us", 1),
          maybe(number(member(g, "wakeup_latency_max_us", "wakeup_latency_us", "max")), " us", 1),
          text(g["overruns"]), text(g["missed_cycles"]), text(g["ring_drops"]),
          text(g["ring_high_water"]), text(g["ring_capacity"]),
          g["realtime"].as<bool>() ? "SCHED_FIFO" : "normal scheduling",
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
      if (a["alarm_state"]) {
        out += fmt::format("  alarm {}: {}\n", text(a["alarm"]), text(a["alarm_state"]));
      } else {
        for (const auto& alarm : a["alarms"]) {
          out += fmt::format("  alarm {}: {}\n", text(alarm["name"]), text(alarm["state"]));
        }
      }
      out +=
          fmt::format("  index p1 {}, p2 {}; score {} (raises at {}, clears at {}); baseline {}\n",
                      maybe(number(member(a, "index_p1_pa", "index_pa", "p1")) / 1e3, " kPa", 2),
                      maybe(number(member(a, "index_p2_pa", "index_pa", "p2")) / 1e3, " kPa", 2),
                      significant(number(a["score"])),
                      significant(number(member(a, "raise_threshold", "threshold", "raise"))),
                      significant(number(member(a, "clear_threshold", "threshold", "clear"))),
                      maybe(number(a["baseline_pa"]) / 1e3, " kPa", 2));
      // The previous release's leak_lpm_per_mpa was {estimate, ci95}.
      const YAML::Node leak_node = a["leak_lpm_per_mpa"];
      const bool old_leak = leak_node && leak_node.IsMap();
      const double leak = number(old_leak ? leak_node["estimate"] : leak_node);
      const double ci = number(old_leak ? leak_node["ci95"] : a["leak_lpm_per_mpa_ci95"]);
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
      // A status from a daemon before judging was reported has no `judged`: say nothing.
      if (a["judged"] && !a["judged"].as<bool>() && state != "learning") {
        out +=
            fmt::format("  NOT JUDGING: {} since t {} (judged {} of the time)\n",
                        text(a["not_judged_reason"]), maybe(number(a["not_judged_since"]), " s", 1),
                        maybe(100.0 * number(a["judged_share"]), " %", 0));
      }
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
