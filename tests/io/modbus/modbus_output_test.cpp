// The alarm output against a real peer: events go to a pymodbus server; the Modbus driver
// reads the coil and register back from the same server.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "config/yaml_reader.hpp"
#include "io/event.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "io/modbus/modbus_output.hpp"
#include "tests/io/modbus/peer_process.hpp"
#include "tests/io/modbus/served_capture.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

std::unique_ptr<io::EventSink> make_output(int port, const std::string& fields) {
  const std::string yaml =
      "name: plc\ntype: modbus\nhost: 127.0.0.1\nport: " + std::to_string(port) +
      "\ntimeout_ms: 100\nreconnect_min_ms: 20\nreconnect_max_ms: 200\n" + fields;
  return io::make_modbus_output(config::ConfigNode::load_string(yaml, "outputs.yaml"));
}

// Reads back coil 20 ("alarm_coil") and holding register 30 ("alarm_register").
std::unique_ptr<io::Driver> make_reader(int port) {
  const std::string yaml = "name: readback\nhost: 127.0.0.1\nport: " + std::to_string(port) +
                           "\npoll_rate_hz: 100\nmax_age_ms: 200\nreconnect_min_ms: 20\n"
                           "reconnect_max_ms: 200\nchannels:\n"
                           "  - {name: alarm_coil, register: coil, address: 20}\n"
                           "  - {name: alarm_register, register: holding, address: 30,"
                           " data_type: INT16}\n";
  auto driver = io::make_modbus_driver(config::ConfigNode::load_string(yaml, "reader.yaml"));
  driver->start();
  return driver;
}

// Waits until channel `index` of `reader` reads `want`; false after 10 s.
bool reads(io::Driver& reader, std::size_t index, double want) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  double values[2];
  while (std::chrono::steady_clock::now() < deadline) {
    reader.read(io::Tick{0, monotonic_ns()}, values);
    if (values[index] == want) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

io::Event alarm(io::EventKind kind, const std::string& actuator,
                const std::string& name = "internal_leakage") {
  io::Event event;
  event.kind = kind;
  event.actuator = actuator;
  event.alarm = name;
  return event;
}

ModbusServerOptions server_options(const std::string& dir, int port = 0) {
  ModbusServerOptions options;
  options.ready_file = dir + "/ready";
  options.tcp_port = port;
  return options;
}

TEST(ModbusOutput, CoilFollowsTheAlarm) {
  const std::string dir = scratch_dir("ModbusOutputCoil");
  ModbusServer server(server_options(dir));
  auto reader = make_reader(server.port());
  auto output = make_output(server.port(), "register: coil\naddress: 20\n");
  ASSERT_TRUE(reads(*reader, 0, 0.0));
  output->publish(alarm(io::EventKind::alarm_raised, "cyl1"));
  EXPECT_TRUE(reads(*reader, 0, 1.0));
  output->publish(alarm(io::EventKind::alarm_cleared, "cyl1"));
  EXPECT_TRUE(reads(*reader, 0, 0.0));
}

TEST(ModbusOutput, RegisterHoldsRaisedWhileAnyMatchingAlarmIsActive) {
  const std::string dir = scratch_dir("ModbusOutputRegister");
  ModbusServer server(server_options(dir));
  auto reader = make_reader(server.port());
  auto output = make_output(server.port(),
                            "register: holding\naddress: 31\naddress_base: 1\ndata_type: INT16\n"
                            "raised_value: 2\ncleared_value: -1\nalarm: internal_leakage\n");
  ASSERT_TRUE(reads(*reader, 1, 0.0));
  output->flush();  // the first flush writes the cleared state: the PLC learns "no alarm"
  EXPECT_TRUE(reads(*reader, 1, -1.0));
  output->publish(alarm(io::EventKind::alarm_raised, "cyl1"));
  output->publish(alarm(io::EventKind::alarm_raised, "cyl2"));
  EXPECT_TRUE(reads(*reader, 1, 2.0));
  output->publish(alarm(io::EventKind::alarm_cleared, "cyl1"));
  output->publish(alarm(io::EventKind::alarm_cleared, "cyl2", "other_alarm"));  // ignored
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_TRUE(reads(*reader, 1, 2.0));
  output->publish(alarm(io::EventKind::alarm_cleared, "cyl2"));
  EXPECT_TRUE(reads(*reader, 1, -1.0));
}

TEST(ModbusOutput, RestartedPlcLearnsTheStateAgain) {
  const std::string dir = scratch_dir("ModbusOutputRestart");
  auto server = std::make_unique<ModbusServer>(server_options(dir));
  const int port = server->port();
  auto output = make_output(port, "register: coil\naddress: 20\nrefresh_ms: 100\n");
  output->publish(alarm(io::EventKind::alarm_raised, "cyl1"));
  {
    auto reader = make_reader(port);
    ASSERT_TRUE(reads(*reader, 0, 1.0));
  }
  server->kill();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));         // writes fail meanwhile
  server = std::make_unique<ModbusServer>(server_options(dir, port));  // its coils start at 0
  auto reader = make_reader(port);
  EXPECT_TRUE(reads(*reader, 0, 1.0));
}

TEST(ModbusOutput, ConfigurationErrorsNameTheField) {
  const auto error_of = [](const std::string& fields) -> std::string {
    try {
      make_output(502, fields);
    } catch (const config::ConfigError& e) {
      return e.what();
    }
    return "accepted";
  };
  // The connection fields take lines 1-7; the output's own fields start on line 8.
  EXPECT_NE(error_of("register: coil\naddress: 1\ndata_type: FLOAT32\n").find("outputs.yaml:10:"),
            std::string::npos);
  EXPECT_NE(error_of("register: input\naddress: 1\n").find("outputs.yaml:8:"), std::string::npos);
  EXPECT_NE(error_of("register: coil\naddress: 1\nraised_value: 5\n").find("raised_value"),
            std::string::npos);
  EXPECT_NE(error_of("register: coil\n").find("missing required key 'address'"), std::string::npos);
  EXPECT_NE(error_of("address: 1\nrefresh: 10\n").find("unknown key 'refresh'"), std::string::npos);
}

}  // namespace
}  // namespace leakmon::test
