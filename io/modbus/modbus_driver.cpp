#include "io/modbus/modbus_driver.hpp"

#include <atomic>
#include <limits>
#include <string>
#include <vector>

#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_poller.hpp"

namespace leakmon::io {
namespace {

class ModbusDriver final : public Driver {
 public:
  explicit ModbusDriver(modbus::ModbusConfig config)
      : poller_(std::move(config)), snapshot_(poller_.config().channels.size()) {
    for (const auto& channel : poller_.config().channels) channel_names_.push_back(channel.name);
  }
  ~ModbusDriver() override { ModbusDriver::stop(); }

  const std::string& name() const override { return poller_.config().name; }
  std::span<const std::string> channels() const override { return channel_names_; }

  // The device need not be reachable yet: the daemon starts, reports the link state and sees
  // gaps until the device answers.
  void start() override { poller_.start(); }
  void stop() override { poller_.stop(); }

  ReadStatus read(const Tick& tick, std::span<double> values) noexcept override {
    const auto& specs = poller_.config().channels;
    const std::size_t n = std::min(values.size(), specs.size());
    const bool have_snapshot = poller_.latest(snapshot_);
    for (std::size_t i = 0; i < n; ++i) {
      const modbus::StampedValue& sample = snapshot_[i];
      if (have_snapshot && sample.received_ns != 0 &&
          tick.monotonic_ns - sample.received_ns <= specs[i].max_age_ns) {
        values[i] = sample.value;
      } else {
        values[i] = std::numeric_limits<double>::quiet_NaN();
        stale_values_.fetch_add(1, std::memory_order_relaxed);
      }
    }
    return ReadStatus::ok;
  }

  DriverHealth health() const override {
    DriverHealth health = poller_.health();
    health.stale_values = stale_values_.load(std::memory_order_relaxed);
    return health;
  }

 private:
  modbus::ModbusPoller poller_;
  std::vector<modbus::StampedValue> snapshot_;  // read()'s scratch, sized once: no allocation
  std::vector<std::string> channel_names_;
  std::atomic<std::uint64_t> stale_values_{0};
};

}  // namespace

std::unique_ptr<Driver> make_modbus_driver(const config::ConfigNode& node) {
  return std::make_unique<ModbusDriver>(modbus::parse_modbus_config(node));
}

}  // namespace leakmon::io
