// The one plug-in point for data sources (in the manner of ros2_control's SensorInterface):
// configuration, device I/O and background polling stay outside the real-time call; read()
// runs once per tick of the acquisition loop and only copies out values that are ready.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "io/device_status.hpp"

namespace leakmon::io {

class DriverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One scheduled wake-up of the acquisition loop.
struct Tick {
  std::uint64_t index = 0;        // ticks since start, missed cycles included
  std::int64_t monotonic_ns = 0;  // CLOCK_MONOTONIC of the scheduled wake-up (simulated for replay)
};

enum class ReadStatus {
  ok,             // values are filled (a NaN value is a gap)
  end_of_stream,  // a finite source (replay) has no more samples; values untouched
};

// Counters and state that non-real-time threads read for metrics and events. Thread-safe.
struct DriverHealth {
  // The NAMUR NE 107 category operators and the daemon act on (driver_fault / driver_recovered
  // events, leakmon_driver_up), and the driver's own word for its state beside it ("ok",
  // "connecting", "disconnected", "bus-off", ...) for people reading logs and status.
  DeviceStatus status = DeviceStatus::ok;
  std::string detail = "ok";
  std::string last_error;    // the newest error message, empty when none
  std::uint64_t errors = 0;  // communication errors since start
  std::uint64_t reconnects = 0;
  std::uint64_t stale_values = 0;  // reads that returned a gap because the value was too old
};

class Driver {
 public:
  Driver() = default;
  virtual ~Driver() = default;
  Driver(const Driver&) = delete;
  Driver& operator=(const Driver&) = delete;

  // Name from the configuration, used in events, metrics and errors.
  virtual const std::string& name() const = 0;
  // Channel names, in the order read() fills values; fixed once constructed.
  virtual std::span<const std::string> channels() const = 0;

  // Not real-time: open devices, start poller threads. Throws DriverError.
  virtual void start() = 0;
  // Not real-time: stop background activity, close devices. Idempotent.
  virtual void stop() = 0;

  // Real-time: one value per channel for this tick; NaN marks a gap. Must not allocate, lock,
  // block on I/O or log, and must not throw: the acquisition loop cannot recover from an
  // exception, so a driver turns its failures into gaps and reports them through health().
  virtual ReadStatus read(const Tick& tick, std::span<double> values) noexcept = 0;

  // The source's own time for the last read, when it has one (replay: the capture's t).
  virtual std::optional<double> source_time() const { return std::nullopt; }
  // Whether the samples of cycles the loop missed are lost: true for a live signal (a device,
  // the simulated rig, which runs on); false for a stream that hands out its next sample when
  // read late (a capture replayed row by row), so a late loop delays it and loses nothing.
  virtual bool loses_missed_cycles() const { return true; }

  virtual DriverHealth health() const { return {}; }
};

}  // namespace leakmon::io
