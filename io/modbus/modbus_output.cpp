#include "io/modbus/modbus_output.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_link.hpp"
#include "io/modbus/register_decoding.hpp"

namespace leakmon::io {
namespace {

using modbus::ByteOrder;
using modbus::DataType;
using modbus::RegisterType;
using Clock = std::chrono::steady_clock;

struct AlarmOutputSpec {
  modbus::ModbusConfig connection;
  int unit_id = 1;
  RegisterType register_type = RegisterType::coil;
  int address = 0;  // protocol address
  DataType data_type = DataType::uint16;
  ByteOrder byte_order = ByteOrder::abcd;
  double raised_value = 1.0;
  double cleared_value = 0.0;
  std::string alarm;     // only this alarm; empty: any
  std::string actuator;  // only this actuator; empty: any
  std::chrono::nanoseconds refresh{std::chrono::seconds(1)};
};

AlarmOutputSpec parse_output(const config::ConfigNode& node) {
  std::vector<std::string> keys = modbus::connection_keys();
  keys.insert(keys.end(), {"register", "address", "data_type", "byte_order", "raised_value",
                           "cleared_value", "alarm", "actuator", "refresh_ms"});
  node.expect_keys(keys);
  AlarmOutputSpec spec;
  spec.connection = modbus::parse_connection(node);
  spec.unit_id = static_cast<int>(node.get_int("unit_id", 1, 0, 247));
  const int address_base = static_cast<int>(node.get_int("address_base", 0, 0, 1));
  spec.register_type = node.get_choice("register", {"coil", "holding"}, "coil") == "coil"
                           ? RegisterType::coil
                           : RegisterType::holding;
  if (spec.register_type == RegisterType::coil) {
    for (auto key : {"data_type", "byte_order"})
      if (auto found = node.find(key)) found->fail("a coil is a single bit; remove this key");
  } else {
    const std::string type = node.get_string("data_type", "UINT16");
    const auto data_type = modbus::parse_data_type(type);
    if (!data_type)
      node.at("data_type")
          .fail(fmt::format("'{}' is not one of: INT16, UINT16, INT32, UINT32, FLOAT32, FLOAT64",
                            type));
    spec.data_type = *data_type;
    const std::string order = node.get_string("byte_order", "ABCD");
    const auto byte_order = modbus::parse_byte_order(order);
    if (!byte_order)
      node.at("byte_order").fail(fmt::format("'{}' is not one of: ABCD, CDAB, BADC, DCBA", order));
    spec.byte_order = *byte_order;
  }
  const int width = spec.register_type == RegisterType::coil
                        ? 1
                        : static_cast<int>(modbus::register_count(spec.data_type));
  spec.address = modbus::parse_address(
      node.at("address"), address_base, width,
      spec.register_type == RegisterType::coil ? "coil" : modbus::to_string(spec.data_type));
  spec.raised_value = node.get_double("raised_value", 1.0, -1e300, 1e300);
  spec.cleared_value = node.get_double("cleared_value", 0.0, -1e300, 1e300);
  if (spec.register_type == RegisterType::coil) {
    for (auto key : {"raised_value", "cleared_value"}) {
      const double value = node.get_double(key, key[0] == 'r' ? 1.0 : 0.0, 0.0, 1.0);
      if (value != 0.0 && value != 1.0) node.at(key).fail("a coil is 0 or 1");
    }
  }
  spec.alarm = node.get_string("alarm", "");
  spec.actuator = node.get_string("actuator", "");
  spec.refresh = std::chrono::nanoseconds(
      static_cast<std::int64_t>(node.get_double("refresh_ms", 1000.0, 10.0, 3'600'000.0) * 1e6));
  return spec;
}

// Mirrors the alarm state into one coil or register. publish() only records the wanted state;
// a writer thread (started with the first event, so that check-config never touches the PLC)
// writes it, rewrites it every refresh_ms so a restarted PLC learns it again, and reconnects
// with backoff when the device is away.
class ModbusAlarmOutput final : public EventSink {
 public:
  explicit ModbusAlarmOutput(AlarmOutputSpec spec) : spec_(std::move(spec)) {}
  ~ModbusAlarmOutput() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (writer_.joinable()) writer_.join();
  }

