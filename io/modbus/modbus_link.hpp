// One libmodbus connection (TCP socket or RTU serial line) and the classification of what went
// wrong with a request, because each kind of fault calls for a different recovery: an exception
// reply means the device is alive and said no; a timeout or garbage on TCP means the stream may
// be out of step (a late reply would be taken for the next request's), so the connection is
// dropped; on a serial line the bus is flushed instead.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "io/modbus/modbus_config.hpp"
#include "io/modbus/request_plan.hpp"

struct _modbus;  // libmodbus' modbus_t, kept out of this header

namespace leakmon::io::modbus {

enum class Outcome {
  ok,
  exception_reply,  // the device answered with a Modbus exception code
  timeout,          // no (complete) answer within the response timeout
  garbage,          // an answer that does not parse: bad CRC, wrong length, wrong unit or function
  disconnected,     // the connection is gone or could not be made
};

std::string_view to_string(Outcome outcome);

class ModbusLink {
 public:
  // Throws DriverError when libmodbus rejects the endpoint (e.g. an invalid serial setting).
  explicit ModbusLink(const ModbusConfig& config);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  bool is_tcp() const { return is_tcp_; }
  bool connected() const { return connected_; }

  Outcome connect();
  void close();

  // Reads request.count registers into `words`, or request.count bits (0/1) into `bits`.
  Outcome read(const ReadRequest& request, std::span<std::uint16_t> words,
               std::span<std::uint8_t> bits);
  Outcome write_bit(int unit_id, int address, bool value);
  Outcome write_registers(int unit_id, int address, std::span<const std::uint16_t> words);

  // After a timeout or garbage: recover so the next request starts clean.
  void recover(Outcome failure);

  // libmodbus' message for the last failure.
  const std::string& last_error() const { return last_error_; }

 private:
  Outcome classify(int result, int expected);

  _modbus* context_ = nullptr;
  bool is_tcp_ = true;
  bool connected_ = false;
  std::string last_error_;
};

// Whether the device of `config` answers (`leakmon check-config`): connects and sends the first
// read of the driver's request plan once, waiting at least a second. An exception reply is an
// answer (the device is there and said no; the driver reports it per request). Empty when it
// answered, else what happened ("Connection refused", "no answer within 1000 ms", ...).
std::string unanswered(const ModbusConfig& config);

}  // namespace leakmon::io::modbus
