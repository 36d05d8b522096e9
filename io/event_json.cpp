#include "io/event_json.hpp"

#include "config/yaml_reader.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <cmath>
#include <ctime>
#include <iterator>

namespace leakmon::io {
namespace {

bool is_alarm(EventKind kind) {
  return kind == EventKind::alarm_raised || kind == EventKind::alarm_cleared ||
         kind == EventKind::alarm_acknowledged;
}

}  // namespace

void append_json_string(std::string& out, std::string_view text) {
  out += '"';
  std::size_t i = 0;
  while (i < text.size()) {
    unsigned code = 0;
    const std::size_t length = config::utf8_sequence(text, i, code);
    if (length == 0) {
      out += "\\ufffd";
      ++i;
      continue;
    }
    switch (code) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (code < 0x20 || (code >= 0x7f && code < 0xa0)) {
          out += fmt::format("\\u{:04x}", code);
        } else {
          out.append(text.substr(i, length));
        }
    }
    i += length;
  }
  out += '"';
}

void append_json_number(std::string& out, double value) {
  if (std::isfinite(value)) {
    fmt::format_to(std::back_inserter(out), "{}", value);
  } else {
    out += "null";
  }
}

std::string json_string(std::string_view text) {
  std::string out;
  append_json_string(out, text);
  return out;
}

void JsonObject::string(std::string_view key_name, std::string_view value) {
  if (value.empty()) return;
  key(key_name);
  append_json_string(text_, value);
}

void JsonObject::number(std::string_view key_name, double value) {
  if (!std::isfinite(value)) return;
  key(key_name);
  append_json_number(text_, value);
}

void JsonObject::boolean(std::string_view key_name, bool value) {
  key(key_name);
  text_ += value ? "true" : "false";
}

void JsonObject::key(std::string_view key_name) {
  text_ += text_.size() > 1 ? ", " : "";
  append_json_string(text_, key_name);
  text_ += ": ";
}

std::string to_json_line(const Event& event) {
  JsonObject json;
  json.number("t", event.t);
  json.string("event", to_string(event.kind));
  json.string("actuator", event.actuator);
  json.string("alarm", event.alarm);
  json.string("channel", event.channel);
  json.string("fault", event.fault);
  json.number("index", event.index / 1e3);
  json.number("score", event.score);
  json.number("baseline", event.baseline / 1e3);
  json.number("leak_coefficient", event.leak_coefficient);
  json.number("leak_lpm_per_mpa", event.leak_lpm_per_mpa);
  json.number("leak_lpm", event.leak_lpm);
  json.number("leak_lpm_per_mpa_ci95", event.leak_lpm_per_mpa_ci95);
  json.number("leak_lpm_ci95", event.leak_lpm_ci95);
  json.number("load_pressure_mpa", event.load_pressure / 1e6);
  if (is_alarm(event.kind)) json.boolean("latched", event.latched);
  json.string("version", event.version);
  json.string("config", event.config);
  if (event.pid != 0) json.number("pid", static_cast<double>(event.pid));
  json.string("reason", event.reason);
  json.number("uptime_s", event.uptime_s);
  json.number("learning_since", event.learning_since);
  json.number("protected_from", event.protected_from);
  json.number("not_judged_since", event.not_judged_since);
  json.number("change_t", event.change_t);
  json.string("feature", event.feature);
  json.string("message", event.message);
  if (std::isfinite(event.unix_time)) {
    const auto seconds = static_cast<std::time_t>(event.unix_time);
    const auto millis = static_cast<int>((event.unix_time - static_cast<double>(seconds)) * 1e3);
    json.string("time", fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03d}Z", fmt::gmtime(seconds), millis));
  }
  return json.finish();
}

}  // namespace leakmon::io
