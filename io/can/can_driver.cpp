#include "io/can/can_driver.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <limits>

#include "io/can/signal_config.hpp"

namespace leakmon::io {

std::unique_ptr<Driver> make_can_driver(const config::ConfigNode& node) {
  return std::make_unique<can::CanDriver>(can::read_can_driver_config(node));
}

}  // namespace leakmon::io

namespace leakmon::io::can {
namespace {

std::int64_t realtime_now_ns() noexcept {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

// One kernel filter per configured identifier; the RTR bit in the mask keeps remote frames out.
std::vector<can_filter> filters_for(const std::vector<SignalDef>& signals) {
  std::vector<can_filter> filters;
  for (const auto& s : signals) {
    can_filter f{};
    f.can_id = s.layout.id | (s.layout.extended ? CAN_EFF_FLAG : 0U);
    f.can_mask = (s.layout.extended ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG;
    const bool known = std::any_of(filters.begin(), filters.end(),
                                   [&](const can_filter& g) { return g.can_id == f.can_id; });
    if (!known) filters.push_back(f);
  }
  return filters;
}

}  // namespace

CanDriverConfig read_can_driver_config(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "interface", "fd", "receive_buffer", "max_frames_per_read",
                    "max_age", "signals"});
  CanDriverConfig config;
  config.name = node.get_string("name");
  if (node.get_string("type") != "can") node.at("type").fail("expected type: can");
  config.socket.interface = node.get_string("interface");
  if (config.socket.interface.empty() || config.socket.interface.size() >= 16) {
    node.at("interface").fail("interface name must be 1..15 characters (e.g. can0)");
  }
  config.socket.fd = node.get_bool("fd", false);
  config.socket.receive_buffer_bytes =
      static_cast<int>(node.get_int("receive_buffer", 0, 0, 64LL * 1024 * 1024));
  config.max_frames_per_read =
      static_cast<std::size_t>(node.get_int("max_frames_per_read", 256, 1, 100000));
  config.signals = read_signals(node);
  if (!config.socket.fd) {
    const auto list = node.at("signals").items();
    for (std::size_t i = 0; i < config.signals.size(); ++i) {
      if (bytes_needed(config.signals[i].layout) > kClassicMaxLength) {
        list[i]
            .at("start_bit")
            .fail(
                "signal needs more than 8 payload bytes: only CAN FD frames "
                "can carry it; set fd: true on the driver");
      }
    }
  }
  return config;
}

CanDriver::CanDriver(CanDriverConfig config)
    : name_(std::move(config.name)),
      socket_options_(std::move(config.socket)),
      filters_(filters_for(config.signals)),
      max_frames_per_read_(config.max_frames_per_read),
      decoder_(std::move(config.signals)) {
  for (const auto& s : decoder_.signals()) channels_.push_back(s.channel);
}

CanDriver::~CanDriver() { stop(); }

void CanDriver::start() {
  if (socket_) return;
  socket_ = std::make_unique<CanSocket>(socket_options_, filters_);
  last_kernel_drops_ = 0;
  decoder_.clear();
  link_down_ = false;
}

void CanDriver::stop() { socket_.reset(); }

void CanDriver::note_error(const char* message) noexcept {
  errors_.fetch_add(1, std::memory_order_relaxed);
  last_error_.store(message, std::memory_order_relaxed);
}

void CanDriver::on_error_frame(const CanFrame& frame) noexcept {
  error_frames_.fetch_add(1, std::memory_order_relaxed);
  const ErrorFrameEffect effect = interpret_error_frame(frame);
  if (effect.changes_state) {
    if (effect.state == BusState::bus_off && bus_state_.load() != BusState::bus_off) {
      bus_off_.fetch_add(1, std::memory_order_relaxed);
    }
    bus_state_.store(effect.state, std::memory_order_relaxed);
  }
  note_error(effect.description);
}

ReadStatus CanDriver::read(const Tick& tick, std::span<double> values) noexcept {
  if (socket_) {
    // Frames are stamped on the tick's clock as "this long before now"; taking now as the
    // tick's time errs only by the wake-up latency, and works for a simulated clock too.
    const std::int64_t realtime_now = realtime_now_ns();
    ReceivedFrame received;
    for (std::size_t n = 0; n < max_frames_per_read_; ++n) {
      const CanSocket::Result result = socket_->receive(received);
      if (result == CanSocket::Result::empty) break;
      if (result == CanSocket::Result::failed) {
        receive_failures_.fetch_add(1, std::memory_order_relaxed);
        const int error = socket_->last_errno();
        if (error == ENETDOWN || error == ENODEV || error == ENXIO) {
          link_down_.store(true, std::memory_order_relaxed);
          note_error("interface is down");
        } else {
          note_error("receive failed");
        }
        break;
      }
      link_down_.store(false, std::memory_order_relaxed);  // only a frame proves the link is back
      frames_.fetch_add(1, std::memory_order_relaxed);
      if (received.frame.error) {
        on_error_frame(received.frame);
        continue;
      }
      const std::int64_t age_ns =
          received.realtime_ns > 0 ? std::max<std::int64_t>(0, realtime_now - received.realtime_ns)
                                   : 0;
      decoder_.apply(received.frame, tick.monotonic_ns - age_ns);
    }
    const std::uint32_t drops = socket_->kernel_drops();
    if (drops != last_kernel_drops_) {
      const std::uint32_t lost = drops - last_kernel_drops_;  // modulo 2^32, as the kernel counts
      last_kernel_drops_ = drops;
      kernel_drops_.fetch_add(lost, std::memory_order_relaxed);
      errors_.fetch_add(lost, std::memory_order_relaxed);
      last_error_.store("frames dropped: socket receive queue overflowed",
                        std::memory_order_relaxed);
    }
    decoded_frames_.store(decoder_.decoded_frames(), std::memory_order_relaxed);
    const std::uint64_t short_frames = decoder_.short_frames();
    if (short_frames != short_frames_.load(std::memory_order_relaxed)) {
      errors_.fetch_add(short_frames - short_frames_.load(std::memory_order_relaxed),
                        std::memory_order_relaxed);
      short_frames_.store(short_frames, std::memory_order_relaxed);
      last_error_.store("frame too short for a configured signal", std::memory_order_relaxed);
    }
  }
  const std::size_t stale = decoder_.sample(values, tick.monotonic_ns);
  stale_values_.fetch_add(stale, std::memory_order_relaxed);
  for (std::size_t i = decoder_.signals().size(); i < values.size(); ++i) {
    values[i] = std::numeric_limits<double>::quiet_NaN();
  }
  return ReadStatus::ok;
}

DriverHealth CanDriver::health() const {
  DriverHealth h;
  const bool link_down = link_down_.load();
  const BusState bus = bus_state_.load();
  h.status = link_down ? DeviceStatus::failure : device_status(bus);
  h.detail = link_down ? "interface-down" : to_string(bus);
  h.last_error = last_error_.load();
  h.errors = errors_.load();
  h.stale_values = stale_values_.load();
  return h;
}

CanCounters CanDriver::counters() const {
  CanCounters c;
  c.frames = frames_.load();
  c.decoded_frames = decoded_frames_.load();
  c.error_frames = error_frames_.load();
  c.bus_off = bus_off_.load();
  c.kernel_drops = kernel_drops_.load();
  c.short_frames = short_frames_.load();
  c.receive_failures = receive_failures_.load();
  c.stale_values = stale_values_.load();
  return c;
}

}  // namespace leakmon::io::can
