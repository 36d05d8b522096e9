// The thread that owns one Modbus connection: it polls the planned requests at the configured
// rate (keeping phase, next += period), publishes each decoded value with the time it arrived,
// and turns faults into reconnects with exponential backoff, counters and one log line per
// state change. The real-time loop never waits for it: it only reads the published values.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "io/driver.hpp"
#include "io/modbus/latest_value.hpp"
#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_link.hpp"
#include "io/modbus/request_plan.hpp"

namespace leakmon::io::modbus {

class ModbusPoller {
 public:
  explicit ModbusPoller(ModbusConfig config);
  ~ModbusPoller();
  ModbusPoller(const ModbusPoller&) = delete;
  ModbusPoller& operator=(const ModbusPoller&) = delete;

  const ModbusConfig& config() const { return config_; }
  const std::vector<ReadRequest>& requests() const { return requests_; }

  void start();
  void stop();  // joins; at most one response timeout plus a poll period

  // Real-time safe: the newest value of every channel and when it arrived (one consistent
  // snapshot); false when the snapshot raced the poller too often.
  bool latest(std::span<StampedValue> out) const { return values_.read(out); }

  DriverHealth health() const;

 private:
  enum class State { connecting, ok, degraded, disconnected };

  void run();
  bool poll_once();  // false when the link was lost
  void publish(const ReadRequest& request, std::int64_t received_ns);
  void record_error(Outcome outcome, const std::string& what);
  void set_state(State state);
  bool wait_until_ns(std::int64_t deadline_ns);  // false when stopping

  ModbusConfig config_;
  std::vector<ReadRequest> requests_;
  LatestValues values_;
  std::vector<std::uint16_t> words_;  // scratch for one request
  std::vector<std::uint8_t> bits_;
  std::unique_ptr<ModbusLink> link_;

  std::thread thread_;
  mutable std::mutex mutex_;  // guards stopping_, state_, last_error_
  std::condition_variable wake_;
  bool stopping_ = false;
  State state_ = State::connecting;
  std::string last_error_;
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  bool ever_connected_ = false;
};

}  // namespace leakmon::io::modbus
