#include "daemon/event_log.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>

namespace leakmon::daemon {
namespace {

// Always valid UTF-8 JSON text: quotes, backslashes and every control character (C0, DEL, C1:
// ESC and CSI included) escaped, bytes that are not UTF-8 replaced by U+FFFD.
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

class JsonObject {
 public:
  void string(std::string_view key, std::string_view value) {
    if (value.empty()) return;
    key_(key);
    append_json_string(text_, value);
  }
  void number(std::string_view key, double value) {
    if (!std::isfinite(value)) return;
    key_(key);
    text_ += fmt::format("{}", value);
  }
  void boolean(std::string_view key, bool value) {
    key_(key);
    text_ += value ? "true" : "false";
  }
  std::string finish() { return text_ + "}"; }

 private:
  void key_(std::string_view key) {
    text_ += text_.size() > 1 ? ", " : "";
    append_json_string(text_, key);
    text_ += ": ";
  }
  std::string text_ = "{";
};

bool is_alarm(io::EventKind kind) {
  return kind == io::EventKind::alarm_raised || kind == io::EventKind::alarm_cleared ||
         kind == io::EventKind::alarm_acknowledged;
}

}  // namespace

std::string to_json_line(const io::Event& event) {
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
  json.string("message", event.message);
  if (std::isfinite(event.unix_time)) {
    const auto seconds = static_cast<std::time_t>(event.unix_time);
    const auto millis = static_cast<int>((event.unix_time - static_cast<double>(seconds)) * 1e3);
    json.string("time", fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03d}Z", fmt::gmtime(seconds), millis));
  }
  return json.finish();
}

std::string to_log_line(const io::Event& event) {
  std::string line(to_string(event.kind));
  if (!event.actuator.empty()) line += fmt::format(" actuator={}", event.actuator);
  if (!event.alarm.empty()) line += fmt::format(" alarm={}", event.alarm);
  if (!event.channel.empty()) line += fmt::format(" channel={}", event.channel);
  if (!event.fault.empty()) line += fmt::format(" fault={}", event.fault);
  if (std::isfinite(event.t)) line += fmt::format(" t={:.3f}s", event.t);
  if (std::isfinite(event.index)) line += fmt::format(" index={:.2f}kPa", event.index / 1e3);
  if (std::isfinite(event.baseline)) {
    line += fmt::format(" baseline={:.2f}kPa", event.baseline / 1e3);
  }
  if (std::isfinite(event.leak_lpm_per_mpa)) {
    line += fmt::format(" leak={:.3f}l/min/MPa", event.leak_lpm_per_mpa);
  }
  if (std::isfinite(event.leak_lpm)) line += fmt::format(" ({:.3f}l/min at load)", event.leak_lpm);
  if (!event.version.empty()) line += fmt::format(" version={}", event.version);
  if (event.pid != 0) line += fmt::format(" pid={}", event.pid);
  if (!event.config.empty()) line += fmt::format(" config={}", event.config);
  if (!event.reason.empty()) line += fmt::format(" reason={}", event.reason);
  if (std::isfinite(event.uptime_s)) line += fmt::format(" uptime={:.1f}s", event.uptime_s);
  if (std::isfinite(event.learning_since)) {
    line += fmt::format(" learning_since={:.3f}s", event.learning_since);
  }
  if (std::isfinite(event.protected_from)) {
    line += fmt::format(" protected_from={:.3f}s", event.protected_from);
  }
  if (!event.message.empty()) line += fmt::format(": {}", event.message);
  // Event text can carry configuration and device content: no raw escape sequences in the log.
  return config::printable(line, 4000);
}

JsonlEventLog::JsonlEventLog(const std::string& path) : path_(path) {
  const auto parent = std::filesystem::path(path).parent_path();
  std::error_code ignored;
  if (!parent.empty()) std::filesystem::create_directories(parent, ignored);
  file_ = std::fopen(path.c_str(), "a");
  if (file_ == nullptr) {
    throw std::runtime_error(
        fmt::format("{}: cannot open event log: {}", path, std::strerror(errno)));
  }
}

JsonlEventLog::~JsonlEventLog() {
  if (file_ != nullptr) std::fclose(file_);
}

void JsonlEventLog::publish(const io::Event& event) {
  const std::string line = to_json_line(event) + "\n";
  std::fwrite(line.data(), 1, line.size(), file_);
  std::fflush(file_);
}

void JsonlEventLog::flush() { std::fflush(file_); }

void LogEventSink::publish(const io::Event& event) {
  const auto level =
      (event.kind == io::EventKind::alarm_raised || event.kind == io::EventKind::driver_fault ||
       event.kind == io::EventKind::overrun || event.kind == io::EventKind::config_rejected ||
       event.kind == io::EventKind::state_discarded ||
       event.kind == io::EventKind::state_save_failed)
          ? spdlog::level::warn
          : spdlog::level::info;
  spdlog::log(level, "{}", to_log_line(event));
}

std::unique_ptr<io::EventSink> make_jsonl_output(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "path"});
  const auto path = node.at("path");
  try {
    return std::make_unique<JsonlEventLog>(path.as_string());
  } catch (const std::runtime_error& e) {
    path.fail(e.what());
  }
}

}  // namespace leakmon::daemon
