#include "io/canlog/canlog_driver.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "io/can/signal_config.hpp"

namespace leakmon::io {

std::unique_ptr<Driver> make_canlog_driver(const config::ConfigNode& node) {
  return std::make_unique<canlog::CanlogDriver>(canlog::read_canlog_driver_config(node));
}

}  // namespace leakmon::io

namespace leakmon::io::canlog {

CanlogDriverConfig read_canlog_driver_config(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "file", "interface", "pace", "period", "max_age", "signals"});
  CanlogDriverConfig config;
  config.name = node.get_string("name");
  if (node.get_string("type") != "canlog") node.at("type").fail("expected type: canlog");
  std::filesystem::path file = node.get_string("file");
  if (file.is_relative()) {
    // Relative to the configuration file, so a config and its log can move together.
    const auto base = std::filesystem::path(node.source()).parent_path();
    if (!base.empty() && std::filesystem::exists(base)) file = base / file;
  }
  if (!std::filesystem::is_regular_file(file)) {
    node.at("file").fail("candump log '" + file.string() + "' does not exist");
  }
  config.file = file.string();
  config.interface = node.get_string("interface", "");
  config.pace = node.get_choice("pace", {"log", "fast"}, "log") == "log" ? Pace::log : Pace::fast;
  config.period_ns = std::llround(node.get_double("period", 0.002, 1e-6, 10.0) * 1e9);
  config.signals = can::read_signals(node);
  return config;
}

CanlogDriver::CanlogDriver(CanlogDriverConfig config)
    : name_(std::move(config.name)),
      file_(std::move(config.file)),
      interface_(std::move(config.interface)),
      pace_(config.pace),
      period_ns_(config.period_ns),
      decoder_(std::move(config.signals)) {
  for (const auto& s : decoder_.signals()) channels_.push_back(s.channel);
}

void CanlogDriver::start() {
  try {
    frames_ = read_candump_file(file_, interface_).frames;
  } catch (const std::runtime_error& e) {
    throw DriverError(e.what());
  }
  if (frames_.empty()) {
    throw DriverError(file_ + ": no frames" +
                      (interface_.empty() ? std::string() : " on interface " + interface_));
  }
  next_frame_ = 0;
  reads_ = 0;
  started_clock_ = false;
  decoder_.clear();
}

ReadStatus CanlogDriver::read(const Tick& tick, std::span<double> values) noexcept {
  if (frames_.empty()) return ReadStatus::end_of_stream;
  const std::int64_t log_start = frames_.front().time_ns;
  if (!started_clock_) {
    started_clock_ = true;
    first_tick_ns_ = tick.monotonic_ns;
  }
  log_now_ns_ = pace_ == Pace::log ? log_start + (tick.monotonic_ns - first_tick_ns_)
                                   : log_start + static_cast<std::int64_t>(reads_) * period_ns_;
  // The stream ends with the first tick after the last frame, so every frame is seen once.
  if (next_frame_ >= frames_.size() && log_now_ns_ > frames_.back().time_ns) {
    return ReadStatus::end_of_stream;
  }
  ++reads_;
  for (; next_frame_ < frames_.size() && frames_[next_frame_].time_ns <= log_now_ns_;
       ++next_frame_) {
    const LoggedFrame& logged = frames_[next_frame_];
    frames_replayed_.fetch_add(1, std::memory_order_relaxed);
    if (logged.frame.error) {
      error_frames_.fetch_add(1, std::memory_order_relaxed);
      errors_.fetch_add(1, std::memory_order_relaxed);
      const can::ErrorFrameEffect effect = can::interpret_error_frame(logged.frame);
      if (effect.changes_state) bus_state_.store(effect.state, std::memory_order_relaxed);
      last_error_.store(effect.description, std::memory_order_relaxed);
      continue;
    }
    decoder_.apply(logged.frame, logged.time_ns);
  }
  short_frames_.store(decoder_.short_frames(), std::memory_order_relaxed);
  stale_values_.fetch_add(decoder_.sample(values, log_now_ns_), std::memory_order_relaxed);
  for (std::size_t i = decoder_.signals().size(); i < values.size(); ++i) {
    values[i] = std::numeric_limits<double>::quiet_NaN();
  }
  source_time_ns_.store(log_now_ns_, std::memory_order_relaxed);
  has_source_time_.store(true, std::memory_order_release);
  return ReadStatus::ok;
}

std::optional<double> CanlogDriver::source_time() const {
  if (!has_source_time_.load(std::memory_order_acquire)) return std::nullopt;
  return static_cast<double>(source_time_ns_.load(std::memory_order_relaxed)) * 1e-9;
}

DriverHealth CanlogDriver::health() const {
  DriverHealth h;
  const can::BusState bus = bus_state_.load();
  h.status = can::device_status(bus);
  h.detail = to_string(bus);
  h.last_error = last_error_.load();
  h.errors = errors_.load() + short_frames_.load();
  h.stale_values = stale_values_.load();
  return h;
}

}  // namespace leakmon::io::canlog
