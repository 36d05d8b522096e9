#include "io/modbus/modbus_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "config/address.hpp"

namespace leakmon::io::modbus {
namespace {

using config::ConfigNode;

constexpr int kLastAddress = 65535;

RegisterType parse_register_type(const ConfigNode& channel) {
  const std::string name =
      channel.get_choice("register", {"coil", "discrete_input", "holding", "input"}, "holding");
  if (name == "coil") return RegisterType::coil;
  if (name == "discrete_input") return RegisterType::discrete_input;
  if (name == "input") return RegisterType::input;
  return RegisterType::holding;
}

std::int64_t milliseconds_to_ns(double ms) {
  return static_cast<std::int64_t>(std::llround(ms * 1e6));
}

ChannelSpec parse_channel(const ConfigNode& node, int default_unit, int address_base,
                          double default_max_age_ms) {
  node.expect_keys({"name", "unit_id", "register", "address", "data_type", "byte_order", "scale",
                    "offset", "max_age_ms"});
  ChannelSpec channel;
  channel.name = node.get_string("name");
  if (channel.name.empty()) node.at("name").fail("channel name must not be empty");
  channel.unit_id = static_cast<int>(node.get_int("unit_id", default_unit, 0, 247));
  channel.register_type = parse_register_type(node);

  if (is_bit_type(channel.register_type)) {
    if (auto type = node.find("data_type"))
      type->fail("coils and discrete inputs are single bits; remove data_type");
    if (auto order = node.find("byte_order"))
      order->fail("coils and discrete inputs are single bits; remove byte_order");
  } else {
    const std::string type_name = node.get_string("data_type", "UINT16");
    auto type = parse_data_type(type_name);
    if (!type)
      node.at("data_type")
          .fail(fmt::format("'{}' is not one of: INT16, UINT16, INT32, UINT32, FLOAT32, FLOAT64",
                            type_name));
    channel.data_type = *type;
    const std::string order_name = node.get_string("byte_order", "ABCD");
    auto order = parse_byte_order(order_name);
    if (!order)
      node.at("byte_order")
          .fail(fmt::format("'{}' is not one of: ABCD, CDAB, BADC, DCBA", order_name));
    channel.byte_order = *order;
  }

  channel.address = parse_address(node.at("address"), address_base, channel.width(),
                                  to_string(channel.data_type));
  channel.scale = node.get_double("scale", 1.0, -1e300, 1e300);
  if (channel.scale == 0.0) node.at("scale").fail("scale must not be zero");
  channel.offset = node.get_double("offset", 0.0, -1e300, 1e300);
  channel.max_age_ns =
      milliseconds_to_ns(node.get_double("max_age_ms", default_max_age_ms, 0.1, 600'000.0));
  return channel;
}

}  // namespace

std::string ModbusConfig::endpoint() const {
  if (tcp) return fmt::format("tcp://{}:{}", tcp->host, tcp->port);
  if (rtu)
    return fmt::format("rtu:{}@{},{}{}{}", rtu->device, rtu->baud, rtu->data_bits, rtu->parity,
                       rtu->stop_bits);
  return "none";
}

std::vector<std::string> connection_keys() {
  return {"name",
          "type",
          "transport",
          "host",
          "port",
          "device",
          "baud",
          "parity",
          "data_bits",
          "stop_bits",
          "unit_id",
          "timeout_ms",
          "retries",
          "reconnect_min_ms",
          "reconnect_max_ms",
          "address_base"};
}

ModbusConfig parse_connection(const ConfigNode& node) {
  ModbusConfig config;
  config.name = node.get_string("name");
  if (config.name.empty()) node.at("name").fail("name must not be empty");
  if (node.get_string("type", "modbus") != "modbus") node.at("type").fail("expected 'modbus'");

  const std::string transport = node.get_choice("transport", {"tcp", "rtu"}, "tcp");
  const auto reject = [&](std::initializer_list<std::string_view> keys) {
    for (auto key : keys)
      if (auto found = node.find(key))
        found->fail(fmt::format("'{}' does not apply to transport {}", key, transport));
  };
  if (transport == "tcp") {
    reject({"device", "baud", "parity", "data_bits", "stop_bits"});
    TcpEndpoint tcp;
    tcp.host = config::read_host(node.at("host"));
    tcp.port = static_cast<int>(node.get_int("port", 502, 1, 65535));
    config.tcp = tcp;
  } else {
    reject({"host", "port"});
    RtuEndpoint rtu;
    rtu.device = node.get_string("device");
    if (rtu.device.empty()) node.at("device").fail("device must not be empty");
    rtu.baud = static_cast<int>(node.get_int("baud", 19200, 50, 4'000'000));
    rtu.parity = node.get_choice("parity", {"N", "E", "O"}, "E").front();
    rtu.data_bits = static_cast<int>(node.get_int("data_bits", 8, 5, 8));
    rtu.stop_bits = static_cast<int>(node.get_int("stop_bits", 1, 1, 2));
    config.rtu = rtu;
  }
  config.timeout_ns = milliseconds_to_ns(node.get_double("timeout_ms", 50.0, 1.0, 60'000.0));
  config.retries = static_cast<int>(node.get_int("retries", 1, 0, 10));
  config.reconnect_min_ns =
      milliseconds_to_ns(node.get_double("reconnect_min_ms", 100.0, 1.0, 600'000.0));
  config.reconnect_max_ns =
      milliseconds_to_ns(node.get_double("reconnect_max_ms", 5000.0, 1.0, 600'000.0));
  if (config.reconnect_max_ns < config.reconnect_min_ns)
    node.at("reconnect_max_ms").fail("must not be less than reconnect_min_ms");
  return config;
}

int parse_address(const ConfigNode& address, int address_base, int width, std::string_view what) {
  const long long written = address.as_int();
  if (written < address_base || written > kLastAddress + address_base)
    address.fail(fmt::format("address {} is outside {}..{} (address_base is {})", written,
                             address_base, kLastAddress + address_base, address_base));
  const auto protocol_address = static_cast<int>(written - address_base);
  if (protocol_address + width - 1 > kLastAddress)
    address.fail(fmt::format("a {} at address {} runs past the last register", what, written));
  return protocol_address;
}

ModbusConfig parse_modbus_config(const ConfigNode& node) {
  std::vector<std::string> keys = connection_keys();
  keys.insert(keys.end(), {"poll_rate_hz", "max_age_ms", "max_registers_per_request", "channels"});
  node.expect_keys(keys);
  ModbusConfig config = parse_connection(node);
  const int default_unit = static_cast<int>(node.get_int("unit_id", 1, 0, 247));
  const int address_base = static_cast<int>(node.get_int("address_base", 0, 0, 1));
  config.poll_rate_hz = node.get_double("poll_rate_hz", 500.0, 0.1, 10'000.0);
  config.max_registers_per_request =
      static_cast<int>(node.get_int("max_registers_per_request", 125, 4, 125));

  // A value may be as old as a few polls before it counts as missing: one late response must
  // not open a gap, but a dead link must within tens of milliseconds.
  const double default_max_age_ms =
      node.get_double("max_age_ms", std::max(10.0, 4000.0 / config.poll_rate_hz), 0.1, 600'000.0);

  const ConfigNode channels = node.at("channels");
  std::set<std::string> names;
  std::vector<ConfigNode> addresses;
  for (const ConfigNode& item : channels.items()) {
    ChannelSpec channel = parse_channel(item, default_unit, address_base, default_max_age_ms);
    if (!names.insert(channel.name).second)
      item.at("name").fail(fmt::format("duplicate channel name '{}'", channel.name));
    // Two channels on the same registers read the same data twice: usually a copied entry
    // whose address was not changed. Legal (a FLOAT32 and its INT16 halves, say), so a warning.
    for (std::size_t k = 0; k < config.channels.size(); ++k) {
      const ChannelSpec& other = config.channels[k];
      if (other.unit_id != channel.unit_id || other.register_type != channel.register_type ||
          other.address + other.width() <= channel.address ||
          channel.address + channel.width() <= other.address) {
        continue;
      }
      config.warnings.push_back(fmt::format(
          "{}: {}: channel '{}' reads {} {}..{} of unit {}, which channel '{}' ({}) also reads",
          item.at("address").location(), item.at("address").path(), channel.name,
          is_bit_type(channel.register_type) ? "bits" : "registers", channel.address + address_base,
          channel.address + address_base + channel.width() - 1, channel.unit_id, other.name,
          addresses[k].location()));
    }
    addresses.push_back(item.at("address"));
    config.channels.push_back(std::move(channel));
  }
  if (config.channels.empty()) channels.fail("at least one channel is required");
  return config;
}

}  // namespace leakmon::io::modbus