  void publish(const Event& event) override {
    ensure_started();
    if (event.kind != EventKind::alarm_raised && event.kind != EventKind::alarm_cleared) return;
    if (!spec_.alarm.empty() && event.alarm != spec_.alarm) return;
    if (!spec_.actuator.empty() && event.actuator != spec_.actuator) return;
    const std::string key = event.actuator + "\n" + event.alarm;
    if (event.kind == EventKind::alarm_raised) {
      active_.insert(key);
    } else {
      active_.erase(key);
    }
    {
      std::lock_guard lock(mutex_);
      wanted_raised_ = !active_.empty();
    }
    wake_.notify_all();
  }

  void flush() override { ensure_started(); }

 private:
  void ensure_started() {
    if (!writer_.joinable()) writer_ = std::thread([this] { write_loop(); });
  }

  bool write(bool raised) {
    const double value = raised ? spec_.raised_value : spec_.cleared_value;
    modbus::Outcome outcome = modbus::Outcome::disconnected;
    if (!link_.connected()) outcome = link_.connect();
    if (link_.connected()) {
      if (spec_.register_type == RegisterType::coil) {
        outcome = link_.write_bit(spec_.unit_id, spec_.address, value != 0.0);
      } else {
        std::array<std::uint16_t, 4> words{};
        const auto width = modbus::register_count(spec_.data_type);
        modbus::encode_registers(value, spec_.data_type, spec_.byte_order, words);
        outcome = link_.write_registers(spec_.unit_id, spec_.address,
                                        std::span<const std::uint16_t>(words).first(width));
      }
      link_.recover(outcome);
    }
    const bool ok = outcome == modbus::Outcome::ok;
    if (ok != last_write_ok_) {
      if (ok) {
        spdlog::info("modbus output {}: writing alarm state to {}", spec_.connection.name,
                     spec_.connection.endpoint());
      } else {
        spdlog::warn("modbus output {}: cannot write alarm state to {}: {}: {}",
                     spec_.connection.name, spec_.connection.endpoint(), modbus::to_string(outcome),
                     link_.last_error());
      }
      last_write_ok_ = ok;
    }
    return ok;
  }

  void write_loop() {
    auto backoff = std::chrono::nanoseconds(spec_.connection.reconnect_min_ns);
    bool written_known = false;  // the device holds the state last written
    bool written_raised = false;
    auto next_write = Clock::now();
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait_until(lock, next_write, [&] {
        return stopping_ || (written_known && written_raised != wanted_raised_);
      });
      if (stopping_) return;
      const bool raised = wanted_raised_;
      lock.unlock();
      const bool ok = write(raised);
      lock.lock();
      if (ok) {
        written_known = true;
        written_raised = raised;
        backoff = std::chrono::nanoseconds(spec_.connection.reconnect_min_ns);
        next_write = Clock::now() + spec_.refresh;
      } else {
        written_known = false;
        next_write = Clock::now() + backoff;
        backoff =
            std::min(backoff * 2, std::chrono::nanoseconds(spec_.connection.reconnect_max_ns));
      }
    }
  }

  AlarmOutputSpec spec_;
  modbus::ModbusLink link_{spec_.connection};
  std::set<std::string> active_;  // worker thread only
  std::thread writer_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool wanted_raised_ = false;
  bool stopping_ = false;
  bool last_write_ok_ = true;
};

}  // namespace

std::unique_ptr<EventSink> make_modbus_output(const config::ConfigNode& node) {
  return std::make_unique<ModbusAlarmOutput>(parse_output(node));
}

}  // namespace leakmon::io
