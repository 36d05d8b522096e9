// `type: can`: signals decoded live from a SocketCAN interface (see README.md and can.yaml).
//
// Why read() drains a non-blocking socket instead of a receiver thread handing values over:
// the kernel's socket queue already is the lock-free hand-over a thread would add, the
// frames carry kernel receive timestamps so nothing is lost by collecting them once per tick,
// and the socket's drop counter (SO_RXQ_OVFL) tells exactly when that queue overflowed. With
// no second thread there is no shared state, no wake-ups and nothing for TSan to find; the
// cost is one recvmsg(MSG_DONTWAIT) per queued frame plus one that returns EAGAIN, bounded
// per tick by max_frames_per_read (frames beyond it wait for the next tick).
#pragma once

#include <linux/can.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/can/bus_state.hpp"
#include "io/can/can_socket.hpp"
#include "io/can/frame_decoder.hpp"
#include "io/driver.hpp"

namespace leakmon::io {

// Builds a `type: can` driver from its YAML mapping (validated; file:line:column errors).
std::unique_ptr<Driver> make_can_driver(const config::ConfigNode& node);

}  // namespace leakmon::io

namespace leakmon::io::can {

struct CanDriverConfig {
  std::string name;
  SocketOptions socket;
  std::vector<SignalDef> signals;
  std::size_t max_frames_per_read = 256;
};

CanDriverConfig read_can_driver_config(const config::ConfigNode& node);

// Counters beyond DriverHealth, for tests and metrics. Safe to read from any thread.
struct CanCounters {
  std::uint64_t frames = 0;          // frames received (data, remote and error)
  std::uint64_t decoded_frames = 0;  // frames that updated at least one signal
  std::uint64_t error_frames = 0;
  std::uint64_t bus_off = 0;       // times the controller went bus-off
  std::uint64_t kernel_drops = 0;  // frames the kernel dropped (socket queue full)
  std::uint64_t short_frames = 0;  // configured id, too few bytes for a signal
  std::uint64_t receive_failures = 0;
  std::uint64_t stale_values = 0;
};

class CanDriver final : public Driver {
 public:
  explicit CanDriver(CanDriverConfig config);
  ~CanDriver() override;

  const std::string& name() const override { return name_; }
  std::span<const std::string> channels() const override { return channels_; }
  void start() override;
  void stop() override;
  ReadStatus read(const Tick& tick, std::span<double> values) noexcept override;
  DriverHealth health() const override;

  CanCounters counters() const;

 private:
  void on_error_frame(const CanFrame& frame) noexcept;
  void note_error(const char* message) noexcept;

  std::string name_;
  SocketOptions socket_options_;
  std::vector<can_filter> filters_;
  std::vector<std::string> channels_;
  std::size_t max_frames_per_read_;
  FrameDecoder decoder_;
  std::unique_ptr<CanSocket> socket_;
  std::uint32_t last_kernel_drops_ = 0;

  // Written by read() only, read by health()/counters() from other threads.
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> decoded_frames_{0};
  std::atomic<std::uint64_t> error_frames_{0};
  std::atomic<std::uint64_t> bus_off_{0};
  std::atomic<std::uint64_t> kernel_drops_{0};
  std::atomic<std::uint64_t> short_frames_{0};
  std::atomic<std::uint64_t> receive_failures_{0};
  std::atomic<std::uint64_t> stale_values_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<BusState> bus_state_{BusState::active};
  std::atomic<bool> link_down_{false};
  std::atomic<const char*> last_error_{""};  // always a string literal
};

}  // namespace leakmon::io::can
