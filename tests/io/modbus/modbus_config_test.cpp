#include <gtest/gtest.h>

#include <string>

#include "config/yaml_reader.hpp"
#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io::modbus {
namespace {

ModbusConfig parse(const std::string& text) {
  return parse_modbus_config(config::ConfigNode::load_string(text, "drivers.yaml"));
}

// The error message for `text`, which must be rejected.
std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return {};
}

const std::string kTcp =
    "name: daq\n"
    "type: modbus\n"
    "host: 127.0.0.1\n"
    "port: 5020\n";

TEST(ModbusConfig, FullTcpConfiguration) {
  const auto config = parse(kTcp +
                            "unit_id: 3\n"
                            "address_base: 1\n"
                            "poll_rate_hz: 250\n"
                            "timeout_ms: 20\n"
                            "retries: 2\n"
                            "reconnect_min_ms: 50\n"
                            "reconnect_max_ms: 2000\n"
                            "max_age_ms: 15\n"
                            "channels:\n"
                            "  - {name: p1, register: input, address: 1, data_type: FLOAT32,\n"
                            "     byte_order: CDAB, scale: 100000, offset: -1.5}\n"
                            "  - {name: valve, register: coil, address: 40, unit_id: 7,\n"
                            "     max_age_ms: 100}\n");
  ASSERT_TRUE(config.tcp.has_value());
  EXPECT_FALSE(config.rtu.has_value());
  EXPECT_EQ(config.tcp->host, "127.0.0.1");
  EXPECT_EQ(config.tcp->port, 5020);
  EXPECT_EQ(config.poll_rate_hz, 250.0);
  EXPECT_EQ(config.timeout_ns, 20'000'000);
  EXPECT_EQ(config.retries, 2);
  EXPECT_EQ(config.reconnect_min_ns, 50'000'000);
  EXPECT_EQ(config.reconnect_max_ns, 2'000'000'000);
  ASSERT_EQ(config.channels.size(), 2U);
  const ChannelSpec& p1 = config.channels[0];
  EXPECT_EQ(p1.unit_id, 3);
  EXPECT_EQ(p1.register_type, RegisterType::input);
  EXPECT_EQ(p1.address, 0);  // 1-based address 1 is protocol address 0
  EXPECT_EQ(p1.data_type, DataType::float32);
  EXPECT_EQ(p1.byte_order, ByteOrder::cdab);
  EXPECT_EQ(p1.scale, 100000.0);
  EXPECT_EQ(p1.offset, -1.5);
  EXPECT_EQ(p1.max_age_ns, 15'000'000);
  const ChannelSpec& valve = config.channels[1];
  EXPECT_EQ(valve.unit_id, 7);
  EXPECT_EQ(valve.address, 39);
  EXPECT_EQ(valve.width(), 1);
  EXPECT_EQ(valve.max_age_ns, 100'000'000);
}

TEST(ModbusConfig, DefaultsAreDocumented) {
  const auto config = parse(kTcp + "channels:\n  - {name: p1, address: 0}\n");
  EXPECT_EQ(config.channels[0].register_type, RegisterType::holding);
  EXPECT_EQ(config.channels[0].data_type, DataType::uint16);
  EXPECT_EQ(config.channels[0].byte_order, ByteOrder::abcd);
  EXPECT_EQ(config.channels[0].unit_id, 1);
  EXPECT_EQ(config.channels[0].address, 0);  // address_base 0 by default
  EXPECT_EQ(config.poll_rate_hz, 500.0);
  EXPECT_EQ(config.timeout_ns, 50'000'000);
  EXPECT_EQ(config.channels[0].max_age_ns, 10'000'000);  // 4 polls at 500 Hz, at least 10 ms
  EXPECT_EQ(config.max_registers_per_request, 125);
  const auto slow = parse(kTcp + "poll_rate_hz: 10\nchannels:\n  - {name: p1, address: 0}\n");
  EXPECT_EQ(slow.channels[0].max_age_ns, 400'000'000);
}

TEST(ModbusConfig, RtuConfiguration) {
  const auto config = parse(
      "name: bus\ntransport: rtu\ndevice: /dev/ttyUSB0\nbaud: 115200\nparity: N\nstop_bits: 2\n"
      "channels:\n  - {name: p2, address: 3, data_type: INT32, byte_order: DCBA}\n");
  ASSERT_TRUE(config.rtu.has_value());
  EXPECT_EQ(config.rtu->device, "/dev/ttyUSB0");
  EXPECT_EQ(config.rtu->baud, 115200);
  EXPECT_EQ(config.rtu->parity, 'N');
  EXPECT_EQ(config.rtu->stop_bits, 2);
  EXPECT_EQ(config.endpoint(), "rtu:/dev/ttyUSB0@115200,8N2");
}

void expect_error(const std::string& text, const std::string& location,
                  const std::string& mention) {
  const std::string message = error_of(text);
  EXPECT_NE(message.find(location), std::string::npos) << message;
  EXPECT_NE(message.find(mention), std::string::npos) << message;
}

TEST(ModbusConfig, ChannelErrorsNameFileLineColumnAndField) {
  const std::string head = kTcp + "channels:\n";  // the first channel is on line 6
  expect_error(head + "  - {name: p1, address: 0, data_type: REAL}\n",
               "drivers.yaml:6:", "data_type: 'REAL' is not one of");
  expect_error(head + "  - {name: p1, address: 0, byte_order: ABDC}\n",
               "drivers.yaml:6:", "byte_order");
  expect_error(head + "  - {name: p1, adress: 0}\n", "drivers.yaml:6:16", "unknown key 'adress'");
  expect_error(head + "  - {name: p1, address: 0, register: holding_register}\n",
               "drivers.yaml:6:", "register");
  expect_error(head + "  - {name: p1, address: 0, register: coil, data_type: FLOAT32}\n",
               "drivers.yaml:6:", "single bits");
  expect_error(head + "  - {name: p1, address: 65533, data_type: FLOAT64}\n",
               "drivers.yaml:6:", "runs past the last register");
  expect_error(head + "  - {name: p1, address: 70000}\n", "drivers.yaml:6:", "outside 0..65535");
  expect_error(head + "  - {name: p1, address: 0, scale: 0}\n", "drivers.yaml:6:", "scale");
  expect_error(head + "  - {name: p1, address: 0}\n  - {name: p1, address: 1}\n",
               "drivers.yaml:7:", "duplicate channel name 'p1'");
  expect_error(head + "  - {name: p1, address: 1.5}\n", "drivers.yaml:6:", "address");
  expect_error("address_base: 1\n" + head + "  - {name: p1, address: 0}\n",
               "drivers.yaml:7:", "address 0 is outside 1..65536 (address_base is 1)");
}

TEST(ModbusConfig, ConnectionErrorsNameFileLineColumnAndField) {
  const std::string channels = "channels:\n  - {name: p1, address: 0}\n";
  expect_error("name: daq\nport: 502\n" + channels, "drivers.yaml:", "missing required key 'host'");
  expect_error(kTcp + "device: /dev/ttyS0\n" + channels,
               "drivers.yaml:5:", "'device' does not apply to transport tcp");
  expect_error(kTcp + "transport: udp\n" + channels, "drivers.yaml:5:", "transport");
  expect_error(kTcp + "timeout_ms: -1\n" + channels, "drivers.yaml:5:", "timeout_ms");
  expect_error(kTcp + "address_base: 2\n" + channels, "drivers.yaml:5:", "address_base");
  expect_error(kTcp + "max_registers_per_request: 200\n" + channels,
               "drivers.yaml:5:", "max_registers_per_request");
  expect_error(kTcp + "reconnect_min_ms: 500\nreconnect_max_ms: 100\n" + channels,
               "drivers.yaml:6:", "reconnect_max_ms");
  expect_error(kTcp + "pol_rate_hz: 100\n" + channels, "drivers.yaml:5:1",
               "unknown key 'pol_rate_hz'");
  expect_error(kTcp + "channels: []\n", "drivers.yaml:5:", "at least one channel");
  expect_error("name: daq\ntransport: rtu\nhost: x\ndevice: /dev/ttyS0\n" + channels,
               "drivers.yaml:3:", "'host' does not apply to transport rtu");
  expect_error("name: daq\ntype: can\nhost: x\n" + channels, "drivers.yaml:2:", "'modbus'");
}

// Issue 25: `host: 127.0.0.300` passed check-config and failed only when connecting.
TEST(ModbusConfig, TheHostIsAnAddressOrAName) {
  const std::string channels = "channels:\n  - {name: p1, address: 0}\n";
  expect_error("name: daq\nhost: 127.0.0.300\n" + channels, "drivers.yaml:2:7: host",
               "'127.0.0.300' is not an IPv4 address");
  expect_error("name: daq\nhost: 192.168.10\n" + channels, "drivers.yaml:2:7: host",
               "not an IPv4 address");
  expect_error("name: daq\nhost: plc_1.lan\n" + channels, "drivers.yaml:2:7: host",
               "neither an IP address nor a host name");
  expect_error("name: daq\nhost: 'fe80::1::2'\n" + channels, "drivers.yaml:2:7: host",
               "not an IPv6 address");
  expect_error("name: daq\nhost: ''\n" + channels, "drivers.yaml:2:7: host", "must not be empty");
  for (const char* good : {"10.0.0.1", "plc-1.plant.lan", "::1", "localhost"}) {
    EXPECT_EQ(parse(std::string("name: daq\nhost: '") + good + "'\n" + channels).tcp->host, good);
  }
}

// Two channels on the same registers are legal (a value and its halves) but usually a copied
// entry whose address was not changed: a warning naming both, with file:line:column.
TEST(ModbusConfig, OverlappingRegistersAreAWarning) {
  const auto config = parse(kTcp +
                            "channels:\n"
                            "  - {name: p1, register: input, address: 0, data_type: FLOAT32}\n"
                            "  - {name: p2, register: input, address: 1, data_type: FLOAT32}\n"
                            "  - {name: x, register: holding, address: 0}\n"
                            "  - {name: u, register: input, address: 2, unit_id: 2}\n"
                            "  - {name: v, register: input, address: 2}\n");
  ASSERT_EQ(config.warnings.size(), 2u);
  EXPECT_EQ(config.warnings[0],
            "drivers.yaml:7:42: channels[1].address: channel 'p2' reads registers 1..2 of unit 1, "
            "which channel 'p1' (drivers.yaml:6:42) also reads");
  EXPECT_NE(config.warnings[1].find("drivers.yaml:10:"), std::string::npos) << config.warnings[1];
  EXPECT_NE(config.warnings[1].find("channel 'v' reads registers 2..2 of unit 1, which channel "
                                    "'p2'"),
            std::string::npos)
      << config.warnings[1];
  // Another register space or another unit is no overlap; neither are adjacent values.
  EXPECT_TRUE(parse(kTcp + "channels:\n  - {name: a, address: 0, data_type: FLOAT32}\n"
                           "  - {name: b, address: 2, data_type: FLOAT32}\n")
                  .warnings.empty());
}

TEST(ModbusConfig, TheFactoryValidatesToo) {
  const auto node = config::ConfigNode::load_string(
      kTcp + "channels:\n  - {name: p1, address: 0, data_type: FLOAT}\n", "drivers.yaml");
  EXPECT_THROW(make_modbus_driver(node), config::ConfigError);
}

TEST(ModbusConfig, SampleConfigurationIsValid) {
  const auto node = config::ConfigNode::load_file(test::source_dir() + "/io/modbus/modbus.yaml");
  const auto driver = make_modbus_driver(node);
  EXPECT_EQ(driver->name(), "rig-daq");
  EXPECT_GE(driver->channels().size(), 4U);
}

}  // namespace
}  // namespace leakmon::io::modbus
