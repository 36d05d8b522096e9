#include "io/modbus/modbus_poller.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

namespace leakmon::io::modbus {
namespace {

std::int64_t monotonic_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string_view to_string_state(int state) {
  constexpr std::string_view kNames[] = {"connecting", "ok", "degraded", "disconnected"};
  return kNames[state];
}

// NE 107 per link state: connecting is an intended, temporary invalid output; degraded (some
// requests refused, the rest still served) still delivers values but needs attention.
DeviceStatus device_status_of(int state) {
  constexpr DeviceStatus kStatus[] = {DeviceStatus::function_check, DeviceStatus::ok,
                                      DeviceStatus::maintenance_required, DeviceStatus::failure};
  return kStatus[state];
}

}  // namespace

ModbusPoller::ModbusPoller(ModbusConfig config)
    : config_(std::move(config)),
      requests_(plan_requests(config_.channels, config_.max_registers_per_request)),
      values_(config_.channels.size()),
      words_(static_cast<std::size_t>(config_.max_registers_per_request)),
      bits_(static_cast<std::size_t>(kMaxBitsPerRequest)),
      link_(std::make_unique<ModbusLink>(config_)) {}

ModbusPoller::~ModbusPoller() { stop(); }

void ModbusPoller::start() {
  if (thread_.joinable()) return;
  {
    std::lock_guard lock(mutex_);
    stopping_ = false;
  }
  spdlog::info("modbus {}: polling {} at {} Hz, {} channels in {} requests", config_.name,
               config_.endpoint(), config_.poll_rate_hz, config_.channels.size(), requests_.size());
  thread_ = std::thread([this] { run(); });
}

void ModbusPoller::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  link_->close();
}

DriverHealth ModbusPoller::health() const {
  DriverHealth health;
  {
    std::lock_guard lock(mutex_);
    health.status = device_status_of(static_cast<int>(state_));
    health.detail = to_string_state(static_cast<int>(state_));
    health.last_error = last_error_;
  }
  health.errors = errors_.load(std::memory_order_relaxed);
  health.reconnects = reconnects_.load(std::memory_order_relaxed);
  return health;
}

bool ModbusPoller::wait_until_ns(std::int64_t deadline_ns) {
  const auto deadline =
      std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
  std::unique_lock lock(mutex_);
  return !wake_.wait_until(lock, deadline, [this] { return stopping_; });
}

void ModbusPoller::run() {
  const auto period_ns = static_cast<std::int64_t>(1e9 / config_.poll_rate_hz);
  std::int64_t backoff_ns = config_.reconnect_min_ns;
  std::int64_t next_poll_ns = monotonic_ns();
  int lost_in_a_row = 0;
  for (;;) {
    if (!link_->connected()) {
      const Outcome connected = link_->connect();
      if (connected != Outcome::ok) {
        record_error(connected, "connect");
        set_state(State::disconnected);
        if (!wait_until_ns(monotonic_ns() + backoff_ns)) return;
        backoff_ns = std::min(backoff_ns * 2, config_.reconnect_max_ns);
        next_poll_ns = monotonic_ns();
        continue;
      }
      if (ever_connected_) reconnects_.fetch_add(1, std::memory_order_relaxed);
      ever_connected_ = true;
    }

    if (poll_once()) {
      backoff_ns = config_.reconnect_min_ns;
      lost_in_a_row = 0;
    } else if (++lost_in_a_row > 1) {
      // One lost connection is reconnected at once; a device that keeps dropping it (or keeps
      // timing out) is backed off like one that refuses connections.
      if (!wait_until_ns(monotonic_ns() + backoff_ns)) return;
      backoff_ns = std::min(backoff_ns * 2, config_.reconnect_max_ns);
      next_poll_ns = monotonic_ns();
      continue;
    }

    // Keep phase; after an overrun (slow device, reconnect) start afresh rather than burst.
    next_poll_ns += period_ns;
    const std::int64_t now = monotonic_ns();
    if (next_poll_ns < now) next_poll_ns = now;
    if (!wait_until_ns(next_poll_ns)) return;
  }
}

bool ModbusPoller::poll_once() {
  bool refused = false;
  for (const ReadRequest& request : requests_) {
    Outcome outcome = Outcome::ok;
    for (int attempt = 0; attempt <= config_.retries; ++attempt) {
      outcome = link_->read(request, words_, bits_);
      if (outcome == Outcome::ok) break;
      record_error(outcome, fmt::format("read {} registers at {} from unit {}", request.count,
                                        request.address, request.unit_id));
      link_->recover(outcome);
      // A dropped TCP connection is not retried here: reconnecting is the outer loop's job,
      // with backoff, so a dead device is not hammered.
      if (!link_->connected()) break;
    }
    if (outcome == Outcome::ok) {
      publish(request, monotonic_ns());
    } else if (outcome == Outcome::exception_reply) {
      refused = true;  // this request's channels go stale and read as gaps
    } else if (!link_->connected()) {
      set_state(State::disconnected);
      return false;
    } else {
      refused = true;  // serial line: flushed, try again next poll
    }
  }
  set_state(refused ? State::degraded : State::ok);
  return true;
}

void ModbusPoller::publish(const ReadRequest& request, std::int64_t received_ns) {
  values_.begin_write();
  for (const ChannelSlot& slot : request.slots) {
    const ChannelSpec& channel = config_.channels[slot.channel];
    const auto offset = static_cast<std::size_t>(slot.offset);
    double raw = 0.0;
    if (is_bit_type(channel.register_type)) {
      raw = bits_[offset] != 0 ? 1.0 : 0.0;
    } else {
      raw = decode_registers(std::span<const std::uint16_t>(words_).subspan(offset),
                             channel.data_type, channel.byte_order);
    }
    values_.set(slot.channel, raw * channel.scale + channel.offset, received_ns);
  }
  values_.end_write();
}

void ModbusPoller::record_error(Outcome outcome, const std::string& what) {
  errors_.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard lock(mutex_);
  last_error_ = fmt::format("{}: {}: {}", what, to_string(outcome), link_->last_error());
}

void ModbusPoller::set_state(State state) {
  std::string error;
  {
    std::lock_guard lock(mutex_);
    if (state == state_) return;
    state_ = state;
    error = last_error_;
  }
  const auto name = to_string_state(static_cast<int>(state));
  if (state == State::ok) {
    spdlog::info("modbus {}: {} ({})", config_.name, name, config_.endpoint());
  } else {
    spdlog::warn("modbus {}: {} ({}): {}", config_.name, name, config_.endpoint(), error);
  }
}

}  // namespace leakmon::io::modbus
