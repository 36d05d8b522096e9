#include "pipeline/event_log.hpp"

#include "config/yaml_reader.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>

namespace leakmon::pipeline {

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
  if (std::isfinite(event.not_judged_since)) {
    line += fmt::format(" not_judged_since={:.3f}s", event.not_judged_since);
  }
  if (std::isfinite(event.change_t)) line += fmt::format(" change_t={:.3f}s", event.change_t);
  if (!event.feature.empty()) line += fmt::format(" feature={}", event.feature);
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
       event.kind == io::EventKind::detection_blind || event.kind == io::EventKind::not_judged ||
       event.kind == io::EventKind::learned_change ||
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

}  // namespace leakmon::pipeline
