// `type: canlog`: replays a `candump -l` log through the same signal decoding as the live
// SocketCAN driver (io/can/frame_decoder.hpp), so captured bus traffic can be run in CI.
//
// The log is loaded and checked in start(); read() then only walks an index. Time: with
// `pace: log` (default) the log's clock follows the loop's tick clock from the first tick, so
// a real-time loop replays at the log's own speed and a simulated clock replays as fast as the
// loop goes; with `pace: fast` every read() advances the log by one `period` whatever the
// clock says.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/can/bus_state.hpp"
#include "io/can/frame_decoder.hpp"
#include "io/canlog/candump.hpp"
#include "io/driver.hpp"

namespace leakmon::io {

// Builds a `type: canlog` driver from its YAML mapping (validated; file:line:column errors).
std::unique_ptr<Driver> make_canlog_driver(const config::ConfigNode& node);

}  // namespace leakmon::io

namespace leakmon::io::canlog {

enum class Pace { log, fast };

struct CanlogDriverConfig {
  std::string name;
  std::string file;       // resolved against the configuration file's folder
  std::string interface;  // empty: every interface in the log
  Pace pace = Pace::log;
  std::int64_t period_ns = 2'000'000;  // log time per read() with pace: fast
  std::vector<can::SignalDef> signals;
};

CanlogDriverConfig read_canlog_driver_config(const config::ConfigNode& node);

class CanlogDriver final : public Driver {
 public:
  explicit CanlogDriver(CanlogDriverConfig config);

  const std::string& name() const override { return name_; }
  std::span<const std::string> channels() const override { return channels_; }
  // Loads the log; throws DriverError `file:line:column: message` for a malformed line.
  void start() override;
  void stop() override {}
  ReadStatus read(const Tick& tick, std::span<double> values) noexcept override;
  std::optional<double> source_time() const override;
  // Paced by the log's clock, frames of missed cycles are passed; read by read (fast), none is.
  bool loses_missed_cycles() const override { return pace_ == Pace::log; }
  DriverHealth health() const override;

  std::uint64_t error_frames() const { return error_frames_.load(); }
  std::uint64_t frames_replayed() const { return frames_replayed_.load(); }
  std::uint64_t short_frames() const { return short_frames_.load(); }

 private:
  std::string name_;
  std::string file_;
  std::string interface_;
  Pace pace_;
  std::int64_t period_ns_;
  std::vector<std::string> channels_;
  can::FrameDecoder decoder_;
  std::vector<LoggedFrame> frames_;

  // Replay position; read() only.
  std::size_t next_frame_ = 0;
  std::uint64_t reads_ = 0;
  bool started_clock_ = false;
  std::int64_t first_tick_ns_ = 0;
  std::int64_t log_now_ns_ = 0;

  std::atomic<std::int64_t> source_time_ns_{0};
  std::atomic<bool> has_source_time_{false};
  std::atomic<std::uint64_t> frames_replayed_{0};
  std::atomic<std::uint64_t> error_frames_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> stale_values_{0};
  std::atomic<std::uint64_t> short_frames_{0};
  std::atomic<can::BusState> bus_state_{can::BusState::active};
  std::atomic<const char*> last_error_{""};
};

}  // namespace leakmon::io::canlog
