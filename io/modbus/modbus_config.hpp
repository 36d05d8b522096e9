// What a Modbus driver is told by its YAML mapping (see modbus.yaml beside this file and
// README.md): one connection (TCP or RTU), how often to poll it, how to survive its faults,
// and which registers become which channels in SI units.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/modbus/register_decoding.hpp"

namespace leakmon::io::modbus {

enum class RegisterType { coil, discrete_input, holding, input };

// Coils and discrete inputs are bits; holding and input registers are 16-bit words.
inline bool is_bit_type(RegisterType type) {
  return type == RegisterType::coil || type == RegisterType::discrete_input;
}

struct ChannelSpec {
  std::string name;
  int unit_id = 1;
  RegisterType register_type = RegisterType::holding;
  int address = 0;  // protocol address (0-based, as on the wire), after address_base is applied
  DataType data_type = DataType::uint16;  // ignored for bit types
  ByteOrder byte_order = ByteOrder::abcd;
  double scale = 1.0;  // SI value = raw * scale + offset
  double offset = 0.0;
  std::int64_t max_age_ns = 0;  // older values read as gaps

  // Registers (or bits) the channel occupies.
  int width() const {
    return is_bit_type(register_type) ? 1 : static_cast<int>(register_count(data_type));
  }
};

struct TcpEndpoint {
  std::string host;
  int port = 502;
};

struct RtuEndpoint {
  std::string device;
  int baud = 19200;
  char parity = 'E';  // Modbus over serial line specification default: 8E1
  int data_bits = 8;
  int stop_bits = 1;
};

struct ModbusConfig {
  std::string name;
  std::optional<TcpEndpoint> tcp;  // exactly one of tcp / rtu
  std::optional<RtuEndpoint> rtu;
  double poll_rate_hz = 500.0;
  std::int64_t timeout_ns = 50'000'000;
  int retries = 1;  // immediate retries of a failed request (exception replies only; see README)
  std::int64_t reconnect_min_ns = 100'000'000;
  std::int64_t reconnect_max_ns = 5'000'000'000;
  int max_registers_per_request = 125;
  std::vector<ChannelSpec> channels;
  // Findings that are legal but probably mistakes (two channels on the same registers), each
  // `file:line:column: message`; check-config prints them and `run` logs them.
  std::vector<std::string> warnings;

  std::string endpoint() const;  // "tcp://host:port" or "rtu:/dev/ttyUSB0@19200,8E1", for logs
};

// Validates every field; errors are config::ConfigError with file:line:column and the field.
ModbusConfig parse_modbus_config(const config::ConfigNode& node);

// The connection part shared by the driver and the alarm output: name, type, transport and
// endpoint, timeout_ms, retries, reconnect_min_ms/max_ms (no channels). connection_keys() lists
// the keys it reads, for expect_keys.
std::vector<std::string> connection_keys();
ModbusConfig parse_connection(const config::ConfigNode& node);
// A written address (counted from `address_base`) as a protocol address; `width` registers
// must fit below 65536. Fails at `address` naming what was to be read there.
int parse_address(const config::ConfigNode& address, int address_base, int width,
                  std::string_view what);

}  // namespace leakmon::io::modbus
