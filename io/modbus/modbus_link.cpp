#include "io/modbus/modbus_link.hpp"

#include <fmt/format.h>
#include <modbus/modbus.h>

#include <algorithm>
#include <cerrno>
#include <vector>

#include "io/driver.hpp"

namespace leakmon::io::modbus {
namespace {

bool is_exception_reply(int error) { return error >= EMBXILFUN && error <= EMBXGTAR; }

bool is_garbage(int error) {
  return error == EMBBADCRC || error == EMBBADDATA || error == EMBBADEXC || error == EMBUNKEXC ||
         error == EMBMDATA || error == EMBBADSLAVE;
}

}  // namespace

std::string_view to_string(Outcome outcome) {
  switch (outcome) {
    case Outcome::ok:
      return "ok";
    case Outcome::exception_reply:
      return "exception reply";
    case Outcome::timeout:
      return "timeout";
    case Outcome::garbage:
      return "garbage";
    case Outcome::disconnected:
      return "disconnected";
  }
  return "unknown";
}

ModbusLink::ModbusLink(const ModbusConfig& config) {
  if (config.tcp) {
    context_ =
        modbus_new_tcp_pi(config.tcp->host.c_str(), std::to_string(config.tcp->port).c_str());
  } else if (config.rtu) {
    is_tcp_ = false;
    context_ = modbus_new_rtu(config.rtu->device.c_str(), config.rtu->baud, config.rtu->parity,
                              config.rtu->data_bits, config.rtu->stop_bits);
  }
  if (context_ == nullptr)
    throw DriverError(fmt::format("modbus driver '{}': cannot use {}: {}", config.name,
                                  config.endpoint(), modbus_strerror(errno)));
  const auto seconds = static_cast<std::uint32_t>(config.timeout_ns / 1'000'000'000);
  const auto microseconds = static_cast<std::uint32_t>(config.timeout_ns % 1'000'000'000 / 1000);
  modbus_set_response_timeout(context_, seconds, microseconds);
  // libmodbus' own recovery would sleep and reconnect inside a call; the poller decides instead.
  modbus_set_error_recovery(context_, MODBUS_ERROR_RECOVERY_NONE);
}

ModbusLink::~ModbusLink() {
  close();
  modbus_free(context_);
}

Outcome ModbusLink::connect() {
  close();
  if (modbus_connect(context_) == -1) {
    last_error_ = modbus_strerror(errno);
    return Outcome::disconnected;
  }
  connected_ = true;
  return Outcome::ok;
}

void ModbusLink::close() {
  if (connected_) modbus_close(context_);
  connected_ = false;
}

Outcome ModbusLink::classify(int result, int expected) {
  if (result == expected) return Outcome::ok;
  if (result >= 0) {
    last_error_ = fmt::format("short answer: {} of {} values", result, expected);
    return Outcome::garbage;
  }
  const int error = errno;
  last_error_ = modbus_strerror(error);
  if (is_exception_reply(error)) return Outcome::exception_reply;
  if (is_garbage(error)) return Outcome::garbage;
  if (error == ETIMEDOUT) return Outcome::timeout;
  return Outcome::disconnected;
}

Outcome ModbusLink::read(const ReadRequest& request, std::span<std::uint16_t> words,
                         std::span<std::uint8_t> bits) {
  if (!connected_) return Outcome::disconnected;
  modbus_set_slave(context_, request.unit_id);
  int result = -1;
  switch (request.register_type) {
    case RegisterType::holding:
      result = modbus_read_registers(context_, request.address, request.count, words.data());
      break;
    case RegisterType::input:
      result = modbus_read_input_registers(context_, request.address, request.count, words.data());
      break;
    case RegisterType::coil:
      result = modbus_read_bits(context_, request.address, request.count, bits.data());
      break;
    case RegisterType::discrete_input:
      result = modbus_read_input_bits(context_, request.address, request.count, bits.data());
      break;
  }
  return classify(result, request.count);
}

Outcome ModbusLink::write_bit(int unit_id, int address, bool value) {
  if (!connected_) return Outcome::disconnected;
  modbus_set_slave(context_, unit_id);
  return classify(modbus_write_bit(context_, address, value ? 1 : 0), 1);
}

Outcome ModbusLink::write_registers(int unit_id, int address,
                                    std::span<const std::uint16_t> words) {
  if (!connected_) return Outcome::disconnected;
  modbus_set_slave(context_, unit_id);
  const int count = static_cast<int>(words.size());
  return classify(modbus_write_registers(context_, address, count, words.data()), count);
}

std::string unanswered(const ModbusConfig& config) {
  ModbusConfig patient = config;
  patient.timeout_ns = std::max<std::int64_t>(config.timeout_ns, 1'000'000'000);
  ModbusLink link(patient);
  if (link.connect() != Outcome::ok) return link.last_error();
  const auto plan = plan_requests(config.channels, config.max_registers_per_request);
  if (plan.empty()) return "";
  const ReadRequest& first = plan.front();
  std::vector<std::uint16_t> words(static_cast<std::size_t>(first.count));
  std::vector<std::uint8_t> bits(static_cast<std::size_t>(first.count));
  const Outcome outcome = link.read(first, words, bits);
  if (outcome == Outcome::ok || outcome == Outcome::exception_reply) return "";
  if (outcome == Outcome::timeout) {
    return fmt::format("connected, but no answer to a read within {} ms",
                       patient.timeout_ns / 1'000'000);
  }
  return fmt::format("{}: {}", to_string(outcome), link.last_error());
}

void ModbusLink::recover(Outcome failure) {
  if (failure == Outcome::ok || failure == Outcome::exception_reply) return;
  if (is_tcp_ || failure == Outcome::disconnected) {
    close();
  } else {
    modbus_flush(context_);
  }
}

}  // namespace leakmon::io::modbus
