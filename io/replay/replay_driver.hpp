// The `replay` driver: plays a capture CSV (FORMATS.md) back, one row per tick of its sampling
// group, optionally looping. Its channels are the capture's columns other than `t`; its
// source_time() is the capture's `t` of the row last read (continued across loops), so events
// carry capture times.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "capture/capture.hpp"
#include "config/yaml_reader.hpp"
#include "io/driver.hpp"

namespace leakmon::io {

struct ReplaySettings {
  std::string name = "replay";
  std::string path;                   // capture file (read in start())
  bool loop = false;                  // start over at the end instead of ending the stream
  std::vector<std::string> channels;  // subset of columns to offer; empty = all but t
};

class ReplayDriver final : public Driver {
 public:
  // From a file: reads the header now (channels are known at once), the rows in start().
  explicit ReplayDriver(ReplaySettings settings);
  // From a capture already in memory (the in-process replay of pipeline/replay.hpp).
  ReplayDriver(ReplaySettings settings, std::shared_ptr<const capture::Capture> capture);

  const std::string& name() const override { return settings_.name; }
  std::span<const std::string> channels() const override { return channels_; }
  void start() override;
  void stop() override {}
  ReadStatus read(const Tick& tick, std::span<double> values) noexcept override;
  std::optional<double> source_time() const override { return source_time_; }
  bool loses_missed_cycles() const override { return false; }  // the next row, however late

  std::size_t rows() const { return capture_ ? capture_->rows() : 0; }
  double sample_rate_hz() const;

 private:
  void select_columns(const std::vector<std::string>& capture_columns);
  void bind_columns();

  ReplaySettings settings_;
  std::shared_ptr<const capture::Capture> capture_;
  std::vector<std::string> channels_;
  std::vector<const std::vector<double>*> columns_;  // one per channel, into capture_
  const std::vector<double>* t_ = nullptr;
  std::size_t next_row_ = 0;
  double loop_offset_ = 0.0;  // added to t on each pass so that t keeps increasing
  std::optional<double> source_time_;
};

// Factory for the driver registry: `{name, type: replay, path, loop, channels}`.
std::unique_ptr<Driver> make_replay_driver(const config::ConfigNode& node);

}  // namespace leakmon::io
