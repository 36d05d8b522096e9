#include "io/replay/replay_driver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

namespace leakmon::io {

ReplayDriver::ReplayDriver(ReplaySettings settings) : settings_(std::move(settings)) {
  capture::CaptureReader header(settings_.path);
  select_columns(header.columns());
}

ReplayDriver::ReplayDriver(ReplaySettings settings, std::shared_ptr<const capture::Capture> capture)
    : settings_(std::move(settings)), capture_(std::move(capture)) {
  select_columns(capture_->columns);
  bind_columns();
}

void ReplayDriver::select_columns(const std::vector<std::string>& capture_columns) {
  if (settings_.channels.empty()) {
    for (const auto& column : capture_columns) {
      if (column != "t") channels_.push_back(column);
    }
    return;
  }
  for (const auto& wanted : settings_.channels) {
    if (wanted == "t" || std::find(capture_columns.begin(), capture_columns.end(), wanted) ==
                             capture_columns.end()) {
      throw DriverError(fmt::format("replay driver '{}': {} has no column '{}' (it has: {})",
                                    settings_.name, settings_.path, wanted,
                                    fmt::join(capture_columns, ", ")));
    }
    channels_.push_back(wanted);
  }
}

void ReplayDriver::bind_columns() {
  t_ = &capture_->column("t");
  columns_.clear();
  for (const auto& channel : channels_) columns_.push_back(&capture_->column(channel));
}

void ReplayDriver::start() {
  if (!capture_) {
    try {
      capture_ = std::make_shared<const capture::Capture>(capture::read_capture(settings_.path));
    } catch (const capture::CaptureError& e) {
      throw DriverError(e.what());
    }
    bind_columns();
  }
  if (settings_.loop && capture_->rows() < 2) {
    throw DriverError(
        fmt::format("replay driver '{}': a looping capture needs at least 2 rows", settings_.name));
  }
  next_row_ = 0;
  loop_offset_ = 0.0;
  source_time_.reset();
}

double ReplayDriver::sample_rate_hz() const { return capture_ ? capture_->sample_rate_hz() : 0.0; }

ReadStatus ReplayDriver::read(const Tick& /*tick*/, std::span<double> values) noexcept {
  const std::size_t rows = t_ ? t_->size() : 0;
  if (next_row_ >= rows) {
    if (!settings_.loop || rows < 2) return ReadStatus::end_of_stream;
    // The next pass starts one sample period after the last row.
    const double period = ((*t_)[rows - 1] - (*t_)[0]) / static_cast<double>(rows - 1);
    loop_offset_ += (*t_)[rows - 1] - (*t_)[0] + period;
    next_row_ = 0;
  }
  for (std::size_t i = 0; i < columns_.size() && i < values.size(); ++i) {
    values[i] = (*columns_[i])[next_row_];
  }
  source_time_ = (*t_)[next_row_] + loop_offset_;
  ++next_row_;
  return ReadStatus::ok;
}

std::unique_ptr<Driver> make_replay_driver(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "path", "loop", "channels"});
  ReplaySettings settings;
  settings.name = node.get_string("name");
  const auto path_node = node.at("path");
  settings.path = path_node.as_string();
  // Relative paths are relative to the configuration file, so a config and its captures can
  // move together.
  if (std::filesystem::path(settings.path).is_relative()) {
    settings.path =
        (std::filesystem::path(node.source()).parent_path() / settings.path).lexically_normal();
  }
  settings.loop = node.get_bool("loop", false);
  if (auto channels = node.find("channels")) {
    for (const auto& item : channels->items()) settings.channels.push_back(item.as_string());
  }
  try {
    return std::make_unique<ReplayDriver>(settings);
  } catch (const DriverError& e) {
    path_node.fail(e.what());
  } catch (const capture::CaptureError& e) {
    path_node.fail(e.what());
  }
}

}  // namespace leakmon::io
